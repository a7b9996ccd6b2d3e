//! Grey pictures of HMD images (spec §4): `grey = clamp(s · H)`; NaN pixels (background,
//! holes) are drawn black, `+inf` white. False-colour pictures of AOVs, with a legend bar.

use std::io::Cursor;
use std::path::Path;

use font8x8::legacy::BASIC_LEGACY;
use image::{GrayImage, ImageBuffer, ImageFormat, Luma, Pixel, Rgb, RgbImage};

use super::{write_atomically, HmdImage};
use crate::error::{Error, Result};

/// The grey picture of `image` at display scale `scale`.
pub fn grey(image: &HmdImage, scale: f32) -> GrayImage {
    GrayImage::from_fn(image.width, image.height, |x, y| {
        let h = image.at(x, y);
        let v = if h.is_nan() {
            0.0
        } else {
            (scale * h).clamp(0.0, 1.0)
        };
        Luma([(v * 255.0).round() as u8])
    })
}

/// Writes `picture` (grey or colour) to the PNG file `path`, through a temporary file and a
/// rename.
pub fn write_png<P>(picture: &ImageBuffer<P, Vec<u8>>, path: &Path) -> Result<()>
where
    P: Pixel<Subpixel = u8> + image::PixelWithColorType,
{
    write_atomically(path, &encode_png(picture, path)?)
}

/// Viridis at five stops (matplotlib's), linearly between: dark blue for low, yellow for high.
const VIRIDIS: [[f32; 3]; 5] = [
    [68.0, 1.0, 84.0],
    [59.0, 82.0, 139.0],
    [33.0, 145.0, 140.0],
    [94.0, 201.0, 98.0],
    [253.0, 231.0, 37.0],
];

/// The colour of `t` in [0, 1] on [`VIRIDIS`].
fn viridis(t: f32) -> Rgb<u8> {
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    Rgb(std::array::from_fn(|c| (a[c] + f * (b[c] - a[c])).round() as u8))
}

/// Height of the legend strip under a false-colour picture.
const LEGEND_HEIGHT: u32 = 30;
/// Narrowest false-colour picture: room for the legend's labels.
const LEGEND_MIN_WIDTH: u32 = 200;

/// How a false-colour picture maps values to colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourScale {
    /// Evenly from the smallest finite value to the largest.
    Linear,
    /// Evenly in `ln v`: for positive values that span decades (rays per pixel of an adaptive
    /// render, 64 … 12,000), where a linear scale leaves most pixels at its dark end. Falls
    /// back to linear where a value is 0 or negative.
    Log,
}

/// A false-colour picture of `values` (`width × height`, row-major) on viridis, from their
/// smallest finite value (dark) to their largest (yellow), with a legend bar under it that
/// names `label` and the two ends. NaN (background) is black, `+inf` white.
pub fn false_colour(values: &[f32], width: u32, height: u32, label: &str) -> RgbImage {
    false_colour_scaled(values, width, height, label, ColourScale::Linear)
}

/// [`false_colour`] on `scale`; a log scale's legend also names its geometric middle, under
/// the bar's centre, and says "log".
pub fn false_colour_scaled(
    values: &[f32],
    width: u32,
    height: u32,
    label: &str,
    scale: ColourScale,
) -> RgbImage {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 1.0) };
    let log = scale == ColourScale::Log && lo > 0.0 && hi > lo;
    // Where a value sits between the ends, 0 to 1, and back.
    let position = |v: f32| -> f32 {
        if log {
            (v / lo).ln() / (hi / lo).ln()
        } else if hi > lo {
            (v - lo) / (hi - lo)
        } else {
            0.0
        }
    };
    let picture_width = width.max(LEGEND_MIN_WIDTH);
    let mut out = RgbImage::from_pixel(picture_width, height + LEGEND_HEIGHT, Rgb([255, 255, 255]));
    for y in 0..height {
        for x in 0..width {
            let v = values[(y * width + x) as usize];
            let colour = if v.is_nan() {
                Rgb([0, 0, 0])
            } else if v == f32::INFINITY {
                Rgb([255, 255, 255])
            } else {
                viridis(position(v))
            };
            out.put_pixel(x, y, colour);
        }
    }
    // The bar, then the low end, the label and the high end under it.
    let (bar_top, margin) = (height + 4, 4);
    for x in margin..picture_width - margin {
        let t = (x - margin) as f32 / (picture_width - 2 * margin - 1) as f32;
        for y in bar_top..bar_top + 10 {
            out.put_pixel(x, y, viridis(t));
        }
    }
    let ink = Rgb([0, 0, 0]);
    let text_top = bar_top + 14;
    let (low, high) = (format_value(lo), format_value(hi));
    draw_text(&mut out, margin, text_top, &low, 1, ink);
    let high_left = picture_width - margin - 8 * high.len() as u32;
    draw_text(&mut out, high_left, text_top, &high, 1, ink);
    let label = if log {
        format!("{label} (log; mid {})", format_value((lo * hi).sqrt().round()))
    } else {
        label.to_string()
    };
    let middle = (picture_width / 2).saturating_sub(4 * label.len() as u32);
    draw_text(&mut out, middle, text_top, &label, 1, ink);
    out
}

/// A legend's number: about four significant digits.
fn format_value(v: f32) -> String {
    if v == v.trunc() && v.abs() < 1e6 {
        format!("{v:.0}")
    } else if v.abs() >= 0.01 && v.abs() < 1e4 {
        format!("{v:.4}").trim_end_matches('0').to_string()
    } else {
        format!("{v:.3e}")
    }
}

/// Draws `text` with its top-left corner at (x, y) in the 8 × 8 bitmap font of `font8x8`
/// (public domain), each font pixel `scale` pixels wide; glyphs past the right edge are cut.
pub(crate) fn draw_text<P: Pixel>(
    image: &mut ImageBuffer<P, Vec<P::Subpixel>>,
    x: u32,
    y: u32,
    text: &str,
    scale: u32,
    ink: P,
) {
    for (k, c) in text.chars().enumerate() {
        let left = x + k as u32 * 8 * scale;
        let glyph = BASIC_LEGACY
            .get(c as usize)
            .copied()
            .unwrap_or(BASIC_LEGACY[b'?' as usize]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in (0..8).filter(|col| bits >> col & 1 == 1) {
                for (dx, dy) in (0..scale).flat_map(|dx| (0..scale).map(move |dy| (dx, dy))) {
                    let (px, py) = (left + col * scale + dx, y + row as u32 * scale + dy);
                    if px < image.width() && py < image.height() {
                        image.put_pixel(px, py, ink);
                    }
                }
            }
        }
    }
}

/// The bytes of the PNG file of `picture` (grey or false colour); `path` names the file in
/// errors.
pub fn encode_png<P>(picture: &ImageBuffer<P, Vec<u8>>, path: &Path) -> Result<Vec<u8>>
where
    P: Pixel<Subpixel = u8> + image::PixelWithColorType,
{
    let mut bytes = Cursor::new(Vec::new());
    picture
        .write_to(&mut bytes, ImageFormat::Png)
        .map_err(|e| Error::file(path, format!("cannot encode PNG: {e}")))?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_scale_puts_the_geometric_middle_at_the_middle_colour() {
        let values = [1.0, 10.0, 100.0];
        let log = false_colour_scaled(&values, 3, 1, "rays", ColourScale::Log);
        assert_eq!(*log.get_pixel(0, 0), viridis(0.0));
        assert_eq!(*log.get_pixel(1, 0), viridis(0.5));
        assert_eq!(*log.get_pixel(2, 0), viridis(1.0));
        let linear = false_colour(&values, 3, 1, "rays");
        assert_eq!(*linear.get_pixel(1, 0), viridis(9.0 / 99.0));
        // Zero or negative values cannot go on a log scale: linear instead.
        let with_zero = false_colour_scaled(&[0.0, 5.0, 10.0], 3, 1, "rays", ColourScale::Log);
        assert_eq!(*with_zero.get_pixel(1, 0), viridis(0.5));
    }
}
