//! Closest-hit traversal of the wide BVH, generic over the kernel ([`Lanes`]).
//!
//! One ray at a time, children visited nearest first: a node's hit children are sorted by
//! their near distance (stable, so ties keep slot order), the nearest is taken next and the
//! others go on a stack with their distance, to be skipped when popped if a hit closer than
//! them has been found since. Everything outside the two kernel calls is shared by all
//! kernels, so all of them visit the same nodes in the same order and return the same hit.
//!
//! Measured on `cube` (256 gather rays, AVX2, one thread) and not kept: several rays taking
//! turns node by node, so that one computes while another waits for memory (17 % slower: it
//! defeats the branch predictor); prefetching pushed children (no change); special paths for
//! one and two hit children before the sort (no change).
//!
//! Hits within their own `t` error bound (see [`super::triangle`]) are kept aside and taken
//! only if the ray finds nothing else, and only where `accept_within_error` allows (see
//! [`super::Accel`]).

use std::mem::MaybeUninit;

use super::kernel::{Lanes, RayData, FAR_SCALE};
use super::wide::{WideBvh, EMPTY, LEAF, WIDTH};

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

/// The closest hit: leaf block, lane and distance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Closest {
    pub block: u32,
    pub lane: usize,
    pub t: f32,
}

/// Counts traversal steps (for the benchmark's nodes and triangles per ray); the no-op
/// implementation on `()` compiles away.
pub trait Counter {
    fn node(&mut self) {}
    fn block(&mut self) {}
}

impl Counter for () {}

/// Nodes and leaf blocks visited.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraversalStats {
    /// Wide nodes whose eight children were box-tested.
    pub nodes: u64,
    /// Leaf blocks whose eight triangles were tested.
    pub blocks: u64,
}

impl Counter for TraversalStats {
    fn node(&mut self) {
        self.nodes += 1;
    }
    fn block(&mut self) {
        self.blocks += 1;
    }
}

/// The best hits so far.
struct Search<'a, C> {
    best: Option<Closest>,
    best_t: f32,
    within_error: Option<Closest>,
    accept_within_error: &'a dyn Fn(u32, usize) -> bool,
    counter: &'a mut C,
}

impl<C: Counter> Search<'_, C> {
    #[inline(always)]
    fn leaf<K: Lanes>(&mut self, bvh: &WideBvh, ray: &RayData, reference: u32) {
        let block = reference & !LEAF;
        self.counter.block();
        let hits = K::block(&bvh.blocks[block as usize], ray, self.best_t);
        let mut solid = hits.hit & !hits.within_error;
        while solid != 0 {
            let lane = solid.trailing_zeros() as usize;
            solid &= solid - 1;
            let t = hits.t[lane];
            if t < self.best_t {
                self.best_t = t;
                self.best = Some(Closest { block, lane, t });
            }
        }
        let mut doubtful = hits.within_error;
        while doubtful != 0 {
            let lane = doubtful.trailing_zeros() as usize;
            doubtful &= doubtful - 1;
            let t = hits.t[lane];
            if self.within_error.is_none_or(|w| t < w.t) && (self.accept_within_error)(block, lane) {
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
    let mut search = Search {
        best: None,
        best_t: t_max,
        within_error: None,
        accept_within_error,
        counter,
    };
    let mut top = 0usize;
    let mut node = 0u32;
    loop {
        search.counter.node();
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
                Some(reference) => search.leaf::<K>(bvh, ray, reference),
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
                return search.best.or(search.within_error);
            }
        };
    }
}
