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
//! the adaptive study (`adaptive.rs`: rays saved at equal f_diff), and accuracy against cost
//! over them all (`cost.rs`).
//! The paper's published numbers are in [`paper`].

mod adaptive;
mod cost;
mod grid;
pub mod paper;
mod photons;
pub mod plan;
pub mod plot;
mod rays;
mod report;
pub mod table;

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::accel::Kernel;
use crate::error::{Error, Result};
use crate::estimators::cubemap::GpuFill;
use crate::estimators::{registry, Aov, AovImage, Backend, CubemapParams, Estimator};
use crate::image::{exr, write_atomically, HmdImage};
use crate::progress::{Progress, Silent};
use crate::render::{render, RenderOptions};
use crate::report::{RenderKey, RenderReport};
use crate::scene::{stable_hash, Scene};
use crate::shard::Shard;
pub use plan::Plan;
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
        name: "fig11",
        summary: "the cube map at the reference's ray count beside the reference (scene B's figure)",
        images: |_| 2,
        run: rays::fig11,
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
    Experiment {
        name: "cost",
        summary: "f_diff against seconds of every image of Tables 1–3, with the Pareto front (renders nothing: run after them)",
        images: |_| 0,
        run: cost::cost,
    },
];

/// The experiments `names` stands for: every one for `all`, or a comma-separated list of
/// names (`table3,fig10`), run in [`EXPERIMENTS`]' order, each once.
pub fn select(names: &str) -> Result<Vec<&'static Experiment>> {
    let asked: Vec<&str> = names.split(',').map(str::trim).collect();
    if asked.contains(&"all") {
        return Ok(EXPERIMENTS.iter().collect());
    }
    if let Some(unknown) = asked.iter().find(|&&a| !EXPERIMENTS.iter().any(|e| e.name == a)) {
        let known: Vec<&str> = EXPERIMENTS.iter().map(|e| e.name).collect();
        let message = format!(
            "'{unknown}' is not all or one of {} (or several, comma-separated)",
            known.join(", ")
        );
        return Err(Error::invalid("experiment", message));
    }
    Ok(EXPERIMENTS.iter().filter(|e| asked.contains(&e.name)).collect())
}

/// Images that cast at least this many rays (2³³, about 20 minutes at 7 M rays/s) are
/// rendered in [`PARTS`] row shards, each cached when done, so that a run stopped by the end
/// of a working session keeps most of the work (at paper scale: the 65,536-ray reference,
/// 6.9·10¹⁰ rays, and Fig. 9's cube maps).
pub const PART_RAYS: u64 = 1 << 33;
/// Parts of such an image.
pub const PARTS: u32 = 16;

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
#[derive(Default)]
pub struct Section {
    /// The experiment's name.
    pub name: String,
    /// Its tables, ours and the paper's.
    pub tables: Vec<Table>,
    /// The files it wrote (tables, plots, picture grids).
    pub files: Vec<PathBuf>,
    /// What the reader needs besides the tables: where the numbers come from, what the
    /// pictures show.
    pub notes: Vec<String>,
    /// The paper's findings this experiment tests, one sentence each: the finding, the
    /// verdict, and the number that decides it. The report lists every section's at its top.
    pub findings: Vec<String>,
}

/// Runs experiments on one scene into one folder.
pub struct Runner<'a> {
    /// The scene.
    pub scene: Scene,
    /// Identifies the scene in the cache's older keys ([`Runner::legacy_stem`]): hmdist's
    /// version, the scene's name and the fingerprint of its content.
    scene_key: String,
    /// The fingerprint of the scene's content ([`Scene::fingerprint`]), for the cache keys.
    scene_content: u64,
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
    /// How the cube map fills its texels on the GPU (every cube map's configuration gets it).
    gpu_fill: GpuFill,
    /// The ray-casting kernel of every render (never changes an image).
    kernel: Kernel,
    /// Set for `experiment --plan`: calibrate instead of render.
    plan: Option<PlanRun>,
    /// The plan a `--plan` run made.
    pub planned: Option<Plan>,
    /// Wall seconds of each experiment this run ran, in order.
    pub timings: Vec<(String, f64)>,
    /// Each image this run asked for, at its first asking: `Some(the seconds its report
    /// gives)` where the cache already held it, `None` where this run rendered it (or, where
    /// it merged parts of it that an earlier run left, `Some(those parts' seconds)`). What an
    /// earlier run rendered after the plan (one stopped at a session's end, then resumed)
    /// counts in the plan against the run ([`plan::comparison`]).
    first_looks: RefCell<std::collections::HashMap<String, Option<f64>>>,
    /// Per image rendered in parts, the seconds (by their reports) of the parts that this run
    /// found cached: an earlier run's work, which this run's clock did not see.
    earlier_parts: RefCell<std::collections::HashMap<String, f64>>,
    /// Images of at least this many rays are rendered in parts ([`PART_RAYS`]).
    part_rays: u64,
    /// The experiments this run runs.
    running: Vec<&'static str>,
    /// Whether the ray studies (Tables 1–2) render the cube map beside final gathering.
    cubemaps: bool,
}

/// A plan in the making ([`plan`]): every image the experiments ask for is looked up in the
/// cache and, where it is not there, calibrated; the experiments' tables and pictures go to a
/// scratch folder, removed at the end, and the plan to `out`.
struct PlanRun {
    out: PathBuf,
    experiment: Cell<&'static str>,
    items: RefCell<Vec<plan::PlanItem>>,
    calibration_seconds: Cell<f64>,
    calibration_failed: Cell<bool>,
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
        let scene_content = scene.fingerprint();
        let scene_key = format!("{}|{}|{scene_content:016x}", env!("CARGO_PKG_VERSION"), scene.name);
        Ok(Runner {
            scene,
            scene_key,
            scene_content,
            preset,
            params: preset.params(),
            out: out.to_path_buf(),
            progress,
            sections: vec![],
            cache: out.join("cache"),
            shard: None,
            backend: Backend::Auto,
            gpu_fill: GpuFill::Raster,
            kernel: Kernel::best(),
            plan: None,
            planned: None,
            timings: vec![],
            first_looks: RefCell::default(),
            earlier_parts: RefCell::default(),
            part_rays: PART_RAYS,
            running: vec![],
            cubemaps: true,
        })
    }

    /// Creates the output folder and its cache, which the runner leaves alone until it has
    /// something to write (a run refused for a bad flag creates nothing).
    fn make_cache(&self) -> Result<()> {
        std::fs::create_dir_all(&self.cache)
            .map_err(|e| Error::io(&self.out, "create the output folder of", e))
    }

    /// Images `size` pixels square instead of the preset's (none: the preset's); at least 1.
    pub fn with_size(mut self, size: Option<u32>) -> Result<Self> {
        if let Some(size) = size {
            if size == 0 {
                return Err(Error::invalid("size", "must be at least 1 pixel, not 0"));
            }
            self.params.size = size;
        }
        Ok(self)
    }

    /// This runner making a plan ([`plan`]) instead of running: `run` calibrates every image
    /// that is not cached, renders nothing whole and writes `plan.json`, `plan.md` and
    /// `plan.csv` into the output folder, and nothing else.
    pub fn with_plan(mut self) -> Result<Self> {
        let scratch = self.out.join(".plan");
        std::fs::create_dir_all(&scratch).map_err(|e| Error::io(&scratch, "create the folder", e))?;
        let out = std::mem::replace(&mut self.out, scratch);
        self.plan = Some(PlanRun {
            out,
            experiment: Cell::new(""),
            items: RefCell::new(vec![]),
            calibration_seconds: Cell::new(0.0),
            calibration_failed: Cell::new(false),
        });
        Ok(self)
    }

    /// Whether this run runs experiment `name` (an image it needs may then be made together
    /// with another experiment's).
    pub fn runs(&self, name: &str) -> bool {
        self.running.contains(&name)
    }

    /// Whether this run only makes a plan.
    pub fn planning(&self) -> bool {
        self.plan.is_some()
    }

    /// For a plan: work of the current experiment that is not an image (`what`, of size
    /// `work`), estimated at `seconds`.
    pub fn plan_work(&self, what: String, work: String, seconds: f64) {
        if let Some(plan) = &self.plan {
            plan.items.borrow_mut().push(plan::PlanItem {
                experiment: plan.experiment.get().into(),
                what,
                work,
                seconds,
                ..plan::PlanItem::default()
            });
        }
    }

    /// This runner with gather and the cube map on `backend` (default: auto). The backend is
    /// part of the image cache's key: shards and the run that assembles them must agree.
    pub fn with_backend(self, backend: Backend) -> Self {
        Runner { backend, ..self }
    }

    /// This runner with Tables 1–2 rendering the cube map beside final gathering (`true`,
    /// the default) or final gathering alone (`false`: the paper's scene-B row of Table 1 has
    /// no cube-map column). Changes no image's cache key: it only decides which images are
    /// asked for.
    pub fn with_cubemaps(self, cubemaps: bool) -> Self {
        Runner { cubemaps, ..self }
    }

    /// Whether Tables 1–2 render the cube map beside final gathering.
    pub fn cubemaps(&self) -> bool {
        self.cubemaps
    }

    /// This runner with the GPU's cube maps filled by `fill` (default: raster, the paper's
    /// method; rays where the GPU rasterises slowly). Part of a cube map's cache key where it
    /// is `rays`.
    pub fn with_gpu_fill(self, gpu_fill: GpuFill) -> Self {
        Runner { gpu_fill, ..self }
    }

    /// The options of an image of this run: the preset's size, `seed`, `aovs` and the
    /// runner's kernel, the whole image.
    fn render_options(&self, seed: u64, aovs: &[Aov]) -> RenderOptions {
        RenderOptions {
            width: self.params.size,
            height: self.params.size,
            seed,
            aovs: aovs.to_vec(),
            kernel: self.kernel,
            ..RenderOptions::default()
        }
    }

    /// This runner casting rays with `kernel` (default [`Kernel::best`]; images do not
    /// depend on it).
    pub fn with_kernel(self, kernel: Kernel) -> Self {
        Runner { kernel, ..self }
    }

    /// This runner rendering images of at least `rays` rays in parts (default [`PART_RAYS`]):
    /// the parts, merged, are the whole image bit for bit, so this changes no output.
    pub fn with_part_rays(self, rays: u64) -> Self {
        Runner {
            part_rays: rays,
            ..self
        }
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
    /// only renders its share of the images, and a plan only calibrates (see [`plan`]).
    pub fn run(&mut self, name: &str) -> Result<()> {
        let experiments = select(name)?;
        self.make_cache()?;
        self.running = experiments.iter().map(|e| e.name).collect();
        for experiment in &experiments {
            if let Some(plan) = &self.plan {
                plan.experiment.set(experiment.name);
            }
            self.progress
                .start(experiment.name, (experiment.images)(&self.params));
            let start = Instant::now();
            let result = (experiment.run)(self);
            self.progress.finish();
            let seconds = start.elapsed().as_secs_f64();
            match (result, &self.shard, &self.plan) {
                (Ok(section), None, None) => {
                    self.sections.push(section);
                    self.timings.push((experiment.name.into(), seconds));
                }
                (Ok(_), _, _) => {}
                // The analysis of stand-in images can fail (nothing to plot); rendering
                // cannot, unnoticed.
                (Err(_), Some(s), _) if !s.render_failed.get() && s.stand_ins.get() > 0 => {}
                (Err(_), _, Some(p)) if !p.calibration_failed.get() && !crate::interrupt::requested() => {}
                (Err(e), _, _) => return Err(e),
            }
        }
        if let Some(plan) = &self.plan {
            let names: Vec<&str> = experiments.iter().map(|e| e.name).collect();
            self.planned = Some(self.write_plan(plan, &names)?);
        }
        match (&self.shard, &self.plan) {
            (Some(_), _) | (_, Some(_)) => {
                std::fs::remove_dir_all(&self.out).map_err(|e| Error::io(&self.out, "remove", e))
            }
            (None, None) => report::write(self),
        }
    }

    /// The plan `plan` gathered, totalled per experiment in `order` and written into its
    /// folder.
    fn write_plan(&self, plan: &PlanRun, order: &[&str]) -> Result<Plan> {
        let mut made = Plan {
            scene: self.scene.name.clone(),
            preset: self.preset.name().into(),
            size: self.params.size,
            backend: format!("{:?}", self.backend).to_lowercase(),
            machine: plan::Machine::this(),
            calibration_seconds: plan.calibration_seconds.get(),
            items: plan.items.borrow().clone(),
            ..Plan::default()
        };
        made.total(order);
        let json = serde_json::to_string_pretty(&made).expect("a plan serialises");
        write_atomically(&plan.out.join("plan.json"), json.as_bytes())?;
        let markdown = format!(
            "{}\n{}",
            made.summary_table().markdown(),
            made.items_table().markdown()
        );
        write_atomically(&plan.out.join("plan.md"), markdown.as_bytes())?;
        write_atomically(&plan.out.join("plan.csv"), made.items_table().csv().as_bytes())?;
        Ok(made)
    }

    /// The plan an earlier `--plan` wrote into this runner's folder for the same scene,
    /// preset and size, if any.
    pub fn earlier_plan(&self) -> Option<Plan> {
        let text = std::fs::read_to_string(self.out.join("plan.json")).ok()?;
        let plan: Plan = serde_json::from_str(&text).ok()?;
        let same = plan.scene == self.scene.name
            && plan.preset == self.preset.name()
            && plan.size == self.params.size;
        same.then_some(plan)
    }

    /// The earlier plan's estimates beside this run's seconds, per experiment: see
    /// [`plan::comparison`].
    pub fn plan_against_run(&self) -> Option<Table> {
        let looks = self.first_looks.borrow();
        plan::comparison(&self.earlier_plan()?, &self.timings, &|stem| {
            looks.get(stem).copied().flatten()
        })
    }

    /// Notes the first asking for image `stem`: see [`Runner::first_looks`]. `None`: this run
    /// rendered it, where some of its parts may have come from an earlier run.
    fn first_look(&self, stem: &str, cached_seconds: Option<f64>) {
        let earlier = cached_seconds.or_else(|| self.earlier_parts.borrow().get(stem).copied());
        self.first_looks
            .borrow_mut()
            .entry(stem.to_string())
            .or_insert(earlier);
    }

    /// The image method `method` (a registry name) renders with `params` (its parameter
    /// struct, or an object naming some of them) and `seed`, on the runner's backend where the
    /// method has one: see [`Runner::image`].
    pub fn method_image(
        &self,
        method: &str,
        params: &impl serde::Serialize,
        seed: u64,
    ) -> Result<(HmdImage, RenderReport)> {
        let (image, report, _) = self.method_image_with(method, params, seed, &[])?;
        Ok((image, report))
    }

    /// [`Runner::method_image`] with `aovs` measured beside H, cached with it, returned in
    /// that order.
    pub fn method_image_with(
        &self,
        method: &str,
        params: &impl serde::Serialize,
        seed: u64,
        aovs: &[Aov],
    ) -> Result<(HmdImage, RenderReport, Vec<HmdImage>)> {
        let estimator = self.method_estimator(method, params, aovs)?;
        self.image_with(estimator.as_ref(), seed, aovs)
    }

    /// The estimator of method `method` (a registry name) with `params` and `aovs`, on the
    /// runner's backend where the method has one.
    fn method_estimator(
        &self,
        method: &str,
        params: &impl serde::Serialize,
        aovs: &[Aov],
    ) -> Result<Box<dyn Estimator>> {
        let entry = registry::method(method)?;
        let mut params = registry::object(params)?;
        if entry.reads("backend") {
            let backend = serde_json::to_value(self.backend).expect("a backend serialises");
            params.insert("backend".into(), backend);
        }
        if entry.reads("gpu_fill") {
            let fill = serde_json::to_value(self.gpu_fill).expect("a fill serialises");
            params.insert("gpu_fill".into(), fill);
        }
        entry.build(&params, aovs)
    }

    /// This runner taking its reference image (gather with the preset's reference ray count
    /// and [`REFERENCE_SEED`]) from the EXR `exr_path` and the report beside it (the same
    /// name ending in `.json`) instead of rendering it: the report must say the image is the
    /// one this run would render (method, parameters, seed, size, scene, hmdist's version);
    /// then both files go into the cache as that image. The backend that rendered it is not
    /// compared: a GPU run measures its images against a CPU reference, as the paper's Fig. 9
    /// does. Call it after the size and backend are set.
    /// `docs/paper-scale/cube/reference.exr` is `cube`'s at `--preset paper`.
    pub fn with_reference(self, exr_path: &Path) -> Result<Self> {
        let estimator = self.method_estimator("gather", &rays::reference_params(&self), &[])?;
        let stem = self.stem(estimator.as_ref(), REFERENCE_SEED, &[]);
        let json_path = exr_path.with_extension("json");
        let report = RenderReport::read(&json_path)?;
        let size = self.params.size;
        let checks: [(&str, String, String); 8] = [
            (
                "hmdist version",
                report.hmdist_version.clone(),
                env!("CARGO_PKG_VERSION").into(),
            ),
            ("method", report.method.clone(), estimator.method().into()),
            ("scene", report.scene.clone(), self.scene.name.clone()),
            (
                "triangles",
                report.triangles.to_string(),
                self.scene.mesh.triangle_count().to_string(),
            ),
            (
                "diagonal",
                report.l_diag.to_string(),
                self.scene.diagonal().to_string(),
            ),
            (
                "size",
                format!("{}x{}", report.width, report.height),
                format!("{size}x{size}"),
            ),
            ("seed", report.seed.to_string(), REFERENCE_SEED.to_string()),
            parameters_check(&report.parameters, &estimator.parameters()),
        ];
        if let Some((what, found, wanted)) = checks.iter().find(|(_, found, wanted)| found != wanted) {
            return Err(Error::invalid(
                "reference",
                format!(
                    "{} is not this run's reference image: its {what} is {found}, this run's is {wanted}",
                    exr_path.display()
                ),
            ));
        }
        let image = exr::read(exr_path)?;
        if (image.width, image.height) != (size, size) {
            return Err(Error::invalid(
                "reference",
                format!(
                    "{} is {}x{} pixels, but its report says {size}x{size}",
                    exr_path.display(),
                    image.width,
                    image.height
                ),
            ));
        }
        let (cached_exr, cached_json) = self.cache_paths(&stem);
        if !cached_json.exists() {
            self.make_cache()?;
            let bytes = std::fs::read(exr_path).map_err(|e| Error::io(exr_path, "read", e))?;
            write_atomically(&cached_exr, &bytes)?;
            let json = std::fs::read(&json_path).map_err(|e| Error::io(&json_path, "read", e))?;
            write_atomically(&cached_json, &json)?;
        }
        Ok(self)
    }

    /// The image `estimator` renders at the preset's size with `seed`, from the cache when
    /// an earlier run made it.
    pub fn image(&self, estimator: &dyn Estimator, seed: u64) -> Result<(HmdImage, RenderReport)> {
        let (image, report, _) = self.image_with(estimator, seed, &[])?;
        Ok((image, report))
    }

    /// [`Runner::image`] with `aovs`: they are part of the cache key, and stored as channels
    /// of the cached EXR.
    fn image_with(
        &self,
        estimator: &dyn Estimator,
        seed: u64,
        aovs: &[Aov],
    ) -> Result<(HmdImage, RenderReport, Vec<HmdImage>)> {
        crate::interrupt::check()?;
        let size = self.params.size;
        let stem = self.stem(estimator, seed, aovs);
        let (exr_path, json_path) = self.cache_paths(&stem);
        let request = self.shard.as_ref().map(|s| {
            let i = s.requests.get();
            s.requests.set(i + 1);
            (s, i % s.shard.count as u64 == s.shard.index as u64)
        });
        let cached = read_cached(&exr_path, &json_path, aovs);
        if let Some(plan) = &self.plan {
            return self.plan_image(plan, estimator, seed, aovs, stem, cached);
        }
        if let Some(cached) = cached {
            self.first_look(&stem, Some(cached.1.seconds.total));
            return Ok(cached);
        }
        if let Some((s, false)) = request {
            // Another shard's image: a stand-in of the right size.
            s.stand_ins.set(s.stand_ins.get() + 1);
            return Ok(self.stand_in(aovs));
        }
        let options = self.render_options(seed, aovs);
        let rendered = self
            .render_in_parts(estimator, &options, &stem)
            .inspect_err(|_| {
                if let Some((s, _)) = request {
                    s.render_failed.set(true);
                }
            })?;
        if let Some((s, _)) = request {
            s.rendered.set(s.rendered.get() + 1);
        }
        self.cache_image(&stem, &rendered)?;
        self.first_look(&stem, None);
        self.progress.advance(1);
        let channels = rendered
            .aovs
            .into_iter()
            .map(|a| HmdImage::new(size, size, a.data))
            .collect();
        Ok((rendered.image, rendered.report, channels))
    }

    /// How many parts an image is rendered in: [`PARTS`] where it casts at least
    /// [`PART_RAYS`] rays (or what [`Runner::with_part_rays`] set), else 1.
    fn parts(&self, estimator: &dyn Estimator) -> u32 {
        let pixels = self.params.size as u64 * self.params.size as u64;
        if estimator.expected_rays(pixels) >= self.part_rays {
            PARTS
        } else {
            1
        }
    }

    /// The cache stem of part `k` of `parts` of the image `stem`.
    fn part_stem(stem: &str, k: u32, parts: u32) -> String {
        format!("{stem}.part-{k}-of-{parts}")
    }

    /// Of the `parts` parts of the image `stem`, those already cached (none for a whole
    /// image).
    fn parts_cached(&self, stem: &str, parts: u32) -> u32 {
        if parts == 1 {
            return 0;
        }
        (0..parts)
            .filter(|&k| {
                let part = Self::part_stem(stem, k, parts);
                self.cache.join(format!("{part}.json")).exists()
            })
            .count() as u32
    }

    /// Renders the image `stem` with `options`: see [`Runner::render_outputs_in_parts`].
    fn render_in_parts(
        &self,
        estimator: &dyn Estimator,
        options: &RenderOptions,
        stem: &str,
    ) -> Result<crate::render::Rendered> {
        let pass =
            |options: &RenderOptions| render(&self.scene, estimator, options, &Silent).map(|r| vec![r]);
        let mut rendered = self.render_outputs_in_parts(&[estimator], &[stem.to_string()], options, &pass)?;
        Ok(rendered.remove(0))
    }

    /// Renders the images `stems` of `estimators` with `options` by `pass`: whole, or (see
    /// [`Runner::parts`]: the estimator that casts the most decides) as row shards, each
    /// shard's images cached as soon as they are done (an interrupted run keeps the parts it
    /// finished, and the next one renders only the others), then merged (bit for bit the
    /// whole images: [`crate::shard::merge`]) and the parts removed.
    fn render_outputs_in_parts(
        &self,
        estimators: &[&dyn Estimator],
        stems: &[String],
        options: &RenderOptions,
        pass: &dyn Fn(&RenderOptions) -> Result<Vec<crate::render::Rendered>>,
    ) -> Result<Vec<crate::render::Rendered>> {
        let count = estimators.iter().map(|e| self.parts(*e)).max().unwrap_or(1);
        if count == 1 {
            return pass(options);
        }
        self.make_cache()?;
        let mut parts: Vec<Vec<crate::shard::Part>> = stems.iter().map(|_| vec![]).collect();
        let mut files = vec![];
        for k in 0..count {
            let paths: Vec<(PathBuf, PathBuf)> = stems
                .iter()
                .map(|stem| {
                    let part = Self::part_stem(stem, k, count);
                    self.cache_paths(&part)
                })
                .collect();
            let cached: Option<Vec<_>> = paths
                .iter()
                .map(|(exr_path, json_path)| read_cached(exr_path, json_path, &options.aovs))
                .collect();
            let outputs = match cached {
                Some(cached) => {
                    let mut earlier = self.earlier_parts.borrow_mut();
                    for (stem, (_, report, _)) in stems.iter().zip(&cached) {
                        *earlier.entry(stem.clone()).or_insert(0.0) += report.seconds.total;
                    }
                    cached
                }
                None => {
                    let options = RenderOptions {
                        shard: Some(Shard::new(k, count)?),
                        ..options.clone()
                    };
                    let mut outputs = vec![];
                    for (rendered, (exr_path, json_path)) in pass(&options)?.into_iter().zip(&paths) {
                        let bytes = exr::encode(&rendered.image, &rendered.aovs, exr_path)?;
                        write_atomically(exr_path, &bytes)?;
                        write_atomically(json_path, rendered.report.to_json().as_bytes())?;
                        let (width, height) = (options.width, options.height);
                        let aovs = rendered
                            .aovs
                            .into_iter()
                            .map(|a| HmdImage::new(width, height, a.data));
                        outputs.push((rendered.image, rendered.report, aovs.collect()));
                    }
                    outputs
                }
            };
            for ((image, report, aovs), output) in outputs.into_iter().zip(&mut parts) {
                let aovs = options
                    .aovs
                    .iter()
                    .zip(aovs)
                    .map(|(&aov, image)| AovImage {
                        aov,
                        data: image.data,
                    })
                    .collect();
                output.push(crate::shard::Part { image, aovs, report });
            }
            files.extend(paths.into_iter().flat_map(|(exr, json)| [exr, json]));
        }
        let merged = parts
            .into_iter()
            .map(crate::shard::merge)
            .collect::<Result<Vec<_>>>()?;
        for file in files {
            // The whole images are written next; a part left behind only costs disk.
            let _ = std::fs::remove_file(file);
        }
        Ok(merged)
    }

    /// Where the cache keeps the image `stem`: its EXR and its JSON report.
    fn cache_paths(&self, stem: &str) -> (PathBuf, PathBuf) {
        (
            self.cache.join(format!("{stem}.exr")),
            self.cache.join(format!("{stem}.json")),
        )
    }

    /// The cache stem of the image `estimator` renders with `seed` and `aovs` at the preset's
    /// size: the method and the [`RenderKey::digest`] of the image's key as this run asks for
    /// it (the backend and BVH preset as requested: `auto` stays `auto`), the key `merge`
    /// compares and photon maps are checked by. An image cached under the key of earlier
    /// versions ([`Runner::legacy_stem`]) is renamed to this one when first asked for, so
    /// caches on disk stay usable.
    fn stem(&self, estimator: &dyn Estimator, seed: u64, aovs: &[Aov]) -> String {
        let options = self.render_options(seed, aovs);
        let key = RenderKey {
            hmdist_version: env!("CARGO_PKG_VERSION").into(),
            scene: self.scene.name.clone(),
            scene_content: format!("{:016x}", self.scene_content),
            method: estimator.method().into(),
            parameters: estimator.parameters(),
            backend: serde_json::to_value(self.backend)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default(),
            adapter_class: None,
            bvh: options.bvh_quality.name().into(),
            width: options.width,
            height: options.height,
            seed,
            max_distance: options.max_distance,
            aovs: aovs.iter().map(|a| a.name().into()).collect(),
            ao_radius: None,
        };
        let stem = format!("{}-{:016x}", estimator.method(), key.digest());
        self.adopt_legacy(&self.legacy_stem(estimator, seed, aovs), &stem);
        stem
    }

    /// The cache stem earlier versions gave the image: a hash of the scene's key, the method,
    /// its parameters, the size, the seed, the backend as requested and the AOVs. Read only, to
    /// find images cached before [`Runner::stem`]'s key.
    fn legacy_stem(&self, estimator: &dyn Estimator, seed: u64, aovs: &[Aov]) -> String {
        let size = self.params.size;
        let parameters = serde_json::to_string(&estimator.parameters()).expect("parameters serialise");
        let mut key = format!(
            "{}|{}|{parameters}|{size}x{size}|{seed}|{:?}",
            self.scene_key,
            estimator.method(),
            self.backend,
        );
        for aov in aovs {
            key += &format!("|{}", aov.name());
        }
        format!("{}-{:016x}", estimator.method(), stable_hash(key.as_bytes()))
    }

    /// Renames the cached files of `legacy` (the image, and any of its parts) to `stem`'s,
    /// where `stem` has none: the EXR first, then the JSON that marks it cached.
    fn adopt_legacy(&self, legacy: &str, stem: &str) {
        let names = std::iter::once((legacy.to_string(), stem.to_string())).chain(
            (0..PARTS).map(|k| (Self::part_stem(legacy, k, PARTS), Self::part_stem(stem, k, PARTS))),
        );
        for (old, new) in names {
            let ((old_exr, old_json), (new_exr, new_json)) = (self.cache_paths(&old), self.cache_paths(&new));
            if old_json.exists() && !new_json.exists() {
                let _ = std::fs::rename(&old_exr, &new_exr);
                let _ = std::fs::rename(&old_json, &new_json);
            }
        }
    }

    /// Writes a rendered image and its report into the cache as `stem`: the JSON last, so
    /// that an image counts as cached only once both files are in place.
    fn cache_image(&self, stem: &str, rendered: &crate::render::Rendered) -> Result<()> {
        self.make_cache()?;
        let (exr_path, json_path) = self.cache_paths(stem);
        write_atomically(
            &exr_path,
            &exr::encode(&rendered.image, &rendered.aovs, &exr_path)?,
        )?;
        write_atomically(&json_path, rendered.report.to_json().as_bytes())
    }

    /// Makes the cube maps `configs` (one resolution; seed `seed`) that are not cached in one
    /// multi-output pass ([`crate::estimators::cubemap::sweep`]: each pixel's hemicube filled
    /// once for all of them, each image bit for bit its own render's), so that asking for
    /// each afterwards finds it cached; in a plan, calibrates that pass. Only on the CPU
    /// backend, and not in a shard (there each image is rendered alone, when asked for).
    pub fn cubemap_sweep(&self, configs: &[CubemapParams], seed: u64) -> Result<()> {
        crate::interrupt::check()?;
        if self.shard.is_some() {
            return Ok(());
        }
        let mut cubemaps = vec![];
        for config in configs {
            let cubemap = CubemapParams {
                backend: self.backend,
                gpu_fill: self.gpu_fill,
                ..config.clone()
            }
            .build()?;
            let stem = self.stem(&cubemap, seed, &[]);
            let json = self.cache.join(format!("{stem}.json"));
            let known = self
                .plan
                .as_ref()
                .is_some_and(|p| p.items.borrow().iter().any(|i| i.cache.as_ref() == Some(&stem)));
            if !json.exists() && !known && cubemap.runs_on_cpu() {
                cubemaps.push((cubemap, stem));
            }
        }
        if cubemaps.len() < 2 {
            return Ok(());
        }
        let options = self.render_options(seed, &[]);
        let group: Vec<&crate::estimators::Cubemap> = cubemaps.iter().map(|(c, _)| c).collect();
        let estimators: Vec<&dyn Estimator> = cubemaps.iter().map(|(c, _)| c as &dyn Estimator).collect();
        let stems: Vec<String> = cubemaps.iter().map(|(_, s)| s.clone()).collect();
        let pass = |options: &RenderOptions| {
            crate::render::render_outputs(&self.scene, &estimators, options, |context, gbuffer| {
                crate::estimators::cubemap::sweep(&group, context, gbuffer, &Silent)
            })
        };
        if let Some(plan) = &self.plan {
            return self.plan_sweep(plan, &estimators, &stems, seed, &pass);
        }
        let rendered = self.render_outputs_in_parts(&estimators, &stems, &options, &pass)?;
        for (stem, rendered) in stems.iter().zip(&rendered) {
            self.cache_image(stem, rendered)?;
            self.first_look(stem, None);
            self.progress.advance(1);
        }
        Ok(())
    }

    /// For a plan: calibrates a multi-output pass over `estimators` (images `stems`) and
    /// records each image at its share of the pass's seconds (the BVH build once, the rest
    /// scaled to the whole image), in proportion to its own timing (its texels and lookups:
    /// shared texels count in every output's timing, but are filled once).
    fn plan_sweep(
        &self,
        plan: &PlanRun,
        estimators: &[&dyn Estimator],
        stems: &[String],
        seed: u64,
        pass: &dyn Fn(&RenderOptions) -> Result<Vec<crate::render::Rendered>>,
    ) -> Result<()> {
        let size = self.params.size;
        let (shard, scale) = plan::calibration_shard(size);
        let options = RenderOptions {
            shard: Some(shard),
            ..self.render_options(seed, &[])
        };
        let start = Instant::now();
        let calibration = pass(&options).inspect_err(|_| plan.calibration_failed.set(true))?;
        let wall = start.elapsed().as_secs_f64();
        plan.calibration_seconds
            .set(plan.calibration_seconds.get() + wall);
        let accel_build = calibration.first().map_or(0.0, |r| r.report.seconds.accel_build);
        let pass_seconds = accel_build + (wall - accel_build).max(0.0) * scale;
        let timed: f64 = calibration.iter().map(|r| r.report.seconds.estimate).sum();
        let parts = estimators.iter().map(|e| self.parts(*e)).max().unwrap_or(1);
        for ((estimator, stem), rendered) in estimators.iter().zip(stems).zip(&calibration) {
            let share = if timed > 0.0 {
                rendered.report.seconds.estimate / timed
            } else {
                1.0 / calibration.len() as f64
            };
            let cached_parts = self.parts_cached(stem, parts);
            let (mut what, work) = plan::describe(
                estimator.method(),
                &estimator.parameters(),
                seed,
                size as u64 * size as u64,
            );
            what += " (one output of a multi-output cube-map pass";
            what += &if parts > 1 {
                format!("; {cached_parts} of {parts} parts cached)")
            } else {
                ")".to_string()
            };
            let left = (parts - cached_parts) as f64 / parts as f64;
            plan.items.borrow_mut().push(plan::PlanItem {
                experiment: plan.experiment.get().into(),
                also_needed_by: vec![],
                what,
                work,
                cache: Some(stem.clone()),
                cached: false,
                seconds: pass_seconds * share * left,
            });
            self.progress.advance(1);
        }
        Ok(())
    }

    /// An image of the preset's size standing in for one this run does not render.
    fn stand_in(&self, aovs: &[Aov]) -> (HmdImage, RenderReport, Vec<HmdImage>) {
        let size = self.params.size;
        let image = HmdImage::new(size, size, vec![1.0; (size * size) as usize]);
        let report = RenderReport {
            width: size,
            height: size,
            ..RenderReport::default()
        };
        (image.clone(), report, vec![image; aovs.len()])
    }

    /// For a plan: records the image (once, however many experiments ask for it) and, when it
    /// is not `cached`, calibrates it; returns the cached image or a stand-in.
    fn plan_image(
        &self,
        plan: &PlanRun,
        estimator: &dyn Estimator,
        seed: u64,
        aovs: &[Aov],
        stem: String,
        cached: Option<(HmdImage, RenderReport, Vec<HmdImage>)>,
    ) -> Result<(HmdImage, RenderReport, Vec<HmdImage>)> {
        let experiment = plan.experiment.get();
        let mut items = plan.items.borrow_mut();
        if let Some(item) = items.iter_mut().find(|i| i.cache.as_ref() == Some(&stem)) {
            if item.experiment != experiment && !item.also_needed_by.iter().any(|e| e == experiment) {
                item.also_needed_by.push(experiment.into());
            }
            drop(items);
            return Ok(cached.unwrap_or_else(|| self.stand_in(aovs)));
        }
        let size = self.params.size;
        let (mut what, work) = plan::describe(
            estimator.method(),
            &estimator.parameters(),
            seed,
            size as u64 * size as u64,
        );
        let parts = self.parts(estimator);
        let parts_cached = self.parts_cached(&stem, parts);
        if parts > 1 {
            what += &format!(" ({parts_cached} of {parts} parts cached)");
        }
        let seconds = match &cached {
            Some(_) => 0.0,
            None => {
                let (shard, scale) = plan::calibration_shard(size);
                let options = RenderOptions {
                    shard: Some(shard),
                    ..self.render_options(seed, aovs)
                };
                let start = Instant::now();
                let calibration = render(&self.scene, estimator, &options, &Silent)
                    .inspect_err(|_| plan.calibration_failed.set(true))?;
                let spent = plan.calibration_seconds.get() + start.elapsed().as_secs_f64();
                plan.calibration_seconds.set(spent);
                self.progress.advance(1);
                let left = (parts - parts_cached) as f64 / parts as f64;
                plan::extrapolate(&calibration.report, scale) * left
            }
        };
        items.push(plan::PlanItem {
            experiment: experiment.into(),
            also_needed_by: vec![],
            what,
            work,
            cached: cached.is_some(),
            cache: Some(stem),
            seconds,
        });
        drop(items);
        Ok(cached.unwrap_or_else(|| self.stand_in(aovs)))
    }
}

/// `("parameters", found, wanted)`: the parameters `wanted` and, in the same order, the values
/// `found` has under their names (the rest of `found`, other groups' fields, is not compared).
fn parameters_check(
    found: &crate::report::Parameters,
    wanted: &crate::report::Parameters,
) -> (&'static str, String, String) {
    let as_object = |p: &crate::report::Parameters| match serde_json::to_value(p) {
        Ok(serde_json::Value::Object(map)) => map,
        _ => unreachable!("parameters serialise to an object"),
    };
    let (found, wanted) = (as_object(found), as_object(wanted));
    let found: serde_json::Map<String, serde_json::Value> = wanted
        .keys()
        .map(|k| {
            (
                k.clone(),
                found.get(k).cloned().unwrap_or(serde_json::Value::Null),
            )
        })
        .collect();
    let json = |m: serde_json::Map<String, serde_json::Value>| serde_json::Value::Object(m).to_string();
    ("parameters", json(found), json(wanted))
}

/// The cached image at `exr_path` with its report at `json_path` and its `aovs`, where both
/// files are there and the report is this version's.
fn read_cached(
    exr_path: &Path,
    json_path: &Path,
    aovs: &[Aov],
) -> Option<(HmdImage, RenderReport, Vec<HmdImage>)> {
    let image = exr::read(exr_path).ok()?;
    let report = RenderReport::read(json_path).ok()?;
    // The version is in the key; a report that says otherwise was not ours.
    if report.hmdist_version != env!("CARGO_PKG_VERSION") {
        return None;
    }
    let channels = aovs
        .iter()
        .map(|a| exr::read_channel(exr_path, a.name()).ok())
        .collect::<Option<Vec<_>>>()?;
    Some((image, report, channels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts of an image that an interrupted run cached count, in the run that finishes
    /// the image, with the seconds their reports give; the parts this run renders do not.
    #[test]
    fn parts_an_earlier_run_left_count_with_their_reports_seconds() {
        let out = std::env::temp_dir().join(format!("hmdist-earlier-parts-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let runner = Runner::new("slab", Preset::Quick, &out, &Silent)
            .unwrap()
            .with_size(Some(32))
            .unwrap()
            .with_backend(Backend::Cpu)
            .with_part_rays(1);
        let estimator = runner
            .method_estimator("gather", &serde_json::json!({ "rays": 16 }), &[])
            .unwrap();
        let stem = runner.stem(estimator.as_ref(), 1, &[]);
        let options = runner.render_options(1, &[]);
        let one = |options: &RenderOptions| {
            render(&runner.scene, estimator.as_ref(), options, &Silent).map(|r| vec![r])
        };
        // The first run stops after three parts.
        let started = Cell::new(0);
        let stopping = |options: &RenderOptions| {
            started.set(started.get() + 1);
            if started.get() > 3 {
                return Err(Error::Interrupted);
            }
            one(options)
        };
        let stems = [stem.clone()];
        assert!(runner
            .render_outputs_in_parts(&[estimator.as_ref()], &stems, &options, &stopping)
            .is_err());
        let left: f64 = (0..3)
            .map(|k| {
                let (exr_path, json_path) = runner.cache_paths(&Runner::part_stem(&stem, k, PARTS));
                read_cached(&exr_path, &json_path, &[]).unwrap().1.seconds.total
            })
            .sum();
        assert!(left > 0.0);
        assert!(
            runner.earlier_parts.borrow().is_empty(),
            "the first run found nothing cached"
        );
        // The next run renders the other parts, takes those three from the cache, and counts them.
        runner.image(estimator.as_ref(), 1).unwrap();
        assert_eq!(runner.first_looks.borrow()[&stem], Some(left));
        // An image rendered whole by this run owes nothing to an earlier one.
        runner.first_look("another", None);
        assert_eq!(runner.first_looks.borrow()["another"], None);
        let _ = std::fs::remove_dir_all(&out);
    }

    /// An image cached under the key of earlier versions (the whole image, or its parts) is
    /// found, not rendered again, and takes the new key's name.
    #[test]
    fn an_image_cached_under_the_old_key_is_found() {
        let out = std::env::temp_dir().join(format!("hmdist-legacy-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let runner = || {
            Runner::new("slab", Preset::Quick, &out, &Silent)
                .unwrap()
                .with_size(Some(16))
                .unwrap()
                .with_backend(Backend::Cpu)
        };
        let first = runner();
        let estimator = first
            .method_estimator("gather", &serde_json::json!({ "rays": 8 }), &[])
            .unwrap();
        let (_, report) = first.image(estimator.as_ref(), 1).unwrap();
        let (stem, legacy) = (
            first.stem(estimator.as_ref(), 1, &[]),
            first.legacy_stem(estimator.as_ref(), 1, &[]),
        );
        assert_ne!(stem, legacy, "the key changed");
        // As an earlier version would have left it: the image under the old name, and a part
        // of another image under its old name.
        let (new_exr, new_json) = first.cache_paths(&stem);
        let (old_exr, old_json) = first.cache_paths(&legacy);
        std::fs::rename(&new_exr, &old_exr).unwrap();
        std::fs::rename(&new_json, &old_json).unwrap();
        let second = runner();
        let (_, found) = second.image(estimator.as_ref(), 1).unwrap();
        // A render again would have taken other seconds.
        assert_eq!(found.seconds.total.to_bits(), report.seconds.total.to_bits());
        assert!(new_json.exists() && !old_json.exists(), "renamed to the new key");
        let _ = std::fs::remove_dir_all(&out);
    }
}
