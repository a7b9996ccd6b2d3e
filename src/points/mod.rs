//! H at arbitrary surface points (spec §8), for a caller that chooses its own points, such as
//! an irradiance cache placing records.
//!
//! Each point is gathered exactly as an image's pixel is ([`Gather`]), with its random
//! numbers keyed by a caller-given key instead of the pixel index: results do not depend on
//! how points are batched, and points taken from an image's own primary hits
//! ([`SurfacePoint::from_hit`]) with keys = pixel indices give that image's H bit for bit.
//!
//! A ray leaving a surface starts just off it, by the floating-point error bound of the point
//! ([`crate::accel::offset_ray_origin`]). A [`SurfacePoint::from_hit`] carries its hit's exact
//! bound; a point on a named triangle ([`SurfacePoint::on_triangle`]) gets the bound of any
//! point interpolated on that triangle, and the rays know which triangle they leave; a bare
//! point gets the bound of any point interpolated in the scene's bounding box. Larger bounds
//! move origins further off the surface (by about 1e-6 of the coordinates' magnitude).
//!
//! [`mod@file`] reads and writes the point files of `hmdist points`.

pub mod file;

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::float_error::gamma;
use crate::accel::GatherStart;
use crate::accel::{Accel, Hit};
use crate::error::{Error, Result};
use crate::estimators::{DistanceClamp, Gather};
use crate::scene::Scene;

/// A point on a surface and the normal of the side it is seen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    point: Vec3,
    normal: Vec3,
    triangle: Option<u32>,
    /// The point's absolute error bound per axis, where known exactly (from a hit).
    error: Option<Vec3>,
}

impl SurfacePoint {
    /// A point and its normal, used as given: the gather samples the hemisphere the normal
    /// points into. The normal is made unit length where it is not already (within 1e-6);
    /// a non-finite coordinate or a zero normal is refused.
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self> {
        if !point.is_finite() || !normal.is_finite() {
            let message = format!("must be finite, not {point} with normal {normal}");
            return Err(Error::invalid("points", message));
        }
        // A normal already of unit length is kept bit for bit (H at an image's points is the
        // image's H); any other is scaled first, so that no length overflows or underflows.
        let normal = if (normal.length_squared() - 1.0).abs() <= 1e-6 {
            normal
        } else {
            crate::sampling::unit(normal).ok_or_else(|| {
                Error::invalid(
                    "points",
                    format!("must have a non-zero normal, not {normal} at {point}"),
                )
            })?
        };
        Ok(SurfacePoint {
            point,
            normal,
            triangle: None,
            error: None,
        })
    }

    /// The point lies on triangle `triangle` of the scene's mesh: its rays know which
    /// triangle they leave, and the origin offset is bounded by that triangle's corners.
    pub fn on_triangle(self, triangle: u32) -> Self {
        SurfacePoint {
            triangle: Some(triangle),
            ..self
        }
    }

    /// The point's absolute floating-point error bound per axis is `error` (as a hit reports
    /// it, [`crate::accel::Hit::point_error`]): its rays start exactly as the hit's would.
    pub fn with_error_bound(self, error: Vec3) -> Self {
        SurfacePoint {
            error: Some(error),
            ..self
        }
    }

    /// A ray hit, with its exact error bound and triangle, and its normal as it is (in a
    /// G-buffer from [`crate::render::primary_hits`], facing the camera).
    pub fn from_hit(hit: &Hit) -> Self {
        SurfacePoint {
            point: hit.point,
            normal: hit.normal,
            triangle: Some(hit.triangle),
            error: Some(hit.point_error),
        }
    }

    /// The point.
    pub fn point(&self) -> Vec3 {
        self.point
    }

    /// The unit normal.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// Where its gather starts in `scene`.
    fn start(&self, scene: &Scene, scene_extent: Vec3) -> Result<GatherStart> {
        let error = match (self.error, self.triangle) {
            (Some(error), _) => error,
            (None, Some(t)) => {
                if t as usize >= scene.mesh.triangle_count() {
                    let message = format!(
                        "{t} is not a triangle of scene '{}', which has {}",
                        scene.name,
                        scene.mesh.triangle_count()
                    );
                    return Err(Error::invalid("triangle", message));
                }
                let [a, b, c] = scene.mesh.triangle(t as usize);
                interpolation_error(a.abs().max(b.abs()).max(c.abs()), self.point)
            }
            (None, None) => interpolation_error(scene_extent, self.point),
        };
        Ok(GatherStart {
            origin: crate::accel::offset_ray_origin(self.point, error, self.normal, self.normal),
            frame: crate::sampling::Frame::from_normal(self.normal),
            leaving: self.triangle,
        })
    }
}

/// The error bound of a point interpolated from corners no larger than `corners` per axis
/// (pbrt-v4 §6.8.5: `γ(7) Σ |b_i p_i| ≤ γ(7) max |p_i|`), or than the point itself.
fn interpolation_error(corners: Vec3, point: Vec3) -> Vec3 {
    gamma(7) * corners.max(point.abs())
}

/// How to gather at points: the rays, the seed and the distance clamp, checked.
#[derive(Clone, Copy, Debug)]
pub struct PointQuery {
    gather: Gather,
    seed: u64,
    max_distance: Option<f32>,
}

impl PointQuery {
    /// `gather`'s rays with random numbers of `seed`, distances clamped at `max_distance`
    /// (positive; `None` for no clamp), as `hmdist render` does with the same values.
    pub fn new(gather: Gather, seed: u64, max_distance: Option<f32>) -> Result<Self> {
        Error::check_positive("max_distance", max_distance)?;
        Ok(PointQuery {
            gather,
            seed,
            max_distance,
        })
    }
}

/// H at each point of `scene` (whose BVH is `accel`): point `i`'s random numbers are keyed
/// by `keys[i]`, or by `i` where `keys` is `None`. `+inf` where every ray escaped. Runs on
/// the current rayon pool, whose size does not change the result; or on the GPU, as the
/// query's [`Gather::with_backend`] says.
pub fn hmd_at(
    scene: &Scene,
    accel: &Accel,
    query: &PointQuery,
    points: &[SurfacePoint],
    keys: Option<&[u64]>,
) -> Result<Vec<f32>> {
    if let Some(keys) = keys {
        if keys.len() != points.len() {
            let message = format!("are {}, for {} points", keys.len(), points.len());
            return Err(Error::invalid("keys", message));
        }
    }
    scene.validate()?;
    let bounds = scene.bounds();
    let extent = bounds.min.abs().max(bounds.max.abs());
    let clamp = DistanceClamp::for_diagonal(bounds.diagonal(), query.max_distance);
    let starts = points
        .iter()
        .map(|p| p.start(scene, extent))
        .collect::<Result<Vec<_>>>()?;
    #[cfg(feature = "gpu")]
    if let Some(gpu) = query.gather.gpu(accel)? {
        let job = query.gather.gpu_job(query.seed, clamp, None);
        let key = |i: usize| keys.map_or(i as u64, |k| k[i]);
        let silent = &crate::progress::Silent;
        let done = crate::gpu::gather::gather_points(&gpu, &job, &starts, key, silent, |p| {
            query.gather.point_from_gpu(None, p).mean.value()
        })?;
        return Ok(done.points);
    }
    let hmd = starts
        .par_iter()
        .enumerate()
        .map(|(i, start)| {
            if crate::interrupt::requested() {
                return f32::NAN;
            }
            let key = keys.map_or(i as u64, |k| k[i]);
            query.gather.at(accel, start, query.seed, key, clamp).0
        })
        .collect();
    crate::interrupt::check()?;
    Ok(hmd)
}
