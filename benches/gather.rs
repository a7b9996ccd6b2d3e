//! Gather throughput and BVH build time on the built-in scenes (issue: foundation).
//!
//! `cargo bench --bench gather` prints, per scene: BVH build seconds for each preset, and
//! gather Mrays/s at 256×256 pixels × 256 rays (all cores, then one thread). Set
//! `HMDIST_BENCH_SCENES=cube` to run a subset, `HMDIST_BENCH_SIZE=128` for a smaller image.
//! Figures, not pass/fail: compare as ratios within one run (timings drift ±10 %).

use std::time::Instant;

use hmdist::accel::{Accel, BuildQuality};
use hmdist::estimators::{DistanceClamp, EstimateContext, Estimator, Gather};
use hmdist::progress::Silent;
use hmdist::render::primary_hits;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

fn main() {
    let scenes = std::env::var("HMDIST_BENCH_SCENES").unwrap_or_else(|_| "cube,hall".into());
    let size: u32 = std::env::var("HMDIST_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    let rays = 256;
    println!("scene  triangles  preset  build_s  threads  Mrays/s  escaped");
    for name in scenes.split(',') {
        let scene = Scene::load(name).expect("built-in scene");
        for quality in [BuildQuality::Fast, BuildQuality::High] {
            let start = Instant::now();
            let accel = Accel::build(&scene.mesh, quality);
            let build = start.elapsed().as_secs_f64();
            let gbuffer = primary_hits(&accel, &scene, size, size);
            let context = EstimateContext {
                accel: &accel,
                scene: &scene,
                seed: 1,
                clamp: DistanceClamp::for_diagonal(scene.diagonal(), None),
            };
            let gather = Gather::new(rays, Weighting::Cosine).unwrap();
            let all = rayon::current_num_threads();
            for threads in [all, 1] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let start = Instant::now();
                let estimate = pool
                    .install(|| gather.estimate(&context, &gbuffer, &Silent))
                    .unwrap();
                let seconds = start.elapsed().as_secs_f64();
                let rays = estimate.rays.expect("gather counts its rays");
                println!(
                    "{name:<6} {:>9}  {:<6} {build:>7.2}  {threads:>7}  {:>7.2}  {:>7}",
                    scene.mesh.triangle_count(),
                    format!("{quality:?}").to_lowercase(),
                    rays.cast as f64 / seconds / 1e6,
                    rays.escaped,
                );
            }
        }
    }
}
