//! Shards: one render split over machines, merged into exactly the image one machine makes.
//!
//! Shard `K/M` renders the rows `r` with `r mod M = K` (interleaved, so every shard gets its
//! share of cheap and expensive rows); its EXR is full size with the other rows NaN. Random
//! numbers are keyed by (seed, pixel, ray) and the BVH preset is chosen for the whole image,
//! so a shard's pixels equal the one-machine render's. A shard's report carries the render's
//! key ([`crate::report::RenderKey`]: the scene's content, camera and light, the method and
//! its parameters, the backend and adapter class it ran on, the BVH preset, size, seed,
//! distance clamp, AOVs with the `ao` radius, and hmdist's version) and the older fingerprint;
//! [`merge`] refuses parts whose keys differ (naming the fields), a missing or repeated
//! shard, and writes the merged report's sums of rays, escapes and seconds with each shard's
//! timings.

use crate::denoise::Guide;
use crate::error::{Error, Result};
use crate::estimators::AovImage;
use crate::image::HmdImage;
pub use crate::options::Shard;
use crate::render::Rendered;
use crate::report::{CubemapDetails, PhaseSeconds, RenderReport, Seconds};
pub use crate::report::{ShardReport, ShardTiming};

/// One shard's output, as read back from its files.
pub struct Part {
    /// H, full size, NaN outside the shard's rows.
    pub image: HmdImage,
    /// Its AOVs, in the report's channel order.
    pub aovs: Vec<AovImage>,
    /// Its report, with its [`ShardReport`].
    pub report: RenderReport,
    /// The denoiser's guide, in a part of a denoised render ([`crate::denoise`]).
    pub guide: Option<Guide>,
}

/// The one-machine image and report from every shard's part, in any order: the parts put in
/// shard order and checked to be one render's, each EXR checked against its JSON, the rows
/// joined, and the reports summed into the image's.
///
/// Parts of a denoised render carry their own rays' H and the filter's guide: the joined
/// image is filtered here, as the one machine filters its image, so the bits are the same.
pub fn merge(parts: Vec<Part>) -> Result<Rendered> {
    let parts = in_shard_order(parts)?;
    let count = parts.len() as u32;
    check_rows(&parts)?;
    let (mut image, aovs, guide) = join_rows(&parts)?;
    let mut report = merged_report(&parts, count, image.width, image.height)?;
    if let Some(denoise) = report.denoise.as_mut().filter(|d| !d.filtered) {
        let guide = guide
            .ok_or_else(|| Error::parameter("the parts of a denoised render lack their guide channels"))?;
        let start = std::time::Instant::now();
        image.data = crate::denoise::filter(&image.data, &guide, &denoise.params);
        denoise.filtered = true;
        denoise.seconds = start.elapsed().as_secs_f64();
        report.seconds.total += denoise.seconds;
    }
    Ok(Rendered {
        image,
        aovs,
        report,
        guide: None,
    })
}

/// `parts` in shard order, one of each shard of one render; refused (naming what is wrong)
/// where a part is no shard, of another render, repeated or missing.
fn in_shard_order(parts: Vec<Part>) -> Result<Vec<Part>> {
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
        if let Some(message) = not_one_render(&reference, &shard) {
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
    Ok(slots.into_iter().flatten().collect())
}

/// Refuses a part whose EXR is not the image its JSON describes: another size, or rows that
/// hash differently from the hash the shard recorded.
fn check_rows(parts: &[Part]) -> Result<()> {
    let count = parts.len() as u32;
    for (index, part) in parts.iter().enumerate() {
        let shard = Shard::new(index as u32, count)?;
        let r = &part.report;
        let what = format!("shard {index}/{}'s EXR", count);
        if (part.image.width, part.image.height) != (r.width, r.height) {
            return Err(Error::parameter(format!(
                "{what} is {}x{}, its report says {}x{}: the EXR is not the image its JSON describes",
                part.image.width, part.image.height, r.width, r.height
            )));
        }
        let expected = r.shard.as_ref().and_then(|s| s.rows_hash.as_deref());
        let guide = part.guide.as_ref().map(Guide::channels).unwrap_or_default();
        let channels = Rendered::hashed_channels(&part.image, &part.aovs, &guide);
        if expected.is_some_and(|h| h != shard.rows_hash(part.image.width, &channels)) {
            return Err(Error::parameter(format!(
                "{what} is not the image its JSON describes (its rows hash differently): was it replaced, swapped or edited?"
            )));
        }
    }
    Ok(())
}

/// H, the AOVs and the denoiser's guide (where the parts have one) with each shard's rows
/// from its part.
fn join_rows(parts: &[Part]) -> Result<(HmdImage, Vec<AovImage>, Option<Guide>)> {
    let count = parts.len() as u32;
    let (width, height) = (parts[0].image.width, parts[0].image.height);
    let mut image = parts[0].image.clone();
    let mut aovs = parts[0].aovs.clone();
    let mut guide = parts[0].guide.clone();
    for (index, part) in parts.iter().enumerate() {
        let shard = Shard::new(index as u32, count)?;
        if part.guide.is_some() != guide.is_some() {
            return Err(Error::parameter(format!(
                "shard {index}/{count} {} the denoiser's guide channels and shard 0/{count} {}",
                if part.guide.is_some() { "has" } else { "lacks" },
                if guide.is_some() { "has them" } else { "does not" },
            )));
        }
        for row in (0..height).filter(|&r| shard.has_row(r)) {
            let range = (row * width) as usize..((row + 1) * width) as usize;
            image.data[range.clone()].copy_from_slice(&part.image.data[range.clone()]);
            for (merged, own) in aovs.iter_mut().zip(&part.aovs) {
                merged.data[range.clone()].copy_from_slice(&own.data[range.clone()]);
            }
            if let (Some(merged), Some(own)) = (guide.as_mut(), part.guide.as_ref()) {
                merged.points[range.clone()].copy_from_slice(&own.points[range.clone()]);
                merged.normals[range.clone()].copy_from_slice(&own.normals[range.clone()]);
                merged.samples[range.clone()].copy_from_slice(&own.samples[range.clone()]);
            }
        }
    }
    Ok((image, aovs, guide))
}

/// The image's report from the parts' (shard order, `count` of them, `width` × `height`):
/// sums of rays, escapes, seconds, photon holes and cube-map counts, means over the image's
/// surface pixels, `null` where the parts disagree, and each shard's timings.
fn merged_report(parts: &[Part], count: u32, width: u32, height: u32) -> Result<RenderReport> {
    let mut report = parts[0].report.clone();
    let sum = |f: fn(&RenderReport) -> Option<u64>| parts.iter().map(|p| f(&p.report)).sum::<Option<u64>>();
    report.rays_cast = sum(|r| r.rays_cast);
    report.escaped_rays = sum(|r| r.escaped_rays);
    report.background_pixels = parts.iter().map(|p| p.report.background_pixels).sum();
    report.seconds = summed_seconds(parts);
    merge_method_details(&mut report, parts);
    let seconds = |p: &Part| p.report.seconds.total;
    // Means over the image's surface pixels, not shard 0's.
    let surface: Vec<f64> = parts
        .iter()
        .enumerate()
        .map(|(index, p)| {
            let shard = Shard::new(index as u32, count)?;
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
    Ok(report)
}

/// The parts' seconds, each phase summed (`null` where a part lacks it).
fn summed_seconds(parts: &[Part]) -> Seconds {
    let mut seconds = parts[0].report.seconds.clone();
    seconds.total = parts.iter().map(|p| p.report.seconds.total).sum();
    seconds.estimate = parts.iter().map(|p| p.report.seconds.estimate).sum();
    seconds.primary = parts.iter().map(|p| p.report.seconds.primary).sum();
    seconds.accel_build = parts.iter().map(|p| p.report.seconds.accel_build).sum();
    seconds.load = parts.iter().map(|p| p.report.seconds.load).sum();
    let phase = |f: fn(&PhaseSeconds) -> Option<f64>| {
        parts
            .iter()
            .map(|p| f(&p.report.seconds.phases))
            .sum::<Option<f64>>()
    };
    let phases = &mut seconds.phases;
    phases.cubemap_build_and_lookup = phase(|p| p.cubemap_build_and_lookup);
    phases.cubemap_build = phase(|p| p.cubemap_build);
    phases.cubemap_lookup = phase(|p| p.cubemap_lookup);
    phases.gather = phase(|p| p.gather);
    phases.photon_trace = phase(|p| p.photon_trace);
    phases.photon_index = phase(|p| p.photon_index);
    phases.gpu_upload = phase(|p| p.gpu_upload);
    phases.gpu_trace = phase(|p| p.gpu_trace);
    phases.gpu_readback = phase(|p| p.gpu_readback);
    seconds
}

/// The cube map's counts and the photon methods' holes summed over the parts, and the photon
/// gather's queries per second over all their seconds.
fn merge_method_details(report: &mut RenderReport, parts: &[Part]) {
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
}

/// Why shards `a` and `b` are not parts of one render, or `None` where they are: a different
/// shard count, or keys that differ (named field by field); parts whose reports predate keys
/// are compared by fingerprint.
fn not_one_render(a: &ShardReport, b: &ShardReport) -> Option<String> {
    let (ia, ib) = (
        format!("{}/{}", a.index, a.count),
        format!("{}/{}", b.index, b.count),
    );
    if a.count != b.count {
        return Some(format!(
            "the parts are not of one render: shard {ia} and shard {ib} split it differently"
        ));
    }
    let differences = match (&a.key, &b.key) {
        // The fingerprint is compared too: it goes into the merged report.
        (Some(ka), Some(kb)) if a.legacy_fingerprint == b.legacy_fingerprint => ka.differences(kb),
        (Some(ka), Some(kb)) if ka == kb => vec![format!(
            "fingerprint ({} against {}), though their keys agree: a report was edited",
            a.legacy_fingerprint, b.legacy_fingerprint
        )],
        (Some(ka), Some(kb)) => ka.differences(kb),
        _ if a.legacy_fingerprint == b.legacy_fingerprint => vec![],
        _ => vec![format!(
            "fingerprint ({} against {}: scene, camera, method, parameters, size, seed, clamp, AOVs or \
             version)",
            a.legacy_fingerprint, b.legacy_fingerprint
        )],
    };
    (!differences.is_empty()).then(|| {
        format!(
            "the parts are not of one render: shard {ia} and shard {ib} differ in {}",
            differences.join(", ")
        )
    })
}
