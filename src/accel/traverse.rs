//! Closest-hit traversal of the wide BVH, generic over the kernel ([`Lanes`]).
//!
//! One ray at a time, children visited nearest first: a node's hit children are sorted by
//! their near distance (stable, so ties keep slot order), the nearest is taken next and the
//! others go on a stack with their distance, to be skipped when popped if a hit closer than
//! them has been found since. Everything outside the two kernel calls is shared by all
//! kernels, so all of them visit the same nodes in the same order and return the same hit.
//!
//! Every hit child is prefetched as soon as the node test names it, before the sort: the
//! sort and the pushes then overlap the wait for the next node or block, whose address the
//! load would otherwise learn only after them. That wait, along node → mask → next node →
//! block → `t`, is most of a ray's time: work added on the chain costs in full, and a cheaper
//! test pays only by shortening it.
//!
//! Hits within their own `t` error bound (see [`super::triangle`]) are kept aside and taken
//! only if the ray finds nothing else, and only where `accept_within_error` allows (see
//! [`super::Accel`]).
//!
//! **The answer does not depend on the order of the visit.** Among hits at the same `t` (a ray
//! through an edge that two triangles share, or two coincident triangles) the lowest triangle
//! index wins, and nothing that could hold such a tie is skipped: a node or stack entry is
//! culled only when its near distance is *strictly* greater than the best `t` (widened by the
//! box test's own rounding), and a leaf block is tested against the best `t` widened by
//! [`FAR_SCALE`], so a triangle whose `t` rounds to the best one is never lost to the rounding
//! of the test's `t·det` comparison; the exact comparison is then made on the `t` values.
//! So every traversal order (this one, a packet's, another BVH preset's) returns the same
//! `(t, triangle)`.
//!
//! A hit's triangle index (`block_triangles`, another array than the block) is read only to
//! break a tie of `t` and by callers that need it, not at every hit: a distance-only gather
//! never reads it, and in a large scene that read is a cache miss per hit.
//!
//! The design, where a ray's time goes, and the dead ends measured and not kept (other visit
//! orders, seeding `t`, a branch-free sort, smaller leaves): `docs/engine.md`.

use std::mem::MaybeUninit;

use super::kernel::{BlockHits, Lanes, RayData, FAR_SCALE};
use super::wide::{Block, WideBvh, EMPTY, LEAF, WIDTH};

/// A traversal stack entry: a child reference and its near distance.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Entry {
    reference: u32,
    near: f32,
}

/// Stack entries a tree of `depth` node levels can need: each level leaves at most seven
/// siblings behind.
pub(crate) fn stack_size(depth: usize) -> usize {
    (WIDTH - 1) * depth + 1
}

/// The closest hit: leaf block, lane and distance (the triangle's index in the mesh is
/// `bvh.block_triangles[block][lane]`, read only where needed: in a large scene that array is
/// one more cache miss per hit).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Closest {
    pub block: u32,
    pub lane: usize,
    pub t: f32,
}

impl Closest {
    /// Whether a hit at `t` in `block`'s `lane` beats this one: nearer, or as near with a
    /// lower triangle index (the rule that makes the answer independent of the visit order).
    #[inline(always)]
    fn beaten_by(&self, bvh: &WideBvh, t: f32, block: u32, lane: usize) -> bool {
        t < self.t
            || (t == self.t
                && bvh.block_triangles[block as usize][lane]
                    < bvh.block_triangles[self.block as usize][self.lane])
    }
}

/// Counts traversal steps (for the benchmark's nodes and triangles per ray); the no-op
/// implementation on `()` compiles away.
pub trait Counter {
    fn node(&mut self) {}
    fn block(&mut self) {}
    /// A node visited by a packet (its children tested against all the packet's rays).
    fn packet_node(&mut self) {}
}

impl Counter for () {}

/// Nodes and leaf blocks visited.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraversalStats {
    /// Wide nodes whose eight children were box-tested.
    pub nodes: u64,
    /// Leaf blocks whose eight triangles were tested.
    pub blocks: u64,
    /// Wide nodes visited by a packet of rays (not counted in `nodes`).
    pub packet_nodes: u64,
}

impl Counter for TraversalStats {
    fn node(&mut self) {
        self.nodes += 1;
    }
    fn block(&mut self) {
        self.blocks += 1;
    }
    fn packet_node(&mut self) {
        self.packet_nodes += 1;
    }
}

/// One ray's best hits so far.
pub(crate) struct Search<'a> {
    best: Option<Closest>,
    /// The best hit's `t`, or `t_max` while there is none.
    pub best_t: f32,
    t_max: f32,
    within_error: Option<Closest>,
    accept_within_error: &'a dyn Fn(u32, usize) -> bool,
}

impl<'a> Search<'a> {
    /// A search for the first hit at `0 < t < t_max`.
    #[inline(always)]
    pub fn new(t_max: f32, accept_within_error: &'a dyn Fn(u32, usize) -> bool) -> Self {
        Search {
            best: None,
            best_t: t_max,
            t_max,
            within_error: None,
            accept_within_error,
        }
    }

    /// The answer: the closest hit, else the closest acceptable hit within its error bound.
    #[inline(always)]
    pub fn result(&self) -> Option<Closest> {
        self.best.or(self.within_error)
    }

    /// Tests the leaf block `reference` (with its [`LEAF`] bit).
    #[inline(always)]
    pub fn leaf<K: Lanes, C: Counter>(
        &mut self,
        bvh: &WideBvh,
        ray: &RayData,
        reference: u32,
        counter: &mut C,
    ) {
        let block = reference & !LEAF;
        counter.block();
        let hits = K::block(&bvh.blocks[block as usize], ray, self.leaf_limit());
        self.take(bvh, block, hits);
    }

    /// The `t_max` of a leaf block test: the best `t`, widened so that a hit whose `t`
    /// equals it reaches the exact comparison of [`Search::take`].
    #[inline(always)]
    pub fn leaf_limit(&self) -> f32 {
        self.best_t * FAR_SCALE
    }

    /// Keeps what the test of leaf block `block` (its index) found, if it beats the best.
    #[inline(always)]
    pub fn take(&mut self, bvh: &WideBvh, block: u32, hits: BlockHits) {
        let mut solid = hits.hit & !hits.within_error;
        while solid != 0 {
            let lane = solid.trailing_zeros() as usize;
            solid &= solid - 1;
            let t = hits.t[lane];
            if t > self.best_t {
                continue;
            }
            let better = match self.best {
                Some(best) => best.beaten_by(bvh, t, block, lane),
                None => t < self.t_max,
            };
            if better {
                self.best_t = t;
                self.best = Some(Closest { block, lane, t });
            }
        }
        let mut doubtful = hits.within_error;
        while doubtful != 0 {
            let lane = doubtful.trailing_zeros() as usize;
            doubtful &= doubtful - 1;
            let t = hits.t[lane];
            if t >= self.t_max {
                continue;
            }
            if self.within_error.is_none_or(|w| w.beaten_by(bvh, t, block, lane))
                && (self.accept_within_error)(block, lane)
            {
                self.within_error = Some(Closest { block, lane, t });
            }
        }
    }
}

/// The first hit at `0 < t < t_max`; see the module docs. `stack` must hold
/// [`stack_size`]`(bvh.depth)` entries.
#[inline(always)]
pub(crate) fn closest<K: Lanes, C: Counter>(
    bvh: &WideBvh,
    ray: &RayData,
    t_max: f32,
    accept_within_error: &dyn Fn(u32, usize) -> bool,
    stack: &mut [MaybeUninit<Entry>],
    counter: &mut C,
) -> Option<Closest> {
    let mut search = Search::new(t_max, accept_within_error);
    descend::<K, C>(bvh, ray, &mut search, 0, stack, counter);
    search.result()
}

/// Visits the subtree at `root` (a node index, or a leaf block with its [`LEAF`] bit) for one
/// ray, nearest child first, adding what it finds to `search`.
#[inline(always)]
pub(crate) fn descend<K: Lanes, C: Counter>(
    bvh: &WideBvh,
    ray: &RayData,
    search: &mut Search,
    root: u32,
    stack: &mut [MaybeUninit<Entry>],
    counter: &mut C,
) {
    if root & LEAF != 0 {
        search.leaf::<K, C>(bvh, ray, root, counter);
        return;
    }
    let mut top = 0usize;
    let mut node = root;
    loop {
        counter.node();
        let (mut mask, near) = K::node(&bvh.nodes[node as usize], ray, search.best_t);
        let children = &bvh.nodes[node as usize].child;
        // The hit children, nearest first (insertion sort: stable, at most eight).
        let mut order = [Entry::default(); WIDTH];
        let mut count = 0;
        while mask != 0 {
            let slot = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let entry = Entry {
                reference: children[slot],
                near: near[slot],
            };
            prefetch(bvh, entry.reference);
            let mut i = count;
            while i > 0 && order[i - 1].near > entry.near {
                order[i] = order[i - 1];
                i -= 1;
            }
            order[i] = entry;
            count += 1;
        }
        debug_assert!(order[..count].iter().all(|e| e.reference != EMPTY));
        // Push all but the nearest, farthest first.
        for &entry in order[1..count.max(1)].iter().rev() {
            stack[top] = MaybeUninit::new(entry);
            top += 1;
        }
        let mut next = (count > 0).then_some(order[0].reference);
        node = loop {
            match next {
                Some(reference) if reference & LEAF == 0 => break reference,
                Some(reference) => search.leaf::<K, C>(bvh, ray, reference, counter),
                None => {}
            }
            // Pop the nearest entry not yet beaten by a closer hit.
            next = None;
            while top > 0 {
                top -= 1;
                // SAFETY: entries below `top` were written above.
                let entry = unsafe { stack[top].assume_init() };
                if entry.near <= search.best_t * FAR_SCALE {
                    next = Some(entry.reference);
                    break;
                }
            }
            if next.is_none() {
                return;
            }
        };
    }
}

/// Asks for node or leaf block `reference` (all its cache lines) to be brought into the cache.
///
/// Without a branch: whether a hit child is a node or a leaf block cannot be predicted, so the
/// address is chosen by a conditional move and the larger object's lines (a node takes four,
/// a block five) are asked for either way. `cube` 256² × 256, 2 threads: 1.3 % faster (5
/// interleaved pairs of `render`, every pair), 1.3 fewer mispredicted branches per ray
/// (cachegrind's model, 64² × 256).
#[inline(always)]
fn prefetch(bvh: &WideBvh, reference: u32) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        const LINES: usize = std::mem::size_of::<Block>().div_ceil(64);
        let index = (reference & !LEAF) as usize;
        // Neither pointer is dereferenced, so an index past one of the arrays is harmless.
        let node = bvh.nodes.as_ptr().wrapping_add(index) as *const i8;
        let block = bvh.blocks.as_ptr().wrapping_add(index) as *const i8;
        let start = std::hint::select_unpredictable(reference & LEAF != 0, block, node);
        for line in 0..LINES {
            // SAFETY: prefetching is only a hint; it never faults, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(line * 64)) };
        }
    }
}
