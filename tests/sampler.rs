//! The progressive sampler of `gather` (`--sampler sobol`, issue #25; the default since
//! issue #54): the closed forms of spec §1 hold with it, it is deterministic across thread
//! counts, each round is its own sequence, every backend takes it, and `--sampler grid` still
//! names the jittered grid. (Its stratification, every power-of-two prefix a (0,k,2)-net, is
//! tested in `sampling.rs`.)

mod common;

use hmdist::estimators::{registry, Estimator, GatherParams};
use hmdist::render::{RenderOptions, Rendered};
use hmdist::sampling::{Sampler, Weighting};
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

fn sobol(rays: u32, weighting: Weighting, rounds: u32) -> Box<dyn Estimator> {
    let params = GatherParams {
        rays,
        weighting,
        rounds: Some(rounds),
        sampler: Sampler::Sobol,
        ..GatherParams::default()
    };
    registry::build("gather", &params, &[]).unwrap()
}

fn rendered(scene: &Scene, estimator: &dyn Estimator, size: u32, threads: Option<usize>) -> Rendered {
    let options = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    common::render_square(scene, estimator, size, options).unwrap()
}

#[test]
fn with_the_sobol_sampler_the_closed_forms_hold() {
    // Inside a closed sphere the mean of R/H over pixels is 1 (1/H is unbiased for 1/R).
    let r = validation::SPHERE_RADIUS;
    let sphere = validation::sphere(r, 7);
    let image = rendered(&sphere, sobol(4096, Weighting::Cosine, 1).as_ref(), 32, None);
    assert_eq!(image.report.escaped_rays, Some(0));
    let mean: f64 =
        image.image.data.iter().map(|&h| r as f64 / h as f64).sum::<f64>() / image.image.data.len() as f64;
    assert!((mean - 1.0).abs() < 0.005, "mean R/H = {mean}");
    // The slab's floor: 3h/2 under cosine weighting, 2h under uniform (not a power of two
    // of rays, in 4 rounds: each round a sequence of its own).
    let h = validation::SLAB_HEIGHT;
    let slab = validation::slab(h, 1000.0);
    for (weighting, expected) in [(Weighting::Cosine, 1.5 * h), (Weighting::Uniform, 2.0 * h)] {
        let got = rendered(&slab, sobol(60_000, weighting, 4).as_ref(), 1, None)
            .image
            .data[0];
        assert!(
            (got / expected - 1.0).abs() < 0.005,
            "{weighting:?}: H = {got}, expected {expected}"
        );
    }
}

#[test]
fn sobol_gather_is_the_same_for_1_and_2_threads_and_not_the_grid() {
    let scene = Scene::load("cube").unwrap();
    let bits = |r: &Rendered| r.image.data.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    let one = rendered(&scene, sobol(64, Weighting::Cosine, 1).as_ref(), 24, Some(1));
    let two = rendered(&scene, sobol(64, Weighting::Cosine, 1).as_ref(), 24, Some(2));
    assert_eq!(bits(&one), bits(&two));
    let grid = serde_json::json!({"rays": 64, "sampler": "grid"});
    let grid = rendered(
        &scene,
        registry::build("gather", &grid, &[]).unwrap().as_ref(),
        24,
        Some(2),
    );
    assert_ne!(bits(&one), bits(&grid));
    // Sobol is the default.
    let default = registry::build("gather", &serde_json::json!({"rays": 64}), &[]).unwrap();
    assert_eq!(bits(&one), bits(&rendered(&scene, default.as_ref(), 24, Some(1))));
    // Two rounds of 32 are two sequences, not the first 64 points of one.
    let rounds = rendered(&scene, sobol(64, Weighting::Cosine, 2).as_ref(), 24, Some(2));
    assert_ne!(bits(&one), bits(&rounds));
    // The report says which sampler, among the parameters.
    let json: serde_json::Value = serde_json::from_str(&one.report.to_json()).unwrap();
    assert_eq!(json["parameters"]["sampler"], "sobol");
    let json: serde_json::Value = serde_json::from_str(&grid.report.to_json()).unwrap();
    assert_eq!(json["parameters"]["sampler"], "grid", "{json}");
}

/// Every backend takes the sobol sampler (the GPU's image against the CPU's is
/// tests/gpu_gather.rs's `gpu_sobol_gather_agrees_with_cpu_on_cube`).
#[test]
fn every_backend_takes_the_sobol_sampler() {
    for backend in ["auto", "cpu", "gpu", "gpu-software"] {
        let params = serde_json::json!({"sampler": "sobol", "backend": backend});
        let gather = registry::build("gather", &params, &[]);
        assert!(gather.is_ok(), "{backend}: {:?}", gather.err());
    }
}

#[test]
fn hmdist_render_takes_the_sampler_flag() {
    use common::cli::{hmdist_ok, read_json, refuses, render_args};
    let dir = common::Scratch::new("sampler-cli");
    for (flags, sampler) in [(&["--sampler", "grid"][..], "grid"), (&[][..], "sobol")] {
        let mut args = render_args(&[flags, &["--backend", "cpu"][..]].concat());
        args.extend(["--out", "s.exr"]);
        hmdist_ok(dir.path(), &args);
        assert_eq!(read_json(&dir.join("s.json"))["parameters"]["sampler"], sampler);
    }
    refuses(
        "sampler-cubemap",
        &[],
        &render_args(&["--method", "cubemap", "--sampler", "sobol"]),
        "--method cubemap does not read --sampler",
    );
}
