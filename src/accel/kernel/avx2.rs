//! The 8-lane AVX2 kernel: the scalar kernel's arithmetic, eight children or triangles per
//! instruction. Separate multiplies and adds (no FMA) and exact division keep every lane's
//! bits equal to [`super::scalar`]'s.
//!
//! The `closest_*` entry points are the traversal compiled with the instruction set enabled;
//! the [`Lanes`] methods are `#[inline(always)]` so they are compiled inside them.

use std::arch::x86_64::*;
use std::mem::MaybeUninit;

use super::{BlockHits, Lanes, RayData, FAR_SCALE};
use crate::accel::float_error::gamma;
use crate::accel::traverse::{closest, Closest, Counter, Entry};
use crate::accel::wide::{Block, Node, WideBvh, WIDTH};
use crate::accel::RayLanes;

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

/// The eight triangles' corners translated to the ray origin, in the ray's permuted axes
/// (`[corner][kx, ky, kz]`): the part of the block test that depends on the ray only through
/// its origin and axis permutation, so that rays which share both can share it.
///
/// # Safety
/// As [`block_translated`]; the block is 32-byte aligned.
#[inline(always)]
pub(crate) unsafe fn translated(block: &Block, ray: &RayData) -> [[__m256; 3]; 3] {
    let [ox, oy, oz] = ray.permuted_origin;
    let origin = [splat(ox), splat(oy), splat(oz)];
    [
        translated_corner(block, ray, origin, 0),
        translated_corner(block, ray, origin, 1),
        translated_corner(block, ray, origin, 2),
    ]
}

/// Corner `k` of [`translated`].
#[inline(always)]
unsafe fn translated_corner(block: &Block, ray: &RayData, origin: [__m256; 3], k: usize) -> [__m256; 3] {
    let r = &ray.triangle;
    [
        _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.kx].as_ptr()), origin[0]),
        _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.ky].as_ptr()), origin[1]),
        _mm256_sub_ps(_mm256_load_ps(block.corner[k][r.kz].as_ptr()), origin[2]),
    ]
}

/// A translated corner sheared in x and y onto +z (z is scaled later, as in the scalar test).
#[inline(always)]
unsafe fn sheared([x, y, z]: [__m256; 3], ray: &RayData) -> [__m256; 3] {
    let r = &ray.triangle;
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
        unsafe { block_translated(translated(block, ray), ray, t_max) }
    }
}

/// [`Lanes::block`] of the block whose corners [`translated`] gave for this ray's origin and
/// axis permutation. One function of ~110 lines on purpose: it is the watertight triangle
/// test of Woop et al. written out over eight lanes (shear, edge functions, the
/// double-precision fallback, depth), one straight-line computation in registers.
///
/// # Safety
/// The CPU must support AVX2 (called only inside the `#[target_feature]` traversals).
#[inline(always)]
pub(crate) unsafe fn block_translated(corners: [[__m256; 3]; 3], ray: &RayData, t_max: f32) -> BlockHits {
    let r = &ray.triangle;
    let [ax, ay, az] = sheared(corners[0], ray);
    let [bx, by, bz] = sheared(corners[1], ray);
    let [cx, cy, cz] = sheared(corners[2], ray);
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

/// [`ray_lanes`] for a test: the rays, the lanes of their origins and reciprocal directions
/// (x, y, z, then 1/x, 1/y, 1/z), and the `y_wins`, `z_wins` bits.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(test)]
#[target_feature(enable = "avx2")]
unsafe fn ray_packet(
    origins: &[glam::Vec3],
    directions: &[glam::Vec3],
) -> (Vec<RayData>, [[f32; WIDTH]; 6], [u32; 2]) {
    let mut rays = [const { MaybeUninit::uninit() }; WIDTH];
    let packet = RayLanes::from_rays(origins, directions);
    let (rays, lanes) = ray_lanes(&packet, directions.len(), &mut rays);
    let [ox, oy, oz] = lanes.origin.map(|v| spill(v));
    let [ix, iy, iz] = lanes.inverse.map(|v| spill(v));
    (
        rays.to_vec(),
        [ox, oy, oz, ix, iy, iz],
        [lanes.y_wins, lanes.z_wins],
    )
}

/// A packet's rays as lanes, what the packet traversal's box tests read: lane `i` holds ray
/// `i` (lanes past the last ray repeat it).
#[derive(Clone, Copy)]
pub(crate) struct PacketLanes {
    pub origin: [__m256; 3],
    /// [`RayData::inv_direction`] per axis.
    pub inverse: [__m256; 3],
    /// All bits set where `inverse < 0`, per axis (the rays' near plane is the max one).
    pub negative: [__m256; 3],
    /// Bit per lane: the watertight test's dominant axis `kz` is z (`z_wins`), else y
    /// (`y_wins`), else x.
    pub y_wins: u32,
    pub z_wins: u32,
}

/// [`RayData::new`] for the first `n` rays of `packet` (1 to [`WIDTH`]) at once, written to
/// the first `n` of `rays`, and the same rays as vectors (lanes past the last ray repeat
/// it): the six divisions per ray (three reciprocals, the shear's two quotients and `1/d_z`)
/// as six vector divisions, the axis permutation and the rows by compares and blends. The
/// same IEEE operations in the same order as the scalar constructor, so every field is the
/// same bits (tested: zeros of both signs, ties of magnitude, NaN and infinite components).
/// Inlined into the packet traversal, so the lanes stay in registers rather than being
/// gathered again from the [`RayData`], and the rays are written where the traversal reads
/// them (built aside and returned, they were copied: ~50 instructions a ray). The load of a
/// ray's origin just after its two 4-byte stores cannot be forwarded, and a profile puts a
/// few percent of samples on it, but avoiding it measured no faster (`docs/engine.md`).
///
/// # Safety
/// The CPU must support AVX2: call it only from code compiled with it.
#[inline(always)]
pub(crate) unsafe fn ray_lanes<'r>(
    packet: &RayLanes,
    n: usize,
    rays: &'r mut [MaybeUninit<RayData>; WIDTH],
) -> (&'r [RayData], PacketLanes) {
    debug_assert!((1..=WIDTH).contains(&n), "cast_packet checks");
    let x = _mm256_loadu_ps(packet.direction[0].as_ptr());
    let y = _mm256_loadu_ps(packet.direction[1].as_ptr());
    let z = _mm256_loadu_ps(packet.direction[2].as_ptr());
    let origin = packet.origin.map(|axis| _mm256_loadu_ps(axis.as_ptr()));
    let inverse = [
        reciprocal(safe_divisor(x)),
        reciprocal(safe_divisor(y)),
        reciprocal(safe_divisor(z)),
    ];
    // `1/d < 0` per axis (false for NaN, as the scalar comparison).
    let negative = inverse.map(|v| _mm256_cmp_ps::<_CMP_LT_OQ>(v, _mm256_setzero_ps()));
    // kz: glam's max_position of |d| (x, then y if greater, then z if greater than that).
    let (ax, ay, az) = (abs(x), abs(y), abs(z));
    let y_wins = _mm256_cmp_ps::<_CMP_GT_OQ>(ay, ax);
    let z_wins = _mm256_cmp_ps::<_CMP_GT_OQ>(az, _mm256_blendv_ps(ax, ay, y_wins));
    // (d[kx], d[ky], d[kz]) with kx = kz + 1 and ky = kz + 2 (mod 3).
    let dx = pick(y, z, x, y_wins, z_wins);
    let dy = pick(z, x, y, y_wins, z_wins);
    let dz = pick(x, y, z, y_wins, z_wins);
    let sign = splat(-0.0);
    let inv = inverse.map(|v| spill(v));
    let shear = [
        spill(_mm256_div_ps(_mm256_xor_ps(dx, sign), dz)),
        spill(_mm256_div_ps(_mm256_xor_ps(dy, sign), dz)),
        spill(reciprocal(dz)),
    ];
    // Per lane, the rows and the permutation from small tables: the sign bits of the three
    // axes (bit `axis` where `negative[axis]`) index the rows, kz the permutation. Both
    // indices found for all lanes at once.
    let bit = |v: __m256, value: i32| _mm256_and_si256(_mm256_castps_si256(v), _mm256_set1_epi32(value));
    let signs = spill_indices(_mm256_or_si256(
        bit(negative[0], 1),
        _mm256_or_si256(bit(negative[1], 2), bit(negative[2], 4)),
    ));
    let axes = spill_indices(_mm256_or_si256(bit(y_wins, 1), bit(z_wins, 2)));
    let (y_wins, z_wins) = (mask(y_wins), mask(z_wins));
    for (i, ray) in rays[..n].iter_mut().enumerate() {
        let origin = packet.origin(i).to_array();
        // kz = 2 where z won (y may have won against x too: 1 | 2 = 3, the same entry).
        let [kx, ky, kz] = PERMUTATION[axes[i] as usize];
        let (near_row, far_row) = ROWS[signs[i] as usize];
        ray.write(RayData {
            origin,
            inv_direction: [inv[0][i], inv[1][i], inv[2][i]],
            near_row,
            far_row,
            permuted_origin: [origin[kx], origin[ky], origin[kz]],
            triangle: crate::accel::triangle::WatertightRay {
                origin: origin.into(),
                kx,
                ky,
                kz,
                sx: shear[0][i],
                sy: shear[1][i],
                sz: shear[2][i],
            },
        });
    }
    let lanes = PacketLanes {
        origin,
        inverse,
        negative,
        y_wins,
        z_wins,
    };
    // SAFETY: the loop above wrote the first `n` rays.
    let rays = &*(&rays[..n] as *const [MaybeUninit<RayData>] as *const [RayData]);
    (rays, lanes)
}

/// `(kx, ky, kz)` by `kz`: `kx = kz + 1`, `ky = kz + 2` (mod 3); index 3 is y and z both
/// winning, so z.
const PERMUTATION: [[usize; 3]; 4] = [[1, 2, 0], [2, 0, 1], [0, 1, 2], [0, 1, 2]];

/// [`RayData`]'s near and far rows by the directions' sign bits (bit `axis` set where the
/// reciprocal direction is negative): `near = axis + 3·bit`, `far` the other row.
const ROWS: [([usize; 3], [usize; 3]); 8] = {
    let mut rows = [([0; 3], [0; 3]); 8];
    let mut signs = 0;
    while signs < 8 {
        let mut axis = 0;
        while axis < 3 {
            let negative = signs >> axis & 1;
            rows[signs].0[axis] = axis + 3 * negative;
            rows[signs].1[axis] = axis + 3 * (1 - negative);
            axis += 1;
        }
        signs += 1;
    }
    rows
};

/// A zero component (either sign) replaced by 1e-30 of its sign, as `RayData::new` does.
#[inline(always)]
unsafe fn safe_divisor(d: __m256) -> __m256 {
    let tiny = _mm256_or_ps(_mm256_and_ps(d, splat(-0.0)), splat(1e-30));
    _mm256_blendv_ps(d, tiny, _mm256_cmp_ps::<_CMP_EQ_OQ>(d, _mm256_setzero_ps()))
}

#[inline(always)]
unsafe fn reciprocal(d: __m256) -> __m256 {
    _mm256_div_ps(splat(1.0), d)
}

/// Per lane: `if_z` where z won, else `if_y` where y won, else `if_x`.
#[inline(always)]
unsafe fn pick(if_x: __m256, if_y: __m256, if_z: __m256, y_wins: __m256, z_wins: __m256) -> __m256 {
    _mm256_blendv_ps(_mm256_blendv_ps(if_x, if_y, y_wins), if_z, z_wins)
}

#[inline(always)]
unsafe fn spill_indices(v: __m256i) -> [u32; WIDTH] {
    let mut out = [0u32; WIDTH];
    _mm256_storeu_si256(out.as_mut_ptr() as *mut __m256i, v);
    out
}

#[inline(always)]
unsafe fn spill(v: __m256) -> [f32; WIDTH] {
    let mut out = [0.0f32; WIDTH];
    _mm256_storeu_ps(out.as_mut_ptr(), v);
    out
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// Every field of `a` and `b`, floats as bits.
    fn same(a: &RayData, b: &RayData) -> bool {
        let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
        let (s, t) = (&a.triangle, &b.triangle);
        bits(&a.origin) == bits(&b.origin)
            && bits(&a.inv_direction) == bits(&b.inv_direction)
            && a.near_row == b.near_row
            && a.far_row == b.far_row
            && bits(&a.permuted_origin) == bits(&b.permuted_origin)
            && bits(&s.origin.to_array()) == bits(&t.origin.to_array())
            && (s.kx, s.ky, s.kz) == (t.kx, t.ky, t.kz)
            && bits(&[s.sx, s.sy, s.sz]) == bits(&[t.sx, t.sy, t.sz])
    }

    #[test]
    fn a_packets_ray_data_is_the_scalar_constructors_bit_for_bit() {
        if !is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2");
            return;
        }
        // Components that exercise every branch: zeros of both signs, ties of magnitude
        // (x = ±y, y = ±z, all three), NaN and infinities, tiny and huge values.
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -0.5,
            2.0,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
            1e-30,
            -1e-38,
            3e38,
            0.3,
            -0.7,
        ];
        let mut directions: Vec<Vec3> = Vec::new();
        for &x in &special {
            for &y in &special {
                for &z in &special {
                    directions.push(Vec3::new(x, y, z));
                }
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            let mut next = || {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
            };
            directions.push(Vec3::new(next(), next(), next()));
        }
        let origins: Vec<Vec3> = (0..directions.len())
            .map(|i| Vec3::new(i as f32 * 0.25, -(i as f32), 1.0 / (i as f32 + 1.0)))
            .collect();
        let mut checked = 0;
        for (chunk, (d, o)) in directions.chunks(WIDTH).zip(origins.chunks(WIDTH)).enumerate() {
            // Packets of every size from 1 to 8.
            let n = chunk % WIDTH + 1;
            let (d, o) = (&d[..n.min(d.len())], &o[..n.min(o.len())]);
            // SAFETY: AVX2 was detected above.
            let (packet, lanes, [y_wins, z_wins]) = unsafe { ray_packet(o, d) };
            assert_eq!(packet.len(), d.len());
            for (i, ray) in packet.iter().enumerate() {
                assert!(same(ray, &RayData::new(o[i], d[i])), "ray {i} of {d:?}");
                checked += 1;
            }
            // The lanes: ray i in lane i, the last ray repeated in the lanes past it.
            for lane in 0..WIDTH {
                let ray = RayData::new(o[lane.min(n - 1)], d[lane.min(n - 1)]);
                let expected = [ray.origin, ray.inv_direction].concat();
                let got: Vec<f32> = lanes.iter().map(|column| column[lane]).collect();
                assert_eq!(
                    got.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                    expected.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                    "lane {lane} of {d:?}"
                );
                let kz = if z_wins >> lane & 1 != 0 {
                    2
                } else {
                    (y_wins >> lane & 1) as usize
                };
                assert_eq!(kz, ray.triangle.kz, "lane {lane} of {d:?}");
            }
        }
        assert!(checked > 10_000);
    }
}
