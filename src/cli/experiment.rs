//! `hmdist experiment NAME`: the paper's analysis on a scene, as tables and an HTML report.

use std::path::PathBuf;

use clap::Args;

use hmdist::error::Result;
use hmdist::estimators::cubemap::GpuFill;
use hmdist::estimators::Backend;
use hmdist::experiments::{select, Preset, Runner, EXPERIMENTS};
use hmdist::shard::Shard;

use super::bar::Bar;

#[derive(Args)]
pub struct ExperimentArgs {
    /// Experiment: all, or one or several of these (table3,fig10 or table3 fig10): they run
    /// in this order, each once, and share one report.
    #[arg(value_parser = experiment_names(), value_delimiter = ',', required = true)]
    names: Vec<String>,
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file.
    #[arg(long, default_value = "cube")]
    scene: String,
    /// quick: 48², reference 16384 rays, minutes; paper: 1024², reference 65536 rays, hours.
    #[arg(long, value_enum, default_value_t = Preset::Quick)]
    preset: Preset,
    /// Image side in pixels instead of the preset's (48 for quick, 1024 for paper): its
    /// other counts stay. Part of the image cache's key.
    #[arg(long, value_name = "PIXELS")]
    size: Option<u32>,
    /// Output folder: tables (CSV, Markdown), index.html, and the image cache that reruns reuse.
    #[arg(long, default_value = "experiments")]
    out: PathBuf,
    /// Render only shard K of M of the images (into OUT/cache); a run without --shard then
    /// finds them all cached and writes the tables and the report.
    #[arg(long, value_name = "K/M", value_parser = super::render::parse_shard)]
    shard: Option<Shard>,
    /// Where gather and the cube map run: auto takes a hardware GPU where there is one. Part
    /// of the image cache's key.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    backend: Backend,
    /// How the cube map fills its texels on the GPU: raster (the paper's method) or rays
    /// (a ray per looked-up texel; far faster on compute GPUs such as the H100/H200, which
    /// rasterise slowly). Part of the cube maps' cache key where it is rays.
    #[arg(long, value_enum, default_value_t = GpuFill::Raster)]
    gpu_fill: GpuFill,
    /// Tables 1–2 with final gathering alone, no cube map (the paper's scene-B row of Table
    /// 1 has no cube-map column): the same gather images, hours fewer on a CPU. Changes no
    /// cached image's key.
    #[arg(long)]
    no_cubemap: bool,
    /// Take the reference image (gather, the preset's reference rays, seed 1000003) from this
    /// EXR and the report beside it (same name, .json) instead of rendering it: refused
    /// unless the report says it is this run's reference (scene, size, parameters, version;
    /// any backend).
    /// docs/paper-scale/cube/reference.exr is cube's at --preset paper --backend cpu.
    #[arg(long, value_name = "EXR")]
    reference: Option<PathBuf>,
    /// Print what the run will cost and render nothing: every image it needs (each once),
    /// which are cached, and each one's seconds, estimated from a calibration render of a few
    /// rows; written to OUT/plan.md, plan.csv and plan.json. A later run's report puts the
    /// estimates beside the seconds taken.
    #[arg(long, conflicts_with = "shard")]
    plan: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// `all` and the experiments' names, with their summaries as help.
fn experiment_names() -> clap::builder::PossibleValuesParser {
    let all = clap::builder::PossibleValue::new("all").help("every experiment below, in order");
    let each = EXPERIMENTS
        .iter()
        .map(|e| clap::builder::PossibleValue::new(e.name).help(e.summary));
    clap::builder::PossibleValuesParser::new(std::iter::once(all).chain(each))
}

impl ExperimentArgs {
    /// What an interrupted run of it keeps: the images it finished, in OUT/cache.
    pub fn kept_when_interrupted(&self) -> String {
        format!(
            "the images it finished are kept in {} (each whole); the same command goes on from them, \
             and no table or report was written",
            self.out.join("cache").display()
        )
    }
}

pub fn run(args: ExperimentArgs) -> Result<()> {
    let preset = args.preset;
    let names = args.names.join(",");
    select(&names)?;
    let bar = Bar::new(args.quiet);
    let mut runner = Runner::new(&args.scene, preset, &args.out, &bar)?
        .with_backend(args.backend)
        .with_gpu_fill(args.gpu_fill)
        .with_cubemaps(!args.no_cubemap)
        .with_kernel(hmdist::accel::Kernel::from_env()?)
        .with_size(args.size)?;
    if let Some(reference) = &args.reference {
        runner = runner.with_reference(reference)?;
    }
    if let Some(shard) = args.shard {
        runner = runner.with_shard(shard)?;
    }
    if args.plan {
        runner = runner.with_plan()?;
    }
    runner.run(&names)?;
    if let Some(plan) = &runner.planned {
        if !args.quiet {
            println!("{}", plan.items_table().markdown());
            println!("{}", plan.summary_table().markdown());
            println!("plan: {}", args.out.join("plan.md").display());
        }
        return Ok(());
    }
    if let Some((rendered, others)) = runner.shard_counts() {
        if !args.quiet {
            println!(
                "shard {}/{}: rendered {rendered} images into {} ({others} are other shards'); \
                 run again without --shard to write the report",
                args.shard.map_or(0, |s| s.index),
                args.shard.map_or(1, |s| s.count),
                args.out.join("cache").display()
            );
        }
        return Ok(());
    }
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
        if let Some(table) = runner.plan_against_run() {
            println!("{}", table.markdown());
        }
        println!("report: {}", args.out.join("index.html").display());
    }
    Ok(())
}
