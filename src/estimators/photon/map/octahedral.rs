//! Unit normals in 2 × u16: the octahedral encoding (Cigolle et al. 2014), error below 0.01°.

use glam::{Vec2, Vec3};

/// A unit vector as two 16-bit octahedral coordinates (Cigolle et al. 2014).
pub fn encode_octahedral(v: Vec3) -> [u16; 2] {
    let p = Vec2::new(v.x, v.y) / (v.x.abs() + v.y.abs() + v.z.abs());
    let p = if v.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * Vec2::new(p.x.signum(), p.y.signum())
    } else {
        p
    };
    let q = |c: f32| ((c.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0).round() as u16;
    [q(p.x), q(p.y)]
}

/// The unit vector of [`encode_octahedral`].
pub fn decode_octahedral(e: [u16; 2]) -> Vec3 {
    let p = Vec2::new(e[0] as f32, e[1] as f32) / 65535.0 * 2.0 - Vec2::ONE;
    let z = 1.0 - p.x.abs() - p.y.abs();
    let t = (-z).max(0.0);
    let x = p.x - t.copysign(p.x);
    let y = p.y - t.copysign(p.y);
    Vec3::new(x, y, z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::random_pair;

    #[test]
    fn octahedral_normals_round_trip_within_a_hundredth_of_a_degree() {
        for i in 0..100_000 {
            let u = random_pair(3, 0, i);
            let z = 2.0 * u.x - 1.0;
            let r = (1.0 - z * z).sqrt();
            let v = Vec3::new(r * (6.2831855 * u.y).cos(), r * (6.2831855 * u.y).sin(), z);
            let back = decode_octahedral(encode_octahedral(v));
            // The angle from |v × back| (a cosine this close to 1 rounds to 1 in f32).
            let angle = v.cross(back).length().asin().to_degrees();
            assert!(angle < 0.01 && back.dot(v) > 0.0, "{v} -> {back}: {angle}°");
        }
        for v in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
            assert!(decode_octahedral(encode_octahedral(v)).dot(v) > 0.99999);
        }
    }
}
