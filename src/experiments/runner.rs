//! The runner: one scene, one preset, one output folder. It hands the experiments their
//! images (cached, rendered, rendered in parts, or, in a plan, calibrated: `cache.rs`,
//! `planning.rs`) and collects what they produced.

use std::cell::{Cell, RefCell};
use std::path::{Path, PathBuf};

use crate::accel::Kernel;
use crate::error::{Error, Result};
use crate::estimators::cubemap::GpuFill;
use crate::estimators::{registry, Aov, Backend, CubemapParams, Estimator, GatherParams, MethodParams};
use crate::image::{exr, write_atomically, HmdImage};
use crate::progress::{Progress, Silent};
use crate::render::RenderOptions;
use crate::report::RenderReport;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::shard::Shard;

use super::plan::{self, Plan};
use super::presets::{Preset, PresetParams, PART_RAYS, REFERENCE_SEED};
use super::section::Section;

/// Runs experiments on one scene into one folder.
pub struct Runner<'a> {
    /// The scene.
    pub scene: Scene,
    /// Identifies the scene in the cache's older keys ([`Runner::legacy_stems`]): hmdist's
    /// version, the scene's name and the fingerprint of its content.
    pub(super) scene_key: String,
    /// The fingerprint of the scene's content ([`Scene::fingerprint`]), for the cache keys.
    pub(super) scene_content: u64,
    /// How much work.
    pub preset: Preset,
    /// The preset's sizes and counts.
    pub params: PresetParams,
    /// The output folder.
    pub out: PathBuf,
    pub(super) progress: &'a dyn Progress,
    /// What the experiments run so far produced, for the report.
    pub sections: Vec<Section>,
    /// Where rendered images are cached: `OUT/cache`.
    pub(super) cache: PathBuf,
    /// Set for `experiment --shard K/M`: which images this run renders.
    pub(super) shard: Option<ShardRun>,
    /// Where gather and the cube map run (every image's configuration gets it).
    pub(super) backend: Backend,
    /// How the cube map fills its texels on the GPU (every cube map's configuration gets it).
    pub(super) gpu_fill: GpuFill,
    /// The ray-casting kernel of every render (never changes an image).
    pub(super) kernel: Kernel,
    /// Set for `experiment --plan`: calibrate instead of render.
    pub(super) plan: Option<PlanRun>,
    /// The plan a `--plan` run made.
    pub planned: Option<Plan>,
    /// Wall seconds of each experiment this run ran, in order.
    pub timings: Vec<(String, f64)>,
    /// Each image this run asked for, at its first asking: `Some(the seconds its report
    /// gives)` where the cache already held it, `None` where this run rendered it (or, where
    /// it merged parts of it that an earlier run left, `Some(those parts' seconds)`). What an
    /// earlier run rendered after the plan (one stopped at a session's end, then resumed)
    /// counts in the plan against the run ([`plan::comparison`]).
    pub(super) first_looks: RefCell<std::collections::HashMap<String, Option<f64>>>,
    /// Per image rendered in parts, the seconds (by their reports) of the parts that this run
    /// found cached: an earlier run's work, which this run's clock did not see.
    pub(super) earlier_parts: RefCell<std::collections::HashMap<String, f64>>,
    /// Images of at least this many rays are rendered in parts ([`PART_RAYS`]).
    pub(super) part_rays: u64,
    /// The experiments this run runs.
    pub(super) running: Vec<&'static str>,
    /// Whether the ray studies (Tables 1–2) render the cube map beside final gathering.
    pub(super) cubemaps: bool,
}

/// A plan in the making ([`plan`]): every image the experiments ask for is looked up in the
/// cache and, where it is not there, calibrated; the experiments' tables and pictures go to a
/// scratch folder, removed at the end, and the plan to `out`.
pub(super) struct PlanRun {
    pub(super) out: PathBuf,
    pub(super) experiment: Cell<&'static str>,
    pub(super) items: RefCell<Vec<plan::PlanItem>>,
    pub(super) calibration_seconds: Cell<f64>,
    pub(super) calibration_failed: Cell<bool>,
}

/// A shard's share of an experiment's images: request `i` (in the order the experiment asks,
/// the same on every shard) is rendered by shard `i mod M`; the others' images, where not
/// cached, are stand-ins, and the shard writes nothing but its images into the cache. A run
/// without `--shard` then finds every image cached and writes the tables and the report.
pub(super) struct ShardRun {
    pub(super) shard: Shard,
    pub(super) requests: Cell<u64>,
    pub(super) rendered: Cell<u64>,
    pub(super) stand_ins: Cell<u64>,
    pub(super) render_failed: Cell<bool>,
}

impl<'a> Runner<'a> {
    /// A runner for the scene `scene_arg` names (built-in or file), writing into `out`.
    pub fn new(scene_arg: &str, preset: Preset, out: &Path, progress: &'a dyn Progress) -> Result<Self> {
        let scene = Scene::load(scene_arg)?;
        let scene_content = scene.fingerprint();
        let scene_key = format!(
            "{}|{}|{scene_content:016x}",
            env!("CARGO_PKG_VERSION"),
            scene.name
        );
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
    pub(super) fn render_options(&self, seed: u64, aovs: &[Aov]) -> RenderOptions {
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

    /// The reference image's parameters: gather with the preset's reference ray count, on the
    /// jittered grid (spec §3.1), so that the committed references keep their cache keys.
    pub fn reference_params(&self) -> GatherParams {
        GatherParams {
            rays: self.params.reference_rays,
            sampler: Sampler::Grid,
            ..GatherParams::default()
        }
    }

    /// The image method `method` (a registry name) renders with `params` (its parameter
    /// struct) and `seed`, on the runner's backend where the method has one: see
    /// [`Runner::image`].
    pub fn method_image(
        &self,
        method: &str,
        params: &impl MethodParams,
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
        params: &impl MethodParams,
        seed: u64,
        aovs: &[Aov],
    ) -> Result<(HmdImage, RenderReport, Vec<HmdImage>)> {
        let estimator = self.method_estimator(method, params, aovs)?;
        self.image_with(estimator.as_ref(), seed, aovs)
    }

    /// The estimator of method `method` (a registry name) with `params` and `aovs`, on the
    /// runner's backend where the method has one.
    pub(super) fn method_estimator<P: MethodParams>(
        &self,
        method: &str,
        params: &P,
        aovs: &[Aov],
    ) -> Result<Box<dyn Estimator>> {
        let mut params = params.clone();
        params.on_backend(self.backend, self.gpu_fill);
        registry::method(method)?.build(&registry::object(&params)?, aovs)
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
        let estimator = self.method_estimator("gather", &self.reference_params(), &[])?;
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

    /// An image of the preset's size standing in for one this run does not render.
    pub(super) fn stand_in(&self, aovs: &[Aov]) -> (HmdImage, RenderReport, Vec<HmdImage>) {
        let size = self.params.size;
        let image = HmdImage::new(size, size, vec![1.0; (size * size) as usize]);
        let report = RenderReport {
            width: size,
            height: size,
            ..RenderReport::default()
        };
        (image.clone(), report, vec![image; aovs.len()])
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
