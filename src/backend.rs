//! Where an estimator runs ([`Backend`]), how the cube map fills its texels there
//! ([`GpuFill`]) and how GPU work is split ([`DispatchSplit`]):
//! vocabulary shared by the estimators, which choose, and the GPU module ([`crate::gpu`],
//! with the `gpu` feature), which opens the device. It exists with or without that feature.

/// Where an estimator runs: `gather`'s rays and the cube map's hemicubes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// gpu if a hardware adapter exists, else cpu (a software implementation such as Mesa's
    /// lavapipe is slower than the CPU backend). A hardware GPU that fails is an error, not a
    /// quiet CPU render.
    #[default]
    Auto,
    /// A hardware GPU through wgpu (Vulkan, Metal or DX12): gather's rays in a compute shader,
    /// the cube map by rasterisation. A software implementation (Mesa's lavapipe, about 0.2 M
    /// rays/s) is refused, naming it, unless `HMDIST_GPU_SOFTWARE=1`.
    Gpu,
    /// As `gpu`, a software implementation included (what CI and the tests use).
    #[serde(rename = "gpu-software")]
    GpuSoftware,
    /// The CPU: gather's rays by the SIMD kernels, the cube map by casting a ray through each
    /// texel looked up.
    Cpu,
}

/// How the cube map's GPU backend fills the hemicube texels that the directions look up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum GpuFill {
    /// Rasterise every texel of every pixel's hemicube (the paper's method).
    #[default]
    Raster,
    /// Cast a ray through the centre of each texel a direction looks up, as the CPU backend
    /// does: the cost of a gather with the same N, whatever R.
    Rays,
}

impl GpuFill {
    /// Whether this is the default, raster (reports leave it out then).
    pub fn is_raster(&self) -> bool {
        *self == GpuFill::Raster
    }
}

impl Backend {
    /// Whether this backend runs on a GPU whenever it runs at all (`gpu`, `gpu-software`).
    pub fn is_gpu(self) -> bool {
        matches!(self, Backend::Gpu | Backend::GpuSoftware)
    }

    /// The error of asking for a GPU from an hmdist built without the `gpu` feature.
    #[cfg(not(feature = "gpu"))]
    pub(crate) fn unavailable() -> crate::error::Error {
        crate::error::Error::device(
            crate::error::DeviceErrorKind::NoAdapter,
            "this hmdist was built without the gpu feature: use the cpu backend",
        )
    }
}

/// How a GPU gather's work is split into dispatches: at most `points` points and `rays` rays
/// per point each. The result does not depend on it (tests check this); without
/// [`crate::estimators::Gather::with_dispatch_split`], dispatches take about half a second
/// each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DispatchSplit {
    /// Points per dispatch.
    pub points: u32,
    /// Rays per point per dispatch.
    pub rays: u32,
    /// Lets `rays` exceed what a software adapter's loop cap allows (16 rays per point per
    /// dispatch on lavapipe): for the test that a loop cut short is caught, not turned into
    /// an image.
    pub past_software_cap: bool,
}
