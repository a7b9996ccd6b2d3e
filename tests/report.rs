//! The JSON sidecar of every method and backend (spec §7) says what was counted, with the
//! values it must have, and `null` for what a method does not measure.
//!
//! The scene: [`floor_scene`], where every ray from the floor escapes.

mod common;

use common::cli::{floor_scene, hmdist, hmdist_ok, read_json, SURFACE_PIXELS};
use common::{gpu_missing, Scratch};
use serde_json::{json, Value};

const RAYS: u64 = 16;
const PHOTONS: u64 = 500;

/// Renders the floor with `method_args` and returns the JSON sidecar, or `None` where the GPU
/// backend was asked for and this machine has none (the skip is said on stderr).
fn report(dir: &Scratch, test: &str, method_args: &[&str]) -> Option<Value> {
    let rays = RAYS.to_string();
    let photons = PHOTONS.to_string();
    let mut args = vec!["render", "--quiet", "--scene", "floor.toml", "--size", "8x8"];
    // Each method is given only the flags it reads (another method's flag is refused).
    let method = method_args.windows(2).find(|w| w[0] == "--method").map(|w| w[1]);
    if matches!(method, Some("photon1" | "photon2")) {
        args.extend_from_slice(&["--photons", &photons, "--gather", "8"]);
    } else {
        args.extend_from_slice(&["--rays", &rays]);
    }
    args.extend_from_slice(method_args);
    let out = hmdist(dir.path(), &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && gpu_missing(test, &stderr) {
        return None;
    }
    assert!(out.status.success(), "{}: {stderr}", args.join(" "));
    Some(read_json(&dir.join("hmd.json")))
}

/// Asserts that `report` has `key` and that it is `null` (indexing a missing key gives `null`
/// too).
fn assert_null(report: &Value, key: &str) {
    assert_eq!(report.get(key), Some(&Value::Null), "{key}");
}

/// The keys every method writes, with the values this scene gives them.
fn assert_common_keys(report: &Value, method: &str, phases: &[&str]) {
    assert_eq!(report["method"], method);
    assert_eq!(
        (report["width"].as_u64(), report["height"].as_u64()),
        (Some(8), Some(8))
    );
    assert_eq!(report["seed"], 1);
    assert_eq!(report["triangles"], 2);
    let l_diag = report["l_diag"].as_f64().unwrap();
    assert!(
        (l_diag - (4f64.powi(2) + 4.2f64.powi(2)).sqrt()).abs() < 1e-6,
        "l_diag {l_diag}"
    );
    assert_eq!(report["background_pixels"], 64 - SURFACE_PIXELS);
    for phase in ["load", "accel_build", "primary", "estimate", "total"]
        .iter()
        .chain(phases)
    {
        assert!(report["seconds"][phase].is_number(), "{method}: seconds.{phase}");
    }
}

#[test]
fn gather_counts_every_ray_and_every_escape() {
    let dir = floor_scene("report-gather");
    let r = report(&dir, "gather", &["--method", "gather"]).unwrap();
    assert_common_keys(&r, "gather", &[]);
    assert_eq!(r["rays"], RAYS);
    assert_eq!(r["rays_cast"], RAYS * SURFACE_PIXELS);
    assert_eq!(r["escaped_rays"], RAYS * SURFACE_PIXELS);
    assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn cubemap_on_the_cpu_counts_texel_rays_and_lookups() {
    let dir = floor_scene("report-cubemap-cpu");
    let r = report(
        &dir,
        "cubemap cpu",
        &["--method", "cubemap", "--backend", "cpu", "--cube-res", "4"],
    )
    .unwrap();
    assert_common_keys(&r, "cubemap", &["cubemap_build_and_lookup"]);
    assert_eq!((&r["rays"], &r["backend"]), (&json!(RAYS), &json!("cpu")));
    assert_null(&r, "adapter");
    assert_null(&r, "adapter_class");
    // One ray per texel looked up: at least one and at most N per pixel.
    let cast = r["rays_cast"].as_u64().unwrap();
    assert!((SURFACE_PIXELS..=RAYS * SURFACE_PIXELS).contains(&cast), "{cast}");
    assert_eq!(r["texels_rasterised"], cast);
    assert_eq!(r["escaped_rays"], cast);
    assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(r["lookups"], RAYS * SURFACE_PIXELS);
    assert_eq!(r["escaped_lookups"], RAYS * SURFACE_PIXELS);
    assert_eq!(r["texels_per_hemicube"], 12 * 4 * 4);
}

#[test]
fn cubemap_on_the_gpu_casts_no_rays_and_counts_what_it_rasterises_and_looks_up() {
    let test = "cubemap_on_the_gpu_casts_no_rays_and_counts_what_it_rasterises_and_looks_up";
    let dir = floor_scene("report-cubemap-gpu");
    let Some(r) = report(
        &dir,
        test,
        &[
            "--method",
            "cubemap",
            "--backend",
            "gpu-software",
            "--cube-res",
            "4",
        ],
    ) else {
        return;
    };
    assert_common_keys(&r, "cubemap", &["cubemap_build", "cubemap_lookup"]);
    assert_eq!((&r["rays"], &r["backend"]), (&json!(RAYS), &json!("gpu")));
    assert!(r["adapter"].is_string());
    // lavapipe (CI's adapter) is Mesa's software Vulkan; any other is hardware.
    let lavapipe = r["adapter"].as_str().unwrap().contains("llvmpipe");
    assert_eq!(
        r["adapter_class"],
        json!(if lavapipe { "software" } else { "hardware" })
    );
    for key in ["rays_cast", "escaped_rays", "mrays_per_s"] {
        assert_null(&r, key);
    }
    assert_eq!(r["texels_rasterised"], SURFACE_PIXELS * 12 * 4 * 4);
    assert_eq!(r["lookups"], RAYS * SURFACE_PIXELS);
    assert_eq!(r["escaped_lookups"], RAYS * SURFACE_PIXELS);
}

#[test]
fn photon_methods_count_the_rays_of_their_paths_and_have_no_gather_rays() {
    // The light's cone lands on the floor, so every emission ray hits it; a photon stored
    // there leaves upwards and escapes, which ends its path: one photon per path at most.
    let dir = floor_scene("report-photon");
    for (method, bytes) in [("photon1", 20), ("photon2", 28)] {
        let r = report(&dir, method, &["--method", method]).unwrap();
        assert_common_keys(&r, method, &["photon_trace", "photon_index", "gather"]);
        assert_null(&r, "rays");
        assert_eq!(r["photons_stored"], PHOTONS);
        assert_eq!(r["escaped_photons"], PHOTONS);
        let paths = r["paths_traced"].as_u64().unwrap();
        assert!(
            paths > PHOTONS,
            "some paths are absorbed at their first hit: {paths}"
        );
        assert_eq!(r["rays_cast"], paths + PHOTONS);
        assert_eq!(r["escaped_rays"], PHOTONS);
        assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0);
        assert_eq!(r["bytes_per_photon"], bytes);
        assert_eq!(r["holes"], 0);
    }
}

#[test]
fn the_summary_line_names_the_escapes_of_each_method() {
    let dir = floor_scene("report-summary");
    let line = hmdist_ok(
        dir.path(),
        &[
            "render",
            "--scene",
            "floor.toml",
            "--size",
            "8x8",
            "--rays",
            "16",
            "--method",
            "cubemap",
            "--backend",
            "cpu",
        ],
    );
    assert!(
        line.contains(&format!("{} escaped", RAYS * SURFACE_PIXELS)),
        "{line}"
    );
}
