//! `cubemap`: hemicube rasterisation (SPEC §3.2; paper §2.2.3, §3.2, Fig. 3–4).
//!
//! Per pixel, a hemicube of per-quadrant resolution `R` around the surface normal holds the
//! depth of the nearest surface per texel; the same gather directions as `gather` look it up
//! and convert depth to distance with `t / (ω · axis)`. Its error against `gather` comes from
//! the texel discretisation; its cost is building the cube maps, and hardly grows with N.
//!
//! Backends: `cpu` fills texels by ray casting (a ray through the texel centre sees exactly
//! what rasterisation stores there); `gpu` rasterises the faces with wgpu; `auto` takes a
//! hardware GPU where there is one, else the CPU.

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
pub mod hemicube;

use super::{EstimateContext, Estimator, GBuffer, Gather, Work};
pub use crate::backend::Backend;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{CubemapParameters, Parameters};
pub use cpu::sweep;
pub use hemicube::{Face, Hemicube};

/// Default per-quadrant resolution `R` (paper: 64 and 128).
pub const DEFAULT_CUBE_RES: u32 = 64;
/// Largest `R` accepted: a 2R × 2R top face must fit a GPU texture comfortably.
pub const MAX_CUBE_RES: u32 = 1024;

/// The cube-map estimator: `gather`'s directions looked up in per-pixel hemicubes.
pub struct Cubemap {
    gather: Gather,
    hemicube: Hemicube,
    backend: Backend,
}

impl Cubemap {
    /// `gather`'s directions looked up in hemicubes of per-quadrant resolution `resolution`
    /// (1 to [`MAX_CUBE_RES`]), built by `backend`.
    pub fn new(gather: Gather, resolution: u32, backend: Backend) -> Result<Self> {
        if resolution == 0 || resolution > MAX_CUBE_RES {
            return Err(Error::invalid(
                "cube_res",
                format!("must be between 1 and {MAX_CUBE_RES}, not {resolution}"),
            ));
        }
        Ok(Cubemap {
            gather,
            hemicube: Hemicube { resolution },
            backend,
        })
    }

    /// The gather whose directions look the hemicube up.
    pub fn gather(&self) -> &Gather {
        &self.gather
    }

    /// The hemicube every pixel gets.
    pub fn hemicube(&self) -> Hemicube {
        self.hemicube
    }

    /// Whether this cube map is built on the CPU (where [`sweep`] runs): `cpu`, or `auto`
    /// without a hardware GPU.
    pub fn runs_on_cpu(&self) -> bool {
        match self.backend {
            Backend::Cpu => true,
            Backend::Gpu | Backend::GpuSoftware => false,
            #[cfg(feature = "gpu")]
            Backend::Auto => !crate::gpu::auto_uses_gpu(),
            #[cfg(not(feature = "gpu"))]
            Backend::Auto => true,
        }
    }

    /// The GPU to rasterise with, or `None` for the CPU backend.
    #[cfg(feature = "gpu")]
    fn gpu(&self) -> Result<Option<gpu::Gpu>> {
        crate::gpu::open_for(self.backend, gpu::Gpu::open)
    }
}

impl Estimator for Cubemap {
    fn method(&self) -> &'static str {
        "cubemap"
    }

    fn parameters(&self) -> Parameters {
        Parameters {
            cubemap: Some(CubemapParameters {
                cube_res: self.hemicube.resolution,
            }),
            ..self.gather.parameters()
        }
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        // The CPU backend casts at most one ray per gather direction (one per texel looked
        // up); the GPU backend rasterises instead.
        if self.backend.is_gpu() {
            0
        } else {
            self.gather.expected_rays(pixels)
        }
    }

    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        gbuffer: &'a GBuffer,
        progress: &dyn Progress,
    ) -> Result<Work<'a>> {
        #[cfg(feature = "gpu")]
        if let Some(gpu) = self.gpu()? {
            return gpu::estimate(&gpu, self, context, gbuffer, progress).map(|e| Work::Done(Box::new(e)));
        }
        #[cfg(not(feature = "gpu"))]
        if self.backend.is_gpu() {
            return Err(Backend::unavailable());
        }
        let _ = (gbuffer, progress);
        Ok(Work::Pixels {
            work: Box::new(cpu::CpuPixels {
                cubemap: self,
                context,
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}
