//! Scenes whose harmonic mean distance is known in closed form (spec §1), for tests and for
//! users who want to check an estimator on their own machine.
//!
//! - `sphere(R)`: the inside of a closed sphere; every point has `H = R` under cosine
//!   weighting (`1/d = 1/(2R cos θ)`, and `E[1/(2R cos θ)]` over `cos θ / π` is `1/R`).
//! - `slab(h)`: a floor and a ceiling `h` apart; `H = 3h/2` (cosine), `2h` (uniform) on the floor
//!   far from the edges.
//! - `dome(R)`: a hemispherical dome over a disc floor; at the centre of the floor `H = R`.

use std::f32::consts::PI;

use glam::Vec3;

use super::shapes;
use crate::scene::{Camera, Mesh, Scene};

/// Radius `R` of the built-in `sphere` scene: `H = R` everywhere (cosine weighting).
pub const SPHERE_RADIUS: f32 = 2.5;
/// Floor-to-ceiling height `h` of the built-in `slab` scene: `H = 3h/2` (cosine), `2h`
/// (uniform) on the floor far from the edges.
pub const SLAB_HEIGHT: f32 = 1.0;
/// Radius `R` of the built-in `dome` scene: `H = R` at the centre of the floor.
pub const DOME_RADIUS: f32 = 2.0;

/// The inside of an icosphere of radius `radius`, subdivided `subdivisions` times
/// (20·4^s triangles: 7 gives 327,680). The camera sits at the centre.
pub fn sphere(radius: f32, subdivisions: u32) -> Scene {
    let mesh = shapes::icosphere(subdivisions, Vec3::ZERO, radius);
    Scene {
        name: "sphere".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, 0.0),
            target: Vec3::new(0.0, -0.2, -1.0),
            up: Vec3::Y,
            fov_y_deg: 90.0,
            mirrored: false,
        },
        light: Some(crate::scene::SpotLight {
            position: Vec3::new(0.0, 0.8 * radius, 0.0),
            direction: Vec3::NEG_Y,
            cone_half_angle_deg: 60.0,
        }),
        display_scale: 0.5 / radius,
        notes: Default::default(),
    }
}

/// Two parallel squares `height` apart (floor at y = 0), `2·half_width` wide; the camera looks
/// straight down at the centre of the floor from half height.
pub fn slab(height: f32, half_width: f32) -> Scene {
    let mut mesh = Mesh::new();
    for y in [0.0, height] {
        let w = half_width;
        let first = mesh.add_vertices([
            Vec3::new(-w, y, -w),
            Vec3::new(w, y, -w),
            Vec3::new(w, y, w),
            Vec3::new(-w, y, w),
        ]);
        mesh.add_triangle(first, first + 1, first + 2);
        mesh.add_triangle(first, first + 2, first + 3);
    }
    Scene {
        name: "slab".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.0, 0.5 * height, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 60.0,
            mirrored: false,
        },
        light: None,
        display_scale: 0.25 / height,
        notes: Default::default(),
    }
}

/// A hemispherical dome of radius `radius` (`rings` latitude bands, `segments` around) closed
/// by a flat disc floor at y = 0 that shares the dome's rim vertices: a watertight room.
/// The camera looks straight down at the centre of the floor.
pub fn dome(radius: f32, segments: u32, rings: u32) -> Scene {
    let mut mesh = Mesh::new();
    // Rim ring first, so the floor and the dome share its vertices exactly.
    let rim = mesh.add_vertices((0..segments).map(|s| {
        let phi = 2.0 * PI * s as f32 / segments as f32;
        Vec3::new(radius * phi.cos(), 0.0, radius * phi.sin())
    }));
    let mut previous = rim;
    for ring in 1..rings {
        let theta = 0.5 * PI * ring as f32 / rings as f32; // elevation above the floor
        let first = mesh.add_vertices((0..segments).map(|s| {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            let r = radius * theta.cos();
            Vec3::new(r * phi.cos(), radius * theta.sin(), r * phi.sin())
        }));
        for s in 0..segments {
            let t = (s + 1) % segments;
            mesh.add_triangle(previous + s, first + s, first + t);
            mesh.add_triangle(previous + s, first + t, previous + t);
        }
        previous = first;
    }
    let top = mesh.add_vertices([Vec3::new(0.0, radius, 0.0)]);
    let floor_centre = mesh.add_vertices([Vec3::ZERO]);
    for s in 0..segments {
        let t = (s + 1) % segments;
        mesh.add_triangle(previous + s, top, previous + t);
        mesh.add_triangle(rim + t, floor_centre, rim + s);
    }
    Scene {
        name: "dome".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.0, 0.5 * radius, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 60.0,
            mirrored: false,
        },
        light: Some(crate::scene::SpotLight {
            position: Vec3::new(0.0, 0.9 * radius, 0.0),
            direction: Vec3::NEG_Y,
            cone_half_angle_deg: 60.0,
        }),
        display_scale: 0.25 / radius,
        notes: Default::default(),
    }
}
