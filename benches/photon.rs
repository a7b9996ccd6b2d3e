//! Photon map build and gather throughput on `cube`, ours against plain kiddo side by side
//! (issue #11).
//!
//! `cargo bench --bench photon` prints, for 1 M and 8.5 M light-sourced photons (20 bounces):
//! trace seconds; per method, our map's build seconds and bytes per photon against kiddo's
//! `ImmutableKdTree` over the same photons; then gather queries per second at K = 64, 256 and
//! 1,024 over each, for the pixels of a `cube` image (256² unless `HMDIST_BENCH_SIZE`) in row
//! order as the renderer asks them, all cores. kiddo's gather is what hmdist did before:
//! `nearest_n_within` (a vector per query), then the orientation filter and the distances.
//! The `same H` column checks every pixel: kiddo's K nearest, summed in our map's order, give
//! our H bit for bit. Set `HMDIST_BENCH_PHOTONS=1000000` for a subset. Figures, not pass/fail.

use std::num::NonZero;
use std::time::Instant;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality};
use hmdist::estimators::photon::map::{decode_octahedral, encode_octahedral};
use hmdist::estimators::photon::{
    trace_photons, GatherScratch, PathRules, PhotonMap, PhotonMethod, PhotonSource, TracedPhoton,
    DEFAULT_ABSORPTION, DEFAULT_MAX_BOUNCES, NORMAL_FILTER_COS,
};
use hmdist::render::primary_hits;
use hmdist::scene::Scene;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use rayon::prelude::*;

type Kiddo = ImmutableKdTree<f32, u32, 3, 32>;

fn main() {
    let budgets: Vec<usize> = std::env::var("HMDIST_BENCH_PHOTONS")
        .unwrap_or_else(|_| "1000000,8500000".into())
        .split(',')
        .map(|s| s.parse().expect("photon count"))
        .collect();
    let size: u32 = std::env::var("HMDIST_BENCH_SIZE").map_or(256, |s| s.parse().expect("image side"));
    let scene = Scene::load("cube").unwrap();
    let accel = Accel::build(&scene.mesh, BuildQuality::High);
    let gbuffer = primary_hits(&accel, &scene, size, size);
    let rows: Vec<Vec<(Vec3, Vec3)>> = gbuffer
        .points
        .chunks(size as usize)
        .map(|row| row.iter().flatten().map(|h| (h.point, h.normal)).collect())
        .collect();
    let queries: usize = rows.iter().map(|r| r.len()).sum();
    let source = PhotonSource::Light(scene.light.unwrap());
    let rules = PathRules {
        max_bounces: DEFAULT_MAX_BOUNCES,
        absorption: DEFAULT_ABSORPTION,
    };
    println!(
        "{queries} queries ({size}² pixels of cube, row order), {} threads",
        rayon::current_num_threads()
    );
    println!(
        "photons   method  trace_s  build_s ours/kiddo  B/photon ours/kiddo     K  queries/s ours   kiddo  ratio  same H"
    );
    for &budget in &budgets {
        let start = Instant::now();
        let traced = trace_photons(&accel, &source, rules, budget, 1, &|_| {}).unwrap();
        let trace = start.elapsed().as_secs_f64();
        let photons = &traced.photons;
        let start = Instant::now();
        let positions: Vec<[f32; 3]> = photons.iter().map(|p| p.position.to_array()).collect();
        let kiddo = Kiddo::new_from_slice(&positions);
        let kiddo_build = start.elapsed().as_secs_f64();
        drop(positions);
        // Tree position of each traced photon, for summing kiddo's photons in our order.
        let order = PhotonMap::order(photons).unwrap();
        let mut rank = vec![0u32; photons.len()];
        for (position, &index) in order.iter().enumerate() {
            rank[index as usize] = position as u32;
        }
        for method in [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint] {
            let start = Instant::now();
            let map = PhotonMap::build(photons, method).unwrap();
            let build = start.elapsed().as_secs_f64();
            // kiddo's tree: 3 × f32 and a u32 per photon; the payload as ours.
            let kiddo_bytes = 16 + method.payload_bytes();
            for k in [64, 256, 1024] {
                let k = NonZero::new(k).unwrap();
                let (ours, ours_s) = timed(|| ours_gather(&map, &rows, k));
                let (_, kiddo_s) = timed(|| kiddo_gather(&kiddo, photons, method, &rows, k));
                let reference = kiddo_in_our_order(&kiddo, photons, (&order, &rank), method, &rows, k);
                let same = ours
                    .iter()
                    .zip(&reference)
                    .filter(|(a, b)| a.to_bits() == b.to_bits())
                    .count();
                println!(
                    "{budget:>9}  {:<6} {trace:>7.2}  {build:>6.2} / {kiddo_build:<5.2}  {:>6} / {:<6}  {:>5}  {:>11.0}  {:>6.0}  {:>5.2}  {same}/{queries}",
                    method.name(),
                    method.bytes_per_photon(),
                    kiddo_bytes,
                    k,
                    queries as f64 / ours_s,
                    queries as f64 / kiddo_s,
                    kiddo_s / ours_s,
                );
            }
        }
    }
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let value = f();
    (value, start.elapsed().as_secs_f64())
}

/// 1 / H per query, row by row in parallel as the renderer runs them (a scratch per row).
fn ours_gather(map: &PhotonMap, rows: &[Vec<(Vec3, Vec3)>], k: NonZero<usize>) -> Vec<f64> {
    rows.par_iter()
        .map_init(GatherScratch::default, |scratch, row| {
            row.iter()
                .map(|&(x, n)| {
                    let mut s = 0.0f64;
                    map.gather(scratch, x, n, k, f32::INFINITY, NORMAL_FILTER_COS, |d| {
                        s += 1.0 / d as f64
                    });
                    s
                })
                .collect::<Vec<f64>>()
        })
        .flatten()
        .collect()
}

/// The distance photon `p` contributes by `method` from `x`, computed as the map does.
fn contribution(p: &TracedPhoton, method: PhotonMethod, x: Vec3) -> f32 {
    match method {
        PhotonMethod::StoredDistance => p.distance,
        PhotonMethod::NextHitPoint if p.distance.is_finite() => {
            (p.position + p.distance * p.direction).distance(x)
        }
        PhotonMethod::NextHitPoint => f32::INFINITY,
    }
}

/// What hmdist did before its own map: kiddo's K nearest, in kiddo's order.
fn kiddo_gather(
    kiddo: &Kiddo,
    photons: &[TracedPhoton],
    method: PhotonMethod,
    rows: &[Vec<(Vec3, Vec3)>],
    k: NonZero<usize>,
) -> Vec<f64> {
    rows.par_iter()
        .flat_map_iter(|row| {
            row.iter().map(|&(x, n)| {
                let found =
                    kiddo.nearest_n_within::<SquaredEuclidean>(&x.to_array(), f32::INFINITY, k, false);
                let mut s = 0.0f64;
                for f in found {
                    let p = &photons[f.item as usize];
                    if decode_octahedral(encode_octahedral(p.normal)).dot(n) >= NORMAL_FILTER_COS {
                        s += 1.0 / contribution(p, method, x) as f64;
                    }
                }
                s
            })
        })
        .collect()
}

/// kiddo's K nearest summed in our map's order (untimed): equal to ours bit for bit when both
/// find the same K photons. Where photons tie at the K-th distance (equal f32 d², a few
/// pixels in 65,536 at 8.5 M photons) kiddo keeps either; ours keeps the earlier in tree
/// order, so kiddo is asked for a few more and the same rule picks among them.
fn kiddo_in_our_order(
    kiddo: &Kiddo,
    photons: &[TracedPhoton],
    (order, rank): (&[u32], &[u32]),
    method: PhotonMethod,
    rows: &[Vec<(Vec3, Vec3)>],
    k: NonZero<usize>,
) -> Vec<f64> {
    let more = k.saturating_add(16);
    rows.par_iter()
        .flat_map_iter(|row| {
            row.iter().map(|&(x, n)| {
                let found =
                    kiddo.nearest_n_within::<SquaredEuclidean>(&x.to_array(), f32::INFINITY, more, true);
                let mut items: Vec<(u32, u32)> = found
                    .iter()
                    .map(|f| (f.distance.to_bits(), rank[f.item as usize]))
                    .collect();
                items.sort_unstable();
                items.truncate(k.get());
                items.sort_by_key(|&(_, r)| r);
                let mut s = 0.0f64;
                for (_, r) in items {
                    let p = &photons[order[r as usize] as usize];
                    if decode_octahedral(encode_octahedral(p.normal)).dot(n) >= NORMAL_FILTER_COS {
                        s += 1.0 / contribution(p, method, x) as f64;
                    }
                }
                s
            })
        })
        .collect()
}
