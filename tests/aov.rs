//! AOVs, error bars and adaptive gathering (spec §8): closed forms on the sphere and the
//! slab, error bars against the spread over seeds, adaptive's determinism and ray budget.

mod common;

use hmdist::backend::Backend;
use hmdist::error::Error;
use hmdist::estimators::{registry, AdaptiveParams, Aov, AovImage, GatherParams, PhotonParams};
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions, Rendered};
use hmdist::sampling::{Sampler, Weighting};
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

/// Renders `scene` by `method` with `config` at `size`², asking for `aovs`.
fn rendered(
    scene: &Scene,
    method: &str,
    config: impl serde::Serialize,
    size: u32,
    aovs: &[Aov],
    seed: u64,
) -> Rendered {
    try_rendered(scene, method, config, size, aovs, seed, None).unwrap()
}

fn try_rendered(
    scene: &Scene,
    method: &str,
    config: impl serde::Serialize,
    size: u32,
    aovs: &[Aov],
    seed: u64,
    threads: Option<usize>,
) -> Result<Rendered, Error> {
    let estimator = registry::build(method, &config, aovs)?;
    let options = RenderOptions {
        seed,
        threads,
        aovs: aovs.to_vec(),
        ..RenderOptions::default()
    };
    common::render_square(scene, estimator.as_ref(), size, options)
}

fn channel(r: &Rendered, aov: Aov) -> &[f32] {
    &r.aovs
        .iter()
        .find(|c: &&AovImage| c.aov == aov)
        .expect("asked for")
        .data
}

#[test]
fn inside_a_sphere_h_lies_between_dmin_and_the_diameter_nothing_escapes_and_ao_is_zero_or_one() {
    let r = validation::SPHERE_RADIUS;
    let scene = validation::sphere(r, 6);
    let config = |ao_radius| GatherParams {
        rays: 64,
        ao_radius: Some(ao_radius),
        ..GatherParams::default()
    };
    let all = [Aov::Dmin, Aov::Escaped, Aov::Ao, Aov::Rays];
    // AO radius beyond the diameter: every ray meets the sphere within it.
    let far = rendered(&scene, "gather", config(2.5 * r), 16, &all, 1);
    let (dmin, escaped, ao, rays) = (
        channel(&far, Aov::Dmin),
        channel(&far, Aov::Escaped),
        channel(&far, Aov::Ao),
        channel(&far, Aov::Rays),
    );
    for (i, &h) in far.image.data.iter().enumerate() {
        assert!(
            dmin[i] <= h && h <= 2.0 * r * 1.0001,
            "pixel {i}: dmin {} H {h}",
            dmin[i]
        );
        assert_eq!((escaped[i], ao[i], rays[i]), (0.0, 0.0, 64.0), "pixel {i}");
    }
    // AO radius below every pixel's dmin: no ray meets anything within it.
    let radius = 0.9 * dmin.iter().copied().fold(f32::INFINITY, f32::min);
    let near = rendered(&scene, "gather", config(radius), 16, &all, 1);
    assert!(channel(&near, Aov::Ao).iter().all(|&a| a == 1.0));
    assert_eq!(near.image.data, far.image.data, "AOVs do not change H");
}

#[test]
fn ao_on_the_slab_floor_is_h_over_r_squared() {
    // A direction at θ from the normal meets the ceiling at h / cos θ; under cosine weighting
    // cos² θ is uniform, so the fraction reaching nothing within R is (h/R)² for R > h.
    let h = validation::SLAB_HEIGHT;
    let scene = validation::slab(h, 1000.0);
    for weighting in [Weighting::Cosine, Weighting::Uniform] {
        for radius in [0.9 * h, 1.5 * h, 2.0 * h, 4.0 * h] {
            let config = GatherParams {
                rays: 65_536,
                weighting,
                ao_radius: Some(radius),
                ..GatherParams::default()
            };
            let image = rendered(&scene, "gather", config, 1, &[Aov::Ao], 1);
            let ao = channel(&image, Aov::Ao)[0];
            let expected = if radius > h { (h / radius).powi(2) } else { 1.0 };
            println!("{weighting:?}, R = {radius}: ao = {ao}, expected {expected}");
            assert!(
                (ao - expected).abs() < 0.01,
                "{weighting:?} R = {radius}: {ao} against {expected}"
            );
        }
    }
}

#[test]
fn the_error_bar_predicts_the_spread_of_h_over_seeds() {
    // 30 seeds, 8 rounds of 32 rays, 8 × 8 pixels of cube: per pixel, the standard deviation
    // of H over the seeds against the mean predicted error bar (relerr · H), and how often H
    // lies within ±2 predicted σ of its mean over the seeds. With either sampler: the grid's
    // rounds are independent grids, sobol's independently scrambled sequences.
    for sampler in [Sampler::Grid, Sampler::Sobol] {
        let config = GatherParams {
            rays: 256,
            rounds: Some(8),
            sampler,
            ..GatherParams::default()
        };
        let (median, coverage) = error_bar_against_spread(&format!("{sampler:?}"), "gather", config);
        // 30 seeds leave the observed spread uncertain by about 13 %, 8 rounds each error bar
        // by about 27 % (so ±2σ from 8 rounds covers about 91 %, Student's t with 7 degrees
        // of freedom, not 95 %): a median within a factor 1.25, coverage within [0.87, 0.97].
        assert!(
            (0.8..1.25).contains(&median),
            "{sampler:?}: median ratio {median}"
        );
        assert!(
            (0.87..0.97).contains(&coverage),
            "{sampler:?}: coverage {coverage}"
        );
    }
}

#[test]
fn adaptive_sobol_blocks_overstate_the_error_of_their_mean() {
    // Adaptive's sobol rounds are consecutive blocks of one sequence: stopped at its first
    // check (8 blocks of 32), the same 256 rays as gather --sampler sobol --rays 256. Blocks
    // of a net are negatively correlated, so their spread overstates the error of the whole:
    // a conservative stop, and an error bar that covers more than ±2σ should (the same test
    // as above; measured 0.59 and 0.99).
    let config = AdaptiveParams {
        sampler: Sampler::Sobol,
        tolerance: 1e9,
        min_rays: 256,
        max_rays: 256,
        ..AdaptiveParams::default()
    };
    let (median, coverage) = error_bar_against_spread("adaptive sobol blocks", "adaptive", config);
    assert!((0.35..0.85).contains(&median), "median ratio {median}");
    assert!(coverage >= 0.96, "coverage {coverage}");
}

/// The observed spread of H over 30 seeds against the predicted error bar, per pixel of 8 × 8
/// of `cube`: the median ratio, and the fraction within ±2 predicted σ, away from creases.
fn error_bar_against_spread(label: &str, method: &str, config: impl serde::Serialize + Clone) -> (f64, f64) {
    let scene = Scene::load("cube").unwrap();
    let seeds = 30;
    let aovs = [Aov::Relerr, Aov::Dmin];
    let runs: Vec<Rendered> = (0..seeds)
        .map(|seed| rendered(&scene, method, config.clone(), 8, &aovs, 100 + seed))
        .collect();
    let (mut ratios, mut smooth, mut crease) = (vec![], (0, 0), (0, 0));
    for i in 0..runs[0].image.data.len() {
        let h: Vec<f64> = runs.iter().map(|r| r.image.data[i] as f64).collect();
        let mean = h.iter().sum::<f64>() / seeds as f64;
        let observed = (h.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64).sqrt();
        let sigma: Vec<f64> = runs
            .iter()
            .map(|r| (channel(r, Aov::Relerr)[i] * r.image.data[i]) as f64)
            .collect();
        let predicted = sigma.iter().sum::<f64>() / seeds as f64;
        // Near a crease some ray meets a surface very close: 1/d is heavy-tailed there
        // (spec §1), and rare very short distances make the spread larger than 8 rounds show.
        let near_crease = runs
            .iter()
            .any(|r| channel(r, Aov::Dmin)[i] < 0.05 * r.image.data[i]);
        let within = h
            .iter()
            .zip(&sigma)
            .filter(|(v, s)| (*v - mean).abs() <= 2.0 * *s)
            .count();
        let tally = if near_crease { &mut crease } else { &mut smooth };
        *tally = (tally.0 + within, tally.1 + seeds as usize);
        if !near_crease {
            ratios.push(observed / predicted);
        }
    }
    ratios.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let median = ratios[ratios.len() / 2];
    let coverage = |(within, total): (usize, usize)| within as f64 / total as f64;
    println!(
        "{label}: away from creases ({} pixels): observed / predicted spread median {median:.3}, range {:.3} … {:.3}, \
         ±2σ coverage {:.3}; near creases ({} pixels): coverage {:.3}",
        ratios.len(),
        ratios[0],
        ratios[ratios.len() - 1],
        coverage(smooth),
        crease.1 / seeds as usize,
        coverage(crease)
    );
    (median, coverage(smooth))
}

#[test]
fn adaptive_is_the_same_for_1_and_2_threads_and_keeps_to_its_budget() {
    let scene = Scene::load("cube").unwrap();
    let l_diag = scene.diagonal();
    let grid = AdaptiveParams {
        sampler: Sampler::Grid,
        tolerance: 0.02,
        min_rays: 32,
        max_rays: 512,
        ..AdaptiveParams::default()
    };
    // Sobol blocks with an absolute part and a loosening stop.
    let sobol = AdaptiveParams {
        sampler: Sampler::Sobol,
        tolerance: 0.01,
        abs_tolerance: 0.0005,
        loosen: 0.5,
        ..grid.clone()
    };
    for config in [grid, sobol] {
        let aovs = [Aov::Rays, Aov::Relerr];
        let one = try_rendered(&scene, "adaptive", config.clone(), 24, &aovs, 1, Some(1)).unwrap();
        let two = try_rendered(&scene, "adaptive", config.clone(), 24, &aovs, 1, Some(2)).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.image.data), bits(&two.image.data), "{config:?}");
        assert_eq!(bits(channel(&one, Aov::Rays)), bits(channel(&two, Aov::Rays)));
        let rays = channel(&one, Aov::Rays);
        assert!(
            rays.iter()
                .all(|&n| (32.0..=512.0).contains(&n) && n % 4.0 == 0.0),
            "{rays:?}"
        );
        assert!(
            rays.iter().any(|&n| n > 32.0) && rays.iter().any(|&n| n < 512.0),
            "it adapts"
        );
        // A pixel stops below (T·H + A·l_diag)·(N/m)^G (computed here in f64), or at the
        // budget.
        let bound = |n: f32, h: f32| {
            (config.tolerance as f64 * h as f64 + config.abs_tolerance as f64 * l_diag as f64)
                * (n as f64 / 32.0).powf(config.loosen as f64)
        };
        let relerr = channel(&one, Aov::Relerr);
        for ((n, e), h) in rays.iter().zip(relerr).zip(&one.image.data) {
            let sigma = *e as f64 * *h as f64;
            assert!(
                sigma < bound(*n, *h) * 1.0001 || *n + 4.0 > 512.0,
                "{config:?}: {n} rays, σ {sigma}, bound {}",
                bound(*n, *h)
            );
        }
        assert_eq!(one.report.rays_cast, Some(rays.iter().map(|&n| n as u64).sum()));
    }
}

#[test]
fn an_adaptive_sobol_pixel_that_stops_at_n_rays_has_the_h_of_a_sobol_gather_of_n() {
    // Its rounds are consecutive blocks of one sequence: nothing of the sequence's
    // stratification is lost by stopping anywhere.
    let scene = Scene::load("cube").unwrap();
    let adaptive = AdaptiveParams {
        sampler: Sampler::Sobol,
        tolerance: 0.06,
        min_rays: 64,
        max_rays: 128,
        ..AdaptiveParams::default()
    };
    let a = rendered(&scene, "adaptive", adaptive, 16, &[Aov::Rays], 3);
    let rays = channel(&a, Aov::Rays);
    let mut counts: Vec<u32> = rays.iter().map(|&n| n as u32).collect();
    counts.sort();
    counts.dedup();
    assert!(counts.len() >= 3, "pixels stop at several counts: {counts:?}");
    let mut compared = 0;
    for n in counts {
        let gather = GatherParams {
            rays: n,
            sampler: Sampler::Sobol,
            ..GatherParams::default()
        };
        let g = rendered(&scene, "gather", gather, 16, &[], 3);
        for (i, &r) in rays.iter().enumerate() {
            if r as u32 == n {
                assert_eq!(
                    a.image.data[i].to_bits(),
                    g.image.data[i].to_bits(),
                    "pixel {i}, {n} rays"
                );
                compared += 1;
            }
        }
    }
    assert_eq!(compared, 256);
    // The grid's rounds are not one grid: its pixels are not gather's of the same N.
    let grid = rendered(
        &scene,
        "adaptive",
        AdaptiveParams {
            sampler: Sampler::Grid,
            tolerance: 1e9,
            min_rays: 64,
            ..AdaptiveParams::default()
        },
        16,
        &[],
        3,
    );
    let gather = GatherParams {
        rays: 64,
        sampler: Sampler::Grid,
        ..GatherParams::default()
    };
    assert_ne!(
        grid.image.data,
        rendered(&scene, "gather", gather, 16, &[], 3).image.data
    );
}

#[test]
fn adaptive_refuses_a_stop_that_never_comes_and_negative_tolerances() {
    let scene = Scene::load("cube").unwrap();
    for (config, name) in [
        (serde_json::json!({"tolerance": 0.0}), "tolerance"),
        (serde_json::json!({"tolerance": -0.1}), "tolerance"),
        (serde_json::json!({"abs_tolerance": -1e-3}), "abs_tolerance"),
        (serde_json::json!({"loosen": -0.5}), "loosen"),
    ] {
        let error = try_rendered(&scene, "adaptive", &config, 4, &[], 1, None)
            .err()
            .unwrap_or_else(|| panic!("{config} accepted"));
        assert!(error.to_string().contains(name), "{config}: {error}");
    }
    let absolute_only = serde_json::json!({"tolerance": 0.0, "abs_tolerance": 1e-3});
    assert!(try_rendered(&scene, "adaptive", &absolute_only, 4, &[], 1, None).is_ok());
}

#[test]
fn adaptive_stopping_at_its_first_check_is_gather_in_the_same_rounds() {
    let scene = Scene::load("cube").unwrap();
    let adaptive = AdaptiveParams {
        sampler: Sampler::Grid,
        tolerance: 1e9,
        min_rays: 64,
        ..AdaptiveParams::default()
    };
    // On the CPU, as adaptive (auto would take a GPU where HMDIST_GPU_SOFTWARE offers one).
    let gather = GatherParams {
        rays: 64,
        rounds: Some(8),
        backend: Backend::Cpu,
        sampler: Sampler::Grid,
        ..GatherParams::default()
    };
    let a = rendered(&scene, "adaptive", adaptive, 16, &[], 3);
    let g = rendered(&scene, "gather", gather, 16, &[], 3);
    assert_eq!(a.image.data, g.image.data);
    // One grid of 64 rays is another set of directions than 8 rounds of 8.
    let single = rendered(
        &scene,
        "gather",
        GatherParams {
            rays: 64,
            backend: Backend::Cpu,
            sampler: Sampler::Grid,
            ..GatherParams::default()
        },
        16,
        &[],
        3,
    );
    assert_ne!(single.image.data, g.image.data);
}

#[test]
fn aovs_a_method_cannot_give_are_refused_by_name() {
    let scene = Scene::load("cube").unwrap();
    let refused = |method: &str, config: serde_json::Value, aovs: &[Aov], name: &str| {
        // Built without the AOVs (so `gather` keeps one round), then asked for them.
        let estimator = registry::build(method, &config, &[]).unwrap();
        let options = RenderOptions {
            width: 4,
            height: 4,
            aovs: aovs.to_vec(),
            ..RenderOptions::default()
        };
        let e = render(&scene, estimator.as_ref(), &options, &Silent)
            .err()
            .expect("refused");
        assert!(
            matches!(&e, Error::Parameter { name: Some(n), .. } if *n == name),
            "{e}"
        );
    };
    let photons = PhotonParams {
        photons: 1000,
        ..PhotonParams::default()
    };
    refused(
        "photon2",
        serde_json::to_value(photons).unwrap(),
        &[Aov::Rays],
        "aov",
    );
    refused("gather", serde_json::json!({}), &[Aov::Relerr], "rounds");
    refused("adaptive", serde_json::json!({}), &[Aov::Ao], "ao_radius");
    let e = registry::build(
        "gather",
        &GatherParams {
            rays: 60,
            rounds: Some(8),
            ..GatherParams::default()
        },
        &[],
    );
    assert!(matches!(
        e.err(),
        Some(Error::Parameter {
            name: Some("rounds"),
            ..
        })
    ));
}

#[test]
fn hmdist_render_writes_each_aov_as_a_channel_of_its_name_and_lists_them() {
    use common::cli::{hmdist_ok, read_json, refuses};
    let dir = common::Scratch::new("aov-cli");
    let args = [
        "render",
        "--quiet",
        "--size",
        "12x10",
        "--rays",
        "16",
        "--aov",
        "rays,escaped,relerr",
        "--png-aov",
        "dmin",
        "dmin.png",
    ];
    hmdist_ok(dir.path(), &args);
    let json = read_json(&dir.join("hmd.json"));
    assert_eq!(
        json["channels"],
        serde_json::json!(["Y", "rays", "escaped", "relerr", "dmin"])
    );
    assert_eq!(
        json["parameters"]["rounds"], 8,
        "relerr without --rounds takes 8 rounds"
    );
    let exr = dir.join("hmd.exr");
    let rays = hmdist::image::exr::read_channel(&exr, "rays").unwrap();
    assert!(rays.data.iter().all(|&n| n == 16.0), "{:?}", rays.data);
    let escaped = hmdist::image::exr::read_channel(&exr, "escaped").unwrap();
    assert!(escaped.data.iter().all(|&e| e == 0.0), "cube is closed");
    let y = hmdist::image::exr::read(&exr).unwrap();
    let dmin = hmdist::image::exr::read_channel(&exr, "dmin").unwrap();
    assert!(y.data.iter().zip(&dmin.data).all(|(h, d)| d <= h));
    let png = image::open(dir.join("dmin.png")).unwrap();
    assert_eq!(png.width(), 200, "widened for the legend");
    refuses(
        "aov-unknown",
        &[],
        &["render", "--quiet", "--size", "4x4", "--aov", "colour"],
        "invalid value 'colour'",
    );
    let photon = [
        "render",
        "--quiet",
        "--size",
        "4x4",
        "--method",
        "photon1",
        "--photons",
        "100",
        "--aov",
        "rays",
    ];
    refuses(
        "aov-photon",
        &[],
        &photon,
        "--aov rays is not measured by photon1",
    );
    let rounds = [
        "render", "--quiet", "--size", "4x4", "--rays", "10", "--rounds", "3",
    ];
    refuses("aov-rounds", &[], &rounds, "--rounds must divide the rays (10)");
}
