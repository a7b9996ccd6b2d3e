//! Floating-point error bounds, in one place (pbrt-v4 §6.8).
//!
//! `gamma(n)` bounds the relative error of `n` successive f32 roundings. The hit point's error
//! bound feeds [`offset_ray_origin`], which moves a ray origin just far enough off the surface
//! that the ray cannot re-hit the surface it leaves: no epsilon tuned to one scene (spec §2).

use glam::Vec3;

/// Unit roundoff of f32: half the machine epsilon.
const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// `γ(n) = n·u / (1 − n·u)`: relative error bound of `n` f32 operations.
#[inline(always)]
pub const fn gamma(n: u32) -> f32 {
    (n as f32 * MACHINE_EPSILON) / (1.0 - n as f32 * MACHINE_EPSILON)
}

/// The next representable f32 above `v` (pbrt's `NextFloatUp`).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    f32::from_bits(if v >= 0.0 { bits + 1 } else { bits - 1 })
}

/// The next representable f32 below `v` (pbrt's `NextFloatDown`).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    -next_float_up(-v)
}

/// Origin for rays leaving a surface point `p` (with absolute error bound `p_error` per axis,
/// geometric normal `n`) towards the side of `n` that `w` points into (pbrt-v4
/// `OffsetRayOrigin`). The offset is along `n`, as short as the error bound allows, and
/// rounded away from `p` so that the origin is strictly on the correct side.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = d * n;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_float_steps_one_ulp() {
        assert_eq!(next_float_up(1.0), 1.0 + f32::EPSILON);
        assert_eq!(next_float_down(1.0), 1.0 - f32::EPSILON / 2.0);
        assert!(next_float_up(0.0) > 0.0);
        assert!(next_float_down(0.0) < 0.0);
    }

    #[test]
    fn offset_moves_to_the_side_the_ray_leaves_towards() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        let e = Vec3::splat(1e-6);
        let up = offset_ray_origin(p, e, Vec3::Y, Vec3::new(0.3, 0.9, 0.0));
        let down = offset_ray_origin(p, e, Vec3::Y, Vec3::new(0.3, -0.9, 0.0));
        assert!(up.y > p.y + 1e-6 && down.y < p.y - 1e-6);
        assert_eq!((up.x, up.z), (p.x, p.z));
    }
}
