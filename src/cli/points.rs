//! `hmdist points`: H at the points of a file (SPEC §8), for callers that choose their own
//! points. Reads rows `x y z nx ny nz` from `.npy` (float32 or float64, shape [n, 6]) or CSV,
//! writes H per row as `.npy` (float32 [n]) or CSV, by extension. Row i is keyed by i, as
//! pixel i is in an image.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::Vec3;

use hmdist::accel::{Accel, BuildQuality, Kernel};
use hmdist::error::{Error, Result};
use hmdist::estimators::gather::DEFAULT_RAYS;
use hmdist::estimators::{Backend, Gather};
use hmdist::image::OutputSet;
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};
use hmdist::render::DEFAULT_SEED;
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

use super::bar::Bar;

#[derive(Args)]
pub struct PointsArgs {
    /// Points: .npy (float32 or float64, shape [n, 6]) or .csv, rows x y z nx ny nz. The normal
    /// is used as given: it says which side of the surface the point is seen from.
    input: PathBuf,
    /// H per row: .npy (float32, shape [n]) or .csv (one value per line); +inf where every
    /// ray escaped.
    output: PathBuf,
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml).
    #[arg(long, default_value = "cube")]
    scene: String,
    /// Gather rays per point N.
    #[arg(long, default_value_t = DEFAULT_RAYS)]
    rays: u32,
    /// Seed of the random numbers; row i is keyed by i, as pixel i is in an image.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    seed: u64,
    /// Direction weighting over the hemisphere.
    #[arg(long, value_enum, default_value_t = Weighting::Cosine)]
    weighting: Weighting,
    /// Where the rays are cast: auto takes a hardware GPU where there is one.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    backend: Backend,
    /// Clamp distances at D; escaping rays then count as D [default: no clamp].
    #[arg(long, value_name = "D")]
    max_distance: Option<f32>,
    /// No progress messages and no summary line.
    #[arg(long)]
    quiet: bool,
}

/// The file formats, by extension.
#[derive(Clone, Copy, PartialEq)]
enum Format {
    Npy,
    Csv,
}

fn format_of(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
    {
        Some(e) if e == "npy" => Ok(Format::Npy),
        Some(e) if e == "csv" => Ok(Format::Csv),
        _ => Err(Error::file(path, "is neither .npy nor .csv")),
    }
}

pub fn run(args: PointsArgs) -> Result<()> {
    let query = PointQuery::new(
        Gather::new(args.rays, args.weighting)?.with_backend(args.backend),
        args.seed,
        args.max_distance,
    )?;
    let (input_format, output_format) = (format_of(&args.input)?, format_of(&args.output)?);
    let outputs = OutputSet::reserve(&[&args.output])?;
    let bar = Bar::new(args.quiet);
    bar.status("reading");
    let rows = match input_format {
        Format::Npy => read_npy(&args.input)?,
        Format::Csv => read_csv(&args.input)?,
    };
    let points = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let p = SurfacePoint::new(Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
            p.map_err(|e| match e {
                Error::Parameter { message, .. } => {
                    Error::file(&args.input, format!("row {i}: the point {message}"))
                }
                other => other,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    bar.status("loading");
    let scene = Scene::load(&args.scene)?;
    scene.validate()?;
    bar.status("BVH");
    let rays = points.len() as u64 * args.rays as u64;
    let quality = BuildQuality::Auto.resolve(rays, scene.mesh.triangle_count());
    let accel = Accel::build(&scene.mesh, quality).with_kernel(Kernel::from_env()?);
    bar.status("gather");
    let start = std::time::Instant::now();
    let hmd = hmd_at(&scene, &accel, &query, &points, None)?;
    let seconds = start.elapsed().as_secs_f64();
    bar.status("");
    let bytes = match output_format {
        Format::Npy => npy_bytes(&hmd),
        Format::Csv => hmd
            .iter()
            .map(|h| format!("{h}\n"))
            .collect::<String>()
            .into_bytes(),
    };
    outputs.commit(&[&bytes])?;
    if !args.quiet {
        println!(
            "{}: {} points x {} rays in {seconds:.2} s ({:.2} Mrays/s) -> {}",
            scene.name,
            points.len(),
            args.rays,
            rays as f64 / seconds.max(1e-9) / 1e6,
            args.output.display()
        );
    }
    Ok(())
}

/// Rows of an `.npy` file of shape [n, 6], float32 or float64, in C or Fortran order.
fn read_npy(path: &Path) -> Result<Vec<[f32; 6]>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
    let npy =
        npyz::NpyFile::new(&bytes[..]).map_err(|e| Error::file(path, format!("is not an .npy file: {e}")))?;
    let shape = npy.shape().to_vec();
    let fortran = npy.order() == npyz::Order::Fortran;
    let dtype = npy.dtype().descr();
    let [n, 6] = shape[..] else {
        return Err(Error::file(path, format!("has shape {shape:?}: expected [n, 6]")));
    };
    let bad = |e: std::io::Error| Error::file(path, format!("cannot read its values: {e}"));
    let values: Vec<f32> = match npy.try_data::<f32>() {
        Ok(data) => data.collect::<std::io::Result<_>>().map_err(bad)?,
        Err(npy) => match npy.try_data::<f64>() {
            Ok(data) => {
                let values: Vec<f64> = data.collect::<std::io::Result<_>>().map_err(bad)?;
                values.into_iter().map(|v| v as f32).collect()
            }
            Err(_) => {
                let message = format!("holds {dtype}: expected float32 or float64");
                return Err(Error::file(path, message));
            }
        },
    };
    rows(path, n as usize, |r, c| {
        values[if fortran { c * n as usize + r } else { r * 6 + c }]
    })
}

/// Rows of a CSV file: six numbers per line, separated by commas (or spaces); a first line
/// that is not numbers (a header), blank lines and `#` comments are skipped.
fn read_csv(path: &Path) -> Result<Vec<[f32; 6]>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, "read", e))?;
    let mut out = vec![];
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split([',', ' ', '\t']).filter(|f| !f.is_empty()).collect();
        let numbers: Vec<f32> = fields.iter().filter_map(|f| f.trim().parse().ok()).collect();
        if numbers.len() != fields.len() && i == 0 {
            continue; // a header
        }
        if numbers.len() != 6 || fields.len() != 6 {
            let message = format!("expected 6 numbers (x y z nx ny nz), found '{line}'");
            return Err(Error::file_line(path, i + 1, message));
        }
        out.push([
            numbers[0], numbers[1], numbers[2], numbers[3], numbers[4], numbers[5],
        ]);
    }
    rows(path, out.len(), |r, c| out[r][c])
}

/// `n` rows from `value(row, column)`; none is refused.
fn rows(path: &Path, n: usize, value: impl Fn(usize, usize) -> f32) -> Result<Vec<[f32; 6]>> {
    if n == 0 {
        return Err(Error::file(path, "holds no points"));
    }
    Ok((0..n).map(|r| std::array::from_fn(|c| value(r, c))).collect())
}

/// H as an `.npy` file: float32, shape [n].
fn npy_bytes(hmd: &[f32]) -> Vec<u8> {
    use npyz::WriterBuilder;
    let mut bytes = vec![];
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[hmd.len() as u64])
        .writer(&mut bytes)
        .begin_nd()
        .expect("writing to memory");
    writer.extend(hmd.iter().copied()).expect("writing to memory");
    writer.finish().expect("writing to memory");
    bytes
}
