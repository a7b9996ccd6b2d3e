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

/// H per pixel, texel rays cast and how many of them escaped.
pub fn estimate(
    cubemap: &Cubemap,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> (Vec<f32>, u64, u64) {
    let width = gbuffer.width as usize;
    let (cast, escaped) = (AtomicU64::new(0), AtomicU64::new(0));
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
                let (mut row_cast, mut row_escaped) = (0, 0);
                for (x, (h, point)) in out.iter_mut().zip(points).enumerate() {
                    let Some(hit) = point else { continue };
                    let pixel = (row * width + x) as u64;
                    let (value, c, e) = pixel_estimate(cubemap, context, cache, hit, pixel);
                    *h = value;
                    (row_cast, row_escaped) = (row_cast + c, row_escaped + e);
                }
                cast.fetch_add(row_cast, Ordering::Relaxed);
                escaped.fetch_add(row_escaped, Ordering::Relaxed);
                progress.advance(1);
            },
        );
    progress.finish();
    (hmd, cast.into_inner(), escaped.into_inner())
}

/// H at one pixel from its (lazily filled) hemicube; texel rays cast and escaped.
fn pixel_estimate(
    cubemap: &Cubemap,
    context: &EstimateContext,
    cache: &mut TexelCache,
    hit: &Hit,
    pixel: u64,
) -> (f32, u64, u64) {
    cache.current = cache.current.wrapping_add(1);
    if cache.current == 0 {
        cache.stamp.fill(0);
        cache.current = 1;
    }
    let hemicube: Hemicube = cubemap.hemicube;
    let origin = hit.spawn_origin(hit.normal);
    let frame = Frame::from_normal(hit.normal);
    let grid = strata(cubemap.gather.rays);
    let (mut cast, mut escaped) = (0, 0);
    let mut mean = HarmonicMean::default();
    for j in 0..cubemap.gather.rays {
        let w = cubemap.gather.local_direction(grid, context.seed, pixel, j);
        let (_, texel, along) = hemicube.lookup(w);
        if cache.stamp[texel] != cache.current {
            let (face, c) = hemicube.texel_direction(texel);
            let t = context
                .accel
                .hit_distance(origin, frame.to_world(c), f32::INFINITY, Some(hit.triangle));
            cast += 1;
            escaped += t.is_infinite() as u64;
            cache.depth[texel] = t * c.dot(face.axis());
            cache.stamp[texel] = cache.current;
        }
        mean.add(cache.depth[texel] / along, context.clamp);
    }
    (mean.value(), cast, escaped)
}
