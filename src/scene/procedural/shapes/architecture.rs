//! Architecture of the procedural scenes (spec §5): fluted columns, arches, balustrades and
//! staircases. Flutes, mouldings and rows of balusters are the hall's fine detail.
//!
//! Units: scene units, y up; each piece stands on y = 0 at the origin, placed by its caller.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Vec2, Vec3};

use super::{cuboid, fluted_lathe, hexahedron, lathe, sweep, tube, turned, Ends};
use crate::scene::Mesh;

/// Points around a turned piece (baluster, newel post) and along a round handrail.
const TURNING_SEGMENTS: usize = 12;
const RAIL_SEGMENTS: usize = 10;

/// A turned baluster `height` tall: a foot, a vase-shaped body, a neck and a cap.
/// 408 triangles.
pub fn baluster(height: f32) -> Mesh {
    let profile = [
        (0.0, 0.0),
        (0.09, 0.0),
        (0.09, 0.06),
        (0.075, 0.08),
        (0.06, 0.1),
        (0.05, 0.14),
        (0.07, 0.25),
        (0.085, 0.35),
        (0.08, 0.45),
        (0.055, 0.58),
        (0.035, 0.68),
        (0.03, 0.75),
        (0.045, 0.8),
        (0.05, 0.84),
        (0.035, 0.88),
        (0.035, 0.93),
        (0.06, 0.95),
        (0.06, 1.0),
        (0.0, 1.0),
    ];
    turned(&profile, height, height, TURNING_SEGMENTS)
}

/// A turned newel post `height` tall and `radius` wide at its foot, with a ball on top.
pub fn newel_post(height: f32, radius: f32) -> Mesh {
    let mut profile = vec![(0.0, 0.0), (1.0, 0.0), (1.0, 0.12), (0.8, 0.15), (0.7, 0.2)];
    profile.extend([(0.75, 0.75), (0.9, 0.8), (0.9, 0.84), (0.5, 0.86)]);
    profile.extend((1..8).map(|i| {
        let angle = PI * (i as f32 / 8.0 - 0.5);
        (0.6 * angle.cos(), 0.92 + 0.06 * angle.sin())
    }));
    profile.push((0.0, 0.98));
    turned(&profile, radius, height, 2 * TURNING_SEGMENTS)
}

/// One baluster of `height` on each of `bases`, under a round handrail from `rail[0]` to
/// `rail[1]`.
pub fn balustrade(bases: &[Vec3], height: f32, rail: [Vec3; 2]) -> Mesh {
    let mut mesh = Mesh::new();
    let one = baluster(height);
    for &base in bases {
        mesh.append_transformed(&one, Affine3A::from_translation(base));
    }
    let rings = bases.len().max(1) + 1;
    let path: Vec<Vec3> = (0..=rings)
        .map(|i| rail[0].lerp(rail[1], i as f32 / rings as f32))
        .collect();
    mesh.append(&tube(&path, 0.1 * height, RAIL_SEGMENTS, false));
    mesh
}

/// A straight, level balustrade from `from` to `to` (floor points) between two newel posts,
/// balusters about `spacing` apart, its rail `height` above the floor.
pub fn straight_balustrade(from: Vec3, to: Vec3, height: f32, spacing: f32) -> Mesh {
    let count = ((to - from).length() / spacing).round().max(1.0) as usize;
    let bases: Vec<Vec3> = (1..count)
        .map(|i| from.lerp(to, i as f32 / count as f32))
        .collect();
    let up = Vec3::new(0.0, height, 0.0);
    let mut mesh = balustrade(&bases, height, [from + up, to + up]);
    let post = newel_post(1.15 * height, 0.12 * height);
    for end in [from, to] {
        mesh.append_transformed(&post, Affine3A::from_translation(end));
    }
    mesh
}

/// A straight flight of stairs climbing along +z from z = 0, centred on x = 0: open treads
/// with a nosing, thin risers, a slanted stringer and a balustrade on each side.
#[derive(Clone, Copy, Debug)]
pub struct Staircase {
    /// Number of steps.
    pub steps: usize,
    /// Height of one step.
    pub rise: f32,
    /// Depth of one tread.
    pub run: f32,
    /// Width of the treads, along x.
    pub width: f32,
    /// Height of the handrail above the treads' front edges.
    pub rail_height: f32,
}

impl Staircase {
    /// The top of the flight, at the back edge of the last tread.
    pub fn top(&self) -> Vec3 {
        Vec3::new(0.0, self.steps as f32 * self.rise, self.steps as f32 * self.run)
    }

    /// The treads and risers, both stringers and both balustrades.
    pub fn mesh(&self) -> Mesh {
        let mut mesh = Mesh::new();
        for step in 0..self.steps {
            mesh.append(&self.step(step));
        }
        for side in [-1.0, 1.0] {
            mesh.append(&self.stringer(side));
            mesh.append(&self.balustrade(side));
        }
        mesh
    }

    /// Tread and riser of step `k` (from 0 at the bottom).
    fn step(&self, k: usize) -> Mesh {
        let (half, k) = (0.5 * self.width, k as f32);
        let tread = 0.25 * self.rise;
        let nosing = 0.12 * self.run;
        let top = (k + 1.0) * self.rise;
        let mut mesh = cuboid(
            Vec3::new(-half, top - tread, k * self.run - nosing),
            Vec3::new(half, top, (k + 1.0) * self.run),
        );
        mesh.append(&cuboid(
            Vec3::new(-half, k * self.rise, k * self.run),
            Vec3::new(half, top - tread, k * self.run + 0.1 * self.run),
        ));
        mesh
    }

    /// The slanted board carrying the steps' ends on the `side` (±1) of the flight.
    fn stringer(&self, side: f32) -> Mesh {
        let n = self.steps as f32;
        let inner = side * 0.5 * self.width;
        let outer = inner + side * 0.06 * self.width;
        let (x0, x1) = (inner.min(outer), inner.max(outer));
        let slope_top = (n - 1.0) * self.rise;
        let lift = self.rise + 0.3 * self.rise;
        hexahedron(std::array::from_fn(|i| {
            let x = if i & 1 == 0 { x0 } else { x1 };
            let (z, y) = if i & 4 == 0 {
                (0.0, 0.0)
            } else {
                (n * self.run, slope_top)
            };
            Vec3::new(x, y + if i & 2 == 0 { 0.0 } else { lift }, z)
        }))
    }

    /// One baluster on each tread and a handrail parallel to the pitch line through the
    /// treads' front edges; all balusters are the same height.
    fn balustrade(&self, side: f32) -> Mesh {
        let x = side * 0.44 * self.width;
        let bases: Vec<Vec3> = (0..self.steps)
            .map(|k| Vec3::new(x, (k + 1) as f32 * self.rise, (k as f32 + 0.5) * self.run))
            .collect();
        let pitch = |z: f32| self.rise + z * self.rise / self.run + self.rail_height;
        let top = self.top().z;
        let rail = [Vec3::new(x, pitch(0.0), 0.0), Vec3::new(x, pitch(top), top)];
        let mut mesh = balustrade(&bases, self.rail_height + 0.5 * self.rise, rail);
        let post = newel_post(self.rail_height + 1.5 * self.rise, 0.1 * self.rail_height);
        mesh.append_transformed(
            &post,
            Affine3A::from_translation(Vec3::new(x, 0.0, -0.3 * self.run)),
        );
        mesh
    }
}

/// A classical column `height` tall with a shaft of radius `radius`: a square plinth, a
/// moulded base, a shaft with `flutes` flutes and a slight entasis, a capital and an abacus.
/// About 7,900 triangles with 20 flutes.
pub fn column(height: f32, radius: f32, flutes: u32) -> Mesh {
    let r = radius;
    let plinth = 0.3 * r;
    let base_top = plinth + 0.6 * r;
    let capital = 0.7 * r;
    let shaft_top = height - capital;
    let mut mesh = cuboid(
        Vec3::new(-1.4 * r, 0.0, -1.4 * r),
        Vec3::new(1.4 * r, plinth, 1.4 * r),
    );
    mesh.append(&column_base(r, plinth, base_top));
    mesh.append(&fluted_shaft(r, base_top, shaft_top, flutes));
    mesh.append(&column_capital(r, shaft_top, height - 0.2 * r));
    mesh.append(&cuboid(
        Vec3::new(-1.35 * r, height - 0.2 * r, -1.35 * r),
        Vec3::new(1.35 * r, height, 1.35 * r),
    ));
    mesh
}

/// Points on the outer half of a round moulding (a torus's profile) of radius `r` at `centre`.
fn torus_moulding(centre: Vec2, r: f32, samples: usize) -> impl Iterator<Item = Vec2> {
    (0..=samples).map(move |i| {
        let angle = PI * (i as f32 / samples as f32 - 0.5);
        centre + r * Vec2::new(angle.cos(), angle.sin())
    })
}

/// The Attic base: two round mouldings with a hollow between them.
fn column_base(r: f32, bottom: f32, top: f32) -> Mesh {
    let h = top - bottom;
    let mut profile = vec![Vec2::new(0.0, bottom)];
    profile.extend(torus_moulding(
        Vec2::new(1.15 * r, bottom + 0.15 * h),
        0.15 * h,
        6,
    ));
    profile.extend([
        Vec2::new(1.0 * r, bottom + 0.4 * h),
        Vec2::new(1.06 * r, bottom + 0.55 * h),
    ]);
    profile.extend(torus_moulding(
        Vec2::new(1.05 * r, bottom + 0.72 * h),
        0.12 * h,
        6,
    ));
    profile.extend([Vec2::new(r, top), Vec2::new(0.0, top)]);
    lathe(&profile, 48)
}

/// A shaft tapering to 0.88·r at the top with a slight swelling, cut by `flutes` concave
/// flutes separated by narrow fillets.
fn fluted_shaft(r: f32, bottom: f32, top: f32, flutes: u32) -> Mesh {
    let rings = 14;
    let mut profile = vec![Vec2::new(0.0, bottom)];
    profile.extend((0..=rings).map(|i| {
        let t = i as f32 / rings as f32;
        let entasis = 1.0 - 0.12 * t * t + 0.03 * (PI * t).sin();
        Vec2::new(r * entasis, bottom + t * (top - bottom))
    }));
    profile.push(Vec2::new(0.0, top));
    let flute = move |angle: f32| {
        let u = (angle * flutes as f32 / TAU).fract();
        let w = (u - 0.5) / 0.38;
        1.0 - 0.07 * (1.0 - w * w).max(0.0).sqrt()
    };
    fluted_lathe(&profile, 8 * flutes as usize, flute)
}

/// The echinus: a cushion flaring from the shaft to the abacus, with a ring below it.
fn column_capital(r: f32, bottom: f32, top: f32) -> Mesh {
    let h = top - bottom;
    let mut profile = vec![Vec2::new(0.0, bottom), Vec2::new(0.88 * r, bottom)];
    profile.extend(torus_moulding(Vec2::new(0.9 * r, bottom + 0.12 * h), 0.08 * h, 4));
    profile.extend((0..=8).map(|i| {
        let t = i as f32 / 8.0;
        Vec2::new(
            r * (0.9 + 0.35 * (0.5 * PI * t).sin()),
            bottom + h * (0.25 + 0.75 * t),
        )
    }));
    profile.push(Vec2::new(0.0, top));
    lathe(&profile, 48)
}

/// A semicircular arch of inner radius `radius` in the xy plane, springing from y = 0 at
/// x = ±radius: a rib of `width` (radially) by `depth` (along z) with a narrower, deeper
/// moulded rib inside it. `samples` points along the curve.
pub fn arch(radius: f32, width: f32, depth: f32, samples: usize) -> Mesh {
    let rib = |inner: f32, outer: f32, depth: f32| {
        let corners = [(inner, -0.5), (outer, -0.5), (outer, 0.5), (inner, 0.5)];
        let at = |i: usize, r: f32, z: f32| {
            let angle = PI * i as f32 / (samples - 1) as f32;
            Vec3::new(r * angle.cos(), r * angle.sin(), z * depth)
        };
        let middle = 0.5 * (inner + outer);
        sweep(
            samples,
            4,
            |i, c| at(i, corners[c].0, corners[c].1),
            Ends::Fans(Some(at(0, middle, 0.0)), Some(at(samples - 1, middle, 0.0))),
        )
    };
    let mut mesh = rib(radius + 0.3 * width, radius + width, depth);
    mesh.append(&rib(radius, radius + 0.3 * width, 0.7 * depth));
    mesh
}

#[cfg(test)]
mod tests {
    use super::super::checks::unshared_edges;
    use super::*;

    #[test]
    fn turned_pieces_and_arches_are_closed() {
        for mesh in [
            baluster(1.0),
            newel_post(1.0, 0.1),
            column(6.0, 0.4, 20),
            arch(2.0, 0.4, 0.5, 16),
        ] {
            mesh.validate().unwrap();
            // Each part of a column or arch is closed on its own.
            assert!(unshared_edges(&mesh).is_empty());
        }
    }

    #[test]
    fn a_column_is_as_tall_as_asked_and_stands_on_the_floor() {
        let b = column(6.0, 0.4, 20).bounds();
        assert_eq!((b.min.y, b.max.y), (0.0, 6.0));
        assert!((b.max.x - 1.4 * 0.4).abs() < 1e-5);
    }

    #[test]
    fn the_staircase_reaches_its_top_and_its_rails_stay_above_the_treads() {
        let stairs = Staircase {
            steps: 10,
            rise: 0.2,
            run: 0.3,
            width: 1.2,
            rail_height: 0.9,
        };
        let mesh = stairs.mesh();
        mesh.validate().unwrap();
        let b = mesh.bounds();
        assert!((b.max.z - stairs.top().z).abs() < 0.1, "{b:?}");
        assert!(b.max.y > stairs.top().y + 0.9 && b.max.y < stairs.top().y + 1.3);
        assert_eq!(b.min.y, 0.0);
    }
}
