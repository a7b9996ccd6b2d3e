//! Loop subdivision, as pbrt's `loopsubdiv` shape does it: `levels` rounds of splitting each
//! triangle in four, then every vertex moved to its place on the limit surface.
//!
//! Each round (Loop 1987, with Warren's weights where pbrt uses them):
//! - an edge's new vertex is `3/8 (a + b) + 1/8 (c + d)` for an interior edge between faces
//!   `abc` and `abd`, and `(a + b) / 2` on the boundary (an edge of one face);
//! - an old vertex of valence `n` moves to `(1 − nβ) v + β Σ neighbours`, with `β = 3/16` for
//!   `n = 3` and `3/(8n)` otherwise; a boundary vertex to `3/4 v + 1/8 (b₀ + b₁)` (its two
//!   boundary neighbours).
//!
//! At the end an interior vertex goes to `(1 − nγ) v + γ Σ neighbours`, `γ = 1 / (n + 3/(8β))`,
//! and a boundary one to `3/5 v + 1/5 (b₀ + b₁)`. An edge of more than two faces and a
//! vertex with other than two boundary neighbours (non-manifold input) keep the plain rules'
//! nearest sense: such an edge's vertex is its midpoint and such a vertex stays where it is.

use std::collections::HashMap;

use glam::DVec3;

/// The mesh `positions`/`triangles` subdivided `levels` times and pushed to the limit.
pub fn subdivide(
    mut positions: Vec<DVec3>,
    mut triangles: Vec<[u32; 3]>,
    levels: u32,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    for _ in 0..levels {
        let topology = Topology::of(positions.len(), &triangles);
        let mut next: Vec<DVec3> = (0..positions.len())
            .map(|v| topology.even(v, &positions))
            .collect();
        let mut edge_vertex = HashMap::with_capacity(topology.edges.len());
        let mut edges: Vec<(&(u32, u32), &Vec<u32>)> = topology.edges.iter().collect();
        edges.sort_unstable_by_key(|(k, _)| **k);
        for (&(a, b), opposite) in edges {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            let p = match opposite[..] {
                [c, d] => 0.375 * (pa + pb) + 0.125 * (positions[c as usize] + positions[d as usize]),
                _ => 0.5 * (pa + pb),
            };
            edge_vertex.insert((a, b), next.len() as u32);
            next.push(p);
        }
        let middle = |a: u32, b: u32| edge_vertex[&(a.min(b), a.max(b))];
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (middle(a, b), middle(b, c), middle(c, a));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
        positions = next;
    }
    let topology = Topology::of(positions.len(), &triangles);
    let limit = (0..positions.len())
        .map(|v| topology.limit(v, &positions))
        .collect();
    (limit, triangles)
}

/// Who is next to whom: each edge's opposite corners, each vertex's neighbours.
struct Topology {
    /// Edge (low, high) → the third corner of each face it bounds.
    edges: HashMap<(u32, u32), Vec<u32>>,
    /// Vertex → its neighbours, each once, in a fixed order.
    neighbours: Vec<Vec<u32>>,
}

impl Topology {
    fn of(vertices: usize, triangles: &[[u32; 3]]) -> Self {
        let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut neighbours = vec![Vec::new(); vertices];
        for &[a, b, c] in triangles {
            for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
                edges.entry((p.min(q), p.max(q))).or_default().push(r);
                for (x, y) in [(p, q), (q, p)] {
                    if !neighbours[x as usize].contains(&y) {
                        neighbours[x as usize].push(y);
                    }
                }
            }
        }
        for n in &mut neighbours {
            n.sort_unstable();
        }
        Topology { edges, neighbours }
    }

    /// Vertex `v`'s neighbours across boundary edges (edges of one face).
    fn boundary_neighbours(&self, v: usize) -> Vec<u32> {
        let v32 = v as u32;
        self.neighbours[v]
            .iter()
            .copied()
            .filter(|&w| self.edges[&(v32.min(w), v32.max(w))].len() == 1)
            .collect()
    }

    /// `v`'s place after a round, by `β` inside and `3/4, 1/8` on the boundary.
    fn even(&self, v: usize, positions: &[DVec3]) -> DVec3 {
        self.smoothed(v, positions, beta, (0.75, 0.125))
    }

    /// `v`'s place on the limit surface, by `γ` inside and `3/5, 1/5` on the boundary.
    fn limit(&self, v: usize, positions: &[DVec3]) -> DVec3 {
        self.smoothed(v, positions, |n| 1.0 / (n + 3.0 / (8.0 * beta(n))), (0.6, 0.2))
    }

    fn smoothed(
        &self,
        v: usize,
        positions: &[DVec3],
        weight: impl Fn(f64) -> f64,
        boundary: (f64, f64),
    ) -> DVec3 {
        let p = positions[v];
        let ring = &self.neighbours[v];
        if ring.is_empty() {
            return p;
        }
        let on_boundary = self.boundary_neighbours(v);
        match on_boundary[..] {
            [] => {
                let n = ring.len() as f64;
                let w = weight(n);
                let sum: DVec3 = ring.iter().map(|&u| positions[u as usize]).sum();
                (1.0 - n * w) * p + w * sum
            }
            [a, b] => boundary.0 * p + boundary.1 * (positions[a as usize] + positions[b as usize]),
            _ => p,
        }
    }
}

/// Loop's `β` for valence `n`, as pbrt takes it (Warren's `3/(8n)`, `3/16` for `n = 3`).
fn beta(n: f64) -> f64 {
    if n == 3.0 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular tetrahedron's limit surface is symmetric: every vertex ends at the same
    /// distance from the centre, and the four old vertices move inwards.
    #[test]
    fn a_tetrahedron_stays_symmetric_and_shrinks() {
        let p = vec![
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ];
        let t = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        let (q, tris) = subdivide(p, t, 1);
        assert_eq!(tris.len(), 16);
        assert_eq!(q.len(), 4 + 6);
        let corner = q[0].length();
        for v in &q[..4] {
            assert!((v.length() - corner).abs() < 1e-12);
        }
        assert!(corner < 3f64.sqrt());
    }

    /// A flat open patch stays in its plane, with 4^levels times its triangles.
    #[test]
    fn a_flat_square_stays_flat() {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let (q, tris) = subdivide(p, vec![[0, 1, 2], [0, 2, 3]], 2);
        assert_eq!(tris.len(), 32);
        assert!(q.iter().all(|v| v.z == 0.0));
        assert_eq!(q.len(), 25);
    }
}
