//! `--plan`: every image the experiments ask for, looked up in the cache or calibrated, the
//! plan written, and a later run's seconds put beside it.

use std::time::Instant;

use crate::error::Result;
use crate::estimators::{Aov, Estimator};
use crate::image::{write_atomically, HmdImage};
use crate::progress::Silent;
use crate::render::{render, RenderOptions};
use crate::report::RenderReport;

use super::plan::{self, Plan};
use super::runner::{PlanRun, Runner};
use super::table::Table;

impl Runner<'_> {
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

    /// The plan `plan` gathered, totalled per experiment in `order` and written into its
    /// folder.
    pub(super) fn write_plan(&self, plan: &PlanRun, order: &[&str]) -> Result<Plan> {
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
    pub(super) fn first_look(&self, stem: &str, cached_seconds: Option<f64>) {
        let earlier = cached_seconds.or_else(|| self.earlier_parts.borrow().get(stem).copied());
        self.first_looks
            .borrow_mut()
            .entry(stem.to_string())
            .or_insert(earlier);
    }

    /// For a plan: calibrates a multi-output pass over `estimators` (images `stems`) and
    /// records each image at its share of the pass's seconds (the BVH build once, the rest
    /// scaled to the whole image), in proportion to its own timing (its texels and lookups:
    /// shared texels count in every output's timing, but are filled once).
    pub(super) fn plan_sweep(
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

    /// For a plan: records the image (once, however many experiments ask for it) and, when it
    /// is not `cached`, calibrates it; returns the cached image or a stand-in.
    pub(super) fn plan_image(
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
