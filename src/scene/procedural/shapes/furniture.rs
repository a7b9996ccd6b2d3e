//! Furniture of the hall (spec §5): tables and chairs with turned legs and spindles, and
//! chandeliers hanging on chains. Many thin parts close to each other and to the floor.
//!
//! Units: scene units read as metres (a table is 0.78 high), y up; each piece stands (or, for
//! a chandelier, hangs) at the origin and is placed by its caller.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Quat, Vec3};

use super::architecture::baluster;
use super::{cuboid, tube, turned};
use crate::scene::Mesh;

/// A turned leg `height` tall and `radius` at its widest: a plain block at the top, a vase
/// and rings below. 416 triangles.
pub fn turned_leg(height: f32, radius: f32) -> Mesh {
    let profile = [
        (0.0, 0.0),
        (0.6, 0.0),
        (0.7, 0.03),
        (0.55, 0.08),
        (0.65, 0.25),
        (0.8, 0.4),
        (0.6, 0.55),
        (0.5, 0.6),
        (0.75, 0.64),
        (0.75, 0.67),
        (0.55, 0.7),
        (0.95, 0.74),
        (1.0, 0.8),
        (1.0, 1.0),
        (0.0, 1.0),
    ];
    turned(&profile, radius, height, 16)
}

fn at(x: f32, y: f32, z: f32) -> Affine3A {
    Affine3A::from_translation(Vec3::new(x, y, z))
}

/// The four corners (±x, ±z) of a rectangle.
const CORNERS: [(f32, f32); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

/// A rectangular table `width` (x) by `depth` (z), `height` tall: a top, an apron of four
/// boards and four turned legs.
pub fn table(width: f32, depth: f32, height: f32) -> Mesh {
    let (w, d, top) = (0.5 * width, 0.5 * depth, height - 0.04);
    let mut mesh = cuboid(Vec3::new(-w, top, -d), Vec3::new(w, height, d));
    let (w, d, apron, board) = (w - 0.08, d - 0.08, top - 0.1, 0.012);
    for s in [-1.0, 1.0] {
        let (x, z) = (s * w, s * d);
        mesh.append(&cuboid(
            Vec3::new(-w, apron, z - board),
            Vec3::new(w, top, z + board),
        ));
        mesh.append(&cuboid(
            Vec3::new(x - board, apron, -d),
            Vec3::new(x + board, top, d),
        ));
    }
    let leg = turned_leg(top, 0.04);
    for (sx, sz) in CORNERS {
        mesh.append_transformed(&leg, at(sx * w, 0.0, sz * d));
    }
    mesh
}

/// A chair facing +z, seat 0.45 high: turned legs joined by side stretchers, and a back of
/// two posts, a top rail and five turned spindles. 0.98 high.
pub fn chair() -> Mesh {
    let (w, seat, top_rail) = (0.22, 0.45, 0.86);
    let mut mesh = cuboid(Vec3::new(-w, seat - 0.03, -w), Vec3::new(w, seat, w));
    let (leg, inset) = (turned_leg(seat - 0.03, 0.025), w - 0.03);
    for (sx, sz) in CORNERS {
        mesh.append_transformed(&leg, at(sx * inset, 0.0, sz * inset));
    }
    for s in [-1.0, 1.0] {
        let ends = [
            Vec3::new(s * inset, 0.15, -inset),
            Vec3::new(s * inset, 0.15, inset),
        ];
        mesh.append(&tube(&ends, 0.01, 8, false));
    }
    let back = -w + 0.02;
    let post_profile = [
        (0.0, 0.0),
        (0.75, 0.0),
        (0.75, 0.9),
        (1.0, 0.92),
        (0.5, 1.0),
        (0.0, 1.0),
    ];
    let post = turned(&post_profile, 0.024, 0.98 - seat, 12);
    for s in [-1.0, 1.0] {
        mesh.append_transformed(&post, at(s * (w - 0.02), seat, back));
    }
    let rail = (
        Vec3::new(-w + 0.02, top_rail, back - 0.015),
        Vec3::new(w - 0.02, 0.94, back + 0.015),
    );
    mesh.append(&cuboid(rail.0, rail.1));
    let spindle = baluster(top_rail - seat);
    let slim = Vec3::new(0.3, 1.0, 0.3);
    for k in 0..5 {
        let x = (k as f32 - 2.0) * 0.065;
        let place = Affine3A::from_scale_rotation_translation(slim, Quat::IDENTITY, Vec3::new(x, seat, back));
        mesh.append_transformed(&spindle, place);
    }
    mesh
}

/// A chandelier hanging `drop` below the origin (the ceiling point): a chain of links, a
/// turned stem, `arms` curved arms out to a ring of radius `radius`, a candle on each arm.
pub fn chandelier(drop: f32, radius: f32, arms: usize) -> Mesh {
    let bottom = -drop;
    let stem_height = 0.9;
    let mut mesh = chain(bottom + stem_height, 0.06);
    let stem = [
        (0.0, 0.0),
        (0.4, 0.0),
        (1.0, 0.11),
        (0.4, 0.24),
        (0.33, 0.55),
        (0.75, 0.67),
        (0.33, 0.83),
        (0.25, 1.0),
        (0.0, 1.0),
    ];
    mesh.append_transformed(&turned(&stem, 0.12, stem_height, 24), at(0.0, bottom, 0.0));
    let ring: Vec<Vec3> = (0..96)
        .map(|i| {
            let a = TAU * i as f32 / 96.0;
            Vec3::new(radius * a.cos(), bottom + 0.15, radius * a.sin())
        })
        .collect();
    mesh.append(&tube(&ring, 0.02, 8, true));
    let candle = [
        (0.0, 0.0),
        (0.8, 0.0),
        (1.0, 0.14),
        (0.4, 0.23),
        (0.37, 0.93),
        (0.2, 0.98),
        (0.0, 1.0),
    ];
    let candle = turned(&candle, 0.06, 0.215, 12);
    for k in 0..arms {
        let a = TAU * (k as f32 + 0.5) / arms as f32;
        let out = Vec3::new(a.cos(), 0.0, a.sin());
        // An S-curve from the stem down and out to the ring.
        let arm: Vec<Vec3> = (0..=16)
            .map(|i| {
                let t = i as f32 / 16.0;
                let rise = 0.45 - 0.3 * t + 0.12 * (PI * t).sin();
                out * (0.08 + t * (radius - 0.08)) + Vec3::new(0.0, bottom + rise, 0.0)
            })
            .collect();
        mesh.append(&tube(&arm, 0.015, 8, false));
        mesh.append_transformed(&candle, Affine3A::from_translation(arm[16]));
    }
    mesh
}

/// Oval links `size` wide, each a quarter turn from the last, hanging from the origin down
/// to height `bottom` (negative).
fn chain(bottom: f32, size: f32) -> Mesh {
    let (pitch, reach) = (1.4 * size, 1.12 * size);
    let links = ((-bottom - reach) / pitch).floor().max(1.0) as usize;
    let oval: Vec<Vec3> = (0..16)
        .map(|i| {
            let a = TAU * i as f32 / 16.0;
            Vec3::new(0.5 * size * a.cos(), size * a.sin(), 0.0)
        })
        .collect();
    let link = tube(&oval, 0.12 * size, 6, true);
    let mut mesh = Mesh::new();
    for k in 0..links {
        let turn = Quat::from_rotation_y(0.5 * PI * (k % 2) as f32);
        let centre = Vec3::new(0.0, -reach - k as f32 * pitch, 0.0);
        mesh.append_transformed(&link, Affine3A::from_rotation_translation(turn, centre));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn furniture_stands_on_the_floor_and_a_chandelier_hangs_below_the_ceiling() {
        for (mesh, height) in [(table(1.6, 0.9, 0.78), 0.78), (chair(), 0.98)] {
            mesh.validate().unwrap();
            let b = mesh.bounds();
            assert_eq!(b.min.y, 0.0);
            assert!((b.max.y - height).abs() < 1e-4, "{b:?}");
        }
        let b = chandelier(3.0, 0.7, 8).bounds();
        assert!(b.max.y <= 0.0 && b.max.y > -0.1, "{b:?}");
        assert!(b.min.y >= -3.0 && b.max.x < 0.8);
    }
}
