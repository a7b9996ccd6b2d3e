//! Options end to end (spec §1, §3.3, §4, §7): `--max-distance`, photon holes and
//! `--max-radius`, the PNG's `clamp(s·H)` and `--scale`, the camera of a file with none, and
//! `diff`'s `l_diag` from the JSON sidecar. Expected values come from the scene's geometry.
//!
//! The trick behind most of them: on [`floor_scene`] every ray escapes, so with
//! `--max-distance D` every surface pixel has H = D exactly.

mod common;

use common::cli::{floor_scene, hmdist_ok, read_json, FLOOR_DIAGONAL, SURFACE_PIXELS};
use common::Scratch;
use hmdist::image::exr;

/// `hmdist render --quiet` of `scene` in `dir` with 4 rays (at 8 × 8 unless `extra` gives a
/// `--size`), writing `out` (.exr, and .png and .json beside it), with `extra` arguments.
fn render(dir: &Scratch, scene: &str, out: &str, extra: &[&str]) {
    let mut args = vec!["render", "--quiet", "--scene", scene, "--out", out];
    // `--rays` only where the method reads it: another method refuses it.
    let method = extra.windows(2).find(|w| w[0] == "--method").map(|w| w[1]);
    if matches!(method, None | Some("gather" | "cubemap")) {
        args.extend(["--rays", "4"]);
    }
    if !extra.contains(&"--size") {
        args.extend(["--size", "8x8"]);
    }
    args.extend_from_slice(extra);
    hmdist_ok(dir.path(), &args);
}

/// The surface pixels' values and the number of NaN pixels of an EXR.
fn values(dir: &Scratch, exr_name: &str) -> (Vec<f32>, usize) {
    let image = exr::read(&dir.join(exr_name)).unwrap();
    let nan = image.data.iter().filter(|h| h.is_nan()).count();
    (image.data.into_iter().filter(|h| !h.is_nan()).collect(), nan)
}

#[test]
fn max_distance_counts_escapes_as_d_and_clamps_hits() {
    let dir = floor_scene("max-distance");
    render(&dir, "floor.toml", "open.exr", &[]);
    render(&dir, "floor.toml", "clamped.exr", &["--max-distance", "3"]);
    let (open, background) = values(&dir, "open.exr");
    assert_eq!((open.len() as u64, background), (SURFACE_PIXELS, 28));
    assert!(open.iter().all(|h| h.is_infinite()), "{open:?}");
    let (clamped, _) = values(&dir, "clamped.exr");
    assert!(clamped.iter().all(|&h| h == 3.0), "{clamped:?}");
    assert_eq!(
        read_json(&dir.join("clamped.json"))["escaped_rays"],
        4 * SURFACE_PIXELS
    );

    // On the slab floor (h = 1) distances d = h / cos θ beyond D = 2 count as D: under cosine
    // weighting E[1/min(d, D)] = 2/(3h) + h²/(3D³) = 17/24, so H = 24/17 (1.5 unclamped).
    hmdist_ok(
        dir.path(),
        &[
            "render",
            "--quiet",
            "--scene",
            "slab",
            "--size",
            "1x1",
            "--rays",
            "16384",
            "--max-distance",
            "2",
            "--out",
            "slab.exr",
        ],
    );
    let h = values(&dir, "slab.exr").0[0];
    assert!(
        (h / (24.0 / 17.0) - 1.0).abs() < 0.003,
        "H = {h}, expected {}",
        24.0 / 17.0
    );
}

#[test]
fn photon_holes_are_nan_and_counted_and_max_radius_makes_them() {
    // The light's cone covers a disc of radius 0.58 in the middle of the floor; pixels 0.75
    // apart. Within --max-radius 0.05 most pixels find no photon: holes. Without it every
    // pixel finds its K nearest, all facing up like the pixel: no holes.
    let dir = floor_scene("holes");
    let photon = ["--method", "photon1", "--photons", "300", "--gather", "4"];
    render(
        &dir,
        "floor.toml",
        "near.exr",
        &[&photon[..], &["--max-radius", "0.05"]].concat(),
    );
    render(&dir, "floor.toml", "all.exr", &photon);
    let (_, nan) = values(&dir, "near.exr");
    let holes = read_json(&dir.join("near.json"))["holes"].as_u64().unwrap();
    assert_eq!(holes as usize, nan - 28, "holes are the NaN surface pixels");
    assert!(holes >= SURFACE_PIXELS / 2, "{holes}");
    assert_eq!(read_json(&dir.join("all.json"))["holes"], 0);
    assert_eq!(values(&dir, "all.exr").1, 28);
}

#[test]
fn png_is_clamped_scale_times_h_with_the_scene_scale_or_scale() {
    // H = 2 on every surface pixel; the TOML's display scale is 0.1.
    let dir = floor_scene("png");
    for (name, scale, grey) in [
        ("own", None, 51u8),
        ("scaled", Some("0.3"), 153),
        ("clamped", Some("0.6"), 255),
    ] {
        let exr_name = format!("{name}.exr");
        let mut extra = vec!["--max-distance", "2"];
        extra.extend(scale.map(|s| ["--scale", s]).iter().flatten());
        render(&dir, "floor.toml", &exr_name, &extra);
        let png = image::open(dir.join(&format!("{name}.png"))).unwrap().to_luma8();
        let exr = exr::read(&dir.join(&exr_name)).unwrap();
        for (value, pixel) in exr.data.iter().zip(png.pixels()) {
            let expected = if value.is_nan() { 0 } else { grey };
            assert_eq!(pixel.0[0], expected, "{name}: H = {value}");
        }
    }
}

#[test]
fn a_file_without_a_camera_gets_the_framing_camera_of_the_readme() {
    // README: looking at the centre of the bounding box from +z, slightly above (direction
    // (0, 0.3, 1)), far enough out for the bounding sphere (radius l_diag / 2) to fit the 50°
    // field of view: distance = radius / sin 25°.
    let dir = floor_scene("framing");
    let centre = [0.0, 0.0, -0.1];
    let distance = 0.5 * FLOOR_DIAGONAL / 25f64.to_radians().sin();
    let norm = (0.09f64 + 1.0).sqrt();
    let eye = [
        centre[0],
        centre[1] + distance * 0.3 / norm,
        centre[2] + distance / norm,
    ];
    dir.write(
        "framed.toml",
        format!(
            "[[mesh]]\npath = \"floor.obj\"\n[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, {}]\nup = [0, 1, 0]\nfov_y_deg = 50.0\n",
            eye[0], eye[1], eye[2], centre[0], centre[1], centre[2]
        ),
    );
    // H = 1 on every surface pixel: the images differ only where the cameras do.
    let args = ["--max-distance", "1", "--size", "48x32"];
    render(&dir, "floor.obj", "own.exr", &args);
    render(&dir, "framed.toml", "framed.exr", &args);
    let own = values(&dir, "own.exr");
    assert!(
        own.1 > 100 && own.0.len() > 100,
        "the floor fills part of the view: {}",
        own.1
    );
    let bits = |file: &str| {
        exr::read(&dir.join(file))
            .unwrap()
            .data
            .iter()
            .map(|h| h.is_nan())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits("own.exr"),
        bits("framed.exr"),
        "the same pixels see the floor"
    );
    let camera = &read_json(&dir.join("own.json"))["camera"];
    for (key, expected) in [("eye", eye), ("target", centre), ("up", [0.0, 1.0, 0.0])] {
        for (i, value) in expected.iter().enumerate() {
            let got = camera[key][i].as_f64().unwrap();
            assert!(
                (got - value).abs() < 1e-4,
                "camera.{key}[{i}] = {got}, expected {value}"
            );
        }
    }
    assert_eq!(camera["fov_y_deg"], 50.0);
}

#[test]
fn diff_takes_l_diag_from_the_reference_sidecar() {
    // H = 2 against H = 3 on the same 36 pixels: f_diff = |ΔH| · 100 / l_diag = 100 / l_diag.
    let dir = floor_scene("diff");
    render(&dir, "floor.toml", "a.exr", &["--max-distance", "2"]);
    render(&dir, "floor.toml", "b.exr", &["--max-distance", "3"]);
    let line = |text: &str, key: &str| {
        text.lines()
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("{text}"))
            .split_whitespace()
            .last()
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let text = hmdist_ok(dir.path(), &["diff", "a.exr", "b.exr"]);
    assert!(
        (line(&text, "f_diff:") - 100.0 / FLOOR_DIAGONAL).abs() < 1e-5,
        "{text}"
    );
    assert_eq!(line(&text, "pixels compared:"), SURFACE_PIXELS as f64);
    assert_eq!(line(&text, "pixels excluded:"), 28.0);
    // The sidecar, not the EXR or the scene, gives l_diag.
    let json = dir.join("a.json");
    let mut report = read_json(&json);
    report["l_diag"] = 50.0.into();
    std::fs::write(&json, report.to_string()).unwrap();
    let text = hmdist_ok(dir.path(), &["diff", "a.exr", "b.exr"]);
    assert_eq!(line(&text, "f_diff:"), 2.0, "{text}");
}
