//! The cache study's section: the table of every cache (the Pareto front starred), the rays
//! each source needs for the errors the records' own H reaches, the plots, the records'
//! picture, and the findings with their numbers.

use std::path::PathBuf;

use image::{Rgb, RgbImage};

use super::sources::{References, Run, ACCURACIES, PICTURED_ACCURACY, SOURCES};
use crate::error::Result;
use crate::experiments::cost::pareto_front;
use crate::experiments::plot::{log_log_with, Marks, Series};
use crate::experiments::presets::REFERENCE_SEED;
use crate::experiments::runner::Runner;
use crate::experiments::section::Section;
use crate::experiments::table::Table;
use crate::image::picture::{draw_text, encode_png};
use crate::image::write_atomically;

/// Rays `runs` (one source, coarsest a first) need for mean error `target`: log-log between
/// the two runs either side of it; `Bound::AtMost` where its cheapest run is better already.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reach {
    At(f64),
    AtMost(f64),
    Never,
}

fn rays_to_reach(runs: &[Run], target: f64) -> Reach {
    let mut sorted: Vec<&Run> = runs.iter().collect();
    sorted.sort_by(|a, b| a.rays().total_cmp(&b.rays()));
    match sorted.first() {
        None => return Reach::Never,
        Some(cheapest) if cheapest.mean() <= target => return Reach::AtMost(cheapest.rays()),
        _ => {}
    }
    for pair in sorted.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if a.mean() >= target && target >= b.mean() && a.mean() != b.mean() {
            let t = (a.mean().ln() - target.ln()) / (a.mean().ln() - b.mean().ln());
            return Reach::At((a.rays().ln() + t * (b.rays().ln() - a.rays().ln())).exp());
        }
    }
    Reach::Never
}

impl Reach {
    fn rays(self) -> Option<f64> {
        match self {
            Reach::At(r) | Reach::AtMost(r) => Some(r),
            Reach::Never => None,
        }
    }

    /// `rays (×ratio against base)`, `≤` for a bound, `—` for never.
    fn cell(self, base: Option<f64>) -> String {
        let bound = if matches!(self, Reach::AtMost(_)) {
            "≤ "
        } else {
            ""
        };
        match (self.rays(), base) {
            (None, _) => "—".into(),
            (Some(r), Some(b)) => format!("{bound}{r:.2e} ({bound}×{:.2})", r / b),
            (Some(r), None) => format!("{bound}{r:.2e}"),
        }
    }
}

/// Tables, plots, the records' picture and the findings, from every source's runs.
pub(super) fn write_section(
    runner: &Runner,
    name: String,
    references: &References,
    runs: &[Vec<Run>],
) -> Result<Section> {
    let p = &runner.params;
    let (all, front) = front_of(runs);
    let mut table = Table::new(
        &format!(
            "Irradiance caches of `{}` at {}²: records of {} rays, against a {}-ray brute-force image of E (★: on the Pareto front of mean error against rays)",
            runner.scene.name, p.size, p.cache_rays, p.cache_reference_rays
        ),
        &[
            "source",
            "a",
            "records",
            "rays (E + H)",
            "seconds",
            "mean error (%)",
            "p95 error (%)",
            "front",
        ],
    );
    for (i, (s, a)) in all.iter().enumerate() {
        let run = &runs[*s][*a];
        let star = if front.contains(&i) { "★" } else { "" };
        table.push(vec![
            SOURCES[*s].name.into(),
            ACCURACIES[*a].to_string(),
            run.records.to_string(),
            format!("{:.4e}", run.rays()),
            format!("{:.2}", run.seconds),
            format!("{:.2}", 100.0 * run.mean()),
            format!("{:.2}", 100.0 * run.errors.p95_relative_error),
            star.into(),
        ]);
    }
    let mut sources = Table::new(
        "The sources of the records' radii, as `hmdist cache` takes them",
        &["source", "flags"],
    );
    for source in &SOURCES {
        sources.push(vec![source.name.into(), source.flags()]);
    }
    let equal = equal_error_table(runs);
    let mut files = sources.write(&runner.out, "cache_sources")?;
    files.extend(table.write(&runner.out, "cache")?);
    files.extend(equal.write(&runner.out, "cache_equal_error")?);
    // E_ref = 0 wherever the camera sees a surface (a light that reaches none of it): every
    // cache is exact, and a log-log plot of zero errors has nothing to draw.
    let exact = runs
        .iter()
        .flatten()
        .all(|r| r.mean() == 0.0 && r.errors.p95_relative_error == 0.0);
    if !exact {
        files.extend(plots(runner, runs, &all, &front)?);
    }
    files.extend(records_grid(runner)?);
    let mut notes = vec![format!(
        "Error: per pixel |E − E_ref| / max(E_ref, 0.01 · mean E_ref), its mean and 95th percentile over the surface pixels. Cost: the records' gather and shadow rays plus what their H cost beyond them (an estimator's rays, a photon map's paths). The two brute-force images (seeds {REFERENCE_SEED} and {}) differ by {:.2} % mean and {:.2} % p95: the floor under every error. The oracle's H is the experiments' reference image of H. The records pictured (red) at a = {PICTURED_ACCURACY} in cache_records.png.",
        REFERENCE_SEED + 1,
        100.0 * references.noise.mean_relative_error,
        100.0 * references.noise.p95_relative_error
    )];
    if exact {
        notes.push(
            "Every cache here is exact: the reference E is 0 wherever the camera sees a surface (the light reaches none of what it sees), so every error is 0 and no plot is drawn."
                .into(),
        );
    }
    Ok(Section {
        name,
        tables: vec![sources, table, equal],
        files,
        notes,
        findings: match exact {
            true => vec!["Nothing to rank: the light reaches nothing the camera sees (E = 0 there), so every cache is exact, whatever spaces its records. Light a surface the camera sees to compare the sources.".into()],
            false => findings(runs, references, (&all, &front)),
        },
    })
}

/// Every run as (source, accuracy) indices, and the indices into that list on the Pareto
/// front of mean error against rays.
fn front_of(runs: &[Vec<Run>]) -> (Vec<(usize, usize)>, Vec<usize>) {
    let all: Vec<(usize, usize)> = (0..runs.len())
        .flat_map(|s| (0..runs[s].len()).map(move |a| (s, a)))
        .collect();
    let points: Vec<(f64, f64)> = all
        .iter()
        .map(|&(s, a)| (runs[s][a].rays(), runs[s][a].mean()))
        .collect();
    let front = pareto_front(&points);
    (all, front)
}

/// The rays each source needs for the mean errors the records' own H (`hmd`, the first
/// source) reaches at each a, and as a multiple of hmd's.
fn equal_error_table(runs: &[Vec<Run>]) -> Table {
    let targets: Vec<f64> = runs[0].iter().map(Run::mean).collect();
    let mut header = vec!["source".to_string()];
    header.extend(
        ACCURACIES
            .iter()
            .zip(&targets)
            .map(|(a, t)| format!("{:.2} % (hmd's at a = {a})", 100.0 * t)),
    );
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut table = Table::new(
        "Rays each source needs for the mean errors the records' own H reaches (log-log between its runs; ≤: its cheapest run is better already; —: no a reaches it), and the multiple of hmd's",
        &header,
    );
    for (s, source) in SOURCES.iter().enumerate() {
        let mut row = vec![source.name.to_string()];
        for &t in &targets {
            row.push(rays_to_reach(&runs[s], t).cell(rays_to_reach(&runs[0], t).rays()));
        }
        table.push(row);
    }
    table
}

/// `cache.svg` and `cache_p95.svg`: each source's error against rays, the front labelled.
fn plots(
    runner: &Runner,
    runs: &[Vec<Run>],
    all: &[(usize, usize)],
    front: &[usize],
) -> Result<Vec<PathBuf>> {
    let mut files = vec![];
    for (file, label, error) in [
        ("cache.svg", "mean", (|r: &Run| r.mean()) as fn(&Run) -> f64),
        ("cache_p95.svg", "p95", |r: &Run| r.errors.p95_relative_error),
    ] {
        let series: Vec<Series> = SOURCES
            .iter()
            .zip(runs)
            .map(|(source, mine)| Series {
                label: source.name.into(),
                points: mine.iter().map(|r| (r.rays(), 100.0 * error(r))).collect(),
            })
            .collect();
        let marks: Vec<(&Series, Marks)> = series.iter().zip(source_marks()).collect();
        // The front of mean error, labelled where it passes to another source.
        let labelled: Vec<(f64, f64, String)> = front
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let (s, a) = all[i];
                // Labelled where a source first reaches the front: fewer labels to pile up.
                let changes = !front[..k].iter().any(|&j| all[j].0 == s);
                let text = if changes {
                    format!("{}, a = {}", SOURCES[s].name, ACCURACIES[a])
                } else {
                    String::new()
                };
                (runs[s][a].rays(), 100.0 * error(&runs[s][a]), text)
            })
            .collect();
        let path = runner.out.join(file);
        let title = format!(
            "{}: {label} relative error of the cached E against rays",
            runner.scene.name
        );
        let front_drawn: &[(f64, f64, String)] = if label == "mean" { &labelled } else { &[] };
        log_log_with(
            &path,
            &title,
            "rays (records' E + H)",
            &format!("{label} error (%)"),
            &marks,
            front_drawn,
        )?;
        files.push(path);
    }
    Ok(files)
}

/// How each source is drawn: those with neighbour clamping hollow and dashed, in the colour
/// of the same spacing and clamps without it; the others solid, each its own colour.
fn source_marks() -> Vec<Marks> {
    let solid: Vec<&str> = SOURCES
        .iter()
        .filter(|s| !s.neighbour_clamp)
        .map(|s| s.name)
        .collect();
    let place = |name: &str| solid.iter().position(|&n| n == name).expect("a solid source");
    SOURCES
        .iter()
        .map(|s| match s.neighbour_clamp {
            false => Marks::LINE.coloured(place(s.name)),
            true => {
                let plain = SOURCES.iter().find(|t| {
                    !t.neighbour_clamp
                        && !t.gradients
                        && (t.spacing, t.clamp_pixels, t.clamp_scene)
                            == (s.spacing, s.clamp_pixels, s.clamp_scene)
                });
                Marks::HOLLOW.coloured(place(plain.map_or(SOURCES[0].name, |t| t.name)))
            }
        })
        .collect()
}

/// `cache_records.png`: the pictured sources' records at [`PICTURED_ACCURACY`], side by side,
/// captioned.
fn records_grid(runner: &Runner) -> Result<Option<PathBuf>> {
    let folder = runner.out.join("cache-irradiance");
    let tiles: Vec<(&str, RgbImage)> = SOURCES
        .iter()
        .filter(|s| s.pictured)
        .filter_map(|s| {
            Some((
                s.name,
                image::open(folder.join(format!("{}.png", s.name)))
                    .ok()?
                    .to_rgb8(),
            ))
        })
        .collect();
    let Some((_, first)) = tiles.first() else {
        return Ok(None);
    };
    let (w, h) = first.dimensions();
    let (caption, gap, columns) = (20, 6, 3.min(tiles.len()) as u32);
    let rows = (tiles.len() as u32).div_ceil(columns);
    let mut grid = RgbImage::from_pixel(
        gap + columns * (w + gap),
        gap + rows * (h + caption + gap),
        Rgb([255; 3]),
    );
    for (i, (name, tile)) in tiles.iter().enumerate() {
        let (x, y) = (
            gap + (i as u32 % columns) * (w + gap),
            gap + (i as u32 / columns) * (h + caption + gap),
        );
        draw_text(&mut grid, x, y + 4, name, 1 + w / 512, Rgb([0; 3]));
        image::imageops::replace(&mut grid, tile, x as i64, (y + caption) as i64);
    }
    let path = runner.out.join("cache_records.png");
    write_atomically(&path, &encode_png(&grid, &path)?)?;
    Ok(Some(path))
}

/// The runs the findings read, by source name.
struct Reading<'a> {
    runs: &'a [Vec<Run>],
}

impl Reading<'_> {
    fn of(&self, name: &str) -> &[Run] {
        &self.runs[SOURCES.iter().position(|s| s.name == name).expect("a source")]
    }

    /// The rays `name` needs for the mean errors the records' own H reaches at each a, as
    /// multiples of H's: only where both reach the error between two of their runs.
    fn ratios(&self, name: &str) -> Vec<f64> {
        let reached = |runs: &[Run], t| match rays_to_reach(runs, t) {
            Reach::At(r) => Some(r),
            _ => None,
        };
        let hmd = &self.runs[0];
        hmd.iter()
            .filter_map(|t| Some(reached(self.of(name), t.mean())? / reached(hmd, t.mean())?))
            .collect()
    }

    /// [`Reading::ratios`] of `name` as `×lo–hi`.
    fn span(&self, name: &str) -> String {
        let v = self.ratios(name);
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        match v.len() {
            0 => "— (no error in common)".into(),
            _ if lo == hi => format!("×{lo:.2}"),
            _ => format!("×{lo:.2}–{hi:.2}"),
        }
    }

    /// The fewest and most records `name` made.
    fn records(&self, name: &str) -> String {
        let r: Vec<usize> = self.of(name).iter().map(|r| r.records).collect();
        format!(
            "{}–{}",
            r.iter().min().unwrap_or(&0),
            r.iter().max().unwrap_or(&0)
        )
    }

    /// `name`'s cheapest cache: its rays and mean error.
    fn cheapest_run(&self, name: &str) -> Option<&Run> {
        self.of(name).iter().min_by(|a, b| a.rays().total_cmp(&b.rays()))
    }

    /// `name`'s cheapest cache as `rays for error`.
    fn cheapest_cost(&self, name: &str) -> String {
        self.cheapest_run(name).map_or("—".into(), |c| {
            format!("{:.2e} rays for {:.2} %", c.rays(), 100.0 * c.mean())
        })
    }

    /// [`Reading::cheapest_cost`] and its multiple of the rays the records' own H needs for
    /// its error (`≥` where H's cheapest is better already).
    fn cheapest(&self, name: &str) -> String {
        let Some(cheapest) = self.cheapest_run(name) else {
            return "—".into();
        };
        let against = match rays_to_reach(&self.runs[0], cheapest.mean()) {
            Reach::At(r) => format!("×{:.2} of H's", cheapest.rays() / r),
            Reach::AtMost(r) => format!("≥ ×{:.2} of H's", cheapest.rays() / r),
            Reach::Never => "no cache of H is as good".into(),
        };
        format!("{} ({against})", self.cheapest_cost(name))
    }

    /// The Pareto front (`front`, indices into `all`) in words: each source on it (in the
    /// order it first appears, by rays) with its points' count, rays and mean errors.
    fn front(&self, all: &[(usize, usize)], front: &[usize]) -> String {
        let mut sources: Vec<(usize, Vec<&Run>)> = vec![];
        for &(s, a) in front.iter().map(|&i| &all[i]) {
            match sources.iter_mut().find(|(source, _)| *source == s) {
                Some((_, points)) => points.push(&self.runs[s][a]),
                None => sources.push((s, vec![&self.runs[s][a]])),
            }
        }
        let words: Vec<String> = sources
            .iter()
            .map(|(s, points)| {
                let (first, last) = (points[0], points[points.len() - 1]);
                match points.len() {
                    1 => format!(
                        "{} once ({:.1e} rays, {:.2} %)",
                        SOURCES[*s].name,
                        first.rays(),
                        100.0 * first.mean()
                    ),
                    n => format!(
                        "{} {n} times ({:.1e}–{:.1e} rays, {:.2}–{:.2} %)",
                        SOURCES[*s].name,
                        first.rays(),
                        last.rays(),
                        100.0 * first.mean(),
                        100.0 * last.mean()
                    ),
                }
            })
            .collect();
        words.join("; ")
    }
}

/// The study's answers, each with the numbers that decide it.
fn findings(
    runs: &[Vec<Run>],
    references: &References,
    (all, front): (&[(usize, usize)], &[usize]),
) -> Vec<String> {
    let reading = Reading { runs };
    let better = reading.ratios("oracle").iter().any(|&r| r < 0.9);
    let pictured = ACCURACIES
        .iter()
        .position(|&a| a == PICTURED_ACCURACY)
        .expect("pictured a");
    let at = |name: &str| &reading.of(name)[pictured];
    let best = runs.iter().flatten().map(Run::mean).fold(f64::INFINITY, f64::min);
    vec![
        format!(
            "Does a more accurate H make a better cache at equal cost? {}: the oracle's H needs {} of the records' own H's rays for the errors that H reaches (gather64 {}, cube map {}, photon I {}, photon II {}).",
            if better { "Yes, somewhat" } else { "No" },
            reading.span("oracle"),
            reading.span("gather64"),
            reading.span("cubemap"),
            reading.span("photon1"),
            reading.span("photon2")
        ),
        format!(
            "The renderers' nearest-hit rules and their clamps make many records: pbrt-v2's {}, Mitsuba's min10 {} (H: {}, its cheapest cache {}). pbrt-v2's cheapest cache: {}; min10's: {}; Mitsuba's whole cache (min10, clamps, neighbour clamping, gradients): {}; the same with H as its radius (hmd-mitsuba): {}.",
            reading.records("pbrt-v2"),
            reading.records("min10-clamped"),
            reading.records("hmd"),
            reading.cheapest_cost("hmd"),
            reading.cheapest("pbrt-v2"),
            reading.cheapest("min10-clamped"),
            reading.cheapest("mitsuba"),
            reading.cheapest("hmd-mitsuba")
        ),
        format!(
            "What the production options buy H: at a = {PICTURED_ACCURACY} Ward and Heckbert's gradients take the mean error from {:.2} % to {:.2} % with the same records (the rays for each of H's errors: {} of H's); neighbour clamping to {:.2} % with {} records against {}.",
            100.0 * at("hmd").mean(),
            100.0 * at("hmd-gradients").mean(),
            reading.span("hmd-gradients"),
            100.0 * at("hmd-neighbours").mean(),
            at("hmd-neighbours").records,
            at("hmd").records
        ),
        format!("Which spacing wins (the Pareto front of mean error against rays): {}.", reading.front(all, front)),
        format!(
            "The floor: the best cache errs by {:.2} % on average; two brute-force images differ by {:.2} % (p95 {:.2} %), so where the two are close the figures rank the sources only coarsely.",
            100.0 * best,
            100.0 * references.noise.mean_relative_error,
            100.0 * references.noise.p95_relative_error
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::CacheErrors;

    fn run(rays: f64, mean: f64) -> Run {
        Run {
            records: 0,
            rays_e: rays as u64,
            rays_h: 0,
            seconds: 0.0,
            errors: CacheErrors {
                path: String::new(),
                mean_relative_error: mean,
                p95_relative_error: mean,
                pixels: 1,
            },
        }
    }

    #[test]
    fn rays_to_reach_an_error_interpolate_log_log_and_say_when_they_are_a_bound() {
        let runs = [run(100.0, 0.08), run(400.0, 0.02), run(1600.0, 0.01)];
        // 0.04 is halfway (in logs) from 0.08 to 0.02: halfway from 100 to 400 rays.
        let Reach::At(r) = rays_to_reach(&runs, 0.04) else {
            panic!()
        };
        assert!((r - 200.0).abs() < 1e-9, "{r}");
        assert_eq!(rays_to_reach(&runs, 0.1), Reach::AtMost(100.0));
        assert_eq!(rays_to_reach(&runs, 0.001), Reach::Never);
        assert_eq!(Reach::AtMost(100.0).cell(Some(50.0)), "≤ 1.00e2 (≤ ×2.00)");
    }

    #[test]
    fn every_source_parses_and_the_records_own_h_comes_first() {
        assert_eq!(SOURCES[0].spacing, "hmd");
        for source in &SOURCES {
            source.params(16, 0.2).unwrap();
        }
        let names: std::collections::BTreeSet<&str> = SOURCES.iter().map(|s| s.name).collect();
        assert_eq!(names.len(), SOURCES.len());
    }
}
