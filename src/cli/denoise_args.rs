//! `render --denoise` and the filter's parameters ([`hmdist::denoise`]).

use hmdist::denoise::{DenoiseParams, DEFAULT_EDGE, DEFAULT_PASSES, DEFAULT_RADIUS};

/// The denoising flags of `render`.
#[derive(clap::Args)]
pub struct DenoiseArgs {
    /// Filter H with its neighbours' rays: an edge-aware filter of each pixel's mean of 1/d,
    /// guided by the surface points and normals, whose reach follows H and tightens as the
    /// rays per pixel grow (guide: "Denoising H"). For gather, adaptive and cubemap; not with
    /// the relerr AOV.
    #[arg(long, help_heading = "Denoising")]
    denoise: bool,
    /// À-trous passes: the filter reaches 2·(2^P − 1) pixels.
    #[arg(long, value_name = "P", default_value_t = DEFAULT_PASSES, requires = "denoise", help_heading = "Denoising")]
    denoise_passes: u32,
    /// The filter's reach in the scene, as a fraction of H.
    #[arg(long, value_name = "F", default_value_t = DEFAULT_RADIUS, requires = "denoise", help_heading = "Denoising")]
    denoise_radius: f32,
    /// How far apart two pixels' means of 1/d, S, may be and still be averaged, in units of
    /// S/N (N: the pixel's rays): the filter steps back as the rays grow.
    #[arg(long, value_name = "K", default_value_t = DEFAULT_EDGE, requires = "denoise", help_heading = "Denoising")]
    denoise_edge: f32,
}

impl DenoiseArgs {
    /// The filter these flags name, or `None` without `--denoise` (checked by the render).
    pub fn params(&self) -> Option<DenoiseParams> {
        self.denoise.then_some(DenoiseParams {
            passes: self.denoise_passes,
            radius: self.denoise_radius,
            edge: self.denoise_edge,
        })
    }
}
