//! AOVs: per-pixel companions of H, written as EXR channels beside `Y` (spec §8).
//!
//! - `relerr`: relative standard error of H, from the spread of independent stratified
//!   rounds (batch means);
//! - `rays`: rays cast for the pixel;
//! - `dmin`: the smallest hit distance over the pixel's rays (`+inf` if all escaped);
//! - `ao`: ambient occlusion, the cosine-weighted fraction of directions that meet nothing
//!   within the AO radius;
//! - `escaped`: the fraction of rays that met nothing;
//! - `E_direct` (`irradiance` only): the direct irradiance from the spot light at the pixel's
//!   point.

pub use crate::options::Aov;

/// One pixel's AOVs; NaN where not measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AovSample {
    /// Relative standard error of H.
    pub relerr: f32,
    /// Rays cast.
    pub rays: f32,
    /// Smallest hit distance.
    pub dmin: f32,
    /// Ambient occlusion.
    pub ao: f32,
    /// Fraction of rays that escaped.
    pub escaped: f32,
    /// Direct irradiance.
    pub e_direct: f32,
}

impl Default for AovSample {
    fn default() -> Self {
        AovSample {
            relerr: f32::NAN,
            rays: f32::NAN,
            dmin: f32::NAN,
            ao: f32::NAN,
            escaped: f32::NAN,
            e_direct: f32::NAN,
        }
    }
}

impl AovSample {
    /// The value of `aov`.
    pub fn get(&self, aov: Aov) -> f32 {
        match aov {
            Aov::Relerr => self.relerr,
            Aov::Rays => self.rays,
            Aov::Dmin => self.dmin,
            Aov::Ao => self.ao,
            Aov::Escaped => self.escaped,
            Aov::EDirect => self.e_direct,
        }
    }
}

/// One AOV over a whole image, row-major like H; NaN for background pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Which AOV.
    pub aov: Aov,
    /// Its value per pixel.
    pub data: Vec<f32>,
}

impl AovImage {
    /// The images of `aovs`, in that order, from each pixel's samples.
    pub fn channels(aovs: &[Aov], samples: &[AovSample]) -> Vec<AovImage> {
        aovs.iter()
            .map(|&aov| AovImage {
                aov,
                data: samples.iter().map(|s| s.get(aov)).collect(),
            })
            .collect()
    }
}
