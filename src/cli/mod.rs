//! Command-line interface (spec §7, §8): flags become the library's configuration, results
//! become files and one summary line. Every error is the user's: printed as one paragraph
//! with parameters spelled as flags, exit status 2 (clap's own usage errors exit 2 as well);
//! an interrupted run exits with 130 (Ctrl-C) or 143 (SIGTERM) ([`signals`]); `diff --exact`
//! exits with 1 where the two images are not the same bit for bit.

mod bar;
mod cache;
mod denoise_args;
mod diff;
mod experiment;
mod gpu;
mod image_args;
mod merge;
mod photons;
mod points;
mod render;
mod scene;
pub mod signals;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use hmdist::error::{Error, Result};

#[derive(Parser)]
#[command(
    name = "hmdist",
    version,
    about = "Harmonic mean distance (HMD) images of triangle-mesh scenes",
    long_about = "Harmonic mean distance (HMD) images of triangle-mesh scenes.\n\n\
        H(x) is the harmonic mean of the distances from a surface point x to the surfaces it \
        sees over its hemisphere. hmdist renders one H per pixel with the estimators of \
        Cha & Ihm 2010 and measures how accurate and how fast each one is."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The GPU adapter for --backend gpu|gpu-software|auto: an index of `hmdist gpu list`, or a
    /// part of an adapter's name or PCI bus id [default: HMDIST_GPU, else CUDA_VISIBLE_DEVICES's
    /// first GPU, else one per SLURM_LOCALID, else wgpu's choice].
    #[arg(long, global = true, value_name = "N|NAME")]
    gpu: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Render an HMD image: EXR (H per pixel), PNG (grey picture) and JSON (parameters, timings).
    Render(render::RenderArgs),
    /// H at the points of a file (.npy or .csv rows x y z nx ny nz), by final gathering.
    Points(points::PointsArgs),
    /// Merge the parts of `render --shard K/M` into the image one machine would render.
    Merge(merge::MergeArgs),
    /// An irradiance cache whose records are spaced by a source of H (or a renderer's rule),
    /// and its error against a brute-force image of E.
    Cache(cache::CacheArgs),
    /// Build a photon map once, for `render --photon-map` (e.g. for every shard).
    #[command(subcommand)]
    Photons(photons::PhotonsCommand),
    /// Compare two HMD images: f_diff (docs/spec.md §4), RMSE, mean relative error, difference picture.
    Diff(diff::DiffArgs),
    /// Reproduce the paper's analysis on a scene: tables, notes and an HTML report.
    Experiment(experiment::ExperimentArgs),
    /// Inspect or export a scene.
    #[command(subcommand)]
    Scene(scene::SceneCommand),
    /// List the GPU adapters and the one the GPU backends take.
    #[command(subcommand)]
    Gpu(gpu::GpuCommand),
}

/// The command line as parsed: [`Cli`], with every flag that takes a value also taking a
/// negative number as its value (`--scale -1`, `--seed -1`), and `--size` any value starting
/// with `-` (`--size -8x8`), so that the message names the value's problem rather than
/// calling `-1` an unknown flag.
pub fn parse() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    fn negatives(command: clap::Command) -> clap::Command {
        command
            .mut_args(|arg| {
                let takes_value = arg.get_action().takes_values() && !arg.is_positional();
                let size = arg.get_id() == "size";
                arg.allow_negative_numbers(takes_value)
                    .allow_hyphen_values(takes_value && size)
            })
            .mut_subcommands(negatives)
    }
    let matches = negatives(Cli::command()).get_matches();
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

pub fn run(cli: Cli) -> Result<ExitCode> {
    #[cfg(feature = "gpu")]
    if let Some(selector) = &cli.gpu {
        hmdist::gpu::select_adapter(selector);
    }
    let done = match cli.command {
        Command::Render(args) => render::run(args),
        Command::Points(args) => points::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Cache(args) => cache::run(args),
        Command::Photons(command) => photons::run(command),
        // `diff --exact` exits 1 where the images differ: an answer, not an error.
        Command::Diff(args) => return diff::run(args),
        Command::Experiment(args) => experiment::run(args),
        Command::Scene(command) => scene::run(command),
        Command::Gpu(command) => gpu::run(command),
    };
    done.map(|()| ExitCode::SUCCESS)
}

/// What a run of `cli` keeps if it is interrupted, for the line hmdist ends with: nothing, but
/// for an experiment, whose finished images stay cached for the same command to go on from.
pub fn kept_when_interrupted(cli: &Cli) -> String {
    match &cli.command {
        Command::Experiment(args) => args.kept_when_interrupted(),
        _ => "no output was written".into(),
    }
}

/// The error as the person who typed the command should read it: library parameter names
/// (`max_distance`) as the flags that set them (`--max-distance`).
pub fn describe(error: &Error) -> String {
    error.describe(|name| match name {
        "width" | "height" => "--size".into(),
        "bvh_quality" => "--bvh".into(),
        name => format!("--{}", name.replace('_', "-")),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_command_line_is_well_formed() {
        // Every method's flags join `render`'s own: a flag name two of them claim fails here.
        use clap::CommandFactory;
        super::Cli::command().debug_assert();
    }
}
