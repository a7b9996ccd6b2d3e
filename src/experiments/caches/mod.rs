//! The irradiance-cache study (issue #55; the use that justifies H in the paper: the spacing
//! of an irradiance cache's records): for each source of the records' radii (each estimator
//! of H, an oracle image of H, the renderers' nearest-hit rules) and each accuracy a, Ward's
//! cache of one-bounce irradiance ([`crate::cache`]) against a brute-force image of E: its
//! error (mean and p95) against what it cost (rays and seconds), the Pareto front, the rays
//! each source needs for the errors the records' own H reaches, and where the records go.
//!
//! The two brute-force images of E (another seed each) and the oracle's H (the experiments'
//! reference) are images of the run, cached, planned and sharded as every image; the caches
//! themselves are made on one machine after them, each kept in `OUT/cache-irradiance` under a
//! digest of everything that determines it, so a rerun reuses them.
//!
//! `sources.rs` names the sources and what a cache measured; `section.rs` writes the tables,
//! plots and findings.

mod section;
mod sources;

use self::section::write_section;
use self::sources::{References, Run, Source, ACCURACIES, PICTURED_ACCURACY, SEED, SOURCES};
use super::presets::REFERENCE_SEED;
use super::rays::reference;
use super::runner::Runner;
use super::section::Section;
use crate::cache::{cache, relative_errors, Spacing};
use crate::error::{Error, Result};
use crate::estimators::irradiance::display_scale;
use crate::estimators::IrradianceParams;
use crate::image::picture::encode_png;
use crate::image::write_atomically;
use crate::progress::Silent;

pub use self::sources::CACHES;

/// The study's section: its tables, plots, pictures and findings.
pub fn caches(runner: &Runner) -> Result<Section> {
    let name = "cache".to_string();
    if runner.scene.light.is_none() {
        let note = format!(
            "`{}` has no spot light, and the irradiance the caches hold needs one: nothing to measure.",
            runner.scene.name
        );
        return Ok(Section {
            name,
            notes: vec![note],
            ..Section::default()
        });
    }
    let p = &runner.params;
    let e_params = IrradianceParams {
        rays: p.cache_reference_rays,
        ..IrradianceParams::default()
    };
    let (e, _) = runner.method_image("irradiance", &e_params, REFERENCE_SEED)?;
    let (other, _) = runner.method_image("irradiance", &e_params, REFERENCE_SEED + 1)?;
    let h = reference(runner)?;
    if runner.planning() || runner.shard_counts().is_some() {
        // A plan or a shard wants the images alone; the caches are made where they meet.
        return Ok(Section::default());
    }
    let (_, noise) = relative_errors(&other, &e, "the second reference")?;
    let bits = e
        .data
        .iter()
        .chain(&h.data)
        .flat_map(|v| v.to_bits().to_le_bytes());
    let digest = crate::scene::stable_hash_of(bits);
    let references = References { e, h, noise, digest };
    let mut runs = vec![];
    for source in &SOURCES {
        let mut mine = vec![];
        for &a in &ACCURACIES {
            mine.push(runner.cache_run(source, a, &references)?);
            runner.progress.advance(1);
        }
        runs.push(mine);
    }
    write_section(runner, name, &references, &runs)
}

impl Runner<'_> {
    /// The cache of `source` at accuracy `a`: from `OUT/cache-irradiance` where it is there,
    /// else made and kept (with its records' picture at [`PICTURED_ACCURACY`]).
    fn cache_run(&self, source: &Source, a: f32, references: &References) -> Result<Run> {
        crate::interrupt::check()?;
        let params = source.params(self.params.cache_rays, a)?;
        let options = self.render_options(SEED, &[]);
        let key = format!(
            "{}|{}|{params:?}|{:016x}",
            self.scene_key, options.width, references.digest
        );
        let folder = self.out.join("cache-irradiance");
        let stem = format!(
            "{}-a{a}-{:016x}",
            source.name,
            crate::scene::stable_hash(key.as_bytes())
        );
        let json = folder.join(format!("{stem}.json"));
        if let Some(run) = std::fs::read(&json)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
        {
            return Ok(run);
        }
        let oracle = (params.spacing == Spacing::Oracle).then_some(&references.h);
        let cached = cache(&self.scene, &params, &options, oracle, &Silent)?;
        let (_, errors) = relative_errors(&cached.image, &references.e, "the first reference")?;
        let run = Run {
            records: cached.records.len(),
            rays_e: cached.report.rays_e,
            rays_h: cached.report.rays_h,
            seconds: cached.report.seconds.total,
            errors,
        };
        std::fs::create_dir_all(&folder).map_err(|e| Error::io(&folder, "create the folder", e))?;
        if source.pictured && a == PICTURED_ACCURACY {
            let picture = cached.picture(display_scale(self.scene.diagonal()));
            let path = folder.join(format!("{}.png", source.name));
            write_atomically(&path, &encode_png(&picture, &path)?)?;
        }
        let text = serde_json::to_string_pretty(&run).expect("a run serialises");
        write_atomically(&json, text.as_bytes())?;
        Ok(run)
    }
}
