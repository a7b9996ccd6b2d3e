//! The adaptive study (issue #12; the paper's future work: how many rays does a pixel need?):
//! f_diff against the rays cast, for a fixed N per pixel and for adaptive gathering at
//! several tolerances, and the rays saved at equal f_diff; and the same for the 95th
//! percentile of the relative error `|ΔH| / H`, the accuracy a record-spacing cache feels,
//! which adaptive's relative tolerance aims at.

use super::plot::{log_log, Series};
use super::rays::reference;
use super::{Runner, Section, Table};
use crate::error::Result;
use crate::estimators::{AdaptiveParams, Aov, GatherParams};
use crate::image::picture::{encode_png, false_colour};
use crate::image::{write_atomically, HmdImage};
use crate::metrics::f_diff;

/// Adaptive's tolerances, loosest first.
pub const TOLERANCES: [f32; 5] = [0.2, 0.1, 0.05, 0.025, 0.0125];
/// Adaptive's first check: 8 rounds of 16 rays (smaller rounds lose more of the stratified
/// grid's accuracy).
const MIN_RAYS: u32 = 128;

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

/// The configuration of adaptive at `tolerance`, up to the preset's largest fixed N.
fn adaptive_config(runner: &Runner, tolerance: f32) -> AdaptiveParams {
    AdaptiveParams {
        tolerance,
        min_rays: MIN_RAYS,
        max_rays: *runner.params.rays.last().expect("a ray sweep"),
        ..AdaptiveParams::default()
    }
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

/// f_diff against rays, fixed N against adaptive, with the saving at equal f_diff.
pub fn adaptive(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let reference = reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let mean_rays =
        |rays_cast: Option<u64>, pixels: usize| rays_cast.unwrap_or(0) as f64 / pixels.max(1) as f64;
    let mut fixed = vec![];
    for &rays in &p.rays {
        let config = GatherParams {
            rays,
            ..GatherParams::default()
        };
        let (image, report) = runner.method_image("gather", &config, 1)?;
        let surface = (report.width * report.height) as usize - report.background_pixels;
        fixed.push(Point {
            rays: mean_rays(report.rays_cast, surface),
            f_diff: f_diff(&reference, &image, l_diag)?.value,
            p95: relative_error_p95(&reference, &image),
        });
    }
    let mut table = Table::new(
        &format!(
            "Adaptive gathering ({}): f_diff against gather with {} rays, {}², `{}`; rounds of {} rays, at most {}",
            runner.preset.name(),
            p.reference_rays,
            p.size,
            runner.scene.name,
            MIN_RAYS / 8,
            adaptive_config(runner, 1.0).max_rays
        ),
        &[
            "tolerance",
            "rays/pixel",
            "f_diff",
            "fixed N rays at this f_diff",
            "saving",
            "p95 |ΔH|/H",
            "fixed N rays at this p95",
            "saving",
        ],
    );
    let mut adaptive = vec![];
    let (mut savings, mut p95_savings) = (vec![], vec![]);
    let cell = |v: Option<f64>, f: fn(f64) -> String| v.map_or("outside the sweep".into(), f);
    for tolerance in TOLERANCES {
        // With the rays AOV, so that the picture of rays per pixel comes from the cache.
        let config = adaptive_config(runner, tolerance);
        let (image, report, _) = runner.method_image_with("adaptive", &config, 1, &[Aov::Rays])?;
        let surface = (report.width * report.height) as usize - report.background_pixels;
        let point = Point {
            rays: mean_rays(report.rays_cast, surface),
            f_diff: f_diff(&reference, &image, l_diag)?.value,
            p95: relative_error_p95(&reference, &image),
        };
        let fixed_rays = fixed_rays_for(&fixed, |p| p.f_diff, point.f_diff);
        let fixed_p95 = fixed_rays_for(&fixed, |p| p.p95, point.p95);
        savings.extend(fixed_rays.map(|r| r / point.rays));
        p95_savings.extend(fixed_p95.map(|r| r / point.rays));
        table.push(vec![
            tolerance.to_string(),
            format!("{:.1}", point.rays),
            format!("{:.4}", point.f_diff),
            cell(fixed_rays, |r| format!("{r:.1}")),
            fixed_rays.map_or("".into(), |r| format!("×{:.2}", r / point.rays)),
            format!("{:.4}", point.p95),
            cell(fixed_p95, |r| format!("{r:.1}")),
            fixed_p95.map_or("".into(), |r| format!("×{:.2}", r / point.rays)),
        ]);
        adaptive.push(point);
    }
    let mut files = table.write(&runner.out, "adaptive")?;
    let plot = runner.out.join("adaptive.svg");
    let series = |label: &str, points: &[Point], error: fn(&Point) -> f64| Series {
        label: label.into(),
        points: points.iter().map(|p| (p.rays, error(p))).collect(),
    };
    log_log(
        &plot,
        "error against rays cast",
        "rays per pixel (mean)",
        "f_diff (% of l_diag); p95 relative error (%)",
        &[
            series("fixed N: f_diff", &fixed, |p| p.f_diff),
            series("adaptive: f_diff", &adaptive, |p| p.f_diff),
            series("fixed N: p95 |ΔH|/H × 100", &fixed, |p| 100.0 * p.p95),
            series("adaptive: p95 |ΔH|/H × 100", &adaptive, |p| 100.0 * p.p95),
        ],
    )?;
    files.push(plot);
    files.push(rays_picture(runner)?);
    let list = |v: &[f64]| {
        if v.is_empty() {
            "none measured (outside the fixed-N sweep)".to_string()
        } else {
            v.iter()
                .map(|s| format!("×{s:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let notes = vec![
        format!(
            "How many rays does a pixel need (the paper's question)? Rays saved by adaptive gathering at equal f_diff, tolerance by tolerance: {}; at an equal 95th percentile of |ΔH|/H: {} (a saving below ×1 is a cost). Adaptive stops each pixel at a relative error, which is what a record-spacing cache feels; f_diff averages absolute errors, dominated by open regions with large H, where adaptive spends few rays; and its independent rounds lose part of one stratified grid's accuracy. The rays per pixel are in adaptive_rays.png.",
            list(&savings),
            list(&p95_savings)
        ),
    ];
    Ok(Section {
        name: "adaptive".into(),
        tables: vec![table],
        files,
        notes,
    })
}

/// A false-colour picture of the rays adaptive casts per pixel at the middle tolerance (its
/// image, with the rays AOV, is one of the study's: cached).
fn rays_picture(runner: &Runner) -> Result<std::path::PathBuf> {
    let tolerance = TOLERANCES[TOLERANCES.len() / 2];
    let config = adaptive_config(runner, tolerance);
    let (_, _, aovs) = runner.method_image_with("adaptive", &config, 1, &[Aov::Rays])?;
    let size = runner.params.size;
    let label = format!("rays, tolerance {tolerance}");
    let picture = false_colour(&aovs[0].data, size, size, &label);
    let path = runner.out.join("adaptive_rays.png");
    write_atomically(&path, &encode_png(&picture, &path)?)?;
    Ok(path)
}
