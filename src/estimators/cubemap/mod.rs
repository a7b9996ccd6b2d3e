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
mod gpu;
pub mod hemicube;

use std::time::Instant;

use serde_json::json;

use super::{Estimate, EstimateContext, Estimator, GBuffer, Gather, RayCount};
use crate::error::{Error, Result};
use crate::progress::Progress;
pub use hemicube::{Face, Hemicube};

/// Default per-quadrant resolution `R` (paper: 64 and 128).
pub const DEFAULT_CUBE_RES: u32 = 64;
/// Largest `R` accepted: a 2R × 2R top face must fit a GPU texture comfortably.
pub const MAX_CUBE_RES: u32 = 1024;

/// Which implementation builds the cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Cpu,
    Gpu,
    /// The GPU where a hardware Vulkan, Metal or DX12 adapter exists, else the CPU (a
    /// software rasteriser such as lavapipe is slower than the CPU backend).
    Auto,
}

/// The cube-map estimator: `gather`'s directions looked up in per-pixel hemicubes.
pub struct Cubemap {
    pub gather: Gather,
    pub hemicube: Hemicube,
    pub backend: Backend,
}

impl Cubemap {
    pub fn new(gather: Gather, resolution: u32, backend: Backend) -> Result<Self> {
        if resolution == 0 || resolution > MAX_CUBE_RES {
            return Err(Error::parameter(format!(
                "--cube-res must be between 1 and {MAX_CUBE_RES}, not {resolution}"
            )));
        }
        Ok(Cubemap {
            gather,
            hemicube: Hemicube { resolution },
            backend,
        })
    }
}

impl Estimator for Cubemap {
    fn method(&self) -> &'static str {
        "cubemap"
    }

    fn parameters(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut p = self.gather.parameters();
        p.insert("cube_res".into(), json!(self.hemicube.resolution));
        p
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        // The CPU backend casts at most one ray per gather direction (one per texel looked
        // up); the GPU backend rasterises instead.
        match self.backend {
            Backend::Gpu => 0,
            _ => self.gather.expected_rays(pixels),
        }
    }

    fn estimate(
        &self,
        context: &EstimateContext,
        gbuffer: &GBuffer,
        progress: &dyn Progress,
    ) -> Result<Estimate> {
        let gpu = match self.backend {
            Backend::Cpu => None,
            Backend::Gpu => {
                Some(gpu::Gpu::open(true).map_err(|e| Error::parameter(format!("--backend gpu: {e}")))?)
            }
            // A software rasteriser is slower than the CPU backend: auto wants real hardware.
            Backend::Auto => gpu::Gpu::open(false).ok(),
        };
        let surface_pixels = (gbuffer.points.len() - gbuffer.background_pixels()) as u64;
        let lookups = surface_pixels * self.gather.rays as u64;
        let Some(gpu) = gpu else {
            let start = Instant::now();
            let cpu = cpu::estimate(self, context, gbuffer, progress);
            let seconds = start.elapsed().as_secs_f64();
            let extra = json!({
                "backend": "cpu",
                "adapter": serde_json::Value::Null,
                // The CPU fills only the texels that are looked up, one ray each.
                "texels_rasterised": cpu.texel_rays,
                "texels_per_hemicube": self.hemicube.texel_count(),
                "lookups": lookups,
                "escaped_lookups": cpu.escaped_lookups,
            });
            return Ok(Estimate {
                hmd: cpu.hmd,
                rays: Some(RayCount {
                    cast: cpu.texel_rays,
                    escaped: cpu.escaped_texel_rays,
                    seconds,
                }),
                // The CPU backend fills a texel at its first lookup: build and lookup interleave.
                phases: vec![("cubemap_build_and_lookup", seconds)],
                extra: crate::estimators::fields(extra),
            });
        };
        let result = gpu::estimate(&gpu, self, context, gbuffer, progress)?;
        let extra = json!({
            "backend": "gpu",
            "adapter": gpu.adapter_name,
            "texels_rasterised": result.texels_rasterised,
            "texels_per_hemicube": self.hemicube.texel_count(),
            "lookups": lookups,
            "escaped_lookups": result.escaped_lookups,
        });
        Ok(Estimate {
            hmd: result.hmd,
            // Rasterisation casts no rays: rays_cast, escaped_rays and mrays_per_s are null.
            rays: None,
            phases: vec![
                ("cubemap_build", result.raster_seconds),
                ("cubemap_lookup", result.lookup_seconds),
            ],
            extra: crate::estimators::fields(extra),
        })
    }
}
