//! Labelled image grids laid out like the paper's figures: tiles in rows, each with an
//! optional caption strip above it, optional labels above the columns and left of the rows.
//! Labels are drawn with the public-domain 8×8 bitmap font of `font8x8`, scaled so that they
//! stay readable when the report shows the grid at its page width, so no font files are
//! needed.

use std::path::Path;

use image::{GrayImage, Rgb, RgbImage};

use crate::error::Result;
use crate::image::picture::encode_png;
use crate::image::{write_atomically, HmdImage};

/// One picture and its caption (empty for none).
pub struct Tile {
    pub caption: String,
    pub picture: RgbImage,
}

impl Tile {
    /// A grey picture with `caption`.
    pub fn grey(caption: impl Into<String>, picture: &GrayImage) -> Tile {
        Tile {
            caption: caption.into(),
            picture: image::DynamicImage::ImageLuma8(picture.clone()).to_rgb8(),
        }
    }

    /// A colour picture with `caption`.
    pub fn colour(caption: impl Into<String>, picture: RgbImage) -> Tile {
        Tile {
            caption: caption.into(),
            picture,
        }
    }
}

/// What a grid's rows and columns stand for: one label per column, drawn above it, and one
/// per row, drawn left of it (either list may be empty).
#[derive(Default)]
pub struct Labels {
    pub columns: Vec<String>,
    pub rows: Vec<String>,
}

/// Pictures narrower than this are enlarged (nearest texel, integer factor).
const MIN_TILE_WIDTH: u32 = 144;
/// The width at which the report shows a grid (its text column: 60em of 16 px): wider grids
/// are shrunk to it.
pub const PAGE_WIDTH: u32 = 960;
/// The least glyph height, in pixels at page width, that a label may have.
pub const MIN_GLYPH_PX: u32 = 12;
const GAP: u32 = 6;
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const INK: Rgb<u8> = Rgb([0, 0, 0]);

/// A grid's layout: glyph scale, strips and cells.
struct Layout {
    scale: u32,
    caption_h: u32,
    column_label_h: u32,
    row_label_w: u32,
    cell_w: u32,
    cell_h: u32,
    width: u32,
    height: u32,
}

impl Layout {
    /// The layout of `rows` × `columns` cells of `tile` pixels (the largest tile), with
    /// captions where `captions`, and `labels`, at glyph scale `scale`.
    fn at(scale: u32, tile: (u32, u32), rows: u32, columns: u32, captions: bool, labels: &Labels) -> Layout {
        let strip = 10 * scale;
        let caption_h = if captions { strip } else { 0 };
        let column_label_h = if labels.columns.is_empty() { 0 } else { strip };
        let longest = labels.rows.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
        let row_label_w = if longest == 0 {
            0
        } else {
            8 * scale * longest + 2 * scale
        };
        let (cell_w, cell_h) = (tile.0, tile.1 + caption_h);
        Layout {
            scale,
            caption_h,
            column_label_h,
            row_label_w,
            cell_w,
            cell_h,
            width: row_label_w + GAP + columns * (cell_w + GAP),
            height: column_label_h + GAP + rows * (cell_h + GAP),
        }
    }

    /// The glyph height, in pixels, of this layout's labels when shown at [`PAGE_WIDTH`].
    fn glyph_px_at_page_width(&self) -> f64 {
        let shrink = (PAGE_WIDTH as f64 / self.width as f64).min(1.0);
        8.0 * self.scale as f64 * shrink
    }

    /// The smallest glyph scale whose labels are [`MIN_GLYPH_PX`] or more at page width.
    fn readable(tile: (u32, u32), rows: u32, columns: u32, captions: bool, labels: &Labels) -> Layout {
        let mut scale = 1;
        loop {
            let layout = Layout::at(scale, tile, rows, columns, captions, labels);
            if layout.glyph_px_at_page_width() >= MIN_GLYPH_PX as f64 || scale >= 256 {
                return layout;
            }
            scale += 1;
        }
    }
}

/// Tiles in rows of `columns`, on white, with `labels` above the columns and left of the
/// rows; a `None` leaves its cell empty.
pub fn labelled_grid(tiles: &[Option<Tile>], columns: usize, labels: &Labels) -> RgbImage {
    let enlarged: Vec<Option<Tile>> = tiles
        .iter()
        .map(|t| {
            t.as_ref().map(|t| {
                let k = MIN_TILE_WIDTH.div_ceil(t.picture.width().max(1)).max(1);
                let (w, h) = (t.picture.width() * k, t.picture.height() * k);
                Tile::colour(
                    t.caption.clone(),
                    image::imageops::resize(&t.picture, w, h, image::imageops::FilterType::Nearest),
                )
            })
        })
        .collect();
    let tiles = &enlarged[..];
    let columns = columns.max(1);
    let rows = tiles.len().div_ceil(columns).max(labels.rows.len());
    let largest = |side: fn(&RgbImage) -> u32| {
        tiles
            .iter()
            .flatten()
            .map(|t| side(&t.picture))
            .max()
            .unwrap_or(1)
    };
    let tile = (largest(RgbImage::width), largest(RgbImage::height));
    let captions = tiles.iter().flatten().any(|t| !t.caption.is_empty());
    let l = Layout::readable(tile, rows as u32, columns as u32, captions, labels);
    let mut out = RgbImage::from_pixel(l.width, l.height, WHITE);
    let cell_x = |column: u32| l.row_label_w + GAP + column * (l.cell_w + GAP);
    let cell_y = |row: u32| l.column_label_h + GAP + row * (l.cell_h + GAP);
    for (column, label) in labels.columns.iter().enumerate().take(columns) {
        draw_text(&mut out, cell_x(column as u32), l.scale, label, l.cell_w, l.scale);
    }
    for (row, label) in labels.rows.iter().enumerate() {
        let y = cell_y(row as u32) + l.caption_h + (l.cell_h - l.caption_h).saturating_sub(8 * l.scale) / 2;
        draw_text(&mut out, l.scale, y, label, l.row_label_w, l.scale);
    }
    for (i, tile) in tiles.iter().enumerate() {
        let Some(tile) = tile else { continue };
        let (x0, y0) = (cell_x((i % columns) as u32), cell_y((i / columns) as u32));
        draw_text(&mut out, x0, y0 + l.scale, &tile.caption, l.cell_w, l.scale);
        image::imageops::replace(&mut out, &tile.picture, x0 as i64, (y0 + l.caption_h) as i64);
    }
    out
}

/// Draws `text` at (x, y) in black, glyphs of `scale`, cut at `max_width` pixels.
fn draw_text(image: &mut RgbImage, x: u32, y: u32, text: &str, max_width: u32, scale: u32) {
    let fits = (max_width / (8 * scale)) as usize;
    let text: String = text.chars().take(fits).collect();
    crate::image::picture::draw_text(image, x, y, &text, scale, INK);
}

/// Writes `tiles` as a [`labelled_grid`] of `columns`, without labels, to the PNG file `path`.
pub fn write_grid(path: &Path, tiles: &[Option<Tile>], columns: usize) -> Result<()> {
    write_labelled_grid(path, tiles, columns, &Labels::default())
}

/// Writes `tiles` as a [`labelled_grid`] to the PNG file `path`: grey where every pixel is.
pub fn write_labelled_grid(
    path: &Path,
    tiles: &[Option<Tile>],
    columns: usize,
    labels: &Labels,
) -> Result<()> {
    let picture = labelled_grid(tiles, columns, labels);
    let bytes = if picture.pixels().all(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2]) {
        encode_png(&image::DynamicImage::ImageRgb8(picture).to_luma8(), path)?
    } else {
        encode_png(&picture, path)?
    };
    write_atomically(path, &bytes)
}

/// Up to `count` square windows of `side` pixels, none overlapping another, where `a` and `b`
/// differ most (the largest mean |a − b| over the window; pixels not finite in either count
/// 0): the top-left corners, best first. Windows start on a grid of `side / 4` pixels.
pub fn windows_differing_most(a: &HmdImage, b: &HmdImage, side: u32, count: usize) -> Vec<(u32, u32)> {
    let (w, h) = (a.width.min(b.width), a.height.min(b.height));
    if side == 0 || side > w || side > h {
        return vec![];
    }
    // A summed-area table of |a − b|: any window's sum in four lookups.
    let stride = w as usize + 1;
    let mut sums = vec![0.0f64; stride * (h as usize + 1)];
    for y in 0..h {
        for x in 0..w {
            let d = (a.at(x, y) - b.at(x, y)).abs();
            let d = if d.is_finite() { d as f64 } else { 0.0 };
            let (i, up) = (
                (y as usize + 1) * stride + x as usize + 1,
                y as usize * stride + x as usize + 1,
            );
            sums[i] = d + sums[i - 1] + sums[up] - sums[up - 1];
        }
    }
    let window = |x: u32, y: u32| {
        let (x0, y0, x1, y1) = (x as usize, y as usize, (x + side) as usize, (y + side) as usize);
        sums[y1 * stride + x1] - sums[y0 * stride + x1] - sums[y1 * stride + x0] + sums[y0 * stride + x0]
    };
    let step = (side / 4).max(1);
    let mut candidates: Vec<(f64, u32, u32)> = (0..=(h - side) / step)
        .flat_map(|j| (0..=(w - side) / step).map(move |i| (i * step, j * step)))
        .map(|(x, y)| (window(x, y), x, y))
        .collect();
    candidates.sort_by(|p, q| q.0.total_cmp(&p.0).then((p.2, p.1).cmp(&(q.2, q.1))));
    let mut chosen: Vec<(u32, u32)> = vec![];
    for (_, x, y) in candidates {
        let apart = |&(cx, cy): &(u32, u32)| x.abs_diff(cx) >= side || y.abs_diff(cy) >= side;
        if chosen.iter().all(apart) {
            chosen.push((x, y));
            if chosen.len() == count {
                break;
            }
        }
    }
    chosen
}

/// The `side`-pixel square of `picture` at (x, y), enlarged `zoom` times (nearest pixel).
pub fn crop(picture: &GrayImage, (x, y): (u32, u32), side: u32, zoom: u32) -> GrayImage {
    let part = image::imageops::crop_imm(picture, x, y, side, side).to_image();
    image::imageops::resize(
        &part,
        side * zoom,
        side * zoom,
        image::imageops::FilterType::Nearest,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of `g` from `top` to `bottom` (exclusive) with black ink in them.
    fn inked_rows(g: &RgbImage, top: u32, bottom: u32) -> u32 {
        (top..bottom.min(g.height()))
            .filter(|&y| (0..g.width()).any(|x| g.get_pixel(x, y).0 == [0, 0, 0]))
            .count() as u32
    }

    /// `tiles` tiles `side` pixels wide and half as tall (the width sets the glyph scale; the
    /// height need only hold a row label) of mid grey, captioned where `caption`.
    fn tiles(count: usize, side: u32, caption: &str) -> Vec<Option<Tile>> {
        (0..count)
            .map(|_| {
                Some(Tile::grey(
                    caption,
                    &GrayImage::from_pixel(side, side / 2, image::Luma([200])),
                ))
            })
            .collect()
    }

    #[test]
    fn every_label_is_readable_at_page_width_whatever_the_grid() {
        // The figures' shapes: 1 to 8 columns of tiles from the quick preset's 48 px (shown
        // enlarged to 144) to the paper's 1024, with and without captions and row labels.
        // Digits and capitals ink 7 of a glyph's 8 rows.
        let need = 7.0 / 8.0 * MIN_GLYPH_PX as f64;
        for side in [48, 256, 1024] {
            for columns in 1..=8 {
                for (caption, rows) in [("N=16384", vec![]), ("", vec!["8530K".to_string(); 5])] {
                    let labels = Labels {
                        columns: vec!["K=1024".into(); columns],
                        rows: rows.clone(),
                    };
                    let g = labelled_grid(&tiles(columns * 5, side, caption), columns, &labels);
                    let shrink = (PAGE_WIDTH as f64 / g.width() as f64).min(1.0);
                    let k = MIN_TILE_WIDTH.div_ceil(side);
                    let l = Layout::readable(
                        (side * k, side / 2 * k),
                        5,
                        columns as u32,
                        !caption.is_empty(),
                        &labels,
                    );
                    assert_eq!((l.width, l.height), (g.width(), g.height()));
                    let column_ink = inked_rows(&g, 0, l.column_label_h) as f64 * shrink;
                    assert!(
                        column_ink >= need,
                        "{side} px x {columns}: column labels {column_ink:.1} px at page width"
                    );
                    if !caption.is_empty() {
                        let top = l.column_label_h + GAP;
                        let caption_ink = inked_rows(&g, top, top + l.caption_h) as f64 * shrink;
                        assert!(
                            caption_ink >= need,
                            "{side} px x {columns}: captions {caption_ink:.1} px"
                        );
                    }
                    if !rows.is_empty() {
                        let left = RgbImage::from_fn(l.row_label_w, g.height(), |x, y| *g.get_pixel(x, y));
                        let row_ink = inked_rows(&left, 0, left.height()) as f64 / 5.0 * shrink;
                        assert!(
                            row_ink >= need,
                            "{side} px x {columns}: row labels {row_ink:.1} px"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_windows_found_are_where_the_images_differ_most_and_do_not_overlap() {
        // Two patches of difference planted in a 64² image: a strong one of 8² at (40, 8), a
        // weaker one of 8² at (8, 48); NaN elsewhere in one image counts as no difference.
        let a = HmdImage::new(64, 64, vec![1.0; 64 * 64]);
        let mut b = a.clone();
        for y in 0..8 {
            for x in 0..8 {
                b.data[(8 + y) * 64 + 40 + x] = 5.0;
                b.data[(48 + y) * 64 + 8 + x] = 3.0;
            }
        }
        b.data[0] = f32::NAN;
        let found = windows_differing_most(&a, &b, 16, 3);
        assert_eq!(found.len(), 3);
        let holds = |(x, y): (u32, u32), (px, py): (u32, u32)| {
            x <= px && px + 8 <= x + 16 && y <= py && py + 8 <= y + 16
        };
        assert!(holds(found[0], (40, 8)), "{found:?}");
        assert!(holds(found[1], (8, 48)), "{found:?}");
        for (i, p) in found.iter().enumerate() {
            for q in &found[i + 1..] {
                assert!(
                    p.0.abs_diff(q.0) >= 16 || p.1.abs_diff(q.1) >= 16,
                    "{p:?} overlaps {q:?}"
                );
            }
        }
        assert!(windows_differing_most(&a, &b, 65, 1).is_empty());
        let zoomed = crop(
            &GrayImage::from_fn(64, 64, |x, y| image::Luma([(x + y) as u8])),
            (40, 8),
            16,
            2,
        );
        assert_eq!(
            (
                zoomed.width(),
                zoomed.get_pixel(0, 0).0[0],
                zoomed.get_pixel(31, 31).0[0]
            ),
            (32, 48, 78)
        );
    }

    #[test]
    fn tiles_land_in_their_cells_below_their_captions_and_beside_their_labels() {
        let tile = |v| Some(Tile::grey("A", &GrayImage::from_pixel(144, 6, image::Luma([v]))));
        let labels = Labels {
            columns: vec!["c0".into(), "c1".into()],
            rows: vec!["r0".into(), "r1".into()],
        };
        let g = labelled_grid(&[tile(10), None, tile(20)], 2, &labels);
        // Small enough to be shown at its own size: glyphs of scale 2 (16 px), strips of 20.
        let (scale, strip) = (2, 20);
        let label_w = 8 * scale * 2 + 2 * scale;
        let cell_h = 6 + strip;
        assert_eq!(
            (g.width(), g.height()),
            (label_w + GAP + 2 * (144 + GAP), strip + GAP + 2 * (cell_h + GAP))
        );
        let (x0, y0) = (label_w + GAP, strip + GAP);
        assert_eq!(g.get_pixel(x0, y0 + strip).0, [10; 3]);
        assert_eq!(g.get_pixel(x0, y0 + cell_h + GAP + strip).0, [20; 3]);
        assert_eq!(
            g.get_pixel(x0 + 144 + GAP, y0 + strip).0,
            [255; 3],
            "the empty cell stays white"
        );
        assert!(inked_rows(&g, y0, y0 + strip) > 0, "the caption is drawn");
        assert!(inked_rows(&g, 0, strip) > 0, "the column labels are drawn");
        let left = RgbImage::from_fn(label_w, g.height(), |x, y| *g.get_pixel(x, y));
        assert!(
            inked_rows(&left, y0, y0 + cell_h) > 0,
            "the first row's label is drawn beside it"
        );
    }
}
