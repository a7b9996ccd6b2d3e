//! Gather throughput, BVH build time and traversal figures on the built-in scenes
//! (issue: ray-casting engine).
//!
//! `cargo bench --bench gather` prints, per scene and BVH preset: build seconds, bytes per
//! triangle, and for each ray count N: gather Mrays/s with all cores and with one thread,
//! node visits per ray (single-ray and packet: a packet visit tests the node for up to 8
//! rays) and leaf blocks per ray, and the nanoseconds per ray of generating the directions,
//! casting them and summing 1/d, timed apart on one thread, made and cast as `render` makes
//! and casts them (4 × 2 blocks of strata as lanes where the grid splits so). Environment:
//! `HMDIST_BENCH_SCENES=cube,hall` (default), `HMDIST_BENCH_SIZE=256` (image side),
//! `HMDIST_BENCH_RAYS=64,256,4096` (N; fewer pixels are used for large N so that each run
//! casts about 16.8 M rays), `HMDIST_BENCH_PRESETS=fast,high`, `HMDIST_BENCH_KERNELS=` (e.g.
//! `scalar,avx2,avx512`; default: the best kernel).
//! Figures, not pass/fail: compare as ratios within one run (timings drift ±10 %).
//!
//! Then the GPU backend (`gather --backend gpu`), where a Vulkan, Metal or DX12 adapter
//! exists: per scene and ray count, upload, trace and readback seconds, seconds per image and
//! Mrays/s of tracing. `HMDIST_BENCH_GPU_RAYS=256,4096` (default), `HMDIST_BENCH_GPU_SIZE` (image side;
//! default 1024 on a hardware GPU, 64 on a software one such as lavapipe, where the figures
//! are only a functional check), `HMDIST_BENCH_GPU=0` skips it.

use std::time::Instant;

use hmdist::accel::{Accel, BuildQuality, Kernel, RayLanes, TraversalStats, PACKET};
use hmdist::estimators::{DistanceClamp, EstimateContext, GBuffer, Gather, HarmonicMean};
use hmdist::progress::Silent;
use hmdist::render::primary_hits;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

fn list(name: &str, default: &str) -> Vec<String> {
    std::env::var(name)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

fn main() {
    let size: u32 = std::env::var("HMDIST_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    let kernels: Vec<Kernel> = list("HMDIST_BENCH_KERNELS", Kernel::best().name())
        .iter()
        .map(|k| Kernel::parse(k).expect("a kernel this CPU has"))
        .collect();
    println!(
        "scene  triangles  preset  build_s  B/tri  kernel   rays  pixels  Mrays/s(all)  Mrays/s(1)  nodes/ray  packet_nodes/ray  blocks/ray  escaped  ns/ray: generate  cast  sum"
    );
    for name in list("HMDIST_BENCH_SCENES", "cube,hall") {
        let scene = Scene::load(&name).expect("built-in scene");
        for preset in list("HMDIST_BENCH_PRESETS", "fast,high") {
            let quality = match preset.as_str() {
                "fast" => BuildQuality::Fast,
                _ => BuildQuality::High,
            };
            let start = Instant::now();
            let built = Accel::build(&scene.mesh, quality);
            let build = start.elapsed().as_secs_f64();
            let bytes_per_triangle = built.size().2 as f64 / scene.mesh.triangle_count() as f64;
            let mut accel = Some(built);
            for &kernel in &kernels {
                let a = accel.take().unwrap().with_kernel(kernel);
                for rays in list("HMDIST_BENCH_RAYS", "64,256,4096") {
                    let rays: u32 = rays.parse().expect("a ray count");
                    // About 16.8 M rays per run: fewer pixels for more rays.
                    let side = ((16_777_216.0 / rays as f64).sqrt() as u32).clamp(8, size);
                    let gbuffer = primary_hits(&a, &scene, side, side);
                    let (all, one, escaped) = throughput(&a, &scene, &gbuffer, rays);
                    let (stats, split) = traversal(&a, &gbuffer, rays);
                    let per_ray = |count: u64| count as f64 / stats_rays(&gbuffer, rays) as f64;
                    println!(
                        "{name:<6} {:>9}  {preset:<6} {build:>7.2}  {bytes_per_triangle:>5.0}  {:<7} {rays:>5}  {:>5}²  {all:>12.2}  {one:>10.2}  {:>9.2}  {:>16.3}  {:>10.2}  {escaped:>7}  {:>16.0}  {:>4.0}  {:>3.0}",
                        scene.mesh.triangle_count(),
                        kernel.name(),
                        side,
                        per_ray(stats.nodes),
                        per_ray(stats.packet_nodes),
                        per_ray(stats.blocks),
                        split[0],
                        split[1],
                        split[2],
                    );
                }
                accel = Some(a);
            }
        }
    }
    if std::env::var("HMDIST_BENCH_GPU").as_deref() != Ok("0") {
        gpu();
    }
}

/// The GPU backend's figures (see the module docs).
fn gpu() {
    println!();
    println!("scene  rays  pixels  upload_s  trace_s  readback_s  s/image  Mrays/s  escaped  adapter");
    for name in list("HMDIST_BENCH_SCENES", "cube,hall") {
        let scene = Scene::load(&name).expect("built-in scene");
        let accel = Accel::build(&scene.mesh, BuildQuality::High);
        let software = match hmdist::gpu::GpuScene::new(&accel, false) {
            Ok(_) => false,
            Err(_) => match hmdist::gpu::GpuScene::new(&accel, true) {
                Ok(_) => true,
                Err(e) => {
                    println!("{name:<6} skipped: {e}");
                    continue;
                }
            },
        };
        let default_side = if software { "64" } else { "1024" };
        let side: u32 = list("HMDIST_BENCH_GPU_SIZE", default_side)[0]
            .parse()
            .expect("an image side");
        let gbuffer = primary_hits(&accel, &scene, side, side);
        let context = EstimateContext {
            accel: &accel,
            scene: &scene,
            seed: 1,
            clamp: DistanceClamp::for_diagonal(scene.diagonal(), None),
            aovs: &[],
            whole_image: true,
            bvh: BuildQuality::High,
        };
        for rays in list("HMDIST_BENCH_GPU_RAYS", "256,4096") {
            let rays: u32 = rays.parse().expect("a ray count");
            // On a software adapter (no hardware GPU) the `gpu` backend refuses to run.
            let backend = if software {
                hmdist::estimators::Backend::GpuSoftware
            } else {
                hmdist::estimators::Backend::Gpu
            };
            let gather = Gather::new(rays, Weighting::Cosine)
                .unwrap()
                .with_backend(backend);
            let start = Instant::now();
            let estimate = hmdist::render::estimate(&gather, &context, &gbuffer, &Silent).unwrap();
            let seconds = start.elapsed().as_secs_f64();
            let phases = estimate.phases;
            let cast = estimate.rays.expect("gather counts its rays");
            let details = estimate.details;
            println!(
                "{name:<6} {rays:>5}  {side:>5}²  {:>8.3}  {:>7.3}  {:>10.4}  {seconds:>7.2}  {:>7.2}  {:>7}  {}",
                phases.gpu_upload.unwrap_or(f64::NAN),
                phases.gpu_trace.unwrap_or(f64::NAN),
                phases.gpu_readback.unwrap_or(f64::NAN),
                details.grays_per_s.unwrap_or(f64::NAN) * 1e3,
                cast.escaped,
                details.device.and_then(|d| d.adapter).unwrap_or_default(),
            );
        }
    }
}

/// Mrays/s with all cores and with one thread, and the escaped rays.
fn throughput(accel: &Accel, scene: &Scene, gbuffer: &GBuffer, rays: u32) -> (f64, f64, u64) {
    let context = EstimateContext {
        accel,
        scene,
        seed: 1,
        clamp: DistanceClamp::for_diagonal(scene.diagonal(), None),
        aovs: &[],
        whole_image: true,
        bvh: BuildQuality::High,
    };
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    let mut figures = [0.0; 2];
    let mut escaped = 0;
    for (i, threads) in [rayon::current_num_threads(), 1].into_iter().enumerate() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let start = Instant::now();
        let estimate = pool
            .install(|| hmdist::render::estimate(&gather, &context, gbuffer, &Silent))
            .unwrap();
        let rays = estimate.rays.expect("gather counts its rays");
        figures[i] = rays.cast as f64 / start.elapsed().as_secs_f64() / 1e6;
        escaped = rays.escaped;
    }
    (figures[0], figures[1], escaped)
}

/// Pixels sampled for the traversal counts: every 7th surface pixel.
fn stats_pixels(gbuffer: &GBuffer) -> impl Iterator<Item = (usize, &hmdist::accel::Hit)> {
    gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.as_ref().map(|h| (i, h)))
        .step_by(7)
}

fn stats_rays(gbuffer: &GBuffer, rays: u32) -> u64 {
    stats_pixels(gbuffer).count() as u64 * rays as u64
}

/// Nodes (single-ray and packet visits) and leaf blocks visited by the same gather rays as
/// the estimator casts, made and cast as it makes and casts them (4 × 2 blocks of strata as
/// lanes, [`Gather::ray_blocks`], where the grid splits so, else 8 in ray order); and the
/// nanoseconds per ray, on one thread, of the gather's three parts timed apart: generate
/// (random numbers, strata, the cosine map, the frame), cast, and sum (clamp, 1/d in f64 in
/// ray order).
fn traversal(accel: &Accel, gbuffer: &GBuffer, rays: u32) -> (TraversalStats, [f64; 3]) {
    let n = rays as usize;
    let pixels: Vec<_> = stats_pixels(gbuffer).collect();
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    // Per pixel its origin, and its rays as blocks of lanes (with their indices) or in order.
    let mut origins = Vec::with_capacity(pixels.len());
    let mut blocks = Vec::new();
    let mut directions = Vec::new();
    let start = Instant::now();
    for &(pixel, hit) in &pixels {
        if let Some((origin, rays)) = gather.ray_blocks(hit, 1, pixel as u64) {
            origins.push(origin);
            blocks.extend(rays);
        } else {
            let (origin, rays) = gather.rays(hit, 1, pixel as u64);
            origins.push(origin);
            directions.extend(rays);
        }
    }
    let generate = start.elapsed().as_secs_f64();
    let in_blocks = !blocks.is_empty();
    let mut stats = TraversalStats::default();
    let mut distances = vec![0.0f32; pixels.len() * n];
    let mut cast = |stats: &mut TraversalStats| {
        let mut t = [0.0f32; PACKET];
        for (p, ((_, hit), out)) in pixels.iter().zip(distances.chunks_mut(n)).enumerate() {
            let (origin, leaving) = (origins[p], Some(hit.triangle));
            if !in_blocks {
                let (origins, leaving) = ([origin; PACKET], [leaving; PACKET]);
                let dirs = &directions[p * n..(p + 1) * n];
                for (d, out) in dirs.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
                    let k = d.len();
                    accel.hit_distances_counted(&origins[..k], d, &leaving[..k], f32::INFINITY, out, stats);
                }
            } else {
                let mut lanes = RayLanes {
                    origin: origin.to_array().map(|o| [o; PACKET]),
                    direction: [[0.0; PACKET]; 3],
                };
                for (direction, index) in &blocks[p * (n / PACKET)..(p + 1) * (n / PACKET)] {
                    lanes.direction = *direction;
                    accel.hit_distances_of_lanes_counted(
                        &lanes,
                        PACKET,
                        leaving,
                        f32::INFINITY,
                        &mut t,
                        stats,
                    );
                    for (&t, &j) in t.iter().zip(index) {
                        out[j as usize] = t;
                    }
                }
            }
        }
    };
    cast(&mut stats);
    let start = Instant::now();
    cast(&mut TraversalStats::default());
    let cast_seconds = start.elapsed().as_secs_f64();
    let clamp = DistanceClamp::for_diagonal(1.0, None);
    let start = Instant::now();
    let mut h = 0.0f32;
    for out in distances.chunks(n) {
        let mut mean = HarmonicMean::default();
        for &d in out {
            mean.add(d, clamp);
        }
        h += mean.value();
    }
    std::hint::black_box(h);
    let sum = start.elapsed().as_secs_f64();
    let ns = |s: f64| s * 1e9 / distances.len() as f64;
    (stats, [ns(generate), ns(cast_seconds), ns(sum)])
}
