//! Which binary nodes become wide nodes: the collapse's cost model (Ylitie, Karras and Laine
//! 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", §4.1).
//!
//! The leaf blocks are the binary tree's leaves whatever the collapse does, so the only choice
//! is which inner nodes are kept as wide nodes; a ray is expected to test a wide node in
//! proportion to its box's area, so the best collapse is the one whose wide nodes have the
//! least total area. For a binary node `n` given `i` child slots in its parent, let `C(n, i)`
//! be that least total within its subtree: a leaf costs nothing; an inner node either becomes
//! a wide node of its own in one slot (its area plus its children sharing its eight slots:
//! `A(n) + D(n, 8)`) or hands its slots to its children (`D(n, i)`, for `i ≥ 2`), where
//! `D(n, i)` is the cheapest split of `i` slots between the left and right subtrees.
//!
//! Against the greedy collapse (open the largest child until there are eight), which fills
//! the bottom of the tree with wide nodes of two to four leaves, this makes fewer, fuller
//! nodes and traces 4–6 % faster on `cube` and `hall`, 13 % on a 5.2 M-triangle sphere (the
//! figures: `docs/engine.md`).

use super::WIDTH;

/// `C(n, i + 1)` in `[i]`: the least total area of the wide nodes that a binary node's subtree
/// makes when it is given `i + 1` child slots. Non-increasing in `i`; all zero for a leaf.
pub(super) type SlotCosts = [f32; WIDTH];

/// The costs of an inner binary node of half-area `area` whose children's costs are `left`
/// and `right`.
pub(super) fn inner(area: f32, left: &SlotCosts, right: &SlotCosts) -> SlotCosts {
    let as_node = area + distributed(left, right, WIDTH).0;
    let mut costs = [as_node; WIDTH];
    for (i, cost) in costs.iter_mut().enumerate().skip(1) {
        *cost = as_node.min(distributed(left, right, i + 1).0);
    }
    costs
}

/// Whether an inner node given `slots` slots is best kept as a wide node of its own (always
/// with one slot), rather than handing the slots to its children.
pub(super) fn stays_node(costs: &SlotCosts, slots: usize) -> bool {
    costs[0] <= costs[slots - 1]
}

/// `D(n, slots)`: the cheapest way to share `slots ≥ 2` slots between subtrees of costs `left`
/// and `right`: the total, and the left's share (the smallest of equal totals).
pub(super) fn distributed(left: &SlotCosts, right: &SlotCosts, slots: usize) -> (f32, usize) {
    let mut best = (f32::INFINITY, 1);
    for k in 1..slots {
        let total = left[k - 1] + right[slots - k - 1];
        if total < best.0 {
            best = (total, k);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_subtrees_hand_their_slots_down_and_large_ones_become_nodes() {
        let leaf = [0.0; WIDTH];
        // A node over two leaves: as a wide node it costs its area, spread it costs nothing
        // but needs two slots.
        let two = inner(1.0, &leaf, &leaf);
        assert_eq!(two, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(stays_node(&two, 1) && !stays_node(&two, 2));
        // Two of those under a parent of area 3: with four slots all four leaves fit.
        let four = inner(3.0, &two, &two);
        assert_eq!(four[3], 0.0);
        assert_eq!(distributed(&two, &two, 4), (0.0, 2));
        // With three slots one child stays a node: cost 1 (the cheaper of the two).
        assert_eq!(four[2], 1.0);
        assert_eq!(four[0], 3.0);
        // A leaf against a costly subtree: the costly side gets the spare slots.
        let costly = inner(10.0, &four, &four);
        assert_eq!(distributed(&leaf, &costly, 8).1, 1);
    }
}
