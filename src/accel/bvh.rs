//! [`Accel`]: a compressed wide BVH (obvhs `CwBvh`, Ylitie et al. 2017) over the scene's
//! triangles, traversed with our watertight triangle test.
//!
//! Choices, measured on the `cube` and `hall` rooms (see `cargo bench`):
//! - obvhs's build preset decides trace speed far more than build time does: the
//!   [`BuildQuality::High`] preset (`very_slow_build`, whole-tree reinsertion) traces several
//!   times faster than `medium_build` for a build of about a second.
//! - Triangles are copied into BVH leaf order, so a leaf's triangles are adjacent in memory.
//! - obvhs's own triangle tests are not used: `Triangle::intersect` (Möller–Trumbore) is not
//!   watertight, and obvhs 0.4's `RtTriangle::intersect_embree` returns `t` scaled by the
//!   determinant, which picks the wrong closest hit.
//! - obvhs's node test is not used either: it culls boxes that end before `t = 1e-4` (a fixed
//!   epsilon, in scene units) and its slab test can round a box that a ray grazes into a miss.
//!   [`NodeRay::child_hits`] widens each slab by the error bound of its own arithmetic, so
//!   the test is conservative and scale-free: together with the watertight triangle test, no
//!   ray slips through a closed mesh.

use std::time::Duration;

use glam::{UVec2, Vec3, Vec3A, Vec4};
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, node::CwBvhNode, CwBvh};
use obvhs::{triangle::Triangle, BvhBuildParams};

use super::float_error::gamma;
use super::triangle::{barycentric_point_error, WatertightRay};
use super::{Hit, RayCaster};
use crate::scene::Mesh;

/// BVH build presets: build time against trace speed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// obvhs `fast_build`: builds in a fraction of the time, traces markedly slower. For tiny
    /// images or ray counts, where the build dominates.
    Fast,
    /// obvhs `very_slow_build`: spatial splits and whole-tree reinsertion. The default: HMD
    /// images cast millions of rays per build.
    #[default]
    High,
}

impl BuildQuality {
    fn params(self) -> BvhBuildParams {
        match self {
            BuildQuality::Fast => BvhBuildParams::fast_build(),
            BuildQuality::High => BvhBuildParams::very_slow_build(),
        }
    }
}

/// The scene's triangles in a BVH, ready for closest-hit queries from many threads.
pub struct Accel {
    bvh: CwBvh,
    /// Triangle corners in BVH leaf order (`bvh.primitive_indices` order).
    corners: Vec<[Vec3A; 3]>,
    /// For each entry of `corners`, the triangle's index in the mesh.
    mesh_index: Vec<u32>,
}

impl Accel {
    pub fn build(mesh: &Mesh, quality: BuildQuality) -> Accel {
        let triangles: Vec<Triangle> = (0..mesh.triangle_count())
            .map(|i| {
                let [v0, v1, v2] = mesh.triangle(i).map(Vec3A::from);
                Triangle { v0, v1, v2 }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&triangles, quality.params(), &mut Duration::default());
        let corners = bvh
            .primitive_indices
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                [t.v0, t.v1, t.v2]
            })
            .collect();
        let mesh_index = bvh.primitive_indices.clone();
        Accel {
            bvh,
            corners,
            mesh_index,
        }
    }

    /// Closest hit as (leaf-order primitive, t, barycentrics).
    #[inline(always)]
    fn trace(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        leaving: Option<u32>,
    ) -> Option<(usize, f32, [f32; 3])> {
        let ray = WatertightRay::new(origin, direction);
        let node_ray = NodeRay::new(origin, direction);
        let mut t_max = t_max;
        let mut best: Option<(usize, f32, [f32; 3])> = None;
        // The nearest hit within its own t error bound on another triangle: taken only if
        // the ray would otherwise escape (see `RayCaster`).
        let mut within_error: Option<(usize, f32, [f32; 3])> = None;
        let mut state = self.bvh.new_traversal(direction.into());
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node_ray.child_hits(node, t_max, state.oct_inv4),
            {
                let id = state.primitive_id as usize;
                let [p0, p1, p2] = self.corners[id];
                match ray.intersect(p0, p1, p2, t_max) {
                    Some(hit) if !hit.within_error => {
                        t_max = hit.t;
                        best = Some((id, hit.t, hit.b));
                    }
                    Some(hit)
                        if leaving != Some(self.mesh_index[id])
                            && within_error.is_none_or(|(_, t, _)| hit.t < t) =>
                    {
                        within_error = Some((id, hit.t, hit.b));
                    }
                    _ => {}
                }
            }
        );
        best.or(within_error)
    }
}

/// A ray prepared for conservative slab tests against a node's quantised child boxes.
#[derive(Clone, Copy)]
struct NodeRay {
    origin: Vec3A,
    /// `1/d` per axis; a zero component is replaced by a tiny one of the same sign, so
    /// parallel slabs give ±huge instead of NaN.
    inv_direction: Vec3A,
}

impl NodeRay {
    #[inline(always)]
    fn new(origin: Vec3, direction: Vec3) -> Self {
        let safe = |d: f32| if d == 0.0 { 1e-30f32.copysign(d) } else { d };
        NodeRay {
            origin: origin.into(),
            inv_direction: Vec3A::new(
                1.0 / safe(direction.x),
                1.0 / safe(direction.y),
                1.0 / safe(direction.z),
            ),
        }
    }

    /// The traversal hit mask of `node`'s children whose boxes the ray meets in `[0, t_max]`.
    ///
    /// A child box is `p + q·e` with 8-bit `q` and power-of-two `e`, so slab distances are
    /// `q·(e/d) + (p − o)/d`. Each is computed with a few roundings; the slab is widened by
    /// the bound `γ(5)·(255·|e/d| + |(p − o)/d|)` on their error, per axis, so no box the ray
    /// truly meets is rejected (at the price of a few extra box hits).
    #[inline(always)]
    fn child_hits(&self, node: &CwBvhNode, t_max: f32, oct_inv4: u32) -> u32 {
        let scale = node.compute_extent() * self.inv_direction;
        let offset = (Vec3A::from(node.p) - self.origin) * self.inv_direction;
        let slop = gamma(5) * (255.0 * scale.abs() + offset.abs());
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        let mut hit_mask = 0;
        let axes = [
            (dequantize(&node.child_min_x), dequantize(&node.child_max_x)),
            (dequantize(&node.child_min_y), dequantize(&node.child_max_y)),
            (dequantize(&node.child_min_z), dequantize(&node.child_max_z)),
        ];
        for half in 0..2 {
            let slab = |axis: usize| {
                let (lo, hi) = axes[axis];
                let t0 = lo[half] * scale[axis] + Vec4::splat(offset[axis]);
                let t1 = hi[half] * scale[axis] + Vec4::splat(offset[axis]);
                (
                    t0.min(t1) - Vec4::splat(slop[axis]),
                    t0.max(t1) + Vec4::splat(slop[axis]),
                )
            };
            let (near_x, far_x) = slab(0);
            let (near_y, far_y) = slab(1);
            let (near_z, far_z) = slab(2);
            let near = near_x.max(near_y).max(near_z).max(Vec4::ZERO);
            let far = far_x.min(far_y).min(far_z).min(Vec4::splat(t_max));
            let mask = near.cmple(far).bitmask();
            for j in 0..4 {
                // Branch-free: box hits are unpredictable.
                let keep = ((mask >> j) & 1).wrapping_neg();
                let child = 4 * half + j as usize;
                let bits = ((child_bits8 >> (8 * child)) & 0xFF) as u32;
                let index = ((bit_index8 >> (8 * child)) & 0xFF) as u32;
                hit_mask |= (bits << index) & keep;
            }
        }
        hit_mask
    }
}

/// Eight quantised box bounds as two `Vec4`s of floats.
#[inline(always)]
fn dequantize(q: &[u8; 8]) -> [Vec4; 2] {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE2 is part of the x86_64 baseline; the load reads exactly the 8 bytes of `q`.
        unsafe {
            use std::arch::x86_64::*;
            let bytes = _mm_loadl_epi64(q.as_ptr() as *const __m128i);
            let words = _mm_unpacklo_epi8(bytes, _mm_setzero_si128());
            let lo = _mm_unpacklo_epi16(words, _mm_setzero_si128());
            let hi = _mm_unpackhi_epi16(words, _mm_setzero_si128());
            [Vec4::from(_mm_cvtepi32_ps(lo)), Vec4::from(_mm_cvtepi32_ps(hi))]
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let f = |i: usize| Vec4::new(q[i] as f32, q[i + 1] as f32, q[i + 2] as f32, q[i + 3] as f32);
        [f(0), f(4)]
    }
}

impl RayCaster for Accel {
    fn closest_hit(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> Option<Hit> {
        let (id, t, b) = self.trace(origin, direction, t_max, leaving)?;
        let p = self.corners[id].map(Vec3::from);
        let point = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
        Some(Hit {
            t,
            triangle: self.mesh_index[id],
            point,
            point_error: barycentric_point_error(b, p),
            normal: (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero(),
        })
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> f32 {
        self.trace(origin, direction, t_max, leaving)
            .map_or(f32::INFINITY, |(_, t, _)| t)
    }
}
