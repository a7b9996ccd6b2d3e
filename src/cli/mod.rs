//! Command-line interface (SPEC §7). Every error is the user's: printed as one paragraph,
//! exit status 2 (clap's own usage errors exit 2 as well).

mod bar;
mod diff;
mod experiment;
mod render;
mod scene;

use clap::{Parser, Subcommand};

use hmdist::error::Result;

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
}

#[derive(Subcommand)]
enum Command {
    /// Render an HMD image: EXR (H per pixel), PNG (grey picture) and JSON (parameters, timings).
    Render(render::RenderArgs),
    /// Compare two HMD images: f_diff (SPEC §4), RMSE, mean relative error, difference picture.
    Diff(diff::DiffArgs),
    /// Reproduce the paper's analysis on a scene: tables, notes and an HTML report.
    Experiment(experiment::ExperimentArgs),
    /// Inspect or export a scene.
    #[command(subcommand)]
    Scene(scene::SceneCommand),
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => render::run(args),
        Command::Diff(args) => diff::run(args),
        Command::Experiment(args) => experiment::run(args),
        Command::Scene(command) => scene::run(command),
    }
}
