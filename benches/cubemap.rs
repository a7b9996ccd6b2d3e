//! Cube-map seconds per image against gather rays N, CPU and GPU backends (issue: cube map).
//!
//! `cargo bench --bench cubemap` renders `cube` at 32 × 32 (`HMDIST_BENCH_SIZE` to change)
//! with R = 64 for N = 256, 4,096 and 16,384, on each backend, next to `gather`: `cpu`,
//! `gpu` (rasterised) and `gpu-rays` (`--gpu-fill rays`: a ray per looked-up texel). The
//! paper's finding: the rasterised cube map's cost hardly grows with N. Without a hardware
//! GPU the `gpu` rows run on lavapipe (software) where `HMDIST_GPU_SOFTWARE=1` allows it, and
//! are skipped otherwise. Figures, not pass/fail.

use hmdist::estimators::cubemap::{Backend, GpuFill};
use hmdist::estimators::{Cubemap, Estimator, Gather};
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions};
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

fn main() {
    let size: u32 = std::env::var("HMDIST_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(32);
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::default()
    };
    println!("{size}x{size} cube, R = 64");
    println!("method   backend   rays   seconds  pixels/s  adapter");
    for rays in [256, 4096, 16384] {
        let gather = Gather::new(rays, Weighting::Cosine).unwrap();
        let mut runs: Vec<(&str, Box<dyn Estimator>)> = vec![("-", Box::new(gather))];
        for (name, backend) in [("cpu", Backend::Cpu), ("gpu", Backend::Gpu)] {
            runs.push((name, Box::new(Cubemap::new(gather, 64, backend).unwrap())));
        }
        let by_rays = Cubemap::new(gather, 64, Backend::Gpu)
            .unwrap()
            .with_gpu_fill(GpuFill::Rays);
        runs.push(("gpu-rays", Box::new(by_rays)));
        for (backend, estimator) in runs {
            match render(&scene, estimator.as_ref(), &options, &Silent) {
                Ok(r) => {
                    let s = r.report.seconds.estimate;
                    let device = r.report.details.device.as_ref();
                    println!(
                        "{:<8} {backend:<8} {rays:>5}  {s:>8.2}  {:>8.0}  {}",
                        estimator.method(),
                        (size * size) as f64 / s,
                        device.and_then(|d| d.adapter.as_deref()).unwrap_or("-")
                    );
                }
                Err(e) => println!("{:<8} {backend:<8} {rays:>5}  skipped: {e}", estimator.method()),
            }
        }
    }
}
