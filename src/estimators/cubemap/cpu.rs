//! The CPU backend of the cube-map estimator: each texel holds what a ray through its centre
//! sees, which is what rasterisation stores there (spec §3.2).
//!
//! Only texels that some gather direction looks up are filled (a texel's depth does not
//! depend on which others are filled), so the cost is one ray per distinct texel looked up,
//! not `12R²` per pixel. A pixel's lookups are made first, the texels they need collected in
//! the order of first lookup (the strata's order: neighbouring directions); those are then
//! cast eight at a time, as packets ([`RayCaster::hit_distances`]: bit for bit the single
//! rays), and the lookups read them. Measured on `cube` (96² × 4,096, 2 threads, 3 interleaved
//! runs): 6.7–7.7 s against 8.5–10.6 s casting each texel at its first lookup; casting the
//! texels sorted by index (face rows) was slower, 8.4–9.7 s. The near plane at `d_min` is the
//! clamp of every distance at `d_min`.
//!
//! **Several N at once** ([`sweep`]): cube maps of one resolution and seed at several ray
//! counts share each pixel's hemicube, so one pass fills the texels any of them looks up once,
//! and gives every N the image (and ray, texel and lookup counts) a render at that N alone
//! gives. Each output is timed as the paper times a cube map: the texels *it* looks up, at the
//! pass's mean seconds per texel filled, plus its own lookups.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::hemicube::Hemicube;
use super::params::Cubemap;
use crate::accel::{Hit, RayCaster, PACKET};
use crate::error::Result;
use crate::estimators::{
    AovSample, Estimate, EstimateContext, GBuffer, Gather, HarmonicMean, PixelJob, PixelPass, PixelWorker,
    RayCount, Tally,
};
use crate::progress::Progress;
use crate::report::{CubemapDetails, Details, DeviceDetails, PhaseSeconds};
use crate::sampling::Frame;

/// The CPU cube map on one image.
pub(super) struct CpuPixels<'a> {
    pub cubemap: &'a Cubemap,
    pub context: &'a EstimateContext<'a>,
}

impl PixelJob for CpuPixels<'_> {
    fn label(&self) -> &'static str {
        "cube maps"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn record_phase(&self, phases: &mut PhaseSeconds, seconds: f64) {
        // A texel is filled for the lookups of its pixel: build and lookup interleave.
        phases.cubemap_build_and_lookup = Some(seconds);
    }

    fn worker<'w>(&'w self, _: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        Box::new(OnePixel {
            pixels: self,
            hemicubes: Hemicubes::new(self.cubemap.hemicube, self.context),
        })
    }

    fn details(&self, pass: &PixelPass) -> Details {
        details(self.cubemap, &pass.tally, pass.pixels, None)
    }
}

/// The report's figures of a cube map that counted `tally` over `pixels` surface pixels.
fn details(cubemap: &Cubemap, tally: &Tally, pixels: u64, timed_as: Option<String>) -> Details {
    Details {
        device: Some(DeviceDetails::cpu()),
        cubemap: Some(CubemapDetails {
            // The CPU fills only the texels that are looked up, one ray each.
            texels_rasterised: tally.rays,
            texels_per_hemicube: cubemap.hemicube.texel_count() as u64,
            lookups: pixels * cubemap.gather.rays_per_point() as u64,
            escaped_lookups: tally.escaped_lookups,
        }),
        timed_as,
        ..Details::default()
    }
}

/// The driver's worker for one cube map.
struct OnePixel<'a> {
    pixels: &'a CpuPixels<'a>,
    hemicubes: Hemicubes<'a>,
}

impl PixelWorker for OnePixel<'_> {
    /// H at one pixel from its hemicube.
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, _: &mut AovSample) -> f32 {
        let mut h = [f32::NAN];
        let gathers = [&self.pixels.cubemap.gather];
        self.hemicubes
            .pixel(hit, pixel, &gathers, std::slice::from_mut(tally), &mut h, None);
        h[0]
    }
}

/// Seconds a worker spent filling texels and looking them up, per output, and the texels it
/// filled.
#[derive(Clone, Default)]
struct Timing {
    fill: f64,
    filled: u64,
    lookups: Vec<f64>,
}

/// One pixel's hemicube at a time, for the lookups of one or more gathers: depth per texel,
/// valid where `filled` holds the current pixel's stamp.
struct Hemicubes<'a> {
    hemicube: Hemicube,
    context: &'a EstimateContext<'a>,
    depth: Vec<f32>,
    filled: Vec<u32>,
    /// Valid for the current (pixel, output): the texel was counted for that output.
    seen: Vec<u32>,
    pixel_stamp: u32,
    output_stamp: u32,
    /// Texels to fill for the current pixel.
    pending: Vec<u32>,
    /// The current pixel's lookups, all outputs one after the other: texel, `w · axis`, and
    /// whether this is the output's first lookup of the texel.
    lookups: Vec<(u32, f32, bool)>,
    ends: Vec<usize>,
}

/// The next stamp after `stamp`, clearing `stamps` when the counter wraps.
fn next_stamp(stamp: &mut u32, stamps: &mut [u32]) -> u32 {
    *stamp = stamp.wrapping_add(1);
    if *stamp == 0 {
        stamps.fill(0);
        *stamp = 1;
    }
    *stamp
}

impl<'a> Hemicubes<'a> {
    fn new(hemicube: Hemicube, context: &'a EstimateContext<'a>) -> Self {
        let texels = hemicube.texel_count();
        Hemicubes {
            hemicube,
            context,
            depth: vec![0.0; texels],
            filled: vec![0; texels],
            seen: vec![0; texels],
            pixel_stamp: 0,
            output_stamp: 0,
            pending: vec![],
            lookups: vec![],
            ends: vec![],
        }
    }

    /// H at one pixel for each of `gathers` (into `h`), counting each output's texels and
    /// lookups into its `tallies` entry as a render of that output alone would; `timing`
    /// gets the seconds of the fill and of each output's lookups.
    fn pixel(
        &mut self,
        hit: &Hit,
        pixel: u64,
        gathers: &[&Gather],
        tallies: &mut [Tally],
        h: &mut [f32],
        mut timing: Option<&mut Timing>,
    ) {
        let context = self.context;
        let pixel_stamp = next_stamp(&mut self.pixel_stamp, &mut self.filled);
        let origin = hit.spawn_origin(hit.normal);
        let frame = Frame::from_normal(hit.normal);
        self.pending.clear();
        self.lookups.clear();
        self.ends.clear();
        for (i, gather) in gathers.iter().enumerate() {
            let start = timing.is_some().then(Instant::now);
            let output_stamp = next_stamp(&mut self.output_stamp, &mut self.seen);
            for (j, w) in gather.directions(context.seed, pixel).enumerate() {
                if crate::interrupt::stop_at_ray(j) {
                    break; // the pass ends with Error::Interrupted; this H is never seen
                }
                let (_, texel, along) = self.hemicube.lookup(w);
                if self.filled[texel] != pixel_stamp {
                    self.filled[texel] = pixel_stamp;
                    self.pending.push(texel as u32);
                }
                let first = self.seen[texel] != output_stamp;
                self.seen[texel] = output_stamp;
                tallies[i].rays += first as u64;
                self.lookups.push((texel as u32, along, first));
            }
            self.ends.push(self.lookups.len());
            if let (Some(t), Some(start)) = (timing.as_deref_mut(), start) {
                t.lookups[i] += start.elapsed().as_secs_f64();
            }
        }
        let start = timing.is_some().then(Instant::now);
        self.fill(origin, &frame, hit.triangle);
        if let (Some(t), Some(start)) = (timing.as_deref_mut(), start) {
            t.fill += start.elapsed().as_secs_f64();
            t.filled += self.pending.len() as u64;
        }
        let mut begin = 0;
        for (i, &end) in self.ends.iter().enumerate() {
            let start = timing.is_some().then(Instant::now);
            let mut mean = HarmonicMean::default();
            for &(texel, along, first) in &self.lookups[begin..end] {
                let depth = self.depth[texel as usize];
                tallies[i].escaped += (first && depth.is_infinite()) as u64;
                let d = depth / along;
                tallies[i].escaped_lookups += (d > context.clamp.max || d.is_infinite()) as u64;
                mean.add(d, context.clamp);
            }
            h[i] = mean.value();
            begin = end;
            if let (Some(t), Some(start)) = (timing.as_deref_mut(), start) {
                t.lookups[i] += start.elapsed().as_secs_f64();
            }
        }
    }

    /// Fills the pending texels, in the order they were first looked up, [`PACKET`] rays at a
    /// time from `origin` (leaving triangle `leaving`) through each texel's centre.
    fn fill(&mut self, origin: Vec3, frame: &Frame, leaving: u32) {
        let origins = [origin; PACKET];
        let leaving = [Some(leaving); PACKET];
        let mut directions = [Vec3::ZERO; PACKET];
        let mut axes = [0.0f32; PACKET];
        let mut t = [0.0f32; PACKET];
        for texels in self.pending.chunks(PACKET) {
            for (k, &texel) in texels.iter().enumerate() {
                let (face, c) = self.hemicube.texel_direction(texel as usize);
                directions[k] = frame.to_world(c);
                axes[k] = c.dot(face.axis());
            }
            let n = texels.len();
            self.context.accel.hit_distances(
                &origins[..n],
                &directions[..n],
                &leaving[..n],
                f32::INFINITY,
                &mut t[..n],
            );
            for (k, &texel) in texels.iter().enumerate() {
                self.depth[texel as usize] = t[k] * axes[k];
            }
        }
    }
}

/// One output of [`sweep`]: H per pixel, its counts, and its seconds as the paper times a
/// cube map.
struct SweepRow {
    h: Vec<Vec<f32>>,
    tallies: Vec<Tally>,
    timing: Timing,
}

/// Cube maps of one resolution at several ray counts (`cubemaps`, on the CPU, the context's
/// seed) in one pass over `gbuffer`: each pixel's hemicube is filled once for the texels any
/// of them looks up. Returns each cube map's estimate, bit for bit what a render of it alone
/// gives, and its seconds: the texels it looks up at the pass's mean cost per texel filled,
/// plus its own lookups, scaled from the workers' seconds to the pass's wall time.
///
/// # Panics
/// If the cube maps differ in resolution.
pub fn sweep(
    cubemaps: &[&Cubemap],
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<Vec<(Estimate, f64)>> {
    let hemicube = cubemaps[0].hemicube;
    assert!(
        cubemaps.iter().all(|c| c.hemicube == hemicube),
        "one resolution per sweep"
    );
    let gathers: Vec<&Gather> = cubemaps.iter().map(|c| &c.gather).collect();
    let outputs = cubemaps.len();
    let width = gbuffer.width as usize;
    let start = Instant::now();
    progress.start("cube maps", gbuffer.surface_pixels());
    let rows: Vec<SweepRow> = gbuffer
        .points
        .par_chunks(width)
        .enumerate()
        .map_init(
            || Hemicubes::new(hemicube, context),
            |hemicubes, (row, points)| sweep_row(hemicubes, &gathers, (row, points), width, progress),
        )
        .collect();
    progress.finish();
    crate::interrupt::check()?;
    let wall = start.elapsed().as_secs_f64();
    let pixels = gbuffer.surface_pixels();
    let mut timing = Timing {
        lookups: vec![0.0; outputs],
        ..Timing::default()
    };
    let mut tallies = vec![Tally::default(); outputs];
    let mut images = vec![Vec::with_capacity(gbuffer.points.len()); outputs];
    for row in rows {
        timing.fill += row.timing.fill;
        timing.filled += row.timing.filled;
        for i in 0..outputs {
            timing.lookups[i] += row.timing.lookups[i];
            tallies[i] = tallies[i] + row.tallies[i];
            images[i].extend_from_slice(&row.h[i]);
        }
    }
    let worker_seconds = timing.fill + timing.lookups.iter().sum::<f64>();
    let to_wall = if worker_seconds > 0.0 {
        wall / worker_seconds
    } else {
        0.0
    };
    let per_texel = timing.fill / timing.filled.max(1) as f64;
    let counts: Vec<String> = gathers.iter().map(|g| g.rays_per_point().to_string()).collect();
    let timed_as = format!(
        "one output of a cube-map pass over N = {} (R = {}): the texels this N looks up at the \
         pass's mean seconds per texel filled, plus its own lookups",
        counts.join(", "),
        hemicube.resolution
    );
    Ok(cubemaps
        .iter()
        .zip(images)
        .enumerate()
        .map(|(i, (cubemap, hmd))| {
            let tally = &tallies[i];
            let seconds = (tally.rays as f64 * per_texel + timing.lookups[i]) * to_wall;
            let estimate = Estimate {
                hmd,
                rays: Some(RayCount {
                    cast: tally.rays,
                    escaped: tally.escaped,
                    seconds,
                }),
                phases: PhaseSeconds {
                    cubemap_build_and_lookup: Some(seconds),
                    ..PhaseSeconds::default()
                },
                aovs: vec![],
                details: details(cubemap, tally, pixels, Some(timed_as.clone())),
            };
            (estimate, seconds)
        })
        .collect())
}

/// One image row of [`sweep`]: each surface pixel's hemicube filled once and looked up by
/// every one of `gathers`.
fn sweep_row(
    hemicubes: &mut Hemicubes,
    gathers: &[&Gather],
    (row, points): (usize, &[Option<Hit>]),
    width: usize,
    progress: &dyn Progress,
) -> SweepRow {
    let outputs = gathers.len();
    let mut out = SweepRow {
        h: vec![vec![f32::NAN; width]; outputs],
        tallies: vec![Tally::default(); outputs],
        timing: Timing {
            lookups: vec![0.0; outputs],
            ..Timing::default()
        },
    };
    let mut h = vec![0.0; outputs];
    for (x, point) in points.iter().enumerate() {
        if crate::interrupt::requested() {
            break;
        }
        if let Some(hit) = point {
            let pixel = (row * width + x) as u64;
            hemicubes.pixel(
                hit,
                pixel,
                gathers,
                &mut out.tallies,
                &mut h,
                Some(&mut out.timing),
            );
            for (image, &value) in out.h.iter_mut().zip(&h) {
                image[x] = value;
            }
            progress.advance(1);
        }
    }
    out
}
