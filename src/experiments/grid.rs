//! Labelled image grids laid out like the paper's figures: tiles in rows, each with a caption
//! strip above it. Captions are drawn with the public-domain 8×8 bitmap font of `font8x8`
//! (doubled), so no font files are needed.

use std::path::Path;

use image::{GrayImage, Luma};

use crate::error::Result;
use crate::image::picture::write_png;

/// One picture and its caption.
pub struct Tile {
    pub caption: String,
    pub picture: GrayImage,
}

const GLYPH_SCALE: u32 = 1;
/// Pictures narrower than this are enlarged (nearest texel, integer factor) to fit a caption.
const MIN_TILE_WIDTH: u32 = 144;
const CAPTION_HEIGHT: u32 = 8 * GLYPH_SCALE + 8;
const GAP: u32 = 6;

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
    let cell_h = tiles
        .iter()
        .flatten()
        .map(|t| t.picture.height())
        .max()
        .unwrap_or(1)
        + CAPTION_HEIGHT;
    let width = GAP + columns as u32 * (cell_w + GAP);
    let height = GAP + rows as u32 * (cell_h + GAP);
    let mut out = GrayImage::from_pixel(width, height, Luma([255]));
    for (i, tile) in tiles.iter().enumerate() {
        let Some(tile) = tile else { continue };
        let x0 = GAP + (i % columns) as u32 * (cell_w + GAP);
        let y0 = GAP + (i / columns) as u32 * (cell_h + GAP);
        draw_text(&mut out, x0, y0 + 4, &tile.caption, cell_w);
        image::imageops::replace(&mut out, &tile.picture, x0 as i64, (y0 + CAPTION_HEIGHT) as i64);
    }
    out
}

/// Draws `text` at (x, y) in black, cut at `max_width` pixels.
fn draw_text(image: &mut GrayImage, x: u32, y: u32, text: &str, max_width: u32) {
    let fits = (max_width / (8 * GLYPH_SCALE)) as usize;
    let text: String = text.chars().take(fits).collect();
    crate::image::picture::draw_text(image, x, y, &text, GLYPH_SCALE, Luma([0]));
}

pub fn write_grid(path: &Path, tiles: &[Option<Tile>], columns: usize) -> Result<()> {
    write_png(&grid(tiles, columns), path)
}

#[cfg(test)]
mod tests {
    use super::*;

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
