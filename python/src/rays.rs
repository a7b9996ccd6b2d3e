//! `Scene.primary_hits`, `Scene.hmd_at` and `Scene.cast`: rays the caller places.

use glam::Vec3;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use hmdist::accel::RayCaster;
use hmdist::estimators::Gather;
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};

use crate::camera::PyCamera;
use crate::convert::{named, py_error, value_error, vectors};
use crate::interrupt::interruptible;
use crate::scene::PyScene;

#[pymethods]
impl PyScene {
    /// Each pixel's first hit (spec §2) as flat float32 arrays: points [n, 3], normals [n, 3]
    /// (facing the camera), point error bounds [n, 3], triangles (int64 [n], -1 for
    /// background; then the other rows are NaN).
    fn primary_hits<'py>(
        &self,
        py: Python<'py>,
        camera: Option<PyCamera>,
        size: (u32, u32),
    ) -> PyResult<Bound<'py, PyDict>> {
        let size = camera.as_ref().map_or(size, |c| c.size);
        let accel = self.accel(py)?;
        let scene = self.seen_by(camera.as_ref());
        let scene = scene.as_ref();
        let gbuffer = py.detach(|| hmdist::render::primary_hits(accel, scene, size.0, size.1));
        let column = |f: &dyn Fn(&hmdist::accel::Hit) -> Vec3| -> Vec<f32> {
            gbuffer
                .points
                .iter()
                .flat_map(|h| h.map_or([f32::NAN; 3], |h| f(&h).to_array()))
                .collect()
        };
        let hits = PyDict::new(py);
        let n = gbuffer.points.len();
        hits.set_item(
            "points",
            PyArray1::from_vec(py, column(&|h| h.point)).reshape([n, 3])?,
        )?;
        hits.set_item(
            "normals",
            PyArray1::from_vec(py, column(&|h| h.normal)).reshape([n, 3])?,
        )?;
        hits.set_item(
            "point_errors",
            PyArray1::from_vec(py, column(&|h| h.point_error)).reshape([n, 3])?,
        )?;
        let triangles: Vec<i64> = gbuffer
            .points
            .iter()
            .map(|h| h.map_or(-1, |h| h.triangle as i64))
            .collect();
        hits.set_item("triangles", PyArray1::from_vec(py, triangles))?;
        Ok(hits)
    }

    /// H at points [n, 3] with normals [n, 3] (float64), float32 [n]: point i's random
    /// numbers keyed by `keys[i]` (uint64 [n]) or by i; optionally the triangle each lies on
    /// (uint64 [n]) and its error bound (float64 [n, 3]), as `primary_hits` gives them; the
    /// rays cast on `backend` (auto, gpu, gpu-software, cpu) with directions from `sampler`
    /// (sobol, grid), as `render`'s are.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (points, normals, rays, seed, keys, weighting, max_distance, triangles = None, errors = None, backend = "auto", sampler = "sobol"))]
    fn hmd_at<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        normals: PyReadonlyArray2<'py, f64>,
        rays: u32,
        seed: u64,
        keys: Option<PyReadonlyArray1<'py, u64>>,
        weighting: &str,
        max_distance: Option<f32>,
        triangles: Option<PyReadonlyArray1<'py, u64>>,
        errors: Option<PyReadonlyArray2<'py, f64>>,
        backend: &str,
        sampler: &str,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (p, n) = (vectors(&points)?, vectors(&normals)?);
        let triangles = match &triangles {
            Some(t) => Some(t.as_slice().map_err(|e| value_error(e.to_string()))?.to_vec()),
            None => None,
        };
        let errors = errors.as_ref().map(vectors).transpose()?;
        let surface = p
            .iter()
            .zip(&n)
            .enumerate()
            .map(|(i, (p, n))| {
                let mut point =
                    SurfacePoint::new(*p, *n).map_err(|e| value_error(format!("point {i}: {e}")))?;
                if let Some(t) = &triangles {
                    point = point.on_triangle(t[i] as u32);
                }
                if let Some(e) = &errors {
                    point = point.with_error_bound(e[i]);
                }
                Ok(point)
            })
            .collect::<PyResult<Vec<_>>>()?;
        let keys: Option<Vec<u64>> = match &keys {
            Some(k) => Some(k.as_slice().map_err(|e| value_error(e.to_string()))?.to_vec()),
            None => None,
        };
        let gather = Gather::new(rays, named("weighting", weighting)?)
            .map_err(py_error)?
            .with_backend(named("backend", backend)?)
            .with_sampler(named("sampler", sampler)?)
            .map_err(py_error)?;
        let query = PointQuery::new(gather, seed, max_distance).map_err(py_error)?;
        let accel = self.accel(py)?;
        let scene = &self.scene;
        let h = interruptible(py, || hmd_at(scene, accel, &query, &surface, keys.as_deref()))?
            .map_err(py_error)?;
        Ok(PyArray1::from_vec(py, h))
    }

    /// Distance to the first hit along each ray (float32 [n], +inf for a miss); directions
    /// need not be unit length.
    fn cast<'py>(
        &self,
        py: Python<'py>,
        origins: PyReadonlyArray2<'py, f64>,
        directions: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (o, d) = (vectors(&origins)?, vectors(&directions)?);
        let mut unit = Vec::with_capacity(d.len());
        for (i, d) in d.iter().enumerate() {
            let n = d.normalize_or_zero();
            if n == Vec3::ZERO {
                return Err(value_error(format!("directions[{i}] is zero")));
            }
            unit.push(n);
        }
        let accel = self.accel(py)?;
        let t: Vec<f32> = interruptible(py, || {
            use rayon::prelude::*;
            // In chunks, so that Ctrl-C stops it between them.
            let mut t = Vec::with_capacity(o.len());
            for (o, d) in o.chunks(1 << 16).zip(unit.chunks(1 << 16)) {
                if hmdist::interrupt::requested() {
                    break;
                }
                t.par_extend(
                    o.par_iter()
                        .zip(d)
                        .map(|(o, d)| accel.hit_distance(*o, *d, f32::INFINITY, None)),
                );
            }
            t
        })?;
        Ok(PyArray1::from_vec(py, t))
    }
}
