//! The gather workload as a file, so that Embree and Open3D cast exactly hmdist's rays
//! (`benches/embree/compare.sh` drives it; not part of the library).
//!
//! ```text
//! gather_rays write SCENE SIDE N FILE   # SIDE² pixels × N cosine gather rays of `render`
//! gather_rays cast SCENE FILE [auto|fast|high]  # build, then cast them all: seconds, Mrays/s
//! gather_rays sphere LEVEL DIR          # DIR/sphere.obj (icosphere, 20·4^LEVEL triangles,
//!                                       # R = 2.5) and DIR/sphere.toml, a camera inside it
//! ```
//!
//! FILE: `HMDR`, then little-endian u32 version (1), pixels, rays per pixel; per surface
//! pixel the ray origin (3 × f32, hmdist's robust offset of the primary hit), the triangle it
//! leaves (u32), and the N unit directions (3 × f32 each). `cast` uses all cores (rayon);
//! it times the BVH build and the casting loop only, as the C and Python peers do.

use std::io::{BufReader, BufWriter, Read, Write};
use std::time::Instant;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality, RayCaster};
use hmdist::estimators::Gather;
use hmdist::render::primary_hits;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["write", scene, side, rays, file] => {
            write(scene, side.parse().unwrap(), rays.parse().unwrap(), file)
        }
        ["cast", scene, file] | ["cast", scene, file, "auto"] => cast(scene, file, BuildQuality::Auto),
        ["cast", scene, file, "fast"] => cast(scene, file, BuildQuality::Fast),
        ["cast", scene, file, "high"] => cast(scene, file, BuildQuality::High),
        ["sphere", level, dir] => sphere(level.parse().unwrap(), std::path::Path::new(dir)),
        _ => {
            eprintln!(
                "usage: gather_rays write SCENE SIDE N FILE | cast SCENE FILE [auto|fast|high] | sphere LEVEL DIR"
            );
            std::process::exit(2);
        }
    }
}

fn write(name: &str, side: u32, rays: u32, file: &str) {
    let scene = Scene::load(name).expect("a scene");
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let gbuffer = primary_hits(&accel, &scene, side, side);
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    let hits: Vec<_> = gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, (*p)?)))
        .collect();
    let mut out = BufWriter::new(std::fs::File::create(file).expect("a writable file"));
    out.write_all(b"HMDR").unwrap();
    for v in [1u32, hits.len() as u32, rays] {
        out.write_all(&v.to_le_bytes()).unwrap();
    }
    for (pixel, hit) in hits {
        let (origin, directions) = gather.rays(&hit, 1, pixel as u64);
        let mut record = Vec::with_capacity(16 + 12 * rays as usize);
        for v in origin.to_array() {
            record.extend(v.to_le_bytes());
        }
        record.extend(hit.triangle.to_le_bytes());
        for dir in directions {
            for v in dir.to_array() {
                record.extend(v.to_le_bytes());
            }
        }
        out.write_all(&record).unwrap();
    }
    out.flush().unwrap();
}

fn sphere(level: u32, dir: &std::path::Path) {
    let mesh = hmdist::scene::procedural::shapes::icosphere(level, Vec3::ZERO, 2.5);
    hmdist::scene::export::write_obj(&mesh, &dir.join("sphere.obj")).expect("a writable folder");
    let toml = "[[mesh]]\npath = \"sphere.obj\"\n[camera]\neye = [0.4, 0.3, 1.2]\ntarget = [0.0, -0.2, -2.0]\nfov_y_deg = 70.0\n";
    std::fs::write(dir.join("sphere.toml"), toml).expect("a writable folder");
}

struct Pixel {
    origin: Vec3,
    triangle: u32,
    directions: Vec<Vec3>,
}

fn read(file: &str) -> Vec<Pixel> {
    let mut input = BufReader::new(std::fs::File::open(file).expect("a rays file"));
    let mut bytes = Vec::new();
    input.read_to_end(&mut bytes).unwrap();
    assert_eq!(&bytes[..4], b"HMDR");
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let vec = |at: usize| Vec3::new(float(at), float(at + 4), float(at + 8));
    let (pixels, rays) = (word(8) as usize, word(12) as usize);
    let record = 16 + 12 * rays;
    (0..pixels)
        .map(|p| {
            let at = 16 + p * record;
            Pixel {
                origin: vec(at),
                triangle: word(at + 12),
                directions: (0..rays).map(|j| vec(at + 16 + 12 * j)).collect(),
            }
        })
        .collect()
}

fn cast(name: &str, file: &str, quality: BuildQuality) {
    let scene = Scene::load(name).expect("a scene");
    let pixels = read(file);
    let rays: usize = pixels.iter().map(|p| p.directions.len()).sum();
    let quality = quality.resolve(rays as u64, scene.mesh.triangle_count());
    let start = Instant::now();
    let accel = Accel::build(&scene.mesh, quality);
    let build = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (escaped, inverse_sum) = pixels
        .par_iter()
        .map(|p| {
            let mut escaped = 0u64;
            let mut inverse_sum = 0.0f64;
            for &d in &p.directions {
                let t = accel.hit_distance(p.origin, d, f32::INFINITY, Some(p.triangle));
                escaped += t.is_infinite() as u64;
                inverse_sum += 1.0 / t as f64;
            }
            (escaped, inverse_sum)
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "hmdist build_s {build:.3} trace_s {seconds:.3} mrays_per_s {:.3} rays {rays} escaped {escaped} mean_inverse {:.6} kernel {} bvh {}",
        rays as f64 / seconds / 1e6,
        inverse_sum / rays as f64,
        accel.kernel().name(),
        quality.name()
    );
}
