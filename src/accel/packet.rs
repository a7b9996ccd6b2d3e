//! Packets: up to eight rays traversed together, one ray per SIMD lane (AVX2).
//!
//! A packet visits a node once for all its rays: the eight children's boxes are tested
//! child by child against every active ray at once, the children that some ray meets are
//! ordered by the nearest entry distance among those rays, and each goes on the stack with
//! the rays that met it and their entry distances (so a ray that has since found a closer hit
//! drops out when the entry is popped). Before that, a first test of all eight children
//! against the packet as a whole ([`PacketBounds`]) skips those that no ray can meet. Leaf
//! blocks are tested ray by ray with the single-ray kernel, and once fewer than
//! [`SINGLE_BELOW`] rays of a packet are left in a subtree, they finish it one at a time
//! ([`super::traverse::descend`]).
//!
//! The answer for each ray is bit for bit the single-ray one: the box tests perform the
//! single-ray kernel's IEEE operations (the same slab distances, min/max order and far-scale,
//! so they are as conservative), the triangle tests *are* the single-ray kernel's, and the
//! closest hit does not depend on the order of the visit (ties of `t` go to the lowest
//! triangle index: see [`super::traverse`]).
//!
//! **Coherent packets.** At many rays per point (the reference's 65,536) a 4 × 2 block of
//! strata spans a few hundredths of a radian and its rays meet nearly the same nodes. So a
//! packet whose directions differ by at most [`SPREAD`] takes an *inner* child on the
//! interval test alone: all its active rays go on, each with the interval's smallest near
//! distance, which is at most the ray's own (see [`PacketBounds`]), so no entry is culled
//! sooner than the ray's own would be. A ray may so visit an inner node whose box it misses;
//! it costs a little work and changes no hit, because *leaf* children are still tested ray by
//! ray with the single-ray expressions: a ray tests a block only where its own box test
//! admits it.
//!
//! **A shared origin.** Where all the packet's rays leave one point along one dominant axis (a
//! gather point's rays, nearly always), a leaf block's corners are translated to that point
//! once for the packet ([`super::kernel::avx2::translated`]) and then tested ray by ray: the
//! same IEEE operations as the single-ray test, a subtraction fewer per corner and ray.
//!
//! Closures inside this `#[target_feature]` code are not inlined and turn every intrinsic
//! into a call (the packet ran 40 % slower): use `#[inline(always)]` functions.
//!
//! What packets gain, and the dead ends measured and not kept (no interval test, wider
//! packets, pixel packets, prefetching, certifying children): `docs/engine.md`.

use std::arch::x86_64::*;
use std::mem::MaybeUninit;

use super::kernel::avx2::{block_translated, ray_lanes, translated, Avx2, PacketLanes};
use super::kernel::{RayData, FAR_SCALE};
use super::traverse::{descend, Counter, Entry, Search};
use super::wide::{Node, WideBvh, EMPTY, LEAF, WIDTH};
use super::{RayLanes, PACKET};

/// Below this many active rays, a packet's subtree is finished ray by ray. Measured on `cube`
/// and `hall` (256² × 256 and 64² × 4,096 rays, Mrays/s on 2 cores): 3 and 4 were as fast at
/// 4,096 rays and 5–10 % slower at 256; 6 was 5 % slower at 4,096; 2 was 10 % slower than 5
/// everywhere (packet visits that serve one or two rays cost more than single-ray visits).
pub(crate) const SINGLE_BELOW: u32 = 5;

/// A packet whose rays' directions differ by at most this much on every axis is *coherent*:
/// its inner children are taken on the packet's interval test alone (see the module docs).
/// Measured (instructions of `gather_rays order … blocks`, one thread): at 65,536 rays per
/// point (a 4 × 2 block of a 256 × 256 grid) 0.025 saved 3 %, 0.05 and 0.1 5 % of the whole
/// run; at 4,096 rays 0.05 saved 0.2 % and 0.1 cost 1 %; at 256 rays (`cube`, `hall`) 0.05
/// and 0.1 cost 0.1–0.2 % (few packets are that narrow), 0.4 cost 60 % on `cube` and 130 %
/// on `hall` (loose interval tests send whole packets down subtrees that few rays meet).
const SPREAD: f32 = 0.05;

/// A packet stack entry: a child reference, the rays that met its box (bit per lane) and
/// their entry distances.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct PacketEntry {
    near: [f32; PACKET],
    reference: u32,
    rays: u32,
}

/// The packet traversal with AVX2 enabled: the hits of ray `r` of `packet` go to
/// `searches[r]` (as many rays as searches).
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn closest_packet_avx2<C: Counter>(
    bvh: &WideBvh,
    packet: &RayLanes,
    searches: &mut [Search],
    packet_stack: &mut [MaybeUninit<PacketEntry>],
    stack: &mut [MaybeUninit<Entry>],
    counter: &mut C,
) {
    let mut rays = [const { MaybeUninit::uninit() }; WIDTH];
    let rays = ray_lanes(packet, searches.len(), &mut rays);
    traverse::<C>(bvh, rays, searches, packet_stack, stack, counter)
}

/// The same compiled for AVX-512 (see [`super::kernel::avx2::closest_avx512`]).
///
/// # Safety
/// The CPU must support AVX2, AVX-512F and AVX-512VL.
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512dq,avx512bw")]
pub(crate) unsafe fn closest_packet_avx512<C: Counter>(
    bvh: &WideBvh,
    packet: &RayLanes,
    searches: &mut [Search],
    packet_stack: &mut [MaybeUninit<PacketEntry>],
    stack: &mut [MaybeUninit<Entry>],
    counter: &mut C,
) {
    let mut rays = [const { MaybeUninit::uninit() }; WIDTH];
    let rays = ray_lanes(packet, searches.len(), &mut rays);
    traverse::<C>(bvh, rays, searches, packet_stack, stack, counter)
}

/// A child that some rays of the packet meet, with the sort key (the nearest entry).
#[derive(Clone, Copy)]
struct Met {
    key: f32,
    slot: usize,
    rays: u32,
}

/// The slots that hold a child (bit per slot): children fill the slots from the first.
#[inline(always)]
fn occupied(node: &Node) -> u32 {
    let mut slots = 0;
    while slots < WIDTH as u32 && node.child[slots as usize] != EMPTY {
        slots += 1;
    }
    (1u32 << slots) - 1
}

/// The slab distances `(b − o)·(1/d)` of child `slot`'s plane in bounds row `row`, for
/// every ray (lanes of `origin` and `inverse`).
#[inline(always)]
unsafe fn slab(node: &Node, row: usize, slot: usize, origin: __m256, inverse: __m256) -> __m256 {
    _mm256_mul_ps(
        _mm256_sub_ps(_mm256_set1_ps(node.bounds[row][slot]), origin),
        inverse,
    )
}

/// The smallest of the lanes of `v` selected by `lanes`.
#[inline(always)]
unsafe fn least(v: __m256, lanes: __m256) -> f32 {
    horizontal_min(_mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), v, lanes))
}

/// The largest of the lanes of `v` selected by `lanes`.
#[inline(always)]
unsafe fn most(v: __m256, lanes: __m256) -> f32 {
    horizontal_max(_mm256_blendv_ps(_mm256_set1_ps(f32::NEG_INFINITY), v, lanes))
}

/// The largest of the eight lanes.
#[inline(always)]
unsafe fn horizontal_max(v: __m256) -> f32 {
    let m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
    let m = _mm_max_ps(m, _mm_movehl_ps(m, m));
    let m = _mm_max_ss(m, _mm_shuffle_ps::<0b01>(m, m));
    _mm_cvtss_f32(m)
}

/// The smallest of the eight lanes.
#[inline(always)]
unsafe fn horizontal_min(v: __m256) -> f32 {
    let m = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
    let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
    let m = _mm_min_ss(m, _mm_shuffle_ps::<0b01>(m, m));
    _mm_cvtss_f32(m)
}

/// One packet through the wide BVH: the packet descends while its lanes agree, splits into
/// single-ray searches where they part, and records each lane's nearest hit. One function of
/// ~170 lines on purpose: it is one loop whose node, leaf and stack steps share the lanes'
/// masks and both stacks, and the hot loop whose figures docs/engine.md gives; helpers would
/// have to take all of that state and be `inline(always)` to cost nothing.
#[inline(always)]
unsafe fn traverse<C: Counter>(
    bvh: &WideBvh,
    (rays, lanes): (&[RayData], PacketLanes),
    searches: &mut [Search],
    packet_stack: &mut [MaybeUninit<PacketEntry>],
    stack: &mut [MaybeUninit<Entry>],
    counter: &mut C,
) {
    let n = rays.len();
    debug_assert!((1..=PACKET).contains(&n) && searches.len() == n);
    // Lane r holds ray r; spare lanes repeat the last ray and are never active.
    let PacketLanes {
        origin,
        inverse,
        negative,
        ..
    } = lanes;
    let zero = _mm256_setzero_ps();
    let far_scale = _mm256_set1_ps(FAR_SCALE);
    let mut best = [f32::NEG_INFINITY; PACKET];
    for r in 0..n {
        best[r] = searches[r].best_t;
    }
    // A ray with a NaN or infinite component meets nothing (as in `Accel::trace`): the lanes
    // of [`RayData::is_finite`].
    let all = finite_lanes(origin, inverse) & ((1u32 << n) - 1);
    let bounds = PacketBounds::new(origin, inverse, negative, all);
    let coherent = bounds.as_ref().is_some_and(|b| b.spread() <= SPREAD);
    let mut top = 0usize;
    let (mut reference, mut active) = (0u32, all);
    if active == 0 {
        return;
    }
    // Rays that leave one point along one dominant axis (a gather point's rays, nearly
    // always) share the first step of every leaf test: the corners translated to the origin.
    let first = &rays[all.trailing_zeros() as usize];
    let shared = one_origin_and_axis(lanes, all);
    'visit: loop {
        if reference & LEAF != 0 && shared {
            let block = reference & !LEAF;
            let corners = translated(&bvh.blocks[block as usize], first);
            let mut m = active;
            while m != 0 {
                let r = m.trailing_zeros() as usize;
                m &= m - 1;
                counter.block();
                let search = &mut searches[r];
                let hits = block_translated(corners, &rays[r], search.leaf_limit());
                search.take(bvh, block, hits);
                best[r] = search.best_t;
            }
        } else if reference & LEAF != 0 || active.count_ones() < SINGLE_BELOW {
            // A leaf (tested ray by ray) or a subtree left to few rays: one ray at a time.
            let mut m = active;
            while m != 0 {
                let r = m.trailing_zeros() as usize;
                m &= m - 1;
                descend::<Avx2, C>(bvh, &rays[r], &mut searches[r], reference, stack, counter);
                best[r] = searches[r].best_t;
            }
        } else {
            counter.packet_node();
            let node = &bvh.nodes[reference as usize];
            let best_t = _mm256_loadu_ps(best.as_ptr());
            let active_lanes = lane_mask(active);
            let mut met = [Met {
                key: 0.0,
                slot: 0,
                rays: 0,
            }; WIDTH];
            let mut near_of = [zero; WIDTH];
            let mut count = 0;
            let (mut candidates, interval_near) = match &bounds {
                Some(b) => b.children_met(node, horizontal_max(best_t)),
                None => (occupied(node), [0.0; WIDTH]),
            };
            while candidates != 0 {
                let slot = candidates.trailing_zeros() as usize;
                candidates &= candidates - 1;
                let (key, rays_met, near) = if coherent && node.child[slot] & LEAF == 0 {
                    // A coherent packet's inner child: every active ray, at the smallest
                    // possible near distance (see the module docs).
                    let key = interval_near[slot];
                    (key, active, _mm256_set1_ps(key))
                } else {
                    let (lo_x, hi_x) = (
                        slab(node, 0, slot, origin[0], inverse[0]),
                        slab(node, 3, slot, origin[0], inverse[0]),
                    );
                    let (lo_y, hi_y) = (
                        slab(node, 1, slot, origin[1], inverse[1]),
                        slab(node, 4, slot, origin[1], inverse[1]),
                    );
                    let (lo_z, hi_z) = (
                        slab(node, 2, slot, origin[2], inverse[2]),
                        slab(node, 5, slot, origin[2], inverse[2]),
                    );
                    let near_x = _mm256_blendv_ps(lo_x, hi_x, negative[0]);
                    let near_y = _mm256_blendv_ps(lo_y, hi_y, negative[1]);
                    let near_z = _mm256_blendv_ps(lo_z, hi_z, negative[2]);
                    let far_x = _mm256_blendv_ps(hi_x, lo_x, negative[0]);
                    let far_y = _mm256_blendv_ps(hi_y, lo_y, negative[1]);
                    let far_z = _mm256_blendv_ps(hi_z, lo_z, negative[2]);
                    // The single-ray kernel's expressions, operand for operand.
                    let t_near = _mm256_max_ps(_mm256_max_ps(near_x, near_y), _mm256_max_ps(near_z, zero));
                    let t_far = _mm256_mul_ps(
                        _mm256_min_ps(_mm256_min_ps(far_x, far_y), _mm256_min_ps(far_z, best_t)),
                        far_scale,
                    );
                    let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far);
                    let rays_met = _mm256_movemask_ps(hit) as u32 & active;
                    if rays_met == 0 {
                        continue;
                    }
                    let key = horizontal_min(_mm256_blendv_ps(
                        _mm256_set1_ps(f32::INFINITY),
                        t_near,
                        _mm256_and_ps(hit, active_lanes),
                    ));
                    (key, rays_met, t_near)
                };
                // Insertion sort by key (stable, at most eight).
                let mut i = count;
                while i > 0 && met[i - 1].key > key {
                    met[i] = met[i - 1];
                    i -= 1;
                }
                met[i] = Met {
                    key,
                    slot,
                    rays: rays_met,
                };
                near_of[slot] = near;
                count += 1;
            }
            if count > 0 {
                // Push all but the nearest, farthest first.
                for m in met[1..count].iter().rev() {
                    let mut entry = PacketEntry {
                        near: [0.0; PACKET],
                        reference: node.child[m.slot],
                        rays: m.rays,
                    };
                    _mm256_storeu_ps(entry.near.as_mut_ptr(), near_of[m.slot]);
                    packet_stack[top] = MaybeUninit::new(entry);
                    top += 1;
                }
                reference = node.child[met[0].slot];
                active = met[0].rays;
                continue 'visit;
            }
        }
        // Pop the nearest entry that some ray still needs.
        loop {
            if top == 0 {
                return;
            }
            top -= 1;
            // SAFETY: entries below `top` were written above.
            let entry = packet_stack[top].assume_init_ref();
            let limit = _mm256_mul_ps(_mm256_loadu_ps(best.as_ptr()), far_scale);
            let near = _mm256_loadu_ps(entry.near.as_ptr());
            let still = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, limit)) as u32 & entry.rays;
            if still != 0 {
                reference = entry.reference;
                active = still;
                continue 'visit;
            }
        }
    }
}

/// Bit per lane: [`RayData::is_finite`] of the lane's ray (a finite origin, and reciprocal
/// directions that are finite and not zero).
#[inline(always)]
unsafe fn finite_lanes(origin: [__m256; 3], inverse: [__m256; 3]) -> u32 {
    let mut lanes = _mm256_and_ps(
        finite(origin[0]),
        _mm256_and_ps(finite(origin[1]), finite(origin[2])),
    );
    for v in inverse {
        let nonzero = _mm256_cmp_ps::<_CMP_NEQ_OQ>(v, _mm256_setzero_ps());
        lanes = _mm256_and_ps(lanes, _mm256_and_ps(finite(v), nonzero));
    }
    _mm256_movemask_ps(lanes) as u32
}

/// Whether the rays of `lanes` (bit per lane, at least one) leave one point (the same bits)
/// along one dominant axis (the watertight test's `kz`).
#[inline(always)]
unsafe fn one_origin_and_axis(packet: PacketLanes, lanes: u32) -> bool {
    let uniform = |bits: u32| bits & lanes == 0 || bits & lanes == lanes;
    let first_lane = _mm256_set1_epi32(lanes.trailing_zeros() as i32);
    let mut same = _mm256_setzero_si256();
    for o in packet.origin {
        let o = _mm256_castps_si256(o);
        let first = _mm256_permutevar8x32_epi32(o, first_lane);
        same = _mm256_or_si256(same, _mm256_xor_si256(o, first));
    }
    let equal = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
        same,
        _mm256_setzero_si256(),
    ))) as u32;
    equal & lanes == lanes && uniform(packet.z_wins) && (packet.z_wins & lanes != 0 || uniform(packet.y_wins))
}

/// All bits set in the lanes whose value is finite (not NaN, not infinite).
#[inline(always)]
unsafe fn finite(v: __m256) -> __m256 {
    let magnitude = _mm256_and_ps(v, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff)));
    _mm256_cmp_ps::<_CMP_LT_OQ>(magnitude, _mm256_set1_ps(f32::INFINITY))
}

/// All bits set in the lanes named by `bits`, for blends.
#[inline(always)]
unsafe fn lane_mask(bits: u32) -> __m256 {
    let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let selected = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane_bits);
    _mm256_castsi256_ps(_mm256_cmpeq_epi32(selected, lane_bits))
}

/// The packet as a whole, for a first test of a node's eight children at once (interval
/// arithmetic, Boulos et al. 2006 "Geometric and arithmetic culling methods for entire ray
/// packets"): per axis the range of the rays' origins and of their reciprocal directions,
/// which must all have one sign. A child whose box no ray of the packet can meet is skipped
/// without testing the rays one by one.
///
/// Why it never skips a child that a ray meets: a ray's slab distance is
/// `fl(fl(b − o)·(1/d))`, and rounding is monotonic, so it lies between the rounded products
/// of the ends of the ranges of `b − o` and `1/d`; the near distance (a max) and the far
/// distance (a min, scaled) are monotonic too. So the packet's smallest possible near
/// distance is at most each ray's, its largest possible far distance at least each ray's, and
/// "smallest near > largest far" means every ray misses.
struct PacketBounds {
    /// Per axis, the bounds row of the near plane (min for positive directions, max for
    /// negative ones) and of the far plane.
    near_row: [usize; 3],
    far_row: [usize; 3],
    /// Per axis, the origin coordinate that makes `b − o` smallest on the near plane's side
    /// (largest origin for positive directions) and largest on the far side.
    near_origin: [f32; 3],
    far_origin: [f32; 3],
    /// Per axis, the smallest and largest reciprocal direction.
    inverse: [[f32; 2]; 3],
}

impl PacketBounds {
    /// `None` where the rays' directions differ in sign on some axis (the ranges would
    /// straddle zero and prove nothing). Lanes: the packet's rays; `rays`: the finite ones.
    #[inline(always)]
    unsafe fn new(
        origin: [__m256; 3],
        inverse: [__m256; 3],
        negative: [__m256; 3],
        rays: u32,
    ) -> Option<Self> {
        let lanes = lane_mask(rays);
        let mut bounds = PacketBounds {
            near_row: [0; 3],
            far_row: [0; 3],
            near_origin: [0.0; 3],
            far_origin: [0.0; 3],
            inverse: [[0.0; 2]; 3],
        };
        for axis in 0..3 {
            let signs = _mm256_movemask_ps(negative[axis]) as u32 & rays;
            if signs != 0 && signs != rays {
                return None;
            }
            let negative = signs != 0;
            let (o_lo, o_hi) = (least(origin[axis], lanes), most(origin[axis], lanes));
            bounds.near_row[axis] = axis + 3 * negative as usize;
            bounds.far_row[axis] = axis + 3 * !negative as usize;
            // Positive: near = (min − o)/d is smallest for the largest o; far = (max − o)/d
            // largest for the smallest o. Negative directions: the other way round.
            (bounds.near_origin[axis], bounds.far_origin[axis]) =
                if negative { (o_lo, o_hi) } else { (o_hi, o_lo) };
            bounds.inverse[axis] = [least(inverse[axis], lanes), most(inverse[axis], lanes)];
        }
        Some(bounds)
    }

    /// The largest difference of the rays' directions on any axis (from the reciprocal
    /// directions' range: a heuristic, which changes no hit).
    #[inline(always)]
    fn spread(&self) -> f32 {
        let mut spread = 0.0f32;
        for [a, b] in self.inverse {
            spread = spread.max((1.0 / a - 1.0 / b).abs());
        }
        spread
    }

    /// The smallest near and largest far slab distances of the eight children on `axis`.
    #[inline(always)]
    unsafe fn axis_range(&self, node: &Node, axis: usize) -> (__m256, __m256) {
        let a = _mm256_set1_ps(self.inverse[axis][0]);
        let b = _mm256_set1_ps(self.inverse[axis][1]);
        let near = _mm256_sub_ps(
            _mm256_load_ps(node.bounds[self.near_row[axis]].as_ptr()),
            _mm256_set1_ps(self.near_origin[axis]),
        );
        let far = _mm256_sub_ps(
            _mm256_load_ps(node.bounds[self.far_row[axis]].as_ptr()),
            _mm256_set1_ps(self.far_origin[axis]),
        );
        (
            _mm256_min_ps(_mm256_mul_ps(near, a), _mm256_mul_ps(near, b)),
            _mm256_max_ps(_mm256_mul_ps(far, a), _mm256_mul_ps(far, b)),
        )
    }

    /// The children (bit per slot) that some ray of the packet may meet before `t_max`.
    #[inline(always)]
    unsafe fn children_met(&self, node: &Node, t_max: f32) -> (u32, [f32; WIDTH]) {
        let (near_x, far_x) = self.axis_range(node, 0);
        let (near_y, far_y) = self.axis_range(node, 1);
        let (near_z, far_z) = self.axis_range(node, 2);
        let t_near = _mm256_max_ps(
            _mm256_max_ps(near_x, near_y),
            _mm256_max_ps(near_z, _mm256_setzero_ps()),
        );
        let t_far = _mm256_mul_ps(
            _mm256_min_ps(
                _mm256_min_ps(far_x, far_y),
                _mm256_min_ps(far_z, _mm256_set1_ps(t_max)),
            ),
            _mm256_set1_ps(FAR_SCALE),
        );
        let mut near = [0.0; WIDTH];
        _mm256_storeu_ps(near.as_mut_ptr(), t_near);
        (
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far)) as u32,
            near,
        )
    }
}
