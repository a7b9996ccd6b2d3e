//! Hemicube geometry (spec §3.2; paper §2.2.3, Fig. 3–4), shared by the CPU and GPU backends.
//!
//! In the local frame of a surface point (z = normal, x = t, y = b) the hemicube has five
//! faces: the top face (axis +z, `2R × 2R` texels) and four side faces (axes ±x, ±y,
//! `2R × R` texels: their upper half). A texel stores the depth `t` along its face's axis of
//! the nearest surface through its centre. A direction `ω` looks up the face of its largest
//! component, the texel it falls in, and converts the stored depth to a distance along `ω`:
//! `d = t / (ω · axis)` (the paper's `t / f(θ, φ)`).

use glam::Vec3;

/// The five faces, in texel-index order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    /// Axis +z (the normal): `2R × 2R` texels.
    Top,
    /// Axis +x (the tangent `t`): `2R × R` texels.
    PosX,
    /// Axis −x: `2R × R` texels.
    NegX,
    /// Axis +y (the bitangent `b`): `2R × R` texels.
    PosY,
    /// Axis −y: `2R × R` texels.
    NegY,
}

/// All five faces, in texel-index order.
pub const FACES: [Face; 5] = [Face::Top, Face::PosX, Face::NegX, Face::PosY, Face::NegY];

impl Face {
    /// The face's axis in the local frame.
    pub fn axis(self) -> Vec3 {
        match self {
            Face::Top => Vec3::Z,
            Face::PosX => Vec3::X,
            Face::NegX => Vec3::NEG_X,
            Face::PosY => Vec3::Y,
            Face::NegY => Vec3::NEG_Y,
        }
    }

    /// The face's two in-plane directions (u across, v up), local frame. On the side faces v
    /// is the normal, so rows count up from the horizon.
    pub fn plane(self) -> (Vec3, Vec3) {
        match self {
            Face::Top => (Vec3::X, Vec3::Y),
            Face::PosX => (Vec3::Y, Vec3::Z),
            Face::NegX => (Vec3::NEG_Y, Vec3::Z),
            Face::PosY => (Vec3::NEG_X, Vec3::Z),
            Face::NegY => (Vec3::X, Vec3::Z),
        }
    }
}

/// A hemicube of per-quadrant resolution `R`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hemicube {
    /// `R`: texels across half a face; the top face is `2R × 2R`, each side face `2R × R`.
    pub resolution: u32,
}

impl Hemicube {
    /// Texel columns × rows of `face`.
    pub fn face_size(&self, face: Face) -> (u32, u32) {
        let r = self.resolution;
        if face == Face::Top {
            (2 * r, 2 * r)
        } else {
            (2 * r, r)
        }
    }

    /// Texels of the whole hemicube: `4R² + 4 · 2R² = 12R²`.
    pub fn texel_count(&self) -> usize {
        12 * (self.resolution as usize).pow(2)
    }

    /// Index of the first texel of `face`.
    fn face_offset(&self, face: Face) -> usize {
        let r2 = (self.resolution as usize).pow(2);
        match face {
            Face::Top => 0,
            Face::PosX => 4 * r2,
            Face::NegX => 6 * r2,
            Face::PosY => 8 * r2,
            Face::NegY => 10 * r2,
        }
    }

    /// The face and texel index a local direction `w` (z ≥ 0) falls in, and `w · axis`.
    #[inline]
    pub fn lookup(&self, w: Vec3) -> (Face, usize, f32) {
        let a = w.abs();
        let face = if w.z >= a.x && w.z >= a.y {
            Face::Top
        } else if a.x >= a.y {
            if w.x > 0.0 {
                Face::PosX
            } else {
                Face::NegX
            }
        } else if w.y > 0.0 {
            Face::PosY
        } else {
            Face::NegY
        };
        let along = w.dot(face.axis());
        let (u, v) = face.plane();
        // Plane coordinates in [-1, 1] (top) or [-1, 1] × [0, 1] (sides).
        let (s, t) = (w.dot(u) / along, w.dot(v) / along);
        let (cols, rows) = self.face_size(face);
        let col = (((s + 1.0) * 0.5 * cols as f32) as u32).min(cols - 1);
        let row = if face == Face::Top {
            (((t + 1.0) * 0.5 * rows as f32) as u32).min(rows - 1)
        } else {
            ((t * rows as f32) as u32).min(rows - 1)
        };
        (face, self.face_offset(face) + (row * cols + col) as usize, along)
    }

    /// The unit local direction through the centre of texel `index`, with its face.
    pub fn texel_direction(&self, index: usize) -> (Face, Vec3) {
        let face = *FACES
            .iter()
            .rev()
            .find(|&&f| self.face_offset(f) <= index)
            .expect("texel index in range");
        let (cols, rows) = self.face_size(face);
        let local = (index - self.face_offset(face)) as u32;
        let (col, row) = (local % cols, local / cols);
        let s = (col as f32 + 0.5) / cols as f32 * 2.0 - 1.0;
        let t = if face == Face::Top {
            (row as f32 + 0.5) / rows as f32 * 2.0 - 1.0
        } else {
            (row as f32 + 0.5) / rows as f32
        };
        let (u, v) = face.plane();
        (face, (face.axis() + s * u + t * v).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{hemisphere, random_pair, Weighting};

    #[test]
    fn every_texel_centre_looks_itself_up() {
        for r in [1, 4, 16] {
            let cube = Hemicube { resolution: r };
            for i in 0..cube.texel_count() {
                let (face, w) = cube.texel_direction(i);
                let (found, index, along) = cube.lookup(w);
                assert_eq!((found, index), (face, i), "R = {r}, texel {i}");
                assert!((along - w.dot(face.axis())).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn directions_fall_in_the_texels_worked_out_by_hand() {
        // R = 2: the top face is 4 × 4 texels (indices 0..16), each side face 4 × 2 (+x from
        // 16, −x from 24, +y from 32, −y from 40). A face's texel (col, row) has index
        // offset + 4·row + col; col counts along the face's u, row along its v, from −1 (top
        // face) or from the horizon (side faces, v = z). In-plane coordinates (s, t) are the
        // direction divided by its component along the axis; col = ⌊(s + 1)·2⌋ and
        // row = ⌊(t + 1)·2⌋ (top) or ⌊2t⌋ (sides).
        let cube = Hemicube { resolution: 2 };
        let cases = [
            // top: u = x, v = y; s = 0.6, t = −0.4: col 3, row 1.
            (Vec3::new(0.6, -0.4, 1.0), Face::Top, 4 + 3),
            // +x: u = y, v = z; s = 0.2, t = 0.3: col 2, row 0.
            (Vec3::new(1.0, 0.2, 0.3), Face::PosX, 16 + 2),
            // −x: u = −y, v = z; s = −0.2, t = 0.6: col 1, row 1.
            (Vec3::new(-1.0, 0.2, 0.6), Face::NegX, 24 + 4 + 1),
            // +y: u = −x, v = z; s = −0.3, t = 0.1: col 1, row 0.
            (Vec3::new(0.3, 1.0, 0.1), Face::PosY, 32 + 1),
            // −y: u = x, v = z; s = 0.9, t = 0.7: col 3, row 1.
            (Vec3::new(0.9, -1.0, 0.7), Face::NegY, 40 + 4 + 3),
        ];
        for (w, face, index) in cases {
            let w = w.normalize();
            let (found, i, along) = cube.lookup(w);
            assert_eq!((found, i), (face, index), "direction {w}");
            assert!((along - w.abs().max_element()).abs() < 1e-6);
        }
    }

    #[test]
    fn the_texel_found_contains_the_direction() {
        // In the face's plane (the direction divided by its component along the axis) the
        // direction lies within half a texel (1/R wide) of the texel centre it looks up.
        for r in [1, 3, 16] {
            let cube = Hemicube { resolution: r };
            for j in 0..20_000 {
                let w = hemisphere(Weighting::Uniform, random_pair(9, r as u64, j));
                let (face, index, along) = cube.lookup(w);
                let (centre_face, c) = cube.texel_direction(index);
                assert_eq!(face, centre_face);
                let offset = w / along - c / c.dot(face.axis());
                assert!(
                    offset.abs().max_element() <= 0.5 / r as f32 + 1e-5,
                    "R = {r}: {w} is {offset} from its texel's centre"
                );
            }
        }
    }

    #[test]
    fn hemisphere_directions_spread_over_all_faces_and_stay_in_range() {
        let cube = Hemicube { resolution: 8 };
        let mut hits = vec![0; cube.texel_count()];
        for j in 0..200_000 {
            let w = hemisphere(Weighting::Uniform, random_pair(5, 0, j));
            let (face, index, along) = cube.lookup(w);
            assert!(along > 0.0 && along <= 1.0 + 1e-6, "{face:?} {along}");
            hits[index] += 1;
        }
        assert!(
            hits.iter().all(|&h| h > 0),
            "every texel is looked up by some direction"
        );
    }
}
