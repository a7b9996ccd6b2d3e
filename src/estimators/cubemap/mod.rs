//! `cubemap`: hemicube rasterisation (SPEC §3.2; paper §2.2.3, §3.2, Fig. 3–4).
//!
//! Per pixel, a hemicube of per-quadrant resolution `R` around the surface normal holds the
//! depth of the nearest surface per texel; the same gather directions as `gather` look it up
//! and convert depth to distance with `t / (ω · axis)`. Its error against `gather` comes from
//! the texel discretisation; its cost is building the cube maps, and hardly grows with N.
//!
//! Backends: `cpu` fills texels by ray casting (a ray through the texel centre sees exactly
//! what rasterisation stores there); `gpu` rasterises the faces with wgpu; `auto` takes a
//! hardware GPU where there is one, else the CPU. On the GPU, `--gpu-fill rays` fills each
//! looked-up texel as the CPU does, by its centre ray, in the GPU gather's shader: for GPUs
//! with little rasterising hardware (an H200 rasterised about 1,900 hemicubes/s at R = 64,
//! slower than its node's CPU cores), where rays go at the gather's speed.

mod cpu;
pub mod hemicube;

use super::{EstimateContext, Estimator, GBuffer, Gather, Prepared};
pub use crate::backend::{Backend, GpuFill};
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
    /// How the GPU fills the texels looked up: raster (every texel of every hemicube, the
    /// paper's method) or rays (a ray through each looked-up texel's centre, as the CPU
    /// backend; for compute GPUs with little rasterising hardware, such as the H100/H200).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_enum, default_value_t = GpuFill::Raster, help_heading = "Cube map")
    )]
    pub gpu_fill: GpuFill,
}

impl Default for CubemapParams {
    fn default() -> Self {
        CubemapParams {
            rays: super::gather::DEFAULT_RAYS,
            weighting: Weighting::default(),
            cube_res: DEFAULT_CUBE_RES,
            backend: Backend::default(),
            gpu_fill: GpuFill::default(),
        }
    }
}

impl super::params::MethodParams for CubemapParams {}

impl CubemapParams {
    /// The cube map these parameters name, checked.
    pub fn build(&self) -> Result<Cubemap> {
        Ok(Cubemap::new(
            Gather::new(self.rays, self.weighting)?,
            self.cube_res,
            self.backend,
        )?
        .with_gpu_fill(self.gpu_fill))
    }
}

/// The cube-map estimator: `gather`'s directions looked up in per-pixel hemicubes.
pub struct Cubemap {
    gather: Gather,
    hemicube: Hemicube,
    backend: Backend,
    gpu_fill: GpuFill,
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
            gpu_fill: GpuFill::Raster,
        })
    }

    /// The same cube map, its texels filled on the GPU by `fill` (the CPU backend always
    /// casts rays).
    pub fn with_gpu_fill(self, fill: GpuFill) -> Self {
        Cubemap {
            gpu_fill: fill,
            ..self
        }
    }

    /// The report's cube-map figures for `surface` surface pixels: every direction looks up
    /// one texel.
    #[cfg(feature = "gpu")]
    fn details(
        &self,
        surface: usize,
        texels_rasterised: u64,
        escaped_lookups: u64,
    ) -> crate::report::CubemapDetails {
        crate::report::CubemapDetails {
            texels_rasterised,
            texels_per_hemicube: self.hemicube.texel_count() as u64,
            lookups: surface as u64 * self.gather.rays_per_point() as u64,
            escaped_lookups,
        }
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
                gpu_fill: self.gpu_fill,
            }),
            ..self.gather.parameters()
        }
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        // The CPU backend casts at most one ray per gather direction (one per texel looked
        // up), the GPU's rays fill one per direction; rasterising casts none.
        if self.backend.is_gpu() && self.gpu_fill == GpuFill::Raster {
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
        if self.gpu_fill == GpuFill::Rays {
            let scene = crate::gpu::open_for(self.backend, |software| {
                crate::gpu::GpuScene::new(context.accel, software)
            })?;
            if let Some(scene) = scene {
                return estimate_by_rays_on_gpu(&scene, self, context, gbuffer, progress)
                    .map(|e| Prepared::Done(Box::new(e)));
            }
        } else if let Some(gpu) = self.gpu()? {
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
    use crate::report::{Details, DeviceDetails, PhaseSeconds};

    let (pixels, starts) = gbuffer.starts();
    let job = HemicubeJob {
        mesh: &context.scene.mesh,
        resolution: cubemap.hemicube.resolution,
        rays: cubemap.gather.rays_per_point(),
        weighting: cubemap.gather.weighting(),
        seed: context.seed,
        d_min: context.clamp.min,
        t_max: context.clamp.max,
        far: 4.0 * context.scene.diagonal() + 1.0,
    };
    let done = look_up(gpu, &job, &starts, |i| pixels[i] as u32, progress)?;
    let texels = pixels.len() as u64 * cubemap.hemicube.texel_count() as u64;
    Ok(super::Estimate {
        hmd: gbuffer.image_of(&pixels, done.hmd),
        rays: None,
        aovs: vec![],
        phases: PhaseSeconds {
            cubemap_build: Some(done.raster_seconds),
            cubemap_lookup: Some(done.lookup_seconds),
            ..PhaseSeconds::default()
        },
        details: Details {
            device: Some(DeviceDetails::gpu(&gpu.adapter_name, gpu.software)),
            cubemap: Some(cubemap.details(pixels.len(), texels, done.escaped_lookups)),
            ..Details::default()
        },
    })
}

/// The cube map on the GPU by rays (`--gpu-fill rays`): the GPU gather's shader with each
/// direction snapped to its texel's centre ray ([`crate::gpu::gather::GatherJob::cube_res`]).
/// `rays_cast` counts those rays (one per lookup: a texel two directions look up is cast
/// twice, where the CPU backend casts it once), `escaped_lookups` the lookups whose distance
/// passed `--max-distance` or found nothing, as on the CPU.
#[cfg(feature = "gpu")]
fn estimate_by_rays_on_gpu(
    scene: &crate::gpu::GpuScene,
    cubemap: &Cubemap,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<super::Estimate> {
    use crate::gpu::gather::{gather_points, GatherJob};
    use crate::report::{Details, DeviceDetails, PhaseSeconds};

    let (pixels, starts) = gbuffer.starts();
    let gather = &cubemap.gather;
    let job = GatherJob {
        cube_res: cubemap.hemicube.resolution,
        ..gather.gpu_job(context.seed, context.clamp, None)
    };
    let done = gather_points(
        scene,
        &job,
        &starts,
        |i| pixels[i] as u64,
        progress,
        |p| {
            let escaped = p.escaped as u64;
            (gather.point_from_gpu(None, p).mean.value(), escaped)
        },
    )?;
    let escaped = done.points.iter().map(|&(_, e)| e).sum();
    let details = cubemap.details(pixels.len(), 0, escaped);
    let lookups = details.lookups;
    Ok(super::Estimate {
        hmd: gbuffer.image_of(&pixels, done.points.iter().map(|&(h, _)| h)),
        rays: Some(super::RayCount {
            cast: lookups,
            escaped,
            seconds: done.trace_seconds,
        }),
        aovs: vec![],
        phases: PhaseSeconds {
            gpu_upload: Some(scene.upload_seconds + done.upload_seconds),
            gpu_trace: Some(done.trace_seconds),
            gpu_readback: Some(done.readback_seconds),
            ..PhaseSeconds::default()
        },
        details: Details {
            device: Some(DeviceDetails::gpu(scene.adapter(), scene.device.software)),
            grays_per_s: Some(lookups as f64 / done.trace_seconds.max(1e-9) / 1e9),
            cubemap: Some(details),
            ..Details::default()
        },
    })
}
