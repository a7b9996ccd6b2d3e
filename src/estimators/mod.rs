//! The HMD estimators of SPEC §3, behind one interface.
//!
//! The render driver ([`crate::render`]) finds each pixel's surface point with a primary ray
//! and hands the whole [`GBuffer`] to an [`Estimator`], which returns H per pixel. Estimators
//! work on the whole image at once because some must (photon maps are built once per image;
//! hemicubes are rasterised in batches on a GPU). Adding a fifth estimator is one new module
//! implementing [`Estimator`].
//!
//! Conventions: distances in scene units; a pixel's normal faces the camera (surfaces are
//! two-sided); H is `+inf` where every sample escaped and NaN for background pixels and holes.

pub mod cubemap;
pub mod gather;
mod harmonic;
pub mod photon;

pub use cubemap::Cubemap;
pub use gather::Gather;
pub use harmonic::{DistanceClamp, HarmonicMean};
pub use photon::PhotonEstimator;

use crate::accel::{Accel, Hit};
use crate::error::Result;
use crate::progress::Progress;

/// Each pixel's first surface hit, normal flipped to face the camera; `None` for background.
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    pub points: Vec<Option<Hit>>,
}

impl GBuffer {
    pub fn background_pixels(&self) -> usize {
        self.points.iter().filter(|p| p.is_none()).count()
    }
}

/// What every estimator may use besides the G-buffer.
pub struct EstimateContext<'a> {
    pub accel: &'a Accel,
    pub scene: &'a crate::scene::Scene,
    /// Counter-based random numbers are keyed by this seed (SPEC §2).
    pub seed: u64,
    pub clamp: DistanceClamp,
}

/// The rays an estimator cast through the scene (primary rays not included), for the report's
/// `rays_cast`, `escaped_rays` and `mrays_per_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayCount {
    pub cast: u64,
    /// Rays that hit nothing (within `--max-distance`, where the estimator's rays stop there).
    pub escaped: u64,
    /// Seconds of the phase that cast them.
    pub seconds: f64,
}

/// An estimator's output: H per pixel (row-major, row 0 at the top) and what it cost.
pub struct Estimate {
    pub hmd: Vec<f32>,
    /// The rays cast; `None` for an estimator that casts none (the GPU cube map rasterises).
    pub rays: Option<RayCount>,
    /// Named phases and their seconds, e.g. `("estimate", 1.2)`; written to the JSON sidecar.
    pub phases: Vec<(&'static str, f64)>,
    /// Method-specific figures for the JSON sidecar.
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// The fields of a JSON object literal, for [`Estimator::parameters`] and [`Estimate::extra`].
pub(crate) fn fields(value: serde_json::Value) -> serde_json::Map<String, serde_json::Value> {
    match value {
        serde_json::Value::Object(map) => map,
        _ => serde_json::Map::new(),
    }
}

/// One way of computing H per pixel.
pub trait Estimator: Sync {
    /// The method's name as the CLI spells it (`gather`, `cubemap`, ...).
    fn method(&self) -> &'static str;

    /// The method's parameters, for the JSON sidecar.
    fn parameters(&self) -> serde_json::Map<String, serde_json::Value>;

    /// About how many rays the estimator will cast for an image of `pixels` surface pixels
    /// (primary rays not included): chooses the BVH preset ([`crate::accel::BuildQuality`]).
    fn expected_rays(&self, pixels: u64) -> u64;

    fn estimate(
        &self,
        context: &EstimateContext,
        gbuffer: &GBuffer,
        progress: &dyn Progress,
    ) -> Result<Estimate>;
}
