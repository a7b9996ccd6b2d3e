//! Labelled image grids laid out like the paper's figures: tiles in rows, each with a caption
//! strip above it. Captions are drawn with the public-domain 8×8 bitmap font of `font8x8`
//! (doubled), so no font files are needed.

use std::path::Path;

use image::{GrayImage, Luma};

use crate::error::Result;
use crate::image::picture::write_png;
use crate::image::HmdImage;

/// One picture and its caption.
pub struct Tile {
    pub caption: String,
    pub picture: GrayImage,
}

/// Pictures narrower than this are enlarged (nearest texel, integer factor) to fit a caption.
const MIN_TILE_WIDTH: u32 = 144;
/// A caption's glyphs are 8 × this many pixels per this many pixels of tile width: 8 px on a
/// 144-px tile, 48 px on a 1024-px one (12 px when the grid is shown at a quarter).
const TILE_WIDTH_PER_GLYPH_SCALE: u32 = 160;
const GAP: u32 = 6;

/// The glyph scale of captions over tiles `cell_w` pixels wide.
fn glyph_scale(cell_w: u32) -> u32 {
    (cell_w / TILE_WIDTH_PER_GLYPH_SCALE).max(1)
}

/// The height of the caption strip above a tile, for glyphs of `scale`.
fn caption_height(scale: u32) -> u32 {
    8 * scale + 8
}

/// Tiles in rows of `columns`, on white; a `None` leaves its cell empty.
pub fn grid(tiles: &[Option<Tile>], columns: usize) -> GrayImage {
    let enlarged: Vec<Option<Tile>> = tiles
        .iter()
        .map(|t| {
            t.as_ref().map(|t| {
                let k = MIN_TILE_WIDTH.div_ceil(t.picture.width().max(1)).max(1);
                let (w, h) = (t.picture.width() * k, t.picture.height() * k);
                Tile {
                    caption: t.caption.clone(),
                    picture: image::imageops::resize(&t.picture, w, h, image::imageops::FilterType::Nearest),
                }
            })
        })
        .collect();
    let tiles = &enlarged[..];
    let columns = columns.max(1);
    let rows = tiles.len().div_ceil(columns);
    let cell_w = tiles
        .iter()
        .flatten()
        .map(|t| t.picture.width())
        .max()
        .unwrap_or(1);
    let scale = glyph_scale(cell_w);
    let caption_h = caption_height(scale);
    let cell_h = tiles
        .iter()
        .flatten()
        .map(|t| t.picture.height())
        .max()
        .unwrap_or(1)
        + caption_h;
    let width = GAP + columns as u32 * (cell_w + GAP);
    let height = GAP + rows as u32 * (cell_h + GAP);
    let mut out = GrayImage::from_pixel(width, height, Luma([255]));
    for (i, tile) in tiles.iter().enumerate() {
        let Some(tile) = tile else { continue };
        let x0 = GAP + (i % columns) as u32 * (cell_w + GAP);
        let y0 = GAP + (i / columns) as u32 * (cell_h + GAP);
        draw_text(&mut out, x0, y0 + 4, &tile.caption, cell_w, scale);
        image::imageops::replace(&mut out, &tile.picture, x0 as i64, (y0 + caption_h) as i64);
    }
    out
}

/// Draws `text` at (x, y) in black, glyphs of `scale`, cut at `max_width` pixels.
fn draw_text(image: &mut GrayImage, x: u32, y: u32, text: &str, max_width: u32, scale: u32) {
    let fits = (max_width / (8 * scale)) as usize;
    let text: String = text.chars().take(fits).collect();
    crate::image::picture::draw_text(image, x, y, &text, scale, Luma([0]));
}

pub fn write_grid(path: &Path, tiles: &[Option<Tile>], columns: usize) -> Result<()> {
    write_png(&grid(tiles, columns), path)
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

    const CAPTION_HEIGHT: u32 = 16;

    #[test]
    fn captions_grow_with_the_tiles_so_that_a_quarter_size_grid_stays_readable() {
        let tile = Some(Tile {
            caption: "N=16384".into(),
            picture: GrayImage::from_pixel(1024, 4, Luma([200])),
        });
        let g = grid(&[tile], 1);
        let inked_rows = (0..g.height() - 4)
            .filter(|&y| (0..g.width()).any(|x| g.get_pixel(x, y).0[0] == 0))
            .count();
        // 48-px glyphs (12 px at a quarter); "N=16384" has ink in 7 of each glyph's 8 rows.
        assert!(inked_rows >= 40, "caption ink rows: {inked_rows}");
        assert_eq!(g.height(), GAP + 4 + caption_height(6) + GAP);
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
            &GrayImage::from_fn(64, 64, |x, y| Luma([(x + y) as u8])),
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
    fn tiles_land_in_their_cells_below_their_captions() {
        let tile = |v| {
            Some(Tile {
                caption: "A".into(),
                picture: GrayImage::from_pixel(144, 6, Luma([v])),
            })
        };
        let g = grid(&[tile(10), None, tile(20)], 2);
        assert_eq!(
            (g.width(), g.height()),
            (GAP + 2 * (144 + GAP), GAP + 2 * (6 + CAPTION_HEIGHT + GAP))
        );
        assert_eq!(g.get_pixel(GAP, GAP + CAPTION_HEIGHT).0[0], 10);
        let second_row = GAP + (6 + CAPTION_HEIGHT + GAP);
        assert_eq!(g.get_pixel(GAP, second_row + CAPTION_HEIGHT).0[0], 20);
        assert_eq!(
            g.get_pixel(GAP + 144 + GAP, GAP + CAPTION_HEIGHT).0[0],
            255,
            "the empty cell stays white"
        );
        let ink = (0..CAPTION_HEIGHT)
            .flat_map(|y| (0..10).map(move |x| (x, y)))
            .any(|(x, y)| g.get_pixel(GAP + x, GAP + y).0[0] == 0);
        assert!(ink, "the caption is drawn");
    }
}
