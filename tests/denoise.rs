//! `--denoise` ([`hmdist::denoise`]): against closed forms (a closed sphere, floors under a
//! ceiling), converging as the rays grow, the same bits on any number of threads, and refused
//! by name where it cannot be honest.

mod common;

use glam::Vec3;
use hmdist::denoise::DenoiseParams;
use hmdist::estimators::{AdaptiveParams, Estimator, Gather, GatherParams};
use hmdist::image::HmdImage;
use hmdist::metrics::f_diff;
use hmdist::render::{RenderOptions, Rendered};
use hmdist::sampling::Weighting;
use hmdist::scene::procedural::validation;
use hmdist::scene::{Camera, Mesh, Scene};

use common::render_square;

fn gather(rays: u32) -> Gather {
    GatherParams {
        rays,
        ..Default::default()
    }
    .build()
    .unwrap()
}

fn rendered(
    scene: &Scene,
    estimator: &dyn Estimator,
    size: u32,
    denoise: bool,
    threads: Option<usize>,
) -> Rendered {
    let options = RenderOptions {
        denoise: denoise.then(DenoiseParams::default),
        threads,
        ..Default::default()
    };
    render_square(scene, estimator, size, options).unwrap()
}

/// The mean of `R/H` over the finite pixels, and the mean of `|R/H − 1|`.
fn ratio_to(image: &HmdImage, radius: f32) -> (f64, f64) {
    let ratios: Vec<f64> = image
        .data
        .iter()
        .filter(|h| h.is_finite())
        .map(|&h| radius as f64 / h as f64)
        .collect();
    let n = ratios.len() as f64;
    let mean = ratios.iter().sum::<f64>() / n;
    let spread = ratios.iter().map(|r| (r - 1.0).abs()).sum::<f64>() / n;
    (mean, spread)
}

#[test]
fn inside_a_closed_sphere_the_filtered_image_is_the_radius_with_less_noise() {
    // H = R at every point inside a closed sphere: the filter's neighbours all estimate the
    // same S = 1/R, so the filtered image must be R (its mean of R/H within the unfiltered
    // image's own standard error of that mean) and nearer R pixel by pixel. A fine sphere
    // (327,680 triangles): a coarser one's facets move H by a few per cent.
    let radius = validation::SPHERE_RADIUS;
    let scene = validation::sphere(radius, 7);
    let plain = rendered(&scene, &gather(32), 48, false, None);
    let filtered = rendered(&scene, &gather(32), 48, true, None);
    let (plain_mean, plain_spread) = ratio_to(&plain.image, radius);
    let (mean, spread) = ratio_to(&filtered.image, radius);
    let pixels = plain.image.data.iter().filter(|h| h.is_finite()).count() as f64;
    // The unfiltered mean of R/H is unbiased; its standard error is about spread/√pixels.
    let standard_error = plain_spread / pixels.sqrt();
    // The tessellated sphere and the ray offset move the unfiltered mean by about 1 %. The
    // filter damps the rare near-horizon hits that make 1/d heavy-tailed here (a pixel far
    // above its neighbours is averaged down, its neighbours keep it out), so its mean of R/H
    // falls by about 1 % at 32 rays: within 2 % of both.
    assert!(
        (plain_mean - 1.0).abs() < 0.02,
        "plain {plain_mean} ± {standard_error}"
    );
    assert!((mean - 1.0).abs() < 0.02, "filtered {mean} ± {standard_error}");
    assert!(
        (mean - plain_mean).abs() < 0.02,
        "filtered {mean}, plain {plain_mean}"
    );
    assert!(
        spread < 0.5 * plain_spread,
        "filtered spread {spread} against {plain_spread}"
    );
    let constant = HmdImage::new(
        48,
        48,
        plain
            .image
            .data
            .iter()
            .map(|h| if h.is_nan() { *h } else { radius })
            .collect(),
    );
    let l_diag = scene.diagonal();
    let (f_plain, f_filtered) = (
        f_diff(&constant, &plain.image, l_diag).unwrap().value,
        f_diff(&constant, &filtered.image, l_diag).unwrap().value,
    );
    assert!(
        f_filtered < 0.5 * f_plain,
        "f_diff {f_filtered} against {f_plain}"
    );
    let report = filtered.report.denoise.expect("the report names the filter");
    assert!(
        report.filtered && report.params == DenoiseParams::default(),
        "{report:?}"
    );
}

/// Floors under a ceiling at height 1: y = 0 where x < 0 and a platform at y = ½ where
/// x > 0, with the step's wall between them, 16 wide; the camera looks straight down at the
/// step from y = 0.9 (H = 3·(1 − y)/2 far from the step: 1.5 below, 0.75 on the platform).
fn step() -> Scene {
    let (w, s) = (8.0f32, 0.5f32);
    let mut mesh = Mesh::new();
    let mut quad = |corners: [Vec3; 4]| {
        let first = mesh.add_vertices(corners);
        mesh.add_triangle(first, first + 1, first + 2);
        mesh.add_triangle(first, first + 2, first + 3);
    };
    quad([
        Vec3::new(-w, 1.0, -w),
        Vec3::new(w, 1.0, -w),
        Vec3::new(w, 1.0, w),
        Vec3::new(-w, 1.0, w),
    ]);
    quad([
        Vec3::new(-w, 0.0, -w),
        Vec3::new(0.0, 0.0, -w),
        Vec3::new(0.0, 0.0, w),
        Vec3::new(-w, 0.0, w),
    ]);
    quad([
        Vec3::new(0.0, s, -w),
        Vec3::new(w, s, -w),
        Vec3::new(w, s, w),
        Vec3::new(0.0, s, w),
    ]);
    quad([
        Vec3::new(0.0, 0.0, -w),
        Vec3::new(0.0, s, -w),
        Vec3::new(0.0, s, w),
        Vec3::new(0.0, 0.0, w),
    ]);
    Scene {
        name: "step".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.0, 0.9, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 90.0,
            mirrored: false,
        },
        light: None,
        display_scale: 0.5,
        notes: Default::default(),
    }
}

/// The mean of `1/H − 1/H_ref` over `pixels`, relative to the mean `1/H_ref` there.
fn relative_bias_of_s(image: &HmdImage, reference: &HmdImage, pixels: &[usize]) -> f64 {
    let (mut difference, mut sum) = (0.0f64, 0.0f64);
    for &i in pixels {
        difference += 1.0 / image.data[i] as f64 - 1.0 / reference.data[i] as f64;
        sum += 1.0 / reference.data[i] as f64;
    }
    difference / sum
}

#[test]
fn the_filter_does_not_average_across_a_step() {
    // S on the platform's edge is twice S below it, far from the wall. Two pixels on either
    // side of the step, 0.5 apart in height, meet the plane term at (0.5·S)²/2σ_p² ≥
    // (0.5/1.5)²/0.02 = 5.6 (σ_p = 0.1 H): a weight of at most e^-5.6 = 0.004 of the same
    // tap within one floor. Even were all of a pixel's taps across the step, that moves its
    // S by under 0.4 % of the twofold difference, 0.4 %; the test allows 2 %, the rest for the
    // noise of the mean of 2 × 2 columns of 64-ray pixels (S's standard error ≈ 12 %/√256).
    let scene = step();
    let size = 64;
    let reference = rendered(&scene, &gather(4096), size, false, None).image;
    let filtered = rendered(&scene, &gather(64), size, true, None).image;
    // The step is the image's middle column line: x = 0 lies between columns 31 and 32, and
    // the image's right is −x (right = forward × up), so the platform is on the left.
    let columns = |range: std::ops::Range<usize>| -> Vec<usize> {
        (0..size as usize)
            .flat_map(|row| range.clone().map(move |c| row * size as usize + c))
            .collect()
    };
    for (side, pixels) in [("platform", columns(30..32)), ("below", columns(32..34))] {
        let bias = relative_bias_of_s(&filtered, &reference, &pixels);
        assert!(bias.abs() < 0.02, "{side}: S off by {:.2} %", 100.0 * bias);
    }
    // Over the whole image, too (4,096 pixels: the noise of the mean is 0.2 %).
    let every: Vec<usize> = (0..filtered.data.len()).collect();
    let bias = relative_bias_of_s(&filtered, &reference, &every);
    assert!(bias.abs() < 0.01, "the image's S off by {:.2} %", 100.0 * bias);
}

#[test]
fn the_filtered_error_falls_with_the_rays_towards_the_unfiltered_one() {
    // Consistency: the filter's tolerance falls as 1/N, so as the rays per pixel grow it
    // steps back and the filtered image's error falls towards the unfiltered image's. At
    // 64² of `cube` (a pixel is a fifth of a typical H: coarse) the filter halves the error
    // at 16 rays, and at 1,024 is within a few per cent of no filter.
    let scene = hmdist::scene::procedural::builtin("cube").unwrap();
    let size = 64;
    let reference = rendered(&scene, &gather(8192), size, false, None).image;
    let l_diag = scene.diagonal();
    let error = |rays, denoise| {
        let image = rendered(&scene, &gather(rays), size, denoise, None).image;
        f_diff(&reference, &image, l_diag).unwrap().value
    };
    let filtered: Vec<f64> = [16, 64, 256, 1024].iter().map(|&n| error(n, true)).collect();
    let plain: Vec<f64> = [16, 64, 256, 1024].iter().map(|&n| error(n, false)).collect();
    for pair in filtered.windows(2) {
        assert!(pair[1] < pair[0], "filtered f_diff by rays {filtered:?}");
    }
    eprintln!("f_diff by rays 16, 64, 256, 1024: filtered {filtered:?}, plain {plain:?}");
    assert!(
        filtered[0] < 0.7 * plain[0],
        "16 rays: {filtered:?} against {plain:?}"
    );
    assert!(filtered[1] < plain[1], "64 rays: {filtered:?} against {plain:?}");
    // Filtered and unfiltered errors close in on each other as the tolerance narrows.
    let ratios: Vec<f64> = filtered.iter().zip(&plain).map(|(f, p)| f / p).collect();
    assert!((ratios[3] - 1.0).abs() < 0.1, "1,024 rays: ratios {ratios:?}");
    assert!(
        (ratios[3] - 1.0).abs() < (ratios[0] - 1.0).abs(),
        "ratios {ratios:?}"
    );
}

#[test]
fn same_bits_for_one_and_two_threads_gather_and_adaptive() {
    let scene = hmdist::scene::procedural::builtin("cube").unwrap();
    let adaptive = AdaptiveParams {
        tolerance: 0.1,
        min_rays: 16,
        ..Default::default()
    }
    .build()
    .unwrap();
    for estimator in [&gather(16) as &dyn Estimator, &adaptive] {
        let one = rendered(&scene, estimator, 40, true, Some(1)).image;
        let two = rendered(&scene, estimator, 40, true, Some(2)).image;
        let plain = rendered(&scene, estimator, 40, false, Some(2)).image;
        let bits = |i: &HmdImage| i.data.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&two), "{}", estimator.method());
        assert_ne!(
            bits(&one),
            bits(&plain),
            "{}: the filter changes the image",
            estimator.method()
        );
    }
}

#[test]
fn uniform_weighting_is_filtered_too() {
    // The slab's floor: H = 2h under uniform weighting, the same at every pixel.
    let scene = validation::slab(validation::SLAB_HEIGHT, 50.0);
    let estimator = Gather::new(64, Weighting::Uniform).unwrap();
    let filtered = rendered(&scene, &estimator, 32, true, None).image;
    let (mean, _) = ratio_to(&filtered, 2.0 * validation::SLAB_HEIGHT);
    assert!((mean - 1.0).abs() < 0.02, "{mean}");
}

#[test]
fn the_command_line_refuses_what_the_filter_cannot_do_by_name() {
    use common::cli::refuses;
    let cases: &[(&str, &[&str], &str)] = &[
        (
            "photon",
            &[
                "render",
                "--size",
                "8x8",
                "--method",
                "photon1",
                "--photons",
                "1000",
                "--denoise",
            ],
            "cannot filter photon1",
        ),
        (
            "irradiance",
            &["render", "--size", "8x8", "--method", "irradiance", "--denoise"],
            "irradiance, not H",
        ),
        (
            "relerr",
            &["render", "--size", "8x8", "--aov", "relerr", "--denoise"],
            "relerr",
        ),
        (
            "passes",
            &["render", "--size", "8x8", "--denoise", "--denoise-passes", "0"],
            "--denoise-passes must be 1 to 10",
        ),
        (
            "radius",
            &["render", "--size", "8x8", "--denoise", "--denoise-radius", "-1"],
            "--denoise-radius must be a positive",
        ),
        (
            "edge",
            &["render", "--size", "8x8", "--denoise", "--denoise-edge", "nan"],
            "--denoise-edge must be a positive",
        ),
        (
            "without",
            &["render", "--size", "8x8", "--denoise-edge", "3"],
            "--denoise",
        ),
        (
            "points",
            &["points", "p.csv", "h.npy", "--denoise"],
            "a list of points has no neighbours",
        ),
    ];
    for (case, args, message) in cases {
        refuses(
            &format!("denoise-{case}"),
            &[("p.csv", b"0 0 0 0 1 0\n")],
            args,
            message,
        );
    }
}

#[test]
fn an_image_rendered_earlier_filters_to_the_denoised_render_bit_for_bit() {
    let scene = hmdist::scene::procedural::builtin("cube").unwrap();
    let plain = rendered(&scene, &gather(16), 40, false, None);
    let denoised = rendered(&scene, &gather(16), 40, true, None);
    let bvh = match plain.report.bvh.as_str() {
        "fast" => hmdist::accel::BuildQuality::Fast,
        _ => hmdist::accel::BuildQuality::High,
    };
    let guide = hmdist::render::guide(&scene, (40, 40), bvh, vec![16.0; 1600]).unwrap();
    let later = hmdist::denoise::filter(&plain.image.data, &guide, &DenoiseParams::default());
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&later), bits(&denoised.image.data));
    assert!(hmdist::render::guide(&scene, (40, 40), bvh, vec![16.0; 10]).is_err());
}
