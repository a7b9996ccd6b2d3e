//! `gather`: ray-traced final gathering (SPEC §3.1; paper §3.1).
//!
//! `N` rays per pixel, stratified on the most nearly square `a × b` grid, jittered, mapped to
//! the hemisphere around the camera-facing normal by the chosen weighting; `H = N / Σ 1/d`.
//! Random numbers are keyed by (seed, pixel index, ray index), so the image is the same
//! whatever the thread count or tiling.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;

use super::{Estimate, EstimateContext, Estimator, GBuffer, HarmonicMean, RayCount};
use crate::accel::{Hit, RayCaster};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::sampling::{hemisphere, random_pair, strata, stratified, Frame, Weighting};

/// Default gather rays per pixel for `hmdist render`: an 8 × 8 stratified grid, a clean
/// picture of `cube` at 1024² in about 20 s on 2 cores. The paper's reference uses 65,536;
/// its accuracy levels off from about 1,024.
pub const DEFAULT_RAYS: u32 = 64;

/// Final gathering with `rays` rays per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Gather {
    pub rays: u32,
    pub weighting: Weighting,
}

impl Gather {
    pub fn new(rays: u32, weighting: Weighting) -> Result<Self> {
        if rays == 0 {
            return Err(Error::parameter("--rays must be at least 1"));
        }
        Ok(Gather { rays, weighting })
    }

    /// Gather direction `j` of a pixel in its local frame (z = normal): shared with the
    /// cube-map estimator, which looks the same directions up in its hemicube (SPEC §3.2).
    #[inline]
    pub fn local_direction(&self, grid: (u32, u32), seed: u64, pixel: u64, j: u32) -> glam::Vec3 {
        let u = stratified(j, grid, random_pair(seed, pixel, j as u64));
        hemisphere(self.weighting, u)
    }

    /// The gather rays of pixel `pixel` from its surface point: the origin (offset off the
    /// surface) and the world-space directions, exactly the rays [`Gather::pixel`] casts.
    #[inline]
    pub fn rays(
        &self,
        hit: &Hit,
        seed: u64,
        pixel: u64,
    ) -> (glam::Vec3, impl Iterator<Item = glam::Vec3> + '_) {
        let origin = hit.spawn_origin(hit.normal);
        let frame = Frame::from_normal(hit.normal);
        let grid = strata(self.rays);
        let directions =
            (0..self.rays).map(move |j| frame.to_world(self.local_direction(grid, seed, pixel, j)));
        (origin, directions)
    }

    /// H at one surface point, and how many of its rays escaped.
    pub fn pixel<R: RayCaster>(
        &self,
        accel: &R,
        context: &EstimateContext,
        hit: &Hit,
        pixel: u64,
    ) -> (f32, u32) {
        let (origin, directions) = self.rays(hit, context.seed, pixel);
        let mut mean = HarmonicMean::default();
        let mut escaped = 0;
        for dir in directions {
            let d = accel.hit_distance(origin, dir, context.clamp.max, Some(hit.triangle));
            escaped += d.is_infinite() as u32;
            mean.add(d, context.clamp);
        }
        (mean.value(), escaped)
    }
}

impl Estimator for Gather {
    fn method(&self) -> &'static str {
        "gather"
    }

    fn parameters(&self) -> serde_json::Map<String, serde_json::Value> {
        let grid = strata(self.rays);
        let value = json!({
            "rays": self.rays,
            "weighting": self.weighting.name(),
            "strata": [grid.0, grid.1],
        });
        super::fields(value)
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        pixels * self.rays as u64
    }

    fn estimate(
        &self,
        context: &EstimateContext,
        gbuffer: &GBuffer,
        progress: &dyn Progress,
    ) -> Result<Estimate> {
        let start = Instant::now();
        let width = gbuffer.width as usize;
        let escaped = AtomicU64::new(0);
        let mut hmd = vec![f32::NAN; gbuffer.points.len()];
        progress.start("gather", gbuffer.height as u64);
        hmd.par_chunks_mut(width)
            .zip(gbuffer.points.par_chunks(width))
            .enumerate()
            .for_each(|(row, (out, points))| {
                let mut row_escaped = 0u64;
                for (x, (h, point)) in out.iter_mut().zip(points).enumerate() {
                    if let Some(hit) = point {
                        let pixel = (row * width + x) as u64;
                        let (value, e) = self.pixel(context.accel, context, hit, pixel);
                        *h = value;
                        row_escaped += e as u64;
                    }
                }
                escaped.fetch_add(row_escaped, Ordering::Relaxed);
                progress.advance(1);
            });
        progress.finish();
        let surface_pixels = (gbuffer.points.len() - gbuffer.background_pixels()) as u64;
        let seconds = start.elapsed().as_secs_f64();
        Ok(Estimate {
            hmd,
            rays: Some(RayCount {
                cast: surface_pixels * self.rays as u64,
                escaped: escaped.into_inner(),
                seconds,
            }),
            phases: vec![("estimate", seconds)],
            extra: Default::default(),
        })
    }
}
