//! `--denoise`: every pixel's rays used by its neighbours, a geometry-aware filter of the
//! mean of `1/d` (guide: "Denoising H").
//!
//! **What is filtered.** A pixel's `S = 1/H` is the sample mean of `1/max(d, d_min)` over its
//! rays, an unbiased estimate of the pixel's true `1/H` (H itself is not unbiased). Neighbours
//! on the same surface see nearly the same hemisphere, so a weighted mean of nearby `S` is an
//! estimate of the pixel's `S` with less noise and a bias that the weights keep small; the
//! output is `H̃ = 1/S̃`. Because `1/x` is convex, a mean of `S` taken across a change of H
//! gives an H below the mean of the H's: the filter errs towards smaller record spacing, the
//! conservative side for a cache, where filtering H itself would err the other way.
//!
//! **The filter** is the edge-avoiding à-trous wavelet filter (Dammertz et al. 2010), with
//! SVGF's variance-guided edge-stopping (Schied et al. 2017): `passes` rounds of a 5 × 5
//! B3-spline kernel whose taps are `2^p` pixels apart in pass `p`, so it reaches
//! `2·(2^passes − 1)` pixels. Tap `j` of pixel `i` is weighted by
//! - `exp(−‖x_j − x_i‖² s² / 2σ_x²)`, `s = max(S_i, S_j)`: the kernel's reach in the scene is
//!   `σ_x` times H, small in creases and contact, wide on an open floor (`radius`);
//! - `exp(−h² s² / 2σ_p²)`, `h` the larger of `|n_i · (x_j − x_i)|` and `|n_j · (x_j − x_i)|`:
//!   a point off either pixel's tangent plane, by the same measure ([`PLANE`]);
//! - `max(0, n_i · n_j)^`[`NORMAL_POWER`]: another orientation;
//! - `exp(−(S_i − S_j)² / 2k²(v_i + v_j))`: two pixels whose `S` differ by more than the
//!   tolerance are not averaged (`edge` = k). The tolerance begins as `v = (S/N)²` and is
//!   carried through each pass as a variance is, `Σ w² v / (Σ w)²`, so it narrows as the
//!   image smooths (SVGF's rule).
//!
//! The last weight is what makes the filter consistent: the tolerance falls as `1/N`, faster
//! than the noise it stands for (a stratified mean of an integrand with jumps, as visibility
//! is, errs as `N^−3/4`; f_diff on `cube`, `hall` and `columns` falls as `N^−0.63 … −0.68`),
//! so as a pixel's rays grow the filter steps back before the noise does, any true difference
//! between neighbours stops the averaging, and the image converges to the unfiltered one.
//! A tolerance that falls as the noise does (`v = S²/N`, or `S²·N^−3/2`) filters about as
//! well at 32–128 rays and is up to 50 % worse than no filter at 1,024 (the guide's table).
//! A pixel whose rays all escaped has `S = 0` (H = +inf) and averages with its neighbours
//! like any other.
//!
//! Every pixel's output is a function of its neighbourhood's inputs alone, computed in the
//! same order whatever the thread count: the same bits on any number of threads. A shard's
//! part carries the [`Guide`] and its unfiltered H, and `hmdist merge` filters the joined
//! image, so a denoised render split into shards merges to the one-machine image byte for
//! byte.

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The plane term's scale σ_p, as a fraction of H: a neighbour `0.1·H` off the tangent plane
/// keeps `exp(−½)` of its weight.
pub const PLANE: f32 = 0.1;

/// The normal term's power: a neighbour whose normal is 10° away keeps `cos 10°^64 ≈ 0.38` of
/// its weight, one 20° away `0.02`.
pub const NORMAL_POWER: i32 = 64;

/// The B3-spline taps of one à-trous pass, at offsets −2 … 2.
const TAPS: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// The filter's parameters: the CLI's `--denoise-*` flags, Python's keywords, the report's
/// `denoise` and part of the render's key.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DenoiseParams {
    /// À-trous passes: the filter reaches `2·(2^passes − 1)` pixels.
    pub passes: u32,
    /// The kernel's reach in the scene, as a fraction of H (σ_x).
    pub radius: f32,
    /// How far apart two pixels' means of `1/d` may be and still be averaged, in units of
    /// `S/N` (k).
    pub edge: f32,
}

/// Default passes: a reach of 14 pixels (5 passes, 62 pixels, measured no better at 256²).
pub const DEFAULT_PASSES: u32 = 3;
/// Default reach: half of H (a quarter or all of H measured within 1 % of it).
pub const DEFAULT_RADIUS: f32 = 0.5;
/// Default edge: a tolerance of `12·S/N` (lower is better on `columns`, higher on `cube`).
pub const DEFAULT_EDGE: f32 = 12.0;
/// The most passes: a reach of 2,046 pixels.
pub const MAX_PASSES: u32 = 10;

impl Default for DenoiseParams {
    fn default() -> Self {
        DenoiseParams {
            passes: DEFAULT_PASSES,
            radius: DEFAULT_RADIUS,
            edge: DEFAULT_EDGE,
        }
    }
}

impl DenoiseParams {
    /// Refuses passes outside 1 … [`MAX_PASSES`], and a radius or edge that is not a positive
    /// finite number, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_PASSES).contains(&self.passes) {
            let message = format!("must be 1 to {MAX_PASSES}, not {}", self.passes);
            return Err(Error::invalid("denoise_passes", message));
        }
        for (name, value) in [("denoise_radius", self.radius), ("denoise_edge", self.edge)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::invalid(
                    name,
                    format!("must be a positive number, not {value}"),
                ));
            }
        }
        Ok(())
    }

    /// How many pixels from its centre the filter reads.
    pub fn reach(&self) -> u32 {
        2 * ((1u32 << self.passes) - 1)
    }
}

/// What the filter knows of each pixel besides its H: the surface point and its
/// camera-facing unit normal (NaN for a pixel with no surface), and the number of rays its H
/// averages. Row-major, `width × height`.
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Surface points.
    pub points: Vec<Vec3>,
    /// Unit normals facing the camera.
    pub normals: Vec<Vec3>,
    /// Rays per pixel.
    pub samples: Vec<f32>,
}

/// The EXR channels a shard's part carries its [`Guide`] in, in [`Guide::channels`]' order.
pub const GUIDE_CHANNELS: [&str; 7] = [
    "guide.x",
    "guide.y",
    "guide.z",
    "guide.nx",
    "guide.ny",
    "guide.nz",
    "guide.rays",
];

impl Guide {
    /// The guide's seven channels, named by [`GUIDE_CHANNELS`].
    pub fn channels(&self) -> Vec<Vec<f32>> {
        let axis = |v: &[Vec3], a: usize| v.iter().map(|p| p[a]).collect::<Vec<f32>>();
        let mut channels: Vec<Vec<f32>> = (0..3).map(|a| axis(&self.points, a)).collect();
        channels.extend((0..3).map(|a| axis(&self.normals, a)));
        channels.push(self.samples.clone());
        channels
    }

    /// The guide of a `width × height` image from its seven channels, in
    /// [`GUIDE_CHANNELS`]' order.
    pub fn from_channels(width: u32, height: u32, channels: &[Vec<f32>]) -> Result<Guide> {
        let pixels = width as usize * height as usize;
        if channels.len() != GUIDE_CHANNELS.len() || channels.iter().any(|c| c.len() != pixels) {
            return Err(Error::parameter(format!(
                "a denoising guide needs {} channels of {width}x{height} pixels",
                GUIDE_CHANNELS.len()
            )));
        }
        let vectors = |first: usize| {
            (0..pixels)
                .map(|i| Vec3::new(channels[first][i], channels[first + 1][i], channels[first + 2][i]))
                .collect()
        };
        Ok(Guide {
            width,
            height,
            points: vectors(0),
            normals: vectors(3),
            samples: channels[6].clone(),
        })
    }
}

/// One pixel's state between passes: its point and normal, its mean of `1/d` and the
/// tolerance's square (carried as a variance); `valid` is false where the pixel has no finite
/// H to filter.
#[derive(Clone, Copy)]
struct Pixel {
    point: Vec3,
    normal: Vec3,
    s: f32,
    variance: f32,
    valid: bool,
}

/// `hmd` (row-major H, NaN where there is none, `+inf` where every ray escaped) filtered with
/// `params` over `guide`: H̃ = 1/S̃ where H is a number, NaN where it is NaN. Runs on the
/// current rayon pool; the same bits on any number of threads.
pub fn filter(hmd: &[f32], guide: &Guide, params: &DenoiseParams) -> Vec<f32> {
    assert_eq!(hmd.len(), guide.points.len(), "an H per guide pixel");
    let mut pixels: Vec<Pixel> = hmd
        .iter()
        .zip(&guide.points)
        .zip(guide.normals.iter().zip(&guide.samples))
        .map(|((&h, &point), (&normal, &n))| {
            let s = 1.0 / h;
            let valid = h > 0.0 && point.is_finite() && normal.is_finite() && n >= 1.0;
            Pixel {
                point,
                normal,
                s,
                variance: if valid { s * s / (n * n) } else { 0.0 },
                valid,
            }
        })
        .collect();
    let width = guide.width as usize;
    let scales = Scales::of(params);
    let mut next = pixels.clone();
    for pass in 0..params.passes {
        let step = 1usize << pass;
        next.par_chunks_mut(width.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, out) in row.iter_mut().enumerate() {
                    *out = filtered(&pixels, (guide.width, guide.height), (x, y), step, &scales);
                }
            });
        std::mem::swap(&mut pixels, &mut next);
    }
    hmd.iter()
        .zip(&pixels)
        .map(|(&h, p)| if p.valid { 1.0 / p.s } else { h })
        .collect()
}

/// The weights' `1/2σ²` factors, worked out once per image.
struct Scales {
    radius: f32,
    plane: f32,
    edge: f32,
}

impl Scales {
    fn of(params: &DenoiseParams) -> Scales {
        Scales {
            radius: 0.5 / (params.radius * params.radius),
            plane: 0.5 / (PLANE * PLANE),
            edge: 0.5 / (params.edge * params.edge),
        }
    }
}

/// Pixel `(x, y)` after one pass with taps `step` pixels apart.
#[inline]
fn filtered(
    pixels: &[Pixel],
    (width, height): (u32, u32),
    (x, y): (usize, usize),
    step: usize,
    scales: &Scales,
) -> Pixel {
    let width = width as usize;
    let centre = pixels[y * width + x];
    if !centre.valid {
        return centre;
    }
    let (mut sum_w, mut sum_s, mut sum_v) = (0.0f32, 0.0f32, 0.0f32);
    for (dy, ty) in TAPS.iter().enumerate() {
        let Some(row) = (y + dy * step)
            .checked_sub(2 * step)
            .filter(|&r| r < height as usize)
        else {
            continue;
        };
        for (dx, tx) in TAPS.iter().enumerate() {
            let Some(column) = (x + dx * step).checked_sub(2 * step).filter(|&c| c < width) else {
                continue;
            };
            let other = &pixels[row * width + column];
            if !other.valid {
                continue;
            }
            let w = if (dx, dy) == (2, 2) {
                tx * ty
            } else {
                tx * ty * affinity(&centre, other, scales)
            };
            sum_w += w;
            sum_s += w * other.s;
            sum_v += w * w * other.variance;
        }
    }
    // The centre tap always counts (its weight is 9/64), so sum_w > 0.
    Pixel {
        s: sum_s / sum_w,
        variance: sum_v / (sum_w * sum_w),
        ..centre
    }
}

/// How much of its tap a neighbour `b` of `a` keeps, symmetric in the two: the product of the
/// distance, plane, normal and tolerance terms of the module's docs.
#[inline]
fn affinity(a: &Pixel, b: &Pixel, scales: &Scales) -> f32 {
    let cos = a.normal.dot(b.normal);
    if cos <= 0.0 {
        return 0.0;
    }
    let offset = b.point - a.point;
    let scale = a.s.max(b.s);
    let scale2 = scale * scale;
    let apart = offset.length_squared() * scale2 * scales.radius;
    let height = a.normal.dot(offset).abs().max(b.normal.dot(offset).abs());
    let off_plane = height * height * scale2 * scales.plane;
    let ds = a.s - b.s;
    let variance = a.variance + b.variance;
    let differ = if variance > 0.0 {
        ds * ds * scales.edge / variance
    } else if ds == 0.0 {
        0.0
    } else {
        f32::INFINITY
    };
    cos.powi(NORMAL_POWER) * (-(apart + off_plane + differ)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat floor of `side²` pixels one unit apart, normal +y.
    fn floor(side: u32, samples: f32) -> Guide {
        let n = (side * side) as usize;
        Guide {
            width: side,
            height: side,
            points: (0..n)
                .map(|i| Vec3::new((i % side as usize) as f32, 0.0, (i / side as usize) as f32))
                .collect(),
            normals: vec![Vec3::Y; n],
            samples: vec![samples; n],
        }
    }

    #[test]
    fn a_constant_image_is_unchanged() {
        let guide = floor(16, 64.0);
        let hmd = vec![3.0f32; 256];
        let out = filter(&hmd, &guide, &DenoiseParams::default());
        assert!(out.iter().all(|&h| (h - 3.0).abs() < 1e-5), "{out:?}");
    }

    #[test]
    fn background_and_infinite_pixels_keep_their_meaning() {
        let guide = floor(8, 64.0);
        let mut hmd = vec![f32::INFINITY; 64];
        hmd[0] = f32::NAN;
        let out = filter(&hmd, &guide, &DenoiseParams::default());
        assert!(out[0].is_nan());
        assert!(out[1..].iter().all(|h| *h == f32::INFINITY), "{out:?}");
    }

    #[test]
    fn bad_parameters_are_named() {
        let bad = [
            DenoiseParams {
                passes: 0,
                ..Default::default()
            },
            DenoiseParams {
                passes: MAX_PASSES + 1,
                ..Default::default()
            },
            DenoiseParams {
                radius: 0.0,
                ..Default::default()
            },
            DenoiseParams {
                radius: f32::NAN,
                ..Default::default()
            },
            DenoiseParams {
                edge: -1.0,
                ..Default::default()
            },
            DenoiseParams {
                edge: f32::INFINITY,
                ..Default::default()
            },
        ];
        let names = [
            "denoise_passes",
            "denoise_passes",
            "denoise_radius",
            "denoise_radius",
            "denoise_edge",
            "denoise_edge",
        ];
        for (params, name) in bad.iter().zip(names) {
            let message = params.validate().unwrap_err().to_string();
            assert!(message.contains(name), "{message}");
        }
        assert!(DenoiseParams::default().validate().is_ok());
    }

    #[test]
    fn the_guide_round_trips_through_its_channels() {
        let guide = floor(4, 16.0);
        let back = Guide::from_channels(4, 4, &guide.channels()).unwrap();
        assert_eq!(back, guide);
        assert!(Guide::from_channels(4, 5, &guide.channels()).is_err());
    }
}
