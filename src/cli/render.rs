//! `hmdist render`: one HMD image of one scene by one method.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};

use hmdist::accel::BuildQuality;
use hmdist::error::{Error, Result};
use hmdist::estimators::cubemap::{self, Backend};
use hmdist::estimators::photon::{self, PathRules, PhotonMethod, PhotonParams, SourceKind};
use hmdist::estimators::{gather, Cubemap, Estimator, Gather, PhotonEstimator};
use hmdist::image::{exr, picture, OutputSet};
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
    /// Gather rays per pixel N, for gather (the paper's reference is 65536).
    #[arg(long, default_value_t = gather::DEFAULT_RAYS)]
    rays: u32,
    /// Photons stored P, exactly.
    #[arg(long, default_value_t = photon::DEFAULT_PHOTONS, help_heading = "Photon methods")]
    photons: usize,
    /// Per-quadrant hemicube resolution R: top face 2R x 2R, sides 2R x R.
    #[arg(long, default_value_t = cubemap::DEFAULT_CUBE_RES, help_heading = "Cube map")]
    cube_res: u32,
    /// Who builds the cube maps: gpu (wgpu rasterisation), cpu (ray casting), auto (gpu if a
    /// hardware adapter exists, else cpu).
    #[arg(long, value_enum, default_value_t = BackendArg::Auto, help_heading = "Cube map")]
    backend: BackendArg,
    /// Nearest photons gathered per pixel K.
    #[arg(long, default_value_t = photon::DEFAULT_GATHER, help_heading = "Photon methods")]
    gather: usize,
    /// Where paths start.
    #[arg(long, value_enum, default_value_t = SourceArg::Light, help_heading = "Photon methods")]
    source: SourceArg,
    /// A path ends at this many surface interactions.
    #[arg(long, default_value_t = photon::DEFAULT_MAX_BOUNCES, help_heading = "Photon methods")]
    max_bounces: u32,
    /// Probability that a path ends at each interaction.
    #[arg(long, default_value_t = photon::DEFAULT_ABSORPTION, help_heading = "Photon methods")]
    absorption: f32,
    /// Gather only within this distance of the pixel [default: no limit].
    #[arg(long, value_name = "R", help_heading = "Photon methods")]
    max_radius: Option<f32>,
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
    /// BVH build preset, by the work to come unless named.
    #[arg(long, value_enum, default_value_t = BvhArg::Auto)]
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
    /// Hemicube rasterisation, looked up with gather's directions (SPEC §3.2).
    Cubemap,
    /// Photon map, method I: harmonic mean of the gathered photons' own distances (SPEC §3.3).
    Photon1,
    /// Photon map, method II: distances from the pixel to the photons' next hits (SPEC §3.3).
    Photon2,
}

#[derive(Clone, Copy, ValueEnum)]
enum BackendArg {
    Auto,
    Gpu,
    Cpu,
}

#[derive(Clone, Copy, ValueEnum)]
enum SourceArg {
    /// The scene's spot light.
    Light,
    /// The camera, through random image positions.
    Camera,
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
    /// high when the render casts at least 500 rays per triangle, else fast.
    Auto,
    /// Binned SAH, parallel: builds about 10x faster than high, traces 3-8% slower.
    Fast,
    /// Spatial splits and whole-tree reinsertion: the fastest tracing.
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
    let photon_params = PhotonParams {
        photons: args.photons,
        gather: args.gather,
        source: match args.source {
            SourceArg::Light => SourceKind::Light,
            SourceArg::Camera => SourceKind::Camera,
        },
        rules: PathRules {
            max_bounces: args.max_bounces,
            absorption: args.absorption,
        },
        max_radius: args.max_radius,
    };
    let estimator: Box<dyn Estimator> = match args.method {
        Method::Gather => Box::new(Gather::new(args.rays, weighting)?),
        Method::Cubemap => {
            let backend = match args.backend {
                BackendArg::Auto => Backend::Auto,
                BackendArg::Gpu => Backend::Gpu,
                BackendArg::Cpu => Backend::Cpu,
            };
            Box::new(Cubemap::new(
                Gather::new(args.rays, weighting)?,
                args.cube_res,
                backend,
            )?)
        }
        Method::Photon1 => Box::new(PhotonEstimator::new(PhotonMethod::StoredDistance, photon_params)?),
        Method::Photon2 => Box::new(PhotonEstimator::new(PhotonMethod::NextHitPoint, photon_params)?),
    };
    let options = RenderOptions {
        width: args.size.0,
        height: args.size.1,
        seed: args.seed,
        threads: args.threads,
        max_distance: args.max_distance,
        bvh_quality: match args.bvh {
            BvhArg::Auto => BuildQuality::Auto,
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
    // Fails now, before a long render, if an output cannot be written.
    let outputs = OutputSet::reserve(&[&args.out, &png, &json])?;

    let bar = Bar::new(args.quiet);
    bar.status("loading");
    let load_start = Instant::now();
    let scene = Scene::load(&args.scene)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
    bar.status("BVH");
    let rendered = render(&scene, estimator.as_ref(), &options, load_seconds, &bar)?;

    let scale = args.scale.unwrap_or(scene.display_scale);
    let exr_bytes = exr::encode(&rendered.image, &args.out)?;
    let png_bytes = picture::encode_png(&picture::grey(&rendered.image, scale), &png)?;
    let text = serde_json::to_string_pretty(&rendered.report).expect("report serialises");
    outputs.commit(&[&exr_bytes, &png_bytes, text.as_bytes()])?;

    if !args.quiet {
        let r = &rendered.report;
        let what = match args.method {
            Method::Cubemap => format!(
                "{} rays/pixel, R = {}, {} backend",
                args.rays,
                args.cube_res,
                r["backend"].as_str().unwrap_or("?")
            ),
            Method::Gather => format!(
                "{} rays/pixel, {:.2} Mrays/s",
                args.rays,
                r["mrays_per_s"].as_f64().unwrap_or(f64::NAN)
            ),
            Method::Photon1 | Method::Photon2 => format!(
                "{} photons, K = {}, {} holes, {:.0} queries/s",
                r["photons_stored"],
                args.gather,
                r["holes"],
                r["gather_queries_per_s"].as_f64().unwrap_or(f64::NAN)
            ),
        };
        println!(
            "{}: {}x{} {} ({what}): {:.2} s, {} escaped, {} background -> {}, {}, {}",
            scene.name,
            options.width,
            options.height,
            estimator.method(),
            r["seconds"]["total"].as_f64().unwrap_or(f64::NAN),
            // The cube map's rays fill texels; its directions are the lookups.
            r.get("escaped_lookups").unwrap_or(&r["escaped_rays"]),
            r["background_pixels"],
            args.out.display(),
            png.display(),
            json.display(),
        );
    }
    Ok(())
}
