//! Photon map build and gather throughput on `cube` (issue: photon-map estimators).
//!
//! `cargo bench --bench photon` prints, for 1 M and 8.5 M light-sourced photons (20 bounces):
//! trace and index seconds and bytes per photon; then gather queries per second at
//! K = 64, 256 and 1,024 over each map, for the 256 × 256 pixels of `cube`, methods I and II.
//! Set `HMDIST_BENCH_PHOTONS=1000000` for a subset. Figures, not pass/fail.

use std::time::Instant;

use hmdist::accel::{Accel, BuildQuality};
use hmdist::estimators::photon::{
    trace_photons, PathRules, PhotonMap, PhotonMethod, PhotonSource, DEFAULT_ABSORPTION, DEFAULT_MAX_BOUNCES,
    NORMAL_FILTER_COS,
};
use hmdist::render::primary_hits;
use hmdist::scene::Scene;
use rayon::prelude::*;

fn main() {
    let budgets: Vec<usize> = std::env::var("HMDIST_BENCH_PHOTONS")
        .unwrap_or_else(|_| "1000000,8500000".into())
        .split(',')
        .map(|s| s.parse().expect("photon count"))
        .collect();
    let scene = Scene::load("cube").unwrap();
    let accel = Accel::build(&scene.mesh, BuildQuality::High);
    let gbuffer = primary_hits(&accel, &scene, 256, 256);
    let points: Vec<_> = gbuffer.points.iter().flatten().collect();
    let source = PhotonSource::Light(scene.light.unwrap());
    let rules = PathRules {
        max_bounces: DEFAULT_MAX_BOUNCES,
        absorption: DEFAULT_ABSORPTION,
    };
    println!("photons   method  trace_s  index_s  B/photon      K  queries/s");
    for &budget in &budgets {
        let start = Instant::now();
        let traced = trace_photons(&accel, &source, rules, budget, 1, &|_| {}).unwrap();
        let trace = start.elapsed().as_secs_f64();
        for method in [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint] {
            let start = Instant::now();
            let map = PhotonMap::build(&traced.photons, method).unwrap();
            let index = start.elapsed().as_secs_f64();
            for k in [64, 256, 1024] {
                let k = std::num::NonZero::new(k).unwrap();
                let start = Instant::now();
                let sum: f64 = points
                    .par_iter()
                    .map(|hit| {
                        let mut s = 0.0f64;
                        map.gather(hit.point, hit.normal, k, f32::INFINITY, NORMAL_FILTER_COS, |d| {
                            s += 1.0 / d as f64
                        });
                        s
                    })
                    .sum();
                let seconds = start.elapsed().as_secs_f64();
                std::hint::black_box(sum);
                println!(
                    "{budget:>9}  {:<6} {trace:>7.2}  {index:>7.2}  {:>8}  {:>5}  {:>9.0}",
                    method.name(),
                    method.bytes_per_photon(),
                    k,
                    points.len() as f64 / seconds,
                );
            }
        }
    }
}
