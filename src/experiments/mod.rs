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
//! Experiments: `table1` (with its grids `fig12`, `fig13` and a plot), `table2`, `fig9`,
//! `table3` (with `fig14`, `fig15`), `fig10`, `table4`, `fig16_17`, `memory`.

mod analysis;
mod grid;
pub mod plot;
mod report;
pub mod table;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::estimators::Estimator;
use crate::image::{exr, write_atomically, HmdImage};
use crate::progress::{Progress, Silent};
use crate::render::{render, RenderOptions};
use crate::report::RenderReport;
use crate::scene::{stable_hash, Scene};
pub use table::Table;

/// Experiments by name, in the order `all` runs them.
pub const EXPERIMENTS: [&str; 8] = [
    "table1", "table2", "fig9", "table3", "fig10", "table4", "fig16_17", "memory",
];

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
    pub size: u32,
    pub reference_rays: u32,
    pub rays: Vec<u32>,
    pub photons: Vec<usize>,
    /// Photons gathered per pixel (K) for Table 3 and Fig. 16/17.
    pub gathers: Vec<usize>,
    /// Photon counts of Fig. 16/17.
    pub fig16_photons: Vec<usize>,
    /// Photons and K of Fig. 10.
    pub fig10: (usize, usize),
    pub cube_res: u32,
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Quick => "quick",
            Preset::Paper => "paper",
        }
    }

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
                fig10: (1_060_000, 4096),
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
                fig10: (8_530_000, 65_536),
                cube_res: 64,
            },
        }
    }
}

/// What one experiment produced, for the report.
pub struct Section {
    pub name: String,
    pub tables: Vec<Table>,
    pub files: Vec<PathBuf>,
    /// Sentences on the paper's findings: reproduced or not, in numbers.
    pub notes: Vec<String>,
}

/// Runs experiments on one scene into one folder.
pub struct Runner<'a> {
    pub scene: Scene,
    /// Identifies the scene in cache keys: hmdist's version, the scene's name and the
    /// fingerprint of its content.
    scene_key: String,
    pub preset: Preset,
    pub params: PresetParams,
    pub out: PathBuf,
    progress: &'a dyn Progress,
    pub sections: Vec<Section>,
}

impl<'a> Runner<'a> {
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
        })
    }

    /// Runs experiment `name` (or every one for `all`), then rewrites the report.
    pub fn run(&mut self, name: &str) -> Result<()> {
        let names: Vec<&str> = if name == "all" {
            EXPERIMENTS.to_vec()
        } else {
            vec![name]
        };
        for name in names {
            // Images each experiment may render (cached ones take no time).
            let images = match name {
                "table1" | "table2" => 1 + 2 * self.params.rays.len() as u64,
                "fig9" => 3,
                "table3" => 1 + 2 * (self.params.photons.len() * self.params.gathers.len()) as u64,
                "fig10" => 3,
                "fig16_17" => 1 + 4 * (self.params.fig16_photons.len() * self.params.gathers.len()) as u64,
                _ => 0,
            };
            self.progress.start(name, images);
            let section = match name {
                "table1" => analysis::table1(self)?,
                "table2" => analysis::table2(self)?,
                "fig9" => analysis::fig9(self)?,
                "table3" => analysis::table3(self)?,
                "fig10" => analysis::fig10(self)?,
                "fig16_17" => analysis::fig16_17(self)?,
                "table4" => analysis::table4(self)?,
                "memory" => analysis::memory(self)?,
                _ => {
                    return Err(Error::parameter(format!(
                        "unknown experiment '{name}': expected all or one of {}",
                        EXPERIMENTS.join(", ")
                    )))
                }
            };
            self.progress.finish();
            self.sections.push(section);
        }
        report::write(self)
    }

    /// The image `estimator` renders at the preset's size with `seed`, from the cache when
    /// an earlier run made it.
    pub fn image(&self, estimator: &dyn Estimator, seed: u64) -> Result<(HmdImage, RenderReport)> {
        let size = self.params.size;
        let parameters = serde_json::to_string(&estimator.parameters()).expect("parameters serialise");
        let key = format!(
            "{}|{}|{parameters}|{size}x{size}|{seed}",
            self.scene_key,
            estimator.method(),
        );
        let stem = format!("{}-{:016x}", estimator.method(), stable_hash(key.as_bytes()));
        let (exr_path, json_path) = (
            self.out.join("cache").join(format!("{stem}.exr")),
            self.out.join("cache").join(format!("{stem}.json")),
        );
        if let (Ok(image), Ok(text)) = (exr::read(&exr_path), std::fs::read_to_string(&json_path)) {
            if let Ok(report) = serde_json::from_str::<RenderReport>(&text) {
                // The version is in the key; a report that says otherwise was not ours.
                if report.hmdist_version == env!("CARGO_PKG_VERSION") {
                    return Ok((image, report));
                }
            }
        }
        let options = RenderOptions {
            width: size,
            height: size,
            seed,
            ..RenderOptions::default()
        };
        let rendered = render(&self.scene, estimator, &options, &Silent)?;
        exr::write(&rendered.image, &exr_path)?;
        // The JSON last: an image counts as cached only once both files are in place.
        write_atomically(&json_path, rendered.report.to_json().as_bytes())?;
        self.progress.advance(1);
        Ok((rendered.image, rendered.report))
    }
}
