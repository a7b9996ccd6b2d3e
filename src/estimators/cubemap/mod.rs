//! `cubemap`: hemicube rasterisation (spec §3.2; paper §2.2.3, §3.2, Fig. 3–4).
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
mod params;

use super::{EstimateContext, Estimator, GBuffer, Prepared};
pub use crate::backend::{Backend, GpuFill};
use crate::error::Result;
#[cfg(feature = "gpu")]
use crate::gpu::hemicube::HemicubeGpu;
use crate::progress::Progress;
use crate::report::Parameters;
pub use cpu::sweep;
pub use hemicube::{Face, Hemicube};
pub use params::{Cubemap, CubemapParams, DEFAULT_CUBE_RES, MAX_CUBE_RES};

impl Estimator for Cubemap {
    fn method(&self) -> &'static str {
        "cubemap"
    }

    fn parameters(&self) -> Parameters {
        Parameters::of(&self.params(), &["backend"])
    }

    fn samples(&self) -> crate::estimators::Samples {
        // Each pixel's lookups are its gather's directions in a hemicube of its own.
        crate::estimators::Samples::Fixed(self.gather.rays_per_point())
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
