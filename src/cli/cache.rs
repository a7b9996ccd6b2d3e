//! `hmdist cache`: an irradiance cache of one scene, its records spaced by a source of H or a
//! renderer's rule, with its error against a brute-force image of E when one is given.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;

use hmdist::cache::{cache, CacheParams, Range, Spacing, DEFAULT_ACCURACY};
use hmdist::error::{Error, Result};
use hmdist::estimators::irradiance::{self, IrradianceParams};
use hmdist::image::{exr, picture, HmdImage, OutputSet};
use hmdist::report::RenderReport;
use hmdist::scene::Scene;

use super::bar::Bar;

#[derive(Args)]
pub struct CacheArgs {
    /// Scene: a built-in (cube, hall, ...) or a file; it needs a spot light.
    #[arg(long, default_value = "cube")]
    scene: String,
    /// Ward's accuracy a: a point uses the records with ε = ‖x − x_i‖/R_i + √(1 − n·n_i) < a.
    #[arg(long, default_value_t = DEFAULT_ACCURACY)]
    accuracy: f32,
    /// Where each record's radius R comes from: hmd (H of its own rays), hmd:METHOD[:NAME=VALUE,...]
    /// (H from an estimator: hmd:gather:rays=64, hmd:photon2:photons=100000,nearest=64),
    /// min (pbrt-v2: half the nearest hit), min10 (Mitsuba: the nearest hit above 10°), or
    /// oracle (H from --oracle).
    #[arg(long, default_value = "hmd", value_name = "SOURCE")]
    spacing: String,
    /// Clamp R to LO..HI pixel footprints at the record (pbrt-v2: 2.5,15; Mitsuba: 3,20).
    #[arg(long, value_name = "LO,HI")]
    clamp_pixels: Option<String>,
    /// Clamp R to LO..HI times l_diag (Mitsuba: 0.005,0.32).
    #[arg(long, value_name = "LO,HI")]
    clamp_scene: Option<String>,
    /// Křivánek's neighbour clamping: a radius (before the clamps above) is cut to a nearby
    /// record's plus the distance between them, and theirs to it plus that distance.
    #[arg(long)]
    neighbour_clamp: bool,
    /// Ward and Heckbert's rotation and translation gradients: each record's E is carried
    /// to the point before weighting. Needs cosine weighting and a grid of one ray per cell
    /// (--sampler grid, or sobol with a power of two --rays).
    #[arg(long)]
    gradients: bool,
    /// An image of H of the same pixels, read by --spacing oracle.
    #[arg(long, value_name = "H.exr")]
    oracle: Option<PathBuf>,
    /// A brute-force image of E of the same pixels (`render --method irradiance`): the
    /// report's mean and p95 relative error, and --diff-png.
    #[arg(long, value_name = "E.exr")]
    reference: Option<PathBuf>,
    #[command(flatten)]
    irradiance: IrradianceParams,
    #[command(flatten)]
    image: super::image_args::ImageArgs,
    /// Stop the records' gather rays at D [default: no limit].
    #[arg(long, value_name = "D")]
    max_distance: Option<f32>,
    /// EXR output: channels E (the cache's irradiance) and records (records each pixel used).
    #[arg(long, default_value = "cache.exr")]
    out: PathBuf,
    /// PNG output: grey = clamp(scale * E), each record's pixel red [default: the EXR path
    /// with .png].
    #[arg(long)]
    png: Option<PathBuf>,
    /// JSON report: records, rays, seconds, errors [default: the EXR path with .json].
    #[arg(long)]
    json: Option<PathBuf>,
    /// A false-colour PNG of each pixel's relative error against --reference.
    #[arg(long, value_name = "FILE")]
    diff_png: Option<PathBuf>,
    /// Display scale of the PNG: its exposure [default: l_diag²/1.6].
    #[arg(long)]
    scale: Option<f32>,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
}

pub fn run(args: CacheArgs) -> Result<()> {
    let params = args.params()?;
    let mut options = hmdist::render::RenderOptions {
        max_distance: args.max_distance,
        ..args.image.options()?
    };
    options.validate()?;
    let png = args.png.clone().unwrap_or_else(|| args.out.with_extension("png"));
    let json = args
        .json
        .clone()
        .unwrap_or_else(|| args.out.with_extension("json"));
    let mut paths: Vec<&Path> = vec![&args.out, &png, &json];
    paths.extend(args.diff_png.as_deref());
    // No output may be a file the cache reads: the scene's, the images and their sidecars,
    // a photon map named inside --spacing.
    let mut inputs = Scene::files_read(&args.scene);
    for image in args.oracle.iter().chain(&args.reference) {
        inputs.extend([image.clone(), image.with_extension("json")]);
    }
    inputs.extend(params.spacing.files_read());
    let inputs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
    let outputs = OutputSet::reserve(&paths, &inputs)?;
    for (path, format) in [(&args.out, "exr"), (&png, "png"), (&json, "json")] {
        hmdist::files::check_extension(path, format)?;
    }
    if let Some(path) = &args.diff_png {
        hmdist::files::check_extension(path, "png")?;
    }

    let bar = Bar::new(args.quiet);
    bar.status("loading");
    let load_start = Instant::now();
    let scene = super::scene::load(&args.scene, &bar)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
    (options.width, options.height) = args.image.size_for(&scene);
    options.validate()?;
    let size = (options.width, options.height);
    let oracle = args
        .oracle
        .as_deref()
        .map(|path| image_of(path, exr::CHANNEL, "oracle", &scene, (&args, size)))
        .transpose()?;
    let reference = args
        .reference
        .as_deref()
        .map(|path| image_of(path, exr::IRRADIANCE_CHANNEL, "reference", &scene, (&args, size)))
        .transpose()?;
    bar.status("BVH");
    let mut cached = cache(&scene, &params, &options, oracle.as_ref(), &bar)?;
    cached.report.seconds.total += load_seconds;
    let errors = match (&reference, &args.reference) {
        (Some(image), Some(path)) => Some(cached.compare(image, &path.display().to_string())?),
        _ => None,
    };
    let mut contents = vec![
        exr::encode_channels(
            &[
                (exr::IRRADIANCE_CHANNEL, &cached.image.data[..]),
                ("records", &cached.records_used[..]),
            ],
            size,
            &args.out,
        )?,
        picture::encode_png(&cached.picture(args.scale(&cached)), &png)?,
        cached.report.to_json().into_bytes(),
    ];
    if let (Some(path), Some(errors)) = (&args.diff_png, &errors) {
        let (w, h) = size;
        let colours =
            picture::false_colour_scaled(errors, w, h, "relative error", picture::ColourScale::Linear);
        contents.push(picture::encode_png(&colours, path)?);
    }
    outputs.commit(&contents.iter().map(|c| c.as_slice()).collect::<Vec<_>>())?;
    if !args.quiet {
        let files = format!("{}, {}, {}", args.out.display(), png.display(), json.display());
        println!("{} -> {files}", cached.report.summary());
    }
    Ok(())
}

impl CacheArgs {
    /// The cache's parameters from the flags, checked (a bad source, clamp, scale or a
    /// `--diff-png` without a reference is refused by name).
    fn params(&self) -> Result<CacheParams> {
        if let Some(s) = self.scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
            let message = format!("must be a positive number, not {s}");
            return Err(Error::invalid("scale", message));
        }
        if self.diff_png.is_some() && self.reference.is_none() {
            return Err(Error::invalid(
                "diff_png",
                "needs --reference: the error is against it",
            ));
        }
        let range = |name, text: &Option<String>| text.as_deref().map(|t| Range::parse(name, t)).transpose();
        Ok(CacheParams {
            irradiance: self.irradiance.clone(),
            accuracy: self.accuracy,
            spacing: Spacing::parse(&self.spacing)?,
            clamp_pixels: range("clamp_pixels", &self.clamp_pixels)?,
            clamp_scene: range("clamp_scene", &self.clamp_scene)?,
            neighbour_clamp: self.neighbour_clamp,
            gradients: self.gradients,
        })
    }

    /// The PNG's exposure: `--scale`, by default irradiance's.
    fn scale(&self, cached: &hmdist::cache::Cached) -> f32 {
        self.scale
            .unwrap_or_else(|| irradiance::display_scale(cached.report.l_diag))
    }
}

/// Channel `channel` of the EXR at `path` (`--oracle` or `--reference`, named `flag`), checked
/// against the cache to come: the same size, and where its JSON sidecar is there, a render of
/// the same pixels ([`not_the_same_pixels`]).
fn image_of(
    path: &Path,
    channel: &str,
    flag: &'static str,
    scene: &Scene,
    (args, size): (&CacheArgs, (u32, u32)),
) -> Result<HmdImage> {
    let image = exr::read_channel(path, channel).map_err(|e| {
        let hint = if channel == exr::IRRADIANCE_CHANNEL {
            "make one with hmdist render --method irradiance"
        } else {
            "an image of H"
        };
        Error::invalid(flag, format!("{}: {hint}", e.describe(|n| n.into())))
    })?;
    if (image.width, image.height) != size {
        let message = format!(
            "{} is {}x{}, the cache {}x{}: it must be an image of the same pixels",
            path.display(),
            image.width,
            image.height,
            size.0,
            size.1
        );
        return Err(Error::invalid(flag, message));
    }
    let sidecar = path.with_extension("json");
    if sidecar.is_file() {
        let report = RenderReport::read(&sidecar).map_err(|e| {
            let what = if made_by_cache(&sidecar) {
                "is the report of `hmdist cache`: a cache's image is what is measured, not a reference"
                    .to_string()
            } else {
                format!("is not the report of a render ({})", e.describe(|n| n.into()))
            };
            let message = format!(
                "{}'s sidecar {} {what}: give the image `hmdist render` wrote{}",
                path.display(),
                sidecar.display(),
                if flag == "reference" {
                    " with --method irradiance"
                } else {
                    ""
                }
            );
            Error::invalid(flag, message)
        })?;
        let differences = not_the_same_pixels(&report, scene, args, flag == "reference");
        if !differences.is_empty() {
            let message = format!(
                "{} is not an image of the pixels this cache makes: {}",
                path.display(),
                differences.join("; ")
            );
            return Err(Error::invalid(flag, message));
        }
    }
    Ok(image)
}

/// What differs between the render `report` describes and the cache `args` makes of `scene`,
/// each as `what (the image's against the cache's)`: a shard's part, the scene (its name,
/// triangles, bounds), the camera, the distance clamp; for a reference of E (`of_e`) also its
/// method, the light and the absorption. The rays, seed and sampler do not count: they change
/// an estimate's noise, not what it estimates.
fn not_the_same_pixels(report: &RenderReport, scene: &Scene, args: &CacheArgs, of_e: bool) -> Vec<String> {
    use hmdist::report::{BoundsReport, CameraReport, LightReport};
    let mut differences = vec![];
    let mut differ = |what: &str, theirs: String, ours: String| {
        if theirs != ours {
            differences.push(format!("{what} ({theirs} against {ours})"));
        }
    };
    if let Some(shard) = &report.shard {
        differ(
            "a shard's part",
            format!("{}/{}", shard.index, shard.count),
            "a whole image".into(),
        );
    }
    differ("scene", report.scene.clone(), scene.name.clone());
    differ(
        "triangles",
        report.triangles.to_string(),
        scene.mesh.triangle_count().to_string(),
    );
    differ(
        "bounds",
        json(&report.bounds),
        json(&BoundsReport::from(&scene.bounds())),
    );
    differ(
        "camera",
        json(&report.camera),
        json(&CameraReport::from(&scene.camera)),
    );
    differ(
        "max_distance",
        format!("{:?}", report.max_distance),
        format!("{:?}", args.max_distance),
    );
    if of_e {
        differ("method", report.method.clone(), "irradiance".into());
        differ(
            "light",
            json(&report.light),
            json(&scene.light.as_ref().map(LightReport::from)),
        );
        let absorption = report.parameters.number("absorption").map(|a| a as f32);
        differ(
            "absorption",
            format!("{absorption:?}"),
            format!("{:?}", Some(args.irradiance.absorption)),
        );
    }
    differences
}

/// Whether the JSON file at `path` is a cache's report (`"method": "cache"`).
fn made_by_cache(path: &Path) -> bool {
    let text = hmdist::files::read_text(path).unwrap_or_default();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    value["method"] == "cache"
}

/// `value` as JSON text, to compare report parts that have no `PartialEq`.
fn json(value: &impl serde::Serialize) -> String {
    serde_json::to_string(value).expect("a report part serialises")
}
