//! Accuracy metrics between two HMD images (spec §4, paper eq. 3).
//!
//! `f_diff = (Σ_i |H_ref(i) − H(i)| / N_pixels) · 100 / l_diag` over the pixels finite in both
//! images; background pixels, holes and `+inf` pixels are excluded and counted.

use crate::error::{Error, Result};
use crate::image::HmdImage;

/// `f_diff` and what it was computed over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FDiff {
    /// Mean absolute difference in percent of the scene diagonal.
    pub value: f64,
    /// Pixels finite in both images.
    pub compared: usize,
    /// Pixels left out: not finite in one image or the other.
    pub excluded: usize,
}

/// `f_diff` of `test` against `reference` for a scene with bounding-box diagonal `l_diag`
/// (positive and finite, else an error naming it).
pub fn f_diff(reference: &HmdImage, test: &HmdImage, l_diag: f32) -> Result<FDiff> {
    if !(l_diag.is_finite() && l_diag > 0.0) {
        return Err(Error::invalid(
            "l_diag",
            format!("must be a positive finite length, not {l_diag}"),
        ));
    }
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(Error::parameter(format!(
            "images differ in size: {}x{} and {}x{}",
            reference.width, reference.height, test.width, test.height
        )));
    }
    let mut sum = 0.0f64;
    let mut compared = 0;
    for (&r, &t) in reference.data.iter().zip(&test.data) {
        if r.is_finite() && t.is_finite() {
            sum += (r as f64 - t as f64).abs();
            compared += 1;
        }
    }
    let value = if compared == 0 {
        f64::NAN
    } else {
        sum / compared as f64 * 100.0 / l_diag as f64
    };
    Ok(FDiff {
        value,
        compared,
        excluded: reference.data.len() - compared,
    })
}

/// Every figure `hmdist diff` prints, over the pixels finite in both images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// `f_diff` (spec §4) and the pixels it was computed over.
    pub f_diff: FDiff,
    /// Root mean square of `H − H_ref`, in scene units.
    pub rmse: f64,
    /// Mean of `|H − H_ref| / H_ref` (pixels with `H_ref = 0` left out of this one figure).
    pub mean_relative_error: f64,
    /// Pixels whose values differ in their bits (`f32` bit patterns, every pixel, holes
    /// included): 0 when the two images are the same bit for bit, what this project's
    /// determinism promises (threads, kernels, BVH presets, shards).
    pub differing: usize,
    /// Signed error, `mean(H − H_ref) · 100 / l_diag`: f_diff's measure with the sign kept, so
    /// a bias shows (a filter's, a ray offset's) where noise averages out.
    pub bias: f64,
    /// f_diff over the creases: the tenth of the compared pixels with the smallest `H_ref`
    /// (corners, contact), where a filter is most biased; and over the other nine tenths.
    pub f_diff_creases: f64,
    /// f_diff over the pixels that are not creases.
    pub f_diff_rest: f64,
    /// The 95th percentile of `|H − H_ref| / H_ref` (pixels with `H_ref = 0` left out).
    pub p95_relative_error: f64,
}

/// The fraction of the compared pixels (by smallest `H_ref`) that [`Comparison`] calls creases.
pub const CREASE_FRACTION: f64 = 0.1;

/// `f_diff` (spec §4) and the other figures of [`Comparison`].
pub fn compare(reference: &HmdImage, test: &HmdImage, l_diag: f32) -> Result<Comparison> {
    let f_diff = f_diff(reference, test, l_diag)?;
    let (mut squares, mut relative, mut relative_count) = (0.0f64, 0.0f64, 0usize);
    for (&r, &t) in reference.data.iter().zip(&test.data) {
        if r.is_finite() && t.is_finite() {
            let d = t as f64 - r as f64;
            squares += d * d;
            if r != 0.0 {
                relative += (d / r as f64).abs();
                relative_count += 1;
            }
        }
    }
    let mean = |sum: f64, n: usize| if n == 0 { f64::NAN } else { sum / n as f64 };
    let pairs: Vec<(f32, f32)> = reference
        .data
        .iter()
        .zip(&test.data)
        .filter(|(r, t)| r.is_finite() && t.is_finite())
        .map(|(&r, &t)| (r, t))
        .collect();
    let percent = 100.0 / l_diag as f64;
    let signed: f64 = pairs.iter().map(|&(r, t)| t as f64 - r as f64).sum();
    let (creases, rest) = split_creases(pairs.clone());
    let absolute =
        |p: &[(f32, f32)]| mean(p.iter().map(|&(r, t)| (t as f64 - r as f64).abs()).sum(), p.len()) * percent;
    let mut relatives: Vec<f64> = pairs
        .iter()
        .filter(|(r, _)| *r != 0.0)
        .map(|&(r, t)| ((t as f64 - r as f64) / r as f64).abs())
        .collect();
    relatives.sort_by(f64::total_cmp);
    Ok(Comparison {
        f_diff,
        rmse: mean(squares, f_diff.compared).sqrt(),
        mean_relative_error: mean(relative, relative_count),
        bias: mean(signed, pairs.len()) * percent,
        f_diff_creases: absolute(&creases),
        f_diff_rest: absolute(&rest),
        p95_relative_error: percentile(&relatives, 0.95),
        differing: reference
            .data
            .iter()
            .zip(&test.data)
            .filter(|(r, t)| r.to_bits() != t.to_bits())
            .count(),
    })
}

/// `(H_ref, H)` pairs split into the creases (the [`CREASE_FRACTION`] with the smallest
/// `H_ref`, ties broken by H) and the rest.
fn split_creases(mut pairs: Vec<(f32, f32)>) -> (Vec<(f32, f32)>, Vec<(f32, f32)>) {
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let count = (pairs.len() as f64 * CREASE_FRACTION).round() as usize;
    let rest = pairs.split_off(count);
    (pairs, rest)
}

/// The `q` quantile of `sorted` (nearest rank); NaN when it is empty.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

/// Where a difference picture has no difference to show (a pixel not finite in both images:
/// background, a window onto nothing): a blue that no difference is drawn in.
pub const NO_SURFACE: image::Rgb<u8> = image::Rgb([96, 150, 220]);

/// The difference picture of spec §4: grey `1 − clamp(10 · s · |ΔH|)`, white where equal;
/// pixels not finite in both images are [`NO_SURFACE`] blue, apart from the greys.
pub fn difference_picture(reference: &HmdImage, test: &HmdImage, scale: f32) -> image::RgbImage {
    image::RgbImage::from_fn(reference.width, reference.height, |x, y| {
        let (r, t) = (reference.at(x, y), test.at(x, y));
        if !(r.is_finite() && t.is_finite()) {
            return NO_SURFACE;
        }
        let v = 1.0 - (10.0 * scale * (r - t).abs()).clamp(0.0, 1.0);
        image::Rgb([(v * 255.0).round() as u8; 3])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(data: Vec<f32>) -> HmdImage {
        HmdImage::new(data.len() as u32, 1, data)
    }

    #[test]
    fn an_image_against_itself_is_zero() {
        let a = image(vec![1.0, 2.0, 3.5, f32::NAN]);
        let d = f_diff(&a, &a, 10.0).unwrap();
        assert_eq!((d.value, d.compared, d.excluded), (0.0, 3, 1));
        // A diagonal that is no length is refused, not a NaN or infinite f_diff.
        for l_diag in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = f_diff(&a, &a, l_diag).unwrap_err().to_string();
            assert!(e.contains("l_diag must be a positive finite length"), "{e}");
        }
    }

    #[test]
    fn a_constant_offset_gives_100_c_over_l_diag() {
        let a = image(vec![1.0, 2.0, 3.0, 4.0]);
        let b = image(vec![1.5, 2.5, 3.5, 4.5]);
        assert!((f_diff(&a, &b, 20.0).unwrap().value - 100.0 * 0.5 / 20.0).abs() < 1e-12);
    }

    #[test]
    fn bias_keeps_the_sign_and_creases_are_the_smallest_tenth() {
        // Twenty pixels: H_ref = 1 … 20; the test image is 0.5 low on the two smallest (the
        // creases) and 1 high on the rest.
        let reference = image((1..=20).map(|i| i as f32).collect());
        let test = image(
            (1..=20)
                .map(|i| i as f32 + if i <= 2 { -0.5 } else { 1.0 })
                .collect(),
        );
        let c = compare(&reference, &test, 100.0).unwrap();
        assert!((c.f_diff_creases - 0.5).abs() < 1e-12, "{c:?}");
        assert!((c.f_diff_rest - 1.0).abs() < 1e-12, "{c:?}");
        assert!((c.bias - (18.0 - 1.0) / 20.0).abs() < 1e-12, "{c:?}");
        // Relative errors: 0.5, 0.25, then 1/3, 1/4 … 1/20; the 19th of 20 (nearest rank) is
        // the second largest, 1/3.
        assert!((c.p95_relative_error - 1.0 / 3.0).abs() < 1e-12, "{c:?}");
        let low = compare(
            &reference,
            &image((1..=20).map(|i| i as f32 - 1.0).collect()),
            100.0,
        )
        .unwrap();
        assert!((low.bias + 1.0).abs() < 1e-12, "{low:?}");
    }

    #[test]
    fn rmse_and_relative_error_of_a_constant_offset() {
        let a = image(vec![1.0, 2.0, 4.0]);
        let b = image(vec![1.5, 2.5, 4.5]);
        let c = compare(&a, &b, 1.0).unwrap();
        assert!((c.rmse - 0.5).abs() < 1e-12);
        assert!((c.mean_relative_error - (0.5 + 0.25 + 0.125) / 3.0).abs() < 1e-12);
        let picture = difference_picture(&a, &b, 0.1);
        assert_eq!(picture.get_pixel(0, 0).0, [128; 3], "1 - 10·0.1·0.5 = 0.5");
        assert_eq!(
            difference_picture(&a, &a, 0.1).get_pixel(2, 0).0,
            [255; 3],
            "equal is white"
        );
        // No surface in either image: its own colour, not the largest difference's black.
        let nan = image(vec![f32::NAN, 2.0, 100.0]);
        let picture = difference_picture(&nan, &a, 0.1);
        assert_eq!(picture.get_pixel(0, 0), &NO_SURFACE);
        assert_eq!(
            picture.get_pixel(2, 0).0,
            [0; 3],
            "the largest difference is black"
        );
    }

    #[test]
    fn nan_and_infinite_pixels_are_excluded_and_counted() {
        let a = image(vec![1.0, f32::NAN, 3.0, f32::INFINITY]);
        let b = image(vec![2.0, 2.0, f32::NAN, 4.0]);
        let d = f_diff(&a, &b, 100.0).unwrap();
        assert_eq!((d.value, d.compared, d.excluded), (1.0, 1, 3));
    }
}
