//! Grey pictures of HMD images (SPEC §4): `grey = clamp(s · H)`; NaN pixels (background,
//! holes) are drawn black, `+inf` white.

use std::io::Cursor;
use std::path::Path;

use image::{GrayImage, ImageFormat, Luma};

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

/// Writes `picture` to the PNG file `path`, through a temporary file and a rename.
pub fn write_png(picture: &GrayImage, path: &Path) -> Result<()> {
    write_atomically(path, &encode_png(picture, path)?)
}

/// The bytes of the PNG file of `picture`; `path` names the file in errors.
pub fn encode_png(picture: &GrayImage, path: &Path) -> Result<Vec<u8>> {
    let mut bytes = Cursor::new(Vec::new());
    picture
        .write_to(&mut bytes, ImageFormat::Png)
        .map_err(|e| Error::file(path, format!("cannot encode PNG: {e}")))?;
    Ok(bytes.into_inner())
}
