//! The 8-lane AVX2 kernel: the scalar kernel's arithmetic, eight children or triangles per
//! instruction. Separate multiplies and adds (no FMA) and exact division keep every lane's
//! bits equal to [`super::scalar`]'s.
//!
//! The `closest_*` entry points are the traversal compiled with the instruction set enabled;
//! the [`Lanes`] methods are `#[inline(always)]` so they are compiled inside them.

use std::arch::x86_64::*;

use super::{BlockHits, Lanes, RayData, FAR_SCALE};
use crate::accel::float_error::gamma;
use crate::accel::traverse::{closest, Closest, Counter, Entry};
use crate::accel::wide::{Block, Node, WideBvh, WIDTH};

pub(crate) struct Avx2;

/// The traversal with AVX2 enabled.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn closest_avx2<C: Counter>(
    bvh: &WideBvh,
    ray: &RayData,
    t_max: f32,
    accept_within_error: &dyn Fn(u32, usize) -> bool,
    stack: &mut [std::mem::MaybeUninit<Entry>],
    counter: &mut C,
) -> Option<Closest> {
    closest::<Avx2, C>(bvh, ray, t_max, accept_within_error, stack, counter)
}

/// The same traversal compiled for AVX-512 (256-bit instructions in EVEX form, mask
/// registers for the compares).
///
/// # Safety
/// The CPU must support AVX2, AVX-512F and AVX-512VL.
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512dq,avx512bw")]
pub(crate) unsafe fn closest_avx512<C: Counter>(
    bvh: &WideBvh,
    ray: &RayData,
    t_max: f32,
    accept_within_error: &dyn Fn(u32, usize) -> bool,
    stack: &mut [std::mem::MaybeUninit<Entry>],
    counter: &mut C,
) -> Option<Closest> {
    closest::<Avx2, C>(bvh, ray, t_max, accept_within_error, stack, counter)
}

#[inline(always)]
unsafe fn splat(v: f32) -> __m256 {
    _mm256_set1_ps(v)
}

#[inline(always)]
unsafe fn abs(v: __m256) -> __m256 {
    _mm256_and_ps(v, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff)))
}

#[inline(always)]
unsafe fn mask(v: __m256) -> u32 {
    _mm256_movemask_ps(v) as u32
}

/// Slab distances `(b − o)·(1/d)` of the eight children's planes in bounds row `row`.
#[inline(always)]
unsafe fn slab(node: &Node, ray: &RayData, row: usize, axis: usize) -> __m256 {
    _mm256_mul_ps(
        _mm256_sub_ps(_mm256_load_ps(node.bounds[row].as_ptr()), splat(ray.origin[axis])),
        splat(ray.inv_direction[axis]),
    )
}

/// Corner `k` of the eight triangles, translated to the ray origin, permuted so that the
/// ray's dominant axis is z, and sheared in x and y onto +z (z is scaled later, as in the
/// scalar test).
#[inline(always)]
unsafe fn sheared_corner(block: &Block, ray: &RayData, origin: [__m256; 3], k: usize) -> [__m256; 3] {
    let r = &ray.triangle;
    let x = _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.kx].as_ptr()), origin[0]);
    let y = _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.ky].as_ptr()), origin[1]);
    let z = _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.kz].as_ptr()), origin[2]);
    [
        _mm256_add_ps(x, _mm256_mul_ps(splat(r.sx), z)),
        _mm256_add_ps(y, _mm256_mul_ps(splat(r.sy), z)),
        z,
    ]
}

/// The 2D edge function `p.x·q.y − p.y·q.x`.
#[inline(always)]
unsafe fn edge(px: __m256, py: __m256, qx: __m256, qy: __m256) -> __m256 {
    _mm256_sub_ps(_mm256_mul_ps(px, qy), _mm256_mul_ps(py, qx))
}

#[inline(always)]
unsafe fn max_abs(p: __m256, q: __m256, s: __m256) -> __m256 {
    _mm256_max_ps(_mm256_max_ps(abs(p), abs(q)), abs(s))
}

impl Lanes for Avx2 {
    #[inline(always)]
    fn node(node: &Node, ray: &RayData, t_max: f32) -> (u32, [f32; WIDTH]) {
        // SAFETY: only compiled into the `#[target_feature]` entry points above; the loads
        // read whole rows of a 64-byte-aligned node.
        unsafe {
            // Two levels of max (and min) rather than three: a shorter dependency chain.
            let t_near = _mm256_max_ps(
                _mm256_max_ps(
                    slab(node, ray, ray.near_row[0], 0),
                    slab(node, ray, ray.near_row[1], 1),
                ),
                _mm256_max_ps(slab(node, ray, ray.near_row[2], 2), _mm256_setzero_ps()),
            );
            let t_far = _mm256_mul_ps(
                _mm256_min_ps(
                    _mm256_min_ps(
                        slab(node, ray, ray.far_row[0], 0),
                        slab(node, ray, ray.far_row[1], 1),
                    ),
                    _mm256_min_ps(slab(node, ray, ray.far_row[2], 2), splat(t_max)),
                ),
                splat(FAR_SCALE),
            );
            let mut near = [0.0; WIDTH];
            _mm256_storeu_ps(near.as_mut_ptr(), t_near);
            (mask(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far)), near)
        }
    }

    #[inline(always)]
    fn block(block: &Block, ray: &RayData, t_max: f32) -> BlockHits {
        // SAFETY: as in `node`; the block is 32-byte aligned.
        unsafe {
            let r = &ray.triangle;
            let [ox, oy, oz] = ray.permuted_origin();
            let origin = [splat(ox), splat(oy), splat(oz)];
            let [ax, ay, az] = sheared_corner(block, ray, origin, 0);
            let [bx, by, bz] = sheared_corner(block, ray, origin, 1);
            let [cx, cy, cz] = sheared_corner(block, ray, origin, 2);
            let mut e0 = edge(bx, by, cx, cy);
            let mut e1 = edge(cx, cy, ax, ay);
            let mut e2 = edge(ax, ay, bx, by);
            let zero = _mm256_setzero_ps();
            let exact_zero = mask(_mm256_or_ps(
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(e0, zero),
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(e1, zero),
                ),
                _mm256_cmp_ps::<_CMP_EQ_OQ>(e2, zero),
            ));
            if exact_zero != 0 {
                [e0, e1, e2] = edges_in_f64(exact_zero, [e0, e1, e2], [ax, ay, bx, by, cx, cy]);
            }
            let negative = _mm256_or_ps(
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_LT_OQ>(e0, zero),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(e1, zero),
                ),
                _mm256_cmp_ps::<_CMP_LT_OQ>(e2, zero),
            );
            let positive = _mm256_or_ps(
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_GT_OQ>(e0, zero),
                    _mm256_cmp_ps::<_CMP_GT_OQ>(e1, zero),
                ),
                _mm256_cmp_ps::<_CMP_GT_OQ>(e2, zero),
            );
            let det = _mm256_add_ps(_mm256_add_ps(e0, e1), e2);
            let sz = splat(r.sz);
            let (az, bz, cz) = (
                _mm256_mul_ps(az, sz),
                _mm256_mul_ps(bz, sz),
                _mm256_mul_ps(cz, sz),
            );
            let t_scaled = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(e0, az), _mm256_mul_ps(e1, bz)),
                _mm256_mul_ps(e2, cz),
            );
            let t_max_det = _mm256_mul_ps(splat(t_max), det);
            let det_negative = _mm256_cmp_ps::<_CMP_LT_OQ>(det, zero);
            let outside_negative = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(t_scaled, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t_scaled, t_max_det),
            );
            let outside_positive = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_scaled, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(t_scaled, t_max_det),
            );
            let outside = _mm256_blendv_ps(outside_positive, outside_negative, det_negative);
            let miss = _mm256_or_ps(
                _mm256_or_ps(
                    _mm256_and_ps(negative, positive),
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero),
                ),
                outside,
            );
            let hit = !mask(miss) & 0xff;
            let mut hits = BlockHits {
                hit,
                within_error: 0,
                t: [0.0; WIDTH],
            };
            if hit == 0 {
                return hits;
            }
            let inv_det = _mm256_div_ps(splat(1.0), det);
            let t = _mm256_mul_ps(t_scaled, inv_det);
            _mm256_storeu_ps(hits.t.as_mut_ptr(), t);

            // The error bound of t (pbrt-v4 §6.8.7), as in `WatertightRay::intersect`.
            let max_zt = max_abs(az, bz, cz);
            let max_xt = max_abs(ax, bx, cx);
            let max_yt = max_abs(ay, by, cy);
            let delta_z = _mm256_mul_ps(splat(gamma(3)), max_zt);
            let delta_x = _mm256_mul_ps(splat(gamma(5)), _mm256_add_ps(max_xt, max_zt));
            let delta_y = _mm256_mul_ps(splat(gamma(5)), _mm256_add_ps(max_yt, max_zt));
            let delta_e = _mm256_mul_ps(
                splat(2.0),
                _mm256_add_ps(
                    _mm256_add_ps(
                        _mm256_mul_ps(_mm256_mul_ps(splat(gamma(2)), max_xt), max_yt),
                        _mm256_mul_ps(delta_y, max_xt),
                    ),
                    _mm256_mul_ps(delta_x, max_yt),
                ),
            );
            let max_e = max_abs(e0, e1, e2);
            let delta_t = _mm256_mul_ps(
                _mm256_mul_ps(
                    splat(3.0),
                    _mm256_add_ps(
                        _mm256_add_ps(
                            _mm256_mul_ps(_mm256_mul_ps(splat(gamma(3)), max_e), max_zt),
                            _mm256_mul_ps(delta_e, max_zt),
                        ),
                        _mm256_mul_ps(delta_z, max_e),
                    ),
                ),
                abs(inv_det),
            );
            hits.within_error = mask(_mm256_cmp_ps::<_CMP_LE_OQ>(t, delta_t)) & hit;
            hits
        }
    }
}

/// The lanes whose edge functions came out exactly zero, recomputed in f64 as the scalar test
/// does (rare: rays through a vertex or along an edge).
#[cold]
#[inline(never)]
fn edges_in_f64(lanes: u32, edges: [__m256; 3], sheared: [__m256; 6]) -> [__m256; 3] {
    let spill = |v: __m256| {
        let mut out = [0.0f32; WIDTH];
        // SAFETY: an unaligned store of one vector into an 8-float array.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
        out
    };
    let mut e = edges.map(spill);
    let [ax, ay, bx, by, cx, cy] = sheared.map(spill);
    let product = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
    for lane in (0..WIDTH).filter(|lane| lanes >> lane & 1 != 0) {
        e[0][lane] = product(bx[lane], cy[lane], by[lane], cx[lane]);
        e[1][lane] = product(cx[lane], ay[lane], cy[lane], ax[lane]);
        e[2][lane] = product(ax[lane], by[lane], ay[lane], bx[lane]);
    }
    // SAFETY: unaligned loads of 8-float arrays.
    e.map(|lane_values| unsafe { _mm256_loadu_ps(lane_values.as_ptr()) })
}
