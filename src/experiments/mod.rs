//! The paper's analysis, reproduced on any scene (SPEC §4, §6): experiments that render with
//! several estimators and parameters, compare against a final-gathering reference, and write
//! CSV and Markdown tables and an HTML report.
//!
//! Every image an experiment needs is cached under `OUT/cache`, keyed by everything that
//! determines it (hmdist's version, the scene's content, method, parameters, size, seed), and
//! reused across experiments and reruns: an interrupted run resumes where it stopped. The
//! scene's content is its [`Scene::fingerprint`], so editing any file it was loaded from (a
//! TOML scene's meshes included) renders again.
//!
//! The experiments are listed once, in [`EXPERIMENTS`]: the ray studies (`rays.rs`: Tables
//! 1–2, Fig. 9), the photon studies (`photons.rs`: Tables 3–4, Fig. 10, 16/17, memory) and
//! the adaptive study (`adaptive.rs`: rays saved at equal f_diff).
//! The paper's published numbers are in [`paper`].

mod adaptive;
mod grid;
pub mod paper;
mod photons;
pub mod plot;
mod rays;
mod report;
pub mod table;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::estimators::{registry, Backend, Estimator, MethodConfig};
use crate::image::{exr, write_atomically, HmdImage};
use crate::progress::{Progress, Silent};
use crate::render::{render, RenderOptions};
use crate::report::RenderReport;
use crate::scene::{stable_hash, Scene};
use crate::shard::Shard;
use std::cell::Cell;
pub use table::Table;

/// One experiment: its name, what it shows, how many images it may render, and the code.
pub struct Experiment {
    /// The name `hmdist experiment` takes.
    pub name: &'static str,
    /// What it reproduces.
    pub summary: &'static str,
    /// At most how many images it renders at a preset (cached ones take no time): the
    /// progress bar's length.
    pub images: fn(&PresetParams) -> u64,
    /// Runs it.
    pub run: fn(&Runner) -> Result<Section>,
}

/// Every experiment, in the order `all` runs them.
pub const EXPERIMENTS: &[Experiment] = &[
    Experiment {
        name: "table1",
        summary: "f_diff against rays, gather and cube map (with fig12, fig13 and a plot)",
        images: |p| 1 + 2 * p.rays.len() as u64,
        run: rays::table1,
    },
    Experiment {
        name: "table2",
        summary: "seconds against rays, gather and cube map",
        images: |p| 1 + 2 * p.rays.len() as u64,
        run: rays::table2,
    },
    Experiment {
        name: "fig9",
        summary: "gather against the cube map at R = 64 and 128",
        images: |_| 3,
        run: rays::fig9,
    },
    Experiment {
        name: "table3",
        summary: "photon gather seconds and f_diff by photons and K, methods I and II (with fig14, fig15)",
        images: |p| 1 + 2 * (p.photons.len() * p.gathers.len()) as u64,
        run: photons::table3,
    },
    Experiment {
        name: "fig10",
        summary: "methods I and II with very many photons and a very large K",
        images: |_| 3,
        run: photons::fig10,
    },
    Experiment {
        name: "table4",
        summary: "photon map build seconds by photons, light and camera sources",
        images: |_| 0,
        run: photons::table4,
    },
    Experiment {
        name: "fig16_17",
        summary: "method II by source, bounces, K and photons",
        images: |p| 1 + 4 * (p.fig16_photons.len() * p.gathers.len()) as u64,
        run: photons::fig16_17,
    },
    Experiment {
        name: "adaptive",
        summary: "f_diff against rays cast, fixed N against adaptive gathering (the rays saved)",
        images: |p| 1 + p.rays.len() as u64 + adaptive::TOLERANCES.len() as u64,
        run: adaptive::adaptive,
    },
    Experiment {
        name: "memory",
        summary: "bytes per photon against the paper's",
        images: |_| 0,
        run: photons::memory,
    },
];

/// The experiments `name` stands for: every one for `all`.
pub fn select(name: &str) -> Result<Vec<&'static Experiment>> {
    if name == "all" {
        return Ok(EXPERIMENTS.iter().collect());
    }
    match EXPERIMENTS.iter().find(|e| e.name == name) {
        Some(e) => Ok(vec![e]),
        None => {
            let names: Vec<&str> = EXPERIMENTS.iter().map(|e| e.name).collect();
            let message = format!("'{name}' is not all or one of {}", names.join(", "));
            Err(Error::invalid("experiment", message))
        }
    }
}

/// Seed of the reference images: independent of the seed of the images compared with them.
pub const REFERENCE_SEED: u64 = 1_000_003;

/// How much work an experiment does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Preset {
    /// Small images, a 16,384-ray reference, fewer points: minutes on 2 cores. What CI runs.
    Quick,
    /// The paper's scale: 1024², a 65,536-ray reference. Hours on a CPU.
    Paper,
}

/// The sizes and counts a preset stands for.
#[derive(Clone, Debug)]
pub struct PresetParams {
    /// Image side in pixels (square images).
    pub size: u32,
    /// Gather rays of the reference image.
    pub reference_rays: u32,
    /// Gather ray counts of Tables 1 and 2.
    pub rays: Vec<u32>,
    /// Photon counts of Tables 3 and 4.
    pub photons: Vec<usize>,
    /// Photons gathered per pixel (K) for Table 3 and Fig. 16/17.
    pub gathers: Vec<usize>,
    /// Photon counts of Fig. 16/17.
    pub fig16_photons: Vec<usize>,
    /// Photons of Fig. 10.
    pub fig10_photons: usize,
    /// Photons gathered per pixel (K) of Fig. 10.
    pub fig10_gather: usize,
    /// Per-quadrant hemicube resolution R of Tables 1 and 2.
    pub cube_res: u32,
}

impl Preset {
    /// The name `--preset` takes.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Quick => "quick",
            Preset::Paper => "paper",
        }
    }

    /// The sizes and counts it stands for.
    pub fn params(self) -> PresetParams {
        let doubling = |from: u32, to: u32| (0..).map(move |k| from << k).take_while(move |&n| n <= to);
        match self {
            Preset::Quick => PresetParams {
                size: 48,
                reference_rays: 16_384,
                rays: doubling(32, 2048).collect(),
                photons: vec![130_000, 260_000, 530_000, 1_060_000],
                gathers: vec![64, 256, 1024],
                fig16_photons: vec![260_000, 1_060_000],
                fig10_photons: 1_060_000,
                fig10_gather: 4096,
                cube_res: 64,
            },
            Preset::Paper => PresetParams {
                size: 1024,
                reference_rays: 65_536,
                rays: doubling(32, 16_384).collect(),
                photons: vec![
                    130_000, 260_000, 530_000, 1_060_000, 2_130_000, 4_260_000, 8_530_000,
                ],
                gathers: vec![64, 128, 256, 512, 1024],
                fig16_photons: vec![1_060_000, 8_530_000],
                fig10_photons: 8_530_000,
                fig10_gather: 65_536,
                cube_res: 64,
            },
        }
    }
}

/// What one experiment produced, for the report.
pub struct Section {
    /// The experiment's name.
    pub name: String,
    /// Its tables, ours and the paper's.
    pub tables: Vec<Table>,
    /// The files it wrote (tables, plots, picture grids).
    pub files: Vec<PathBuf>,
    /// Sentences on the paper's findings: reproduced or not, in numbers.
    pub notes: Vec<String>,
}

/// Runs experiments on one scene into one folder.
pub struct Runner<'a> {
    /// The scene.
    pub scene: Scene,
    /// Identifies the scene in cache keys: hmdist's version, the scene's name and the
    /// fingerprint of its content.
    scene_key: String,
    /// How much work.
    pub preset: Preset,
    /// The preset's sizes and counts.
    pub params: PresetParams,
    /// The output folder.
    pub out: PathBuf,
    progress: &'a dyn Progress,
    /// What the experiments run so far produced, for the report.
    pub sections: Vec<Section>,
    /// Where rendered images are cached: `OUT/cache`.
    cache: PathBuf,
    /// Set for `experiment --shard K/M`: which images this run renders.
    shard: Option<ShardRun>,
    /// Where gather and the cube map run (every image's configuration gets it).
    backend: Backend,
}

/// A shard's share of an experiment's images: request `i` (in the order the experiment asks,
/// the same on every shard) is rendered by shard `i mod M`; the others' images, where not
/// cached, are stand-ins, and the shard writes nothing but its images into the cache. A run
/// without `--shard` then finds every image cached and writes the tables and the report.
struct ShardRun {
    shard: Shard,
    requests: Cell<u64>,
    rendered: Cell<u64>,
    stand_ins: Cell<u64>,
    render_failed: Cell<bool>,
}

impl<'a> Runner<'a> {
    /// A runner for the scene `scene_arg` names (built-in or file), writing into `out`.
    pub fn new(scene_arg: &str, preset: Preset, out: &Path, progress: &'a dyn Progress) -> Result<Self> {
        let scene = Scene::load(scene_arg)?;
        let scene_key = format!(
            "{}|{}|{:016x}",
            env!("CARGO_PKG_VERSION"),
            scene.name,
            scene.fingerprint()
        );
        std::fs::create_dir_all(out.join("cache"))
            .map_err(|e| Error::io(out, "create the output folder of", e))?;
        Ok(Runner {
            scene,
            scene_key,
            preset,
            params: preset.params(),
            out: out.to_path_buf(),
            progress,
            sections: vec![],
            cache: out.join("cache"),
            shard: None,
            backend: Backend::Auto,
        })
    }

    /// This runner with gather and the cube map on `backend` (default: auto). The backend is
    /// part of the image cache's key: shards and the run that assembles them must agree.
    pub fn with_backend(self, backend: Backend) -> Self {
        Runner { backend, ..self }
    }

    /// This runner as shard `shard` of a run spread over machines (see `ShardRun`): its tables
    /// and pictures go to a scratch folder, removed at the end.
    pub fn with_shard(mut self, shard: Shard) -> Result<Self> {
        let scratch = self
            .out
            .join(format!(".shard-{}-of-{}", shard.index, shard.count));
        std::fs::create_dir_all(&scratch).map_err(|e| Error::io(&scratch, "create the folder", e))?;
        self.out = scratch;
        self.shard = Some(ShardRun {
            shard,
            requests: Cell::new(0),
            rendered: Cell::new(0),
            stand_ins: Cell::new(0),
            render_failed: Cell::new(false),
        });
        Ok(self)
    }

    /// For a shard: how many images it rendered, and how many it left to other shards.
    pub fn shard_counts(&self) -> Option<(u64, u64)> {
        self.shard.as_ref().map(|s| (s.rendered.get(), s.stand_ins.get()))
    }

    /// Runs experiment `name` (or every one for `all`), then rewrites the report; a shard
    /// only renders its share of the images.
    pub fn run(&mut self, name: &str) -> Result<()> {
        for experiment in select(name)? {
            self.progress
                .start(experiment.name, (experiment.images)(&self.params));
            let result = (experiment.run)(self);
            self.progress.finish();
            match (result, &self.shard) {
                (Ok(section), None) => self.sections.push(section),
                (Ok(_), Some(_)) => {}
                // The analysis of stand-in images can fail (nothing to plot); rendering
                // cannot, unnoticed.
                (Err(_), Some(s)) if !s.render_failed.get() && s.stand_ins.get() > 0 => {}
                (Err(e), _) => return Err(e),
            }
        }
        match &self.shard {
            Some(_) => std::fs::remove_dir_all(&self.out).map_err(|e| Error::io(&self.out, "remove", e)),
            None => report::write(self),
        }
    }

    /// The image method `method` (a registry name) renders with `config` and `seed`: see
    /// [`Runner::image`].
    pub fn method_image(
        &self,
        method: &str,
        config: &MethodConfig,
        seed: u64,
    ) -> Result<(HmdImage, RenderReport)> {
        let config = MethodConfig {
            backend: self.backend,
            ..config.clone()
        };
        self.image(registry::build(method, &config)?.as_ref(), seed)
    }

    /// The image `estimator` renders at the preset's size with `seed`, from the cache when
    /// an earlier run made it.
    pub fn image(&self, estimator: &dyn Estimator, seed: u64) -> Result<(HmdImage, RenderReport)> {
        crate::interrupt::check()?;
        let size = self.params.size;
        let parameters = serde_json::to_string(&estimator.parameters()).expect("parameters serialise");
        let key = format!(
            "{}|{}|{parameters}|{size}x{size}|{seed}|{:?}",
            self.scene_key,
            estimator.method(),
            self.backend,
        );
        let stem = format!("{}-{:016x}", estimator.method(), stable_hash(key.as_bytes()));
        let (exr_path, json_path) = (
            self.cache.join(format!("{stem}.exr")),
            self.cache.join(format!("{stem}.json")),
        );
        let request = self.shard.as_ref().map(|s| {
            let i = s.requests.get();
            s.requests.set(i + 1);
            (s, i % s.shard.count as u64 == s.shard.index as u64)
        });
        if let (Ok(image), Ok(text)) = (exr::read(&exr_path), std::fs::read_to_string(&json_path)) {
            if let Ok(report) = serde_json::from_str::<RenderReport>(&text) {
                // The version is in the key; a report that says otherwise was not ours.
                if report.hmdist_version == env!("CARGO_PKG_VERSION") {
                    return Ok((image, report));
                }
            }
        }
        if let Some((s, false)) = request {
            // Another shard's image: a stand-in of the right size.
            s.stand_ins.set(s.stand_ins.get() + 1);
            let pixels = (size * size) as usize;
            let report = RenderReport {
                width: size,
                height: size,
                ..RenderReport::default()
            };
            return Ok((HmdImage::new(size, size, vec![1.0; pixels]), report));
        }
        let options = RenderOptions {
            width: size,
            height: size,
            seed,
            ..RenderOptions::default()
        };
        let rendered = render(&self.scene, estimator, &options, &Silent).inspect_err(|_| {
            if let Some((s, _)) = request {
                s.render_failed.set(true);
            }
        })?;
        if let Some((s, _)) = request {
            s.rendered.set(s.rendered.get() + 1);
        }
        exr::write(&rendered.image, &exr_path)?;
        // The JSON last: an image counts as cached only once both files are in place.
        write_atomically(&json_path, rendered.report.to_json().as_bytes())?;
        self.progress.advance(1);
        Ok((rendered.image, rendered.report))
    }
}
