//! The cube-map estimator (SPEC §3.2) against closed forms and against final gathering with
//! the same directions.

mod common;

use hmdist::estimators::cubemap::Backend;
use hmdist::estimators::{Cubemap, Estimator, Gather};
use hmdist::image::HmdImage;
use hmdist::metrics::f_diff;
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions};
use hmdist::sampling::Weighting;
use hmdist::scene::procedural::validation;
use hmdist::scene::{Mesh, Scene};

fn cubemap(
    scene: &Scene,
    size: u32,
    rays: u32,
    resolution: u32,
    backend: Backend,
) -> (HmdImage, serde_json::Value) {
    let estimator = Cubemap::new(Gather::new(rays, Weighting::Cosine).unwrap(), resolution, backend).unwrap();
    let options = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::default()
    };
    let rendered = render(scene, &estimator as &dyn Estimator, &options, 0.0, &Silent).unwrap();
    (rendered.image, rendered.report)
}

#[test]
fn inside_a_closed_sphere_the_cube_map_gives_the_radius() {
    let r = validation::SPHERE_RADIUS;
    let scene = validation::sphere(r, 7);
    let (image, report) = cubemap(&scene, 32, 1024, 64, Backend::Cpu);
    assert_eq!(report["escaped_rays"], 0);
    let mean = image.data.iter().map(|&h| r as f64 / h as f64).sum::<f64>() / image.data.len() as f64;
    println!("cubemap R = 64: mean R/H = {mean:.5}");
    assert!((mean - 1.0).abs() < 0.01, "mean R/H = {mean}");
}

#[test]
fn against_gather_with_the_same_directions_the_error_is_small_and_does_not_grow_with_resolution() {
    let scene = Scene::load("cube").unwrap();
    let (size, rays) = (64, 1024);
    let (reference, _) = common::gather(&scene, size, size, rays, Weighting::Cosine, None);
    let l_diag = scene.diagonal();
    let at = |resolution| {
        f_diff(
            &reference,
            &cubemap(&scene, size, rays, resolution, Backend::Cpu).0,
            l_diag,
        )
        .unwrap()
    };
    let (d64, d128) = (at(64), at(128));
    println!(
        "f_diff against gather, {rays} rays: R = 64 {:.4}, R = 128 {:.4} (paper: 0.029)",
        d64.value, d128.value
    );
    assert_eq!(d64.excluded, 0);
    assert!(d64.value < 0.1, "R = 64: {}", d64.value);
    assert!(
        d128.value <= d64.value * 1.05,
        "R = 128 {} vs R = 64 {}",
        d128.value,
        d64.value
    );
}

#[test]
fn open_scenes_count_directions_that_see_nothing_as_one_over_d_zero() {
    // Between two planes h apart every direction sees the ceiling: H = 3h/2 (cosine).
    let h = validation::SLAB_HEIGHT;
    let (slab, _) = cubemap(&validation::slab(h, 1000.0), 1, 4096, 64, Backend::Cpu);
    println!("slab: H = {} (expected {})", slab.data[0], 1.5 * h);
    assert!((slab.data[0] / (1.5 * h) - 1.0).abs() < 0.01);
    // Remove the ceiling: every direction escapes, as in gather.
    let mut floor = validation::slab(h, 1000.0);
    floor.mesh = Mesh {
        positions: floor.mesh.positions[..4].to_vec(),
        indices: floor.mesh.indices[..2].to_vec(),
    };
    let (open, report) = cubemap(&floor, 1, 256, 64, Backend::Cpu);
    let (gathered, _) = common::gather(&floor, 1, 1, 256, Weighting::Cosine, None);
    assert_eq!((open.data[0], gathered.data[0]), (f32::INFINITY, f32::INFINITY));
    assert_eq!(report["escaped_rays"], report["rays_cast"]);
}

#[test]
fn gpu_and_cpu_backends_agree_on_cube() {
    // Needs a Vulkan (or Metal/DX12) adapter: Mesa's lavapipe on machines without a GPU
    // (Debian: mesa-vulkan-drivers libvulkan1; .ci/run installs them). Skips only where no
    // adapter exists, and never in CI.
    let scene = Scene::load("cube").unwrap();
    let estimator = Cubemap::new(Gather::new(64, Weighting::Cosine).unwrap(), 16, Backend::Gpu).unwrap();
    let options = RenderOptions {
        width: 64,
        height: 64,
        ..RenderOptions::default()
    };
    let gpu = match render(&scene, &estimator as &dyn Estimator, &options, 0.0, &Silent) {
        Ok(rendered) => rendered,
        Err(e) if std::env::var("CI").is_err() && e.to_string().contains("no Vulkan") => {
            println!("skipped: {e}");
            return;
        }
        Err(e) => panic!("the GPU backend must run here: {e}"),
    };
    println!("adapter: {}", gpu.report["adapter"]);
    assert_eq!(gpu.report["backend"], "gpu");
    let (cpu, _) = cubemap(&scene, 64, 64, 16, Backend::Cpu);
    let d = f_diff(&cpu, &gpu.image, scene.diagonal()).unwrap();
    println!(
        "gpu vs cpu: mean |ΔH| / l_diag × 100 = {:.5} over {} pixels",
        d.value, d.compared
    );
    assert_eq!(d.excluded, 0);
    assert!(d.value < 0.01, "{}", d.value);
}
