//! `hmdist cache` and the library's `cache`: the brute-force image in the limit a → 0, the
//! same records whatever the threads, the placement rule level by level, the error against a
//! reference, and refusals by name.

mod common;

use common::cli::{hmdist_ok, read_json, refuses};
use common::Scratch;
use hmdist::cache::{cache, CacheParams, Spacing};
use hmdist::estimators::IrradianceParams;
use hmdist::image::exr;
use hmdist::progress::Silent;
use hmdist::render::RenderOptions;
use hmdist::scene::Scene;

const SIZE: &str = "64x48";

/// `render --method irradiance` of `scene` at `size` with `rays` rays, into `out`.
fn irradiance(dir: &Scratch, out: &str, scene_size_rays: (&str, &str, &str)) {
    irradiance_with(dir, out, scene_size_rays, &[]);
}

/// [`irradiance`] with `extra` flags.
fn irradiance_with(dir: &Scratch, out: &str, (scene, size, rays): (&str, &str, &str), extra: &[&str]) {
    let mut args = vec![
        "render",
        "--quiet",
        "--method",
        "irradiance",
        "--scene",
        scene,
        "--size",
        size,
        "--rays",
        rays,
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    hmdist_ok(dir.path(), &args);
}

fn cache_args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["cache", "--quiet", "--size", SIZE, "--rays", "16", "--out", out];
    args.extend_from_slice(extra);
    args
}

#[test]
fn a_tiny_accuracy_gives_every_pixel_its_own_record_and_the_brute_force_image() {
    let dir = Scratch::new("cache-limit");
    irradiance(&dir, "e.exr", ("cube", SIZE, "16"));
    hmdist_ok(
        dir.path(),
        &cache_args("c.exr", &["--accuracy", "1e-9", "--reference", "e.exr"]),
    );
    let (e, cached) = (
        exr::read_channel(&dir.join("e.exr"), "E").unwrap(),
        exr::read_channel(&dir.join("c.exr"), "E").unwrap(),
    );
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&cached.data), bits(&e.data));
    let report = read_json(&dir.join("c.json"));
    assert_eq!(
        report["records"],
        64 * 48,
        "cube is closed: every pixel a surface"
    );
    assert_eq!(report["reference"]["mean_relative_error"], 0.0);
    let used = exr::read_channel(&dir.join("c.exr"), "records").unwrap();
    assert!(used.data.iter().all(|&n| n == 1.0));
    // With a usual accuracy the cache makes far fewer records and errs a little.
    hmdist_ok(
        dir.path(),
        &cache_args("d.exr", &["--accuracy", "0.3", "--reference", "e.exr"]),
    );
    let report = read_json(&dir.join("d.json"));
    let records = report["records"].as_u64().unwrap();
    assert!(records < 64 * 48 / 3, "{records} records");
    let error = report["reference"]["mean_relative_error"].as_f64().unwrap();
    assert!(error > 0.0 && error < 0.5, "mean relative error {error}");
}

#[test]
fn the_same_records_whatever_the_threads_and_each_outside_the_coarser_records() {
    let scene = Scene::load("cube").unwrap();
    // (spacing, neighbour clamping, gradients)
    for (spacing, neighbour_clamp, gradients) in [
        ("hmd", false, false),
        ("min10", false, false),
        ("hmd:gather:rays=8", false, false),
        ("hmd:photon1:photons=3000,nearest=16", false, false),
        ("hmd", true, true),
        ("min10", true, false),
    ] {
        let params = CacheParams {
            irradiance: IrradianceParams {
                rays: 16,
                ..IrradianceParams::default()
            },
            accuracy: 0.25,
            spacing: Spacing::parse(spacing).unwrap(),
            neighbour_clamp,
            gradients,
            ..CacheParams::default()
        };
        let spacing = format!("{spacing} neighbour_clamp={neighbour_clamp} gradients={gradients}");
        let run = |threads| {
            let options = RenderOptions {
                width: 40,
                height: 30,
                threads: Some(threads),
                ..RenderOptions::default()
            };
            cache(&scene, &params, &options, None, &Silent).unwrap()
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one.records, two.records, "{spacing}");
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.image.data), bits(&two.image.data), "{spacing}");
        // A record is made only where no record of a coarser level covers its pixel.
        for record in &one.records {
            for earlier in one.records.iter().filter(|r| r.level > record.level) {
                let error = earlier.error(record.pixel, record.point, record.normal);
                assert!(
                    error >= params.accuracy,
                    "{spacing}: {record:?} is covered by {earlier:?}"
                );
            }
        }
        assert!(one.records.iter().any(|r| r.level > 0) && one.records.len() < 40 * 30);
        // Every pixel covered (with neighbour clamping only because its finest level repeats
        // until none is left: without that, NaN pixels here, seen).
        assert!(one.image.data.iter().all(|e| e.is_finite() && *e >= 0.0));
    }
}

#[test]
fn oracle_spacing_reads_an_image_of_h_and_places_the_same_records_twice() {
    let dir = Scratch::new("cache-oracle");
    hmdist_ok(
        dir.path(),
        &[
            "render", "--quiet", "--size", SIZE, "--rays", "64", "--out", "h.exr",
        ],
    );
    for out in ["a.exr", "b.exr"] {
        hmdist_ok(
            dir.path(),
            &cache_args(out, &["--spacing", "oracle", "--oracle", "h.exr"]),
        );
    }
    for name in ["a.exr", "a.png"] {
        let other = name.replace('a', "b");
        assert!(
            std::fs::read(dir.join(name)).unwrap() == std::fs::read(dir.join(&other)).unwrap(),
            "{name} and {other} differ"
        );
    }
    assert_eq!(read_json(&dir.join("a.json"))["spacing"], "oracle");
}

#[test]
fn bad_input_is_refused_by_name() {
    for (case, extra, says) in [
        ("a0", &["--accuracy", "0"][..], "--accuracy"),
        ("a-neg", &["--accuracy=-0.1"], "--accuracy"),
        (
            "source",
            &["--spacing", "nearest"],
            "--spacing 'nearest' is not one of",
        ),
        (
            "source-method",
            &["--spacing", "hmd:irradiance"],
            "does not estimate H",
        ),
        ("oracle-missing", &["--spacing", "oracle"], "--oracle"),
        ("clamp", &["--clamp-pixels", "15,2.5"], "--clamp-pixels"),
        ("no-light", &["--scene", "slab"], "has no spot light"),
        (
            "gradients-uniform",
            &["--gradients", "--weighting", "uniform"],
            "--gradients need cosine-weighted rays",
        ),
    ] {
        refuses(&format!("cache-{case}"), &[], &cache_args("c.exr", extra), says);
    }
    let twelve = [
        "cache",
        "--quiet",
        "--size",
        SIZE,
        "--rays",
        "12",
        "--gradients",
        "--out",
        "c.exr",
    ];
    refuses(
        "cache-gradients-rays",
        &[],
        &twelve,
        "sobol with a power of two --rays (not 12)",
    );
    // A reference of another size, and of another scene.
    let dir = Scratch::new("cache-reference");
    irradiance(&dir, "small.exr", ("cube", "16x12", "4"));
    irradiance(&dir, "hall.exr", ("hall", SIZE, "4"));
    for (reference, says) in [
        ("small.exr", "16x12, the cache 64x48"),
        ("hall.exr", "scene (hall against cube)"),
    ] {
        let out = common::cli::hmdist(dir.path(), &cache_args("c.exr", &["--reference", reference]));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains("--reference") && stderr.contains(says),
            "{stderr}"
        );
        assert!(!dir.join("c.exr").exists());
    }
}

#[test]
fn gradients_keep_the_records_and_lower_the_error_neighbour_clamping_adds_records() {
    // cube 96 × 72, records of 256 rays, a = 0.3, against a 2,048-ray image of E: Ward and
    // Heckbert's gradients carry each record's E to the point, so the same records give a
    // smaller error (measured: mean 5.7 → 4.9 %, p95 19 → 16 % against 4,096 rays); the
    // neighbours' radii cut each other's, so there are more records, each no larger than
    // without.
    let dir = Scratch::new("cache-gradients");
    irradiance(&dir, "e.exr", ("cube", "96x72", "2048"));
    let reference = exr::read_channel(&dir.join("e.exr"), "E").unwrap();
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: 96,
        height: 72,
        ..RenderOptions::default()
    };
    let run = |neighbour_clamp, gradients| {
        let params = CacheParams {
            irradiance: IrradianceParams {
                rays: 256,
                ..IrradianceParams::default()
            },
            accuracy: 0.3,
            neighbour_clamp,
            gradients,
            ..CacheParams::default()
        };
        let mut cached = cache(&scene, &params, &options, None, &Silent).unwrap();
        cached.compare(&reference, "e.exr").unwrap();
        cached
    };
    let (plain, graded, clamped) = (run(false, false), run(false, true), run(true, false));
    let pixels = |c: &hmdist::cache::Cached| c.records.iter().map(|r| r.pixel).collect::<Vec<_>>();
    assert_eq!(pixels(&plain), pixels(&graded), "gradients move no record");
    let errors = |c: &hmdist::cache::Cached| {
        let r = c.report.reference.as_ref().unwrap();
        (r.mean_relative_error, r.p95_relative_error)
    };
    let (before, after) = (errors(&plain), errors(&graded));
    println!("without gradients {before:?}, with {after:?}");
    assert!(
        after.0 < 0.95 * before.0 && after.1 < before.1,
        "{before:?} → {after:?}"
    );
    assert!(graded.records.iter().all(|r| r.gradients.is_some()));
    assert!(plain.records.iter().all(|r| r.gradients.is_none()));
    assert!(
        clamped.records.len() > plain.records.len(),
        "{} against {}",
        clamped.records.len(),
        plain.records.len()
    );
    assert!(clamped.report.neighbour_clamp && graded.report.gradients);
}

/// `hmdist cache ARGS` in `dir`: its exit status and stderr.
fn cache_in(dir: &Scratch, extra: &[&str]) -> (Option<i32>, String) {
    let out = common::cli::hmdist(dir.path(), &cache_args("c.exr", extra));
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The image at `from` with `change` applied to its data, written to `to` (no sidecar).
fn edited(dir: &Scratch, from: &str, channel: &str, to: &str, change: impl FnOnce(&mut Vec<f32>)) {
    let mut image = exr::read_channel(&dir.join(from), channel).unwrap();
    change(&mut image.data);
    let bytes = exr::encode_as(channel, &image, &[], &dir.join(to)).unwrap();
    std::fs::write(dir.join(to), bytes).unwrap();
}

#[test]
fn an_oracle_or_a_reference_that_is_not_h_or_e_of_these_pixels_is_refused_by_what_it_holds() {
    let dir = Scratch::new("cache-hostile-images");
    hmdist_ok(
        dir.path(),
        &[
            "render", "--quiet", "--size", SIZE, "--rays", "16", "--out", "h.exr",
        ],
    );
    irradiance(&dir, "e.exr", ("cube", SIZE, "4"));
    // A negative H made neighbour clamping loop for ever; NaN and -inf are no H either.
    for (name, value) in [
        ("negative.exr", -1.0f32),
        ("nan.exr", f32::NAN),
        ("minus-inf.exr", f32::NEG_INFINITY),
    ] {
        edited(&dir, "h.exr", "Y", name, |d| d[100] = value);
        let (code, stderr) = cache_in(
            &dir,
            &["--spacing", "oracle", "--oracle", name, "--neighbour-clamp"],
        );
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains("--oracle holds H =") && stderr.contains("pixel (36, 1)"),
            "{name}: {stderr}"
        );
    }
    // A reference that is no irradiance: negative, infinite, or NaN where the cache sees a surface.
    for (name, value) in [
        ("e-negative.exr", -0.5f32),
        ("e-inf.exr", f32::INFINITY),
        ("e-nan.exr", f32::NAN),
    ] {
        edited(&dir, "e.exr", "E", name, |d| d[7] = value);
        let (code, stderr) = cache_in(&dir, &["--reference", name]);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains("holds E =") && stderr.contains("pixel (7, 0)"),
            "{name}: {stderr}"
        );
    }
    // Renders of other pixels: another absorption, a shard's part, an image of H.
    irradiance_with(&dir, "e-half.exr", ("cube", SIZE, "4"), &["--absorption", "0.5"]);
    irradiance_with(&dir, "e-part.exr", ("cube", SIZE, "4"), &["--shard", "0/2"]);
    for (name, says) in [
        ("e-half.exr", "absorption (Some(0.5) against Some(0.2))"),
        ("e-part.exr", "a shard's part (0/2 against a whole image)"),
    ] {
        let (code, stderr) = cache_in(&dir, &["--reference", name]);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains("is not an image of the pixels this cache makes") && stderr.contains(says),
            "{name}: {stderr}"
        );
    }
    // The sidecar of a reference is an input too: --json may not overwrite it.
    let before = std::fs::read(dir.join("e.json")).unwrap();
    let (code, stderr) = cache_in(&dir, &["--reference", "e.exr", "--json", "e.json"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert_eq!(
        std::fs::read(dir.join("e.json")).unwrap(),
        before,
        "the reference's report is kept"
    );
    assert!(!dir.join("c.exr").exists());
}

#[test]
fn a_light_that_reaches_nothing_the_camera_sees_is_a_valid_cache_with_no_error() {
    // E = 0 everywhere is an answer, not a reference "of another scene". The light lights a
    // second floor under the first, which nothing the camera sees can see.
    let dir = Scratch::new("cache-dark");
    dir.write(
        "floor.obj",
        "v -5 0 -5\nv 5 0 -5\nv 5 0 5\nv -5 0 5\nv -5 -3 -5\nv 5 -3 -5\nv 5 -3 5\nv -5 -3 5\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n",
    );
    dir.write(
        "dark.toml",
        "[[mesh]]\npath = \"floor.obj\"\n[camera]\neye = [0, 3, 3]\ntarget = [0, 0, 0]\nfov_y_deg = 60\n\
         [light]\nposition = [0, -1, 0]\ndirection = [0, -1, 0]\ncone_half_angle_deg = 30\n",
    );
    irradiance(&dir, "e.exr", ("dark.toml", SIZE, "4"));
    hmdist_ok(
        dir.path(),
        &cache_args("c.exr", &["--scene", "dark.toml", "--reference", "e.exr"]),
    );
    let report = read_json(&dir.join("c.json"));
    assert_eq!(report["reference"]["mean_relative_error"], 0.0, "{report}");
    // The cache study of such a scene says there is nothing to rank, and draws no plot of
    // zeros on log axes.
    hmdist_ok(
        dir.path(),
        &[
            "experiment",
            "cache",
            "--quiet",
            "--scene",
            "dark.toml",
            "--size",
            "16",
            "--out",
            "x",
        ],
    );
    let html = std::fs::read_to_string(dir.join("x/index.html")).unwrap();
    assert!(html.contains("Nothing to rank: the light reaches nothing the camera sees"));
    assert!(!dir.join("x/cache.svg").exists() && dir.join("x/cache.md").is_file());
}

#[test]
fn a_reference_made_by_cache_is_named_as_such() {
    // A cache's image is what a reference measures: given as one, its report is named for
    // what it is, not as a report missing a field.
    let dir = Scratch::new("cache-of-cache");
    hmdist_ok(dir.path(), &cache_args("first.exr", &[]));
    let (code, stderr) = cache_in(&dir, &["--reference", "first.exr"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("first.json is the report of `hmdist cache`") && !stderr.contains("missing field"),
        "{stderr}"
    );
    assert!(!dir.join("c.exr").exists());
}
