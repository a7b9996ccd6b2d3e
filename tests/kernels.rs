//! Every ray-casting kernel returns the same hit distances, bit for bit (SPEC §8, issue:
//! ray-casting engine): the SIMD kernels perform each lane's IEEE operations in the scalar
//! kernel's order, and the traversal around them is shared.

use std::process::Command;

use hmdist::accel::{Accel, BuildQuality, Kernel, RayCaster};
use hmdist::estimators::Gather;
use hmdist::render::primary_hits;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;
use rayon::prelude::*;

/// The kernels this CPU has; the others are skipped with their reason on stderr.
fn kernels() -> Vec<Kernel> {
    Kernel::ALL
        .into_iter()
        .filter(|k| {
            let available = k.available();
            if !available {
                eprintln!("skipped: this CPU cannot run the {} kernel", k.name());
            }
            available
        })
        .collect()
}

/// Hit distances (as bits) of `rays` cosine gather rays from each of the `side²` primary
/// hits, and the triangle each primary ray hits.
fn gather_bits(accel: &Accel, scene: &Scene, side: u32, rays: u32) -> (Vec<u32>, Vec<u32>) {
    let gbuffer = primary_hits(accel, scene, side, side);
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    let hits: Vec<_> = gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, (*p)?)))
        .collect();
    let distances = hits
        .par_iter()
        .flat_map_iter(|&(pixel, hit)| {
            let (origin, directions) = gather.rays(&hit, 7, pixel as u64);
            directions
                .map(move |dir| {
                    accel
                        .hit_distance(origin, dir, f32::INFINITY, Some(hit.triangle))
                        .to_bits()
                })
                .collect::<Vec<_>>()
        })
        .collect();
    (distances, hits.iter().map(|(_, h)| h.triangle).collect())
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

#[test]
fn every_kernel_renders_the_same_exr_bytes() {
    let dir = std::env::temp_dir().join(format!("hmdist-kernels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut reference: Option<Vec<u8>> = None;
    for kernel in kernels() {
        let out = dir.join(format!("{}.exr", kernel.name()));
        let status = Command::new(env!("CARGO_BIN_EXE_hmdist"))
            .args(["render", "--size", "48x40", "--rays", "64", "--quiet", "--out"])
            .arg(&out)
            .env("HMDIST_KERNEL", kernel.name())
            .status()
            .unwrap();
        assert!(status.success());
        let bytes = std::fs::read(&out).unwrap();
        match &reference {
            None => reference = Some(bytes),
            Some(r) => assert!(r == &bytes, "{} renders other EXR bytes", kernel.name()),
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
