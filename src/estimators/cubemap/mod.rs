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
pub mod hemicube;

use super::{EstimateContext, Estimator, GBuffer, Gather, Prepared};
pub use crate::backend::Backend;
use crate::error::{Error, Result};
#[cfg(feature = "gpu")]
use crate::gpu::hemicube::HemicubeGpu;
use crate::progress::Progress;
use crate::report::{CubemapParameters, Parameters};
use crate::sampling::Weighting;
pub use cpu::sweep;
pub use hemicube::{Face, Hemicube};

/// Default per-quadrant resolution `R` (paper: 64 and 128).
pub const DEFAULT_CUBE_RES: u32 = 64;
/// Largest `R` accepted: a 2R × 2R top face must fit a GPU texture comfortably.
pub const MAX_CUBE_RES: u32 = 1024;

/// `cubemap`'s parameters: the CLI's flags, Python's keywords and the registry's build all
/// come from this one list.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct CubemapParams {
    /// Gather rays per pixel N: the directions looked up in the hemicube.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = super::gather::DEFAULT_RAYS))]
    pub rays: u32,
    /// Direction weighting over the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Weighting::Cosine))]
    pub weighting: Weighting,
    /// Per-quadrant hemicube resolution R: top face 2R x 2R, sides 2R x R.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = DEFAULT_CUBE_RES, help_heading = "Cube map")
    )]
    pub cube_res: u32,
    /// Where the hemicubes are built.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Backend::Auto))]
    pub backend: Backend,
}

impl Default for CubemapParams {
    fn default() -> Self {
        CubemapParams {
            rays: super::gather::DEFAULT_RAYS,
            weighting: Weighting::default(),
            cube_res: DEFAULT_CUBE_RES,
            backend: Backend::default(),
        }
    }
}

impl super::params::MethodParams for CubemapParams {}

impl CubemapParams {
    /// The cube map these parameters name, checked.
    pub fn build(&self) -> Result<Cubemap> {
        Cubemap::new(
            Gather::new(self.rays, self.weighting)?,
            self.cube_res,
            self.backend,
        )
    }
}

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
    fn gpu(&self) -> Result<Option<HemicubeGpu>> {
        crate::gpu::open_for(self.backend, HemicubeGpu::open)
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
    ) -> Result<Prepared<'a>> {
        #[cfg(feature = "gpu")]
        if let Some(gpu) = self.gpu()? {
            return estimate_on_gpu(&gpu, self, context, gbuffer, progress)
                .map(|e| Prepared::Done(Box::new(e)));
        }
        #[cfg(not(feature = "gpu"))]
        if self.backend.is_gpu() {
            return Err(Backend::unavailable());
        }
        let _ = (gbuffer, progress);
        Ok(Prepared::Pixels {
            job: Box::new(cpu::CpuPixels {
                cubemap: self,
                context,
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}

/// The cube map on the GPU over the whole image ([`crate::gpu::hemicube`]): H per pixel and
/// what it took. Rasterisation casts no rays, so the report's `rays_cast`, `escaped_rays` and
/// `mrays_per_s` are null.
#[cfg(feature = "gpu")]
fn estimate_on_gpu(
    gpu: &HemicubeGpu,
    cubemap: &Cubemap,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<super::Estimate> {
    use crate::gpu::hemicube::{look_up, HemicubeJob};
    use crate::report::{CubemapDetails, Details, DeviceDetails, PhaseSeconds};

    let (pixels, starts) = gbuffer.starts();
    let rays = cubemap.gather.rays_per_point();
    let job = HemicubeJob {
        mesh: &context.scene.mesh,
        resolution: cubemap.hemicube.resolution,
        rays,
        weighting: cubemap.gather.weighting(),
        seed: context.seed,
        d_min: context.clamp.min,
        t_max: context.clamp.max,
        far: 4.0 * context.scene.diagonal() + 1.0,
    };
    let done = look_up(gpu, &job, &starts, |i| pixels[i] as u32, progress)?;
    let mut hmd = vec![f32::NAN; gbuffer.points.len()];
    for (&pixel, h) in pixels.iter().zip(done.hmd) {
        hmd[pixel] = h;
    }
    Ok(super::Estimate {
        hmd,
        rays: None,
        aovs: vec![],
        phases: PhaseSeconds {
            cubemap_build: Some(done.raster_seconds),
            cubemap_lookup: Some(done.lookup_seconds),
            ..PhaseSeconds::default()
        },
        details: Details {
            device: Some(DeviceDetails::gpu(&gpu.adapter_name, gpu.software)),
            cubemap: Some(CubemapDetails {
                texels_rasterised: pixels.len() as u64 * cubemap.hemicube.texel_count() as u64,
                texels_per_hemicube: cubemap.hemicube.texel_count() as u64,
                lookups: pixels.len() as u64 * rays as u64,
                escaped_lookups: done.escaped_lookups,
            }),
            ..Details::default()
        },
    })
}
