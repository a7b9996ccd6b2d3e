//! The cube map's parameters ([`CubemapParams`]: flags, keywords, the registry's build) and
//! the configured estimator ([`Cubemap`]), below both its CPU pass (`cpu.rs`) and its
//! estimate (`mod.rs`).

use super::hemicube::Hemicube;
use crate::backend::{Backend, GpuFill};
use crate::error::{Error, Result};
use crate::estimators::Gather;
#[cfg(feature = "gpu")]
use crate::gpu::hemicube::HemicubeGpu;
use crate::sampling::Weighting;

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
    #[cfg_attr(feature = "cli", arg(long, default_value_t = crate::estimators::gather::DEFAULT_RAYS))]
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
            rays: crate::estimators::gather::DEFAULT_RAYS,
            weighting: Weighting::default(),
            cube_res: DEFAULT_CUBE_RES,
            backend: Backend::default(),
            gpu_fill: GpuFill::default(),
        }
    }
}

impl crate::estimators::params::MethodParams for CubemapParams {
    fn on_backend(&mut self, backend: Backend, gpu_fill: GpuFill) {
        self.backend = backend;
        self.gpu_fill = gpu_fill;
    }
}

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
    pub(super) gather: Gather,
    pub(super) hemicube: Hemicube,
    pub(super) backend: Backend,
    pub(super) gpu_fill: GpuFill,
}

impl Cubemap {
    /// The parameters this cube map is built from ([`CubemapParams::build`]).
    pub fn params(&self) -> CubemapParams {
        let gather = self.gather.params();
        CubemapParams {
            rays: gather.rays,
            weighting: gather.weighting,
            cube_res: self.hemicube.resolution,
            backend: self.backend,
            gpu_fill: self.gpu_fill,
        }
    }

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
    pub(super) fn details(
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
    pub(super) fn gpu(&self) -> Result<Option<HemicubeGpu>> {
        crate::gpu::open_for(self.backend, HemicubeGpu::open)
    }
}
