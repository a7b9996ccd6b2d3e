//! What a cache is built with, besides the image's options.

use super::spacing::{Range, Spacing};
use crate::estimators::IrradianceParams;

/// Default accuracy a: Ward's recommended range is 0.1 … 0.2.
pub const DEFAULT_ACCURACY: f32 = 0.2;

/// What a cache is built with, besides the image's options.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheParams {
    /// The records' irradiance: rays M, weighting, sampler, absorption.
    pub irradiance: IrradianceParams,
    /// Ward's a: a point uses records with ε < a.
    pub accuracy: f32,
    /// Where each record's radius comes from.
    pub spacing: Spacing,
    /// Clamp of the radius, in pixel footprints at the record (pbrt-v2: 2.5, 15).
    pub clamp_pixels: Option<Range>,
    /// Clamp of the radius, in fractions of `l_diag` (Mitsuba: 0.005, 0.32).
    pub clamp_scene: Option<Range>,
    /// Křivánek's neighbour clamping of the radii ([`super::neighbours`]).
    pub neighbour_clamp: bool,
    /// Ward and Heckbert's gradients in the interpolation ([`super::gradients`]).
    pub gradients: bool,
}

impl Default for CacheParams {
    fn default() -> Self {
        CacheParams {
            irradiance: IrradianceParams::default(),
            accuracy: DEFAULT_ACCURACY,
            spacing: Spacing::Hmd,
            clamp_pixels: None,
            clamp_scene: None,
            neighbour_clamp: false,
            gradients: false,
        }
    }
}
