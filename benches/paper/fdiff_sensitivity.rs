//! Why the paper's f_diff is lower than ours at equal N: each assumption of the paper's
//! method that its text leaves open, alone and together, measured on one scene at a small
//! size (docs/paper-scale/sensitivity.md gives the tables and what they conclude).
//!
//! The gather here is written out independently of the estimators (no `GridBlocks`, no
//! lanes): a pixel's primary hit, its normal turned to the camera, N directions on an `a × b`
//! grid of strata (`hmdist::sampling::strata`), mapped by the weighting, cast with
//! `RayCaster::hit_distances`, `H = N / Σ 1/max(d, d_min)` (spec §1). What varies:
//!
//! - the weighting: cosine (the spec's default) or uniform;
//! - the origin: the robust offset of spec §2, or a fixed offset `ε` along the normal (ε as
//!   a multiple of the spec's `d_min = 1e-6 l_diag`: ×10³ and ×10⁴), as a renderer with a scene
//!   epsilon would;
//! - the pattern: jittered strata drawn per pixel (ours), or the strata centres, the same
//!   pattern in every pixel (`regular`: what a fixed cube-map-like lookup would give);
//! - the reference: made the same way as the estimate at the reference's N, or the
//!   independent jittered cosine robust reference (ours);
//! - which pixels the mean runs over: all finite, the room's shell only (floor, walls,
//!   ceiling: a hit on the scene's bounding box), the objects only, or with background
//!   pixels counted in N_pixels at zero difference (hall sees out of its window).
//!
//! Two independent references (seeds 1 and 2 of the reference's N) give the noise floor
//! that any difference at that N sits on (Fig. 9).
//!
//!     cargo run --release --example fdiff_sensitivity -- cube 128 65536 > cube.csv
//!
//! Arguments: scene (a built-in or file), image side, reference rays, and optionally the
//! estimates' ray counts (comma-separated; default 32,64,…,8192). Prints CSV on stdout and
//! progress on stderr.

use std::time::Instant;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality, Hit, RayCaster, PACKET};
use hmdist::sampling::{hemisphere, random_pair, strata, Frame, Weighting};
use hmdist::scene::Scene;
use rayon::prelude::*;

/// How a configuration gathers.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Method {
    weighting: Weighting,
    /// `None`: the robust offset; `Some(k)`: a fixed offset of `k · d_min` along the normal.
    fixed_offset: Option<f32>,
    /// Strata centres, the same in every pixel, instead of jitter drawn per pixel.
    regular: bool,
}

impl Method {
    const OURS: Method = Method {
        weighting: Weighting::Cosine,
        fixed_offset: None,
        regular: false,
    };

    fn name(&self) -> String {
        let mut parts = vec![self.weighting.name().to_string()];
        parts.push(match self.fixed_offset {
            None => "robust".into(),
            Some(k) => format!("eps=dmin*{k:e}"),
        });
        parts.push(if self.regular { "regular" } else { "jittered" }.into());
        parts.join(" ")
    }
}

/// A pixel's primary hit, its normal facing the camera.
struct Primary {
    hit: Hit,
    shell: bool,
}

fn primaries(scene: &Scene, accel: &Accel, size: u32) -> Vec<Option<Primary>> {
    let camera = scene.camera.rays(size, size);
    let bounds = scene.bounds();
    let tolerance = 1e-5 * scene.diagonal();
    (0..size * size)
        .into_par_iter()
        .map(|i| {
            let dir = camera.pixel_direction(i % size, i / size);
            let mut hit = accel.closest_hit(camera.eye(), dir, f32::INFINITY, None)?;
            if hit.normal.dot(dir) > 0.0 {
                hit.normal = -hit.normal;
            }
            let on_plane = |p: Vec3| {
                (p - bounds.min).abs().min_element() < tolerance
                    || (bounds.max - p).abs().min_element() < tolerance
            };
            Some(Primary {
                shell: on_plane(hit.point),
                hit,
            })
        })
        .collect()
}

/// H at every pixel with `n` rays by `method`, seed `seed` (NaN where the primary ray missed).
fn h_image(
    scene: &Scene,
    accel: &Accel,
    primary: &[Option<Primary>],
    method: Method,
    n: u32,
    seed: u64,
) -> Vec<f64> {
    let l_diag = scene.diagonal();
    let d_min = 1e-6 * l_diag;
    let (a, b) = strata(n);
    primary
        .par_iter()
        .enumerate()
        .map(|(pixel, p)| {
            let Some(p) = p else { return f64::NAN };
            let frame = Frame::from_normal(p.hit.normal);
            let origin = match method.fixed_offset {
                None => p.hit.spawn_origin(p.hit.normal),
                Some(k) => p.hit.point + (k * d_min) * p.hit.normal,
            };
            let leaving = [Some(p.hit.triangle); PACKET];
            let origins = [origin; PACKET];
            let mut sum = 0.0f64;
            let mut j = 0;
            while j < n {
                let len = ((n - j) as usize).min(PACKET);
                let mut dirs = [Vec3::ZERO; PACKET];
                for (l, dir) in dirs.iter_mut().enumerate().take(len) {
                    let s = j + l as u32;
                    let xi = if method.regular {
                        glam::Vec2::splat(0.5)
                    } else {
                        random_pair(seed, pixel as u64, s as u64)
                    };
                    let u = hmdist::sampling::stratified(s, (a, b), xi);
                    *dir = frame.to_world(hemisphere(method.weighting, u));
                }
                let mut out = [0.0f32; PACKET];
                accel.hit_distances(
                    &origins[..len],
                    &dirs[..len],
                    &leaving[..len],
                    f32::INFINITY,
                    &mut out,
                );
                for d in &out[..len] {
                    if d.is_finite() {
                        sum += 1.0 / d.max(d_min) as f64;
                    }
                }
                j += len as u32;
            }
            if sum == 0.0 {
                f64::INFINITY
            } else {
                n as f64 / sum
            }
        })
        .collect()
}

/// The mean of `|ΔH| / H_ref` and of `H_ref` (in percent of `l_diag`) over the pixels finite
/// in both: f_diff is about their product, so a scene whose H is smaller beside its diagonal
/// has a smaller f_diff at the same relative error.
fn relative(reference: &[f64], image: &[f64], l_diag: f64) -> (f64, f64) {
    let (mut rel, mut h, mut count) = (0.0, 0.0, 0usize);
    for (r, x) in reference.iter().zip(image) {
        if r.is_finite() && x.is_finite() {
            rel += (r - x).abs() / r;
            h += r;
            count += 1;
        }
    }
    (rel / count as f64, h / count as f64 * 100.0 / l_diag)
}

/// f_diff over the pixels `keep` selects that are finite in both; with `background`, the
/// pixels missed by the primary ray count in N_pixels at zero difference.
fn f_diff(
    reference: &[f64],
    image: &[f64],
    l_diag: f64,
    keep: &dyn Fn(usize) -> bool,
    background: bool,
) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for i in 0..reference.len() {
        if !keep(i) {
            continue;
        }
        if reference[i].is_finite() && image[i].is_finite() {
            sum += (reference[i] - image[i]).abs();
            count += 1;
        } else if background && reference[i].is_nan() && image[i].is_nan() {
            count += 1;
        }
    }
    sum / count as f64 * 100.0 / l_diag
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: fdiff_sensitivity SCENE SIZE REFERENCE_RAYS [N,N,...]");
        std::process::exit(2);
    }
    let scene = Scene::load(&args[1]).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    let size: u32 = args[2].parse().expect("SIZE is a whole number");
    let reference_rays: u32 = args[3].parse().expect("REFERENCE_RAYS is a whole number");
    let counts: Vec<u32> = match args.get(4) {
        Some(list) => list
            .split(',')
            .map(|s| s.parse().expect("N is a whole number"))
            .collect(),
        None => (5..=13).map(|k| 1 << k).collect(),
    };
    let started = Instant::now();
    let accel = Accel::build(&scene.mesh, BuildQuality::High);
    let primary = primaries(&scene, &accel, size);
    let l_diag = scene.diagonal() as f64;
    let shell = |i: usize| primary[i].as_ref().is_some_and(|p| p.shell);
    let objects = |i: usize| primary[i].as_ref().is_some_and(|p| !p.shell);
    let all = |_: usize| true;
    let log = |what: &str| eprintln!("[{:7.1} s] {what}", started.elapsed().as_secs_f64());
    log(&format!(
        "{}: {size}², {} background, {} shell, {} object pixels",
        scene.name,
        primary.iter().filter(|p| p.is_none()).count(),
        (0..primary.len()).filter(|&i| shell(i)).count(),
        (0..primary.len()).filter(|&i| objects(i)).count()
    ));
    let cosine = Weighting::Cosine;
    let uniform = Weighting::Uniform;
    let m = |weighting, fixed_offset, regular| Method {
        weighting,
        fixed_offset,
        regular,
    };
    // Each estimate's method, and whether its reference is made the same way (else ours).
    let configs: Vec<(Method, bool)> = vec![
        (Method::OURS, true),
        (m(uniform, None, false), true),
        (m(cosine, Some(1e3), false), true),
        (m(cosine, Some(1e4), false), true),
        (m(cosine, None, true), false),
        (m(cosine, None, true), true),
        (m(uniform, Some(1e4), false), true),
        (m(uniform, Some(1e4), true), true),
    ];
    let mut references: Vec<(Method, Vec<f64>)> = vec![];
    let reference_of = |method: Method, references: &mut Vec<(Method, Vec<f64>)>| -> usize {
        if let Some(k) = references.iter().position(|(r, _)| *r == method) {
            return k;
        }
        let image = h_image(&scene, &accel, &primary, method, reference_rays, 1_000_003);
        log(&format!("reference {} ({reference_rays} rays)", method.name()));
        references.push((method, image));
        references.len() - 1
    };
    println!("scene,size,method,reference,rays,f_diff,f_diff_shell,f_diff_objects,f_diff_with_background,mean_rel_err,mean_h_ref_pct");
    // The noise floor: a second reference of our method with another seed.
    let ours = reference_of(Method::OURS, &mut references);
    let second = h_image(&scene, &accel, &primary, Method::OURS, reference_rays, 2);
    let row = |method: &Method, reference: &str, n: u32, r: &[f64], image: &[f64]| {
        let (rel, h) = relative(r, image, l_diag);
        println!(
            "{},{size},{},{reference},{n},{:.5},{:.5},{:.5},{:.5},{rel:.5},{h:.3}",
            scene.name,
            method.name(),
            f_diff(r, image, l_diag, &all, false),
            f_diff(r, image, l_diag, &shell, false),
            f_diff(r, image, l_diag, &objects, false),
            f_diff(r, image, l_diag, &all, true),
        );
    };
    row(
        &Method::OURS,
        "ours seed 1000003 vs seed 2",
        reference_rays,
        &references[ours].1,
        &second,
    );
    log("noise floor");
    for (method, same) in configs {
        let k = if same {
            reference_of(method, &mut references)
        } else {
            ours
        };
        let label = if same {
            "same method".to_string()
        } else {
            "ours".to_string()
        };
        for &n in &counts {
            let image = h_image(&scene, &accel, &primary, method, n, 1);
            row(&method, &label, n, &references[k].1, &image);
        }
        log(&format!("{} against {label}", method.name()));
    }
}
