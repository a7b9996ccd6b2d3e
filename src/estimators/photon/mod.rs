//! `photon1` and `photon2`: the photon-map estimators (SPEC §3.3; paper §3.3–3.4, §4.2).
//!
//! Photon paths are traced from the spot light or the camera ([`trace`]); each bounce stores
//! a photon at its start point with the distance to the next hit. At a pixel, the `K` nearest
//! photons whose normal agrees with the pixel's (`n_j · n ≥ 0.9`) give
//! `H = k' / Σ 1/d_j`, with `d_j` the photon's own distance (method I) or the distance from the
//! pixel to the photon's next hit (method II). No accepted photon: a hole (NaN, counted).

pub mod map;
pub mod trace;

use std::num::NonZero;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;

use super::{Estimate, EstimateContext, Estimator, GBuffer, HarmonicMean, RayCount};
use crate::error::{Error, Result};
use crate::progress::Progress;
pub use map::{PhotonMap, PhotonMethod};
pub use trace::{trace_photons, PathRules, PhotonSource, PhotonTrace, TracedPhoton};

/// Default stored photons `P` (paper: 130 K … 8.53 M).
pub const DEFAULT_PHOTONS: usize = 1_000_000;
/// Default photons gathered per pixel `K` (paper: 64 … 1,024).
pub const DEFAULT_GATHER: usize = 256;
/// Default bounce limit (paper: 20 and 80).
pub const DEFAULT_MAX_BOUNCES: u32 = 20;
/// Default absorption probability per interaction (paper: 0.2).
pub const DEFAULT_ABSORPTION: f32 = 0.2;
/// A gathered photon counts when `n_j · n` is at least this (same surface orientation).
pub const NORMAL_FILTER_COS: f32 = 0.9;

/// Where photon paths start, as the CLI names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    Light,
    Camera,
}

impl SourceKind {
    pub fn name(self) -> &'static str {
        match self {
            SourceKind::Light => "light",
            SourceKind::Camera => "camera",
        }
    }
}

/// The photon estimators' parameters.
#[derive(Clone, Copy, Debug)]
pub struct PhotonParams {
    /// Stored photons `P`, exactly.
    pub photons: usize,
    /// Nearest photons gathered per pixel `K`.
    pub gather: usize,
    pub source: SourceKind,
    pub rules: PathRules,
    /// Gather only within this distance of the pixel (`None`: no limit).
    pub max_radius: Option<f32>,
}

impl Default for PhotonParams {
    fn default() -> Self {
        PhotonParams {
            photons: DEFAULT_PHOTONS,
            gather: DEFAULT_GATHER,
            source: SourceKind::Light,
            rules: PathRules {
                max_bounces: DEFAULT_MAX_BOUNCES,
                absorption: DEFAULT_ABSORPTION,
            },
            max_radius: None,
        }
    }
}

/// Method I or II over a photon map built once per image.
pub struct PhotonEstimator {
    pub method: PhotonMethod,
    pub params: PhotonParams,
}

impl PhotonEstimator {
    pub fn new(method: PhotonMethod, params: PhotonParams) -> Result<Self> {
        if params.photons == 0 {
            return Err(Error::parameter("--photons must be at least 1"));
        }
        if params.gather == 0 {
            return Err(Error::parameter("--gather must be at least 1"));
        }
        if params.rules.max_bounces == 0 {
            return Err(Error::parameter("--max-bounces must be at least 1"));
        }
        let a = params.rules.absorption;
        if !(0.0..1.0).contains(&a) {
            return Err(Error::parameter(format!(
                "--absorption must be in [0, 1), not {a}"
            )));
        }
        if let Some(r) = params.max_radius {
            if r.is_nan() || r <= 0.0 {
                return Err(Error::parameter(format!(
                    "--max-radius must be positive, not {r}"
                )));
            }
        }
        check_memory(method, params.photons)?;
        Ok(PhotonEstimator { method, params })
    }

    fn source(&self, context: &EstimateContext, gbuffer: &GBuffer) -> Result<PhotonSource> {
        match self.params.source {
            SourceKind::Light => context.scene.light.map(PhotonSource::Light).ok_or_else(|| {
                Error::parameter(format!(
                    "scene '{}' has no spot light for --source light: add a [light] to its TOML \
                     file or use --source camera",
                    context.scene.name
                ))
            }),
            SourceKind::Camera => Ok(PhotonSource::Camera(
                context.scene.camera.rays(gbuffer.width, gbuffer.height),
                gbuffer.width,
                gbuffer.height,
            )),
        }
    }
}

/// Refuses a photon budget whose map would not fit in the memory available now.
fn check_memory(method: PhotonMethod, photons: usize) -> Result<()> {
    let needed = method.peak_build_bytes(photons);
    if let Some(available) = available_memory() {
        if needed > available {
            return Err(Error::parameter(format!(
                "{photons} photons need about {:.1} GB to build the {} map ({} B per photon while \
                 building), but only {:.1} GB of memory is available",
                needed as f64 / 1e9,
                method.name(),
                method.peak_build_bytes(1),
                available as f64 / 1e9
            )));
        }
    }
    Ok(())
}

/// `MemAvailable` of /proc/meminfo, where there is one.
fn available_memory() -> Option<u128> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u128 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

impl Estimator for PhotonEstimator {
    fn method(&self) -> &'static str {
        self.method.name()
    }

    fn expected_rays(&self, _pixels: u64) -> u64 {
        // About one ray per stored photon, plus the paths' first rays.
        self.params.photons as u64
    }

    fn parameters(&self) -> serde_json::Map<String, serde_json::Value> {
        let p = &self.params;
        let value = json!({
            // No gather rays: H comes from the photon map.
            "rays": serde_json::Value::Null,
            "photons": p.photons,
            "gather": p.gather,
            "source": p.source.name(),
            "max_bounces": p.rules.max_bounces,
            "absorption": p.rules.absorption,
            "max_radius": p.max_radius,
            "normal_filter_cos": NORMAL_FILTER_COS,
        });
        crate::estimators::fields(value)
    }

    fn estimate(
        &self,
        context: &EstimateContext,
        gbuffer: &GBuffer,
        progress: &dyn Progress,
    ) -> Result<Estimate> {
        let source = self.source(context, gbuffer)?;
        let p = &self.params;

        let start = Instant::now();
        progress.start("photons", p.photons as u64);
        let done = AtomicU64::new(0);
        let report = |stored: usize| {
            let before = done.swap(stored as u64, Ordering::Relaxed);
            progress.advance(stored as u64 - before);
        };
        let traced = trace_photons(context.accel, &source, p.rules, p.photons, context.seed, &report)?;
        progress.finish();
        let photon_trace = start.elapsed().as_secs_f64();

        let start = Instant::now();
        let map = PhotonMap::build(&traced.photons, self.method)?;
        let photon_index = start.elapsed().as_secs_f64();
        let (stored, paths, escaped) = (traced.photons.len(), traced.paths_traced, traced.escaped);
        let rays = RayCount {
            cast: traced.rays_cast(),
            escaped: traced.escaped_rays(),
            seconds: photon_trace,
        };
        drop(traced);

        let start = Instant::now();
        let (hmd, holes) = self.gather(context, gbuffer, &map, progress);
        let gather = start.elapsed().as_secs_f64();
        let queries = gbuffer.points.len() - gbuffer.background_pixels();

        let extra = json!({
            "photons_stored": stored,
            "paths_traced": paths,
            "escaped_photons": escaped,
            "bytes_per_photon": self.method.bytes_per_photon(),
            "holes": holes,
            "gather_queries_per_s": queries as f64 / gather.max(1e-9),
        });
        Ok(Estimate {
            hmd,
            rays: Some(rays),
            phases: vec![
                ("photon_trace", photon_trace),
                ("photon_index", photon_index),
                ("gather", gather),
            ],
            extra: crate::estimators::fields(extra),
        })
    }
}

impl PhotonEstimator {
    /// H per pixel from the map, and the number of holes. Rows run in parallel; neighbouring
    /// pixels of a row query neighbouring points, which keeps the tree's nodes in cache.
    fn gather(
        &self,
        context: &EstimateContext,
        gbuffer: &GBuffer,
        map: &PhotonMap,
        progress: &dyn Progress,
    ) -> (Vec<f32>, u64) {
        let k = NonZero::new(self.params.gather).expect("validated: gather ≥ 1");
        let max_radius = self.params.max_radius.unwrap_or(f32::INFINITY);
        let width = gbuffer.width as usize;
        let holes = AtomicU64::new(0);
        let mut hmd = vec![f32::NAN; gbuffer.points.len()];
        progress.start("gather", gbuffer.height as u64);
        hmd.par_chunks_mut(width)
            .zip(gbuffer.points.par_chunks(width))
            .for_each(|(out, points)| {
                let mut row_holes = 0;
                for (h, point) in out.iter_mut().zip(points) {
                    let Some(hit) = point else { continue };
                    let mut mean = HarmonicMean::default();
                    map.gather(hit.point, hit.normal, k, max_radius, NORMAL_FILTER_COS, |d| {
                        mean.add(d, context.clamp)
                    });
                    *h = mean.value();
                    row_holes += h.is_nan() as u64;
                }
                holes.fetch_add(row_holes, Ordering::Relaxed);
                progress.advance(1);
            });
        progress.finish();
        (hmd, holes.into_inner())
    }
}
