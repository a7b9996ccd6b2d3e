//! The photon-map estimators (SPEC §3.3) against closed forms and against final gathering.

mod common;

use hmdist::accel::{Accel, BuildQuality};
use hmdist::estimators::photon::{
    trace_photons, PathRules, PhotonMethod, PhotonParams, PhotonSource, SourceKind,
};
use hmdist::estimators::{Estimator, PhotonEstimator};
use hmdist::image::HmdImage;
use hmdist::metrics::f_diff;
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions};
use hmdist::sampling::Weighting;
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

fn photon_image(
    scene: &Scene,
    method: PhotonMethod,
    params: PhotonParams,
    size: u32,
    threads: Option<usize>,
) -> (HmdImage, serde_json::Value) {
    let estimator = PhotonEstimator::new(method, params).unwrap();
    let options = RenderOptions {
        width: size,
        height: size,
        threads,
        ..RenderOptions::default()
    };
    let rendered = render(scene, &estimator as &dyn Estimator, &options, 0.0, &Silent).unwrap();
    (rendered.image, rendered.report)
}

#[test]
fn inside_a_closed_sphere_both_methods_give_the_radius_from_light_and_from_camera() {
    let r = validation::SPHERE_RADIUS;
    let scene = validation::sphere(r, 6);
    for source in [SourceKind::Light, SourceKind::Camera] {
        for method in [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint] {
            let params = PhotonParams {
                photons: 200_000,
                gather: 256,
                source,
                ..PhotonParams::default()
            };
            let (image, report) = photon_image(&scene, method, params, 32, None);
            assert_eq!(report["holes"], 0);
            let mean = image.data.iter().map(|&h| r as f64 / h as f64).sum::<f64>() / image.data.len() as f64;
            println!("{} from {}: mean R/H = {mean:.4}", method.name(), source.name());
            assert!(
                (mean - 1.0).abs() < 0.03,
                "{} from {}: mean R/H = {mean}",
                method.name(),
                source.name()
            );
        }
    }
}

#[test]
fn on_cube_method_two_is_closer_to_final_gathering_than_method_one() {
    // The paper's Fig. 6–7 finding: recomputing the distance from the query point (method II)
    // removes much of method I's error near corners and thin parts.
    let scene = Scene::load("cube").unwrap();
    let size = 64;
    let (reference, _) = common::gather(&scene, size, size, 1024, Weighting::Cosine, None);
    let l_diag = scene.diagonal();
    let params = PhotonParams {
        photons: 500_000,
        gather: 256,
        ..PhotonParams::default()
    };
    let one = photon_image(&scene, PhotonMethod::StoredDistance, params, size, None).0;
    let two = photon_image(&scene, PhotonMethod::NextHitPoint, params, size, None).0;
    let (d1, d2) = (
        f_diff(&reference, &one, l_diag).unwrap(),
        f_diff(&reference, &two, l_diag).unwrap(),
    );
    println!(
        "f_diff against gather 1024: method I {:.4}, method II {:.4} ({} pixels)",
        d1.value, d2.value, d2.compared
    );
    assert!(
        d2.value < d1.value,
        "method II {} vs method I {}",
        d2.value,
        d1.value
    );
}

#[test]
fn exactly_p_photons_are_stored_whatever_the_bounce_limit() {
    let scene = Scene::load("cube").unwrap();
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let source = PhotonSource::Light(scene.light.unwrap());
    for (budget, max_bounces) in [(1, 20), (12_345, 20), (12_345, 80), (100_003, 1)] {
        let rules = PathRules {
            max_bounces,
            absorption: 0.2,
        };
        let traced = trace_photons(&accel, &source, rules, budget, 7, &|_| {}).unwrap();
        assert_eq!(traced.photons.len(), budget);
        assert!(
            traced.photons.iter().all(|p| p.distance > 0.0),
            "distances are positive"
        );
        assert!(traced
            .photons
            .iter()
            .all(|p| (p.normal.length() - 1.0).abs() < 1e-4));
        if max_bounces == 1 {
            assert!(
                traced.paths_traced as usize > budget,
                "one photon per path at most, some absorbed"
            );
        }
    }
}

#[test]
fn same_photon_image_with_1_and_2_threads() {
    let scene = Scene::load("cube").unwrap();
    let params = PhotonParams {
        photons: 100_000,
        gather: 64,
        source: SourceKind::Camera,
        ..PhotonParams::default()
    };
    let bits = |i: &HmdImage| i.data.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    let one = photon_image(&scene, PhotonMethod::NextHitPoint, params, 32, Some(1)).0;
    let two = photon_image(&scene, PhotonMethod::NextHitPoint, params, 32, Some(2)).0;
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn bad_photon_parameters_are_refused() {
    let ok = PhotonParams::default();
    let refused = |p: PhotonParams, what: &str| {
        let e = PhotonEstimator::new(PhotonMethod::NextHitPoint, p)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains(what), "{e}");
    };
    refused(PhotonParams { photons: 0, ..ok }, "--photons");
    refused(PhotonParams { gather: 0, ..ok }, "--gather");
    refused(
        PhotonParams {
            photons: usize::MAX / 64,
            ..ok
        },
        "memory",
    );
    refused(
        PhotonParams {
            rules: PathRules {
                max_bounces: 20,
                absorption: 1.0,
            },
            ..ok
        },
        "--absorption",
    );
    // No spot light: refused when the estimate starts.
    let slab = validation::slab(1.0, 10.0);
    let estimator =
        PhotonEstimator::new(PhotonMethod::StoredDistance, PhotonParams { photons: 10, ..ok }).unwrap();
    let options = RenderOptions {
        width: 4,
        height: 4,
        ..RenderOptions::default()
    };
    let e = render(&slab, &estimator, &options, 0.0, &Silent)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("no spot light"), "{e}");
}
