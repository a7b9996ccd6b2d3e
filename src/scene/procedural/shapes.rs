//! Mesh building blocks for the procedural scenes `cube` and `hall` (spec §5).
//!
//! Units: scene units, y up. Every builder here returns a closed surface unless its doc says
//! otherwise: seams share vertices, and ends are closed by fans to a pole rather than by
//! collapsed rings, so there are no zero-area triangles. Winding is consistent within a
//! builder, but nothing relies on it: triangles are two-sided (spec §1).
//!
//! This file holds the primitives (sweeps, turnings, spheres, capsules, tubes, boxes); the
//! submodules build the scenes' objects from them: the room shell, figures, architecture,
//! furniture and ornaments.

pub mod architecture;
pub(crate) mod figure;
pub mod furniture;
pub mod ornaments;
pub mod room;

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Quat, Vec2, Vec3};

use crate::scene::Mesh;

/// An icosphere: an icosahedron subdivided `subdivisions` times, vertices pushed onto the
/// sphere. 20·4^s triangles; shared edges use shared vertices, so the surface is watertight.
#[rustfmt::skip]
pub fn icosphere(subdivisions: u32, center: Vec3, radius: f32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0), (1.0, t, 0.0), (-1.0, -t, 0.0), (1.0, -t, 0.0),
        (0.0, -1.0, t), (0.0, 1.0, t), (0.0, -1.0, -t), (0.0, 1.0, -t),
        (t, 0.0, -1.0), (t, 0.0, 1.0), (-t, 0.0, -1.0), (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut positions);
                let bc = midpoint(b, c, &mut positions);
                let ca = midpoint(c, a, &mut positions);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    Mesh {
        positions: positions.into_iter().map(|p| center + radius * p).collect(),
        indices: faces,
    }
}

/// How the two ends of a [`sweep`] are finished.
#[derive(Clone, Copy, Debug)]
pub enum Ends {
    /// The last ring joins back to the first: a closed loop, such as a torus or a knot.
    Loop,
    /// Each end is either left open (`None`) or closed by a fan of triangles to a point.
    Fans(Option<Vec3>, Option<Vec3>),
}

/// The surface through `rings` rings of `segments` points each, `point(ring, segment)`
/// giving the positions; each ring closes on itself, consecutive rings are joined by quads.
/// 2·segments triangles per band between rings, plus `segments` per fan.
pub fn sweep(rings: usize, segments: usize, mut point: impl FnMut(usize, usize) -> Vec3, ends: Ends) -> Mesh {
    let mut mesh = Mesh::new();
    mesh.positions.reserve(rings * segments + 2);
    for ring in 0..rings {
        for segment in 0..segments {
            mesh.positions.push(point(ring, segment));
        }
    }
    let index = |ring: usize, segment: usize| (ring * segments + segment % segments) as u32;
    let bands = match ends {
        Ends::Loop => rings,
        Ends::Fans(..) => rings - 1,
    };
    for ring in 0..bands {
        let next = (ring + 1) % rings;
        for s in 0..segments {
            let (a, b) = (index(ring, s), index(ring, s + 1));
            let (c, d) = (index(next, s + 1), index(next, s));
            mesh.add_triangle(a, b, c);
            mesh.add_triangle(a, c, d);
        }
    }
    if let Ends::Fans(start, end) = ends {
        if let Some(pole) = start {
            let pole = mesh.add_vertices([pole]);
            for s in 0..segments {
                mesh.add_triangle(pole, index(0, s + 1), index(0, s));
            }
        }
        if let Some(pole) = end {
            let pole = mesh.add_vertices([pole]);
            for s in 0..segments {
                mesh.add_triangle(pole, index(rings - 1, s), index(rings - 1, s + 1));
            }
        }
    }
    mesh
}

/// A turning: the surface of revolution about the y axis of `profile`, a list of
/// (radius, height) points from bottom to top. A profile point of radius 0 at either end is a
/// pole closing that end (a flat lid when it has the same height as its neighbour).
pub fn lathe(profile: &[Vec2], segments: usize) -> Mesh {
    fluted_lathe(profile, segments, |_| 1.0)
}

/// [`lathe`] of a profile written as (radius, height) fractions of `radius` and `height`: the
/// proportions of a turned piece, independent of its size.
pub fn turned(profile: &[(f32, f32)], radius: f32, height: f32, segments: usize) -> Mesh {
    let scaled: Vec<Vec2> = profile
        .iter()
        .map(|&(r, y)| Vec2::new(radius * r, height * y))
        .collect();
    lathe(&scaled, segments)
}

/// A turning whose radius is scaled by `flutes(angle)` around the circumference, for fluted
/// column shafts and ribbed vases; see [`lathe`].
pub fn fluted_lathe(profile: &[Vec2], segments: usize, flutes: impl Fn(f32) -> f32) -> Mesh {
    let on_axis = |p: &Vec2| p.x == 0.0;
    let start = profile.first().filter(|p| on_axis(p));
    let end = profile.last().filter(|p| on_axis(p));
    let rings = &profile[start.is_some() as usize..profile.len() - end.is_some() as usize];
    let scale: Vec<f32> = (0..segments)
        .map(|s| flutes(TAU * s as f32 / segments as f32))
        .collect();
    let pole = |p: &Vec2| Vec3::new(0.0, p.y, 0.0);
    sweep(
        rings.len(),
        segments,
        |ring, s| {
            let angle = TAU * s as f32 / segments as f32;
            let r = rings[ring].x * scale[s];
            Vec3::new(r * angle.cos(), rings[ring].y, -r * angle.sin())
        },
        Ends::Fans(start.map(pole), end.map(pole)),
    )
}

/// The unit sphere as `rings` latitude bands of `segments` quads, closed by fans at the poles.
/// 2·segments·(rings − 1) triangles.
pub fn uv_sphere(segments: usize, rings: usize) -> Mesh {
    let profile: Vec<Vec2> = (0..=rings)
        .map(|i| {
            let polar = PI * (rings - i) as f32 / rings as f32;
            if i == 0 || i == rings {
                Vec2::new(0.0, polar.cos())
            } else {
                Vec2::new(polar.sin(), polar.cos())
            }
        })
        .collect();
    lathe(&profile, segments)
}

/// An ellipsoid with semi-axes `radii` (before `rotation`) centred on `center`.
pub fn ellipsoid(center: Vec3, radii: Vec3, rotation: Quat, segments: usize, rings: usize) -> Mesh {
    let mut mesh = uv_sphere(segments, rings);
    mesh.transform(Affine3A::from_scale_rotation_translation(radii, rotation, center));
    mesh
}

/// A tapered capsule: a hemisphere of radius `radius_a` around `a`, one of radius `radius_b`
/// around `b`, and the cone between their equators. For limbs, fingers and toes.
/// `segments` points around; 4·segments·max(2, ⌊segments/4⌋) triangles.
pub fn capsule(a: Vec3, b: Vec3, radius_a: f32, radius_b: f32, segments: usize) -> Mesh {
    let axis = (b - a).normalize();
    let (u, v) = axis.any_orthonormal_pair();
    let cap_rings = (segments / 4).max(2);
    let around: Vec<Vec3> = (0..segments)
        .map(|s| {
            let angle = TAU * s as f32 / segments as f32;
            angle.cos() * u + angle.sin() * v
        })
        .collect();
    // Rings 0..cap_rings climb the hemisphere at `a` from its pole to its equator; the rest
    // descend the hemisphere at `b` from its equator to its pole.
    let ring_frame = |ring: usize| -> (Vec3, f32, f32) {
        if ring < cap_rings {
            let polar = 0.5 * PI * (ring + 1) as f32 / cap_rings as f32;
            (a, -radius_a * polar.cos(), radius_a * polar.sin())
        } else {
            let polar = 0.5 * PI * (2 * cap_rings - ring) as f32 / cap_rings as f32;
            (b, radius_b * polar.cos(), radius_b * polar.sin())
        }
    };
    sweep(
        2 * cap_rings,
        segments,
        |ring, s| {
            let (center, along, radius) = ring_frame(ring);
            center + along * axis + radius * around[s]
        },
        Ends::Fans(Some(a - radius_a * axis), Some(b + radius_b * axis)),
    )
}

/// A tube of radius `radius` along `path`: a loop when `closed`, otherwise open ends closed by
/// flat lids. The rings follow parallel-transported frames, so the tube does not twist; a
/// loop's leftover twist is spread evenly along it so that the seam matches.
pub fn tube(path: &[Vec3], radius: f32, segments: usize, closed: bool) -> Mesh {
    let n = path.len();
    let tangent = |i: usize| -> Vec3 {
        let (prev, next) = if closed {
            (path[(i + n - 1) % n], path[(i + 1) % n])
        } else {
            (path[i.saturating_sub(1)], path[(i + 1).min(n - 1)])
        };
        (next - prev).normalize()
    };
    let tangents: Vec<Vec3> = (0..n).map(tangent).collect();
    let mut normals = Vec::with_capacity(n);
    let mut normal = tangents[0].any_orthonormal_vector();
    for t in &tangents {
        normal = (normal - t.dot(normal) * *t).normalize();
        normals.push(normal);
    }
    let twist = if closed {
        let carried = (normal - tangents[0].dot(normal) * tangents[0]).normalize();
        let cross = carried.cross(normals[0]).dot(tangents[0]);
        cross.atan2(carried.dot(normals[0]))
    } else {
        0.0
    };
    sweep(
        n,
        segments,
        |i, s| {
            let angle = TAU * s as f32 / segments as f32 + twist * i as f32 / n as f32;
            let binormal = tangents[i].cross(normals[i]);
            path[i] + radius * (angle.cos() * normals[i] + angle.sin() * binormal)
        },
        if closed {
            Ends::Loop
        } else {
            Ends::Fans(Some(path[0]), Some(path[n - 1]))
        },
    )
}

/// A six-faced solid from its eight corners, corner `i` at the (x, y, z) extreme given by bits
/// 0, 1, 2 of `i`: boxes, slanted stringers, wedges. 12 triangles.
pub fn hexahedron(corners: [Vec3; 8]) -> Mesh {
    const QUADS: [[u32; 4]; 6] = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    let mut mesh = Mesh::new();
    mesh.add_vertices(corners);
    for [a, b, c, d] in QUADS {
        mesh.add_triangle(a, b, c);
        mesh.add_triangle(a, c, d);
    }
    mesh
}

/// The axis-aligned box from `min` to `max`. 12 triangles.
pub fn cuboid(min: Vec3, max: Vec3) -> Mesh {
    hexahedron(std::array::from_fn(|i| {
        Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), max, min)
    }))
}

/// Where an object built standing on the origin goes: scaled by `scale`, turned by `yaw`
/// radians about y, its origin moved to `at`.
pub fn placement(at: Vec3, yaw: f32, scale: f32) -> Affine3A {
    Affine3A::from_scale_rotation_translation(Vec3::splat(scale), Quat::from_rotation_y(yaw), at)
}

/// A pseudo-random number in [0, 1) from integers: the same on every machine (a fixed
/// integer hash, no state), for the scenes' deliberate irregularity.
pub fn unit_hash(a: i32, b: i32, c: i32, seed: u32) -> f32 {
    let mut h = seed ^ 0x9e37_79b9;
    for v in [a, b, c] {
        h ^= (v as u32).wrapping_mul(0x85eb_ca6b);
        h = h.rotate_left(13).wrapping_mul(0xc2b2_ae35);
        h ^= h >> 16;
    }
    h = h.wrapping_mul(0x27d4_eb2d);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Smooth value noise in [0, 1): [`unit_hash`] on the integer lattice, blended with a
/// smoothstep. For bumps on surfaces.
pub fn value_noise(p: Vec3, seed: u32) -> f32 {
    let cell = p.floor();
    let f = p - cell;
    let w = f * f * (Vec3::splat(3.0) - 2.0 * f);
    let [x, y, z] = [cell.x as i32, cell.y as i32, cell.z as i32];
    let corner = |dx: i32, dy: i32, dz: i32| unit_hash(x + dx, y + dy, z + dz, seed);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let edge = |dy: i32, dz: i32| lerp(corner(0, dy, dz), corner(1, dy, dz), w.x);
    let face = |dz: i32| lerp(edge(0, dz), edge(1, dz), w.y);
    lerp(face(0), face(1), w.z)
}

/// Checks on meshes that the scenes' tests share.
#[cfg(test)]
pub mod checks {
    use glam::Vec3;

    use crate::scene::{Bounds, Mesh};

    /// `p` lies strictly inside `b`.
    pub fn inside(b: Bounds, p: Vec3) -> bool {
        p.cmpgt(b.min).all() && p.cmplt(b.max).all()
    }

    /// The edges (vertex pairs, smaller first) used by other than exactly two triangles:
    /// empty for a closed, manifold surface.
    pub fn unshared_edges(mesh: &Mesh) -> Vec<(u32, u32)> {
        let mut uses = std::collections::HashMap::new();
        for t in &mesh.indices {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let mut edges: Vec<_> = uses
            .into_iter()
            .filter(|&(_, n)| n != 2)
            .map(|(e, _)| e)
            .collect();
        edges.sort_unstable();
        edges
    }

    /// How many triangles have (numerically) zero area.
    pub fn zero_area_triangles(mesh: &Mesh) -> usize {
        (0..mesh.triangle_count())
            .filter(|&i| {
                let [a, b, c] = mesh.triangle(i);
                (b - a).cross(c - a).length_squared() <= 0.0
            })
            .count()
    }
}
