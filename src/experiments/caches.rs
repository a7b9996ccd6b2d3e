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

use std::path::PathBuf;

use image::{Rgb, RgbImage};
use serde::{Deserialize, Serialize};

use super::cost::pareto_front;
use super::plot::{log_log_with, Marks, Series};
use super::presets::REFERENCE_SEED;
use super::rays::reference;
use super::runner::Runner;
use super::section::Section;
use super::table::Table;
use crate::cache::{cache, relative_errors, CacheErrors, CacheParams, Range, Spacing};
use crate::error::{Error, Result};
use crate::estimators::irradiance::display_scale;
use crate::estimators::IrradianceParams;
use crate::image::picture::{draw_text, encode_png};
use crate::image::{write_atomically, HmdImage};
use crate::progress::Silent;

/// Ward's a of every source, coarsest first.
pub const ACCURACIES: [f32; 6] = [0.4, 0.3, 0.2, 0.15, 0.1, 0.05];
/// The accuracy whose records are pictured.
const PICTURED_ACCURACY: f32 = 0.2;
/// The seed of the caches' records.
const SEED: u64 = 1;

/// One way to space the records.
struct Source {
    name: &'static str,
    /// `--spacing`.
    spacing: &'static str,
    clamp_pixels: Option<(f32, f32)>,
    clamp_scene: Option<(f32, f32)>,
    neighbour_clamp: bool,
    gradients: bool,
    /// Pictured at [`PICTURED_ACCURACY`].
    pictured: bool,
}

/// pbrt-v2's clamp in pixel footprints; Mitsuba 0.6's, and its clamp in fractions of l_diag.
const PBRT_PIXELS: Option<(f32, f32)> = Some((2.5, 15.0));
const MITSUBA_PIXELS: Option<(f32, f32)> = Some((3.0, 20.0));
const MITSUBA_SCENE: Option<(f32, f32)> = Some((0.005, 0.32));

const fn source(name: &'static str, spacing: &'static str) -> Source {
    Source {
        name,
        spacing,
        clamp_pixels: None,
        clamp_scene: None,
        neighbour_clamp: false,
        gradients: false,
        pictured: false,
    }
}

/// Mitsuba 0.6's clamps, neighbour clamping and gradients (its defaults) with `spacing`.
const fn mitsuba(name: &'static str, spacing: &'static str) -> Source {
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        neighbour_clamp: true,
        gradients: true,
        pictured: true,
        ..source(name, spacing)
    }
}

/// The sources, the records' own H first (the others are measured against it).
const SOURCES: [Source; 13] = [
    Source {
        pictured: true,
        ..source("hmd", "hmd")
    },
    Source {
        pictured: true,
        ..source("oracle", "oracle")
    },
    source("gather64", "hmd:gather:rays=64,backend=cpu"),
    source("cubemap", "hmd:cubemap:cube_res=16,rays=256,backend=cpu"),
    source("photon1", "hmd:photon1:photons=200000,nearest=64"),
    Source {
        pictured: true,
        ..source("photon2", "hmd:photon2:photons=200000,nearest=64")
    },
    Source {
        clamp_pixels: PBRT_PIXELS,
        pictured: true,
        ..source("pbrt-v2", "min")
    },
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        ..source("min10-clamped", "min10")
    },
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        ..source("hmd-clamped", "hmd")
    },
    Source {
        gradients: true,
        ..source("hmd-gradients", "hmd")
    },
    Source {
        neighbour_clamp: true,
        ..source("hmd-neighbours", "hmd")
    },
    mitsuba("mitsuba", "min10"),
    mitsuba("hmd-mitsuba", "hmd"),
];

/// How many caches the study makes: the progress bar's share.
pub const CACHES: usize = SOURCES.len() * ACCURACIES.len();

impl Source {
    /// `--spacing` and the options that differ from the defaults, as the CLI takes them.
    fn flags(&self) -> String {
        let mut flags = vec![format!("--spacing {}", self.spacing)];
        let range = |(lo, hi): (f32, f32)| format!("{lo},{hi}");
        flags.extend(self.clamp_pixels.map(|r| format!("--clamp-pixels {}", range(r))));
        flags.extend(self.clamp_scene.map(|r| format!("--clamp-scene {}", range(r))));
        flags.extend(self.neighbour_clamp.then(|| "--neighbour-clamp".to_string()));
        flags.extend(self.gradients.then(|| "--gradients".to_string()));
        flags.join(" ")
    }

    fn params(&self, rays: u32, accuracy: f32) -> Result<CacheParams> {
        let range = |(lo, hi): (f32, f32)| Range { lo, hi };
        Ok(CacheParams {
            irradiance: IrradianceParams {
                rays,
                ..IrradianceParams::default()
            },
            accuracy,
            spacing: Spacing::parse(self.spacing)?,
            clamp_pixels: self.clamp_pixels.map(range),
            clamp_scene: self.clamp_scene.map(range),
            neighbour_clamp: self.neighbour_clamp,
            gradients: self.gradients,
        })
    }
}

/// What one cache cost and how far it is from the brute-force image.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Run {
    records: usize,
    rays_e: u64,
    rays_h: u64,
    seconds: f64,
    errors: CacheErrors,
}

impl Run {
    fn rays(&self) -> f64 {
        (self.rays_e + self.rays_h) as f64
    }
    fn mean(&self) -> f64 {
        self.errors.mean_relative_error
    }
}

/// The references the caches are measured against, and what they say of themselves.
struct References {
    e: HmdImage,
    h: HmdImage,
    /// The second brute-force image against the first: the floor under every error.
    noise: CacheErrors,
    /// Digest of both images' bits: part of each cache's key.
    digest: u64,
}

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
        let mut cached = cache(&self.scene, &params, &options, oracle, &Silent)?;
        let (_, errors) = relative_errors(&cached.image, &references.e, "the first reference")?;
        cached.report.reference = Some(errors.clone());
        let run = Run {
            records: cached.records.len(),
            rays_e: cached.report.rays_e,
            rays_h: cached.report.rays_h,
            seconds: cached.report.seconds.total,
            errors,
        };
        std::fs::create_dir_all(&folder).map_err(|e| Error::io(&folder, "create the folder", e))?;
        if source.pictured && a == PICTURED_ACCURACY {
            let picture = records_picture(&cached, self.scene.diagonal());
            let path = folder.join(format!("{}.png", source.name));
            write_atomically(&path, &encode_png(&picture, &path)?)?;
        }
        let text = serde_json::to_string_pretty(&run).expect("a run serialises");
        write_atomically(&json, text.as_bytes())?;
        Ok(run)
    }
}

/// E in grey at the irradiance's display scale, each record's pixel red.
fn records_picture(cached: &crate::cache::Cached, l_diag: f32) -> RgbImage {
    let grey = crate::image::picture::grey(&cached.image, display_scale(l_diag));
    let mut picture = image::DynamicImage::ImageLuma8(grey).to_rgb8();
    for record in &cached.records {
        let w = cached.image.width;
        picture.put_pixel(record.pixel % w, record.pixel / w, Rgb([230, 30, 30]));
    }
    picture
}

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
            (Some(r), Some(b)) => format!("{bound}{r:.3e} (×{bound}{:.2})", r / b),
            (Some(r), None) => format!("{bound}{r:.3e}"),
        }
    }
}

/// Tables, plots, the records' picture and the findings, from every source's runs.
fn write_section(
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
            "flags",
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
            SOURCES[*s].flags(),
        ]);
    }
    let equal = equal_error_table(runs);
    let mut files = table.write(&runner.out, "cache")?;
    files.extend(equal.write(&runner.out, "cache_equal_error")?);
    files.extend(plots(runner, runs, &all, &front)?);
    files.extend(records_grid(runner)?);
    let notes = vec![format!(
        "Error: per pixel |E − E_ref| / max(E_ref, 0.01 · mean E_ref), its mean and 95th percentile over the surface pixels. Cost: the records' gather and shadow rays plus what their H cost beyond them (an estimator's rays, a photon map's paths). The two brute-force images (seeds {REFERENCE_SEED} and {}) differ by {:.2} % mean and {:.2} % p95: the floor under every error. The oracle's H is the experiments' reference image of H. Flags as `hmdist cache` takes them; the records pictured (red) at a = {PICTURED_ACCURACY} in cache_records.png.",
        REFERENCE_SEED + 1,
        100.0 * references.noise.mean_relative_error,
        100.0 * references.noise.p95_relative_error
    )];
    Ok(Section {
        name,
        tables: vec![table, equal],
        files,
        notes,
        findings: findings(runs, references),
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
        let marks: Vec<(&Series, Marks)> = series
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (
                    s,
                    if i < 10 { Marks::LINE } else { Marks::HOLLOW }.coloured(i % 10),
                )
            })
            .collect();
        // The front of mean error, labelled where it passes to another source.
        let labelled: Vec<(f64, f64, String)> = front
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let (s, a) = all[i];
                let changes = k == 0 || all[front[k - 1]].0 != s;
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

/// The study's answers, each with the numbers that decide it.
fn findings(runs: &[Vec<Run>], references: &References) -> Vec<String> {
    let index = |name: &str| SOURCES.iter().position(|s| s.name == name).expect("a source");
    let targets: Vec<f64> = runs[0].iter().map(Run::mean).collect();
    // Only where both reach the error between two of their runs (not a bound).
    let ratios = |name: &str| -> Vec<f64> {
        let mine = &runs[index(name)];
        let reached = |runs: &[Run], t| match rays_to_reach(runs, t) {
            Reach::At(r) => Some(r),
            _ => None,
        };
        targets
            .iter()
            .filter_map(|&t| Some(reached(mine, t)? / reached(&runs[0], t)?))
            .collect()
    };
    let span = |v: &[f64]| match (
        v.iter().copied().reduce(f64::min),
        v.iter().copied().reduce(f64::max),
    ) {
        (Some(lo), Some(hi)) => format!("×{lo:.2}–{hi:.2}"),
        _ => "— (no common error)".into(),
    };
    let oracle = ratios("oracle");
    let better = oracle.iter().any(|&r| r < 0.9);
    let records = |name: &str| {
        let r: Vec<usize> = runs[index(name)].iter().map(|r| r.records).collect();
        format!(
            "{}–{}",
            r.iter().min().unwrap_or(&0),
            r.iter().max().unwrap_or(&0)
        )
    };
    let pictured = ACCURACIES
        .iter()
        .position(|&a| a == PICTURED_ACCURACY)
        .expect("pictured a");
    let at = |name: &str| 100.0 * runs[index(name)][pictured].mean();
    let best = runs.iter().flatten().map(Run::mean).fold(f64::INFINITY, f64::min);
    vec![
        format!(
            "Does a more accurate H make a better cache at equal cost? {}: the oracle's H needs {} of the records' own H's rays for the errors that H reaches (gather64 {}, cube map {}, photon I {}, photon II {}).",
            if better { "Yes, somewhat" } else { "No" },
            span(&oracle),
            span(&ratios("gather64")),
            span(&ratios("cubemap")),
            span(&ratios("photon1")),
            span(&ratios("photon2"))
        ),
        format!(
            "The renderers' nearest-hit rules against H: pbrt-v2's makes {} records, Mitsuba's min10 with its clamps {}, H {}; for H's errors they need {} and {} of H's rays; Mitsuba's whole cache (min10, clamps, neighbour clamping, gradients) {}, and the same with H as the radius (hmd-mitsuba) {}.",
            records("pbrt-v2"),
            records("min10-clamped"),
            records("hmd"),
            span(&ratios("pbrt-v2")),
            span(&ratios("min10-clamped")),
            span(&ratios("mitsuba")),
            span(&ratios("hmd-mitsuba"))
        ),
        format!(
            "What the production options buy H: at a = {PICTURED_ACCURACY} Ward and Heckbert's gradients take the mean error from {:.2} % to {:.2} % with the same records; neighbour clamping to {:.2} % with more records ({} against {}).",
            at("hmd"),
            at("hmd-gradients"),
            at("hmd-neighbours"),
            runs[index("hmd-neighbours")][pictured].records,
            runs[0][pictured].records
        ),
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
        assert_eq!(Reach::AtMost(100.0).cell(Some(50.0)), "≤ 1.000e2 (×≤ 2.00)");
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
