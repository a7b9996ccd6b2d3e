//! `hmdist points`: H at the points of a file (spec §8), for callers that choose their own
//! points. Reads rows `x y z nx ny nz` from `.npy` (float32 or float64, shape [n, 6]) or CSV,
//! writes H per row as `.npy` (float32 [n]) or CSV, by extension. Row i is keyed by i, as
//! pixel i is in an image.

use std::path::PathBuf;

use clap::Args;
use glam::Vec3;

use hmdist::accel::{Accel, BuildQuality, Kernel};
use hmdist::error::{Error, Result};
use hmdist::estimators::gather::DEFAULT_RAYS;
use hmdist::estimators::{Backend, Gather};
use hmdist::image::OutputSet;
use hmdist::points::file::{encode_values, read_rows, PointFormat};
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};
use hmdist::render::DEFAULT_SEED;
use hmdist::sampling::{Sampler, Weighting};
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
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml,
    /// .pbrt, .pbrt.gz, Mitsuba 3 .xml).
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
    /// How the directions fill the hemisphere: a progressive Owen-scrambled Sobol sequence,
    /// or one jittered grid of the N rays (docs/spec.md §3.1), as `render`'s gather.
    #[arg(long, value_enum, default_value_t = Sampler::Sobol)]
    sampler: Sampler,
    /// Where the rays are cast: auto takes a hardware GPU where there is one.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    backend: Backend,
    /// Clamp distances at D; escaping rays then count as D [default: no clamp].
    #[arg(long, value_name = "D")]
    max_distance: Option<f32>,
    /// No progress messages and no summary line.
    /// Refused: the denoising filter averages an image's neighbouring pixels, and a list of
    /// points has no neighbours (render an image with `render --denoise`).
    #[arg(long, hide = true)]
    denoise: bool,
    #[arg(long)]
    quiet: bool,
}

pub fn run(args: PointsArgs) -> Result<()> {
    if args.denoise {
        let message = "cannot filter H at points: the filter averages an image's neighbouring pixels on one \
                       surface, and a list of points has no neighbours (render an image with `render --denoise`)";
        return Err(hmdist::error::Error::invalid("denoise", message));
    }
    let query = PointQuery::new(
        Gather::new(args.rays, args.weighting)?
            .with_backend(args.backend)
            .with_sampler(args.sampler)?,
        args.seed,
        args.max_distance,
    )?;
    PointFormat::of(&args.input)?;
    let mut inputs = Scene::files_read(&args.scene);
    inputs.push(args.input.clone());
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let outputs = OutputSet::reserve(&[&args.output], &inputs)?;
    // After the reservation: an output that is an input is the first thing to say.
    PointFormat::of(&args.output)?;
    let bar = Bar::new(args.quiet);
    bar.status("reading");
    let rows = read_rows(&args.input)?;
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
    let scene = super::scene::load(&args.scene, &bar)?;
    scene.validate()?;
    bar.status("BVH");
    let rays = points.len() as u64 * args.rays as u64;
    let (accel, _) = Accel::for_work(&scene.mesh, BuildQuality::Auto, rays, Kernel::from_env()?)?;
    bar.status("gather");
    let start = std::time::Instant::now();
    let hmd = hmd_at(&scene, &accel, &query, &points, None)?;
    let seconds = start.elapsed().as_secs_f64();
    bar.status("");
    let bytes = encode_values(&args.output, &hmd)?;
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
