//! H at given points (spec §8): the library's `points::hmd_at` and `hmdist points`, against
//! the image's own pixels, a closed form, and bad input.

mod common;

use common::cli::{hmdist_ok, refuses};
use common::Scratch;
use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality};
use hmdist::estimators::Gather;
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};
use hmdist::progress::Silent;
use hmdist::render::{primary_hits, render, RenderOptions};
use hmdist::sampling::{Sampler, Weighting};
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

const RAYS: u32 = 16;
const SIZE: (u32, u32) = (40, 30);

/// The cube rendered at [`SIZE`] with [`RAYS`] gather rays, and the surface pixels' hits as
/// (pixel index, point).
fn cube_image_and_points() -> (Scene, Vec<f32>, Vec<(u64, SurfacePoint)>) {
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: SIZE.0,
        height: SIZE.1,
        bvh_quality: BuildQuality::Fast,
        ..RenderOptions::default()
    };
    let gather = Gather::new(RAYS, Weighting::Cosine).unwrap();
    let image = render(&scene, &gather, &options, &Silent).unwrap().image.data;
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let gbuffer = primary_hits(&accel, &scene, SIZE.0, SIZE.1);
    let points = gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, hit)| hit.map(|h| (i as u64, SurfacePoint::from_hit(&h))))
        .collect();
    (scene, image, points)
}

fn query() -> PointQuery {
    PointQuery::new(Gather::new(RAYS, Weighting::Cosine).unwrap(), 1, None).unwrap()
}

#[test]
fn an_images_own_primary_hits_keyed_by_pixel_give_the_image_bit_for_bit() {
    let (scene, image, points) = cube_image_and_points();
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let keys: Vec<u64> = points.iter().map(|(k, _)| *k).collect();
    let surface: Vec<SurfacePoint> = points.iter().map(|(_, p)| *p).collect();
    let h = hmd_at(&scene, &accel, &query(), &surface, Some(&keys)).unwrap();
    assert_eq!(
        points.len(),
        (SIZE.0 * SIZE.1) as usize,
        "the cube's camera sees no background"
    );
    for (k, h) in keys.iter().zip(&h) {
        assert_eq!(h.to_bits(), image[*k as usize].to_bits(), "pixel {k}");
    }
}

#[test]
fn results_do_not_depend_on_batching() {
    let (scene, _, points) = cube_image_and_points();
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let keys: Vec<u64> = points.iter().map(|(k, _)| *k).collect();
    let surface: Vec<SurfacePoint> = points.iter().map(|(_, p)| *p).collect();
    let whole = hmd_at(&scene, &accel, &query(), &surface, Some(&keys)).unwrap();
    // Reversed, in two uneven batches.
    let cut = surface.len() / 3;
    let (rs, rk): (Vec<_>, Vec<_>) = surface.iter().zip(&keys).rev().unzip();
    let mut batched = hmd_at(&scene, &accel, &query(), &rs[..cut], Some(&rk[..cut])).unwrap();
    batched.extend(hmd_at(&scene, &accel, &query(), &rs[cut..], Some(&rk[cut..])).unwrap());
    batched.reverse();
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&whole), bits(&batched));
}

#[test]
fn a_bare_point_on_the_slab_floor_gives_three_halves_height() {
    // spec §1: H = 3h/2 under cosine weighting on the floor of a slab, far from its edges.
    let h = validation::SLAB_HEIGHT;
    let scene = validation::slab(h, 1000.0);
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let point = SurfacePoint::new(Vec3::new(0.3, 0.0, -0.2), Vec3::new(0.0, 2.0, 0.0)).unwrap();
    let query = PointQuery::new(Gather::new(65_536, Weighting::Cosine).unwrap(), 7, None).unwrap();
    let got = hmd_at(&scene, &accel, &query, &[point], None).unwrap()[0];
    println!("H = {got}, expected {}", 1.5 * h);
    assert!((got / (1.5 * h) - 1.0).abs() < 0.005, "H = {got}");
    // Facing down, the same point sees nothing: every ray escapes.
    let down = SurfacePoint::new(Vec3::new(0.3, 0.0, -0.2), Vec3::NEG_Y).unwrap();
    assert_eq!(
        hmd_at(&scene, &accel, &query, &[down], None).unwrap()[0],
        f32::INFINITY
    );
}

#[test]
fn bad_points_and_keys_are_refused_by_name() {
    use hmdist::error::Error;
    let named = |r: Result<SurfacePoint, Error>, name: &str| {
        let e = r.expect_err("refused");
        assert!(
            matches!(&e, Error::Parameter { name: Some(n), .. } if *n == name),
            "{e}"
        );
    };
    named(
        SurfacePoint::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y),
        "points",
    );
    named(SurfacePoint::new(Vec3::ZERO, Vec3::ZERO), "points");
    let scene = validation::slab(1.0, 10.0);
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let p = SurfacePoint::new(Vec3::ZERO, Vec3::Y).unwrap();
    let e = hmd_at(&scene, &accel, &query(), &[p, p], Some(&[0]))
        .err()
        .unwrap();
    assert!(
        matches!(
            e,
            Error::Parameter {
                name: Some("keys"),
                ..
            }
        ),
        "{e}"
    );
    let e = hmd_at(&scene, &accel, &query(), &[p.on_triangle(99)], None)
        .err()
        .unwrap();
    assert!(
        matches!(
            e,
            Error::Parameter {
                name: Some("triangle"),
                ..
            }
        ),
        "{e}"
    );
}

/// An `.npy` file (format 1.0) of `rows`, as `descr` (`<f4` or `<f8`), shape [n, 6]; written
/// here by hand rather than by the library hmdist reads it with.
fn npy(rows: &[[f32; 6]], descr: &str) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': ({}, 6), }}",
        rows.len()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for v in rows.iter().flatten() {
        match descr {
            "<f4" => bytes.extend(v.to_le_bytes()),
            _ => bytes.extend((*v as f64).to_le_bytes()),
        }
    }
    bytes
}

/// The float32 values of a 1-D `.npy` file: the data is its last 4·n bytes.
fn read_npy_f32(bytes: &[u8], n: usize) -> Vec<f32> {
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(
        header.contains("'<f4'") && header.replace(' ', "").contains(&format!("({n},)")),
        "{header}"
    );
    bytes[10 + header_len..]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn hmdist_points_on_the_images_hits_matches_the_image_from_npy_and_csv() {
    let (_, image, points) = cube_image_and_points();
    let rows: Vec<[f32; 6]> = points
        .iter()
        .map(|(_, p)| {
            let (x, n) = (p.point(), p.normal());
            [x.x, x.y, x.z, n.x, n.y, n.z]
        })
        .collect();
    let dir = Scratch::new("points-cli");
    dir.write("hits32.npy", npy(&rows, "<f4"));
    dir.write("hits64.npy", npy(&rows, "<f8"));
    let csv: String = std::iter::once("x,y,z,nx,ny,nz\n".to_string())
        .chain(rows.iter().map(|r| r.map(|v| v.to_string()).join(",") + "\n"))
        .collect();
    dir.write("hits.csv", csv);
    let rays = RAYS.to_string();
    // The image's sampler (the library's `Gather::new` starts from the grid).
    let run = |input: &str, output: &str| {
        let args = [
            "points",
            "--quiet",
            "--rays",
            &rays,
            "--sampler",
            "grid",
            input,
            output,
        ];
        hmdist_ok(dir.path(), &args);
    };
    run("hits32.npy", "h32.npy");
    run("hits64.npy", "h64.npy");
    run("hits.csv", "h.csv");
    let n = rows.len();
    let h32 = read_npy_f32(&std::fs::read(dir.join("h32.npy")).unwrap(), n);
    let h64 = read_npy_f32(&std::fs::read(dir.join("h64.npy")).unwrap(), n);
    let hcsv: Vec<f32> = std::fs::read_to_string(dir.join("h.csv"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&h32), bits(&h64), "float64 rows that hold float32 values");
    assert_eq!(bits(&h32), bits(&hcsv), "CSV rows in shortest form");
    // Without the triangle, the origin offset is the scene-wide bound: the rays start a
    // little further off the surface than the image's, and H differs by about that much.
    let mut relative: Vec<f64> = image
        .iter()
        .zip(&h32)
        .map(|(a, b)| ((a - b) / a).abs() as f64)
        .collect();
    relative.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let (median, p99) = (relative[n / 2], relative[n * 99 / 100]);
    println!("relative difference from the image: median {median:e}, 99th percentile {p99:e}");
    assert!(median < 1e-5 && p99 < 1e-3, "median {median:e}, p99 {p99:e}");
    // Without --sampler, the rows' H is the library's with the sobol sampler, bit for bit.
    hmdist_ok(
        dir.path(),
        &["points", "--quiet", "--rays", &rays, "hits32.npy", "hs.npy"],
    );
    let default = read_npy_f32(&std::fs::read(dir.join("hs.npy")).unwrap(), n);
    let bare: Vec<SurfacePoint> = rows
        .iter()
        .map(|r| SurfacePoint::new(Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5])).unwrap())
        .collect();
    let sobol = Gather::new(RAYS, Weighting::Cosine)
        .unwrap()
        .with_sampler(Sampler::Sobol)
        .unwrap();
    let query = PointQuery::new(sobol, 1, None).unwrap();
    let scene = Scene::load("cube").unwrap();
    // The BVH the CLI builds for this work (an exact tie may resolve otherwise in another).
    let rays = bare.len() as u64 * RAYS as u64;
    let kernel = hmdist::accel::Kernel::from_env().unwrap();
    let (accel, _) = Accel::for_work(&scene.mesh, BuildQuality::Auto, rays, kernel).unwrap();
    let library = hmd_at(&scene, &accel, &query, &bare, None).unwrap();
    assert_eq!(bits(&default), bits(&library));
    assert_ne!(bits(&default), bits(&h32));
}

#[test]
fn hmdist_points_refuses_bad_input() {
    let good = npy(&[[0.0, 0.5, 0.0, 0.0, 1.0, 0.0]], "<f4");
    let args = |input: &'static str| ["points", "--quiet", input, "out.npy"];
    refuses("points-missing", &[], &args("nowhere.npy"), "cannot read file");
    refuses(
        "points-ext",
        &[("in.txt", b"0 0 0 0 1 0\n")],
        &args("in.txt"),
        "neither .npy nor .csv",
    );
    refuses(
        "points-garbage",
        &[("in.npy", b"not numpy")],
        &args("in.npy"),
        "not an .npy file",
    );
    let mut five = npy(&[[0.0; 6]], "<f4");
    let at = five.windows(6).position(|w| w == b"(1, 6)").unwrap();
    five[at + 4] = b'5';
    five.truncate(five.len() - 4);
    refuses(
        "points-shape",
        &[("in.npy", &five)],
        &args("in.npy"),
        "expected [n, 6]",
    );
    let mut ints = good.clone();
    let at = ints.windows(3).position(|w| w == b"<f4").unwrap();
    ints[at + 1] = b'i';
    refuses(
        "points-dtype",
        &[("in.npy", &ints)],
        &args("in.npy"),
        "expected float32 or float64",
    );
    let truncated = &good[..good.len() - 8];
    refuses(
        "points-truncated",
        &[("in.npy", truncated)],
        &args("in.npy"),
        "in.npy",
    );
    let nan = npy(&[[0.0, f32::NAN, 0.0, 0.0, 1.0, 0.0]], "<f4");
    refuses(
        "points-nan",
        &[("in.npy", &nan)],
        &args("in.npy"),
        "row 0: the point must be finite",
    );
    let zero = b"0,0.5,0,0,1,0\n1,0.5,0,0,0,0\n";
    refuses(
        "points-normal",
        &[("in.csv", zero)],
        &args("in.csv"),
        "row 1: the point must have a non-zero normal",
    );
    let short = b"0,0.5,0,0,1\n";
    refuses(
        "points-columns",
        &[("in.csv", short)],
        &args("in.csv"),
        "in.csv:1: expected 6 numbers",
    );
    refuses(
        "points-empty",
        &[("in.csv", b"x,y,z,nx,ny,nz\n")],
        &args("in.csv"),
        "holds no points",
    );
    let rays = ["points", "--quiet", "--rays", "0", "in.npy", "out.npy"];
    refuses(
        "points-rays",
        &[("in.npy", &good)],
        &rays,
        "--rays must be at least 1",
    );
    let d = ["points", "--quiet", "--max-distance", "0", "in.npy", "out.npy"];
    refuses(
        "points-max-distance",
        &[("in.npy", &good)],
        &d,
        "--max-distance must be positive",
    );
}

/// `hmdist points` on the slab with the CSV `text`: H per row, as written.
fn points_of_csv(case: &str, text: &str) -> Vec<String> {
    let dir = Scratch::new(case);
    dir.write("in.csv", text.as_bytes());
    hmdist_ok(
        dir.path(),
        &[
            "points", "--quiet", "--scene", "slab", "--rays", "16", "in.csv", "h.csv",
        ],
    );
    std::fs::read_to_string(dir.join("h.csv"))
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

#[test]
fn a_csv_header_is_recognised_by_what_it_is_not_by_failing_to_parse() {
    let rows = "0,0.5,0,0,1,0\n1,0.5,0,0,1,0\n2,0.5,0,0,1,0\n";
    let plain = points_of_csv("csv-plain", rows);
    assert_eq!(plain.len(), 3);
    // A byte-order mark, a header, a trailing comment: the same three rows.
    assert_eq!(points_of_csv("csv-bom", &format!("\u{feff}{rows}")), plain);
    assert_eq!(
        points_of_csv("csv-bom-header", &format!("\u{feff}x,y,z,nx,ny,nz\n{rows}")),
        plain
    );
    let commented = rows.replacen("0,0.5,0,0,1,0\n", "0,0.5,0,0,1,0  # the first\n", 1);
    assert_eq!(points_of_csv("csv-comment", &commented), plain);
    // A typo in the first row is a bad row, not a header.
    let typo = rows.replacen("0,0.5,0,", "0,0.5,x0,", 1);
    refuses(
        "csv-typo",
        &[("in.csv", typo.as_bytes())],
        &["points", "--scene", "slab", "in.csv", "h.csv"],
        "in.csv:1: expected 6 numbers",
    );
}

#[test]
fn a_normal_of_any_finite_length_is_the_unit_normal() {
    // 1e30 squared overflows f32; 1e-15 squared is 1e-30: both are the unit normal +y.
    let unit = points_of_csv("normal-unit", "0,0.5,0,0,1,0\n");
    assert_eq!(points_of_csv("normal-huge", "0,0.5,0,0,1e30,0\n"), unit);
    assert_eq!(points_of_csv("normal-tiny", "0,0.5,0,0,1e-15,0\n"), unit);
}
