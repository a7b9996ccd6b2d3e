//! `hmdist photons build`: the photon map as a stage of its own, traced and indexed once and
//! written to a file that `render --photon-map FILE` gathers over (every shard of a sharded
//! photon render over the same map).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use hmdist::error::{Error, Result};
use hmdist::estimators::photon::{PhotonEstimator, PhotonMethod, PhotonParams};
use hmdist::image::write_atomically;
use hmdist::scene::Scene;

use super::bar::Bar;

#[derive(Subcommand)]
pub enum PhotonsCommand {
    /// Trace and index the photon map a render would build, into a file for --photon-map.
    Build(BuildArgs),
}

#[derive(Args)]
// The photon parameters' --photon-map is what this command writes: hidden here (and refused).
#[command(mut_arg("photon_map", |arg| arg.hide(true)))]
pub struct BuildArgs {
    /// Scene: a built-in (cube, hall, sphere, slab, dome) or a file.
    #[arg(long, default_value = "cube")]
    scene: String,
    /// Photon method the map is for: photon1 stores distances, photon2 next-hit points.
    #[arg(long, default_value = "photon2", value_parser = PhotonMethod::ALL.map(PhotonMethod::name))]
    method: String,
    #[command(flatten)]
    params: PhotonParams,
    /// The renders' size, seed and BVH preset: camera-sourced photons depend on the size,
    /// and the BVH preset is chosen by it.
    #[command(flatten)]
    image: super::image_args::ImageArgs,
    /// The map file.
    #[arg(long, default_value = "photons.map")]
    out: PathBuf,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
}

pub fn run(command: PhotonsCommand) -> Result<()> {
    let PhotonsCommand::Build(args) = command;
    let method = PhotonMethod::from_name(&args.method).expect("clap allows only the methods' names");
    if args.params.photon_map.is_some() {
        let message = "is what `photons build` writes (--out), not something it reads";
        return Err(Error::invalid("photon_map", message));
    }
    let scene_files = Scene::files_read(&args.scene);
    let inputs: Vec<&std::path::Path> = scene_files.iter().map(|p| p.as_path()).collect();
    hmdist::files::check_output(&args.out, &inputs)?;
    let estimator = PhotonEstimator::new(method, args.params.clone())?;
    let mut options = args.image.options()?;
    let bar = Bar::new(args.quiet);
    bar.status("loading");
    let scene = super::scene::load(&args.scene, &bar)?;
    (options.width, options.height) = args.image.size_for(&scene);
    let start = std::time::Instant::now();
    let bytes = estimator.build_map_file(&scene, &options, &bar)?;
    write_atomically(&args.out, &bytes)?;
    if !args.quiet {
        println!(
            "{}: {} map of {} photons in {:.2} s, {:.1} MB -> {}",
            scene.name,
            method.name(),
            args.params.photons,
            start.elapsed().as_secs_f64(),
            bytes.len() as f64 / 1e6,
            args.out.display()
        );
    }
    Ok(())
}
