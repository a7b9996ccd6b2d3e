//! The render driver: scene → BVH → primary hits → estimator → image and report (SPEC §2, §7).
//!
//! It owns the loop over pixels for primary rays and nothing else; the estimators own theirs.
//! The output depends only on (scene, camera, method, parameters, seed): never on `threads`.

use std::time::Instant;

use rayon::prelude::*;
use serde_json::{json, Value};

use crate::accel::{Accel, BuildQuality, Kernel, RayCaster};
use crate::error::{Error, Result};
use crate::estimators::{DistanceClamp, EstimateContext, Estimator, GBuffer};
use crate::image::HmdImage;
use crate::progress::Progress;
use crate::scene::Scene;

/// Default image size (SPEC §2).
pub const DEFAULT_SIZE: (u32, u32) = (1024, 1024);
/// Default seed of the counter-based random numbers.
pub const DEFAULT_SEED: u64 = 1;
/// Largest image accepted: 64 M pixels (the G-buffer alone then takes about 3 GB).
pub const MAX_PIXELS: u64 = 1 << 26;

/// How to render, apart from the estimator and its parameters.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    /// Worker threads; `None` uses every core. Never changes the output.
    pub threads: Option<usize>,
    /// `--max-distance`: clamp distances (and count escapes) at this value.
    pub max_distance: Option<f32>,
    pub bvh_quality: BuildQuality,
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
        }
    }
}

impl RenderOptions {
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::parameter(format!(
                "the image size {}x{} is empty: width and height must be at least 1",
                self.width, self.height
            )));
        }
        if self.width as u64 * self.height as u64 > MAX_PIXELS {
            return Err(Error::parameter(format!(
                "the image size {}x{} exceeds the limit of {MAX_PIXELS} pixels",
                self.width, self.height
            )));
        }
        if let Some(d) = self.max_distance {
            if d.is_nan() || d <= 0.0 {
                return Err(Error::parameter(format!(
                    "--max-distance must be positive, not {d}"
                )));
            }
        }
        if self.threads == Some(0) {
            return Err(Error::parameter("--threads must be at least 1"));
        }
        Ok(())
    }
}

/// An HMD image and its JSON report (SPEC §7 keys).
pub struct Rendered {
    pub image: HmdImage,
    pub report: Value,
}

/// Renders `scene` with `estimator`. `load_seconds` is how long loading the scene took, for
/// the report.
pub fn render(
    scene: &Scene,
    estimator: &dyn Estimator,
    options: &RenderOptions,
    load_seconds: f64,
    progress: &dyn Progress,
) -> Result<Rendered> {
    options.validate()?;
    scene.validate()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::parameter(format!("cannot start worker threads: {e}")))?;
    pool.install(|| render_in_pool(scene, estimator, options, load_seconds, progress))
}

fn render_in_pool(
    scene: &Scene,
    estimator: &dyn Estimator,
    options: &RenderOptions,
    load_seconds: f64,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let kernel = Kernel::from_env()?;
    let pixels = options.width as u64 * options.height as u64;
    let bvh = options.bvh_quality.resolve(
        pixels + estimator.expected_rays(pixels),
        scene.mesh.triangle_count(),
    );
    let start = Instant::now();
    let accel = Accel::build(&scene.mesh, bvh).with_kernel(kernel);
    let accel_build = start.elapsed().as_secs_f64();

    let primary_start = Instant::now();
    let gbuffer = primary_hits(&accel, scene, options.width, options.height);
    let primary = primary_start.elapsed().as_secs_f64();

    let bounds = scene.bounds();
    let l_diag = bounds.diagonal();
    let context = EstimateContext {
        accel: &accel,
        scene,
        seed: options.seed,
        clamp: DistanceClamp::for_diagonal(l_diag, options.max_distance),
    };
    let estimate_start = Instant::now();
    let estimate = estimator.estimate(&context, &gbuffer, progress)?;
    let estimate_seconds = estimate_start.elapsed().as_secs_f64();

    let mut seconds = json!({
        "load": load_seconds,
        "accel_build": accel_build,
        "primary": primary,
        "estimate": estimate_seconds,
        "total": load_seconds + start.elapsed().as_secs_f64(),
    });
    for (phase, s) in &estimate.phases {
        seconds[*phase] = json!(s);
    }
    let mut report = json!({
        "hmdist_version": env!("CARGO_PKG_VERSION"),
        "method": estimator.method(),
        "scene": scene.name,
        "width": options.width,
        "height": options.height,
        "seed": options.seed,
        "threads": rayon::current_num_threads(),
        "kernel": kernel.name(),
        "bvh": bvh.name(),
        "max_distance": options.max_distance,
        "triangles": scene.mesh.triangle_count(),
        "l_diag": l_diag,
        "d_min": context.clamp.min,
        "bounds": { "min": bounds.min.to_array(), "max": bounds.max.to_array() },
        "camera": {
            "eye": scene.camera.eye.to_array(),
            "target": scene.camera.target.to_array(),
            "up": scene.camera.up.to_array(),
            "fov_y_deg": scene.camera.fov_y_deg,
        },
        "light": scene.light.map(|l| json!({
            "position": l.position.to_array(),
            "direction": l.direction.to_array(),
            "cone_half_angle_deg": l.cone_half_angle_deg,
        })),
        "display_scale": scene.display_scale,
        "background_pixels": gbuffer.background_pixels(),
        "rays_cast": estimate.rays.map(|r| r.cast),
        "escaped_rays": estimate.rays.map(|r| r.escaped),
        "mrays_per_s": estimate.rays.map(|r| r.cast as f64 / r.seconds.max(1e-9) / 1e6),
        "seconds": seconds,
    });
    let fields = report.as_object_mut().expect("report is an object");
    fields.extend(estimator.parameters());
    fields.extend(estimate.extra);
    Ok(Rendered {
        image: HmdImage::new(options.width, options.height, estimate.hmd),
        report,
    })
}

/// Each pixel's first hit along its camera ray (SPEC §2), normal flipped to face the camera.
pub fn primary_hits(accel: &impl RayCaster, scene: &Scene, width: u32, height: u32) -> GBuffer {
    let camera = scene.camera.rays(width, height);
    let points = (0..width as u64 * height as u64)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % width as u64) as u32, (i / width as u64) as u32);
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
