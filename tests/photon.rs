//! The photon-map estimators (spec §3.3) against closed forms and against final gathering.

mod common;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality};
use hmdist::error::Error;
use hmdist::estimators::photon::{
    trace_photons, PathRules, PhotonMethod, PhotonParams, PhotonSource, SourceKind, TracedPhoton,
};
use hmdist::estimators::{Estimator, PhotonEstimator};
use hmdist::image::HmdImage;
use hmdist::metrics::f_diff;
use hmdist::progress::Silent;
use hmdist::render::{primary_hits, render, RenderOptions, DEFAULT_SEED};
use hmdist::report::RenderReport;
use hmdist::sampling::Weighting;
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

fn photon_image(
    scene: &Scene,
    method: PhotonMethod,
    params: PhotonParams,
    size: u32,
    threads: Option<usize>,
) -> (HmdImage, RenderReport) {
    let estimator = PhotonEstimator::new(method, params).unwrap();
    let options = RenderOptions {
        width: size,
        height: size,
        threads,
        ..RenderOptions::default()
    };
    let rendered = render(scene, &estimator as &dyn Estimator, &options, &Silent).unwrap();
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
                nearest: 256,
                source,
                ..PhotonParams::default()
            };
            let (image, report) = photon_image(&scene, method, params, 32, None);
            assert_eq!(report.details.photon.as_ref().unwrap().holes, 0);
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
        nearest: 256,
        ..PhotonParams::default()
    };
    let one = photon_image(&scene, PhotonMethod::StoredDistance, params.clone(), size, None).0;
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
        if max_bounces == 1 {
            assert!(
                traced.paths_traced as usize > budget,
                "one photon per path at most, some absorbed"
            );
        }
    }
}

/// The slab (floor at y = 0, ceiling at y = h, 2000 wide) and camera-sourced photons on it.
fn slab_photons(budget: usize) -> (Scene, Vec<TracedPhoton>) {
    let scene = validation::slab(validation::SLAB_HEIGHT, 1000.0);
    let accel = Accel::build(&scene.mesh, BuildQuality::default());
    let (w, h) = (4, 4);
    let source = PhotonSource::Camera(scene.camera.rays(w, h), w, h);
    let rules = PhotonParams::default().rules();
    let traced = trace_photons(&accel, &source, rules, budget, DEFAULT_SEED, &|_| {}).unwrap();
    (scene, traced.photons)
}

#[test]
fn photons_are_stored_at_the_start_of_each_bounce_facing_where_they_came_from() {
    // Between the slab's two planes a photon on the floor (y = 0) arrived from above: normal
    // +y; one on the ceiling (y = h): normal −y. It leaves into its normal's hemisphere and
    // its next hit is the other plane, at distance (other y − y) / ω_y, which is finite unless
    // that point lies beyond the slab's edge.
    let h = validation::SLAB_HEIGHT;
    let (_, photons) = slab_photons(20_000);
    let on_ceiling = photons.iter().filter(|p| p.position.y > 0.5 * h).count();
    assert!(
        on_ceiling > 5_000 && photons.len() - on_ceiling > 5_000,
        "{on_ceiling} on the ceiling"
    );
    for p in &photons {
        let (plane, other, normal) = if p.position.y > 0.5 * h {
            (h, 0.0, Vec3::NEG_Y)
        } else {
            (0.0, h, Vec3::Y)
        };
        assert!((p.position.y - plane).abs() < 1e-5, "{p:?}");
        assert_eq!(p.normal, normal, "{p:?}");
        assert!(p.direction.dot(p.normal) > 0.0, "{p:?}");
        let t = (other - p.position.y) / p.direction.y;
        let q = p.position + t * p.direction;
        let from_centre = q.x.abs().max(q.z.abs());
        if from_centre < 999.0 {
            // Hits on triangles 2000 wide are good to about 1e-4 in absolute terms.
            assert!((p.distance - t).abs() < 1e-3, "{p:?}: expected distance {t}");
        } else if from_centre > 1001.0 {
            assert_eq!(p.distance, f32::INFINITY, "{p:?} escapes past the edge");
        }
    }
}

#[test]
fn method_one_uses_the_photons_distance_and_method_two_the_distance_from_the_pixel() {
    // One stored photon, at x on the floor, leaving along ω with its next hit q = x + d·ω on
    // the ceiling. Every pixel (all see the floor, normal +y like the photon's) gathers it:
    // method I gives H = d everywhere, method II H = |q − pixel's point|, which differs from
    // pixel to pixel and from d.
    let (scene, photons) = slab_photons(1);
    let photon = photons[0];
    let q = photon.position + photon.distance * photon.direction;
    let size = 4;
    let accel = Accel::build(&scene.mesh, BuildQuality::default());
    let points = primary_hits(&accel, &scene, size, size).points;
    let params = PhotonParams {
        photons: 1,
        nearest: 1,
        source: SourceKind::Camera,
        ..PhotonParams::default()
    };
    let one = photon_image(&scene, PhotonMethod::StoredDistance, params.clone(), size, None).0;
    let two = photon_image(&scene, PhotonMethod::NextHitPoint, params, size, None).0;
    for ((h1, h2), point) in one.data.iter().zip(&two.data).zip(&points) {
        let x = point.expect("every pixel sees the floor").point;
        let from_pixel = q.distance(x);
        assert!(
            (h1 / photon.distance - 1.0).abs() < 1e-5,
            "method I: {h1}, d = {}",
            photon.distance
        );
        assert!(
            (h2 / from_pixel - 1.0).abs() < 1e-5,
            "method II: {h2}, |q − x| = {from_pixel}"
        );
        assert!(
            (from_pixel / photon.distance - 1.0).abs() > 1e-3,
            "the test tells them apart"
        );
    }
}

#[test]
fn same_photon_image_with_1_and_2_threads() {
    // Each worker starts its searches from its previous pixel's radius, so the two runs search
    // differently; the photons found, and their order in the sum, must not change.
    let scene = Scene::load("cube").unwrap();
    let bits = |i: &HmdImage| i.data.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    for (source, gather) in [(SourceKind::Camera, 64), (SourceKind::Light, 1024)] {
        let params = PhotonParams {
            photons: 100_000,
            nearest: gather,
            source,
            ..PhotonParams::default()
        };
        let one = photon_image(&scene, PhotonMethod::NextHitPoint, params.clone(), 32, Some(1)).0;
        let two = photon_image(&scene, PhotonMethod::NextHitPoint, params, 32, Some(2)).0;
        assert_eq!(bits(&one), bits(&two), "{} K = {gather}", source.name());
    }
}

#[test]
fn a_photon_map_is_the_same_bytes_through_either_bvh_preset() {
    // Why a map's fingerprint leaves the preset out: a map that `photons build` traced
    // through one tree serves a cache or render whose work resolves `auto` to the other.
    for (scene, source) in [("cube", SourceKind::Light), ("hall", SourceKind::Camera)] {
        let scene = Scene::load(scene).unwrap();
        let estimator = PhotonEstimator::new(
            PhotonMethod::NextHitPoint,
            PhotonParams {
                photons: 20_000,
                source,
                ..PhotonParams::default()
            },
        )
        .unwrap();
        let map = |bvh_quality| {
            let options = RenderOptions {
                width: 24,
                height: 16,
                bvh_quality,
                ..RenderOptions::default()
            };
            estimator.build_map_file(&scene, &options, &Silent).unwrap()
        };
        let (fast, high) = (map(BuildQuality::Fast), map(BuildQuality::High));
        assert!(
            fast == high,
            "{}: the maps differ between the presets",
            scene.name
        );
    }
}

#[test]
fn bad_photon_parameters_are_refused() {
    let ok = PhotonParams::default();
    // Refused as a bad value of the parameter called `what`.
    let refused = |p: PhotonParams, what: &str| {
        let e = PhotonEstimator::new(PhotonMethod::NextHitPoint, p)
            .err()
            .expect("refused");
        assert!(
            matches!(&e, Error::Parameter { name: Some(n), .. } if *n == what),
            "{e}"
        );
        e.to_string()
    };
    refused(
        PhotonParams {
            photons: 0,
            ..ok.clone()
        },
        "photons",
    );
    refused(
        PhotonParams {
            nearest: 0,
            ..ok.clone()
        },
        "nearest",
    );
    let e = refused(
        PhotonParams {
            photons: usize::MAX / 64,
            ..ok.clone()
        },
        "photons",
    );
    assert!(e.contains("memory"), "{e}");
    refused(
        PhotonParams {
            max_bounces: 20,
            absorption: 1.0,
            ..ok.clone()
        },
        "absorption",
    );
    // No spot light: refused when the estimate starts.
    let slab = validation::slab(1.0, 10.0);
    let estimator = PhotonEstimator::new(
        PhotonMethod::StoredDistance,
        PhotonParams {
            photons: 10,
            ..ok.clone()
        },
    )
    .unwrap();
    let options = RenderOptions {
        width: 4,
        height: 4,
        ..RenderOptions::default()
    };
    let e = render(&slab, &estimator, &options, &Silent)
        .err()
        .expect("refused");
    assert!(
        matches!(
            &e,
            Error::Parameter {
                name: Some("source"),
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("no spot light"), "{e}");
}

/// H at each pixel of `scene` from kiddo's K nearest photons (an independent search), summed
/// in the map's tree order, with exact ties at the K-th distance going to the earlier photon
/// in that order, as the map's gather does.
fn kiddo_reference(scene: &Scene, method: PhotonMethod, params: PhotonParams, size: u32) -> Vec<f32> {
    use hmdist::estimators::photon::map::{decode_octahedral, encode_octahedral};
    use hmdist::estimators::photon::{PhotonMap, NORMAL_FILTER_COS};
    use hmdist::estimators::{DistanceClamp, HarmonicMean};
    use kiddo::immutable::float::kdtree::ImmutableKdTree;
    use kiddo::SquaredEuclidean;

    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let source = match params.source {
        SourceKind::Light => PhotonSource::Light(scene.light.unwrap()),
        SourceKind::Camera => PhotonSource::Camera(scene.camera.rays(size, size), size, size),
    };
    let traced = trace_photons(
        &accel,
        &source,
        params.rules(),
        params.photons,
        DEFAULT_SEED,
        &|_| {},
    )
    .unwrap();
    let photons = &traced.photons;
    let order = PhotonMap::order(photons).unwrap();
    let mut rank = vec![0u32; photons.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    let positions: Vec<[f32; 3]> = photons.iter().map(|p| p.position.to_array()).collect();
    let tree: ImmutableKdTree<f32, u32, 3, 32> = ImmutableKdTree::new_from_slice(&positions);
    let r2 = params.max_radius.map_or(f32::INFINITY, |r| r * r);
    let more = std::num::NonZero::new(params.nearest + 16).unwrap();
    let clamp = DistanceClamp::for_diagonal(scene.diagonal(), None);
    let gbuffer = primary_hits(&accel, scene, size, size);
    gbuffer
        .points
        .iter()
        .map(|hit| {
            let Some(hit) = hit else { return f32::NAN };
            let x = hit.point;
            let found = tree.nearest_n_within::<SquaredEuclidean>(&x.to_array(), r2, more, true);
            let mut near: Vec<(u32, u32)> = found
                .iter()
                .map(|f| (f.distance.to_bits(), rank[f.item as usize]))
                .collect();
            near.sort_unstable();
            near.truncate(params.nearest);
            near.sort_by_key(|&(_, r)| r);
            let mut mean = HarmonicMean::default();
            for (_, r) in near {
                let p = &photons[order[r as usize] as usize];
                if decode_octahedral(encode_octahedral(p.normal)).dot(hit.normal) < NORMAL_FILTER_COS {
                    continue;
                }
                let d = match method {
                    PhotonMethod::StoredDistance => p.distance,
                    PhotonMethod::NextHitPoint if p.distance.is_finite() => {
                        (p.position + p.distance * p.direction).distance(x)
                    }
                    PhotonMethod::NextHitPoint => f32::INFINITY,
                };
                mean.add(d, clamp);
            }
            mean.value()
        })
        .collect()
}

#[test]
fn the_maps_gather_equals_kiddos_k_nearest_bit_for_bit() {
    // spec §3.3's K nearest, found by kiddo instead of our tree: both sources, both methods,
    // K = 64 and 1,024, with and without a gather radius (one that leaves some pixels short
    // of K photons), on 64² pixels of cube.
    let scene = Scene::load("cube").unwrap();
    for source in [SourceKind::Light, SourceKind::Camera] {
        for (gather, max_radius) in [(64, None), (64, Some(0.25)), (1024, None), (1024, Some(0.3))] {
            for method in [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint] {
                let params = PhotonParams {
                    photons: 200_000,
                    nearest: gather,
                    source,
                    max_radius,
                    ..PhotonParams::default()
                };
                let (image, report) = photon_image(&scene, method, params.clone(), 64, None);
                let reference = kiddo_reference(&scene, method, params, 64);
                let different = image
                    .data
                    .iter()
                    .zip(&reference)
                    .filter(|(a, b)| a.to_bits() != b.to_bits())
                    .count();
                let holes = report.details.photon.unwrap().holes;
                println!(
                    "{} from {}, K = {gather}, radius {max_radius:?}: {different} pixels differ, {holes} holes",
                    method.name(),
                    source.name()
                );
                assert_eq!(
                    different,
                    0,
                    "{} from {}, K = {gather}",
                    method.name(),
                    source.name()
                );
            }
        }
    }
}
