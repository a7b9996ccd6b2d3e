//! Shards: one render split over machines, merged into exactly the image one machine makes.
//!
//! Shard `K/M` renders the rows `r` with `r mod M = K` (interleaved, so every shard gets its
//! share of cheap and expensive rows); its EXR is full size with the other rows NaN. Random
//! numbers are keyed by (seed, pixel, ray) and the BVH preset is chosen for the whole image,
//! so a shard's pixels equal the one-machine render's. A shard's report carries a fingerprint
//! of everything that determines the pixels (the scene's content, camera and light, the
//! method and its parameters, size, seed, distance clamp, AOVs and hmdist's version);
//! [`merge`] refuses parts whose fingerprints differ, a missing or repeated shard, and writes
//! the merged report's sums of rays, escapes and seconds with each shard's timings.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::estimators::{AovImage, Estimator};
use crate::image::HmdImage;
use crate::render::{RenderOptions, Rendered};
use crate::report::{CubemapDetails, PhaseSeconds, RenderReport};
use crate::scene::{stable_hash, Scene};

/// Shard `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard, from 0.
    pub index: u32,
    /// How many shards.
    pub count: u32,
}

impl Shard {
    /// Shard `index` of `count`: `index < count`.
    pub fn new(index: u32, count: u32) -> Result<Shard> {
        if count == 0 || index >= count {
            let message = format!("{index}/{count} is not a shard: K/M needs 0 <= K < M");
            return Err(Error::invalid("shard", message));
        }
        Ok(Shard { index, count })
    }

    /// `K/M`, e.g. `0/4`.
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || Error::invalid("shard", format!("'{text}' is not K/M, e.g. 0/4"));
        let (k, m) = text.split_once('/').ok_or_else(bad)?;
        Shard::new(
            k.trim().parse().map_err(|_| bad())?,
            m.trim().parse().map_err(|_| bad())?,
        )
    }

    /// Whether image row `row` is this shard's.
    pub fn has_row(&self, row: u32) -> bool {
        row % self.count == self.index
    }
}

/// What a shard's report says about it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardReport {
    /// Which shard, from 0.
    pub index: u32,
    /// How many shards.
    pub count: u32,
    /// Hash of everything that determines the pixels.
    pub fingerprint: String,
}

/// One shard's timings in a merged report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardTiming {
    /// Which shard.
    pub index: u32,
    /// Its total seconds.
    pub seconds: f64,
    /// Rays it cast, where the method counts them.
    pub rays_cast: Option<u64>,
}

/// The fingerprint of a render: everything that determines its pixels, and nothing that
/// does not (threads, the shard itself).
pub fn fingerprint(scene: &Scene, estimator: &dyn Estimator, options: &RenderOptions) -> String {
    let parameters = serde_json::to_string(&estimator.parameters()).expect("parameters serialise");
    let key = format!(
        "{}|{}|{:016x}|{}|{parameters}|{}x{}|{}|{:?}|{:?}",
        env!("CARGO_PKG_VERSION"),
        scene.name,
        scene.fingerprint(),
        estimator.method(),
        options.width,
        options.height,
        options.seed,
        options.max_distance.map(f32::to_bits),
        options.aovs,
    );
    format!("{:016x}", stable_hash(key.as_bytes()))
}

/// One shard's output, as read back from its files.
pub struct Part {
    /// H, full size, NaN outside the shard's rows.
    pub image: HmdImage,
    /// Its AOVs, in the report's channel order.
    pub aovs: Vec<AovImage>,
    /// Its report, with its [`ShardReport`].
    pub report: RenderReport,
}

/// The one-machine image and report from every shard's part, in any order.
pub fn merge(parts: Vec<Part>) -> Result<Rendered> {
    let shard_of = |p: &Part| {
        p.report
            .shard
            .clone()
            .ok_or_else(|| Error::parameter(format!("a part of scene '{}' is not a shard", p.report.scene)))
    };
    let first = parts
        .first()
        .ok_or_else(|| Error::parameter("no parts to merge"))?;
    let reference = shard_of(first)?;
    let mut slots: Vec<Option<Part>> = (0..reference.count).map(|_| None).collect();
    for part in parts {
        let shard = shard_of(&part)?;
        if shard.fingerprint != reference.fingerprint || shard.count != reference.count {
            let message = format!(
                "the parts are not of one render: shard {}/{} has fingerprint {}, shard {}/{} has {} \
                 (scene, camera, method, parameters, size, seed or version differ)",
                reference.index,
                reference.count,
                reference.fingerprint,
                shard.index,
                shard.count,
                shard.fingerprint
            );
            return Err(Error::parameter(message));
        }
        let slot = &mut slots[shard.index as usize];
        if slot.is_some() {
            let message = format!("the parts include shard {}/{} twice", shard.index, shard.count);
            return Err(Error::parameter(message));
        }
        *slot = Some(part);
    }
    let missing: Vec<String> = (0..reference.count)
        .filter(|&i| slots[i as usize].is_none())
        .map(|i| format!("{i}/{}", reference.count))
        .collect();
    if !missing.is_empty() {
        return Err(Error::parameter(format!(
            "the parts lack shard {}",
            missing.join(", ")
        )));
    }
    let parts: Vec<Part> = slots.into_iter().flatten().collect();
    let (width, height) = (parts[0].image.width, parts[0].image.height);
    let mut image = parts[0].image.clone();
    let mut aovs = parts[0].aovs.clone();
    for (index, part) in parts.iter().enumerate() {
        let shard = Shard::new(index as u32, reference.count)?;
        for row in (0..height).filter(|&r| shard.has_row(r)) {
            let range = (row * width) as usize..((row + 1) * width) as usize;
            image.data[range.clone()].copy_from_slice(&part.image.data[range.clone()]);
            for (merged, own) in aovs.iter_mut().zip(&part.aovs) {
                merged.data[range.clone()].copy_from_slice(&own.data[range.clone()]);
            }
        }
    }
    let mut report = parts[0].report.clone();
    let sum = |f: fn(&RenderReport) -> Option<u64>| parts.iter().map(|p| f(&p.report)).sum::<Option<u64>>();
    report.rays_cast = sum(|r| r.rays_cast);
    report.escaped_rays = sum(|r| r.escaped_rays);
    report.background_pixels = parts.iter().map(|p| p.report.background_pixels).sum();
    let seconds = |p: &Part| p.report.seconds.total;
    report.seconds.total = parts.iter().map(seconds).sum();
    report.seconds.estimate = parts.iter().map(|p| p.report.seconds.estimate).sum();
    report.seconds.primary = parts.iter().map(|p| p.report.seconds.primary).sum();
    report.seconds.accel_build = parts.iter().map(|p| p.report.seconds.accel_build).sum();
    report.seconds.load = parts.iter().map(|p| p.report.seconds.load).sum();
    let phase = |f: fn(&PhaseSeconds) -> Option<f64>| {
        parts
            .iter()
            .map(|p| f(&p.report.seconds.phases))
            .sum::<Option<f64>>()
    };
    let phases = &mut report.seconds.phases;
    phases.cubemap_build_and_lookup = phase(|p| p.cubemap_build_and_lookup);
    phases.cubemap_build = phase(|p| p.cubemap_build);
    phases.cubemap_lookup = phase(|p| p.cubemap_lookup);
    phases.gather = phase(|p| p.gather);
    phases.photon_trace = phase(|p| p.photon_trace);
    phases.photon_index = phase(|p| p.photon_index);
    phases.gpu_upload = phase(|p| p.gpu_upload);
    phases.gpu_trace = phase(|p| p.gpu_trace);
    phases.gpu_readback = phase(|p| p.gpu_readback);
    if let Some(cubemap) = &mut report.details.cubemap {
        let count = |f: fn(&CubemapDetails) -> u64| {
            parts
                .iter()
                .map(|p| p.report.details.cubemap.as_ref().map_or(0, f))
                .sum::<u64>()
        };
        cubemap.texels_rasterised = count(|c| c.texels_rasterised);
        cubemap.lookups = count(|c| c.lookups);
        cubemap.escaped_lookups = count(|c| c.escaped_lookups);
    }
    if let Some(photon) = &mut report.details.photon {
        photon.holes = parts
            .iter()
            .map(|p| p.report.details.photon.as_ref().map_or(0, |d| d.holes))
            .sum();
        // Queries per second of the whole gather: each part's queries over all its seconds.
        let (queries, gather_seconds) = parts
            .iter()
            .filter_map(|p| Some((p.report.details.photon.as_ref()?, p.report.seconds.phases.gather?)))
            .fold((0.0, 0.0), |(q, s), (d, g)| {
                (q + d.gather_queries_per_s * g, s + g)
            });
        if gather_seconds > 0.0 {
            photon.gather_queries_per_s = queries / gather_seconds;
        }
    }
    // Means over the image's surface pixels, not shard 0's.
    let surface: Vec<f64> = parts
        .iter()
        .enumerate()
        .map(|(index, p)| {
            let shard = Shard::new(index as u32, reference.count)?;
            let rows = (0..height).filter(|&r| shard.has_row(r)).count() as u64;
            Ok((rows * width as u64).saturating_sub(p.report.background_pixels as u64) as f64)
        })
        .collect::<Result<_>>()?;
    report.details.mean_rays_per_pixel = parts
        .iter()
        .zip(&surface)
        .map(|(p, surface)| Some(p.report.details.mean_rays_per_pixel? * surface))
        .sum::<Option<f64>>()
        .map(|rays| rays / surface.iter().sum::<f64>().max(1.0));
    // What must be the same in every part to be the image's; where it is not, null.
    if parts
        .iter()
        .any(|p| p.report.details.device != report.details.device)
    {
        report.details.device = None;
    }
    let radius = |r: &RenderReport| r.details.ao_radius.map(f32::to_bits);
    if parts.iter().any(|p| radius(&p.report) != radius(&report)) {
        report.details.ao_radius = None;
    }
    report.details.grays_per_s = report
        .rays_cast
        .zip(report.seconds.phases.gpu_trace)
        .filter(|_| report.details.grays_per_s.is_some())
        .map(|(rays, seconds)| rays as f64 / seconds.max(1e-9) / 1e9);
    let ray_seconds: f64 = parts.iter().map(|p| p.report.seconds.estimate).sum();
    report.mrays_per_s = report.rays_cast.map(|r| r as f64 / ray_seconds.max(1e-9) / 1e6);
    report.shard = None;
    report.shards = Some(
        parts
            .iter()
            .enumerate()
            .map(|(i, p)| ShardTiming {
                index: i as u32,
                seconds: seconds(p),
                rays_cast: p.report.rays_cast,
            })
            .collect(),
    );
    Ok(Rendered { image, aovs, report })
}
