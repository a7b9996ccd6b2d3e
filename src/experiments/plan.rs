//! `hmdist experiment NAME --plan`: what a run will cost, before it is paid.
//!
//! The experiments run as they would, but every image they ask for is looked up in the cache
//! and, where it is not there, *calibrated* instead of rendered: the same estimator renders
//! every `M`-th row of the image (a shard, [`crate::shard`], of [`CALIBRATION_ROWS`] rows
//! spread over the image), and its seconds are extrapolated to the whole image: the BVH
//! build, the primary rays and the work an estimator does once per image (tracing and
//! indexing photons, uploading to the GPU) count once, the per-pixel work `size / rows`
//! times ([`extrapolate`]). An image two experiments need is listed once, under the first that
//! asks for it (in the order `all` runs them), with the others named beside it. Work that is
//! not an image (Table 4's photon map builds) is estimated by its experiment from a smaller
//! instance of itself, timed.
//!
//! The plan is written to `OUT/plan.json` (and `plan.md`, `plan.csv`); nothing else is
//! written, the cache included. A later run's report states each experiment's planned
//! seconds beside the seconds it took ([`comparison`]).

use serde::{Deserialize, Serialize};

use super::table::Table;
use crate::estimators::photon::PhotonMethod;
use crate::estimators::{AdaptiveParams, CubemapParams, PhotonParams};
use crate::report::{Parameters, RenderReport};
use crate::sampling::Sampler;

/// Rows a calibration renders (every `size / CALIBRATION_ROWS`-th row of the image).
pub const CALIBRATION_ROWS: u32 = 8;

/// The plan of one or more experiments on one scene and preset.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Plan {
    /// The scene's name.
    pub scene: String,
    /// The preset's name.
    pub preset: String,
    /// Image side in pixels.
    pub size: u32,
    /// Where gather and the cube map run (as asked: `auto`, `cpu`, `gpu`).
    pub backend: String,
    /// The machine the estimates hold for.
    pub machine: Machine,
    /// Seconds the calibrations took.
    pub calibration_seconds: f64,
    /// Every image and piece of work, each once, in the order the run meets them.
    pub items: Vec<PlanItem>,
    /// Per experiment: what it adds and its estimated seconds.
    pub experiments: Vec<PlannedExperiment>,
    /// Estimated seconds of the whole run.
    pub total_seconds: f64,
}

/// One image (or other piece of work) of a plan.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PlanItem {
    /// The first experiment that needs it: its cost is counted there.
    pub experiment: String,
    /// The other experiments that use it (from the cache, at no cost).
    pub also_needed_by: Vec<String>,
    /// Method and parameters, e.g. `gather N = 65536, seed 1000003`.
    pub what: String,
    /// Its size in rays, or photons and queries.
    pub work: String,
    /// The cache file's stem, for images.
    pub cache: Option<String>,
    /// Whether the cache already holds it.
    pub cached: bool,
    /// Estimated seconds; 0 when cached.
    pub seconds: f64,
}

/// One experiment's share of a plan.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PlannedExperiment {
    /// Its name.
    pub name: String,
    /// Images it needs first (rendered in it), and of those already cached.
    pub images: usize,
    /// Of those, already in the cache.
    pub cached: usize,
    /// Estimated seconds.
    pub seconds: f64,
}

/// The CPU and cores the plan was measured on.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Machine {
    /// The CPU's model name (`/proc/cpuinfo`), or `unknown`.
    pub cpu: String,
    /// Threads the renders use.
    pub threads: usize,
}

impl Machine {
    /// This machine.
    pub fn this() -> Machine {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| {
                text.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, name)| name.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            cpu,
            threads: rayon::current_num_threads(),
        }
    }
}

/// The shard a calibration renders of a `size`-row image: every `M`-th row, and the factor
/// from its rows to the image's.
pub fn calibration_shard(size: u32) -> (crate::shard::Shard, f64) {
    let count = (size / CALIBRATION_ROWS).max(1);
    let rows = size.div_ceil(count);
    let shard = crate::shard::Shard { index: 0, count };
    (shard, size as f64 / rows as f64)
}

/// The seconds of the whole image from a calibration render's report: the estimator's
/// per-pixel work scaled by `scale` (where the report times it as a phase, the photon
/// methods' `gather`, that phase; else all of the estimate but its once-per-image phases);
/// the BVH build, the primary rays, the once-per-image phases (tracing and indexing
/// photons, uploading to the GPU), the rest of the estimate and whatever of the total no
/// phase names (setting up) as measured. The primary rays count once because a shard's
/// primary pass still allocates and walks the whole image's G-buffer: at 1024² that fixed
/// part is most of a calibration's primary seconds (20 ms of 8 rows against 170 ms for all
/// 1,024), and scaling it counted 2.5 s too many per photon image.
pub fn extrapolate(report: &RenderReport, scale: f64) -> f64 {
    let s = &report.seconds;
    let p = &s.phases;
    let once = [p.photon_trace, p.photon_index, p.gpu_upload]
        .iter()
        .fold(0.0, |total, phase| total + phase.unwrap_or(0.0));
    let per_row = p.gather.unwrap_or((s.estimate - once).max(0.0));
    let set_up = (s.estimate - once - per_row).max(0.0);
    let rest = (s.total - s.accel_build - s.primary - s.estimate).max(0.0);
    s.accel_build + s.primary + once + set_up + rest + per_row * scale
}

/// `method` with `parameters` and `seed`, in words, and its work at `pixels` pixels.
pub fn describe(method: &str, parameters: &Parameters, seed: u64, pixels: u64) -> (String, String) {
    let mut what = vec![method.to_string()];
    let mut work = String::new();
    if let Some(rays) = parameters.number("rays") {
        what.push(format!("N = {rays}"));
        work = format!("{:.3e} rays", pixels as f64 * rays);
    }
    if let Some(c) = parameters
        .typed::<CubemapParams>()
        .filter(|_| method == "cubemap")
    {
        what.push(format!("R = {}", c.cube_res));
        work = format!("{:.3e} lookups", pixels as f64 * c.rays as f64);
    }
    let sampler = parameters.get("sampler").and_then(|s| s.as_str());
    if let Some(sampler) = sampler.filter(|&s| s != Sampler::Grid.name()) {
        what.push(format!("{sampler} sampler"));
    }
    if let Some(a) = parameters
        .typed::<AdaptiveParams>()
        .filter(|_| method == "adaptive")
    {
        let mut stop = format!("tolerance {}", a.tolerance);
        if a.abs_tolerance != 0.0 {
            stop += &format!(", absolute tolerance {}", a.abs_tolerance);
        }
        if a.loosen != 0.0 {
            stop += &format!(", loosen {}", a.loosen);
        }
        what.push(format!("{stop} (N ≤ {})", a.max_rays));
        work = format!("≤ {:.3e} rays", pixels as f64 * a.max_rays as f64);
    }
    if let Some(p) = parameters
        .typed::<PhotonParams>()
        .filter(|_| PhotonMethod::from_name(method).is_some())
    {
        what.push(format!(
            "{} photons, K = {}, {} source, {} bounces",
            p.photons,
            p.nearest,
            p.source.name(),
            p.max_bounces
        ));
        work = format!(
            "{:.3e} photons, {:.3e} photons gathered",
            p.photons as f64,
            pixels as f64 * p.nearest as f64
        );
    }
    what.push(format!("seed {seed}"));
    (what.join(", "), work)
}

impl Plan {
    /// Adds up the items per experiment (in `order`) and in all.
    pub fn total(&mut self, order: &[&str]) {
        self.experiments = order
            .iter()
            .map(|&name| {
                let first: Vec<&PlanItem> = self.items.iter().filter(|i| i.experiment == name).collect();
                PlannedExperiment {
                    name: name.into(),
                    images: first.iter().filter(|i| i.cache.is_some()).count(),
                    cached: first.iter().filter(|i| i.cache.is_some() && i.cached).count(),
                    seconds: first.iter().fold(0.0, |total, i| total + i.seconds),
                }
            })
            .collect();
        self.total_seconds = self.experiments.iter().fold(0.0, |total, e| total + e.seconds);
    }

    /// Every item, as a table.
    pub fn items_table(&self) -> Table {
        let mut table = Table::new(
            &format!(
                "Plan: `{}`, preset {}, {}², {} threads on {}",
                self.scene, self.preset, self.size, self.machine.threads, self.machine.cpu
            ),
            &[
                "experiment",
                "image or work",
                "size",
                "cached",
                "estimated s",
                "also used by",
            ],
        );
        for item in &self.items {
            table.push(vec![
                item.experiment.clone(),
                item.what.clone(),
                item.work.clone(),
                if item.cache.is_none() {
                    "—".into()
                } else if item.cached {
                    "yes".into()
                } else {
                    "no".into()
                },
                format!("{:.1}", item.seconds),
                item.also_needed_by.join(" "),
            ]);
        }
        table
    }

    /// The experiments' totals, as a table.
    pub fn summary_table(&self) -> Table {
        let mut table = Table::new(
            &format!(
                "Plan by experiment: {} (calibration took {:.1} s)",
                hours(self.total_seconds),
                self.calibration_seconds
            ),
            &["experiment", "new images", "of them cached", "estimated s"],
        );
        for e in &self.experiments {
            table.push(vec![
                e.name.clone(),
                e.images.to_string(),
                e.cached.to_string(),
                format!("{:.1}", e.seconds),
            ]);
        }
        table.push(vec![
            "total".into(),
            self.experiments
                .iter()
                .map(|e| e.images)
                .sum::<usize>()
                .to_string(),
            self.experiments
                .iter()
                .map(|e| e.cached)
                .sum::<usize>()
                .to_string(),
            format!("{:.1}", self.total_seconds),
        ]);
        table
    }
}

/// `seconds` as hours and minutes, for people.
fn hours(seconds: f64) -> String {
    let minutes = (seconds / 60.0).round() as u64;
    format!("{} h {:02} min", minutes / 60, minutes % 60)
}

/// The planned seconds of each experiment that `actual` (name, wall seconds of this run)
/// timed, beside the seconds it took; `None` when the plan covers none of them. An image the
/// plan counted in the experiment as not cached, and this run found cached (`earlier(stem)`:
/// the seconds its report gives), was rendered after the plan by an earlier run (one stopped
/// at a session's end, then resumed): its seconds count in the experiment's, and in a column
/// of their own. So do, for an image in parts (see `Runner::parts`) that this run finished,
/// the parts an earlier run left (`earlier(stem)`: their reports' seconds).
pub fn comparison(
    plan: &Plan,
    actual: &[(String, f64)],
    earlier: &dyn Fn(&str) -> Option<f64>,
) -> Option<Table> {
    let mut table = Table::new(
        &format!(
            "Plan against run: estimated seconds (calibrated on {}, {} threads) and seconds taken",
            plan.machine.cpu, plan.machine.threads
        ),
        &[
            "experiment",
            "planned s",
            "actual s",
            "from earlier runs",
            "actual ÷ planned",
        ],
    );
    for (name, seconds) in actual {
        if let Some(planned) = plan.experiments.iter().find(|e| &e.name == name) {
            let before: f64 = plan
                .items
                .iter()
                .filter(|i| &i.experiment == name && !i.cached)
                .filter_map(|i| earlier(i.cache.as_deref()?))
                // Not `sum`: the empty sum of f64 is −0, printed "-0.0".
                .fold(0.0, |a, s| a + s);
            let seconds = seconds + before;
            let ratio = if planned.seconds > 0.0 {
                format!("{:.2}", seconds / planned.seconds)
            } else {
                "".into()
            };
            table.push(vec![
                name.clone(),
                format!("{:.1}", planned.seconds),
                format!("{seconds:.1}"),
                format!("{before:.1}"),
                ratio,
            ]);
        }
    }
    (!table.rows.is_empty()).then_some(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_an_earlier_run_rendered_after_the_plan_count_in_their_experiment() {
        let item = |experiment: &str, stem: &str, cached: bool| PlanItem {
            experiment: experiment.into(),
            cache: Some(stem.into()),
            cached,
            ..PlanItem::default()
        };
        let plan = Plan {
            items: vec![
                item("a", "a1", false),
                item("a", "a2", false),
                item("a", "a3", true),
                item("b", "b1", false),
            ],
            experiments: vec![
                PlannedExperiment {
                    name: "a".into(),
                    seconds: 100.0,
                    ..Default::default()
                },
                PlannedExperiment {
                    name: "b".into(),
                    seconds: 50.0,
                    ..Default::default()
                },
            ],
            ..Plan::default()
        };
        // a1 was rendered by an earlier run, a2 by this one, a3 was cached when planned (an
        // older image, not counted); b1 by this run.
        let earlier = |stem: &str| match stem {
            "a1" => Some(30.0),
            "a3" => Some(1000.0),
            _ => None,
        };
        let actual = [("a".to_string(), 60.0), ("b".to_string(), 40.0)];
        let table = comparison(&plan, &actual, &earlier).unwrap();
        assert_eq!(table.rows[0], ["a", "100.0", "90.0", "30.0", "0.90"]);
        assert_eq!(table.rows[1], ["b", "50.0", "40.0", "0.0", "0.80"]);
    }

    #[test]
    fn the_calibration_shard_renders_about_eight_rows_spread_over_the_image() {
        let (shard, scale) = calibration_shard(1024);
        assert_eq!((shard.count, scale), (128, 128.0));
        let (shard, scale) = calibration_shard(48);
        assert_eq!((shard.count, scale), (6, 6.0));
        let rows = (0..50).filter(|&r| calibration_shard(50).0.has_row(r)).count();
        assert_eq!(50.0 / rows as f64, calibration_shard(50).1);
        assert_eq!(
            calibration_shard(5),
            (crate::shard::Shard { index: 0, count: 1 }, 1.0)
        );
    }

    #[test]
    fn a_description_tells_apart_images_that_differ_in_sampler_or_stop() {
        use crate::estimators::{AdaptiveParams, GatherParams};
        let fixed = |sampler| {
            let params = GatherParams {
                rays: 32,
                sampler,
                ..GatherParams::default()
            };
            Parameters::of(&params, &[])
        };
        let (grid, work) = describe("gather", &fixed(crate::sampling::Sampler::Grid), 1, 100);
        assert_eq!(
            (grid.as_str(), work.as_str()),
            ("gather, N = 32, seed 1", "3.200e3 rays")
        );
        let (sobol, _) = describe("gather", &fixed(crate::sampling::Sampler::Sobol), 1, 100);
        assert_eq!(sobol, "gather, N = 32, sobol sampler, seed 1");
        let adaptive = Parameters::of(
            &AdaptiveParams {
                sampler: crate::sampling::Sampler::Sobol,
                tolerance: 0.0,
                abs_tolerance: 0.001,
                loosen: 1.0,
                min_rays: 64,
                max_rays: 4096,
                ..AdaptiveParams::default()
            },
            &[],
        );
        let (stop, _) = describe("adaptive", &adaptive, 1, 100);
        assert_eq!(
            stop,
            "adaptive, sobol sampler, tolerance 0, absolute tolerance 0.001, loosen 1 (N ≤ 4096), seed 1"
        );
    }

    #[test]
    fn extrapolation_scales_only_the_per_pixel_work() {
        let mut report = RenderReport::default();
        report.seconds.accel_build = 1.0;
        report.seconds.phases.photon_trace = Some(2.0);
        report.seconds.phases.photon_index = Some(0.5);
        report.seconds.primary = 0.125;
        report.seconds.estimate = 2.5 + 0.25;
        report.seconds.total = 1.0 + 0.125 + 2.75 + 0.5;
        // No per-pixel phase: all of the estimate but the photon map scales.
        assert_eq!(extrapolate(&report, 8.0), 1.0 + 0.125 + 2.5 + 0.5 + 8.0 * 0.25);
        // The photon gather timed as a phase: it scales, the estimate's set-up does not.
        report.seconds.phases.gather = Some(0.1875);
        assert_eq!(
            extrapolate(&report, 8.0),
            1.0 + 0.125 + 2.5 + 0.0625 + 0.5 + 8.0 * 0.1875
        );
    }
}
