//! The CPU backend of the cube-map estimator: each texel holds what a ray through its centre
//! sees, which is what rasterisation stores there (SPEC §3.2).
//!
//! Only texels that some gather direction looks up are filled (a texel's depth does not
//! depend on which others are filled), so the cost is one ray per distinct texel looked up,
//! not `12R²` per pixel. The near plane at `d_min` is the clamp of every distance at `d_min`.

use super::Cubemap;
use crate::accel::{Hit, RayCaster};
use crate::estimators::{AovSample, EstimateContext, HarmonicMean, PixelPass, PixelWork, PixelWorker, Tally};
use crate::progress::Progress;
use crate::report::{CubemapDetails, Details, DeviceDetails, PhaseSeconds};
use crate::sampling::Frame;

/// The CPU cube map on one image.
pub(super) struct CpuPixels<'a> {
    pub cubemap: &'a Cubemap,
    pub context: &'a EstimateContext<'a>,
}

impl PixelWork for CpuPixels<'_> {
    fn label(&self) -> &'static str {
        "cube maps"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn record_phase(&self, phases: &mut PhaseSeconds, seconds: f64) {
        // A texel is filled at its first lookup: build and lookup interleave.
        phases.cubemap_build_and_lookup = Some(seconds);
    }

    fn worker<'w>(&'w self, _: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        let texels = self.cubemap.hemicube.texel_count();
        Box::new(TexelCache {
            pixels: self,
            depth: vec![0.0; texels],
            stamp: vec![0; texels],
            current: 0,
        })
    }

    fn details(&self, pass: &PixelPass) -> Details {
        Details {
            device: Some(DeviceDetails::cpu()),
            cubemap: Some(CubemapDetails {
                // The CPU fills only the texels that are looked up, one ray each.
                texels_rasterised: pass.tally.rays,
                texels_per_hemicube: self.cubemap.hemicube.texel_count() as u64,
                lookups: pass.pixels * self.cubemap.gather.rays_per_point() as u64,
                escaped_lookups: pass.tally.escaped_lookups,
            }),
            ..Details::default()
        }
    }
}

/// Per-worker texel cache: depth per texel, valid where `stamp` equals the current pixel's.
struct TexelCache<'a> {
    pixels: &'a CpuPixels<'a>,
    depth: Vec<f32>,
    stamp: Vec<u32>,
    current: u32,
}

impl PixelWorker for TexelCache<'_> {
    /// H at one pixel from its (lazily filled) hemicube.
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, _: &mut AovSample) -> f32 {
        let (cubemap, context) = (self.pixels.cubemap, self.pixels.context);
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.fill(0);
            self.current = 1;
        }
        let hemicube = cubemap.hemicube;
        let origin = hit.spawn_origin(hit.normal);
        let frame = Frame::from_normal(hit.normal);
        let mut mean = HarmonicMean::default();
        for (j, w) in cubemap.gather.directions(context.seed, pixel).enumerate() {
            if crate::interrupt::stop_at_ray(j) {
                break; // the pass ends with Error::Interrupted; this H is never seen
            }
            let (_, texel, along) = hemicube.lookup(w);
            if self.stamp[texel] != self.current {
                let (face, c) = hemicube.texel_direction(texel);
                let t =
                    context
                        .accel
                        .hit_distance(origin, frame.to_world(c), f32::INFINITY, Some(hit.triangle));
                tally.rays += 1;
                tally.escaped += t.is_infinite() as u64;
                self.depth[texel] = t * c.dot(face.axis());
                self.stamp[texel] = self.current;
            }
            let d = self.depth[texel] / along;
            tally.escaped_lookups += (d > context.clamp.max || d.is_infinite()) as u64;
            mean.add(d, context.clamp);
        }
        mean.value()
    }
}
