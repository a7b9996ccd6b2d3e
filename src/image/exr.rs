//! OpenEXR files with a float32 channel `Y` holding H per pixel (spec §7), and one float32
//! channel per AOV beside it, named as the AOV (spec §8). An irradiance image
//! (`--method irradiance`) names its channel `E` instead of `Y`.

use std::io::Cursor;
use std::path::Path;

use exr::prelude::*;

use super::{write_atomically, HmdImage};
use crate::error::{catch_file_panic, Error as HmdError, Result};
use crate::estimators::AovImage;
use crate::options::MAX_PIXELS;

/// The channel name every hmdist EXR of H uses, `Y`.
pub use crate::estimators::HMD_CHANNEL as CHANNEL;

/// The channel an image of irradiance uses instead of [`CHANNEL`], `E`.
pub use crate::estimators::irradiance::CHANNEL as IRRADIANCE_CHANNEL;

/// Writes `image` to the EXR file `path`, through a temporary file and a rename.
pub fn write(image: &HmdImage, path: &Path) -> Result<()> {
    write_atomically(path, &encode(image, &[], path)?)
}

/// The bytes of the EXR file of `image` (H, channel `Y`) and its `aovs`; `path` names the
/// file in errors.
pub fn encode(image: &HmdImage, aovs: &[AovImage], path: &Path) -> Result<Vec<u8>> {
    encode_as(CHANNEL, image, aovs, path)
}

/// [`encode`] with the image's channel named `channel` (an estimator's
/// [`crate::estimators::Estimator::channel`]).
pub fn encode_as(channel: &str, image: &HmdImage, aovs: &[AovImage], path: &Path) -> Result<Vec<u8>> {
    encode_with(channel, image, aovs, &[], path)
}

/// [`encode_as`] with `extra` channels `(name, values)` after the AOVs (a shard's part of a
/// denoised render: the filter's guide).
pub fn encode_with(
    channel: &str,
    image: &HmdImage,
    aovs: &[AovImage],
    extra: &[(&str, &[f32])],
    path: &Path,
) -> Result<Vec<u8>> {
    let mut channels: Vec<(&str, &[f32])> = vec![(channel, &image.data)];
    channels.extend(aovs.iter().map(|aov| (aov.aov.name(), &aov.data[..])));
    channels.extend_from_slice(extra);
    encode_channels(&channels, (image.width, image.height), path)
}

/// The bytes of an EXR file of float32 channels `(name, values)` over `width × height`
/// pixels (row-major, row 0 at the top); `path` names the file in errors.
pub fn encode_channels(
    channels: &[(&str, &[f32])],
    (width, height): (u32, u32),
    path: &Path,
) -> Result<Vec<u8>> {
    let channels: SmallVec<_> = channels
        .iter()
        .map(|(name, values)| AnyChannel::new(*name, FlatSamples::F32(values.to_vec())))
        .collect();
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::named("hmd"),
        // Scan lines in increasing order: the file's bytes depend only on the pixels, not on
        // which compression thread finished first (exr's default order is unspecified).
        Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(channels),
    );
    let mut bytes = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| HmdError::file(path, format!("cannot encode EXR: {e}")))?;
    Ok(bytes.into_inner())
}

/// Reads the channel `name` of an EXR's first layer, as an image.
pub fn read_channel(path: &Path, name: &str) -> Result<HmdImage> {
    read_named(path, name, false)
}

/// Reads the denoiser's guide ([`crate::denoise::GUIDE_CHANNELS`]) from a shard's part of a
/// denoised render.
pub fn read_guide(path: &Path) -> Result<crate::denoise::Guide> {
    let channels = crate::denoise::GUIDE_CHANNELS
        .iter()
        .map(|name| read_channel(path, name))
        .collect::<Result<Vec<_>>>()?;
    let (width, height) = (channels[0].width, channels[0].height);
    let data: Vec<Vec<f32>> = channels.into_iter().map(|c| c.data).collect();
    crate::denoise::Guide::from_channels(width, height, &data)
        .map_err(|e| HmdError::file(path, e.to_string()))
}

/// Reads an EXR written by hmdist (or any EXR whose first layer has a `Y` channel, or a
/// single channel): its `Y`, or its `E` where it has no `Y` (an irradiance image).
pub fn read(path: &Path) -> Result<HmdImage> {
    read_named(path, CHANNEL, true)
}

fn read_named(path: &Path, name: &str, only_channel_will_do: bool) -> Result<HmdImage> {
    let bytes = crate::files::read_regular(path)?;
    decode_named(&bytes, path, name, only_channel_will_do)
}

/// [`read()`] of the file at `path` whose bytes are `bytes`.
pub fn decode(bytes: &[u8], path: &Path) -> Result<HmdImage> {
    decode_named(bytes, path, CHANNEL, true)
}

fn decode_named(bytes: &[u8], path: &Path, name: &str, only_channel_will_do: bool) -> Result<HmdImage> {
    check_declared_size(bytes, path)?;
    let image = catch_file_panic(path, || {
        exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
            .map_err(|e| HmdError::file(path, format!("not a readable EXR image: {e}")))
    })?;
    let layer = &image.layer_data;
    let channels = &layer.channel_data.list;
    let named = |n: &str| channels.iter().find(|c| c.name.eq(n));
    // An image of irradiance has E where an image of H has Y.
    let irradiance = only_channel_will_do && name == CHANNEL;
    let channel = named(name)
        .or_else(|| irradiance.then(|| named(IRRADIANCE_CHANNEL)).flatten())
        .or(if only_channel_will_do && channels.len() == 1 {
            channels.first()
        } else {
            None
        })
        .ok_or_else(|| HmdError::file(path, format!("the EXR has no channel named {name}")))?;
    let data: Vec<f32> = channel.sample_data.values_as_f32().collect();
    let (w, h) = (layer.size.width(), layer.size.height());
    if data.len() != w * h || u32::try_from(w.max(h)).is_err() {
        let message = format!(
            "channel {} holds {} values for a {w}x{h} image (subsampled channels are not \
             supported)",
            channel.name,
            data.len()
        );
        return Err(HmdError::file(path, message));
    }
    Ok(HmdImage::new(w as u32, h as u32, data))
}

/// Pixel bytes an EXR may declare per byte of file: deflate (ZIP) gives at most 1032:1, RLE
/// 64:1; a wide margin for PIZ's run-length Huffman codes.
const MAX_COMPRESSION: u128 = 4096;
/// Pixel bytes any file may declare, however small: 16 MB (a 2048² float image).
const MIN_DECLARED_BYTES: u128 = 1 << 24;

/// Refuses, from its headers alone, an EXR whose pixels could not be held or could not be
/// in the file: the exr crate reserves every channel's samples as the header declares them
/// before it reads any, and a failed allocation aborts the process (found by fuzzing: a
/// 379-byte file declaring a layer of 77 GB). A layer may have at most [`MAX_PIXELS`]
/// pixels, as an image hmdist renders; at most [`MAX_COMPRESSION`] bytes of samples per byte
/// of file (or [`MIN_DECLARED_BYTES`]); and its samples must fit in the memory available.
/// Headers that cannot be read are left to the reader to refuse in its words.
fn check_declared_size(bytes: &[u8], path: &Path) -> Result<()> {
    let Ok(meta) = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false) else {
        return Ok(());
    };
    for header in &meta.headers {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        let pixels = w as u128 * h as u128;
        if pixels > MAX_PIXELS as u128 {
            let message = format!(
                "declares a {w}x{h} image, more than the {MAX_PIXELS} pixels an hmdist image may have"
            );
            return Err(HmdError::file(path, message));
        }
        let stored: usize = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample())
            .sum();
        let limit = (bytes.len() as u128 * MAX_COMPRESSION).max(MIN_DECLARED_BYTES);
        if pixels * stored as u128 > limit {
            let message = format!(
                "declares a {w}x{h} image of {} MB in a file of {} bytes: no compression gives \
                 that (the file is damaged or cut short)",
                pixels * stored as u128 / 1_000_000,
                bytes.len()
            );
            return Err(HmdError::file(path, message));
        }
        // Every channel as stored, and one as f32 (the channel read).
        let per_pixel = 4 + stored;
        let what = format!("its {w}x{h} image of {} channels", header.channels.list.len());
        crate::memory::check(None, &what, pixels * per_pixel as u128, None).map_err(|e| match e {
            HmdError::Scene(message) => HmdError::file(path, message),
            other => other,
        })?;
    }
    Ok(())
}
