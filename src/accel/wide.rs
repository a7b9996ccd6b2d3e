//! The 8-wide BVH that the kernels traverse: float (uncompressed) child boxes stored
//! structure-of-arrays, one node per 256 bytes, leaves of up to 8 triangles stored
//! structure-of-arrays so one 8-lane instruction tests them all.
//!
//! Built by collapsing a binary BVH, from our binned SAH builder ([`super::sah`]) or from
//! obvhs (PLOC, spatial splits, reinsertion: Meister & Bittner 2018, Meister et al. 2021).
//! Which binary nodes become wide nodes is chosen by the least total area of wide nodes
//! ([`super::slots`], Ylitie et al. 2017), from costs the SAH builder computes as it builds.
//! Nodes and leaf blocks are laid out in depth-first order, so a subtree's nodes are near each
//! other. The collapse first walks the binary tree on one thread to fix that layout (which
//! binary nodes become each wide node's children, where every node and block goes), then
//! fills the leaf blocks on all threads, each into its place, then the nodes' boxes
//! bottom-up: the same bytes for any thread count.
//!
//! Boxes are computed here, bottom-up, from the triangles themselves, not taken from obvhs:
//! with spatial splits obvhs clips a triangle's box at a split plane with rounded arithmetic,
//! and a box a few ulps too small could let a ray through. A leaf's box is the union of its
//! triangles' boxes, each cut to the (slightly widened) split box; without splits that is
//! exactly the triangles' box.
//!
//! The layout's design, and the collapses measured and not kept (the greedy collapse of Wald
//! et al. 2008, subtrees collapsed in parallel): `docs/engine.md`.

use std::time::Duration;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{builder::build_bvh2_from_tris, Bvh2};
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::slots::{self, SlotCosts};
use crate::scene::Mesh;

pub use super::WIDTH;

/// A child slot that holds nothing: its box is empty (`lo = +inf`, `hi = −inf`), which every
/// kernel's slab test rejects.
pub const EMPTY: u32 = u32::MAX;
/// Set in a child reference that names a leaf block rather than a node.
pub const LEAF: u32 = 1 << 31;

/// One wide node: the boxes of its eight children per axis (`bounds[0..3]` the minima in x,
/// y, z, `bounds[3..6]` the maxima), and what each child is: a node index, `LEAF | block`, or
/// [`EMPTY`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    pub bounds: [[f32; WIDTH]; 6],
    pub child: [u32; WIDTH],
}

/// Up to eight triangles, `corner[k][axis][lane]`. A block with fewer triangles repeats its
/// last one in the spare lanes: a repeated triangle gives the same hit, and ties go to the
/// lowest lane, so no lane mask is needed.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Block {
    pub corner: [[[f32; WIDTH]; 3]; 3],
}

impl Block {
    /// The three corners of the triangle in `lane`.
    #[inline]
    pub fn triangle(&self, lane: usize) -> [Vec3A; 3] {
        self.corner
            .map(|c| Vec3A::new(c[0][lane], c[1][lane], c[2][lane]))
    }
}

/// The wide BVH: nodes (the root is node 0), leaf blocks, and each block lane's triangle index
/// in the mesh.
pub struct WideBvh {
    pub nodes: Vec<Node>,
    pub blocks: Vec<Block>,
    pub block_triangles: Vec<[u32; WIDTH]>,
    /// Longest path from the root to a leaf, in nodes: bounds the traversal stack.
    pub depth: usize,
}

/// Which builder makes the binary BVH that is collapsed.
#[derive(Clone, Copy, Debug)]
pub enum BinaryBuilder {
    /// Our binned SAH builder ([`super::sah`]), parallel; with obvhs's spatial pre-splits of
    /// large triangles where `pre_split`.
    Sah { pre_split: bool },
    /// obvhs's builder with these parameters (leaves capped at [`WIDTH`] triangles).
    Obvhs(BvhBuildParams),
}

impl WideBvh {
    /// Builds the binary BVH of `mesh` with `builder` and collapses it.
    pub fn build(mesh: &Mesh, builder: BinaryBuilder) -> WideBvh {
        let mut wide = WideBvh {
            nodes: Vec::new(),
            blocks: Vec::new(),
            block_triangles: Vec::new(),
            depth: 1,
        };
        if mesh.triangle_count() == 0 {
            wide.nodes.push(empty_node());
            return wide;
        }
        let (bvh2, costs) = match builder {
            BinaryBuilder::Sah { pre_split } => super::sah::build(mesh, pre_split),
            BinaryBuilder::Obvhs(params) => {
                let params = BvhBuildParams {
                    max_prims_per_leaf: params.max_prims_per_leaf.min(WIDTH as u32),
                    ..params
                };
                let bvh2 = build_bvh2_from_tris(
                    &super::sah::obvhs_triangles(mesh),
                    params,
                    &mut Duration::default(),
                );
                let mut costs = vec![[0.0; WIDTH]; bvh2.nodes.len()];
                slot_costs(&bvh2, 0, &mut costs);
                (bvh2, costs)
            }
        };
        let collapse = Collapse {
            bvh2: &bvh2,
            costs: &costs,
            mesh,
        };
        let root = &bvh2.nodes[0];
        if root.prim_count > 0 {
            // A single leaf: one node whose only child is that leaf.
            let mut node = empty_node();
            let (block, lanes, bounds) = collapse.leaf(0);
            set_child(&mut node, 0, LEAF, bounds);
            wide.nodes.push(node);
            wide.blocks.push(block);
            wide.block_triangles.push(lanes);
        } else {
            collapse.build(0, &mut wide);
        }
        wide
    }

    /// Bytes held by the nodes and leaf blocks (what the kernels read).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.blocks.len() * (std::mem::size_of::<Block>() + std::mem::size_of::<[u32; WIDTH]>())
    }
}

fn empty_node() -> Node {
    let mut bounds = [[f32::INFINITY; WIDTH]; 6];
    bounds[3..].fill([f32::NEG_INFINITY; WIDTH]);
    Node {
        bounds,
        child: [EMPTY; WIDTH],
    }
}

fn set_child(node: &mut Node, slot: usize, reference: u32, bounds: Aabb) {
    for axis in 0..3 {
        node.bounds[axis][slot] = bounds.min[axis];
        node.bounds[3 + axis][slot] = bounds.max[axis];
    }
    node.child[slot] = reference;
}

struct Collapse<'a> {
    bvh2: &'a Bvh2,
    /// Each binary node's collapse costs, by node index.
    costs: &'a [SlotCosts],
    mesh: &'a Mesh,
}

/// Fills `costs` for binary node `index`'s subtree (for trees not built by [`super::sah`],
/// which fills them as it builds).
fn slot_costs(bvh2: &Bvh2, index: usize, costs: &mut [SlotCosts]) -> SlotCosts {
    let node = &bvh2.nodes[index];
    if node.prim_count == 0 {
        let first = node.first_index as usize;
        let left = slot_costs(bvh2, first, costs);
        let right = slot_costs(bvh2, first + 1, costs);
        costs[index] = slots::inner(node.aabb().half_area(), &left, &right);
    }
    costs[index]
}

/// The shape of the wide BVH, in the order it is laid out: wide nodes depth-first (a node,
/// then its subtrees in slot order), leaf blocks in the order the walk meets them.
struct Plan {
    /// Per wide node, before its boxes are known, what each child is: a wide node's index,
    /// `LEAF | block`, or [`EMPTY`] after the last child.
    nodes: Vec<[u32; WIDTH]>,
    /// The binary leaf that each block holds.
    leaves: Vec<u32>,
    depth: usize,
}

impl Collapse<'_> {
    /// Builds the wide BVH for binary inner node `root`. The walk that fixes the layout is
    /// cheap and runs on one thread; filling the leaf blocks (most of the work: reading the
    /// triangles in leaf order) runs on all of them, each block into its place, so the result
    /// is the same for any thread count.
    fn build(&self, root: usize, wide: &mut WideBvh) {
        let mut plan = Plan {
            nodes: Vec::new(),
            leaves: Vec::new(),
            depth: 1,
        };
        self.plan(root, &mut plan, 1);
        // Each block written once, in place, on memory advised to be huge pages.
        let count = plan.leaves.len();
        let mut blocks: Vec<Block> = super::pages::with_capacity(count);
        let mut block_triangles: Vec<[u32; WIDTH]> = super::pages::with_capacity(count);
        let mut leaf_bounds = vec![Aabb::INVALID; count];
        blocks.spare_capacity_mut()[..count]
            .par_iter_mut()
            .zip(&mut block_triangles.spare_capacity_mut()[..count])
            .zip(&mut leaf_bounds)
            .zip(&plan.leaves)
            .for_each(|(((block, lanes), bounds), &leaf)| {
                let (leaf_block, leaf_lanes, leaf_box) = self.leaf(leaf as usize);
                block.write(leaf_block);
                lanes.write(leaf_lanes);
                *bounds = leaf_box;
            });
        // SAFETY: the loop above wrote all `count` values of both.
        unsafe {
            blocks.set_len(count);
            block_triangles.set_len(count);
        }
        // Boxes bottom-up: a node's children come after it, so walk the nodes backwards.
        let mut node_bounds = vec![Aabb::INVALID; plan.nodes.len()];
        let mut nodes: Vec<Node> = super::pages::with_capacity(plan.nodes.len());
        for (position, children) in plan.nodes.iter().enumerate().rev() {
            let mut node = empty_node();
            let mut bounds = Aabb::INVALID;
            for (slot, &reference) in children.iter().take_while(|&&r| r != EMPTY).enumerate() {
                let child_bounds = if reference & LEAF != 0 {
                    leaf_bounds[(reference & !LEAF) as usize]
                } else {
                    node_bounds[reference as usize]
                };
                set_child(&mut node, slot, reference, child_bounds);
                bounds = bounds.union(&child_bounds);
            }
            nodes.spare_capacity_mut()[position].write(node);
            node_bounds[position] = bounds;
        }
        // SAFETY: the loop above wrote every position.
        unsafe { nodes.set_len(plan.nodes.len()) };
        wide.blocks = blocks;
        wide.block_triangles = block_triangles;
        wide.nodes = nodes;
        wide.depth = plan.depth;
    }

    /// Plans the wide node for binary inner node `index` and, depth-first, its subtrees;
    /// returns its index. Its children are the binary nodes that the cheapest sharing of its
    /// eight slots keeps ([`slots`]).
    fn plan(&self, index: usize, plan: &mut Plan, depth: usize) -> u32 {
        plan.depth = plan.depth.max(depth);
        let mut children = [0usize; WIDTH];
        let mut count = 0;
        self.expand(index, WIDTH, true, &mut children, &mut count);
        let position = plan.nodes.len();
        let mut planned = [EMPTY; WIDTH];
        plan.nodes.push(planned);
        for (slot, &child) in children[..count].iter().enumerate() {
            planned[slot] = if self.bvh2.nodes[child].prim_count > 0 {
                plan.leaves.push(child as u32);
                LEAF | (plan.leaves.len() - 1) as u32
            } else {
                self.plan(child, plan, depth + 1)
            };
        }
        plan.nodes[position] = planned;
        position as u32
    }

    /// Appends to `children` what binary node `index` becomes in at most `slots` slots of a
    /// wide node: itself (a leaf, or an inner node that is cheapest as a wide node of its
    /// own), or, where `open` or cheaper, what its two children become sharing the slots.
    fn expand(
        &self,
        index: usize,
        slots: usize,
        open: bool,
        children: &mut [usize; WIDTH],
        count: &mut usize,
    ) {
        let node = &self.bvh2.nodes[index];
        if node.prim_count > 0 || (!open && slots::stays_node(&self.costs[index], slots)) {
            children[*count] = index;
            *count += 1;
            return;
        }
        let first = node.first_index as usize;
        let (_, left_slots) = slots::distributed(&self.costs[first], &self.costs[first + 1], slots);
        self.expand(first, left_slots, false, children, count);
        self.expand(first + 1, slots - left_slots, false, children, count);
    }

    /// The leaf block for binary leaf `index`: its triangles, their indices and its box.
    fn leaf(&self, index: usize) -> (Block, [u32; WIDTH], Aabb) {
        let leaf = &self.bvh2.nodes[index];
        let first = leaf.first_index as usize;
        let primitives = &self.bvh2.primitive_indices[first..first + leaf.prim_count as usize];
        let split_box = widened(*leaf.aabb());
        let mut block = Block {
            corner: [[[0.0; WIDTH]; 3]; 3],
        };
        let mut lanes = [0u32; WIDTH];
        let mut bounds = Aabb::INVALID;
        for lane in 0..WIDTH {
            let triangle = primitives[lane.min(primitives.len() - 1)];
            let corners = self.mesh.triangle(triangle as usize).map(Vec3A::from);
            for (k, v) in corners.iter().enumerate() {
                for axis in 0..3 {
                    block.corner[k][axis][lane] = v[axis];
                }
            }
            lanes[lane] = triangle;
            let tight = Aabb::from_points(&corners);
            bounds = bounds.union(&tight.intersection(&split_box));
        }
        (block, lanes, bounds)
    }
}

/// `bounds` grown by a few ulps of its coordinates: obvhs's split boxes are computed with
/// rounding, and cutting a triangle's box to one must never cut off part of the triangle.
fn widened(bounds: Aabb) -> Aabb {
    let slack = (bounds.min.abs().max(bounds.max.abs())) * (8.0 * f32::EPSILON) + f32::MIN_POSITIVE;
    Aabb::new(bounds.min - slack, bounds.max + slack)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::procedural::shapes::icosphere;

    /// 65 × 65 small triangles on a unit lattice: their doubled centroids `(2i, 2j)` fall
    /// exactly on bin edges (32 bins over a span of 128), where binning and partitioning must
    /// agree on the side.
    fn lattice() -> Mesh {
        let mut mesh = Mesh::new();
        for i in 0..65 {
            for j in 0..65 {
                let (x, y) = (i as f32, j as f32);
                let first = mesh.add_vertices([
                    glam::Vec3::new(x - 0.25, y - 0.25, 0.0),
                    glam::Vec3::new(x + 0.25, y - 0.25, 0.0),
                    glam::Vec3::new(x, y + 0.25, 0.0),
                ]);
                mesh.add_triangle(first, first + 1, first + 2);
            }
        }
        mesh
    }

    #[test]
    fn every_triangle_is_in_a_leaf_inside_every_box_above_it() {
        let sphere = icosphere(3, glam::Vec3::new(0.3, -0.2, 0.1), 2.0);
        let lattice = lattice();
        for (mesh, builder, pre_split) in [
            (&lattice, BinaryBuilder::Sah { pre_split: false }, false),
            (&sphere, BinaryBuilder::Sah { pre_split: false }, false),
            (&sphere, BinaryBuilder::Sah { pre_split: true }, true),
            (
                &sphere,
                BinaryBuilder::Obvhs(BvhBuildParams::very_slow_build()),
                true,
            ),
        ] {
            let wide = WideBvh::build(mesh, builder);
            let mut seen = vec![false; mesh.triangle_count()];
            // Walk the tree, checking each child's box contains what is below it.
            let mut stack = vec![(0u32, Aabb::LARGEST)];
            while let Some((index, outer)) = stack.pop() {
                let node = &wide.nodes[index as usize];
                for slot in 0..WIDTH {
                    let reference = node.child[slot];
                    if reference == EMPTY {
                        continue;
                    }
                    let min = Vec3A::new(node.bounds[0][slot], node.bounds[1][slot], node.bounds[2][slot]);
                    let max = Vec3A::new(node.bounds[3][slot], node.bounds[4][slot], node.bounds[5][slot]);
                    assert!(outer.min.cmple(min).all() && max.cmple(outer.max).all());
                    let inner = Aabb::new(min, max);
                    if reference & LEAF != 0 {
                        let block = (reference & !LEAF) as usize;
                        for lane in 0..WIDTH {
                            seen[wide.block_triangles[block][lane] as usize] = true;
                            let [a, b, c] = wide.blocks[block].triangle(lane);
                            if !pre_split {
                                for v in [a, b, c] {
                                    assert!(inner.contains_point(v));
                                }
                            }
                        }
                    } else {
                        stack.push((reference, inner));
                    }
                }
            }
            assert!(seen.iter().all(|&s| s), "a triangle is in no leaf");
        }
    }

    /// The total half-area of the wide nodes below the root: what the collapse minimises.
    fn wide_node_area(wide: &WideBvh) -> f64 {
        let mut total = 0.0;
        for node in &wide.nodes {
            for slot in 0..WIDTH {
                if node.child[slot] & LEAF == 0 && node.child[slot] != EMPTY {
                    let min = Vec3A::new(node.bounds[0][slot], node.bounds[1][slot], node.bounds[2][slot]);
                    let max = Vec3A::new(node.bounds[3][slot], node.bounds[4][slot], node.bounds[5][slot]);
                    total += Aabb::new(min, max).half_area() as f64;
                }
            }
        }
        total
    }

    /// The least total half-area over every choice of binary inner nodes to keep as wide
    /// nodes (the root always) in which no wide node has more than eight children: by trying
    /// them all.
    fn least_area_by_search(bvh2: &Bvh2) -> f64 {
        let inner: Vec<usize> = (1..bvh2.nodes.len())
            .filter(|&i| bvh2.nodes[i].prim_count == 0 && bvh2.nodes[i].first_index != 0)
            .collect();
        fn children(bvh2: &Bvh2, kept: &[bool], index: usize) -> usize {
            let first = bvh2.nodes[index].first_index as usize;
            [first, first + 1]
                .iter()
                .map(|&c| {
                    if bvh2.nodes[c].prim_count > 0 || kept[c] {
                        1
                    } else {
                        children(bvh2, kept, c)
                    }
                })
                .sum()
        }
        let mut best = f64::INFINITY;
        for subset in 0u32..1 << inner.len() {
            let mut kept = vec![false; bvh2.nodes.len()];
            kept[0] = true;
            for (bit, &i) in inner.iter().enumerate() {
                kept[i] = subset >> bit & 1 == 1;
            }
            let fits = (0..bvh2.nodes.len())
                .filter(|&i| kept[i])
                .all(|i| children(bvh2, &kept, i) <= WIDTH);
            if fits {
                let area: f64 = inner
                    .iter()
                    .filter(|&&i| kept[i])
                    .map(|&i| bvh2.nodes[i].aabb().half_area() as f64)
                    .sum();
                best = best.min(area);
            }
        }
        best
    }

    #[test]
    fn the_collapse_keeps_the_wide_nodes_of_least_total_area() {
        // Small scattered triangles, few enough that every choice can be tried.
        let mut state = 12345u32;
        let mut random = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let mut tried = 0;
        for count in [40, 56, 64, 72, 80, 96] {
            let mut mesh = Mesh::new();
            for _ in 0..count {
                let c = glam::Vec3::new(random(), random(), random()) * 10.0;
                let size = 0.05 + random();
                let first = mesh.add_vertices([c, c + glam::Vec3::X * size, c + glam::Vec3::Y * size]);
                mesh.add_triangle(first, first + 1, first + 2);
            }
            let (bvh2, _) = super::super::sah::build(&mesh, false);
            let used: Vec<usize> = (1..bvh2.nodes.len())
                .filter(|&i| bvh2.nodes[i].prim_count == 0 && bvh2.nodes[i].first_index != 0)
                .collect();
            if used.len() > 16 {
                continue;
            }
            let wide = WideBvh::build(&mesh, BinaryBuilder::Sah { pre_split: false });
            let (ours, least) = (wide_node_area(&wide), least_area_by_search(&bvh2));
            assert!(
                (ours - least).abs() <= 1e-5 * least.max(1.0),
                "{count} triangles: wide nodes of area {ours}, the least is {least}"
            );
            tried += 1;
        }
        assert!(tried >= 3, "only {tried} trees were small enough");
    }

    #[test]
    fn the_tree_is_the_same_for_any_thread_count() {
        // 81,920 triangles: large enough that subtrees are built and blocks filled in parallel.
        let mesh = icosphere(6, glam::Vec3::new(0.3, -0.2, 0.1), 2.0);
        let words = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let wide = pool.install(|| WideBvh::build(&mesh, BinaryBuilder::Sah { pre_split: false }));
            let mut words = vec![wide.depth as u32];
            for node in &wide.nodes {
                words.extend(node.bounds.iter().flatten().map(|v| v.to_bits()));
                words.extend(node.child);
            }
            for block in &wide.blocks {
                words.extend(block.corner.iter().flatten().flatten().map(|v| v.to_bits()));
            }
            words.extend(wide.block_triangles.iter().flatten());
            words
        };
        let one = words(1);
        assert!(one.len() > 100_000);
        for threads in [2, 5] {
            assert!(one == words(threads), "the tree differs with {threads} threads");
        }
    }
}
