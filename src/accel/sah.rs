//! A binned SAH builder for the binary BVH that [`super::wide`] collapses (Wald 2007, "On
//! fast Construction of SAH-based Bounding Volume Hierarchies"), parallel over subtrees.
//!
//! Why our own: obvhs's best preset (`very_slow_build`: PLOC, spatial splits, whole-tree
//! reinsertion) traces fastest but builds `hall` (608 K triangles) in 2.6 s, where Embree's
//! high-quality build takes 0.1–0.3 s; its fast preset builds in 0.3 s but traces `hall` 7×
//! slower (PLOC's top levels suffer from large wall triangles). Top-down binned SAH traces
//! nearly as fast in about a tenth of the build time (`hall`: 0.15 s on 2 cores); see
//! `cargo bench --bench gather`. obvhs's spatial pre-splits of large triangles can be added
//! (`pre_split`); on `cube` and `hall` they did not pay, so the `fast` preset leaves them out.
//!
//! The tree is the same for any thread count: each node's references are partitioned in
//! place by the same rule, and a subtree's nodes go to a range of the node array fixed by its
//! position, not by which thread built it.
//!
//! Build timings, where the `high` tree traces faster, and what was tried on this tree to
//! close the gap and not kept: `docs/engine.md`.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;
use obvhs::splits::split_aabbs_preset;
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use super::slots::{self, SlotCosts};
use super::WIDTH;
use crate::scene::Mesh;

/// Most bins per axis; a node of `n` references uses [`bins_for`]`(n)` of them.
const BINS: usize = 32;
/// Most triangles in a leaf: one block of the wide BVH.
const MAX_LEAF: usize = super::WIDTH;
/// Cost of a node visit against one triangle test in the SAH. A leaf block of up to eight
/// triangles costs one kernel call however full it is, so leaves are kept rather full.
const TRAVERSAL_COST: f32 = 4.0;
/// Subtrees at least this large are built on another thread.
const PARALLEL_REFERENCES: usize = 4096;

/// One reference in 32 bytes (every level of the build streams them all): a box (of a whole
/// triangle, or of a piece of a large one) with its triangle's index in `min.w`.
#[derive(Clone, Copy)]
struct Reference {
    min: Vec4,
    max: Vec4,
}

impl Reference {
    fn new(bounds: Aabb, triangle: u32) -> Self {
        Reference {
            min: bounds.min.extend(f32::from_bits(triangle)),
            max: bounds.max.extend(0.0),
        }
    }

    fn triangle(&self) -> u32 {
        self.min.w.to_bits()
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.min.truncate().into(), self.max.truncate().into())
    }

    /// Twice the centroid (no halving: only compared and binned).
    fn centroid2(&self) -> Vec3A {
        (self.min + self.max).truncate().into()
    }
}

/// Builds the binary BVH of `mesh`'s triangles, with spatial pre-splits where `pre_split`,
/// and each node's collapse costs ([`slots`]), by node index, computed as its subtree is built.
pub fn build(mesh: &Mesh, pre_split: bool) -> (Bvh2, Vec<SlotCosts>) {
    let mut references: Vec<Reference> = if pre_split && mesh.triangle_count() > 0 {
        let triangles = obvhs_triangles(mesh);
        let mut boxes: Vec<Aabb> = triangles.iter().map(|t| t.aabb()).collect();
        let mut indices: Vec<u32> = (0..triangles.len() as u32).collect();
        let areas = boxes.iter().map(|b| b.half_area());
        let largest = areas.clone().fold(0.0f32, f32::max);
        let average = areas.sum::<f32>() / boxes.len() as f32;
        split_aabbs_preset(&mut boxes, &mut indices, &triangles, average, largest);
        boxes
            .iter()
            .zip(&indices)
            .map(|(&bounds, &triangle)| Reference::new(bounds, triangle))
            .collect()
    } else {
        // The box of the corners, as obvhs's `Triangle::aabb` makes it.
        (0..mesh.triangle_count())
            .into_par_iter()
            .map(|i| {
                let corners = mesh.triangle(i).map(Vec3A::from);
                Reference::new(Aabb::from_points(&corners), i as u32)
            })
            .collect()
    };
    let n = references.len().max(1);
    // Zeroed by the allocator: the pages of the slots a leafy tree never uses (most of them,
    // at the end of each subtree's range: see `subtree`) are never touched.
    let mut nodes: Vec<Bvh2Node> = bytemuck::zeroed_vec(2 * n - 1);
    // Zeroed like the nodes, so the pages of the slots never used are never touched.
    let mut costs: Vec<SlotCosts> = bytemuck::zeroed_vec(2 * n - 1);
    if !references.is_empty() {
        let extent = Extent::of(&references);
        let (root, below) = nodes.split_at_mut(1);
        let (root_costs, below_costs) = costs.split_at_mut(1);
        subtree(
            &mut references,
            extent,
            0,
            Slot(&mut root[0], &mut root_costs[0]),
            Below(below, below_costs),
            1,
        );
    }
    let bvh = Bvh2 {
        nodes,
        primitive_indices: references.par_iter().map(|r| r.triangle()).collect(),
        ..Bvh2::default()
    };
    (bvh, costs)
}

/// A node's place in the node array and in the costs array.
struct Slot<'a>(&'a mut Bvh2Node, &'a mut SlotCosts);

/// The places of a subtree's descendants in both arrays.
struct Below<'a>(&'a mut [Bvh2Node], &'a mut [SlotCosts]);

impl<'a> Below<'a> {
    fn split_at(self, at: usize) -> (Below<'a>, Below<'a>) {
        let (nodes_a, nodes_b) = self.0.split_at_mut(at);
        let (costs_a, costs_b) = self.1.split_at_mut(at);
        (Below(nodes_a, costs_a), Below(nodes_b, costs_b))
    }

    fn reborrow(&mut self) -> Below<'_> {
        Below(&mut *self.0, &mut *self.1)
    }

    fn first(self) -> Slot<'a> {
        Slot(&mut self.0[0], &mut self.1[0])
    }
}

/// The mesh's triangles as obvhs takes them (for its builders and spatial splits).
pub(super) fn obvhs_triangles(mesh: &Mesh) -> Vec<Triangle> {
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|i| {
            let [v0, v1, v2] = mesh.triangle(i).map(Vec3A::from);
            Triangle { v0, v1, v2 }
        })
        .collect()
}

/// The box of a set of references and the box of their (doubled) centroids.
#[derive(Clone, Copy)]
struct Extent {
    bounds: Aabb,
    centroids: Aabb,
}

impl Extent {
    const EMPTY: Extent = Extent {
        bounds: Aabb::INVALID,
        centroids: Aabb::INVALID,
    };

    fn of(references: &[Reference]) -> Extent {
        references.iter().fold(Extent::EMPTY, |e, r| e.with(r))
    }

    #[inline(always)]
    fn with(mut self, r: &Reference) -> Extent {
        self.bounds = self.bounds.union(&r.bounds());
        self.centroids.extend(r.centroid2());
        self
    }
}

/// Builds the subtree of `references` (which start at `offset` in the final reference order,
/// and span `extent`) into `slot`, its descendants into `below`, whose first slot has index
/// `base` in the node array; returns its node's collapse costs (also left in `slot`) and how
/// many slots of `below` it used. `below` holds at least `2·len − 2` slots: a binary tree over
/// `len` references needs no more. Subtrees built on one thread take their slots one after
/// the other from the front of `below`; subtrees built in parallel each take a range of fixed
/// size, so the layout is the same for any thread count, and the slots a subtree never uses
/// lie together at the end of its range, in pages that are never touched. (With a fixed range
/// for every subtree the few used slots of each small range were spread over all of the
/// array's `2n − 1` slots, and the pages of both arrays, 670 MB on the 5.2 M-triangle sphere,
/// were all touched: its whole build took 1.8–1.9 s instead of 1.2–1.4 s, 2 threads.)
fn subtree(
    references: &mut [Reference],
    extent: Extent,
    offset: usize,
    slot: Slot,
    below: Below,
    base: usize,
) -> (SlotCosts, usize) {
    let Some(split) = best_split(references, extent) else {
        *slot.0 = Bvh2Node::new(extent.bounds, references.len() as u32, offset as u32);
        *slot.1 = [0.0; WIDTH];
        return (*slot.1, 0);
    };
    let left_len = split.left_len;
    *slot.0 = Bvh2Node::new(extent.bounds, 0, base as u32);
    let (children, mut rest) = below.split_at(2);
    let (left_child, right_child) = children.split_at(1);
    let (left, right) = references.split_at_mut(left_len);
    let right_len = right.len();
    let left_job = |below: Below| subtree(left, split.left, offset, left_child.first(), below, base + 2);
    // The right subtree's slots start `skip` slots after the left's.
    let right_job = |below: Below, skip: usize| {
        let right_base = base + 2 + skip;
        subtree(
            right,
            split.right,
            offset + left_len,
            right_child.first(),
            below,
            right_base,
        )
    };
    let (left_costs, right_costs, used) = if left_len.min(right_len) >= PARALLEL_REFERENCES {
        let reserved = 2 * left_len - 2;
        let (left_below, right_below) = rest.split_at(reserved);
        let ((left_costs, _), (right_costs, right_used)) =
            rayon::join(|| left_job(left_below), || right_job(right_below, reserved));
        (left_costs, right_costs, 2 + reserved + right_used)
    } else {
        let (left_costs, left_used) = left_job(rest.reborrow());
        let (_, right_below) = rest.split_at(left_used);
        let (right_costs, right_used) = right_job(right_below, left_used);
        (left_costs, right_costs, 2 + left_used + right_used)
    };
    *slot.1 = slots::inner(extent.bounds.half_area(), &left_costs, &right_costs);
    (*slot.1, used)
}

/// A chosen split: how many references go left (they are moved to the front) and the extent
/// of each side.
struct Split {
    left_len: usize,
    left: Extent,
    right: Extent,
}

/// Partitions `references` by the cheapest binned SAH split, or returns `None` when a leaf
/// is cheaper (or the references cannot be told apart and fit in one). One pass bins the
/// references on all three axes at once; each bin keeps the box of its references, so the
/// children's boxes come from the bins, and the partition gathers their centroids' boxes (bins
/// that kept those too made the whole build of the 5.2 M-triangle sphere 2.60 s instead of
/// 2.34 s: medians of 5 interleaved runs, 2 threads).
fn best_split(references: &mut [Reference], extent: Extent) -> Option<Split> {
    let n = references.len();
    if n <= 1 {
        return None;
    }
    let centroids = extent.centroids;
    let size = centroids.diagonal();
    let used = bins_for(n);
    let scale = Vec3A::select(size.cmpgt(Vec3A::ZERO), used as f32 / size, Vec3A::ZERO);
    let mut counts = [[0usize; BINS]; 3];
    let mut bins = [[Aabb::INVALID; BINS]; 3];
    let last = Vec3A::splat((used - 1) as f32);
    for r in references.iter() {
        let bin = bins_of(r.centroid2(), centroids.min, scale, last);
        let bounds = r.bounds();
        for axis in 0..3 {
            let b = bin[axis];
            counts[axis][b] += 1;
            bins[axis][b] = bins[axis][b].union(&bounds);
        }
    }
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, first bin on the right)
    for axis in (0..3).filter(|&axis| size[axis] > 0.0) {
        // Sweep from the right for the right-hand areas, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut right_box, mut count) = (Aabb::INVALID, 0);
        for b in (1..used).rev() {
            right_box = right_box.union(&bins[axis][b]);
            count += counts[axis][b];
            right_area[b] = if count > 0 { right_box.half_area() } else { 0.0 };
            right_count[b] = count;
        }
        let (mut left_box, mut left_count) = (Aabb::INVALID, 0);
        for b in 1..used {
            left_box = left_box.union(&bins[axis][b - 1]);
            left_count += counts[axis][b - 1];
            if left_count == 0 || right_count[b] == 0 {
                continue;
            }
            let cost = left_box.half_area() * left_count as f32 + right_area[b] * right_count[b] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let area = extent.bounds.half_area().max(f32::MIN_POSITIVE);
    let Some((cost, axis, first_right)) = best else {
        // All centroids coincide: a leaf if it fits, else halves by count.
        if n <= MAX_LEAF {
            return None;
        }
        let (left, right) = references.split_at(n / 2);
        return Some(Split {
            left_len: n / 2,
            left: Extent::of(left),
            right: Extent::of(right),
        });
    };
    if n <= MAX_LEAF && (n as f32) <= TRAVERSAL_COST + cost / area {
        return None;
    }
    let (min, scale) = (centroids.min[axis], scale[axis]);
    // The binning's rule, without the conversion: for an integer k, floor(x) < k ⟺ x < k,
    // and a position clamped to the last bin (or NaN) is on the right either way.
    let first_right_at = first_right as f32;
    let (left_len, [left_centroids, right_centroids]) = partition(references, |r| {
        (r.centroid2()[axis] - min) * scale < first_right_at
    });
    let side =
        |range: std::ops::Range<usize>| bins[axis][range].iter().fold(Aabb::INVALID, |e, b| e.union(b));
    Some(Split {
        left_len,
        left: Extent {
            bounds: side(0..first_right),
            centroids: left_centroids,
        },
        right: Extent {
            bounds: side(first_right..used),
            centroids: right_centroids,
        },
    })
}

/// Bins per axis for a node of `n` references: Embree's rule (`4 + n/20`, at most
/// [`BINS`]), so the sweep over the bins, the same work for 8 references as for 8 million,
/// does not dominate the million small nodes near the leaves. On the 5.2 M-triangle sphere
/// the binary build took 1.0 s instead of 1.5 s (2 threads); tracing `cube`, `hall` and the
/// sphere did not change measurably (`gather_rays cast`, medians of 5 and 3 interleaved runs).
fn bins_for(n: usize) -> usize {
    BINS.min(4 + n / 20)
}

/// The bin of centroid `c` on each axis: `(c − min)·scale` rounded down, at most `last` (a
/// NaN from a degenerate extent goes to the last bin too), converted four lanes at once.
#[inline(always)]
fn bins_of(c: Vec3A, min: Vec3A, scale: Vec3A, last: Vec3A) -> [usize; 3] {
    // `min` takes its second operand where the first is NaN, as `minps` does.
    let position = ((c - min) * scale).min(last);
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of x86-64; the lanes hold values in [0, last].
        let lanes: [i32; 4] =
            unsafe { std::mem::transmute::<__m128i, _>(_mm_cvttps_epi32(__m128::from(position))) };
        [lanes[0] as usize, lanes[1] as usize, lanes[2] as usize]
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        position.as_uvec3().to_array().map(|b| b as usize)
    }
}

/// Moves the references for which `left` holds to the front (order otherwise deterministic)
/// and returns how many there are, with the box of each side's (doubled) centroids, gathered
/// on the way (each reference is looked at once), so the bins need hold only boxes.
fn partition(references: &mut [Reference], left: impl Fn(&Reference) -> bool) -> (usize, [Aabb; 2]) {
    let mut centroids = [Aabb::INVALID; 2];
    let mut i = 0;
    let mut j = references.len();
    while i < j {
        let r = &references[i];
        if left(r) {
            centroids[0].extend(r.centroid2());
            i += 1;
        } else {
            centroids[1].extend(r.centroid2());
            j -= 1;
            references.swap(i, j);
        }
    }
    (i, centroids)
}
