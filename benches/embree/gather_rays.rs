//! The gather workload as a file, so that Embree and Open3D cast exactly hmdist's rays
//! (`benches/embree/compare.sh` drives it; not part of the library).
//!
//! ```text
//! gather_rays write SCENE SIDE N FILE   # SIDE² pixels × N cosine gather rays of `render`
//! gather_rays cast SCENE FILE [auto|fast|high]  # build, then cast them all: seconds, Mrays/s
//! gather_rays sphere LEVEL DIR          # DIR/sphere.obj (icosphere, 20·4^LEVEL triangles,
//!                                       # R = 2.5) and DIR/sphere.toml, a camera inside it
//! gather_rays order SCENE FILE MODE G   # the rays cast single|strata|blocks|pixels (below),
//!                                       # G pixels per work item: Mrays/s
//! gather_rays stats SCENE FILE          # nodes and leaf blocks per ray of each mode
//! gather_rays points SCENE SIDE FILE    # the SIDE² image's gather points, for the
//!                                       # end-to-end peer (embree_gather.c)
//! gather_rays exr SIDE POINTS HMD OUT   # the peer's H (HMD: f32 per point, in the points
//!                                       # file's order) as a SIDE² EXR, NaN where no point
//! ```
//!
//! Modes of `order` (how packets were chosen; the distances are the same bits in all):
//! `single` one ray at a time; `strata` each pixel's rays 8 at a time in ray order; `blocks`
//! each pixel's rays in 4 × 2 blocks of strata (what `render` does); `pixels` ray j of 8
//! neighbouring pixels together.
//!
//! Points file: `HMDP`, then little-endian u32 version (1), points; per surface pixel the
//! gather origin (3 × f32), the unit normal facing the camera (3 × f32) and the pixel index
//! (u32).
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
        ["stats", scene, file] => stats(scene, file),
        ["points", scene, side, file] => points(scene, side.parse().unwrap(), file),
        ["order", scene, file, mode, group] => order(scene, file, mode, group.parse().unwrap()),
        ["sphere", level, dir] => sphere(level.parse().unwrap(), std::path::Path::new(dir)),
        ["exr", side, points, hmd, out] => exr(side.parse().unwrap(), points, hmd, out),
        _ => {
            eprintln!(
                "usage: gather_rays write SCENE SIDE N FILE | cast SCENE FILE [auto|fast|high] | sphere LEVEL DIR | order SCENE FILE MODE G | stats SCENE FILE | points SCENE SIDE FILE | exr SIDE POINTS HMD OUT"
            );
            std::process::exit(2);
        }
    }
}

/// The surface points of scene `name`'s `side²` image, keyed by pixel.
fn surface_hits(name: &str, side: u32) -> Vec<(usize, hmdist::accel::Hit)> {
    let scene = Scene::load(name).expect("a scene");
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let gbuffer = primary_hits(&accel, &scene, side, side);
    gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, (*p)?)))
        .collect()
}

/// `file` created, its magic and little-endian u32 header written.
fn create(file: &str, magic: &[u8; 4], header: &[u32]) -> BufWriter<std::fs::File> {
    let mut out = BufWriter::new(std::fs::File::create(file).expect("a writable file"));
    out.write_all(magic).unwrap();
    for v in header {
        out.write_all(&v.to_le_bytes()).unwrap();
    }
    out
}

fn write(name: &str, side: u32, rays: u32, file: &str) {
    let hits = surface_hits(name, side);
    let gather = Gather::new(rays, Weighting::Cosine).unwrap();
    let mut out = create(file, b"HMDR", &[1, hits.len() as u32, rays]);
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

fn points(name: &str, side: u32, file: &str) {
    let hits = surface_hits(name, side);
    let mut out = create(file, b"HMDP", &[1, hits.len() as u32]);
    for (pixel, hit) in hits {
        let origin = hit.spawn_origin(hit.normal);
        for v in origin.to_array().into_iter().chain(hit.normal.to_array()) {
            out.write_all(&v.to_le_bytes()).unwrap();
        }
        out.write_all(&(pixel as u32).to_le_bytes()).unwrap();
    }
    out.flush().unwrap();
}

/// A peer's H per point (`hmd`: little-endian f32 in the order of `points`, a points file)
/// as a `side²` EXR for `hmdist diff`: each value at its point's pixel, NaN elsewhere.
fn exr(side: u32, points: &str, hmd: &str, out: &str) {
    let bytes = std::fs::read(points).expect("a points file");
    assert_eq!(&bytes[..4], b"HMDP");
    let values = std::fs::read(hmd).expect("an H file");
    let word = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    let count = word(&bytes, 8) as usize;
    assert_eq!(values.len(), 4 * count, "one f32 per point");
    let mut data = vec![f32::NAN; (side * side) as usize];
    for i in 0..count {
        let pixel = word(&bytes, 12 + 28 * i + 24) as usize;
        data[pixel] = f32::from_le_bytes(values[4 * i..4 * i + 4].try_into().unwrap());
    }
    let image = hmdist::image::HmdImage::new(side, side, data);
    hmdist::image::exr::write(&image, std::path::Path::new(out)).expect("a writable EXR");
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
    // As `render` casts them: packets of 4 × 2 neighbouring strata where the grid allows.
    let n = pixels.first().map_or(0, |p| p.directions.len());
    let (a, b) = hmdist::sampling::strata(n.max(1) as u32);
    let mode = if a % 4 == 0 && b % 2 == 0 {
        "blocks"
    } else {
        "strata"
    };
    let (escaped, inverse_sum) = pixels
        .par_chunks(16)
        .map(|chunk| {
            let mut escaped = 0u64;
            let mut inverse_sum = 0.0f64;
            for (sum, missed) in cast_chunk(&accel, chunk, n, mode, None) {
                escaped += missed;
                inverse_sum += sum;
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

/// Experiment: the same rays cast in other ways. `mode`: `single` (each pixel's rays in
/// turn, one at a time), `strata` (each pixel's rays 8 at a time as packets: neighbouring
/// strata), `pixels` (groups of 8 neighbouring pixels, ray j of each as a packet).
fn order(name: &str, file: &str, mode: &str, group: usize) {
    let scene = Scene::load(name).expect("a scene");
    let pixels = read(file);
    let rays: usize = pixels.iter().map(|p| p.directions.len()).sum();
    let n = pixels[0].directions.len();
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let start = Instant::now();
    let sums: Vec<(f64, u64)> = pixels
        .par_chunks(group)
        .flat_map_iter(|chunk| cast_chunk(&accel, chunk, n, mode, None))
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let total: f64 = sums.iter().map(|s| s.0).sum();
    println!(
        "{mode:<8} {:.3} Mrays/s  mean_inverse {:.9}",
        rays as f64 / seconds / 1e6,
        total / rays as f64
    );
}

/// The sums of 1/t of `chunk`'s pixels and their escaped rays, cast as `mode` says (see
/// [`order`]).
fn cast_chunk(
    accel: &Accel,
    chunk: &[Pixel],
    n: usize,
    mode: &str,
    mut stats: Option<&mut hmdist::accel::TraversalStats>,
) -> Vec<(f64, u64)> {
    let mut sums = vec![(0.0f64, 0u64); chunk.len()];
    let add = |sum: &mut (f64, u64), t: f32| {
        sum.0 += 1.0 / t as f64;
        sum.1 += t.is_infinite() as u64;
    };
    let mut t = [0.0f32; 8];
    let mut cast = |o: &[Vec3], d: &[Vec3], l: &[Option<u32>], t: &mut [f32]| match stats.as_deref_mut() {
        Some(s) => accel.hit_distances_counted(o, d, l, f32::INFINITY, t, s),
        None => accel.hit_distances(o, d, l, f32::INFINITY, t),
    };
    match mode {
        "single" => {
            for (p, sum) in chunk.iter().zip(&mut sums) {
                for &d in &p.directions {
                    cast(&[p.origin], &[d], &[Some(p.triangle)], &mut t);
                    add(sum, t[0]);
                }
            }
        }
        "blocks" => {
            // 4 × 2 blocks of the a × b strata grid (stratum (i, k) is ray k·a + i).
            let (a, b) = hmdist::sampling::strata(n as u32);
            let (a, b) = (a as usize, b as usize);
            assert!(a % 4 == 0 && b % 2 == 0, "{a} x {b} strata");
            for (p, sum) in chunk.iter().zip(&mut sums) {
                let mut d = vec![0.0f32; n];
                for k0 in (0..b).step_by(2) {
                    for i0 in (0..a).step_by(4) {
                        let index: [usize; 8] = std::array::from_fn(|q| (k0 + q / 4) * a + i0 + q % 4);
                        let dirs: [Vec3; 8] = index.map(|j| p.directions[j]);
                        cast(&[p.origin; 8], &dirs, &[Some(p.triangle); 8], &mut t);
                        for (q, &j) in index.iter().enumerate() {
                            d[j] = t[q];
                        }
                    }
                }
                for t in d {
                    add(sum, t);
                }
            }
        }
        "strata" => {
            for (p, sum) in chunk.iter().zip(&mut sums) {
                for dirs in p.directions.chunks(8) {
                    let k = dirs.len();
                    cast(&[p.origin; 8][..k], dirs, &[Some(p.triangle); 8][..k], &mut t);
                    for &t in &t[..k] {
                        add(sum, t);
                    }
                }
            }
        }
        _ => {
            for group in chunk.chunks(8).zip(sums.chunks_mut(8)) {
                let (pixels, sums) = group;
                let origins: Vec<Vec3> = pixels.iter().map(|p| p.origin).collect();
                let leaving: Vec<Option<u32>> = pixels.iter().map(|p| Some(p.triangle)).collect();
                for j in 0..n {
                    let dirs: Vec<Vec3> = pixels.iter().map(|p| p.directions[j]).collect();
                    cast(&origins, &dirs, &leaving, &mut t);
                    for (sum, &t) in sums.iter_mut().zip(&t) {
                        add(sum, t);
                    }
                }
            }
        }
    }
    sums
}

/// Nodes and leaf blocks per ray of each mode (every 16th group of 8 pixels).
fn stats(name: &str, file: &str) {
    use hmdist::accel::TraversalStats;
    let scene = Scene::load(name).expect("a scene");
    let pixels = read(file);
    let n = pixels[0].directions.len();
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    for mode in ["single", "strata", "blocks", "pixels"] {
        let mut stats = TraversalStats::default();
        let mut rays = 0u64;
        for chunk in pixels.chunks(8).step_by(16) {
            cast_chunk(&accel, chunk, n, mode, Some(&mut stats));
            rays += (chunk.len() * n) as u64;
        }
        let r = rays as f64;
        println!(
            "{mode:<8} {:.2} single-ray nodes/ray {:.3} packet nodes/ray {:.2} blocks/ray",
            stats.nodes as f64 / r,
            stats.packet_nodes as f64 / r,
            stats.blocks as f64 / r
        );
    }
}
