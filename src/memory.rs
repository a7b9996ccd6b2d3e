//! Memory a request will need, checked against the memory available before anything is
//! allocated: a request that cannot fit is refused at once with what it needs and what there
//! is, instead of being killed by the operating system minutes in (issue #16).
//!
//! The figures are the measured peaks, rounded up: the render's per-pixel buffers
//! ([`image_bytes`]), the BVH build ([`BVH_BYTES_PER_TRIANGLE`]) and the photon map's build
//! (`PhotonMethod::peak_build_bytes`). Where the available memory cannot be known (no
//! `/proc/meminfo`), nothing is refused.

use crate::accel::Hit;
use crate::error::{Error, Result};
use crate::estimators::AovSample;

/// Peak memory of building the BVH, per triangle, beyond the mesh itself: 290 B measured with
/// obvhs's best preset on a 5 M-triangle sphere (210 B with our binned SAH builder).
pub const BVH_BYTES_PER_TRIANGLE: u128 = 320;

/// `MemAvailable` of /proc/meminfo, where there is one.
pub fn available() -> Option<u128> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u128 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory a render of `pixels` pixels with `aovs` AOV channels holds at its peak: the
/// G-buffer, H, the AOV samples and the encoded EXR's channels.
pub fn image_bytes(pixels: u64, aovs: usize) -> u128 {
    let samples = if aovs == 0 { 0 } else { size_of::<AovSample>() };
    let per_pixel = size_of::<Option<Hit>>() + 4 + samples + 2 * 4 * (1 + aovs);
    pixels as u128 * per_pixel as u128
}

/// Refuses `needed` bytes for `what` where more than `available` bytes (or, for `None`, the
/// memory available now) would be needed: a [`Error::Parameter`] on `parameter` (`None`:
/// [`Error::Scene`]), saying how much is needed and how much there is.
pub fn check(
    parameter: Option<&'static str>,
    what: &str,
    needed: u128,
    available: Option<u128>,
) -> Result<()> {
    let Some(available) = available.or_else(self::available) else {
        return Ok(());
    };
    if needed <= available {
        return Ok(());
    }
    let message = format!(
        "{what} needs about {:.1} GB of memory, but only {:.1} GB is available",
        needed as f64 / 1e9,
        available as f64 / 1e9
    );
    Err(match parameter {
        Some(name) => Error::invalid(name, message),
        None => Error::scene(message),
    })
}

/// Refuses a BVH over `triangles` triangles that would not fit in the memory available now.
pub fn check_bvh(triangles: usize) -> Result<()> {
    let what = format!("the BVH of the scene's {triangles} triangles");
    check(None, &what, triangles as u128 * BVH_BYTES_PER_TRIANGLE, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_over_the_available_memory_is_refused_saying_what_it_needs() {
        let gb = 1_000_000_000;
        assert!(check(Some("size"), "x", 2 * gb, Some(2 * gb)).is_ok());
        let e = check(Some("size"), "8192x8192", 3 * gb, Some(2 * gb)).unwrap_err();
        let expected =
            "bad parameter: size 8192x8192 needs about 3.0 GB of memory, but only 2.0 GB is available";
        assert_eq!(e.to_string(), expected);
        let e = check(None, "the BVH", 5 * gb, Some(gb)).unwrap_err();
        assert!(matches!(e, Error::Scene(_)), "{e}");
    }

    #[test]
    fn an_image_needs_its_g_buffer_and_channels() {
        let one = image_bytes(1, 0);
        assert!(one >= size_of::<Option<Hit>>() as u128 + 4, "{one}");
        assert_eq!(image_bytes(1000, 0), 1000 * one);
        assert!(image_bytes(1, 2) > one + 2 * 4);
    }
}
