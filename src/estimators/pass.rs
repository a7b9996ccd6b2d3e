//! The pixel loop every per-pixel estimator runs in: rows in parallel, one worker (with its
//! scratch) per rayon job, NaN for background, holes and rays counted, AOVs kept, progress and
//! interruption. The render driver ([`crate::render`]) calls [`estimate`]; an estimator that
//! needs a pass of its own (gather's first pass for the `ao` radius) calls [`pixel_pass`].

use std::time::Instant;

use rayon::prelude::*;

use super::{
    Aov, AovImage, AovSample, Estimate, EstimateContext, Estimator, GBuffer, PixelJob, PixelPass,
    PixelWorker, Prepared, RayCount, Tally,
};
use crate::accel::Hit;
use crate::error::Result;
use crate::progress::Progress;

/// H per pixel of `gbuffer` by `estimator`: its preparation, then the driver's pixel loop (or
/// the whole image it estimated itself). Runs on the current rayon pool.
pub fn estimate(
    estimator: &dyn Estimator,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<Estimate> {
    Ok(match estimator.prepare(context, gbuffer, progress)? {
        Prepared::Done(estimate) => *estimate,
        Prepared::Pixels { job, phases, rays } => {
            let (hmd, aovs, pass) = pixel_pass(job.as_ref(), gbuffer, context.aovs, progress)?;
            let mut phases = phases;
            job.record_phase(&mut phases, pass.seconds);
            let pixel_rays = job.casts_rays().then_some(RayCount {
                cast: pass.tally.rays,
                escaped: pass.tally.escaped,
                seconds: pass.seconds,
            });
            Estimate {
                hmd,
                aovs,
                rays: rays.or(pixel_rays),
                phases,
                details: job.details(&pass),
            }
        }
    })
}

/// The driver's loop over the estimator's pixels: rows in parallel, each row a rayon job of
/// its own (`with_max_len(1)`: rayon otherwise hands a thread runs of rows that no idle thread
/// can take from it, and a shard of `cube` at 1024² × 65,536 rays, 64 rows of 7 s each, left
/// one core idle for 30 of 244 s; per row, 8 s of 230), one worker (with its scratch) per job, NaN for background, holes counted, the AOVs in `aovs` kept; progress
/// in surface pixels, or in [`PixelJob::progress_per_pixel`] steps each. The image does not depend on how rows are split among threads.
/// [`Error::Interrupted`] if [`crate::interrupt::request`] was called before it finished.
pub(crate) fn pixel_pass(
    work: &dyn PixelJob,
    gbuffer: &GBuffer,
    aovs: &[Aov],
    progress: &dyn Progress,
) -> Result<(Vec<f32>, Vec<AovImage>, PixelPass)> {
    let start = Instant::now();
    let width = gbuffer.width as usize;
    let mut hmd = vec![f32::NAN; gbuffer.points.len()];
    // Each pixel's AOVs, only where some are asked for.
    let mut samples = vec![AovSample::default(); if aovs.is_empty() { 0 } else { hmd.len() }];
    let per_pixel = work.progress_per_pixel();
    progress.start(work.label(), gbuffer.surface_pixels().saturating_mul(per_pixel));
    // The driver counts each pixel done, unless the workers count their own steps.
    let silent = crate::progress::Silent;
    let counted: &dyn Progress = if per_pixel == 1 { progress } else { &silent };
    let rows = hmd.par_chunks_mut(width).zip(gbuffer.points.par_chunks(width));
    let tally = if aovs.is_empty() {
        rows.enumerate()
            .with_max_len(1)
            .map_init(
                || work.worker(progress),
                |worker, (row, (out, points))| {
                    pixel_row(worker.as_mut(), row * width, out, points, None, counted)
                },
            )
            .reduce(Tally::default, |a, b| a + b)
    } else {
        rows.zip(samples.par_chunks_mut(width))
            .enumerate()
            .with_max_len(1)
            .map_init(
                || work.worker(progress),
                |worker, (row, ((out, points), samples))| {
                    let samples = Some(samples);
                    pixel_row(worker.as_mut(), row * width, out, points, samples, counted)
                },
            )
            .reduce(Tally::default, |a, b| a + b)
    };
    progress.finish();
    crate::interrupt::check()?;
    let pass = PixelPass {
        tally,
        pixels: gbuffer.surface_pixels(),
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((hmd, AovImage::channels(aovs, &samples), pass))
}

/// One row of the pixel pass, whose first pixel has index `first`; it stops early once an
/// interruption is requested.
fn pixel_row(
    worker: &mut dyn PixelWorker,
    first: usize,
    out: &mut [f32],
    points: &[Option<Hit>],
    mut samples: Option<&mut [AovSample]>,
    counted: &dyn Progress,
) -> Tally {
    let mut tally = Tally::default();
    let mut scratch = AovSample::default();
    for (x, (h, point)) in out.iter_mut().zip(points).enumerate() {
        if crate::interrupt::requested() {
            break;
        }
        if let Some(hit) = point {
            let aov = match samples.as_deref_mut() {
                Some(samples) => &mut samples[x],
                None => &mut scratch,
            };
            *h = worker.pixel(hit, (first + x) as u64, &mut tally, aov);
            tally.holes += h.is_nan() as u64;
            counted.advance(1);
        }
    }
    tally
}
