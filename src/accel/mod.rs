//! Ray casting: closest hits against the scene's triangles (spec §2). The engine's design,
//! and what was measured and not kept: `docs/engine.md`.
//!
//! Guarantees every estimator relies on:
//! - **Watertight**: a ray cannot slip between two triangles that share an edge
//!   (`triangle.rs`), and BVH boxes are tested conservatively (`kernel/`). In a closed room no
//!   ray escapes.
//! - **Robust origins**: a ray leaving a surface starts at [`offset_ray_origin`] of the hit,
//!   and hits closer than their own `t` error bound (whose sign cannot be trusted) are set
//!   aside, so a ray never re-hits the surface it leaves and never sees a neighbouring facet
//!   at a spurious tiny distance; near-horizon hits in concave places are kept. One exception
//!   keeps closed meshes closed: a ray that would otherwise escape takes the nearest such hit,
//!   unless it lies in the plane of the triangle the ray leaves. (A point a few ulps from a
//!   second wall, in a room's corner, really does see that wall; a face's coincident
//!   duplicate, common in real files, is in the plane the ray leaves and so never hit.)
//! - **The same bits on every CPU path**: the kernels (scalar, AVX2, AVX-512) return the same
//!   hit distances bit for bit, and so the same images; `HMDIST_KERNEL` forces one.
//! - **The same answer whatever the visit order**: among hits at equal `t` the lowest triangle
//!   index wins, and nothing that could hold such a tie is culled (`traverse.rs`), so BVH
//!   presets and packets agree bit for bit; the GPU's traversal follows the same rule, with
//!   its own rounding.
//!
//! The interface is [`RayCaster`]: no per-ray allocation and no dynamic dispatch; estimators
//! are generic over it. [`Accel`] is the implementation: an 8-wide BVH (`wide.rs`) traversed
//! nearest child first (`traverse.rs`) by SIMD kernels chosen at run time (`kernel/`), one ray
//! at a time or up to [`PACKET`] rays together (`packet.rs`, [`RayCaster::hit_distances`]).
//! Distances are in scene units; directions must be unit length for `t` to be a distance.

mod bvh;
pub(crate) mod float_error;
mod kernel;
#[cfg(target_arch = "x86_64")]
mod packet;
mod pages;
mod sah;
mod slots;
mod traverse;
mod triangle;
pub(crate) mod wide;

use glam::Vec3;

pub use bvh::{Accel, BuildQuality, AUTO_RAYS_PER_TRIANGLE};
pub use float_error::offset_ray_origin;
pub use kernel::Kernel;
pub use traverse::TraversalStats;

use crate::sampling::Frame;

/// A ray's first hit, with what a secondary ray needs to leave the surface robustly.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray (in units of the direction's length).
    pub t: f32,
    /// Index of the triangle in the scene mesh.
    pub triangle: u32,
    /// The hit point, from barycentric interpolation of the triangle's corners.
    pub point: Vec3,
    /// Absolute floating-point error bound of `point`, per axis.
    pub point_error: Vec3,
    /// Unit geometric normal of the triangle, in its winding's orientation (not yet flipped).
    pub normal: Vec3,
}

impl Hit {
    /// Origin for a ray leaving this hit towards `w`.
    #[inline]
    pub fn spawn_origin(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(self.point, self.point_error, self.normal, w)
    }
}

/// A gather's start: the origin offset off the surface, the frame of the normal whose
/// hemisphere is sampled, and the triangle the rays leave (`None` where it is not known).
#[derive(Clone, Copy, Debug)]
pub(crate) struct GatherStart {
    pub origin: Vec3,
    /// The frame around the normal whose hemisphere is sampled.
    pub frame: Frame,
    pub leaving: Option<u32>,
}

impl GatherStart {
    /// The start at a primary hit, its normal already facing the camera.
    pub fn at_hit(hit: &Hit) -> Self {
        GatherStart {
            origin: hit.spawn_origin(hit.normal),
            frame: Frame::from_normal(hit.normal),
            leaving: Some(hit.triangle),
        }
    }
}

/// What estimators need from ray casting.
pub trait RayCaster: Sync {
    /// The first hit along `origin + t·direction`, `0 < t < t_max`. `leaving` is the triangle
    /// the ray leaves (its origin from [`Hit::spawn_origin`]), `None` for camera rays.
    fn closest_hit(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> Option<Hit>;

    /// Distance to the first hit, `+inf` if the ray escapes (cheaper than `closest_hit`).
    fn hit_distance(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> f32;

    /// [`RayCaster::hit_distance`] of up to [`PACKET`] rays at once: `out[i]` is exactly what
    /// `hit_distance(origins[i], directions[i], t_max, leaving[i])` gives, bit for bit.
    /// `origins`, `directions` and `leaving` have one length, at most [`PACKET`], and `out` at
    /// least that. Rays from nearby points in nearby directions (a point's neighbouring
    /// strata) are traversed together, sharing each node's visit.
    fn hit_distances(
        &self,
        origins: &[Vec3],
        directions: &[Vec3],
        leaving: &[Option<u32>],
        t_max: f32,
        out: &mut [f32],
    ) {
        for (i, out) in out.iter_mut().enumerate().take(directions.len()) {
            *out = self.hit_distance(origins[i], directions[i], t_max, leaving[i]);
        }
    }

    /// [`RayCaster::hit_distances`] of the first `len` rays of `rays` (at most [`PACKET`]),
    /// which all leave triangle `leaving`: the same bits, without taking the rays apart and
    /// putting them together again where the caller has them as lanes already.
    fn hit_distances_of_lanes(
        &self,
        rays: &RayLanes,
        len: usize,
        leaving: Option<u32>,
        t_max: f32,
        out: &mut [f32],
    ) {
        for (i, out) in out.iter_mut().enumerate().take(len) {
            *out = self.hit_distance(rays.origin(i), rays.direction(i), t_max, leaving);
        }
    }
}

/// Up to [`PACKET`] rays as lanes: lane `i` holds ray `i`'s origin and direction, axis by
/// axis; lanes past a packet's last ray repeat it.
#[derive(Clone, Copy, Debug)]
pub struct RayLanes {
    /// The origins' x, y and z.
    pub origin: [[f32; PACKET]; 3],
    /// The directions' x, y and z (any length).
    pub direction: [[f32; PACKET]; 3],
}

impl RayLanes {
    /// The rays from `origins[i]` along `directions[i]` (one length, 1 to [`PACKET`]).
    #[inline(always)]
    pub fn from_rays(origins: &[Vec3], directions: &[Vec3]) -> RayLanes {
        let n = directions.len();
        debug_assert!((1..=PACKET).contains(&n) && origins.len() == n);
        let mut lanes = RayLanes {
            origin: [[0.0; PACKET]; 3],
            direction: [[0.0; PACKET]; 3],
        };
        for i in 0..PACKET {
            let (o, d) = (origins[i.min(n - 1)], directions[i.min(n - 1)]);
            for axis in 0..3 {
                lanes.origin[axis][i] = o[axis];
                lanes.direction[axis][i] = d[axis];
            }
        }
        lanes
    }

    /// Ray `i`'s origin.
    #[inline(always)]
    pub fn origin(&self, i: usize) -> Vec3 {
        Vec3::new(self.origin[0][i], self.origin[1][i], self.origin[2][i])
    }

    /// Ray `i`'s direction.
    #[inline(always)]
    pub fn direction(&self, i: usize) -> Vec3 {
        Vec3::new(self.direction[0][i], self.direction[1][i], self.direction[2][i])
    }
}

/// Children per node of the wide BVH, and triangles per leaf block: what the SAH builder
/// (`sah.rs`) fills a leaf up to and the collapse (`wide.rs`) packs.
pub const WIDTH: usize = 8;

/// The most rays [`RayCaster::hit_distances`] casts at once: one per AVX2 lane.
pub const PACKET: usize = 8;
