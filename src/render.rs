//! The render driver: scene → BVH → primary hits → estimator → image and report (SPEC §2, §7).
//!
//! It owns the loops over pixels: primary rays, then the estimator's pixels, rows in
//! parallel, with progress, ray and hole counts and timings; an estimator implements one
//! pixel ([`crate::estimators::PixelWorker`]). The output depends only on (scene, camera,
//! method, parameters, seed): never on `threads`. Progress is counted in surface pixels (or in
//! the work's own steps, such as gather's rays), so a slow row or pixel still moves the bar; every loop stops early, with [`Error::Interrupted`], once
//! [`crate::interrupt::request`] is called.

use std::time::Instant;

use rayon::prelude::*;

use crate::accel::{Accel, BuildQuality, Kernel, RayCaster};
use crate::error::{Error, Result};
use crate::estimators::{
    Aov, AovImage, AovSample, DistanceClamp, Estimate, EstimateContext, Estimator, GBuffer, PixelPass,
    PixelWork, PixelWorker, RayCount, Tally, Work,
};
use crate::image::HmdImage;
use crate::progress::Progress;
use crate::report::{BoundsReport, CameraReport, LightReport, RenderReport, Seconds};
use crate::scene::Scene;
use crate::shard::{Shard, ShardReport};

/// Default image size (SPEC §2).
pub const DEFAULT_SIZE: (u32, u32) = (1024, 1024);
/// Default seed of the counter-based random numbers.
pub const DEFAULT_SEED: u64 = 1;
/// Largest image accepted: 64 M pixels (the G-buffer alone then takes about 3 GB).
pub const MAX_PIXELS: u64 = 1 << 26;

/// How to render, apart from the estimator and its parameters. Checked by [`render`]
/// ([`RenderOptions::validate`]).
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of the counter-based random numbers.
    pub seed: u64,
    /// Worker threads; `None` uses every core. Never changes the output.
    pub threads: Option<usize>,
    /// Clamp distances (and count escapes) at this value; `None` for no clamp.
    pub max_distance: Option<f32>,
    /// The BVH preset.
    pub bvh_quality: BuildQuality,
    /// AOVs to measure beside H, each an EXR channel (SPEC §8).
    pub aovs: Vec<Aov>,
    /// Render only this shard's rows ([`crate::shard`]); `None` for the whole image.
    pub shard: Option<Shard>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            seed: DEFAULT_SEED,
            threads: None,
            max_distance: None,
            bvh_quality: BuildQuality::default(),
            aovs: vec![],
            shard: None,
        }
    }
}

impl RenderOptions {
    /// Refuses an empty or oversized image, a non-positive `max_distance` and zero threads.
    pub fn validate(&self) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            let message = format!("{w}x{h} is empty: width and height must be at least 1");
            return Err(Error::invalid("size", message));
        }
        if w as u64 * h as u64 > MAX_PIXELS {
            let message = format!("{w}x{h} exceeds the limit of {MAX_PIXELS} pixels");
            return Err(Error::invalid("size", message));
        }
        Error::check_positive("max_distance", self.max_distance)?;
        if self.threads == Some(0) {
            return Err(Error::invalid("threads", "must be at least 1, not 0"));
        }
        Ok(())
    }
}

/// Runs `f` on a pool of `threads` workers (`None`: every core).
pub(crate) fn in_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::parameter(format!("cannot start worker threads: {e}")))?;
    Ok(pool.install(f))
}

/// An HMD image and its report (SPEC §7).
pub struct Rendered {
    /// H per pixel.
    pub image: HmdImage,
    /// The AOVs asked for, in that order.
    pub aovs: Vec<AovImage>,
    /// Parameters, statistics and timings; `seconds.load` is 0 until the caller that loaded
    /// the scene adds it ([`RenderReport::add_load_seconds`]).
    pub report: RenderReport,
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
    }
    let pixels = options.width as u64 * options.height as u64;
    let what = format!("{}x{}", options.width, options.height);
    let needed = crate::memory::image_bytes(pixels, options.aovs.len()) * estimators.len() as u128;
    crate::memory::check(Some("size"), &what, needed, None)?;
    crate::memory::check_bvh(scene.mesh.triangle_count())?;
    in_pool(options.threads, || {
        render_in_pool(scene, estimators, options, pass)
    })?
}

fn render_in_pool(
    scene: &Scene,
    estimators: &[&dyn Estimator],
    options: &RenderOptions,
    pass: impl FnOnce(&EstimateContext, &GBuffer) -> Result<Vec<(Estimate, f64)>>,
) -> Result<Vec<Rendered>> {
    let kernel = Kernel::from_env()?;
    let pixels = options.width as u64 * options.height as u64;
    let expected = estimators
        .iter()
        .map(|e| e.expected_rays(pixels))
        .max()
        .unwrap_or(0);
    let bvh = options
        .bvh_quality
        .resolve(pixels + expected, scene.mesh.triangle_count());
    let start = Instant::now();
    let accel = Accel::build(&scene.mesh, bvh).with_kernel(kernel);
    let accel_build = start.elapsed().as_secs_f64();
    crate::interrupt::check()?;

    let primary_start = Instant::now();
    let shard = options.shard;
    let gbuffer = primary_hits_where(&accel, scene, options.width, options.height, |row| {
        shard.is_none_or(|s| s.has_row(row))
    });
    let background = gbuffer
        .points
        .chunks(options.width as usize)
        .enumerate()
        .filter(|(row, _)| shard.is_none_or(|s| s.has_row(*row as u32)))
        .map(|(_, points)| points.iter().filter(|p| p.is_none()).count())
        .sum();
    let primary = primary_start.elapsed().as_secs_f64();
    crate::interrupt::check()?;

    let bounds = scene.bounds();
    let l_diag = bounds.diagonal();
    let context = EstimateContext {
        accel: &accel,
        scene,
        seed: options.seed,
        clamp: DistanceClamp::for_diagonal(l_diag, options.max_distance),
        aovs: &options.aovs,
        whole_image: shard.is_none(),
        bvh,
    };
    let setup = start.elapsed().as_secs_f64();
    let estimates = pass(&context, &gbuffer)?;
    let camera = &scene.camera;
    let outputs = estimators
        .iter()
        .zip(estimates)
        .map(|(estimator, (estimate, estimate_seconds))| {
            let report = RenderReport {
                hmdist_version: env!("CARGO_PKG_VERSION").into(),
                method: estimator.method().into(),
                scene: scene.name.clone(),
                width: options.width,
                height: options.height,
                seed: options.seed,
                threads: rayon::current_num_threads(),
                kernel: kernel.name().into(),
                bvh: bvh.name().into(),
                max_distance: options.max_distance,
                triangles: scene.mesh.triangle_count(),
                l_diag,
                d_min: context.clamp.min,
                bounds: BoundsReport {
                    min: bounds.min.to_array(),
                    max: bounds.max.to_array(),
                },
                camera: CameraReport {
                    eye: camera.eye.to_array(),
                    target: camera.target.to_array(),
                    up: camera.up.to_array(),
                    fov_y_deg: camera.fov_y_deg,
                },
                light: scene.light.map(|l| LightReport {
                    position: l.position.to_array(),
                    direction: l.direction.to_array(),
                    cone_half_angle_deg: l.cone_half_angle_deg,
                }),
                display_scale: scene.display_scale,
                background_pixels: background,
                rays_cast: estimate.rays.map(|r| r.cast),
                escaped_rays: estimate.rays.map(|r| r.escaped),
                mrays_per_s: estimate.rays.map(|r| r.cast as f64 / r.seconds.max(1e-9) / 1e6),
                seconds: Seconds {
                    load: 0.0,
                    accel_build,
                    primary,
                    estimate: estimate_seconds,
                    // The shared set-up (BVH, primary rays) and this output's own estimate.
                    total: setup + estimate_seconds,
                    phases: estimate.phases,
                },
                channels: std::iter::once("Y")
                    .chain(options.aovs.iter().map(|a| a.name()))
                    .map(String::from)
                    .collect(),
                shard: shard.map(|s| ShardReport {
                    index: s.index,
                    count: s.count,
                    fingerprint: crate::shard::fingerprint(scene, *estimator, options),
                }),
                shards: None,
                parameters: estimator.parameters(),
                details: estimate.details,
            };
            Rendered {
                image: HmdImage::new(options.width, options.height, estimate.hmd),
                aovs: estimate.aovs,
                report,
            }
        });
    Ok(outputs.collect())
}

/// H per pixel of `gbuffer` by `estimator`: its preparation, then the driver's pixel loop (or
/// the whole image it estimated itself). Runs on the current rayon pool.
pub fn estimate(
    estimator: &dyn Estimator,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<Estimate> {
    Ok(match estimator.prepare(context, gbuffer, progress)? {
        Work::Done(estimate) => *estimate,
        Work::Pixels { work, phases, rays } => {
            let (hmd, aovs, pass) = pixel_pass(work.as_ref(), gbuffer, context.aovs, progress)?;
            let mut phases = phases;
            work.record_phase(&mut phases, pass.seconds);
            let pixel_rays = work.casts_rays().then_some(RayCount {
                cast: pass.tally.rays,
                escaped: pass.tally.escaped,
                seconds: pass.seconds,
            });
            Estimate {
                hmd,
                aovs,
                rays: rays.or(pixel_rays),
                phases,
                details: work.details(&pass),
            }
        }
    })
}

/// The driver's loop over the estimator's pixels: rows in parallel, one worker (with its
/// scratch) per rayon job, NaN for background, holes counted, the AOVs in `aovs` kept; progress
/// in surface pixels, or in [`PixelWork::progress_per_pixel`] steps each. The image does not depend on how rows are split among threads.
/// [`Error::Interrupted`] if [`crate::interrupt::request`] was called before it finished.
pub(crate) fn pixel_pass(
    work: &dyn PixelWork,
    gbuffer: &GBuffer,
    aovs: &[Aov],
    progress: &dyn Progress,
) -> Result<(Vec<f32>, Vec<AovImage>, PixelPass)> {
    let start = Instant::now();
    let width = gbuffer.width as usize;
    let mut hmd = vec![f32::NAN; gbuffer.points.len()];
    // Each pixel's AOVs, only where some are asked for.
    let mut samples = vec![AovSample::default(); if aovs.is_empty() { 0 } else { hmd.len() }];
    let per_pixel = work.progress_per_pixel();
    progress.start(work.label(), gbuffer.surface_pixels().saturating_mul(per_pixel));
    // The driver counts each pixel done, unless the workers count their own steps.
    let silent = crate::progress::Silent;
    let counted: &dyn Progress = if per_pixel == 1 { progress } else { &silent };
    let rows = hmd.par_chunks_mut(width).zip(gbuffer.points.par_chunks(width));
    let tally = if aovs.is_empty() {
        rows.enumerate()
            .map_init(
                || work.worker(progress),
                |worker, (row, (out, points))| {
                    pixel_row(worker.as_mut(), row * width, out, points, None, counted)
                },
            )
            .reduce(Tally::default, |a, b| a + b)
    } else {
        rows.zip(samples.par_chunks_mut(width))
            .enumerate()
            .map_init(
                || work.worker(progress),
                |worker, (row, ((out, points), samples))| {
                    let samples = Some(samples);
                    pixel_row(worker.as_mut(), row * width, out, points, samples, counted)
                },
            )
            .reduce(Tally::default, |a, b| a + b)
    };
    progress.finish();
    crate::interrupt::check()?;
    let pass = PixelPass {
        tally,
        pixels: gbuffer.surface_pixels(),
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((hmd, AovImage::channels(aovs, &samples), pass))
}

/// One row of the pixel pass, whose first pixel has index `first`; it stops early once an
/// interruption is requested.
fn pixel_row(
    worker: &mut dyn PixelWorker,
    first: usize,
    out: &mut [f32],
    points: &[Option<crate::accel::Hit>],
    mut samples: Option<&mut [AovSample]>,
    counted: &dyn Progress,
) -> Tally {
    let mut tally = Tally::default();
    let mut scratch = AovSample::default();
    for (x, (h, point)) in out.iter_mut().zip(points).enumerate() {
        if crate::interrupt::requested() {
            break;
        }
        if let Some(hit) = point {
            let aov = match samples.as_deref_mut() {
                Some(samples) => &mut samples[x],
                None => &mut scratch,
            };
            *h = worker.pixel(hit, (first + x) as u64, &mut tally, aov);
            tally.holes += h.is_nan() as u64;
            counted.advance(1);
        }
    }
    tally
}

/// Each pixel's first hit along its camera ray (SPEC §2), normal flipped to face the camera.
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
