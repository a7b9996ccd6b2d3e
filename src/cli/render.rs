//! `hmdist render`: one HMD image of one scene by one method.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, ValueEnum};

use hmdist::accel::BuildQuality;
use hmdist::error::{Error, Result};
use hmdist::estimators::{gather, Estimator, Gather};
use hmdist::image::{exr, picture, write_atomically};
use hmdist::render::{render, RenderOptions, DEFAULT_SEED};
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

use super::bar::Bar;

#[derive(Args)]
pub struct RenderArgs {
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml).
    #[arg(long, default_value = "cube")]
    scene: String,
    /// Estimator (SPEC §3).
    #[arg(long, value_enum, default_value_t = Method::Gather)]
    method: Method,
    /// Gather rays per pixel N (the paper's reference is 65536).
    #[arg(long, default_value_t = gather::DEFAULT_RAYS)]
    rays: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x1024", value_parser = parse_size)]
    size: (u32, u32),
    /// Seed of the per-pixel random numbers: same seed, same image, whatever the thread count.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    seed: u64,
    /// Direction weighting over the hemisphere.
    #[arg(long, value_enum, default_value_t = WeightingArg::Cosine)]
    weighting: WeightingArg,
    /// Clamp distances at D; escaping rays then count as D [default: no clamp].
    #[arg(long, value_name = "D")]
    max_distance: Option<f32>,
    /// Worker threads [default: all cores]. Never changes the output.
    #[arg(long)]
    threads: Option<usize>,
    /// BVH build preset: high traces faster, fast builds faster.
    #[arg(long, value_enum, default_value_t = BvhArg::High)]
    bvh: BvhArg,
    /// EXR output: one float32 channel Y with H per pixel, NaN for background.
    #[arg(long, default_value = "hmd.exr")]
    out: PathBuf,
    /// PNG output, grey = clamp(scale * H) [default: the EXR path with .png].
    #[arg(long)]
    png: Option<PathBuf>,
    /// JSON sidecar: parameters, scene statistics, timings [default: the EXR path with .json].
    #[arg(long)]
    json: Option<PathBuf>,
    /// Display scale s of the PNG [default: the scene's own].
    #[arg(long)]
    scale: Option<f32>,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum Method {
    /// Ray-traced final gathering (SPEC §3.1).
    Gather,
}

#[derive(Clone, Copy, ValueEnum)]
enum WeightingArg {
    /// pdf cos θ / π (final gathering, diffuse photon paths).
    Cosine,
    /// pdf 1 / 2π.
    Uniform,
}

#[derive(Clone, Copy, ValueEnum)]
enum BvhArg {
    Fast,
    High,
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT, e.g. 1024x1024"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{v}' in '{s}' is not a whole number"))
    };
    Ok((parse(w)?, parse(h)?))
}

pub fn run(args: RenderArgs) -> Result<()> {
    let weighting = match args.weighting {
        WeightingArg::Cosine => Weighting::Cosine,
        WeightingArg::Uniform => Weighting::Uniform,
    };
    let estimator: Box<dyn Estimator> = match args.method {
        Method::Gather => Box::new(Gather::new(args.rays, weighting)?),
    };
    let options = RenderOptions {
        width: args.size.0,
        height: args.size.1,
        seed: args.seed,
        threads: args.threads,
        max_distance: args.max_distance,
        bvh_quality: match args.bvh {
            BvhArg::Fast => BuildQuality::Fast,
            BvhArg::High => BuildQuality::High,
        },
    };
    options.validate()?;
    if let Some(s) = args.scale {
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::parameter(format!(
                "--scale must be a positive number, not {s}"
            )));
        }
    }
    let png = args.png.unwrap_or_else(|| args.out.with_extension("png"));
    let json = args.json.unwrap_or_else(|| args.out.with_extension("json"));
    for path in [&args.out, &png, &json] {
        check_writable(path)?;
    }

    let bar = Bar::new(args.quiet);
    bar.status("loading");
    let load_start = Instant::now();
    let scene = Scene::load(&args.scene)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
    bar.status("BVH");
    let rendered = render(&scene, estimator.as_ref(), &options, load_seconds, &bar)?;

    exr::write(&rendered.image, &args.out)?;
    let scale = args.scale.unwrap_or(scene.display_scale);
    picture::write_png(&picture::grey(&rendered.image, scale), &png)?;
    let text = serde_json::to_string_pretty(&rendered.report).expect("report serialises");
    write_atomically(&json, text.as_bytes())?;

    if !args.quiet {
        let r = &rendered.report;
        println!(
            "{}: {}x{} {} ({} rays/pixel): {:.2} s, {:.2} Mrays/s, {} escaped, {} background -> {}, {}, {}",
            scene.name,
            options.width,
            options.height,
            estimator.method(),
            args.rays,
            r["seconds"]["total"].as_f64().unwrap_or(f64::NAN),
            r["mrays_per_s"].as_f64().unwrap_or(f64::NAN),
            r["escaped_rays"],
            r["background_pixels"],
            args.out.display(),
            png.display(),
            json.display(),
        );
    }
    Ok(())
}

/// Fails now, before a long render, if `path` cannot be written.
fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::file(path, "is a directory, not a file name"));
    }
    write_atomically(&path.with_extension("hmdist-write-test"), b"")?;
    let _ = std::fs::remove_file(path.with_extension("hmdist-write-test"));
    Ok(())
}
