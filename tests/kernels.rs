//! Every ray-casting kernel returns the same hit distances, bit for bit (spec §8, issue:
//! ray-casting engine): the SIMD kernels perform each lane's IEEE operations in the scalar
//! kernel's order, and the traversal around them is shared.

use std::process::Command;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality, Hit, Kernel, RayCaster};
use hmdist::estimators::Gather;
use hmdist::render::primary_hits;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;
use rayon::prelude::*;

/// The kernels this CPU has; the others are skipped with their reason on stderr (written to
/// it directly: libtest hides `eprintln!` of a passing test). A kernel whose instructions the
/// CPU has (asked of `std::arch` here, not of hmdist) must be available: a build that lost
/// its AVX2 kernel fails instead of comparing the scalar kernel with itself.
fn kernels() -> Vec<Kernel> {
    let kernels: Vec<Kernel> = Kernel::ALL
        .into_iter()
        .filter(|k| {
            assert!(
                k.available() || !cpu_has(*k),
                "this CPU has the {} instructions, but hmdist's {} kernel is not available",
                k.name(),
                k.name()
            );
            if !k.available() {
                use std::io::Write;
                let _ = writeln!(
                    std::io::stderr(),
                    "SKIPPED the {} kernel: this CPU cannot run it",
                    k.name()
                );
            }
            k.available()
        })
        .collect();
    assert!(kernels.contains(&Kernel::Scalar));
    kernels
}

/// Whether the CPU has the instructions `kernel` needs.
fn cpu_has(kernel: Kernel) -> bool {
    match kernel {
        Kernel::Scalar => true,
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx512 => {
            std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl")
        }
        #[cfg(not(target_arch = "x86_64"))]
        _ => false,
    }
}

/// Hit distances (as bits) of `rays` cosine gather rays from each of the `side²` primary
/// hits, and the triangle each primary ray hits.
fn gather_bits(accel: &Accel, scene: &Scene, side: u32, rays: u32) -> (Vec<u32>, Vec<u32>) {
    gather_bits_with(accel, scene, side, rays, 1)
}

/// The surface points of the `side²` primary rays, keyed by pixel.
fn primary(accel: &Accel, scene: &Scene, side: u32) -> Vec<(u64, Hit)> {
    let gbuffer = primary_hits(accel, scene, side, side);
    gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i as u64, (*p)?)))
        .collect()
}

/// [`gather_bits`] with each point's rays cast `packet` at a time through
/// [`RayCaster::hit_distances`] (1: one at a time through [`RayCaster::hit_distance`]).
fn gather_bits_with(
    accel: &Accel,
    scene: &Scene,
    side: u32,
    rays: u32,
    packet: usize,
) -> (Vec<u32>, Vec<u32>) {
    let hits = primary(accel, scene, side);
    (
        distance_bits(accel, &hits, rays, packet),
        hits.iter().map(|(_, h)| h.triangle).collect(),
    )
}

/// The hit distances (as bits) of `rays` cosine gather rays from each point of `hits`, cast
/// `packet` at a time (1: one at a time through [`RayCaster::hit_distance`]).
fn distance_bits(accel: &Accel, hits: &[(u64, Hit)], rays: u32, packet: usize) -> Vec<u32> {
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    hits.par_iter()
        .flat_map_iter(|&(key, hit)| {
            let (origin, directions) = gather.rays(&hit, 7, key);
            let directions: Vec<Vec3> = directions.collect();
            let mut out = vec![0.0f32; directions.len()];
            if packet == 1 {
                for (d, &dir) in out.iter_mut().zip(&directions) {
                    *d = accel.hit_distance(origin, dir, f32::INFINITY, Some(hit.triangle));
                }
            } else {
                for (out, dirs) in out.chunks_mut(packet).zip(directions.chunks(packet)) {
                    let k = dirs.len();
                    let origins = vec![origin; k];
                    let leaving = vec![Some(hit.triangle); k];
                    accel.hit_distances(&origins, dirs, &leaving, f32::INFINITY, out);
                }
            }
            out.into_iter().map(f32::to_bits).collect::<Vec<_>>()
        })
        .collect()
}

/// The number of places where two lists of distance bits differ.
fn differing(a: &[u32], b: &[u32]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).filter(|(a, b)| a != b).count()
}

/// Packets of every size give each ray exactly its single-ray distance, for every kernel
/// (the scalar kernel casts a packet ray by ray; the SIMD ones traverse it together).
fn packets_match_single_rays(
    label: &str,
    mesh: &hmdist::scene::Mesh,
    hits: &dyn Fn(&Accel) -> Vec<(u64, Hit)>,
    rays: u32,
) {
    let mut accel = Some(Accel::build(mesh, BuildQuality::Fast));
    let mut reference: Option<Vec<u32>> = None;
    for kernel in kernels() {
        let a = accel.take().unwrap().with_kernel(kernel);
        let points = hits(&a);
        let single = distance_bits(&a, &points, rays, 1);
        assert!(single.len() >= 1_000_000, "{label}: {} rays", single.len());
        assert!(
            single.iter().any(|&d| f32::from_bits(d).is_finite()),
            "{label}: nothing hit"
        );
        for packet in [2, 5, 8] {
            let packed = distance_bits(&a, &points, rays, packet);
            let n = differing(&single, &packed);
            assert_eq!(
                n,
                0,
                "{label}: {}, packets of {packet}: {n} rays differ",
                kernel.name()
            );
        }
        if let Some(r) = &reference {
            let n = differing(r, &single);
            assert_eq!(n, 0, "{label}: {} differs from scalar on {n} rays", kernel.name());
        }
        reference.get_or_insert(single);
        accel = Some(a);
    }
}

#[test]
fn packets_give_single_ray_hits_in_cube() {
    let scene = Scene::load("cube").unwrap();
    packets_match_single_rays("cube", &scene.mesh, &|a| primary(a, &scene, 64), 256);
}

#[test]
fn packets_give_single_ray_hits_in_hall() {
    let scene = Scene::load("hall").unwrap();
    packets_match_single_rays("hall", &scene.mesh, &|a| primary(a, &scene, 64), 256);
}

/// At many rays per point a packet's rays are close enough in direction for the coherent path
/// of `packet.rs` (inner children by the packet's interval test alone, leaf corners translated
/// once for the packet): 16 points of `cube` at the reference's 65,536 rays, 64 of `hall` at
/// 4,096 (where some packets take it and some do not).
#[test]
fn packets_give_single_ray_hits_at_many_rays_per_point() {
    let scene = Scene::load("cube").unwrap();
    packets_match_single_rays(
        "cube, 65,536 rays",
        &scene.mesh,
        &|a| primary(a, &scene, 4),
        65_536,
    );
    let scene = Scene::load("hall").unwrap();
    packets_match_single_rays(
        "hall, 4,096 rays",
        &scene.mesh,
        &|a| primary(a, &scene, 16),
        4_096,
    );
}

#[test]
fn packets_give_single_ray_hits_in_a_closed_sphere() {
    // 20,480 triangles; gather points where rays from inside meet the sphere.
    let mesh = hmdist::scene::procedural::shapes::icosphere(5, Vec3::new(0.1, -0.2, 0.05), 2.5);
    let points = |a: &Accel| -> Vec<(u64, Hit)> {
        (0..4096u64)
            .map(|i| {
                let u = hmdist::sampling::random_pair(3, 0, i);
                let d = hmdist::sampling::hemisphere(Weighting::Uniform, u);
                let d = if i % 2 == 0 { d } else { -d };
                let hit = a
                    .closest_hit(Vec3::new(0.3, 0.2, -0.1), d, f32::INFINITY, None)
                    .expect("inside a closed sphere");
                // Gather towards the inside: the normal facing the centre.
                let normal = if hit.normal.dot(d) > 0.0 {
                    -hit.normal
                } else {
                    hit.normal
                };
                (i, Hit { normal, ..hit })
            })
            .collect()
    };
    packets_match_single_rays("closed sphere", &mesh, &points, 256);
}

fn same_distances_for_every_kernel(name: &str, quality: BuildQuality, side: u32, rays: u32) {
    let scene = Scene::load(name).unwrap();
    let mut accel = Some(Accel::build(&scene.mesh, quality));
    let mut reference: Option<(Vec<u32>, Vec<u32>)> = None;
    for kernel in kernels() {
        let a = accel.take().unwrap().with_kernel(kernel);
        let (distances, triangles) = gather_bits(&a, &scene, side, rays);
        assert!(distances.len() >= 1_000_000, "{} rays", distances.len());
        match &reference {
            None => reference = Some((distances, triangles)),
            Some((d, t)) => {
                let differing = d.iter().zip(&distances).filter(|(a, b)| a != b).count();
                assert_eq!(
                    differing,
                    0,
                    "{name}: {} differs from scalar on {differing} rays",
                    kernel.name()
                );
                assert_eq!(
                    t,
                    &triangles,
                    "{name}: {} hits other primary triangles",
                    kernel.name()
                );
            }
        }
        accel = Some(a);
    }
}

#[test]
fn every_kernel_gives_the_same_hit_distances_in_cube() {
    same_distances_for_every_kernel("cube", BuildQuality::High, 64, 256);
}

#[test]
fn every_kernel_gives_the_same_hit_distances_in_hall() {
    same_distances_for_every_kernel("hall", BuildQuality::Fast, 64, 256);
}

/// The same distances and primary triangles from both BVH presets, cast one ray at a time
/// or as packets: the closest hit does not depend on the order in which the tree is visited
/// (ties go to the lowest triangle index).
fn same_distances_whatever_the_order(name: &str, side: u32, rays: u32) {
    let scene = Scene::load(name).unwrap();
    let mut reference: Option<(Vec<u32>, Vec<u32>)> = None;
    for quality in [BuildQuality::Fast, BuildQuality::High] {
        let accel = Accel::build(&scene.mesh, quality);
        for packet in [1, 8] {
            let (distances, triangles) = gather_bits_with(&accel, &scene, side, rays, packet);
            assert!(distances.len() >= 1_000_000, "{} rays", distances.len());
            match &reference {
                None => reference = Some((distances, triangles)),
                Some((d, t)) => {
                    let differing = d.iter().zip(&distances).filter(|(a, b)| a != b).count();
                    assert_eq!(
                        differing, 0,
                        "{name}: {quality:?}, packets of {packet}: {differing} rays differ"
                    );
                    let primary = t.iter().zip(&triangles).filter(|(a, b)| a != b).count();
                    assert_eq!(
                        primary, 0,
                        "{name}: {quality:?}: {primary} primary rays hit another triangle"
                    );
                }
            }
        }
    }
}

#[test]
fn both_presets_and_packets_give_the_same_hits_in_cube() {
    same_distances_whatever_the_order("cube", 64, 256);
}

#[test]
fn both_presets_and_packets_give_the_same_hits_in_hall() {
    same_distances_whatever_the_order("hall", 64, 256);
}

#[test]
fn every_kernel_renders_the_same_exr_bytes() {
    let dir = std::env::temp_dir().join(format!("hmdist-kernels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The default sampler (sobol: nets cast as packets of their boxes) and the grid (4 × 2
    // blocks of strata).
    for sampler in ["sobol", "grid"] {
        let mut reference: Option<Vec<u8>> = None;
        for kernel in kernels() {
            let out = dir.join(format!("{}-{sampler}.exr", kernel.name()));
            let status = Command::new(env!("CARGO_BIN_EXE_hmdist"))
                .args(["render", "--size", "48x40", "--rays", "64", "--sampler", sampler])
                .args(["--backend", "cpu", "--quiet", "--out"])
                .arg(&out)
                .env("HMDIST_KERNEL", kernel.name())
                .status()
                .unwrap();
            assert!(status.success());
            let bytes = std::fs::read(&out).unwrap();
            match &reference {
                None => reference = Some(bytes),
                Some(r) => assert!(
                    r == &bytes,
                    "{} renders other EXR bytes ({sampler})",
                    kernel.name()
                ),
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_unknown_kernel_is_refused_with_status_2() {
    let dir = std::env::temp_dir().join(format!("hmdist-kernels-unknown-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(["render", "--size", "8x8", "--rays", "4", "--quiet"])
        .current_dir(&dir)
        .env("HMDIST_KERNEL", "sse9")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("HMDIST_KERNEL"));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "no output is written"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
