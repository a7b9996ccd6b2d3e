//! Accuracy against cost, the paper's own question: f_diff against seconds for every image the
//! ray and photon studies tabulated in the output folder (Tables 1 and 2: gather and the cube
//! map by N; Table 3 with Table 4's map builds: methods I and II by photons and K), with the
//! Pareto front drawn and named — which estimator gives which accuracy for which cost, on the
//! machine that rendered them — and the same images at the paper's seconds where the paper
//! times their settings, beside the paper's own points.
//!
//! It renders nothing and reads the tables those experiments wrote (`table1.csv`, `table2.csv`,
//! `table3.csv`, `table4.csv`): run it after them into the same `--out` (`all` does).

use super::paper::{self, PaperScene};
use super::photons::{default_source, photon_count};
use super::plot::{log_log_with, Marks, Series};
use super::runner::Runner;
use super::section::Section;
use super::table::Table;
use crate::accel::BuildQuality;
use crate::denoise::DenoiseParams;
use crate::error::Result;

/// One image's accuracy and cost.
#[derive(Clone, Debug, PartialEq)]
pub struct CostPoint {
    /// The estimator: `gather`, `cube map`, `photon I` or `photon II`.
    pub estimator: &'static str,
    /// Its setting: `N = 32`, `130 K, K = 64`.
    pub setting: String,
    /// f_diff against the reference.
    pub f_diff: f64,
    /// Seconds as the run measured them (a photon image's: its map's build and its gather).
    pub seconds: f64,
    /// The paper's seconds for the same setting, where the paper times it.
    pub paper_seconds: Option<f64>,
}

/// The Pareto front of `points` (seconds, f_diff): the indices of the points that no other
/// point beats in both (as fast or faster and strictly more accurate), in order of seconds.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0).then(pa.1.total_cmp(&pb.1))
    });
    let mut best = f64::INFINITY;
    order
        .into_iter()
        .filter(|&i| {
            let better = points[i].1 < best;
            if better {
                best = points[i].1;
            }
            better
        })
        .collect()
}

/// The front of `points` read as sentences: each run of consecutive front points of one
/// estimator (methods I and II together, as one family), with the f_diff and seconds it spans,
/// and the estimators never on it.
pub fn front_in_words(points: &[CostPoint], front: &[usize], seconds: impl Fn(&CostPoint) -> f64) -> String {
    let mut runs: Vec<Vec<&CostPoint>> = vec![];
    for p in front.iter().map(|&i| &points[i]) {
        match runs.last_mut() {
            Some(run) if family(run[0]) == family(p) => run.push(p),
            _ => runs.push(vec![p]),
        }
    }
    let at = |p: &CostPoint| format!("{} (f_diff {:.4}, {:.1} s)", p.setting, p.f_diff, seconds(p));
    let words: Vec<String> = runs
        .iter()
        .map(|run| {
            let (a, b) = (run[0], run[run.len() - 1]);
            let count = |e: &str| run.iter().filter(|p| p.estimator == e).count();
            let name = match (count("photon I"), count("photon II")) {
                (i, ii) if i > 0 && ii > 0 => format!("photon I and II ({i} and {ii} images)"),
                _ => a.estimator.to_string(),
            };
            if run.len() == 1 {
                format!("{name} {}", at(a))
            } else {
                format!("{name} from {} to {}", at(a), at(b))
            }
        })
        .collect();
    let absent: Vec<&str> = ESTIMATORS
        .iter()
        .copied()
        .filter(|&e| points.iter().any(|p| p.estimator == e))
        .filter(|&e| !front.iter().any(|&i| points[i].estimator == e))
        .collect();
    let mut text = words.join("; then ");
    if !absent.is_empty() {
        text += &format!("; never on the front: {}", absent.join(", "));
    }
    text
}

/// `v` to 5 significant digits (seconds and f_diff span decades: a fixed number of decimals
/// would round the small ones to 0).
fn significant(v: f64) -> String {
    let digits = (4 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.digits$}")
}

/// The number in `row`'s cell of `column`, if the column exists and the cell holds one.
fn number(table: &Table, row: &[String], column: &str) -> Option<f64> {
    table.column(column).and_then(|c| row[c].parse().ok())
}

/// The first column whose name starts with `start` and ends with `end`.
fn column_like(table: &Table, start: &str, end: &str) -> Option<String> {
    table
        .header
        .iter()
        .find(|h| h.starts_with(start) && h.ends_with(end))
        .cloned()
}

/// Every image of Tables 1–3 in `runner.out` with its f_diff and seconds (and Table 1's gathers
/// denoised: [`denoised`]), and the tables that
/// were not there.
fn cost_points(runner: &Runner) -> Result<(Vec<CostPoint>, Vec<&'static str>)> {
    let read = |name: &str| Table::read_csv(&runner.out.join(format!("{name}.csv")));
    let (table1, table2, table3, table4) =
        (read("table1")?, read("table2")?, read("table3")?, read("table4")?);
    let missing: Vec<&'static str> = [("table1", &table1), ("table2", &table2), ("table3", &table3)]
        .into_iter()
        .filter(|(_, t)| t.is_none())
        .map(|(name, _)| name)
        .collect();
    let mut points = vec![];
    let mut gathers = vec![];
    if let (Some(t1), Some(t2)) = (&table1, &table2) {
        let cube_f = column_like(t1, "cubemap", " f_diff");
        let cube_s = column_like(t2, "cubemap", " s");
        for row in &t1.rows {
            let Some(rays) = number(t1, row, "rays") else {
                continue;
            };
            let Some(timed) = t2.rows.iter().find(|r| number(t2, r, "rays") == Some(rays)) else {
                continue;
            };
            let published = paper::table2_row(rays as u32);
            let cube = (cube_f.as_deref(), cube_s.as_deref());
            for (estimator, (f_column, s_column), paper_seconds) in [
                (
                    "gather",
                    (Some("gather f_diff"), Some("gather s")),
                    published.map(|p| p.cpu_seconds),
                ),
                ("cube map", cube, published.map(|p| p.gpu_seconds)),
            ] {
                let f_diff = f_column.and_then(|c| number(t1, row, c));
                let seconds = s_column.and_then(|c| number(t2, timed, c));
                if let (Some(f_diff), Some(seconds)) = (f_diff, seconds) {
                    if estimator == "gather" {
                        gathers.push((rays as u32, seconds));
                    }
                    points.push(CostPoint {
                        estimator,
                        setting: format!("N = {rays}"),
                        f_diff,
                        seconds,
                        paper_seconds,
                    });
                }
            }
        }
    }
    if let Some(t3) = &table3 {
        // Table 3's source, as its rows say (a table from before the column: the default
        // source, which it was rendered with then).
        let source_of = |row: &[String]| match t3.column("source") {
            Some(c) => row[c].clone(),
            None => default_source(runner).name().to_string(),
        };
        for row in &t3.rows {
            let source = source_of(row);
            let (Some(photons), Some(k)) = (number(t3, row, "photons"), number(t3, row, "K")) else {
                continue;
            };
            let (photons, k) = (photons as usize, k as usize);
            // The map's build, from Table 4 (80 bounces: at most what Table 3's 20-bounce map
            // costs); nothing where Table 4 has no row for the map.
            let build = table4
                .as_ref()
                .and_then(|t4| {
                    let source_column = t4.column("source")?;
                    let row = t4.rows.iter().find(|r| {
                        number(t4, r, "photons") == Some(photons as f64) && r[source_column] == source
                    })?;
                    number(t4, row, "total s")
                })
                .unwrap_or(0.0);
            let published = paper::table3_cell(photons, k);
            let paper_build = paper::table4_row(photons).map(|r| match source.as_str() {
                "light" => r.light_seconds,
                _ => r.camera_seconds,
            });
            let setting = format!("{}, K = {k}", photon_count(photons));
            for (estimator, method, paper_gather) in [
                ("photon I", "I", published.map(|c| c.method1_seconds)),
                ("photon II", "II", published.map(|c| c.method2_seconds)),
            ] {
                let figures = (
                    number(t3, row, &format!("{method} f_diff")),
                    number(t3, row, &format!("{method} gather s")),
                );
                if let (Some(f_diff), Some(gather)) = figures {
                    points.push(CostPoint {
                        estimator,
                        setting: setting.clone(),
                        f_diff,
                        seconds: build + gather,
                        paper_seconds: paper_gather.zip(paper_build).map(|(g, b)| g + b),
                    });
                }
            }
        }
    }
    points.extend(denoised(runner, &gathers)?);
    Ok((points, missing))
}

/// Table 1's gather images (`gathers`: rays and Table 2's seconds) filtered as `render
/// --denoise` filters them ([`crate::denoise`], default parameters): f_diff against the run's
/// reference, at the gather's seconds and the filter's (timed here, on the cached images). None
/// in a plan, which renders nothing.
fn denoised(runner: &Runner, gathers: &[(u32, f64)]) -> Result<Vec<CostPoint>> {
    if runner.plan.is_some() || gathers.is_empty() {
        return Ok(vec![]);
    }
    let reference = super::rays::reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let size = (runner.params.size, runner.params.size);
    let mut guides: Vec<(String, crate::denoise::Guide)> = vec![];
    let mut points = vec![];
    for &(rays, gather_seconds) in gathers {
        let (image, report) = runner.method_image("gather", &super::rays::gather_params(rays), 1)?;
        // One guide per BVH preset the images were rendered with (their primary hits).
        if !guides.iter().any(|(bvh, _)| *bvh == report.bvh) {
            let bvh = if report.bvh == "high" {
                BuildQuality::High
            } else {
                BuildQuality::Fast
            };
            let samples = vec![1.0; image.data.len()];
            guides.push((
                report.bvh.clone(),
                crate::render::guide(&runner.scene, size, bvh, samples)?,
            ));
        }
        let guide = &mut guides
            .iter_mut()
            .find(|(bvh, _)| *bvh == report.bvh)
            .expect("made above")
            .1;
        guide.samples.fill(rays as f32);
        let start = std::time::Instant::now();
        let filtered = crate::denoise::filter(&image.data, guide, &DenoiseParams::default());
        let seconds = start.elapsed().as_secs_f64();
        let filtered = crate::image::HmdImage::new(image.width, image.height, filtered);
        points.push(CostPoint {
            estimator: "gather + denoise",
            setting: format!("N = {rays}"),
            f_diff: crate::metrics::f_diff(&reference, &filtered, l_diag)?.value,
            seconds: gather_seconds + seconds,
            paper_seconds: None,
        });
    }
    Ok(points)
}

/// The estimators in the plots' order (and colours): the paper's four, then ours.
const ESTIMATORS: [&str; 5] = ["gather", "cube map", "photon I", "photon II", "gather + denoise"];

/// The points of `estimator` as a series at `seconds`.
fn series_of(points: &[CostPoint], estimator: &str, seconds: impl Fn(&CostPoint) -> Option<f64>) -> Series {
    let mut xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.estimator == estimator)
        .filter_map(|p| Some((seconds(p)?, p.f_diff)))
        .collect();
    xy.sort_by(|a, b| a.0.total_cmp(&b.0));
    Series {
        label: estimator.into(),
        points: xy,
    }
}

/// The paper's own accuracy and cost, Table 1 as read against Table 2 (scene A: the CPU
/// gather and the GPU cube map; scene B: the CPU gather).
fn paper_series(scene: PaperScene) -> Vec<Series> {
    let at_seconds = |points: Vec<(u32, f64)>, seconds: fn(&paper::Table2Row) -> f64| -> Vec<(f64, f64)> {
        points
            .into_iter()
            .filter_map(|(rays, f_diff)| Some((seconds(paper::table2_row(rays)?), f_diff)))
            .collect()
    };
    let (cpu, gpu) = paper::table1_points(scene);
    let name = if scene == PaperScene::A { "A" } else { "B" };
    let mut series = vec![Series {
        label: format!("paper's gather, scene {name}"),
        points: at_seconds(cpu, |r| r.cpu_seconds),
    }];
    if let Some(gpu) = gpu {
        series.push(Series {
            label: format!("paper's GPU cube map, scene {name}"),
            points: at_seconds(gpu, |r| r.gpu_seconds),
        });
    }
    series
}

/// The estimators of one family (methods I and II are one: the photon map).
fn family(p: &CostPoint) -> &'static str {
    if p.estimator.starts_with("photon") {
        "photon"
    } else {
        p.estimator
    }
}

/// The front's points at `seconds`, labelled where the labels do not crowd: the ends of each
/// family's run along the front, and between them each point at least ×2 the seconds and ÷1.5
/// the f_diff of the last one labelled.
fn front_labels(
    points: &[CostPoint],
    front: &[usize],
    seconds: &dyn Fn(&CostPoint) -> f64,
) -> Vec<(f64, f64, String)> {
    let mut last: Option<(f64, f64)> = None;
    let family_at = |j: usize| front.get(j).map(|&i| family(&points[i]));
    front
        .iter()
        .enumerate()
        .map(|(j, &i)| {
            let p = &points[i];
            let (x, y) = (seconds(p), p.f_diff);
            let end = j == 0 || family_at(j - 1) != Some(family(p)) || family_at(j + 1) != Some(family(p));
            let apart = last.is_none_or(|(lx, ly)| x >= 2.0 * lx && y <= ly / 1.5);
            let text = if end || apart {
                last = Some((x, y));
                format!("{} {}", p.estimator, p.setting)
            } else {
                String::new()
            };
            (x, y, text)
        })
        .collect()
}

/// Accuracy against cost: `cost.svg` (seconds as measured), `cost_paper.svg` (the paper's
/// seconds for the same settings, with the paper's own points), `cost.csv`, and the fronts.
pub fn cost(runner: &Runner) -> Result<Section> {
    let (points, missing) = cost_points(runner)?;
    let scene = &runner.scene.name;
    let size = runner.params.size;
    let mut notes = vec![];
    if !missing.is_empty() {
        notes.push(format!(
            "Not found in this folder: {} (run those experiments first, into the same --out); their images are not plotted.",
            missing.join(", ")
        ));
    }
    if points.is_empty() {
        return Ok(Section {
            name: "cost".into(),
            notes,
            ..Section::default()
        });
    }
    let ours: Vec<(f64, f64)> = points.iter().map(|p| (p.seconds, p.f_diff)).collect();
    let front = pareto_front(&ours);
    let at_paper: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].paper_seconds.is_some())
        .collect();
    let paper_xy: Vec<(f64, f64)> = at_paper
        .iter()
        .map(|&i| (points[i].paper_seconds.unwrap_or(0.0), points[i].f_diff))
        .collect();
    let paper_front: Vec<usize> = pareto_front(&paper_xy).into_iter().map(|j| at_paper[j]).collect();

    let (table, front_table) = cost_tables(&points, &front, &paper_front, scene, size);
    let mut files = table.write(&runner.out, "cost")?;
    files.push(plot_measured(runner, &points, &front)?);
    notes.push(format!(
        "Which estimator for which accuracy at which cost (cost.svg; seconds as the runs measured them, a photon image's with its map's build from Table 4): {}. Every other image is beaten by a front image that is as fast and more accurate.",
        front_in_words(&points, &front, |p| p.seconds)
    ));
    if !paper_front.is_empty() {
        let (plot, note) = plot_at_paper(runner, &points, &paper_front)?;
        files.push(plot);
        notes.push(note);
    }
    notes.push(
        "Not plotted: Fig. 10, Fig. 16/17 and the adaptive study, whose tables give no seconds per image."
            .into(),
    );
    Ok(Section {
        name: "cost".into(),
        tables: vec![front_table],
        files,
        notes,
        findings: vec![],
    })
}

/// The table of every image (`cost.csv`) and the table of the front.
fn cost_tables(
    points: &[CostPoint],
    front: &[usize],
    paper_front: &[usize],
    scene: &str,
    size: u32,
) -> (Table, Table) {
    let mut table = Table::new(
        &format!("Accuracy against cost, {size}², `{scene}`: every image of Tables 1–3, and Table 1's gathers denoised"),
        &[
            "estimator",
            "setting",
            "f_diff",
            "seconds",
            "on the front",
            "paper s",
            "on the front at paper s",
        ],
    );
    for (i, p) in points.iter().enumerate() {
        table.push(vec![
            p.estimator.into(),
            p.setting.clone(),
            significant(p.f_diff),
            significant(p.seconds),
            if front.contains(&i) { "yes" } else { "" }.into(),
            p.paper_seconds.map_or(String::new(), |s| format!("{s:.1}")),
            if paper_front.contains(&i) { "yes" } else { "" }.into(),
        ]);
    }
    let mut front_table = Table::new(
        &format!("The Pareto front, {size}², `{scene}`: the most accurate image for its seconds"),
        &["estimator", "setting", "f_diff", "seconds"],
    );
    for &i in front {
        let p = &points[i];
        front_table.push(vec![
            p.estimator.into(),
            p.setting.clone(),
            format!("{:.4}", p.f_diff),
            format!("{:.2}", p.seconds),
        ]);
    }
    (table, front_table)
}

/// `points`' series, one per estimator with any point, at `seconds`, each drawn as its
/// estimator is (the photon methods as points, the sweeps as lines).
fn drawn(points: &[CostPoint], seconds: &dyn Fn(&CostPoint) -> Option<f64>) -> Vec<(Series, Marks)> {
    ESTIMATORS
        .iter()
        .enumerate()
        .map(|(place, e)| {
            let marks = if e.starts_with("photon") {
                Marks::POINTS
            } else {
                Marks::LINE
            };
            (series_of(points, e, seconds), marks.coloured(place))
        })
        .filter(|(s, _)| !s.points.is_empty())
        .collect()
}

/// `cost.svg`: f_diff against the seconds as measured, the front labelled.
fn plot_measured(runner: &Runner, points: &[CostPoint], front: &[usize]) -> Result<std::path::PathBuf> {
    let (scene, size) = (&runner.scene.name, runner.params.size);
    let measured = drawn(points, &|p| Some(p.seconds));
    let plot = runner.out.join("cost.svg");
    log_log_with(
        &plot,
        &format!("f_diff against seconds, {size}², `{scene}`"),
        "seconds (as measured)",
        "f_diff",
        &measured.iter().map(|(s, m)| (s, *m)).collect::<Vec<_>>(),
        &front_labels(points, front, &|p| p.seconds),
    )?;
    Ok(plot)
}

/// `cost_paper.svg`: our f_diff at the paper's seconds for the same settings, with the
/// paper's own points; and the note that reads it.
fn plot_at_paper(
    runner: &Runner,
    points: &[CostPoint],
    paper_front: &[usize],
) -> Result<(std::path::PathBuf, String)> {
    let (scene, size) = (&runner.scene.name, runner.params.size);
    let mut at_paper_seconds = drawn(points, &|p| p.paper_seconds);
    let analogue = paper::analogue(scene);
    // The paper's gather in gather's colour, its GPU cube map in the cube map's.
    for (place, s) in analogue
        .map(paper_series)
        .unwrap_or_default()
        .into_iter()
        .enumerate()
    {
        at_paper_seconds.push((s, Marks::HOLLOW.coloured(place)));
    }
    let plot = runner.out.join("cost_paper.svg");
    log_log_with(
        &plot,
        &format!("our f_diff at the paper's seconds, {size}², `{scene}`"),
        "seconds (the paper's, Tables 2–4)",
        "f_diff",
        &at_paper_seconds.iter().map(|(s, m)| (s, *m)).collect::<Vec<_>>(),
        &front_labels(points, paper_front, &|p| p.paper_seconds.unwrap_or(0.0)),
    )?;
    let note = format!(
        "At the paper's seconds for the same settings (cost_paper.svg: its Table 2 for gather on the CPU and the cube map on the GPU, Table 3 and Table 4 for the photon methods), the front is: {}.{}",
        front_in_words(points, paper_front, |p| p.paper_seconds.unwrap_or(0.0)),
        match analogue {
            Some(_) => " Hollow points: the paper's own f_diff (Table 1 as read) at its seconds.",
            None => "",
        }
    );
    Ok((plot, note))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_keeps_each_point_no_faster_point_beats() {
        // (seconds, f_diff): 1 beats 3 (faster and better); 2 ties 0's f_diff later: off.
        let points = [
            (1.0, 3.0),
            (2.0, 1.0),
            (4.0, 3.0),
            (3.0, 2.0),
            (5.0, 0.5),
            (0.5, 9.0),
        ];
        assert_eq!(pareto_front(&points), vec![5, 0, 1, 4]);
        assert!(pareto_front(&[]).is_empty());
    }

    #[test]
    fn the_front_in_words_groups_one_estimators_runs() {
        let point = |estimator, setting: &str, f_diff, seconds| CostPoint {
            estimator,
            setting: setting.into(),
            f_diff,
            seconds,
            paper_seconds: None,
        };
        let points = [
            point("photon II", "130 K, K = 64", 3.0, 1.5),
            point("photon I", "1.06 M, K = 64", 2.5, 2.0),
            point("gather", "N = 32", 1.5, 9.0),
            point("gather", "N = 64", 1.0, 18.0),
            point("cube map", "N = 64", 1.1, 20.0),
        ];
        assert_eq!(
            front_in_words(&points, &[0, 1, 2, 3], |p| p.seconds),
            "photon I and II (1 and 1 images) from 130 K, K = 64 (f_diff 3.0000, 1.5 s) to 1.06 M, K = 64 (f_diff 2.5000, 2.0 s); \
             then gather from N = 32 (f_diff 1.5000, 9.0 s) to N = 64 (f_diff 1.0000, 18.0 s); never on the front: cube map"
        );
        assert_eq!(
            front_in_words(&points, &[2], |p| p.seconds),
            "gather N = 32 (f_diff 1.5000, 9.0 s); never on the front: cube map, photon I, photon II"
        );
    }
}
