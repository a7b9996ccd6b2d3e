//! Indexed triangle meshes.
//!
//! Units: scene units throughout (whatever the file used). Triangles are two-sided: their
//! winding is kept for export but never used to decide which side is "outside" (spec §1).

use glam::{Affine3A, Vec3};

use crate::error::{Error, Result};

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// The corner with the smallest coordinates.
    pub min: Vec3,
    /// The corner with the largest coordinates.
    pub max: Vec3,
}

impl Bounds {
    /// Bounds of no point (`min = +inf`, `max = −inf`): the first [`Bounds::grow`] sets both
    /// corners.
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// Grows the box to hold `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Length of the diagonal: `l_diag` of spec §1 and §4.
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    /// The centre of the box.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
}

/// A triangle soup with shared vertices: `indices[i]` names the three corners of triangle `i`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, in scene units.
    pub positions: Vec<Vec3>,
    /// Per triangle, the indices of its three corners in `positions`.
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.indices[i].map(|v| self.positions[v as usize])
    }

    /// Adds `vertices` and returns the index of the first, for building faces on top.
    pub fn add_vertices(&mut self, vertices: impl IntoIterator<Item = Vec3>) -> u32 {
        let first = self.positions.len() as u32;
        self.positions.extend(vertices);
        first
    }

    /// Adds the triangle with corners `a`, `b`, `c` (indices into `positions`).
    pub fn add_triangle(&mut self, a: u32, b: u32, c: u32) {
        self.indices.push([a, b, c]);
    }

    /// Appends `other`, keeping its triangles' shapes and order.
    pub fn append(&mut self, other: &Mesh) {
        let offset = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|v| v + offset)));
    }

    /// Appends `other` moved by `transform`.
    pub fn append_transformed(&mut self, other: &Mesh, transform: Affine3A) {
        let offset = self.positions.len() as u32;
        self.positions
            .extend(other.positions.iter().map(|&p| transform.transform_point3(p)));
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|v| v + offset)));
    }

    /// Moves every vertex by `transform`.
    pub fn transform(&mut self, transform: Affine3A) {
        for p in &mut self.positions {
            *p = transform.transform_point3(*p);
        }
    }

    /// Bounds of the vertices that triangles use.
    pub fn bounds(&self) -> Bounds {
        let mut b = Bounds::EMPTY;
        for t in &self.indices {
            for &v in t {
                b.grow(self.positions[v as usize]);
            }
        }
        b
    }

    /// Checks what the renderer relies on: at least one triangle, every index in range, every
    /// used vertex finite and within ±10¹⁸ (float32 geometry). The message names the first
    /// offender.
    pub fn validate(&self) -> Result<()> {
        /// Beyond this a squared distance or a cross product leaves float32's range (3.4e38).
        const MAX_COORDINATE: f32 = 1e18;
        if self.indices.is_empty() {
            return Err(Error::scene("the scene has no triangles"));
        }
        let n = self.positions.len();
        for (i, t) in self.indices.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::scene(format!(
                    "triangle {i} uses vertex {v}, but there are only {n} vertices"
                )));
            }
        }
        let used = {
            let mut used = vec![false; n];
            self.indices
                .iter()
                .flatten()
                .for_each(|&v| used[v as usize] = true);
            used
        };
        if let Some((v, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|&(v, p)| used[v] && !p.is_finite())
        {
            return Err(Error::scene(format!(
                "vertex {v} is not finite: ({}, {}, {})",
                p.x, p.y, p.z
            )));
        }
        if let Some((v, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|&(v, p)| used[v] && p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(Error::scene(format!(
                "vertex {v} at ({:e}, {:e}, {:e}) is too far out for float32 geometry: coordinates must stay within ±{MAX_COORDINATE:e} (scale the model down)",
                p.x, p.y, p.z
            )));
        }
        let diagonal = self.bounds().diagonal();
        if diagonal < MIN_DIAGONAL {
            return Err(Error::scene(format!(
                "the scene is {diagonal:e} across: too small for float32 geometry, whose ray offsets and \
                 d_min (1e-6 of the diagonal) need it at least {MIN_DIAGONAL:e} across (scale the model up)"
            )));
        }
        Ok(())
    }
}

/// The smallest bounding-box diagonal a scene may have: below it a squared distance (and
/// `d_min`'s square) leaves float32's normal range.
pub const MIN_DIAGONAL: f32 = 1e-15;
