//! `hmdist diff REF.exr TEST.exr`: f_diff (spec §4) and friends, whether the two are the same
//! bit for bit, and the difference picture.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use hmdist::error::{Error, Result};
use hmdist::image::{exr, picture};
use hmdist::metrics::{compare, difference_picture};
use hmdist::scene::Scene;

#[derive(Args)]
pub struct DiffArgs {
    /// The reference image (EXR, channel Y), e.g. gather with 65536 rays.
    reference: PathBuf,
    /// The image to compare with it.
    test: PathBuf,
    /// Scene giving l_diag (and the display scale) [default: read from REF's JSON sidecar].
    #[arg(long)]
    scene: Option<String>,
    /// Write the difference picture, grey = 1 - clamp(10 * scale * |dH|), white where equal.
    #[arg(long, value_name = "DIFF.png")]
    png: Option<PathBuf>,
    /// Display scale s of the difference picture [default: the scene's].
    #[arg(long)]
    scale: Option<f32>,
    /// Exit with status 1 unless the two images are the same bit for bit (as `cmp` does; for
    /// scripts that check determinism: thread counts, kernels, shards, reruns).
    #[arg(long)]
    exact: bool,
}

pub fn run(args: DiffArgs) -> Result<ExitCode> {
    if let Some(png) = &args.png {
        // Not over either image or its report (they are what this command reads).
        let reports = [
            args.reference.with_extension("json"),
            args.test.with_extension("json"),
        ];
        let inputs = [
            args.reference.as_path(),
            args.test.as_path(),
            &reports[0],
            &reports[1],
        ];
        hmdist::files::check_output(png, &inputs)?;
        hmdist::files::check_extension(png, "png")?;
    }
    let reference = exr::read(&args.reference)?;
    let test = exr::read(&args.test)?;
    let (l_diag, scene_scale) = match &args.scene {
        Some(name) => {
            let scene = Scene::load(name)?;
            (scene.diagonal(), scene.display_scale)
        }
        None => from_sidecar(&args.reference)?,
    };
    let c = compare(&reference, &test, l_diag)?;
    println!("f_diff:              {:.6}", c.f_diff.value);
    println!("rmse:                {:.6}", c.rmse);
    println!("mean relative error: {:.6}", c.mean_relative_error);
    println!("p95 relative error:  {:.6}", c.p95_relative_error);
    println!("bias:                {:.6}", c.bias);
    println!("f_diff, creases:     {:.6}", c.f_diff_creases);
    println!("f_diff, the rest:    {:.6}", c.f_diff_rest);
    println!("pixels compared:     {}", c.f_diff.compared);
    println!("pixels excluded:     {}", c.f_diff.excluded);
    println!("l_diag:              {l_diag}");
    match c.differing {
        0 => println!("bit for bit:         identical"),
        n => println!("bit for bit:         {n} of {} pixels differ", test.data.len()),
    }
    if let Some(png) = &args.png {
        let scale = args.scale.unwrap_or(scene_scale);
        picture::write_png(&difference_picture(&reference, &test, scale), png)?;
        println!("difference picture:  {}", png.display());
    }
    Ok(if args.exact && c.differing > 0 {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// `l_diag` and the display scale from the JSON that `hmdist render` wrote beside `exr`.
fn from_sidecar(exr: &Path) -> Result<(f32, f32)> {
    let json = exr.with_extension("json");
    let text = hmdist::files::read_text(&json).map_err(|e| match e {
        Error::File {
            path,
            line,
            message,
            source,
        } => Error::File {
            path,
            line,
            message: format!("{message} (the sidecar that gives l_diag): pass --scene"),
            source,
        },
        other => other,
    })?;
    /// The two keys of the report that `diff` reads.
    #[derive(serde::Deserialize)]
    struct Sidecar {
        l_diag: Option<f32>,
        display_scale: Option<f32>,
    }
    let sidecar: Sidecar =
        serde_json::from_str(&text).map_err(|e| Error::file(&json, format!("not a report: {e}")))?;
    let l_diag = sidecar
        .l_diag
        .ok_or_else(|| Error::file(&json, "has no 'l_diag': pass --scene"))?;
    Ok((l_diag, sidecar.display_scale.unwrap_or(2.0 / l_diag)))
}
