//! What the pbrt-v4 and Mitsuba 3 readers share: a scene put together shape by shape (each
//! shape's triangles placed by its own matrix and counted by its source), the quadrics
//! (spheres, disks, cylinders) tessellated once the scene's size is known, and a camera from
//! the frame a renderer's camera matrix gives.
//!
//! **Quadrics** are tessellated so that no edge's chord strays more than [`CHORD_ERROR`] of the
//! scene's bounding-box diagonal from its arc (the sagitta `r (1 − cos(Δφ/2))` of each
//! segment, `r` the shape's radius as its matrix scales it; a face's middle, curved both
//! ways on a sphere, within twice that), with at least [`MIN_SEGMENTS`] segments a full circle
//! and at most [`MAX_SEGMENTS`]. A full circle's seam and a sphere's poles share
//! their vertices, so the tessellation is closed where the shape is.

use glam::{DMat4, DVec3};

use crate::error::{Error, Result};
use crate::scene::{Bounds, Camera, Mesh, SceneNotes};

/// The largest distance between a quadric and its triangles, as a fraction of the scene's
/// bounding-box diagonal.
pub const CHORD_ERROR: f64 = 2e-4;
/// The fewest segments a full circle of a quadric gets.
pub const MIN_SEGMENTS: usize = 12;
/// The most segments a full circle of a quadric gets (a sphere: this × half of it).
pub const MAX_SEGMENTS: usize = 1024;

/// A sphere, disk or cylinder in its own space, as pbrt and Mitsuba define them (z is the axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quadric {
    /// Centred at the origin, cut to `z_min ≤ z ≤ z_max` and `0 ≤ φ ≤ phi_max`.
    Sphere {
        radius: f64,
        z_min: f64,
        z_max: f64,
        phi_max: f64,
    },
    /// At `z = height`, between radii `inner` and `radius`, `0 ≤ φ ≤ phi_max`.
    Disk {
        height: f64,
        radius: f64,
        inner: f64,
        phi_max: f64,
    },
    /// Around z from `z_min` to `z_max`, open at both ends, `0 ≤ φ ≤ phi_max`.
    Cylinder {
        radius: f64,
        z_min: f64,
        z_max: f64,
        phi_max: f64,
    },
}

impl Quadric {
    /// Refuses a quadric with no surface, naming what makes it empty.
    pub fn check(&self) -> std::result::Result<(), String> {
        let problem = match *self {
            Quadric::Sphere { radius, .. }
            | Quadric::Disk { radius, .. }
            | Quadric::Cylinder { radius, .. }
                if radius.is_nan() || radius <= 0.0 =>
            {
                format!("its radius must be positive, not {radius}")
            }
            Quadric::Sphere { z_min, z_max, .. } if z_min.is_nan() || z_max.is_nan() || z_min >= z_max => {
                format!("its zmin ({z_min}) must be below its zmax ({z_max})")
            }
            Quadric::Cylinder { z_min, z_max, .. } if z_min == z_max => {
                format!("its zmin and zmax ({z_min}) must differ")
            }
            Quadric::Disk { radius, inner, .. } if !(0.0..radius).contains(&inner) => {
                format!("its inner radius ({inner}) must be from 0 to below its radius ({radius})")
            }
            _ => return Ok(()),
        };
        Err(format!("the {} is empty: {problem}", self.name()))
    }

    /// The shape's name: "sphere", "disk" or "cylinder".
    pub fn name(&self) -> &'static str {
        match self {
            Quadric::Sphere { .. } => "sphere",
            Quadric::Disk { .. } => "disk",
            Quadric::Cylinder { .. } => "cylinder",
        }
    }
}

/// Triangles or a quadric, placed, waiting to be added (to the scene, or to an object that
/// instances copy).
#[derive(Clone)]
pub enum Piece {
    Triangles {
        source: String,
        positions: Vec<DVec3>,
        indices: Vec<[u32; 3]>,
        to_world: DMat4,
    },
    Quadric {
        source: String,
        quadric: Quadric,
        to_world: DMat4,
    },
}

impl Piece {
    /// The piece placed by `m` after its own matrix.
    pub fn placed(&self, m: &DMat4) -> Piece {
        let mut piece = self.clone();
        match &mut piece {
            Piece::Triangles { to_world, .. } | Piece::Quadric { to_world, .. } => *to_world = *m * *to_world,
        }
        piece
    }
}

/// A scene being put together: the mesh so far (in world space), the quadrics waiting for
/// the scene's size, and the notes.
#[derive(Default)]
pub struct Assembly {
    mesh: Mesh,
    quadrics: Vec<(Quadric, DMat4, String)>,
    /// What the file said and what became of it.
    pub notes: SceneNotes,
}

impl Assembly {
    /// Adds triangles `indices` over `positions` (object space), placed by `to_world`, counted
    /// for `source`. Indices must be in range (the readers check them, naming the file).
    pub fn add_triangles(
        &mut self,
        source: &str,
        positions: &[DVec3],
        indices: &[[u32; 3]],
        to_world: &DMat4,
    ) -> Result<()> {
        let first = self.mesh.positions.len();
        if first + positions.len() > u32::MAX as usize {
            return Err(Error::scene(
                "the scene has more than 2^32 vertices: more than hmdist can hold",
            ));
        }
        self.mesh
            .positions
            .extend(positions.iter().map(|&p| to_world.transform_point3(p).as_vec3()));
        let first = first as u32;
        self.mesh
            .indices
            .extend(indices.iter().map(|t| t.map(|v| v + first)));
        self.notes.add_source(source, indices.len());
        Ok(())
    }

    /// Adds `piece`, placed by `placed_by` after its own matrix (an instance's transform, or
    /// the identity).
    pub fn add(&mut self, piece: &Piece, placed_by: &DMat4) -> Result<()> {
        match piece {
            Piece::Triangles {
                source,
                positions,
                indices,
                to_world,
            } => self.add_triangles(source, positions, indices, &(*placed_by * *to_world)),
            Piece::Quadric {
                source,
                quadric,
                to_world,
            } => {
                self.add_quadric(source, *quadric, *placed_by * *to_world);
                Ok(())
            }
        }
    }

    /// Adds a quadric placed by `to_world`, tessellated by [`Assembly::finish`].
    pub fn add_quadric(&mut self, source: &str, quadric: Quadric, to_world: DMat4) {
        self.quadrics.push((quadric, to_world, source.to_string()));
    }

    /// The bounds of what has been added: the triangles, and each quadric's box.
    pub fn bounds(&self) -> Bounds {
        let mut bounds = self.mesh.bounds();
        for (q, m, _) in &self.quadrics {
            let (r, z0, z1) = match *q {
                Quadric::Sphere {
                    radius, z_min, z_max, ..
                } => (radius, z_min, z_max),
                Quadric::Disk { height, radius, .. } => (radius, height, height),
                Quadric::Cylinder {
                    radius, z_min, z_max, ..
                } => (radius, z_min, z_max),
            };
            for corner in 0..8 {
                let pick = |bit: usize, lo: f64, hi: f64| if corner >> bit & 1 == 0 { lo } else { hi };
                let local = DVec3::new(pick(0, -r, r), pick(1, -r, r), pick(2, z0, z1));
                bounds.grow(m.transform_point3(local).as_vec3());
            }
        }
        bounds
    }

    /// The scene loaded from `path`: [`Assembly::finish`]'s mesh and notes, with `camera`,
    /// `light` and the file's image `size`.
    pub fn into_scene(
        self,
        path: &std::path::Path,
        camera: Camera,
        light: Option<crate::scene::SpotLight>,
        size: Option<(u32, u32)>,
    ) -> Result<crate::scene::Scene> {
        let (mesh, mut notes) = self.finish().map_err(|e| super::common::in_file(path, e))?;
        notes.size = size;
        let bounds = mesh.bounds();
        Ok(crate::scene::Scene {
            name: super::common::file_name(path),
            mesh,
            camera,
            light,
            display_scale: crate::scene::default_display_scale(bounds),
            notes,
        })
    }

    /// The mesh, with every quadric tessellated to [`CHORD_ERROR`] of the whole scene's
    /// diagonal, and the notes.
    pub fn finish(mut self) -> Result<(Mesh, SceneNotes)> {
        let tolerance = CHORD_ERROR * self.bounds().diagonal() as f64;
        for (quadric, to_world, source) in std::mem::take(&mut self.quadrics) {
            let (positions, indices) = tessellate(quadric, &to_world, tolerance);
            self.add_triangles(&source, &positions, &indices, &to_world)?;
        }
        Ok((self.mesh, self.notes))
    }
}

/// How many segments an arc of `angle` radians and radius `radius` needs for its chords to
/// stay within `tolerance` of it.
fn segments(angle: f64, radius: f64, tolerance: f64) -> usize {
    let full = if tolerance > 0.0 && tolerance < radius {
        (std::f64::consts::PI / (1.0 - tolerance / radius).acos()).ceil()
    } else {
        0.0
    };
    let full = (full as usize).clamp(MIN_SEGMENTS, MAX_SEGMENTS);
    ((full as f64 * angle / std::f64::consts::TAU).ceil() as usize).max(1)
}

/// The largest factor by which `m` stretches a length (an upper bound: its longest column).
fn stretch(m: &DMat4) -> f64 {
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|c| c.truncate().length())
        .fold(0.0, f64::max)
}

/// A quadric's triangles in its own space, its chords within `tolerance` once placed by
/// `to_world`.
fn tessellate(quadric: Quadric, to_world: &DMat4, tolerance: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let scale = stretch(to_world);
    let mut grid = Grid::default();
    match quadric {
        Quadric::Sphere {
            radius,
            z_min,
            z_max,
            phi_max,
        } => {
            let (z0, z1) = (z_min.max(-radius), z_max.min(radius));
            let theta0 = (z1 / radius).clamp(-1.0, 1.0).acos();
            let theta1 = (z0 / radius).clamp(-1.0, 1.0).acos();
            let around = segments(phi_max, radius * scale, tolerance);
            let rings = segments(theta1 - theta0, radius * scale, tolerance);
            grid.build(rings, around, phi_max, |i, phi| {
                let theta = theta0 + (theta1 - theta0) * i as f64 / rings as f64;
                let (s, c) = theta.sin_cos();
                // A pole is one point whatever φ.
                let s = if i == 0 && theta0 == 0.0 || i == rings && theta1 == std::f64::consts::PI {
                    0.0
                } else {
                    s
                };
                DVec3::new(radius * s * phi.cos(), radius * s * phi.sin(), radius * c)
            });
        }
        Quadric::Disk {
            height,
            radius,
            inner,
            phi_max,
        } => {
            let around = segments(phi_max, radius * scale, tolerance);
            grid.build(1, around, phi_max, |i, phi| {
                let r = if i == 0 { radius } else { inner };
                DVec3::new(r * phi.cos(), r * phi.sin(), height)
            });
        }
        Quadric::Cylinder {
            radius,
            z_min,
            z_max,
            phi_max,
        } => {
            let around = segments(phi_max, radius * scale, tolerance);
            grid.build(1, around, phi_max, |i, phi| {
                let z = if i == 0 { z_max } else { z_min };
                DVec3::new(radius * phi.cos(), radius * phi.sin(), z)
            });
        }
    }
    (grid.positions, grid.indices)
}

/// Rows × columns of vertices over (row, φ), sharing the seam of a full circle and collapsing
/// a row of one point (a pole, a disk's centre) to one vertex.
#[derive(Default)]
struct Grid {
    positions: Vec<DVec3>,
    indices: Vec<[u32; 3]>,
}

impl Grid {
    fn build(&mut self, rows: usize, around: usize, phi_max: f64, at: impl Fn(usize, f64) -> DVec3) {
        let full = phi_max >= std::f64::consts::TAU;
        let columns = if full { around } else { around + 1 };
        let mut row_vertices: Vec<Vec<u32>> = Vec::with_capacity(rows + 1);
        for i in 0..=rows {
            let points: Vec<DVec3> = (0..columns)
                .map(|j| at(i, phi_max.min(std::f64::consts::TAU) * j as f64 / around as f64))
                .collect();
            let first = self.positions.len() as u32;
            if points.iter().all(|p| *p == points[0]) {
                self.positions.push(points[0]);
                row_vertices.push(vec![first; columns]);
            } else {
                self.positions.extend(&points);
                row_vertices.push((first..first + columns as u32).collect());
            }
        }
        for i in 0..rows {
            let (a, b) = (&row_vertices[i], &row_vertices[i + 1]);
            for j in 0..around {
                let k = (j + 1) % columns;
                for t in [[a[j], b[j], b[k]], [a[j], b[k], a[k]]] {
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        self.indices.push(t);
                    }
                }
            }
        }
    }
}

/// A renderer's camera as hmdist's: at `eye`, looking along `forward`, with `up` its picture's
/// up and `right` its picture's right (world vectors, any length). Where `right` is
/// `up × forward` rather than hmdist's `forward × up`, the camera is [`Camera::mirrored`].
pub fn camera_from_frame(eye: DVec3, right: DVec3, up: DVec3, forward: DVec3, fov_y_deg: f64) -> Camera {
    Camera {
        eye: eye.as_vec3(),
        target: (eye + forward.normalize_or_zero()).as_vec3(),
        up: up.normalize_or_zero().as_vec3(),
        fov_y_deg: fov_y_deg as f32,
        mirrored: forward.cross(up).dot(right) < 0.0,
    }
}
