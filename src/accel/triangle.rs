//! Watertight ray/triangle intersection (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1); as in pbrt-v4 `IntersectTriangle`).
//!
//! Why not Möller–Trumbore (obvhs's default): it evaluates each edge from different
//! intermediate quantities in the two triangles that share it, so a ray through a shared edge
//! can miss both. Here the ray is transformed so it runs along +z from the origin and each edge
//! function is a 2D cross product of the two *same* transformed vertices in both triangles:
//! the two triangles get exactly negated values, so one of them is hit. Exact zeros are
//! re-evaluated in f64. Surfaces are two-sided: both windings are accepted.
//!
//! A hit closer than the error bound of its own `t` is flagged `within_error`: its sign cannot
//! be trusted (pbrt-v4 rejects such hits; see [`super::bvh`] for what we do with them).

use glam::{Vec3, Vec3A};

use super::float_error::gamma;

/// Per-ray constants of the watertight test: the axis permutation and the shear that maps the
/// ray direction onto +z.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub(crate) origin: Vec3A,
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
}

/// Where a ray hits a triangle: distance and barycentric weights of the three corners.
#[derive(Clone, Copy, Debug)]
pub struct TriangleHit {
    pub t: f32,
    pub b: [f32; 3],
    /// `t` is within its own error bound (pbrt-v4 §6.8.7): the hit may be behind the origin.
    pub within_error: bool,
}

impl WatertightRay {
    /// `direction` need not be normalised; `t` is then in units of its length.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        let kz = direction.abs().max_position();
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        let d = Vec3::new(direction[kx], direction[ky], direction[kz]);
        WatertightRay {
            origin: origin.into(),
            kx,
            ky,
            kz,
            sx: -d.x / d.z,
            sy: -d.y / d.z,
            sz: 1.0 / d.z,
        }
    }

    /// The hit with triangle `(p0, p1, p2)` at `0 < t < t_max`, if any.
    #[inline(always)]
    pub fn intersect(&self, p0: Vec3A, p1: Vec3A, p2: Vec3A, t_max: f32) -> Option<TriangleHit> {
        // Translate to the ray origin, permute so the dominant axis is z, shear onto +z.
        let (a, b, c) = (p0 - self.origin, p1 - self.origin, p2 - self.origin);
        let (ax, ay, az) = (a[self.kx], a[self.ky], a[self.kz]);
        let (bx, by, bz) = (b[self.kx], b[self.ky], b[self.kz]);
        let (cx, cy, cz) = (c[self.kx], c[self.ky], c[self.kz]);
        let (ax, ay) = (ax + self.sx * az, ay + self.sy * az);
        let (bx, by) = (bx + self.sx * bz, by + self.sy * bz);
        let (cx, cy) = (cx + self.sx * cz, cy + self.sy * cz);

        let mut e0 = bx * cy - by * cx;
        let mut e1 = cx * ay - cy * ax;
        let mut e2 = ax * by - ay * bx;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            let product = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
            e0 = product(bx, cy, by, cx);
            e1 = product(cx, ay, cy, ax);
            e2 = product(ax, by, ay, bx);
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return None;
        }

        let (az, bz, cz) = (az * self.sz, bz * self.sz, cz * self.sz);
        let t_scaled = e0 * az + e1 * bz + e2 * cz;
        let outside = if det < 0.0 {
            t_scaled >= 0.0 || t_scaled < t_max * det
        } else {
            t_scaled <= 0.0 || t_scaled > t_max * det
        };
        if outside {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;

        // The error bound of t (pbrt-v4 §6.8.7).
        let max_zt = az.abs().max(bz.abs()).max(cz.abs());
        let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
        let max_yt = ay.abs().max(by.abs()).max(cy.abs());
        let delta_z = gamma(3) * max_zt;
        let delta_x = gamma(5) * (max_xt + max_zt);
        let delta_y = gamma(5) * (max_yt + max_zt);
        let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
        Some(TriangleHit {
            t,
            b: [e0 * inv_det, e1 * inv_det, e2 * inv_det],
            within_error: t <= delta_t,
        })
    }
}

/// Absolute error bound of the point `b0·p0 + b1·p1 + b2·p2` (pbrt-v4 §6.8.5).
#[inline]
pub fn barycentric_point_error(b: [f32; 3], p: [Vec3; 3]) -> Vec3 {
    gamma(7) * ((b[0] * p[0]).abs() + (b[1] * p[1]).abs() + (b[2] * p[2]).abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3A {
        Vec3A::new(x, y, z)
    }

    #[test]
    fn hits_both_windings_at_the_right_distance() {
        let ray = WatertightRay::new(Vec3::new(0.2, 0.2, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let (a, b, c) = (v(0.0, 0.0, 1.0), v(1.0, 0.0, 1.0), v(0.0, 1.0, 1.0));
        for hit in [
            ray.intersect(a, b, c, f32::INFINITY),
            ray.intersect(a, c, b, f32::INFINITY),
        ] {
            let hit = hit.expect("hit");
            assert!((hit.t - 4.0).abs() < 1e-6);
            let p = hit.b[0] * a + hit.b[1] * b + hit.b[2] * c;
            assert!((p - v(0.2, 0.2, 1.0)).length() < 1e-6);
        }
        assert!(ray.intersect(a, b, c, 3.9).is_none(), "beyond t_max");
    }

    #[test]
    fn ray_through_a_shared_edge_hits_one_of_the_two_triangles() {
        // A quad split along its diagonal; rays aimed exactly at points of the diagonal.
        let (a, b, c, d) = (
            v(-1.0, -1.0, 0.0),
            v(1.0, -1.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(-1.0, 1.0, 0.0),
        );
        let origin = Vec3::new(0.3, -0.7, 2.0);
        for i in 0..1000 {
            let s = -1.0 + 2.0 * i as f32 / 999.0;
            let dir = Vec3::new(s, s, 0.0) - origin;
            let ray = WatertightRay::new(origin, dir);
            let hits = ray.intersect(a, b, c, f32::INFINITY).is_some() as u32
                + ray.intersect(a, c, d, f32::INFINITY).is_some() as u32;
            assert!(hits >= 1, "ray {i} slipped through the shared edge");
        }
    }

    #[test]
    fn a_ray_leaving_a_triangle_from_its_surface_cannot_trust_a_rehit() {
        let (a, b, c) = (v(0.0, 0.0, 3.0), v(7.0, 1.0, 3.0), v(1.0, 5.0, 3.1));
        let p = 0.3 * a + 0.3 * b + 0.4 * c;
        let ray = WatertightRay::new(p.into(), Vec3::new(0.9, 0.1, 0.05));
        assert!(ray
            .intersect(a, b, c, f32::INFINITY)
            .is_none_or(|hit| hit.within_error));
        // The same point seen from a little way off the surface is a trustworthy hit, at the
        // distance travelled (so the test above cannot pass by never hitting anything).
        let normal = Vec3::from((b - a).cross(c - a)).normalize();
        for d in [1e-2f32, 1e-3] {
            let hit = WatertightRay::new(Vec3::from(p) + d * normal, -normal)
                .intersect(a, b, c, f32::INFINITY)
                .expect("a hit from just off the surface");
            assert!(
                !hit.within_error && (hit.t - d).abs() < 1e-5,
                "t = {} for {d}",
                hit.t
            );
        }
    }
}
