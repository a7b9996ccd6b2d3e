//! `hmdist experiment NAME`: the paper's analysis on a scene, as tables and an HTML report.

use std::path::PathBuf;

use clap::Args;

use hmdist::error::Result;
use hmdist::experiments::{Preset, Runner, EXPERIMENTS};

use super::bar::Bar;

#[derive(Args)]
pub struct ExperimentArgs {
    /// Experiment: all, table1 (f_diff vs rays, fig12/fig13), table2 (seconds vs rays), fig9
    /// (gather vs cube map), table3 (photons x K, fig14/fig15), fig10 (methods I and II),
    /// table4 (photon map build), fig16_17 (source x bounces x K x photons), memory.
    name: String,
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file.
    #[arg(long, default_value = "cube")]
    scene: String,
    /// quick: 48², reference 16384 rays, minutes; paper: 1024², reference 65536 rays, hours.
    #[arg(long, value_enum, default_value_t = Preset::Quick)]
    preset: Preset,
    /// Output folder: tables (CSV, Markdown), index.html, and the image cache that reruns reuse.
    #[arg(long, default_value = "experiments")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

pub fn run(args: ExperimentArgs) -> Result<()> {
    let preset = args.preset;
    if args.name != "all" && !EXPERIMENTS.contains(&args.name.as_str()) {
        return Err(hmdist::error::Error::parameter(format!(
            "unknown experiment '{}': expected all or one of {}",
            args.name,
            EXPERIMENTS.join(", ")
        )));
    }
    let bar = Bar::new(args.quiet);
    let mut runner = Runner::new(&args.scene, preset, &args.out, &bar)?;
    runner.run(&args.name)?;
    if !args.quiet {
        for section in &runner.sections {
            for table in &section.tables {
                println!("{}", table.markdown());
            }
            for note in &section.notes {
                println!("- {note}");
            }
            println!();
        }
        println!("report: {}", args.out.join("index.html").display());
    }
    Ok(())
}
