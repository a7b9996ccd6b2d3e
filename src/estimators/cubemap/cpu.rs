//! The CPU backend of the cube-map estimator: each texel holds what a ray through its centre
//! sees, which is what rasterisation stores there (SPEC §3.2).
//!
//! Only texels that some gather direction looks up are filled (a texel's depth does not
//! depend on which others are filled), so the cost is one ray per distinct texel looked up,
//! not `12R²` per pixel. The near plane at `d_min` is the clamp of every distance at `d_min`.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::hemicube::Hemicube;
use super::Cubemap;
use crate::accel::{Hit, RayCaster};
use crate::estimators::{EstimateContext, GBuffer, HarmonicMean};
use crate::progress::Progress;
use crate::sampling::{strata, Frame};

/// Per-worker texel cache: depth per texel, valid where `stamp` equals the current pixel's.
struct TexelCache {
    depth: Vec<f32>,
    stamp: Vec<u32>,
    current: u32,
}

/// What the CPU backend measured over the whole image.
pub struct CpuEstimate {
    pub hmd: Vec<f32>,
    /// Rays cast to fill texels: one per texel looked up, per pixel.
    pub texel_rays: u64,
    /// Texel rays that met nothing.
    pub escaped_texel_rays: u64,
    /// Lookups (pixel, direction) whose texel holds no surface within `--max-distance`.
    pub escaped_lookups: u64,
}

/// Counts of one pixel or row, summed into a [`CpuEstimate`].
#[derive(Clone, Copy, Default)]
struct Counts {
    texel_rays: u64,
    escaped_texel_rays: u64,
    escaped_lookups: u64,
}

impl std::ops::AddAssign for Counts {
    fn add_assign(&mut self, other: Counts) {
        self.texel_rays += other.texel_rays;
        self.escaped_texel_rays += other.escaped_texel_rays;
        self.escaped_lookups += other.escaped_lookups;
    }
}

/// H per pixel and the counts of [`CpuEstimate`].
pub fn estimate(
    cubemap: &Cubemap,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> CpuEstimate {
    let width = gbuffer.width as usize;
    let [cast, escaped, escaped_lookups] = [(); 3].map(|_| AtomicU64::new(0));
    let texels = cubemap.hemicube.texel_count();
    let mut hmd = vec![f32::NAN; gbuffer.points.len()];
    progress.start("cube maps", gbuffer.height as u64);
    hmd.par_chunks_mut(width)
        .zip(gbuffer.points.par_chunks(width))
        .enumerate()
        .for_each_init(
            || TexelCache {
                depth: vec![0.0; texels],
                stamp: vec![0; texels],
                current: 0,
            },
            |cache, (row, (out, points))| {
                let mut counts = Counts::default();
                for (x, (h, point)) in out.iter_mut().zip(points).enumerate() {
                    let Some(hit) = point else { continue };
                    let pixel = (row * width + x) as u64;
                    let (value, c) = pixel_estimate(cubemap, context, cache, hit, pixel);
                    *h = value;
                    counts += c;
                }
                cast.fetch_add(counts.texel_rays, Ordering::Relaxed);
                escaped.fetch_add(counts.escaped_texel_rays, Ordering::Relaxed);
                escaped_lookups.fetch_add(counts.escaped_lookups, Ordering::Relaxed);
                progress.advance(1);
            },
        );
    progress.finish();
    CpuEstimate {
        hmd,
        texel_rays: cast.into_inner(),
        escaped_texel_rays: escaped.into_inner(),
        escaped_lookups: escaped_lookups.into_inner(),
    }
}

/// H at one pixel from its (lazily filled) hemicube, and its counts.
fn pixel_estimate(
    cubemap: &Cubemap,
    context: &EstimateContext,
    cache: &mut TexelCache,
    hit: &Hit,
    pixel: u64,
) -> (f32, Counts) {
    cache.current = cache.current.wrapping_add(1);
    if cache.current == 0 {
        cache.stamp.fill(0);
        cache.current = 1;
    }
    let hemicube: Hemicube = cubemap.hemicube;
    let origin = hit.spawn_origin(hit.normal);
    let frame = Frame::from_normal(hit.normal);
    let grid = strata(cubemap.gather.rays);
    let mut counts = Counts::default();
    let mut mean = HarmonicMean::default();
    for j in 0..cubemap.gather.rays {
        let w = cubemap.gather.local_direction(grid, context.seed, pixel, j);
        let (_, texel, along) = hemicube.lookup(w);
        if cache.stamp[texel] != cache.current {
            let (face, c) = hemicube.texel_direction(texel);
            let t = context
                .accel
                .hit_distance(origin, frame.to_world(c), f32::INFINITY, Some(hit.triangle));
            counts.texel_rays += 1;
            counts.escaped_texel_rays += t.is_infinite() as u64;
            cache.depth[texel] = t * c.dot(face.axis());
            cache.stamp[texel] = cache.current;
        }
        let d = cache.depth[texel] / along;
        counts.escaped_lookups += (d > context.clamp.max || d.is_infinite()) as u64;
        mean.add(d, context.clamp);
    }
    (mean.value(), counts)
}
