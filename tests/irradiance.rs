//! `hmdist render --method irradiance` end to end: the channels it writes, the direct
//! irradiance against the inverse-square law on a floor under a spot light, the gather's own
//! rays, bit-identical images whatever the threads or the kernel, and refusals by name. The
//! closed form between two planes is in the estimator's own tests.

mod common;

use common::cli::{floor_scene, hmdist_ok, read_json, refuses, render_args, SURFACE_PIXELS};
use common::Scratch;
use hmdist::image::exr;

#[test]
fn a_floor_under_a_spot_light_gets_the_inverse_square_law_and_no_indirect_light() {
    // The floor of `floor_scene` at y = 0, the light 1 above its middle pointing down with a
    // 30° cone: pixel (px, py) of 8 × 8 looks at x, z = 3·((p + ½)/4 − 1). Only the four
    // middle pixels (x² + z² = 0.28 < tan² 30° = 1/3) are inside the cone: E_d = cos θ / r² =
    // 1 / r³ there, 0 on the rest of the floor. Nothing is above the floor: E = 0.
    let dir = floor_scene("irradiance-floor");
    let args = render_args(&[
        "--scene",
        "floor.toml",
        "--method",
        "irradiance",
        "--aov",
        "E_direct",
    ]);
    hmdist_ok(dir.path(), &args);
    let json = read_json(&dir.join("hmd.json"));
    assert_eq!(json["method"], "irradiance");
    assert_eq!(json["channels"], serde_json::json!(["E", "E_direct"]));
    let e = exr::read_channel(&dir.join("hmd.exr"), "E").unwrap();
    let direct = exr::read_channel(&dir.join("hmd.exr"), "E_direct").unwrap();
    let mut lit = 0;
    for py in 0..8u32 {
        for px in 0..8u32 {
            let at = |p: u32| 3.0 * ((p as f64 + 0.5) / 4.0 - 1.0);
            let (x, z) = (at(px), at(py));
            let (e, direct) = (e.at(px, py), direct.at(px, py));
            if x.abs() > 2.0 || z.abs() > 2.0 {
                assert!(e.is_nan() && direct.is_nan(), "background ({px}, {py})");
                continue;
            }
            assert_eq!(e, 0.0, "({px}, {py}): nothing above the floor");
            let r2 = x * x + z * z + 1.0;
            let expected = if x * x + z * z < 1.0 / 3.0 {
                r2.powf(-1.5)
            } else {
                0.0
            };
            lit += (expected > 0.0) as u32;
            assert!(
                (direct as f64 - expected).abs() <= 1e-5 * expected,
                "({px}, {py}): E_direct {direct}, expected {expected}"
            );
        }
    }
    assert_eq!(lit, 4);
    // The gather rays, every one escaped (so no shadow ray from a hit), and a shadow ray for
    // E_direct from each pixel the light faces within its cone.
    let rays = 4 * SURFACE_PIXELS;
    assert_eq!(json["rays_cast"], rays + lit as u64);
    assert_eq!(json["escaped_rays"], rays);
}

#[test]
fn irradiance_casts_the_gathers_rays() {
    // With the same rays, sampler and seed, the rays that escape past --max-distance are the
    // gather's, one for one: the same count over the image.
    let dir = Scratch::new("irradiance-rays");
    let render = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "--quiet",
            "--size",
            "24x20",
            "--rays",
            "32",
            "--max-distance",
            "2",
        ];
        args.extend_from_slice(extra);
        hmdist_ok(dir.path(), &args);
    };
    render(&["--out", "h.exr", "--backend", "cpu"]);
    render(&["--out", "e.exr", "--method", "irradiance"]);
    let (h, e) = (read_json(&dir.join("h.json")), read_json(&dir.join("e.json")));
    let escaped = h["escaped_rays"].as_u64().unwrap();
    assert!(escaped > 0, "some rays go further than 2 in cube");
    assert_eq!(e["escaped_rays"].as_u64(), Some(escaped));
    let image = exr::read(&dir.join("e.exr")).unwrap();
    assert!(image.data.iter().all(|&v| v.is_finite() && v >= 0.0));
    assert!(image.data.iter().any(|&v| v > 0.0));
}

#[test]
fn same_exr_bytes_whatever_the_threads_and_kernel() {
    let dir = Scratch::new("irradiance-bits");
    let mut reference: Option<Vec<u8>> = None;
    let kernels = ["scalar", "avx2", "avx512"]
        .into_iter()
        .filter(|k| hmdist::accel::Kernel::parse(k).is_ok_and(|k| k.available()));
    let runs: Vec<(&str, &str)> = [("1", "scalar"), ("2", "scalar")]
        .into_iter()
        .chain(kernels.map(|k| ("2", k)))
        .collect();
    for (threads, kernel) in runs {
        let out = format!("t{threads}-{kernel}.exr");
        let args = [
            "render",
            "--quiet",
            "--method",
            "irradiance",
            "--aov",
            "E_direct",
            "--out",
            &out,
            "--size",
            "40x30",
            "--rays",
            "64",
            "--threads",
            threads,
        ];
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_hmdist"))
            .args(&args)
            .current_dir(dir.path())
            .env("HMDIST_KERNEL", kernel)
            .status()
            .unwrap();
        assert!(status.success());
        let bytes = std::fs::read(dir.join(&out)).unwrap();
        match &reference {
            None => reference = Some(bytes),
            Some(r) => assert!(r == &bytes, "{threads} threads, {kernel}: other EXR bytes"),
        }
    }
}

#[test]
fn what_irradiance_cannot_do_is_refused_by_name() {
    refuses(
        "irradiance-no-light",
        &[],
        &render_args(&["--method", "irradiance", "--scene", "slab"]),
        "has no spot light",
    );
    refuses(
        "irradiance-gpu",
        &[],
        &render_args(&["--method", "irradiance", "--backend", "gpu"]),
        "irradiance does not read --backend",
    );
    refuses(
        "irradiance-relerr",
        &[],
        &render_args(&["--method", "irradiance", "--aov", "relerr"]),
        "relerr is not measured by irradiance",
    );
    refuses(
        "gather-e-direct",
        &[],
        &render_args(&["--aov", "E_direct"]),
        "E_direct is not measured by gather",
    );
    refuses(
        "irradiance-absorption",
        &[],
        &render_args(&["--method", "irradiance", "--absorption", "2"]),
        "--absorption",
    );
}
