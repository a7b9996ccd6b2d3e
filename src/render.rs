//! The render driver: scene → BVH → primary hits → estimator → image and report (spec §2, §7).
//!
//! It owns the loops over pixels: primary rays, then the estimator's pixels, rows in
//! parallel, with progress, ray and hole counts and timings; an estimator implements one
//! pixel ([`crate::estimators::PixelWorker`]). The output depends only on (scene, camera,
//! method, parameters, seed): never on `threads`. Progress is counted in surface pixels (or in
//! the work's own steps, such as gather's rays), so a slow row or pixel still moves the bar; every loop stops early, with [`Error::Interrupted`], once
//! [`crate::interrupt::request`] is called.

use std::time::Instant;

use rayon::prelude::*;

use crate::accel::Hit;
use crate::accel::{Accel, BuildQuality, RayCaster};
use crate::denoise::{Guide, GUIDE_CHANNELS};
use crate::error::{Error, Result};
pub use crate::estimators::pass::estimate;
use crate::estimators::Samples;
use crate::estimators::{
    Aov, AovImage, AovSample, DistanceClamp, Estimate, EstimateContext, Estimator, GBuffer,
};
use crate::image::HmdImage;
use crate::options::in_pool;
pub use crate::options::{RenderOptions, DEFAULT_SEED, DEFAULT_SIZE, MAX_PIXELS};
use crate::progress::Progress;
use crate::report::{BoundsReport, CameraReport, LightReport, RenderReport, Seconds};
use crate::report::{Details, RenderKey, ShardReport};
use crate::scene::{Bounds, Scene};

/// An HMD image and its report (spec §7).
pub struct Rendered {
    /// H per pixel.
    pub image: HmdImage,
    /// The AOVs asked for, in that order.
    pub aovs: Vec<AovImage>,
    /// Parameters, statistics and timings; `seconds.load` is 0 until the caller that loaded
    /// the scene adds it ([`RenderReport::add_load_seconds`]).
    pub report: RenderReport,
    /// A shard's part of a denoised render: the filter's guide, for `merge` to filter the
    /// joined image with (the part's `image` is then its own rays' H); `None` otherwise.
    pub guide: Option<Guide>,
}

impl Rendered {
    /// The EXR of the image and its AOVs, the image's channel named as the report names it
    /// (`Y` for H, `E` for irradiance); `path` names the file in errors.
    pub fn exr(&self, path: &std::path::Path) -> Result<Vec<u8>> {
        let channel = self
            .report
            .channels
            .first()
            .map_or(crate::image::exr::CHANNEL, String::as_str);
        let guide = self.guide.as_ref().map(Guide::channels).unwrap_or_default();
        let extra: Vec<(&str, &[f32])> = GUIDE_CHANNELS
            .iter()
            .copied()
            .zip(guide.iter().map(|c| &c[..]))
            .collect();
        crate::image::exr::encode_with(channel, &self.image, &self.aovs, &extra, path)
    }

    /// The channels a shard's rows hash covers: H, the AOVs, and the guide where there is one.
    pub fn hashed_channels<'a>(
        image: &'a HmdImage,
        aovs: &'a [AovImage],
        guide: &'a [Vec<f32>],
    ) -> Vec<&'a [f32]> {
        std::iter::once(&image.data[..])
            .chain(aovs.iter().map(|a| &a.data[..]))
            .chain(guide.iter().map(|c| &c[..]))
            .collect()
    }
}

/// Memory a render of `pixels` pixels with `aovs` AOV channels holds at its peak: the
/// G-buffer, H, the AOV samples and the encoded EXR's channels.
pub fn image_bytes(pixels: u64, aovs: usize) -> u128 {
    let samples = if aovs == 0 { 0 } else { size_of::<AovSample>() };
    let per_pixel = size_of::<Option<Hit>>() + 4 + samples + 2 * 4 * (1 + aovs);
    pixels as u128 * per_pixel as u128
}

/// Renders `scene` with `estimator`. A request whose image or BVH would not fit in the memory
/// available is refused before anything is allocated ([`crate::memory`]).
pub fn render(
    scene: &Scene,
    estimator: &dyn Estimator,
    options: &RenderOptions,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let mut rendered = render_outputs(scene, &[estimator], options, |context, gbuffer| {
        let start = Instant::now();
        let estimate = estimate(estimator, context, gbuffer, progress)?;
        Ok(vec![(estimate, start.elapsed().as_secs_f64())])
    })?;
    Ok(rendered.remove(0))
}

/// Renders `scene` once for several `estimators` that share the BVH, the primary hits and
/// the seed (built for the one that casts the most rays): `pass` makes every estimator's
/// [`Estimate`] and its seconds, in order, from the one context and G-buffer; each comes back
/// with its own report, as [`render`] would write it for that estimator alone (but for its
/// timings). A multi-output pass ([`crate::estimators::cubemap::sweep`]) uses it.
pub fn render_outputs(
    scene: &Scene,
    estimators: &[&dyn Estimator],
    options: &RenderOptions,
    pass: impl FnOnce(&EstimateContext, &GBuffer) -> Result<Vec<(Estimate, f64)>> + Send,
) -> Result<Vec<Rendered>> {
    options.validate()?;
    scene.validate()?;
    for estimator in estimators {
        if let Some(aov) = options.aovs.iter().find(|a| !estimator.aovs().contains(a)) {
            let message = format!("{} is not measured by {}", aov.name(), estimator.method());
            return Err(Error::invalid("aov", message));
        }
        if options.denoise.is_some() {
            check_denoise(*estimator, &options.aovs)?;
        }
    }
    let pixels = options.width as u64 * options.height as u64;
    let what = format!("{}x{}", options.width, options.height);
    // The denoiser's guide (7 channels) and its two passes' state (10 floats each).
    let channels = options.aovs.len() + if options.denoise.is_some() { 14 } else { 0 };
    let needed = image_bytes(pixels, channels) * estimators.len() as u128;
    crate::memory::check(Some("size"), &what, needed, None)?;
    in_pool(options.threads, || {
        render_in_pool(scene, estimators, options, pass)
    })?
}

/// Refuses `--denoise` for an estimator whose pixels are not means of their own rays, and
/// beside the `relerr` AOV, naming why.
fn check_denoise(estimator: &dyn Estimator, aovs: &[Aov]) -> Result<()> {
    if let Samples::Unsuited(why) = estimator.samples() {
        let message = format!("cannot filter {}: {why}", estimator.method());
        return Err(Error::invalid("denoise", message));
    }
    if aovs.contains(&Aov::Relerr) {
        let message = "cannot go with the relerr AOV: relerr is the error bar of a pixel's own rays, \
                       and a filtered pixel's error is mostly the filter's bias, which no per-pixel \
                       figure measures (render without --denoise for relerr)";
        return Err(Error::invalid("denoise", message));
    }
    Ok(())
}

/// The AOVs the estimators measure for `options`: those asked for, and `rays` where the
/// denoiser needs each pixel's ray count.
fn measured_aovs(estimators: &[&dyn Estimator], options: &RenderOptions) -> Vec<Aov> {
    let mut aovs = options.aovs.clone();
    let per_pixel = estimators.iter().any(|e| e.samples() == Samples::PerPixel);
    if options.denoise.is_some() && per_pixel && !aovs.contains(&Aov::Rays) {
        aovs.push(Aov::Rays);
    }
    aovs
}

fn render_in_pool(
    scene: &Scene,
    estimators: &[&dyn Estimator],
    options: &RenderOptions,
    pass: impl FnOnce(&EstimateContext, &GBuffer) -> Result<Vec<(Estimate, f64)>>,
) -> Result<Vec<Rendered>> {
    let pixels = options.width as u64 * options.height as u64;
    let expected = estimators
        .iter()
        .map(|e| e.expected_rays(pixels))
        .max()
        .unwrap_or(0);
    let start = Instant::now();
    let (accel, bvh) = Accel::for_work(
        &scene.mesh,
        options.bvh_quality,
        pixels + expected,
        options.kernel,
    )?;
    let accel_build = start.elapsed().as_secs_f64();
    crate::interrupt::check()?;

    let primary_start = Instant::now();
    let (gbuffer, background) = primary_pass(&accel, scene, options);
    let primary = primary_start.elapsed().as_secs_f64();
    crate::interrupt::check()?;

    let bounds = scene.bounds();
    let aovs = measured_aovs(estimators, options);
    let context = EstimateContext {
        accel: &accel,
        scene,
        seed: options.seed,
        clamp: DistanceClamp::for_diagonal(bounds.diagonal(), options.max_distance),
        aovs: &aovs,
        whole_image: options.shard.is_none(),
        bvh,
    };
    let setup = Setup {
        bounds,
        bvh,
        background,
        accel_build,
        primary,
        seconds: start.elapsed().as_secs_f64(),
        d_min: context.clamp.min,
        // The scene's content hash, for the shard reports: hashed once, not per output.
        scene_content: options.shard.map(|_| scene.fingerprint()),
    };
    let estimates = pass(&context, &gbuffer)?;
    estimators
        .iter()
        .zip(estimates)
        .map(|(estimator, (estimate, seconds))| {
            let (estimate, denoised) = denoise(*estimator, estimate, &gbuffer, options)?;
            Ok(output(
                scene, options, &setup, *estimator, estimate, seconds, denoised,
            ))
        })
        .collect()
}

/// The denoiser's part of one output: the report's `denoise`, and a shard's guide.
struct Denoised {
    report: Option<crate::report::DenoiseReport>,
    guide: Option<Guide>,
}

/// `estimate` filtered as `options.denoise` says (a whole image), or with the guide a shard's
/// part carries for `merge`; the `rays` AOV taken out again where only the filter wanted it.
fn denoise(
    estimator: &dyn Estimator,
    mut estimate: Estimate,
    gbuffer: &GBuffer,
    options: &RenderOptions,
) -> Result<(Estimate, Denoised)> {
    let Some(params) = options.denoise else {
        return Ok((
            estimate,
            Denoised {
                report: None,
                guide: None,
            },
        ));
    };
    let start = Instant::now();
    let samples = match estimator.samples() {
        Samples::Fixed(n) => vec![n as f32; estimate.hmd.len()],
        Samples::PerPixel => {
            let rays = estimate.aovs.iter().position(|a| a.aov == Aov::Rays);
            let rays = rays.expect("the rays AOV is measured for the denoiser");
            if options.aovs.contains(&Aov::Rays) {
                estimate.aovs[rays].data.clone()
            } else {
                estimate.aovs.remove(rays).data
            }
        }
        Samples::Unsuited(_) => unreachable!("refused before the render"),
    };
    let guide = guide_of(gbuffer, samples);
    let filtered = options.shard.is_none();
    if filtered {
        estimate.hmd = crate::denoise::filter(&estimate.hmd, &guide, &params);
    }
    let report = crate::report::DenoiseReport {
        params,
        filtered,
        seconds: start.elapsed().as_secs_f64(),
    };
    let guide = (!filtered).then_some(guide);
    Ok((
        estimate,
        Denoised {
            report: Some(report),
            guide,
        },
    ))
}

/// The denoiser's guide of an image of `scene` rendered earlier at `width × height` through
/// a BVH of preset `bvh` (the one its report names: at exact ties another preset's primary
/// hits can differ), with `samples` rays per pixel: with it, [`crate::denoise::filter`] filters
/// that image bit for bit as `render` with [`RenderOptions::denoise`] would have.
pub fn guide(
    scene: &Scene,
    (width, height): (u32, u32),
    bvh: BuildQuality,
    samples: Vec<f32>,
) -> Result<Guide> {
    RenderOptions {
        width,
        height,
        ..RenderOptions::default()
    }
    .validate()?;
    if samples.len() != width as usize * height as usize {
        return Err(Error::parameter(format!(
            "{} ray counts for {width}x{height} pixels",
            samples.len()
        )));
    }
    scene.validate()?;
    let (accel, _) = Accel::for_work(&scene.mesh, bvh, 0, crate::accel::Kernel::best())?;
    Ok(guide_of(&primary_hits(&accel, scene, width, height), samples))
}

/// The denoiser's guide from the G-buffer (points and camera-facing normals, NaN for
/// background) and each pixel's ray count.
fn guide_of(gbuffer: &GBuffer, samples: Vec<f32>) -> Guide {
    let none = glam::Vec3::NAN;
    Guide {
        width: gbuffer.width,
        height: gbuffer.height,
        points: gbuffer
            .points
            .iter()
            .map(|p| p.as_ref().map_or(none, |h| h.point))
            .collect(),
        normals: gbuffer
            .points
            .iter()
            .map(|p| p.as_ref().map_or(none, |h| h.normal))
            .collect(),
        samples,
    }
}

/// The primary hits of the rows `options` renders (a shard's, or all), and how many of those
/// rows' pixels are background.
fn primary_pass(accel: &Accel, scene: &Scene, options: &RenderOptions) -> (GBuffer, usize) {
    let shard = options.shard;
    let gbuffer = primary_hits_where(accel, scene, options.width, options.height, |row| {
        shard.is_none_or(|s| s.has_row(row))
    });
    let background = gbuffer
        .points
        .chunks(options.width as usize)
        .enumerate()
        .filter(|(row, _)| shard.is_none_or(|s| s.has_row(*row as u32)))
        .map(|(_, points)| points.iter().filter(|p| p.is_none()).count())
        .sum();
    (gbuffer, background)
}

/// What every output of one pass shares: the scene's bounds, the BVH preset built, the
/// background pixels, the set-up's seconds (BVH, primary rays, both), the distance clamp's
/// floor, and the scene's content hash where the render is a shard.
struct Setup {
    bounds: Bounds,
    bvh: BuildQuality,
    background: usize,
    accel_build: f64,
    primary: f64,
    seconds: f64,
    d_min: f32,
    scene_content: Option<u64>,
}

/// One output of the pass: `estimator`'s image, AOVs and report, from its `estimate` that
/// took `estimate_seconds` after the shared `setup`.
fn output(
    scene: &Scene,
    options: &RenderOptions,
    setup: &Setup,
    estimator: &dyn Estimator,
    estimate: Estimate,
    estimate_seconds: f64,
    denoised: Denoised,
) -> Rendered {
    let denoise_seconds = denoised.report.map_or(0.0, |d| d.seconds);
    let bounds = &setup.bounds;
    let parameters = estimator.parameters();
    let mut report = RenderReport {
        hmdist_version: env!("CARGO_PKG_VERSION").into(),
        method: estimator.method().into(),
        scene: scene.name.clone(),
        width: options.width,
        height: options.height,
        seed: options.seed,
        threads: rayon::current_num_threads(),
        kernel: options.kernel.name().into(),
        bvh: setup.bvh.name().into(),
        max_distance: options.max_distance,
        triangles: scene.mesh.triangle_count(),
        l_diag: bounds.diagonal(),
        d_min: setup.d_min,
        bounds: BoundsReport::from(bounds),
        camera: CameraReport::from(&scene.camera),
        light: scene.light.as_ref().map(LightReport::from),
        display_scale: scene.display_scale,
        background_pixels: setup.background,
        rays_cast: estimate.rays.map(|r| r.cast),
        escaped_rays: estimate.rays.map(|r| r.escaped),
        mrays_per_s: estimate.rays.map(|r| r.cast as f64 / r.seconds.max(1e-9) / 1e6),
        seconds: Seconds {
            load: 0.0,
            accel_build: setup.accel_build,
            primary: setup.primary,
            estimate: estimate_seconds,
            // The shared set-up (BVH, primary rays), this output's own estimate and filter.
            total: setup.seconds + estimate_seconds + denoise_seconds,
            phases: estimate.phases,
        },
        channels: std::iter::once(estimator.channel())
            .chain(options.aovs.iter().map(|a| a.name()))
            .map(String::from)
            .collect(),
        shard: options
            .shard
            .zip(setup.scene_content)
            .map(|(s, content)| ShardReport {
                index: s.index,
                count: s.count,
                legacy_fingerprint: legacy_fingerprint(scene, content, estimator, options),
                key: Some(render_key(
                    scene,
                    content,
                    estimator,
                    options,
                    setup.bvh,
                    &estimate.details,
                )),
                rows_hash: None,
            }),
        shards: None,
        rays: parameters.number("rays").map(|rays| rays as u32),
        parameters,
        denoise: denoised.report,
        details: estimate.details,
    };
    let image = HmdImage::new(options.width, options.height, estimate.hmd);
    if let (Some(part), Some(shard)) = (report.shard.as_mut(), options.shard) {
        let guide = denoised.guide.as_ref().map(Guide::channels).unwrap_or_default();
        let channels = Rendered::hashed_channels(&image, &estimate.aovs, &guide);
        part.rows_hash = Some(shard.rows_hash(image.width, &channels));
    }
    Rendered {
        image,
        aovs: estimate.aovs,
        report,
        guide: denoised.guide,
    }
}

/// The fingerprint shard reports carried before they carried a [`RenderKey`] (still
/// written, for `merge` to read beside old parts): a hash of the scene (name
/// and content), the method and its parameters, size, seed, distance clamp, AOVs and version.
/// It holds fewer fields than the [`RenderKey`] and keeps its first form, so that `merge` can
/// still join a part written before keys existed (which it compares by fingerprint) with
/// parts written after: an experiment's image rendered in parts over several sessions may
/// have both.
/// `scene_content` is [`Scene::fingerprint`].
fn legacy_fingerprint(
    scene: &Scene,
    scene_content: u64,
    estimator: &dyn Estimator,
    options: &RenderOptions,
) -> String {
    let parameters = serde_json::to_string(&estimator.parameters()).expect("parameters serialise");
    let key = format!(
        "{}|{}|{:016x}|{}|{parameters}|{}x{}|{}|{:?}|{:?}",
        env!("CARGO_PKG_VERSION"),
        scene.name,
        scene_content,
        estimator.method(),
        options.width,
        options.height,
        options.seed,
        options.max_distance.map(f32::to_bits),
        options.aovs,
    );
    format!("{:016x}", crate::scene::stable_hash(key.as_bytes()))
}

/// The key of `scene` rendered by `estimator` with `options` through BVH preset `bvh`
/// (resolved), whose estimate reported `details` (where it ran, the `ao` radius);
/// `scene_content` is [`Scene::fingerprint`]. The same [`RenderKey`] names an image in the
/// experiment cache (with the backend and preset as asked for) and checks a photon map file
/// (with what the map depends on), by its [`RenderKey::digest`].
fn render_key(
    scene: &Scene,
    scene_content: u64,
    estimator: &dyn Estimator,
    options: &RenderOptions,
    bvh: BuildQuality,
    details: &Details,
) -> RenderKey {
    let device = details.device.as_ref();
    RenderKey::new(
        (&scene.name, scene_content),
        (estimator.method(), estimator.parameters()),
        bvh.name(),
        options.key_image(),
    )
    .on(
        device.map_or("cpu", |d| d.backend.as_str()),
        device.and_then(|d| d.adapter_class.clone()),
    )
    .with_ao_radius(details.ao_radius)
}

/// Each pixel's first hit along its camera ray (spec §2), normal flipped to face the camera.
pub fn primary_hits(accel: &impl RayCaster, scene: &Scene, width: u32, height: u32) -> GBuffer {
    primary_hits_where(accel, scene, width, height, |_| true)
}

/// [`primary_hits`] in the rows `rows` says yes to; the others are left background.
pub fn primary_hits_where(
    accel: &impl RayCaster,
    scene: &Scene,
    width: u32,
    height: u32,
    rows: impl Fn(u32) -> bool + Sync,
) -> GBuffer {
    let camera = scene.camera.rays(width, height);
    let points = (0..width as u64 * height as u64)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % width as u64) as u32, (i / width as u64) as u32);
            if !rows(y) || crate::interrupt::requested() {
                return None;
            }
            let dir = camera.pixel_direction(x, y);
            accel
                .closest_hit(camera.eye(), dir, f32::INFINITY, None)
                .map(|mut hit| {
                    if hit.normal.dot(dir) > 0.0 {
                        hit.normal = -hit.normal;
                    }
                    hit
                })
        })
        .collect();
    GBuffer {
        width,
        height,
        points,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_needs_its_g_buffer_and_channels() {
        let one = image_bytes(1, 0);
        assert!(one >= size_of::<Option<Hit>>() as u128 + 4, "{one}");
        assert_eq!(image_bytes(1000, 0), 1000 * one);
        assert!(image_bytes(1, 2) > one + 2 * 4);
    }
}
