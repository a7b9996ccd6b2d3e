//! Sculptural ornaments of the procedural scenes (spec §5): a torus knot, a bumpy sphere, a
//! cluster of small boxes and the pedestals they stand on. Thin tubes, narrow slots and
//! crevices: the places where a harmonic mean distance is small and hard to estimate.
//!
//! Units: scene units, y up; each ornament is built around the origin at a size of about one
//! unit and placed by its caller.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};

use super::{cuboid, icosphere, tube, turned, unit_hash, value_noise};
use crate::scene::Mesh;

/// A (p, q) torus knot: a tube winding p times around the axis (y) of a torus and q times
/// through its hole.
#[derive(Clone, Copy, Debug)]
pub struct TorusKnot {
    /// Turns around the torus's axis (y).
    pub p: u32,
    /// Turns through the torus's hole.
    pub q: u32,
    /// Radius of the torus's core circle.
    pub radius: f32,
    /// Radius of the torus's tube, around which the knot winds.
    pub winding_radius: f32,
    /// Radius of the knot's own tube.
    pub tube_radius: f32,
}

impl TorusKnot {
    /// The knot as a closed tube: `samples` rings of `segments` points; 2·samples·segments
    /// triangles.
    pub fn mesh(&self, samples: usize, segments: usize) -> Mesh {
        let path: Vec<Vec3> = (0..samples)
            .map(|i| {
                let t = TAU * i as f32 / samples as f32;
                let (p, q) = (self.p as f32 * t, self.q as f32 * t);
                let r = self.radius + self.winding_radius * q.cos();
                Vec3::new(r * p.cos(), self.winding_radius * q.sin(), r * p.sin())
            })
            .collect();
        tube(&path, self.tube_radius, segments, true)
    }
}

/// A sphere of radius about `radius` roughened by value noise: rounded bumps with sharp
/// creases between them, up to `relief`·radius high. An icosphere underneath, so
/// 20·4^subdivisions triangles; `seed` picks the pattern.
pub fn bumpy_sphere(radius: f32, relief: f32, subdivisions: u32, seed: u32) -> Mesh {
    let mut mesh = icosphere(subdivisions, Vec3::ZERO, 1.0);
    for p in &mut mesh.positions {
        let bumps = value_noise(3.0 * *p, seed) + 0.5 * value_noise(7.0 * *p, seed + 1);
        let crease = (value_noise(5.0 * *p, seed + 2) - 0.5).abs();
        let height = relief * (0.6 * bumps - crease - 0.3);
        *p *= radius * (1.0 + height);
    }
    mesh
}

/// A cluster of small boxes like a model city block: a `columns × rows` grid of towers on
/// square cells of side `cell`, `gap` apart, of heights up to `max_height`, some with a
/// narrower storey on top. Its footprint is centred on the origin, on y = 0.
pub fn box_cluster(columns: i32, rows: i32, cell: f32, gap: f32, max_height: f32, seed: u32) -> Mesh {
    let mut mesh = Mesh::new();
    let origin = -0.5 * Vec2::new(columns as f32, rows as f32) * cell;
    for i in 0..columns {
        for j in 0..rows {
            let random = |k: i32| unit_hash(i, j, k, seed);
            let centre = origin + (Vec2::new(i as f32, j as f32) + 0.5) * cell;
            let half = 0.5 * (cell - gap);
            let height = max_height * (0.15 + 0.85 * random(0) * random(1));
            mesh.append(&tower(centre, Vec2::splat(half), 0.0, height));
            if random(2) < 0.5 {
                let storey = Vec2::new(0.6, 0.3 + 0.5 * random(3)) * half;
                mesh.append(&tower(centre, storey, height, 1.25 * height));
            }
        }
    }
    mesh
}

/// A box over the footprint `centre ± half` (in x, z) from height `bottom` to `top`.
fn tower(centre: Vec2, half: Vec2, bottom: f32, top: f32) -> Mesh {
    let (min, max) = (centre - half, centre + half);
    cuboid(Vec3::new(min.x, bottom, min.y), Vec3::new(max.x, top, max.y))
}

/// A turned pedestal `height` tall and about `radius` wide: a plinth, mouldings, a waisted
/// shaft and a top for an ornament to stand on. 2·segments·16 triangles or so.
pub fn pedestal(height: f32, radius: f32, segments: usize) -> Mesh {
    let profile = [
        (0.0, 0.0),
        (1.0, 0.0),
        (1.0, 0.08),
        (0.92, 0.1),
        (0.9, 0.14),
        (0.75, 0.17),
        (0.62, 0.22),
        (0.55, 0.4),
        (0.52, 0.6),
        (0.55, 0.78),
        (0.68, 0.84),
        (0.78, 0.88),
        (0.9, 0.9),
        (0.95, 0.93),
        (0.95, 1.0),
        (0.0, 1.0),
    ];
    turned(&profile, radius, height, segments)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_torus_knot_is_a_closed_tube_of_the_requested_size() {
        let knot = TorusKnot {
            p: 2,
            q: 3,
            radius: 1.0,
            winding_radius: 0.4,
            tube_radius: 0.1,
        };
        let mesh = knot.mesh(300, 8);
        assert_eq!(mesh.triangle_count(), 2 * 300 * 8);
        assert!(super::super::checks::unshared_edges(&mesh).is_empty());
        let b = mesh.bounds();
        assert!(
            (b.max.x - 1.5).abs() < 0.02 && (b.max.y - 0.5).abs() < 0.02,
            "{b:?}"
        );
    }

    #[test]
    fn a_bumpy_sphere_stays_within_its_relief() {
        let mesh = bumpy_sphere(2.0, 0.2, 3, 7);
        for p in &mesh.positions {
            let r = p.length();
            assert!(r > 2.0 * 0.7 && r < 2.0 * 1.3, "{r}");
        }
        assert_eq!(mesh.triangle_count(), 20 * 64);
    }

    #[test]
    fn the_box_cluster_stands_on_its_centred_footprint() {
        let mesh = box_cluster(4, 3, 0.5, 0.05, 1.0, 1);
        let b = mesh.bounds();
        assert_eq!(b.min.y, 0.0);
        assert!(
            (b.min.x + 1.0).abs() < 0.03 && (b.max.z - 0.75).abs() < 0.03,
            "{b:?}"
        );
        assert!(b.max.y <= 1.0 * 1.25);
    }
}
