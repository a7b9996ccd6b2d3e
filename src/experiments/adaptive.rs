//! The adaptive study (issues #12 and #25; the paper's future work: how many rays does a
//! pixel need?): f_diff and the 95th percentile of the relative error `|ΔH| / H` (the
//! accuracy a record-spacing cache feels) against the rays cast, for a fixed N per pixel
//! (the grid and the progressive sampler) and for three adaptive schemes at several
//! tolerances, with the rays the best fixed N needs for the same error.

use super::plot::{log_log, Series};
use super::rays::reference;
use super::runner::Runner;
use super::section::Section;
use super::table::Table;
use crate::error::Result;
use crate::estimators::{AdaptiveParams, Aov, GatherParams};
use crate::image::picture::{encode_png, false_colour_scaled, ColourScale};
use crate::image::{write_atomically, HmdImage};
use crate::metrics::f_diff;
use crate::sampling::Sampler;

/// Relative tolerances, loosest first.
pub const TOLERANCES: [f32; 5] = [0.2, 0.1, 0.05, 0.025, 0.0125];
/// Absolute tolerances in units of the scene's diagonal, loosest first.
pub const ABS_TOLERANCES: [f32; 5] = [0.004, 0.002, 0.001, 0.0005, 0.00025];

/// An adaptive scheme of the study: a sampler, a kind of tolerance, its loosening and first
/// check.
struct Scheme {
    name: &'static str,
    sampler: Sampler,
    absolute: bool,
    loosen: f32,
    min_rays: u32,
}

/// The schemes, the one before issue #25 first: its first check is 8 rounds of 16 rays
/// (smaller grids lose more of one grid's accuracy); sobol blocks lose nothing by being
/// small, so theirs is 8 of 8. The loosening of each is the one measured best for its error
/// (README): 0.5 for the 95th percentile of |ΔH|/H, 1 (the least mean error per ray) for
/// f_diff.
const SCHEMES: [Scheme; 3] = [
    Scheme {
        name: "grid rounds of 16 · relative T",
        sampler: Sampler::Grid,
        absolute: false,
        loosen: 0.0,
        min_rays: 128,
    },
    Scheme {
        name: "sobol blocks of 8 · relative T · loosen 0.5",
        sampler: Sampler::Sobol,
        absolute: false,
        loosen: 0.5,
        min_rays: 64,
    },
    Scheme {
        name: "sobol blocks of 8 · absolute A · loosen 1",
        sampler: Sampler::Sobol,
        absolute: true,
        loosen: 1.0,
        min_rays: 64,
    },
];

impl Scheme {
    fn tolerances(&self) -> [f32; 5] {
        if self.absolute {
            ABS_TOLERANCES
        } else {
            TOLERANCES
        }
    }

    /// Its configuration at `tolerance`, up to the preset's largest fixed N.
    fn config(&self, runner: &Runner, tolerance: f32) -> AdaptiveParams {
        let (tolerance, abs_tolerance) = match self.absolute {
            true => (0.0, tolerance),
            false => (tolerance, 0.0),
        };
        AdaptiveParams {
            sampler: self.sampler,
            tolerance,
            abs_tolerance,
            loosen: self.loosen,
            min_rays: self.min_rays,
            max_rays: *runner.params.rays.last().expect("a ray sweep"),
            ..AdaptiveParams::default()
        }
    }
}

/// One image of the study: its mean rays per surface pixel, f_diff and the 95th percentile
/// of the relative error.
struct Point {
    rays: f64,
    f_diff: f64,
    p95: f64,
}

/// The 95th percentile of `|H − H_ref| / H_ref` over pixels finite in both.
fn relative_error_p95(reference: &HmdImage, image: &HmdImage) -> f64 {
    let mut e: Vec<f64> = reference
        .data
        .iter()
        .zip(&image.data)
        .filter(|(r, h)| r.is_finite() && h.is_finite() && **r > 0.0)
        .map(|(r, h)| ((h - r) / r).abs() as f64)
        .collect();
    if e.is_empty() {
        return f64::NAN;
    }
    let at = (e.len() * 95 / 100).min(e.len() - 1);
    *e.select_nth_unstable_by(at, f64::total_cmp).1
}

/// Rays a fixed N would need for error `target` by `error`, interpolated log-log along
/// `fixed` (sorted by rays); `None` outside its range.
fn fixed_rays_for(fixed: &[Point], error: fn(&Point) -> f64, target: f64) -> Option<f64> {
    fixed.windows(2).find_map(|w| {
        let (a, b) = (error(&w[0]), error(&w[1]));
        let (hi, lo) = (a.max(b), a.min(b));
        if !(lo..=hi).contains(&target) || a == b {
            return None;
        }
        let t = (target.ln() - a.ln()) / (b.ln() - a.ln());
        Some((w[0].rays.ln() + t * (w[1].rays.ln() - w[0].rays.ln())).exp())
    })
}

/// The fewest rays either fixed-N sweep needs for `target`, and which sampler that is.
fn best_fixed(
    sweeps: &[(Sampler, Vec<Point>)],
    error: fn(&Point) -> f64,
    target: f64,
) -> Option<(f64, Sampler)> {
    sweeps
        .iter()
        .filter_map(|(sampler, fixed)| fixed_rays_for(fixed, error, target).map(|r| (r, *sampler)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The study's figures of one image against the reference.
fn point(
    reference: &HmdImage,
    image: &HmdImage,
    report: &crate::report::RenderReport,
    l_diag: f32,
) -> Result<Point> {
    let surface = (report.width * report.height) as usize - report.background_pixels;
    Ok(Point {
        rays: report.rays_cast.unwrap_or(0) as f64 / surface.max(1) as f64,
        f_diff: f_diff(reference, image, l_diag)?.value,
        p95: relative_error_p95(reference, image),
    })
}

/// f_diff and p95 against rays, fixed N against adaptive, with the savings at equal error.
pub fn adaptive(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let reference = reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let sweeps = fixed_sweeps(runner, &reference, l_diag)?;
    let mut table = Table::new(
        &format!(
            "Adaptive gathering (preset {}): f_diff against gather with {} rays, {}², `{}`; at most {} rays; the best fixed N of the grid and the sobol sampler",
            runner.preset.name(),
            p.reference_rays,
            p.size,
            runner.scene.name,
            p.rays.last().expect("a ray sweep")
        ),
        &[
            "scheme",
            "tolerance",
            "rays/pixel",
            "f_diff",
            "best fixed N at this f_diff",
            "saving",
            "p95 |ΔH|/H",
            "best fixed N at this p95",
            "saving",
        ],
    );
    let mut series = vec![];
    let mut notes = vec![];
    let fixed_cell = |v: Option<(f64, Sampler)>| {
        v.map_or("outside the sweeps".into(), |(r, s)| {
            format!("{r:.1} ({})", s.name())
        })
    };
    let saving =
        |v: Option<(f64, Sampler)>, rays: f64| v.map_or("".into(), |(r, _)| format!("×{:.2}", r / rays));
    for scheme in &SCHEMES {
        let mut points = vec![];
        let (mut savings, mut p95_savings) = (vec![], vec![]);
        for tolerance in scheme.tolerances() {
            // With the rays AOV, so that the picture of rays per pixel comes from the cache.
            let config = scheme.config(runner, tolerance);
            let (image, report, _) = runner.method_image_with("adaptive", &config, 1, &[Aov::Rays])?;
            let point = point(&reference, &image, &report, l_diag)?;
            let fixed_rays = best_fixed(&sweeps, |p| p.f_diff, point.f_diff);
            let fixed_p95 = best_fixed(&sweeps, |p| p.p95, point.p95);
            savings.extend(fixed_rays.map(|(r, _)| r / point.rays));
            p95_savings.extend(fixed_p95.map(|(r, _)| r / point.rays));
            table.push(vec![
                scheme.name.to_string(),
                tolerance.to_string(),
                format!("{:.1}", point.rays),
                format!("{:.4}", point.f_diff),
                fixed_cell(fixed_rays),
                saving(fixed_rays, point.rays),
                format!("{:.4}", point.p95),
                fixed_cell(fixed_p95),
                saving(fixed_p95, point.rays),
            ]);
            points.push(point);
        }
        notes.push(format!(
            "{}: rays saved against the best fixed N at equal f_diff, tolerance by tolerance: {}; at an equal 95th percentile of |ΔH|/H: {} (a saving below ×1 is a cost).",
            scheme.name,
            list(&savings),
            list(&p95_savings)
        ));
        series.push((scheme.name, points));
    }
    let mut files = table.write(&runner.out, "adaptive")?;
    files.extend(plots(runner, &sweeps, &series)?);
    files.push(rays_picture(runner)?);
    notes.push(
        "How many rays does a pixel need (the paper's question)? A relative tolerance stops each pixel at a relative error, which is what a record-spacing cache feels; f_diff averages absolute errors, dominated by open regions with large H, which an absolute tolerance (in units of l_diag, f_diff's unit) aims at. Grid rounds are independent small grids and lose part of one grid's stratification; sobol blocks are one progressive sequence, so a pixel that stops at N rays has the H of gather --sampler sobol --rays N. The rays per pixel are in adaptive_rays.png.".into(),
    );
    Ok(Section {
        name: "adaptive".into(),
        tables: vec![table],
        files,
        notes,
        ..Section::default()
    })
}

/// Fixed N over the preset's ray sweep, with the grid and with the sobol sampler.
fn fixed_sweeps(runner: &Runner, reference: &HmdImage, l_diag: f32) -> Result<Vec<(Sampler, Vec<Point>)>> {
    let p = &runner.params;
    let mut sweeps = vec![];
    for sampler in [Sampler::Grid, Sampler::Sobol] {
        let mut fixed = vec![];
        for &rays in &p.rays {
            let config = GatherParams {
                rays,
                sampler,
                ..GatherParams::default()
            };
            let (image, report) = runner.method_image("gather", &config, 1)?;
            fixed.push(point(reference, &image, &report, l_diag)?);
        }
        sweeps.push((sampler, fixed));
    }
    Ok(sweeps)
}

/// `adaptive.svg` and `adaptive_p95.svg`: f_diff and p95 against the mean rays per pixel,
/// fixed N against each adaptive scheme.
fn plots(
    runner: &Runner,
    sweeps: &[(Sampler, Vec<Point>)],
    series: &[(&str, Vec<Point>)],
) -> Result<Vec<std::path::PathBuf>> {
    let mut files = vec![];
    let plot = runner.out.join("adaptive.svg");
    let mut curves: Vec<(String, &[Point])> = sweeps
        .iter()
        .map(|(s, fixed)| (format!("fixed N, {}", s.name()), fixed.as_slice()))
        .collect();
    curves.extend(
        series
            .iter()
            .map(|(name, points)| (format!("adaptive, {name}"), points.as_slice())),
    );
    let plot_of = |error: fn(&Point) -> f64| -> Vec<Series> {
        curves
            .iter()
            .map(|(label, points)| Series {
                label: label.clone(),
                points: points.iter().map(|p| (p.rays, error(p))).collect(),
            })
            .collect()
    };
    log_log(
        &plot,
        "f_diff against rays cast",
        "rays per pixel (mean)",
        "f_diff (% of l_diag)",
        &plot_of(|p| p.f_diff),
    )?;
    files.push(plot);
    let plot = runner.out.join("adaptive_p95.svg");
    log_log(
        &plot,
        "95th percentile of |ΔH|/H against rays cast",
        "rays per pixel (mean)",
        "p95 |ΔH|/H",
        &plot_of(|p| p.p95),
    )?;
    files.push(plot);
    Ok(files)
}

/// Savings as `×a, ×b, …`.
fn list(v: &[f64]) -> String {
    if v.is_empty() {
        "none measured (outside the fixed-N sweeps)".to_string()
    } else {
        v.iter()
            .map(|s| format!("×{s:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A false-colour picture of the rays the sobol relative scheme casts per pixel at the middle
/// tolerance (its image, with the rays AOV, is one of the study's: cached).
fn rays_picture(runner: &Runner) -> Result<std::path::PathBuf> {
    let tolerance = TOLERANCES[TOLERANCES.len() / 2];
    let config = SCHEMES[1].config(runner, tolerance);
    let (_, _, aovs) = runner.method_image_with("adaptive", &config, 1, &[Aov::Rays])?;
    let size = runner.params.size;
    let label = format!("rays, tolerance {tolerance}");
    let picture = false_colour_scaled(&aovs[0].data, size, size, &label, ColourScale::Log);
    let path = runner.out.join("adaptive_rays.png");
    write_atomically(&path, &encode_png(&picture, &path)?)?;
    Ok(path)
}
