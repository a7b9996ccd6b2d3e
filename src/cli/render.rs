//! `hmdist render`: one HMD image of one scene by one method. Flags map onto the library's
//! [`RenderOptions`] and onto the chosen method's parameter struct (every method's flags are
//! offered; [`registry::flags`] makes them, and a flag the method does not read is refused);
//! the work is [`render`]'s.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use hmdist::error::{Error, Result};
use hmdist::estimators::registry::{self, METHODS};
use hmdist::estimators::Aov;
use hmdist::image::{picture, OutputSet};
use hmdist::render::{render, RenderOptions};
use hmdist::scene::Scene;
use hmdist::shard::Shard;

use super::bar::Bar;

#[derive(Args)]
pub struct RenderArgs {
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml,
    /// .pbrt, .pbrt.gz, Mitsuba 3 .xml).
    #[arg(long, default_value = "cube")]
    scene: String,
    /// Estimator (docs/spec.md §3).
    #[arg(long, default_value = "gather", value_parser = method_names())]
    method: String,
    #[command(flatten)]
    method_flags: MethodFlags,
    #[command(flatten)]
    image: super::image_args::ImageArgs,
    /// Clamp distances at D; escaping rays then count as D [default: no clamp].
    #[arg(long, value_name = "D")]
    max_distance: Option<f32>,
    /// EXR output: one float32 channel Y with H per pixel (E, irradiance, with --method
    /// irradiance), NaN for background.
    #[arg(long, default_value = "hmd.exr")]
    out: PathBuf,
    /// PNG output, grey = clamp(scale * H) (or E) [default: the EXR path with .png].
    #[arg(long)]
    png: Option<PathBuf>,
    /// JSON sidecar: parameters, scene statistics, timings [default: the EXR path with .json].
    #[arg(long)]
    json: Option<PathBuf>,
    /// Display scale s of the PNG: its exposure [default: the scene's own; for irradiance,
    /// l_diag²/1.6].
    #[arg(long)]
    scale: Option<f32>,
    /// AOVs to add as EXR channels beside Y, comma-separated: relerr (relative standard error
    /// of H), rays (rays cast), dmin (smallest hit distance), ao (ambient occlusion within
    /// --ao-radius), escaped (fraction of rays that escaped); with --method irradiance,
    /// E_direct (direct irradiance from the light).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        value_name = "LIST",
        help_heading = "AOVs and adaptive"
    )]
    aov: Vec<Aov>,
    /// A false-colour PNG of an AOV, with a legend (repeatable); adds the AOV if not asked for.
    #[arg(long, num_args = 2, value_names = ["NAME", "FILE"], help_heading = "AOVs and adaptive")]
    png_aov: Vec<String>,
    /// Render only shard K of M: the rows r with r mod M = K, for `hmdist merge` (a denoised
    /// shard's part holds its own rays' H and the filter's guide; the merge filters).
    #[arg(long, value_name = "K/M", value_parser = parse_shard)]
    shard: Option<Shard>,
    #[command(flatten)]
    denoise: super::denoise_args::DenoiseArgs,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
}

/// Every method's flags (`--rays`, `--photons`, ...), kept as parsed until the method named
/// by `--method` reads its own from them.
pub struct MethodFlags(clap::ArgMatches);

impl clap::FromArgMatches for MethodFlags {
    fn from_arg_matches(matches: &clap::ArgMatches) -> std::result::Result<Self, clap::Error> {
        Ok(MethodFlags(matches.clone()))
    }

    fn update_from_arg_matches(
        &mut self,
        matches: &clap::ArgMatches,
    ) -> std::result::Result<(), clap::Error> {
        self.0 = matches.clone();
        Ok(())
    }
}

impl clap::Args for MethodFlags {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        registry::flags(cmd)
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        registry::flags(cmd)
    }
}

pub(super) fn parse_shard(text: &str) -> std::result::Result<Shard, String> {
    Shard::parse(text).map_err(|e| e.describe(|_| "--shard".into()))
}

/// `--method`'s values, with the registry's sentence on each as its help.
fn method_names() -> clap::builder::PossibleValuesParser {
    let values = METHODS
        .iter()
        .map(|m| clap::builder::PossibleValue::new(m.name).help(m.summary));
    clap::builder::PossibleValuesParser::new(values)
}

/// The existing files that method flags name (`--photon-map`): inputs of the render.
fn flag_files(matches: &clap::ArgMatches) -> Vec<PathBuf> {
    registry::flag_ids()
        .iter()
        .filter_map(|id| matches.get_raw(id))
        .flatten()
        .map(PathBuf::from)
        .filter(|path| path.is_file())
        .collect()
}

pub fn run(args: RenderArgs) -> Result<()> {
    let mut aovs = args.aov.clone();
    let mut pictures = vec![];
    for pair in args.png_aov.chunks(2) {
        let aov = Aov::parse(&pair[0])?;
        if !aovs.contains(&aov) {
            aovs.push(aov);
        }
        pictures.push((aov, PathBuf::from(&pair[1])));
    }
    aovs.dedup();
    let estimator = registry::method(&args.method)?.build_from_flags(&args.method_flags.0, &aovs)?;
    let mut options = RenderOptions {
        max_distance: args.max_distance,
        aovs,
        shard: args.shard,
        denoise: args.denoise.params(),
        ..args.image.options()?
    };
    options.validate()?;
    if let Some(s) = args.scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(Error::invalid(
            "scale",
            format!("must be a positive number, not {s}"),
        ));
    }
    let png = args.png.unwrap_or_else(|| args.out.with_extension("png"));
    let json = args.json.unwrap_or_else(|| args.out.with_extension("json"));
    // Fails now, before a long render, if an output cannot be written.
    let mut paths: Vec<&std::path::Path> = vec![&args.out, &png, &json];
    paths.extend(pictures.iter().map(|(_, path)| path.as_path()));
    // No output may be a file this render reads: the scene's files, a photon map.
    let mut inputs = Scene::files_read(&args.scene);
    inputs.extend(flag_files(&args.method_flags.0));
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let outputs = OutputSet::reserve(&paths, &inputs)?;
    // After the reservation: a path named twice or an input is the first thing to say.
    for (path, format) in [(&args.out, "exr"), (&png, "png"), (&json, "json")] {
        hmdist::files::check_extension(path, format)?;
    }
    for (_, path) in &pictures {
        hmdist::files::check_extension(path, "png")?;
    }

    let bar = Bar::new(args.quiet);
    bar.status("loading");
    let load_start = Instant::now();
    let scene = super::scene::load(&args.scene, &bar)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
    (options.width, options.height) = args.image.size_for(&scene);
    options.validate()?;
    bar.status("BVH");
    let mut rendered = render(&scene, estimator.as_ref(), &options, &bar)?;
    rendered.report.add_load_seconds(load_seconds);

    // The JSON records the PNG's scale, so that `merge` draws the merged PNG the same way.
    let scale = args.scale.unwrap_or_else(|| estimator.display_scale(&scene));
    rendered.report.display_scale = scale;
    let exr_bytes = rendered.exr(&args.out)?;
    let png_bytes = picture::encode_png(&picture::grey(&rendered.image, scale), &png)?;
    let mut contents = vec![exr_bytes, png_bytes, rendered.report.to_json().into_bytes()];
    for (aov, path) in &pictures {
        let channel = rendered.aovs.iter().find(|c| c.aov == *aov).expect("asked for");
        let (w, h) = (rendered.image.width, rendered.image.height);
        // An adaptive render's rays per pixel span decades: a log scale shows them.
        let scale = match aov {
            Aov::Rays => picture::ColourScale::Log,
            _ => picture::ColourScale::Linear,
        };
        contents.push(picture::encode_png(
            &picture::false_colour_scaled(&channel.data, w, h, aov.name(), scale),
            path,
        )?);
    }
    outputs.commit(&contents.iter().map(|c| c.as_slice()).collect::<Vec<_>>())?;
    if !args.quiet {
        let files = format!("{}, {}, {}", args.out.display(), png.display(), json.display());
        println!("{} -> {files}", rendered.report.summary());
    }
    Ok(())
}
