//! `hmdist merge OUT.exr PART.exr...`: the one-machine image from every shard's part
//! (`hmdist render --shard K/M`), checked: one render, each shard exactly once.

use std::path::PathBuf;

use clap::Args;

use hmdist::error::Result;
use hmdist::estimators::{Aov, AovImage};
use hmdist::image::{exr, picture, OutputSet};
use hmdist::report::RenderReport;
use hmdist::shard::{merge, Part};

#[derive(Args)]
pub struct MergeArgs {
    /// The merged EXR (its PNG and JSON beside it, as `render` writes them).
    out: PathBuf,
    /// Every shard's EXR, in any order; each one's JSON sidecar beside it.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// PNG output [default: OUT with .png].
    #[arg(long)]
    png: Option<PathBuf>,
    /// JSON output [default: OUT with .json].
    #[arg(long)]
    json: Option<PathBuf>,
    /// No summary line.
    #[arg(long)]
    quiet: bool,
}

/// A part's image, AOVs and report from its EXR and JSON.
fn read_part(path: &std::path::Path) -> Result<Part> {
    let json = path.with_extension("json");
    let report = RenderReport::read(&json)?;
    let image = match report.channels.first() {
        Some(channel) => exr::read_channel(path, channel)?,
        None => exr::read(path)?,
    };
    // Channel 0 is the image itself: Y, H (or E, irradiance).
    let aovs = report
        .channels
        .iter()
        .skip(1)
        .map(|name| {
            Ok(AovImage {
                aov: Aov::parse(name)?,
                data: exr::read_channel(path, name)?.data,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // A part of a denoised render carries the filter's guide for the merge to filter with.
    let guide = match &report.denoise {
        Some(denoise) if !denoise.filtered => Some(exr::read_guide(path)?),
        _ => None,
    };
    Ok(Part {
        image,
        aovs,
        report,
        guide,
    })
}

pub fn run(args: MergeArgs) -> Result<()> {
    let png = args.png.clone().unwrap_or_else(|| args.out.with_extension("png"));
    let json = args
        .json
        .clone()
        .unwrap_or_else(|| args.out.with_extension("json"));
    // No output may be a part or a part's report.
    let reports: Vec<std::path::PathBuf> = args.parts.iter().map(|p| p.with_extension("json")).collect();
    let inputs: Vec<&std::path::Path> = args.parts.iter().chain(&reports).map(|p| p.as_path()).collect();
    let outputs = OutputSet::reserve(&[&args.out, &png, &json], &inputs)?;
    // After the reservation: a path named twice or an input is the first thing to say.
    for (path, format) in [(&args.out, "exr"), (&png, "png"), (&json, "json")] {
        hmdist::files::check_extension(path, format)?;
    }
    let parts = args
        .parts
        .iter()
        .map(|p| read_part(p))
        .collect::<Result<Vec<_>>>()?;
    let merged = merge(parts)?;
    let channel = merged
        .report
        .channels
        .first()
        .map_or(exr::CHANNEL, String::as_str);
    let exr_bytes = exr::encode_as(channel, &merged.image, &merged.aovs, &args.out)?;
    let grey = picture::grey(&merged.image, merged.report.display_scale);
    let png_bytes = picture::encode_png(&grey, &png)?;
    outputs.commit(&[&exr_bytes, &png_bytes, merged.report.to_json().as_bytes()])?;
    if !args.quiet {
        println!(
            "merged {} shards -> {}, {}, {}",
            args.parts.len(),
            args.out.display(),
            png.display(),
            json.display()
        );
    }
    Ok(())
}
