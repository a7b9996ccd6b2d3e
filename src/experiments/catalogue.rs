//! The experiments, listed once ([`EXPERIMENTS`]), and running them on a [`Runner`].

use std::time::Instant;

use crate::error::{Error, Result};

use super::presets::PresetParams;
use super::runner::Runner;
use super::section::Section;
use super::{adaptive, caches, cost, photons, rays, report};

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
        summary: "f_diff against rays, gather and cube map (with the pictures by N: fig12 of the cube map, fig13 of gather, and a plot)",
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
        summary: "photon gather seconds and f_diff by photons and K, methods I and II, camera-sourced, 20 bounces (with fig14, fig15)",
        images: |p| 1 + 2 * (p.photons.len() * p.nearest.len()) as u64,
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
        summary: "method II by source, bounces, K and photons (fig16_17), and where the bounce cap binds",
        images: |p| {
            let sources = 2 * photons::BOUNCE_CAPS as u64;
            1 + 4 * (p.fig16_photons.len() * p.fig16_nearest.len()) as u64 + sources * photons::CAP_ABSORPTIONS.len() as u64
        },
        run: photons::fig16_17,
    },
    Experiment {
        name: "adaptive",
        summary: "f_diff against rays cast, fixed N against adaptive gathering (the rays saved)",
        images: |p| 1 + p.rays.len() as u64 + adaptive::TOLERANCES.len() as u64,
        run: adaptive::adaptive,
    },
    Experiment {
        name: "cache",
        summary: "irradiance caches spaced by each estimator of H, an oracle and the renderers' rules: error against rays",
        images: |_| 3 + caches::CACHES as u64,
        run: caches::caches,
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

impl Runner<'_> {
    /// Runs experiment `name` (or every one for `all`), then rewrites the report; a shard
    /// only renders its share of the images, and a plan only calibrates (see [`plan`]).
    pub fn run(&mut self, name: &str) -> Result<()> {
        let experiments = select(name)?;
        let made_cache = !self.cache.exists();
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
                // A plan caches nothing: the image cache it made for its calibrations goes
                // again where it stayed empty.
                if self.plan.is_some() && made_cache {
                    let _ = std::fs::remove_dir(&self.cache);
                }
                std::fs::remove_dir_all(&self.out).map_err(|e| Error::io(&self.out, "remove", e))
            }
            (None, None) => report::write(self),
        }
    }
}
