//! Room shells: the walls, floor and ceiling of a box-shaped room (spec §5).
//!
//! Units: scene units, y up. The shell is a grid of square-ish cells on the six faces of the
//! room's box, every lattice point one shared vertex: walls meet the floor and ceiling on the
//! same vertices, so a shell without openings is watertight (every edge in two triangles).
//! An opening (window, doorway) removes the cells whose centres lie in its box.

use glam::{UVec3, Vec3};

use crate::scene::{Bounds, Mesh};

/// The inside surface of the box `room`, in cells about `cell_size` wide (the count per
/// axis rounded, at least one), less the cells whose centres lie inside one of `openings`.
pub fn shell(room: Bounds, cell_size: f32, openings: &[Bounds]) -> Mesh {
    let cells = ((room.max - room.min) / cell_size)
        .round()
        .max(Vec3::ONE)
        .as_uvec3();
    let mut lattice = Lattice::new(room, cells);
    let mut mesh = Mesh::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, cells[axis]] {
            for i in 0..cells[u] {
                for j in 0..cells[v] {
                    let corner = |di: u32, dj: u32| {
                        let mut at = UVec3::ZERO;
                        at[axis] = side;
                        at[u] = i + di;
                        at[v] = j + dj;
                        at
                    };
                    let centre = 0.5 * (lattice.position(corner(0, 0)) + lattice.position(corner(1, 1)));
                    if openings.iter().any(|o| contains(o, centre)) {
                        continue;
                    }
                    let quad = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|at| lattice.vertex(at, &mut mesh));
                    mesh.add_triangle(quad[0], quad[1], quad[2]);
                    mesh.add_triangle(quad[0], quad[2], quad[3]);
                }
            }
        }
    }
    mesh
}

fn contains(b: &Bounds, p: Vec3) -> bool {
    p.cmpge(b.min).all() && p.cmple(b.max).all()
}

/// The points of a regular lattice over a box, each given one vertex the first time a face
/// uses it.
struct Lattice {
    room: Bounds,
    cells: UVec3,
    vertex: Vec<u32>,
}

impl Lattice {
    fn new(room: Bounds, cells: UVec3) -> Self {
        let points = (cells + UVec3::ONE).element_product() as usize;
        Lattice {
            room,
            cells,
            vertex: vec![u32::MAX; points],
        }
    }

    /// Computed from the integer lattice coordinates alone, so that every face asking for
    /// the same point gets bit-identical coordinates.
    fn position(&self, at: UVec3) -> Vec3 {
        let t = at.as_vec3() / self.cells.as_vec3();
        self.room.min + t * (self.room.max - self.room.min)
    }

    fn vertex(&mut self, at: UVec3, mesh: &mut Mesh) -> u32 {
        let n = self.cells + UVec3::ONE;
        let slot = (at.x + n.x * (at.y + n.y * at.z)) as usize;
        if self.vertex[slot] == u32::MAX {
            self.vertex[slot] = mesh.add_vertices([self.position(at)]);
        }
        self.vertex[slot]
    }
}

#[cfg(test)]
mod tests {
    use super::super::checks::unshared_edges;
    use super::*;

    fn room() -> Bounds {
        Bounds {
            min: Vec3::new(-2.0, 0.0, -1.0),
            max: Vec3::new(2.0, 3.0, 1.0),
        }
    }

    #[test]
    fn a_shell_without_openings_is_watertight() {
        let mesh = shell(room(), 0.5, &[]);
        // 8·6 + 8·4 + 6·4 cells on each of two sides, two triangles each.
        assert_eq!(mesh.triangle_count(), 2 * 2 * (48 + 32 + 24));
        assert!(unshared_edges(&mesh).is_empty());
        assert_eq!(mesh.bounds(), room());
    }

    #[test]
    fn an_opening_leaves_a_rim_of_single_edges_around_it() {
        let window = Bounds {
            min: Vec3::new(-1.0, 1.0, 0.9),
            max: Vec3::new(1.0, 2.0, 1.1),
        };
        let mesh = shell(room(), 0.5, &[window]);
        assert_eq!(mesh.triangle_count(), 2 * 2 * (48 + 32 + 24) - 2 * 8);
        let rim = unshared_edges(&mesh);
        // The 2 × 1 window in 0.5 cells has a perimeter of 12 cell edges.
        assert_eq!(rim.len(), 12);
        for (a, b) in rim {
            for p in [mesh.positions[a as usize], mesh.positions[b as usize]] {
                assert!(
                    p.z == 1.0 && contains(&window, p),
                    "{p} is not on the window's rim"
                );
            }
        }
    }
}
