//! `photon1` and `photon2`: the photon-map estimators (spec §3.3; paper §3.3–3.4, §4.2).
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

use super::{
    AovSample, EstimateContext, Estimator, GBuffer, HarmonicMean, PixelJob, PixelPass, PixelWorker, Prepared,
    RayCount, Tally,
};
use crate::accel::Accel;
use crate::accel::Hit;
use crate::error::{Error, Result};
use crate::options::{in_pool, RenderOptions};
use crate::progress::Progress;
pub use crate::report::SourceKind;
use crate::report::{Details, KeyImage, Parameters, PhaseSeconds, PhotonDetails, RenderKey};
use crate::scene::Scene;
pub use map::{GatherScratch, MapHeader, PhotonMap, PhotonMethod};
pub use trace::{trace_photons, PathRules, PhotonSource, PhotonTrace, TracedPhoton};

/// Default stored photons `P` (paper: 130 K … 8.53 M).
pub const DEFAULT_PHOTONS: usize = 1_000_000;
/// Default photons gathered per pixel `K` (paper: 64 … 1,024).
pub const DEFAULT_NEAREST: usize = 256;
/// Default bounce limit (paper: 20 and 80).
pub const DEFAULT_MAX_BOUNCES: u32 = 20;
/// Default absorption probability per interaction (paper: 0.2).
pub const DEFAULT_ABSORPTION: f32 = 0.2;
/// A gathered photon counts when `n_j · n` is at least this (same surface orientation).
pub const NORMAL_FILTER_COS: f32 = 0.9;

/// The photon estimators' parameters, `photon1`'s and `photon2`'s one list: the CLI's flags
/// (`--photons`), Python's keywords and the registry's build all come from here.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct PhotonParams {
    /// Gather over this photon map file (from `hmdist photons build`) instead of tracing one.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "FILE", help_heading = "Photon methods")
    )]
    pub photon_map: Option<std::path::PathBuf>,
    /// Photons stored P, exactly.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = DEFAULT_PHOTONS, help_heading = "Photon methods")
    )]
    pub photons: usize,
    /// Nearest photons gathered per pixel K (`--gather` is its older name).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "K", alias = "gather", default_value_t = DEFAULT_NEAREST, help_heading = "Photon methods")
    )]
    #[serde(alias = "gather")]
    pub nearest: usize,
    /// Where paths start.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_enum, default_value_t = SourceKind::Light, help_heading = "Photon methods")
    )]
    pub source: SourceKind,
    /// A path ends at this many surface interactions.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = DEFAULT_MAX_BOUNCES, help_heading = "Photon methods")
    )]
    pub max_bounces: u32,
    /// Probability that a path ends at each interaction.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = DEFAULT_ABSORPTION, help_heading = "Photon methods")
    )]
    pub absorption: f32,
    /// Gather only within this distance of the pixel [default: no limit].
    #[cfg_attr(feature = "cli", arg(long, value_name = "R", help_heading = "Photon methods"))]
    pub max_radius: Option<f32>,
}

impl Default for PhotonParams {
    fn default() -> Self {
        PhotonParams {
            photon_map: None,
            photons: DEFAULT_PHOTONS,
            nearest: DEFAULT_NEAREST,
            source: SourceKind::Light,
            max_bounces: DEFAULT_MAX_BOUNCES,
            absorption: DEFAULT_ABSORPTION,
            max_radius: None,
        }
    }
}

impl super::params::MethodParams for PhotonParams {}

impl PhotonParams {
    /// When paths end: the bounce limit and the absorption.
    pub fn rules(&self) -> PathRules {
        PathRules {
            max_bounces: self.max_bounces,
            absorption: self.absorption,
        }
    }
}

/// Method I or II over a photon map built once per image (or read from a file).
pub struct PhotonEstimator {
    method: PhotonMethod,
    params: PhotonParams,
    /// A map built beforehand ([`PhotonEstimator::build_map_file`]), and its header.
    prebuilt: Option<(PhotonMap, MapHeader)>,
}

impl PhotonEstimator {
    /// Method `method` with `params`, checked: counts at least 1, absorption in [0, 1), a
    /// positive radius, and a map that fits in the memory available now; over the map file
    /// `params.photon_map` where it names one ([`PhotonEstimator::with_map_file`]).
    pub fn new(method: PhotonMethod, params: PhotonParams) -> Result<Self> {
        if params.photons == 0 {
            return Err(Error::invalid("photons", "must be at least 1, not 0"));
        }
        if params.nearest == 0 {
            return Err(Error::invalid("nearest", "must be at least 1, not 0"));
        }
        if params.max_bounces == 0 {
            return Err(Error::invalid("max_bounces", "must be at least 1, not 0"));
        }
        let a = params.absorption;
        if !(0.0..1.0).contains(&a) {
            return Err(Error::invalid(
                "absorption",
                format!("must be in [0, 1), not {a}"),
            ));
        }
        Error::check_positive("max_radius", params.max_radius)?;
        check_memory(method, params.photons)?;
        let map_file = params.photon_map.clone();
        let estimator = PhotonEstimator {
            method,
            params,
            prebuilt: None,
        };
        match map_file {
            Some(path) => {
                let bytes = crate::files::read_regular(&path)?;
                estimator.with_map_file(&bytes, &path)
            }
            None => Ok(estimator),
        }
    }

    fn source(&self, context: &EstimateContext, gbuffer: &GBuffer) -> Result<PhotonSource> {
        self.source_for(context.scene, (gbuffer.width, gbuffer.height))
    }

    fn source_for(&self, scene: &Scene, (width, height): (u32, u32)) -> Result<PhotonSource> {
        match self.params.source {
            SourceKind::Light => scene.light.map(PhotonSource::Light).ok_or_else(|| {
                let message = format!(
                    "light needs a spot light, and scene '{}' has no spot light: {}, or take the camera as the source",
                    scene.name,
                    crate::scene::procedural::light_advice(scene)
                );
                Error::invalid("source", message)
            }),
            SourceKind::Camera => Ok(PhotonSource::Camera(
                scene.camera.rays(width, height),
                width,
                height,
            )),
        }
    }
}

impl PhotonEstimator {
    /// The fingerprint of this estimator's map for `scene` with `seed`, for images of `size`
    /// (which camera-sourced photons depend on): the [`RenderKey::digest`] of the map's key,
    /// the render key with what the map depends on (the scene's content, not its name; the
    /// photon method, count, source, bounces and absorption, not K; the size only for
    /// camera-sourced photons). Not the BVH preset: the tie rule gives every photon the same
    /// hit through either tree, so the map is the same bytes (tests/photon.rs), and a map
    /// built by `photons build` serves a render or a cache whose work resolves `auto` to the
    /// other preset.
    pub fn map_fingerprint(&self, scene: &Scene, seed: u64, size: (u32, u32)) -> u64 {
        /// The photon parameters a map depends on.
        #[derive(serde::Serialize)]
        struct MapParameters {
            photons: usize,
            source: SourceKind,
            max_bounces: u32,
            absorption: f32,
        }
        let p = &self.params;
        let (width, height) = if p.source == SourceKind::Camera {
            size
        } else {
            (0, 0)
        };
        let key = RenderKey::new(
            ("", scene.fingerprint()),
            (
                self.method.name(),
                Parameters::of(
                    &MapParameters {
                        photons: p.photons,
                        source: p.source,
                        max_bounces: p.max_bounces,
                        absorption: p.absorption,
                    },
                    &[],
                ),
            ),
            "any",
            KeyImage {
                width,
                height,
                seed,
                max_distance: None,
                aovs: vec![],
                denoise: None,
            },
        );
        key.digest()
    }

    /// Traces and indexes the photon map that a render of `scene` with `options` (its size,
    /// seed, threads and BVH preset) would build, as the bytes of a map file.
    pub fn build_map_file(
        &self,
        scene: &Scene,
        options: &RenderOptions,
        progress: &dyn Progress,
    ) -> Result<Vec<u8>> {
        options.validate()?;
        scene.validate()?;
        in_pool(options.threads, || {
            let pixels = options.width as u64 * options.height as u64;
            let rays = pixels + self.expected_rays(pixels);
            let kernel = options.kernel;
            let (accel, _) = Accel::for_work(&scene.mesh, options.bvh_quality, rays, kernel)?;
            let source = self.source_for(scene, (options.width, options.height))?;
            let (map, header, _) = self.trace_and_index(&accel, &source, options.seed, progress)?;
            let fingerprint = self.map_fingerprint(scene, options.seed, (options.width, options.height));
            Ok(map.to_bytes(&MapHeader {
                fingerprint,
                ..header
            }))
        })?
    }

    /// This estimator, gathering over the map in `bytes` (a map file, named `path` in
    /// errors) instead of tracing its own; a render checks that the map is its own.
    pub fn with_map_file(self, bytes: &[u8], path: &std::path::Path) -> Result<Self> {
        let (map, header) = PhotonMap::from_bytes(bytes, self.method).map_err(|e| Error::file(path, e))?;
        if header.photons_stored != self.params.photons as u64 {
            let message = format!(
                "holds {} photons, not {}",
                header.photons_stored, self.params.photons
            );
            return Err(Error::file(path, message));
        }
        Ok(PhotonEstimator {
            prebuilt: Some((map, header)),
            ..self
        })
    }

    /// Traces the photons from `source` and indexes them: the map, its header (fingerprint
    /// 0) and the seconds of each phase.
    fn trace_and_index(
        &self,
        accel: &Accel,
        source: &PhotonSource,
        seed: u64,
        progress: &dyn Progress,
    ) -> Result<(PhotonMap, MapHeader, PhaseSeconds)> {
        let p = &self.params;
        let start = Instant::now();
        progress.start("photons", p.photons as u64);
        let done = AtomicU64::new(0);
        let report = |stored: usize| {
            let before = done.swap(stored as u64, Ordering::Relaxed);
            progress.advance(stored as u64 - before);
        };
        let traced = trace_photons(accel, source, p.rules(), p.photons, seed, &report)?;
        progress.finish();
        let photon_trace = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let map = PhotonMap::build(&traced.photons, self.method)?;
        let header = MapHeader {
            fingerprint: 0,
            photons_stored: traced.photons.len() as u64,
            paths_traced: traced.paths_traced,
            escaped_photons: traced.escaped,
            rays_cast: traced.rays_cast(),
            escaped_rays: traced.escaped_rays(),
        };
        let phases = PhaseSeconds {
            photon_trace: Some(photon_trace),
            photon_index: Some(start.elapsed().as_secs_f64()),
            ..PhaseSeconds::default()
        };
        Ok((map, header, phases))
    }
}

/// Refuses a photon budget whose map would not fit in the memory available now.
fn check_memory(method: PhotonMethod, photons: usize) -> Result<()> {
    let what = format!(
        "of {photons} (the {} map takes {} B per photon while building)",
        method.name(),
        method.peak_build_bytes(1)
    );
    crate::memory::check(Some("photons"), &what, method.peak_build_bytes(photons), None)
}

impl Estimator for PhotonEstimator {
    fn method(&self) -> &'static str {
        self.method.name()
    }

    fn samples(&self) -> crate::estimators::Samples {
        crate::estimators::Samples::Unsuited(
            "neighbouring pixels gather the same photons, so their errors are not independent, which the filter's noise model assumes",
        )
    }

    fn expected_rays(&self, _pixels: u64) -> u64 {
        // About one ray per stored photon, plus the paths' first rays.
        self.params.photons as u64
    }

    fn parameters(&self) -> Parameters {
        Parameters::of(&self.params, &["photon_map"])
    }

    /// Traces the photons and builds the map; the driver then gathers per pixel.
    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        gbuffer: &'a GBuffer,
        progress: &dyn Progress,
    ) -> Result<Prepared<'a>> {
        let (map, header, phases) = match &self.prebuilt {
            Some((map, header)) => {
                let size = (gbuffer.width, gbuffer.height);
                let expected = self.map_fingerprint(context.scene, context.seed, size);
                if header.fingerprint != expected {
                    let message = "is not this render's photon map: built for another scene, photon \
                                   parameters, seed, image size (camera source) or version";
                    return Err(Error::invalid("photon_map", message));
                }
                // Nothing traced or indexed here: the keys stay, at zero seconds.
                let phases = PhaseSeconds {
                    photon_trace: Some(0.0),
                    photon_index: Some(0.0),
                    ..PhaseSeconds::default()
                };
                (Maps::Shared(map), *header, phases)
            }
            None => {
                let source = self.source(context, gbuffer)?;
                let (map, header, phases) =
                    self.trace_and_index(context.accel, &source, context.seed, progress)?;
                (Maps::Own(Box::new(map)), header, phases)
            }
        };
        let rays = RayCount {
            cast: header.rays_cast,
            escaped: header.escaped_rays,
            seconds: phases.photon_trace.unwrap_or(0.0),
        };
        let work = PhotonPixels {
            estimator: self,
            context,
            map,
            nearest: NonZero::new(self.params.nearest).expect("validated: nearest ≥ 1"),
            photons_stored: header.photons_stored as usize,
            paths_traced: header.paths_traced,
            escaped_photons: header.escaped_photons,
        };
        Ok(Prepared::Pixels {
            job: Box::new(work),
            phases,
            // A prebuilt map's tracing cast its rays elsewhere, once.
            rays: self.prebuilt.is_none().then_some(rays),
        })
    }
}

/// The map a render gathers over: its own, or one read from a file.
enum Maps<'a> {
    Own(Box<PhotonMap>),
    Shared(&'a PhotonMap),
}

impl std::ops::Deref for Maps<'_> {
    type Target = PhotonMap;
    fn deref(&self) -> &PhotonMap {
        match self {
            Maps::Own(map) => map,
            Maps::Shared(map) => map,
        }
    }
}

/// The photon gather on one image, over the map built for it. Neighbouring pixels of a row
/// query neighbouring points, which keeps the tree's nodes in cache.
struct PhotonPixels<'a> {
    estimator: &'a PhotonEstimator,
    context: &'a EstimateContext<'a>,
    map: Maps<'a>,
    nearest: NonZero<usize>,
    photons_stored: usize,
    paths_traced: u64,
    escaped_photons: u64,
}

impl PixelJob for PhotonPixels<'_> {
    fn label(&self) -> &'static str {
        "gather"
    }

    fn casts_rays(&self) -> bool {
        false
    }

    fn record_phase(&self, phases: &mut PhaseSeconds, seconds: f64) {
        phases.gather = Some(seconds);
    }

    fn worker<'w>(&'w self, _: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        Box::new(PhotonWorker {
            pixels: self,
            scratch: GatherScratch::default(),
        })
    }

    fn details(&self, pass: &PixelPass) -> Details {
        Details {
            photon: Some(PhotonDetails {
                photons_stored: self.photons_stored,
                paths_traced: self.paths_traced,
                escaped_photons: self.escaped_photons,
                bytes_per_photon: self.estimator.method.bytes_per_photon(),
                holes: pass.tally.holes,
                gather_queries_per_s: pass.pixels as f64 / pass.seconds.max(1e-9),
            }),
            ..Details::default()
        }
    }
}

/// A thread's view of [`PhotonPixels`], with its gather buffers; consecutive pixels of a row
/// start each search from the previous one's radius.
struct PhotonWorker<'a> {
    pixels: &'a PhotonPixels<'a>,
    scratch: GatherScratch,
}

impl PixelWorker for PhotonWorker<'_> {
    fn pixel(&mut self, hit: &Hit, _: u64, _: &mut Tally, _: &mut AovSample) -> f32 {
        let w = self.pixels;
        let max_radius = w.estimator.params.max_radius.unwrap_or(f32::INFINITY);
        let clamp = w.context.clamp;
        let mut mean = HarmonicMean::default();
        let (x, n) = (hit.point, hit.normal);
        w.map.gather(
            &mut self.scratch,
            x,
            n,
            w.nearest,
            max_radius,
            NORMAL_FILTER_COS,
            |d| mean.add(d, clamp),
        );
        mean.value()
    }
}
