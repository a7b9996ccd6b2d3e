//! The SIMD kernels: one box test of a node's eight children and one watertight test of a
//! leaf block's eight triangles, per instruction set, behind the [`Lanes`] trait that the
//! traversal ([`super::traverse`]) is generic over.
//!
//! Every kernel returns the same bits as the scalar one: each lane performs the same IEEE
//! operations in the same order (no fused multiply-add, exact division, `min`/`max` with the
//! SSE operand rule written out in the scalar code), so the traversal takes the same path and
//! finds the same hit whatever kernel runs. `tests/kernels.rs` checks this on millions of
//! rays. The kernel is chosen once, when the [`super::Accel`] is built: the fastest one the
//! CPU has, or the one the caller names (`RenderOptions::kernel`, `Accel::for_work`). The
//! CLI and Python take it from the environment variable `HMDIST_KERNEL` (`scalar`, `avx2`,
//! `avx512`) with [`Kernel::from_env`]; the library itself never reads it. The design, and
//! what was measured and not kept: `docs/engine.md`.

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx2;
pub(crate) mod scalar;

use glam::Vec3;

use super::float_error::gamma;
use super::triangle::WatertightRay;
use super::wide::{Block, Node, WIDTH};
use crate::error::{Error, Result};

/// The ray-casting kernels; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Portable Rust, one lane at a time.
    Scalar,
    /// 8-lane AVX2.
    Avx2,
    /// The AVX2 kernel compiled for AVX-512 (EVEX encoding, mask registers). On AMD Zen 4,
    /// which runs 512-bit instructions as two 256-bit halves, 16-lane node tests do not pay;
    /// this variant lets the compiler use what AVX-512 adds at 256 bits.
    Avx512,
}

impl Kernel {
    /// Every kernel, whether this CPU can run it or not.
    pub const ALL: [Kernel; 3] = [Kernel::Scalar, Kernel::Avx2, Kernel::Avx512];

    /// The kernel's name, as `HMDIST_KERNEL` and the render report spell it.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Scalar => "scalar",
            Kernel::Avx2 => "avx2",
            Kernel::Avx512 => "avx512",
        }
    }

    /// Whether the kernel traverses packets of rays ([`crate::accel::PACKET`] lanes): the
    /// AVX2 kernels, on x86-64.
    pub fn has_packets(self) -> bool {
        cfg!(target_arch = "x86_64") && matches!(self, Kernel::Avx2 | Kernel::Avx512)
    }

    /// Whether this CPU can run the kernel.
    pub fn available(self) -> bool {
        match self {
            Kernel::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => {
                is_x86_feature_detected!("avx2")
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The fastest kernel this CPU has (AVX2: measured at least as fast as the AVX-512 build
    /// on Zen 4; see `docs/engine.md`).
    pub fn best() -> Kernel {
        [Kernel::Avx2, Kernel::Scalar]
            .into_iter()
            .find(|k| k.available())
            .unwrap_or(Kernel::Scalar)
    }

    /// The kernel named by `HMDIST_KERNEL`, or [`Kernel::best`] when it is unset. An unknown
    /// name, or a kernel this CPU cannot run, is an error.
    pub fn from_env() -> Result<Kernel> {
        match std::env::var("HMDIST_KERNEL") {
            Err(_) => Ok(Kernel::best()),
            Ok(name) => Kernel::parse(name.trim()),
        }
    }

    /// The kernel named `name` (`scalar`, `avx2`, `avx512`); an unknown name, or a kernel this
    /// CPU cannot run, is an error.
    pub fn parse(name: &str) -> Result<Kernel> {
        let kernel = Kernel::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                Error::parameter(format!(
                    "HMDIST_KERNEL={name:?} names no ray-casting kernel (scalar, avx2, avx512)"
                ))
            })?;
        if !kernel.available() {
            return Err(Error::parameter(format!(
                "HMDIST_KERNEL={name}: this CPU cannot run the {name} kernel"
            )));
        }
        Ok(kernel)
    }
}

/// Per-ray constants of both tests.
#[derive(Clone)]
pub(crate) struct RayData {
    pub origin: [f32; 3],
    /// `1/d` per axis; a zero component is replaced by a tiny one of the same sign, so
    /// parallel slabs give ±huge instead of NaN.
    pub inv_direction: [f32; 3],
    /// Per axis, the row of [`Node::bounds`] that holds the near plane (min for a positive
    /// direction, max for a negative one) and the far plane.
    pub near_row: [usize; 3],
    pub far_row: [usize; 3],
    pub triangle: WatertightRay,
    /// The origin in the watertight test's permuted axes (`[o[kx], o[ky], o[kz]]`), which
    /// every leaf block test reads: kept here rather than picked again per block.
    pub permuted_origin: [f32; 3],
}

impl RayData {
    #[inline(always)]
    pub fn new(origin: Vec3, direction: Vec3) -> RayData {
        let safe = |d: f32| if d == 0.0 { 1e-30f32.copysign(d) } else { d };
        let inv_direction = [
            1.0 / safe(direction.x),
            1.0 / safe(direction.y),
            1.0 / safe(direction.z),
        ];
        let near_row = [0, 1, 2].map(|axis| axis + 3 * (inv_direction[axis] < 0.0) as usize);
        let triangle = WatertightRay::new(origin, direction);
        RayData {
            origin: origin.to_array(),
            inv_direction,
            near_row,
            far_row: near_row.map(|row| (row + 3) % 6),
            permuted_origin: [origin[triangle.kx], origin[triangle.ky], origin[triangle.kz]],
            triangle,
        }
    }

    /// Whether origin and direction were finite: `1/d` is NaN for a NaN component and 0 for an
    /// infinite one (a zero component was replaced by a tiny one).
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        self.origin.iter().all(|v| v.is_finite())
            && self.inv_direction.iter().all(|v| v.is_finite() && *v != 0.0)
    }
}

/// `1 + 2γ(3)`: a slab distance `(b − o)·(1/d)` carries at most three roundings, so scaling
/// the far distance by this makes the box test conservative (pbrt-v4 `Bounds3::IntersectP`).
pub(crate) const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);

/// What the eight lanes of a leaf block gave: which triangles are hit (bit per lane), which
/// of those hits lie within their own `t` error bound, and each lane's `t`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BlockHits {
    pub hit: u32,
    pub within_error: u32,
    pub t: [f32; WIDTH],
}

/// One instruction set's tests. Implementations are `#[inline(always)]` so that the
/// traversal, instantiated inside a `#[target_feature]` function, is compiled for that set.
pub(crate) trait Lanes {
    /// The children whose boxes the ray meets within `[0, t_max]` (bit per slot), and each
    /// slot's near distance.
    fn node(node: &Node, ray: &RayData, t_max: f32) -> (u32, [f32; WIDTH]);

    /// The watertight test of the block's triangles at `0 < t ≤ t_max`, lane by lane exactly
    /// [`WatertightRay::intersect`].
    fn block(block: &Block, ray: &RayData, t_max: f32) -> BlockHits;
}
