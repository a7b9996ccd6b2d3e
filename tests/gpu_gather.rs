//! `gather --backend gpu`: the compute-shader traversal against the CPU (issue #14).
//!
//! These run on any Vulkan, Metal or DX12 adapter, Mesa's lavapipe included (CI installs it
//! and sets HMDIST_REQUIRE_GPU, so that there a missing adapter fails instead of skipping).
//! lavapipe casts about 0.2 M rays/s per core, so the images are small.

mod common;

use glam::Vec3;
use hmdist::accel::{Accel, BuildQuality, RayCaster};
use hmdist::error::Result;
use hmdist::estimators::gather::DispatchSplit;
use hmdist::estimators::{Aov, Backend, Gather};
use hmdist::gpu::{GpuRay, GpuScene};
use hmdist::metrics::f_diff;
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};
use hmdist::render::{primary_hits, RenderOptions, Rendered};
use hmdist::sampling::{Sampler, Weighting};
use hmdist::scene::procedural::validation;
use hmdist::scene::Scene;

fn render_with(scene: &Scene, gather: Gather, size: u32, aovs: Vec<Aov>) -> Result<Rendered> {
    let options = RenderOptions {
        aovs,
        bvh_quality: BuildQuality::Fast,
        ..RenderOptions::default()
    };
    common::render_square(scene, &gather, size, options)
}

fn gpu_gather(rays: u32) -> Gather {
    Gather::new(rays, Weighting::Cosine)
        .unwrap()
        .with_backend(Backend::GpuSoftware)
}

/// The GPU image, or `None` (the test skips) where this machine has no adapter.
fn gpu_render(test: &str, scene: &Scene, gather: Gather, size: u32, aovs: Vec<Aov>) -> Option<Rendered> {
    let rendered = common::gpu_or_skip(test, render_with(scene, gather, size, aovs))?;
    let device = rendered.report.details.device.as_ref().expect("device details");
    assert_eq!(device.backend, "gpu");
    println!("{test}: adapter {:?}", device.adapter);
    Some(rendered)
}

/// The GPU against the CPU at 64² × 1,024 rays: f_diff, and the mean of R/H on the sphere.
fn agrees_with_cpu(test: &str, scene: &Scene, sphere_radius: Option<f32>) {
    let Some(gpu) = gpu_render(test, scene, gpu_gather(1024), 64, vec![]) else {
        return;
    };
    let cpu = render_with(scene, gpu_gather(1024).with_backend(Backend::Cpu), 64, vec![]).unwrap();
    let diff = f_diff(&cpu.image, &gpu.image, scene.diagonal()).unwrap();
    println!("{test}: f_diff {:e} over {} pixels", diff.value, diff.compared);
    assert_eq!(
        diff.compared,
        cpu.image.data.iter().filter(|h| h.is_finite()).count()
    );
    // The GPU's distances differ from the CPU's in the last bits only (fused multiply-adds,
    // sin/cos/division not correctly rounded): f_diff is about 1e-5, not 1e-2.
    assert!(diff.compared > 0 && diff.value <= 1e-4, "f_diff {}", diff.value);
    assert_eq!(gpu.report.rays_cast, cpu.report.rays_cast);
    if let Some(r) = sphere_radius {
        let h: Vec<f64> = gpu
            .image
            .data
            .iter()
            .filter(|h| h.is_finite())
            .map(|&h| (r / h) as f64)
            .collect();
        let mean = h.iter().sum::<f64>() / h.len() as f64;
        println!("{test}: mean R/H {mean}");
        assert!((mean - 1.0).abs() < 0.01, "mean R/H = {mean}");
        assert_eq!(gpu.report.escaped_rays, Some(0));
    }
}

#[test]
fn gpu_gather_agrees_with_cpu_on_cube() {
    agrees_with_cpu(
        "gpu_gather_agrees_with_cpu_on_cube",
        &Scene::load("cube").unwrap(),
        None,
    );
}

/// `--sampler sobol` on the GPU: each round the first points of its own scrambled Sobol
/// sequence, as on the CPU (4 rounds of 64, so the replicates are exercised), within the grid's
/// tolerance of the CPU image; and not the grid's image.
#[test]
fn gpu_sobol_gather_agrees_with_cpu_on_cube() {
    let test = "gpu_sobol_gather_agrees_with_cpu_on_cube";
    let scene = Scene::load("cube").unwrap();
    let sobol = |backend| {
        Gather::new(256, Weighting::Cosine)
            .unwrap()
            .with_rounds(4)
            .unwrap()
            .with_backend(backend)
            .with_sampler(Sampler::Sobol)
            .unwrap()
    };
    let Some(gpu) = gpu_render(test, &scene, sobol(Backend::GpuSoftware), 48, vec![]) else {
        return;
    };
    let cpu = render_with(&scene, sobol(Backend::Cpu), 48, vec![]).unwrap();
    let diff = f_diff(&cpu.image, &gpu.image, scene.diagonal()).unwrap();
    println!("{test}: f_diff {:e} over {} pixels", diff.value, diff.compared);
    assert!(diff.compared > 0 && diff.value <= 1e-4, "f_diff {}", diff.value);
    let grid = render_with(
        &scene,
        gpu_gather(256).with_rounds(4).unwrap().with_backend(Backend::Cpu),
        48,
        vec![],
    )
    .unwrap();
    let apart = f_diff(&grid.image, &gpu.image, scene.diagonal()).unwrap();
    assert!(
        apart.value > 1e-2,
        "the GPU's sobol image is the grid's: f_diff {}",
        apart.value
    );
}

#[test]
fn gpu_gather_on_closed_sphere_agrees_with_cpu_and_gives_h_equal_r() {
    let r = validation::SPHERE_RADIUS;
    agrees_with_cpu(
        "gpu_gather_on_closed_sphere_agrees_with_cpu_and_gives_h_equal_r",
        &validation::sphere(r, 7),
        Some(r),
    );
}

#[test]
fn gpu_hit_distances_equal_the_cpus_ray_by_ray() {
    let test = "gpu_hit_distances_equal_the_cpus_ray_by_ray";
    for (name, scene) in [
        ("cube", Scene::load("cube").unwrap()),
        ("sphere", validation::sphere(validation::SPHERE_RADIUS, 5)),
    ] {
        let accel = Accel::build(&scene.mesh, BuildQuality::High);
        let gpu = match GpuScene::new(&accel, true) {
            Ok(gpu) => gpu,
            Err(e) if common::gpu_missing(test, &e.to_string()) => return,
            Err(e) => panic!("{e}"),
        };
        // The gather rays of a sample of pixels: every 7th pixel of a 64² image, 64 rays
        // each, leaving their triangle as the renderer's do.
        let gbuffer = primary_hits(&accel, &scene, 64, 64);
        let gather = Gather::new(64, Weighting::Cosine).unwrap();
        let mut rays = Vec::new();
        for (pixel, hit) in gbuffer.points.iter().enumerate().step_by(7) {
            let Some(hit) = hit else { continue };
            let (origin, directions) = gather.rays(hit, 1, pixel as u64);
            rays.extend(directions.map(|direction| GpuRay {
                origin,
                direction,
                t_max: f32::INFINITY,
                leaving: Some(hit.triangle),
            }));
        }
        // Rays along the axes and in the axis planes, whose zero direction components the
        // box test must handle (a zero z once let a gather ray out of the closed sphere).
        let centre = scene.bounds().center();
        for direction in [
            Vec3::X,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::new(-0.8, 0.6, 0.0),
            Vec3::new(0.0, -0.6, 0.8),
        ] {
            for offset in [Vec3::ZERO, Vec3::new(0.31, -0.17, 0.05)] {
                rays.push(GpuRay {
                    origin: centre + offset,
                    direction,
                    t_max: f32::INFINITY,
                    leaving: None,
                });
            }
        }
        // And rays that must miss: outward from outside the scene.
        let outside = scene.bounds().max + Vec3::ONE;
        rays.push(GpuRay {
            origin: outside,
            direction: Vec3::ONE.normalize(),
            t_max: f32::INFINITY,
            leaving: None,
        });
        let on_gpu = gpu.hit_distances(&rays).unwrap();
        let mut worst = 0.0f32;
        for (ray, &t) in rays.iter().zip(&on_gpu) {
            let expected = accel.hit_distance(ray.origin, ray.direction, ray.t_max, ray.leaving);
            if expected.is_infinite() || t.is_infinite() {
                assert_eq!(t, expected, "{name}: one hit, one miss: {ray:?}");
                continue;
            }
            let relative = (t - expected).abs() / expected;
            worst = worst.max(relative);
            assert!(relative <= 1e-5, "{name}: GPU t {t}, CPU {expected}: {ray:?}");
        }
        println!(
            "{name}: {} rays, largest relative difference {worst:e}",
            rays.len()
        );
        assert!(on_gpu.last().unwrap().is_infinite());
        assert!(rays.len() > 10_000);
    }
}

#[test]
fn no_gpu_gather_ray_escapes_the_closed_cube() {
    let test = "no_gpu_gather_ray_escapes_the_closed_cube";
    let scene = Scene::load("cube").unwrap();
    let Some(gpu) = gpu_render(test, &scene, gpu_gather(64), 256, vec![Aov::Escaped]) else {
        return;
    };
    assert_eq!(gpu.report.rays_cast, Some(256 * 256 * 64));
    assert_eq!(gpu.report.escaped_rays, Some(0));
    assert!(gpu.image.data.iter().all(|h| h.is_finite() && *h > 0.0));
}

#[test]
fn gpu_images_do_not_depend_on_the_run_or_the_dispatch_split() {
    let test = "gpu_images_do_not_depend_on_the_run_or_the_dispatch_split";
    let scene = Scene::load("cube").unwrap();
    // Four rounds and every AOV: the running sums cross dispatches mid-round.
    let gather = gpu_gather(64)
        .with_rounds(4)
        .unwrap()
        .with_ao_radius(Some(2.0))
        .unwrap();
    let aovs = Aov::OF_GATHER.to_vec();
    let Some(first) = gpu_render(test, &scene, gather, 32, aovs.clone()) else {
        return;
    };
    let splits = [
        DispatchSplit {
            points: 100,
            rays: 7,
            ..Default::default()
        },
        DispatchSplit {
            points: 1 << 20,
            rays: 1,
            ..Default::default()
        },
    ];
    let again = render_with(&scene, gather, 32, aovs.clone()).unwrap();
    let bits = |r: &Rendered| {
        let mut all: Vec<u32> = r.image.data.iter().map(|h| h.to_bits()).collect();
        for channel in &r.aovs {
            all.extend(channel.data.iter().map(|v| v.to_bits()));
        }
        all
    };
    assert_eq!(first.aovs.len(), Aov::OF_GATHER.len());
    assert_eq!(bits(&first), bits(&again), "two runs differ");
    for split in splits {
        let split_run = render_with(&scene, gather.with_dispatch_split(split), 32, aovs.clone()).unwrap();
        assert_eq!(bits(&first), bits(&split_run), "{split:?} differs");
    }
    // The AOVs are the CPU's, to within the GPU's rounding.
    let cpu = render_with(&scene, gather.with_backend(Backend::Cpu), 32, aovs).unwrap();
    for (g, c) in first.aovs.iter().zip(&cpu.aovs) {
        assert_eq!(g.aov, c.aov);
        let worst = g
            .data
            .iter()
            .zip(&c.data)
            .map(|(a, b)| ((a - b).abs() / b.abs().max(1e-3)) as f64)
            .fold(0.0, f64::max);
        println!("{:?}: largest relative difference {worst:e}", g.aov);
        let tolerance = if g.aov == Aov::Relerr { 1e-2 } else { 1e-3 };
        assert!(
            worst <= tolerance,
            "{:?} differs from the CPU's by {worst}",
            g.aov
        );
    }
}

#[test]
fn gpu_h_at_points_is_the_gpu_image() {
    let test = "gpu_h_at_points_is_the_gpu_image";
    let scene = Scene::load("cube").unwrap();
    let gather = gpu_gather(64);
    let Some(image) = gpu_render(test, &scene, gather, 24, vec![]) else {
        return;
    };
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let gbuffer = primary_hits(&accel, &scene, 24, 24);
    let (points, keys): (Vec<SurfacePoint>, Vec<u64>) = gbuffer
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.as_ref().map(|hit| (SurfacePoint::from_hit(hit), i as u64)))
        .unzip();
    let query = PointQuery::new(gather, 1, None).unwrap();
    let at_points = hmd_at(&scene, &accel, &query, &points, Some(&keys)).unwrap();
    for (h, &key) in at_points.iter().zip(&keys) {
        assert_eq!(
            h.to_bits(),
            image.image.data[key as usize].to_bits(),
            "pixel {key}"
        );
    }
}

/// A render small enough for lavapipe, for the CLI tests.
const TINY_RENDER: [&str; 6] = ["render", "--quiet", "--size", "8x6", "--rays", "4"];

#[test]
fn backend_gpu_refuses_a_software_adapter_by_name_unless_asked() {
    let test = "backend_gpu_refuses_a_software_adapter_by_name_unless_asked";
    let dir = common::Scratch::new("gpu-software");
    let run = |backend: &str, out: &str, software: bool| {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_hmdist"));
        command
            .args(TINY_RENDER)
            .args(["--backend", backend, "--out", out])
            .current_dir(dir.path())
            .env_remove("HMDIST_GPU_SOFTWARE");
        if software {
            command.env("HMDIST_GPU_SOFTWARE", "1");
        }
        command.output().unwrap()
    };
    let asked = run("gpu-software", "asked.exr", false);
    let stderr = String::from_utf8_lossy(&asked.stderr);
    if !asked.status.success() && common::gpu_missing(test, &stderr) {
        return;
    }
    assert!(asked.status.success(), "{stderr}");
    let json = common::cli::read_json(&dir.join("asked.json"));
    let adapter = json["adapter"].as_str().unwrap().to_string();
    if !adapter.contains("llvmpipe") {
        common::skip(
            test,
            &format!("the adapter here, {adapter}, is hardware: nothing to refuse"),
            None,
        );
        return;
    }
    // --backend gpu: refused, naming the adapter and the way to use it anyway; nothing written.
    let refused = run("gpu", "refused.exr", false);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    for words in [
        "llvmpipe",
        "software implementation",
        "--backend gpu-software",
        "HMDIST_GPU_SOFTWARE=1",
    ] {
        assert!(stderr.contains(words), "{words}: {stderr}");
    }
    assert!(!dir.join("refused.exr").exists());
    // Asked through the environment, gpu runs on it; auto stays on the CPU without it.
    assert!(run("gpu", "env.exr", true).status.success());
    assert_eq!(
        common::cli::read_json(&dir.join("env.json"))["adapter"],
        json["adapter"]
    );
    assert!(run("auto", "auto.exr", false).status.success());
    assert_eq!(common::cli::read_json(&dir.join("auto.json"))["backend"], "cpu");
}

#[test]
fn gpu_list_numbers_the_adapters_and_gpu_picks_one_or_says_what_there_is() {
    let test = "gpu_list_numbers_the_adapters_and_gpu_picks_one_or_says_what_there_is";
    let dir = common::Scratch::new("gpu-select");
    let list = common::cli::hmdist(dir.path(), &["gpu", "list"]);
    let listing = String::from_utf8_lossy(&list.stdout).to_string();
    assert!(list.status.success(), "{listing}");
    if listing.starts_with("no Vulkan") {
        common::gpu_missing(test, "no Vulkan, Metal or DX12 adapter");
        return;
    }
    // "*  0  llvmpipe (...)  cpu  Vulkan ...": the first adapter's name, as --gpu takes it.
    let first = listing.lines().next().unwrap();
    assert!(first.contains(" 0  "), "{listing}");
    let name: String = first[6..].split("  ").next().unwrap().trim().to_string();
    let render = |args: &[&str]| {
        let mut all = TINY_RENDER.to_vec();
        all.extend(["--backend", "gpu-software"]);
        all.extend_from_slice(args);
        common::cli::hmdist(dir.path(), &all)
    };
    let named = render(&["--gpu", &name[..4], "--out", "named.exr"]);
    assert!(
        named.status.success(),
        "{}",
        String::from_utf8_lossy(&named.stderr)
    );
    let adapter = common::cli::read_json(&dir.join("named.json"))["adapter"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(adapter.starts_with(&name), "{adapter} is not {name}");
    let count = listing
        .lines()
        .filter(|l| l.len() > 4 && l[2..4].trim().parse::<usize>().is_ok())
        .count();
    for args in [
        vec!["--gpu".to_string(), count.to_string()],
        vec!["--gpu".into(), "no such GPU".into()],
    ] {
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        all.extend(["--out", "bad.exr"]);
        let bad = render(&all);
        let stderr = String::from_utf8_lossy(&bad.stderr);
        assert_eq!(bad.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&args[1]) && stderr.contains(&format!("0: {name}")),
            "{stderr}"
        );
        assert!(!dir.join("bad.exr").exists());
    }
}

#[test]
fn a_gpu_loop_cut_short_is_an_error_not_an_image() {
    let test = "a_gpu_loop_cut_short_is_an_error_not_an_image";
    // 4,096 rays per point in one dispatch: on lavapipe, far past its cap of 65,535 loop
    // iterations per invocation (the split lifts hmdist's own guard against it).
    let scene = Scene::load("cube").unwrap();
    let split = DispatchSplit {
        points: 1 << 20,
        rays: 4096,
        past_software_cap: true,
    };
    let gather = gpu_gather(4096).with_dispatch_split(split);
    match render_with(&scene, gather, 4, vec![]) {
        Err(e) if common::gpu_missing(test, &e.to_string()) => {}
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.contains("cut short") && message.contains("4096 rays"),
                "{message}"
            );
        }
        Ok(rendered) => {
            // A hardware GPU has no such cap: then every ray was cast.
            let device = rendered.report.details.device.unwrap();
            assert!(
                !device.adapter.unwrap_or_default().contains("llvmpipe"),
                "lavapipe's cut went unseen"
            );
            assert_eq!(rendered.report.rays_cast, Some(16 * 4096));
        }
    }
}

#[test]
fn a_gpu_gather_is_denoised_as_the_cpu_filters_its_image() {
    // The filter runs on the CPU after the GPU's pixels: the GPU image filtered later through
    // the same guide is the denoised GPU render, bit for bit.
    let scene = validation::sphere(validation::SPHERE_RADIUS, 5);
    let test = "a_gpu_gather_is_denoised_as_the_cpu_filters_its_image";
    let Some(plain) = gpu_render(test, &scene, gpu_gather(16), 24, vec![]) else {
        return;
    };
    let options = RenderOptions {
        bvh_quality: BuildQuality::Fast,
        denoise: Some(Default::default()),
        ..RenderOptions::default()
    };
    let denoised = common::render_square(&scene, &gpu_gather(16), 24, options).unwrap();
    assert_eq!(denoised.report.details.device.as_ref().unwrap().backend, "gpu");
    let guide = hmdist::render::guide(&scene, (24, 24), BuildQuality::Fast, vec![16.0; 576]).unwrap();
    let later = hmdist::denoise::filter(&plain.image.data, &guide, &Default::default());
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&later), bits(&denoised.image.data));
    assert_ne!(bits(&later), bits(&plain.image.data));
}
