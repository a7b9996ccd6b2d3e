//! The portable kernel: one lane at a time, the reference the SIMD kernels must match bit
//! for bit. `max`/`min` follow the SSE rule (`max(a, b) = a > b ? a : b`), so a signed zero
//! or a NaN comes out as it does from `maxps`/`minps`.

use super::{BlockHits, Lanes, RayData, FAR_SCALE};
use crate::accel::wide::{Block, Node, WIDTH};
use glam::Vec3A;

pub(crate) struct Scalar;

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

impl Lanes for Scalar {
    #[inline(always)]
    fn node(node: &Node, ray: &RayData, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut near = [0.0; WIDTH];
        let mut mask = 0;
        for (lane, lane_near) in near.iter_mut().enumerate() {
            let slab = |row: usize, axis: usize| {
                (node.bounds[row][lane] - ray.origin[axis]) * ray.inv_direction[axis]
            };
            let t_near = max(
                max(slab(ray.near_row[0], 0), slab(ray.near_row[1], 1)),
                max(slab(ray.near_row[2], 2), 0.0),
            );
            let t_far = min(
                min(slab(ray.far_row[0], 0), slab(ray.far_row[1], 1)),
                min(slab(ray.far_row[2], 2), t_max),
            ) * FAR_SCALE;
            *lane_near = t_near;
            mask |= ((t_near <= t_far) as u32) << lane;
        }
        (mask, near)
    }

    #[inline(always)]
    fn block(block: &Block, ray: &RayData, t_max: f32) -> BlockHits {
        let mut hits = BlockHits {
            hit: 0,
            within_error: 0,
            t: [0.0; WIDTH],
        };
        for lane in 0..WIDTH {
            let [p0, p1, p2]: [Vec3A; 3] = block.triangle(lane);
            if let Some(hit) = ray.triangle.intersect(p0, p1, p2, t_max) {
                hits.hit |= 1 << lane;
                hits.within_error |= (hit.within_error as u32) << lane;
                hits.t[lane] = hit.t;
            }
        }
        hits
    }
}
