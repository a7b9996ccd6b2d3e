//! What a cache reports: what it was built with, its records per level, the rays and seconds
//! each part cost, and its error against a brute-force image of E.

use super::params::CacheParams;
use super::records::Record;
use super::spacing::Range;
use crate::error::{Error, Result};
use crate::estimators::IrradianceParams;
use crate::image::HmdImage;
use crate::options::RenderOptions;
use crate::scene::Scene;

/// Seconds of a cache's parts.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct CacheSeconds {
    /// The BVH and the primary rays.
    pub setup: f64,
    /// The spacing estimator's preparation (a photon map; a GPU image of H).
    pub spacing_prepare: f64,
    /// The records' H from the spacing estimator (0 for the records' own rays or the oracle).
    pub h: f64,
    /// The records' irradiance (and their own rays' H, min, min10).
    pub e: f64,
    /// Every pixel's E from the records.
    pub interpolate: f64,
    /// Everything.
    pub total: f64,
}

/// A cache's report: what it was built with, its records and what they cost.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CacheReport {
    /// hmdist's version.
    pub hmdist_version: String,
    /// `cache`.
    pub method: String,
    /// The scene's name.
    pub scene: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The random numbers' seed.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// The scene's bounding-box diagonal.
    pub l_diag: f32,
    /// Ward's a.
    pub accuracy: f32,
    /// The spacing source, as `--spacing` names it.
    pub spacing: String,
    /// The pixel-footprint clamp, `[lo, hi]`.
    pub clamp_pixels: Option<Range>,
    /// The scene clamp, `[lo, hi]` in fractions of `l_diag`.
    pub clamp_scene: Option<Range>,
    /// Whether the radii were clamped by their neighbours'.
    pub neighbour_clamp: bool,
    /// Whether the records carried gradients.
    pub gradients: bool,
    /// The records' irradiance parameters.
    pub irradiance: IrradianceParams,
    /// Records made.
    pub records: usize,
    /// Records made per level, coarsest first.
    pub records_per_level: Vec<Level>,
    /// Mean records a surface pixel uses.
    pub mean_records_per_pixel: f64,
    /// Rays cast for the records' E (gather and shadow rays).
    pub rays_e: u64,
    /// Rays cast for the records' H beyond those (the spacing estimator's, with its
    /// preparation's: the photons' paths).
    pub rays_h: u64,
    /// Seconds of the parts.
    pub seconds: CacheSeconds,
    /// The error against a reference image of E, where one was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<CacheErrors>,
}

impl CacheReport {
    /// Pretty JSON, with a final newline.
    pub fn to_json(&self) -> String {
        let mut json = serde_json::to_string_pretty(self).expect("a report serialises");
        json.push('\n');
        json
    }

    /// One line for the terminal.
    pub fn summary(&self) -> String {
        let mut line = format!(
            "cache {} a={} on {} {}x{}: {} records, {:.2} used per pixel, {} + {} rays (E + H), {:.2} s",
            self.spacing,
            self.accuracy,
            self.scene,
            self.width,
            self.height,
            self.records,
            self.mean_records_per_pixel,
            self.rays_e,
            self.rays_h,
            self.seconds.total
        );
        if let Some(r) = &self.reference {
            line += &format!(
                "; relative error mean {:.2} %, p95 {:.2} %",
                100.0 * r.mean_relative_error,
                100.0 * r.p95_relative_error
            );
        }
        line
    }
}

/// A cache's error against a brute-force image of E (`render --method irradiance`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CacheErrors {
    /// The reference's file, as given.
    pub path: String,
    /// Mean over the pixels of `|E − E_ref| / max(E_ref, 0.01 · mean E_ref)`.
    pub mean_relative_error: f64,
    /// Its 95th percentile.
    pub p95_relative_error: f64,
    /// Pixels compared (both values finite).
    pub pixels: u64,
}

/// Each pixel's relative error of `image` against `reference` (the same size): `|E − E_ref|
/// / max(E_ref, 0.01 · mean E_ref)`, NaN where either is not finite; and its mean and p95,
/// the reference named `path`.
pub fn relative_errors(
    image: &HmdImage,
    reference: &HmdImage,
    path: &str,
) -> Result<(Vec<f32>, CacheErrors)> {
    let (w, h) = (image.width, image.height);
    if (reference.width, reference.height) != (w, h) {
        let message = format!(
            "is {}x{}, the cache {w}x{h}: it must be an image of the same pixels",
            reference.width, reference.height
        );
        return Err(Error::invalid("reference", message));
    }
    // An irradiance is a finite non-negative number wherever the cache has a surface.
    let bad = image
        .data
        .iter()
        .zip(&reference.data)
        .position(|(&e, &r)| r < 0.0 || r.is_infinite() || (r.is_nan() && e.is_finite()));
    if let Some(i) = bad {
        let (x, y) = (i % w as usize, i / w as usize);
        let message = format!(
            "{path} holds E = {} at pixel ({x}, {y}), where the cache sees a surface: an irradiance is a \
             finite number, at least 0 (NaN only where the camera sees nothing)",
            reference.data[i]
        );
        return Err(Error::invalid("reference", message));
    }
    let finite: Vec<f64> = reference
        .data
        .iter()
        .filter(|v| v.is_finite())
        .map(|&v| v as f64)
        .collect();
    // 1 % of the mean E: below it an error is relative to the floor (a dark pixel's tiny E
    // would make any difference huge). A scene whose light reaches nothing the camera sees
    // has E = 0 everywhere, a valid answer: there the floor is the smallest positive number.
    let floor = (0.01 * finite.iter().sum::<f64>() / finite.len().max(1) as f64).max(f64::MIN_POSITIVE);
    let errors: Vec<f32> = image
        .data
        .iter()
        .zip(&reference.data)
        .map(|(&e, &r)| {
            if e.is_finite() && r.is_finite() {
                ((e as f64 - r as f64).abs() / (r as f64).max(floor)) as f32
            } else {
                f32::NAN
            }
        })
        .collect();
    let mut sorted: Vec<f32> = errors.iter().copied().filter(|e| e.is_finite()).collect();
    if sorted.is_empty() {
        let message = "shares no pixel with a finite value with the cache: is it an image of this scene?";
        return Err(Error::invalid("reference", message));
    }
    sorted.sort_unstable_by(f32::total_cmp);
    let n = sorted.len();
    let p95 = sorted[((0.95 * n as f64).ceil() as usize).clamp(1, n) - 1];
    let summary = CacheErrors {
        path: path.into(),
        mean_relative_error: sorted.iter().map(|&e| e as f64).sum::<f64>() / n as f64,
        p95_relative_error: p95 as f64,
        pixels: n as u64,
    };
    Ok((errors, summary))
}

impl CacheReport {
    /// The report of a cache of `scene` made of `records` (and how many each pixel used),
    /// which cost `counts` and `seconds`.
    pub(super) fn new(
        scene: &Scene,
        params: &CacheParams,
        options: &RenderOptions,
        l_diag: f32,
        (records, used): (&[Record], &[f32]),
        counts: Counts,
        seconds: CacheSeconds,
    ) -> CacheReport {
        let used: Vec<f64> = used.iter().filter(|u| u.is_finite()).map(|&u| u as f64).collect();
        CacheReport {
            hmdist_version: env!("CARGO_PKG_VERSION").into(),
            method: "cache".into(),
            scene: scene.name.clone(),
            width: options.width,
            height: options.height,
            seed: options.seed,
            threads: rayon::current_num_threads(),
            l_diag,
            accuracy: params.accuracy,
            spacing: params.spacing.name(),
            clamp_pixels: params.clamp_pixels,
            clamp_scene: params.clamp_scene,
            neighbour_clamp: params.neighbour_clamp,
            gradients: params.gradients,
            irradiance: params.irradiance.clone(),
            records: records.len(),
            records_per_level: counts.levels,
            mean_records_per_pixel: used.iter().sum::<f64>() / used.len().max(1) as f64,
            rays_e: counts.rays_e,
            rays_h: counts.rays_h,
            seconds,
            reference: None,
        }
    }
}

/// Records made, per level, and the rays they cast.
#[derive(Default)]
pub(super) struct Counts {
    pub levels: Vec<Level>,
    pub rays_e: u64,
    pub rays_h: u64,
}

/// One placement level: its stride and the records it made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Level {
    /// Pixels between the level's grid points.
    pub stride: u32,
    /// Records made at this level.
    pub records: usize,
}
