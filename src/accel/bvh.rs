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

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::{cwbvh::builder::build_cwbvh_from_tris, cwbvh::CwBvh, ray::Ray, triangle::Triangle, BvhBuildParams};

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
    fn trace(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(usize, f32, [f32; 3])> {
        let ray = WatertightRay::new(origin, direction);
        let mut node_ray = Ray::new(origin.into(), direction.into(), 0.0, t_max);
        let mut best: Option<(usize, f32, [f32; 3])> = None;
        let mut state = self.bvh.new_traversal(node_ray.direction);
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node.intersect_ray(&node_ray, state.oct_inv4),
            {
                let id = state.primitive_id as usize;
                let [p0, p1, p2] = self.corners[id];
                if let Some(hit) = ray.intersect(p0, p1, p2, node_ray.tmax) {
                    node_ray.tmax = hit.t;
                    best = Some((id, hit.t, hit.b));
                }
            }
        );
        best
    }
}

use glam::UVec2;

impl RayCaster for Accel {
    fn closest_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<Hit> {
        let (id, t, b) = self.trace(origin, direction, t_max)?;
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
    fn hit_distance(&self, origin: Vec3, direction: Vec3, t_max: f32) -> f32 {
        self.trace(origin, direction, t_max).map_or(f32::INFINITY, |(_, t, _)| t)
    }
}
