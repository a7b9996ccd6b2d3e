//! `hmdist cache`: Ward's irradiance cache over an image's primary hits, its records placed
//! coarse to fine and spaced by any source of H (or a renderer's rule), with what each part
//! cost.
//!
//! **Placement.** Levels from a stride of `2^K` pixels down to 1 (Tabellion and Lamorlette
//! 2004): at each level every pixel on the level's grid that no record made so far covers
//! (ε < a) gets a record; the level's records are then made in parallel, in pixel order. The
//! decisions of a level depend only on the records of the levels before it, so the records are
//! the same whatever the thread count. Two records of one level may be closer than the rule
//! allows; a record is never covered by one of an earlier level.
//!
//! **A record** at pixel p holds E from `irradiance`'s M rays with p's random numbers (so it
//! is the irradiance image's pixel p, bit for bit) and a radius from the spacing source,
//! clamped to pixel footprints and to fractions of `l_diag` where asked. A source that gives no
//! H at a record (a photon-map hole, NaN) falls back to the H of the record's own rays.

use std::time::Instant;

use rayon::prelude::*;

use super::gradients::{GradientRays, Gradients};
use super::neighbours::Neighbours;
use super::params::CacheParams;
use super::records::{interpolate, Record, RecordIndex};
use super::report::{relative_errors, CacheReport, CacheSeconds, Counts, Level};
use super::spacing::{OwnRays, Spacing};
use crate::accel::{Accel, GatherStart, Hit};
use crate::error::{Error, Result};
use crate::estimators::irradiance::Spot;
use crate::estimators::{
    AovSample, DistanceClamp, EstimateContext, Estimator, GBuffer, Irradiance, PixelJob, Prepared, Tally,
};
use crate::image::HmdImage;
use crate::options::{in_pool, RenderOptions};
use crate::progress::{Progress, Silent};
use crate::render::primary_hits;
use crate::scene::Scene;

/// The cache's image and what it is made of.
pub struct Cached {
    /// E per pixel from the records; NaN for background.
    pub image: HmdImage,
    /// Records each pixel used; NaN for background.
    pub records_used: Vec<f32>,
    /// The records, in the order made.
    pub records: Vec<Record>,
    /// The report.
    pub report: CacheReport,
}

impl Cached {
    /// E in grey at exposure `scale` (`clamp(scale · E)`), each record's pixel red.
    pub fn picture(&self, scale: f32) -> image::RgbImage {
        let grey = crate::image::picture::grey(&self.image, scale);
        let mut picture = image::DynamicImage::ImageLuma8(grey).to_rgb8();
        let width = self.image.width;
        for record in &self.records {
            picture.put_pixel(
                record.pixel % width,
                record.pixel / width,
                image::Rgb([230, 30, 30]),
            );
        }
        picture
    }

    /// Each pixel's relative error against `reference` ([`relative_errors`]), its mean and
    /// p95 put into the report under `path`.
    pub fn compare(&mut self, reference: &HmdImage, path: &str) -> Result<Vec<f32>> {
        let (errors, summary) = relative_errors(&self.image, reference, path)?;
        self.report.reference = Some(summary);
        Ok(errors)
    }
}

/// The coarsest level's stride: the largest power of two at most an eighth of the image's
/// shorter side (1 for images under 16 pixels).
pub fn top_stride(width: u32, height: u32) -> u32 {
    let side = (width.min(height) / 8).max(1);
    1 << (31 - side.leading_zeros())
}

/// Builds the cache of `scene` as `options` frames it (size, seed, threads, BVH, kernel,
/// `max_distance`; no AOVs, no shard). `oracle` is the image of H that `Spacing::Oracle`
/// reads (the same size).
pub fn cache(
    scene: &Scene,
    params: &CacheParams,
    options: &RenderOptions,
    oracle: Option<&HmdImage>,
    progress: &dyn Progress,
) -> Result<Cached> {
    let checked = check(scene, params, options, oracle)?;
    in_pool(options.threads, || {
        build(scene, params, options, &checked, progress)
    })?
}

/// What a cache is made with, checked before any work: the records' irradiance, the light,
/// the estimator of H the spacing takes (if one), and the oracle's image.
struct Checked<'a> {
    irradiance: Irradiance,
    light: Spot,
    spacing: Option<Box<dyn Estimator>>,
    oracle: Option<&'a HmdImage>,
}

/// Refuses, by name, what cannot make a cache, before anything is built.
fn check<'a>(
    scene: &Scene,
    params: &CacheParams,
    options: &RenderOptions,
    oracle: Option<&'a HmdImage>,
) -> Result<Checked<'a>> {
    options.validate()?;
    scene.validate()?;
    if !(params.accuracy.is_finite() && params.accuracy > 0.0) {
        let message = format!("must be a positive number, not {}", params.accuracy);
        return Err(Error::invalid("accuracy", message));
    }
    if !options.aovs.is_empty() || options.shard.is_some() {
        return Err(Error::parameter("a cache takes no AOVs and no shard"));
    }
    let (w, h) = (options.width, options.height);
    match (&params.spacing, oracle) {
        (Spacing::Oracle, None) => {
            return Err(Error::invalid(
                "spacing",
                "oracle needs an image of H to read (--oracle)",
            ));
        }
        (Spacing::Oracle, Some(image)) if (image.width, image.height) != (w, h) => {
            let message = format!("is {}x{}, the cache {w}x{h}", image.width, image.height);
            return Err(Error::invalid("oracle", message));
        }
        (Spacing::Oracle, Some(_)) => {}
        (_, Some(_)) => return Err(Error::invalid("oracle", "is read only by --spacing oracle")),
        (_, None) => {}
    }
    let light = crate::estimators::irradiance::light_of(scene)?;
    if params.gradients {
        super::gradients::check(&params.irradiance)?;
    }
    let pixels = w as u64 * h as u64;
    let what = format!("{w}x{h}");
    crate::memory::check(Some("size"), &what, crate::render::image_bytes(pixels, 2), None)?;
    Ok(Checked {
        irradiance: params.irradiance.build()?,
        light,
        spacing: params.spacing.estimator()?,
        oracle,
    })
}

/// Refuses an oracle image of H that is not one: a value that is not positive (H is a
/// distance: `+inf` where every ray escapes, NaN only where the camera sees nothing), or NaN
/// at a pixel where the cache has a surface, naming the first such pixel.
fn check_oracle(oracle: &HmdImage, gbuffer: &crate::estimators::GBuffer) -> Result<()> {
    let width = oracle.width as usize;
    let bad = oracle
        .data
        .iter()
        .zip(&gbuffer.points)
        .position(|(&h, point)| (h.is_nan() && point.is_some()) || h <= 0.0);
    match bad {
        None => Ok(()),
        Some(i) => {
            let (x, y, h) = (i % width, i / width, oracle.data[i]);
            let message = format!(
                "holds H = {h} at pixel ({x}, {y}), where the cache sees a surface: an H is a positive distance \
                 (+inf where every ray escapes, NaN only where the camera sees nothing)"
            );
            Err(Error::invalid("oracle", message))
        }
    }
}

/// The cache, on the current pool: the BVH and primary hits, the spacing estimator's
/// preparation, the records level by level, every pixel's E.
fn build(
    scene: &Scene,
    params: &CacheParams,
    options: &RenderOptions,
    checked: &Checked,
    progress: &dyn Progress,
) -> Result<Cached> {
    let start = Instant::now();
    let (w, h) = (options.width, options.height);
    let rays = w as u64 * h as u64 * (1 + 2 * params.irradiance.rays as u64);
    let (accel, bvh) = Accel::for_work(&scene.mesh, options.bvh_quality, rays, options.kernel)?;
    let gbuffer = primary_hits(&accel, scene, w, h);
    crate::interrupt::check()?;
    if let Some(oracle) = checked.oracle {
        check_oracle(oracle, &gbuffer)?;
    }
    let l_diag = scene.bounds().diagonal();
    let context = EstimateContext {
        accel: &accel,
        scene,
        seed: options.seed,
        clamp: DistanceClamp::for_diagonal(l_diag, options.max_distance),
        aovs: &[],
        whole_image: true,
        bvh,
    };
    let mut seconds = CacheSeconds {
        setup: start.elapsed().as_secs_f64(),
        ..CacheSeconds::default()
    };
    let prepare_start = Instant::now();
    let prepared = match &checked.spacing {
        Some(estimator) => Some(
            estimator
                .prepare(&context, &gbuffer, progress)
                .map_err(|e| params.spacing.blame(e))?,
        ),
        None => None,
    };
    seconds.spacing_prepare = prepare_start.elapsed().as_secs_f64();
    let source = match (prepared, checked.oracle) {
        (Some(Prepared::Pixels { job, rays, .. }), _) => Source::Job(job, rays.map_or(0, |r| r.cast)),
        (Some(Prepared::Done(estimate)), _) => {
            Source::Image(estimate.hmd, estimate.rays.map_or(0, |r| r.cast))
        }
        (None, Some(image)) => Source::Image(image.data.clone(), 0),
        (None, None) => Source::Own,
    };
    let placement = Placement {
        context: &context,
        gbuffer: &gbuffer,
        irradiance: &checked.irradiance,
        light: checked.light,
        params,
        source: &source,
        pixel_size: 2.0 * (scene.camera.fov_y_deg.to_radians() / 2.0).tan() / h as f32,
        l_diag,
    };
    let (records, index, mut counts) = placement.place(&mut seconds, progress)?;
    let interpolate_start = Instant::now();
    let (image, records_used) = placement.interpolate(&records, &index, progress)?;
    seconds.interpolate = interpolate_start.elapsed().as_secs_f64();
    seconds.total = start.elapsed().as_secs_f64();
    counts.rays_h += source.prepared_rays();
    let report = CacheReport::new(
        scene,
        params,
        options,
        l_diag,
        (&records, &records_used),
        counts,
        seconds,
    );
    Ok(Cached {
        image: HmdImage::new(w, h, image),
        records_used,
        records,
        report,
    })
}

/// Where the records' H comes from.
enum Source<'a> {
    /// The records' own rays (`hmd`, `min`, `min10`).
    Own,
    /// A per-pixel estimator's job, and the rays its preparation cast.
    Job(Box<dyn PixelJob + 'a>, u64),
    /// A whole image of H (the oracle, or an estimator that made the whole image at once), and
    /// the rays it cost.
    Image(Vec<f32>, u64),
}

impl Source<'_> {
    fn prepared_rays(&self) -> u64 {
        match self {
            Source::Own => 0,
            Source::Job(_, rays) | Source::Image(_, rays) => *rays,
        }
    }
}

/// A record's irradiance, what it cast, what its own rays saw, and its gradients where asked.
struct Gathered {
    e: f32,
    tally: Tally,
    own: OwnRays,
    gradients: Option<Gradients>,
}

/// A record's radius from its spacing source (before clamping), and the rays it cost.
struct Spaced {
    radius: f32,
    tally: Tally,
}

/// The records placed so far, and what finds them.
struct Placed {
    records: Vec<Record>,
    index: RecordIndex,
    neighbours: Neighbours,
    counts: Counts,
}

/// What placing records needs.
struct Placement<'a> {
    context: &'a EstimateContext<'a>,
    gbuffer: &'a GBuffer,
    irradiance: &'a Irradiance,
    light: Spot,
    params: &'a CacheParams,
    source: &'a Source<'a>,
    /// A pixel's footprint per unit of distance from the camera.
    pixel_size: f32,
    l_diag: f32,
}

impl Placement<'_> {
    fn hit(&self, pixel: u32) -> &Hit {
        self.gbuffer.points[pixel as usize]
            .as_ref()
            .expect("a surface pixel")
    }

    /// Every level's records, coarse to fine, and the index over them. Neighbour clamping
    /// can shrink a record after a pixel was found covered by it, so with it the finest level
    /// goes on until no pixel is left uncovered.
    fn place(
        &self,
        seconds: &mut CacheSeconds,
        progress: &dyn Progress,
    ) -> Result<(Vec<Record>, RecordIndex, Counts)> {
        let (w, h) = (self.gbuffer.width, self.gbuffer.height);
        let mut placed = Placed {
            records: vec![],
            index: RecordIndex::new(self.params.accuracy, self.l_diag / 256.0),
            neighbours: Neighbours::new(self.l_diag / 64.0),
            counts: Counts::default(),
        };
        for level in (0..=top_stride(w, h).trailing_zeros()).rev() {
            let stride = 1u32 << level;
            let mut made = 0;
            loop {
                let needy = self.uncovered(stride, &placed.records, &placed.index);
                crate::interrupt::check()?;
                self.add(&mut placed, &needy, (stride, level), seconds, progress)?;
                made += needy.len();
                if needy.is_empty() || level > 0 || !self.params.neighbour_clamp {
                    break;
                }
            }
            placed.counts.levels.push(Level {
                stride,
                records: made,
            });
        }
        Ok((placed.records, placed.index, placed.counts))
    }

    /// Records at pixels `needy` of the level of `stride` (its number `level`): their E and
    /// radii, in parallel, then each clamped by its neighbours where asked and indexed, in
    /// pixel order.
    fn add(
        &self,
        placed: &mut Placed,
        needy: &[u32],
        (stride, level): (u32, u32),
        seconds: &mut CacheSeconds,
        progress: &dyn Progress,
    ) -> Result<()> {
        let e_start = Instant::now();
        let gathered = self.gather(needy, stride, progress)?;
        seconds.e += e_start.elapsed().as_secs_f64();
        let h_start = Instant::now();
        let spaced = self.radii(needy, &gathered)?;
        seconds.h += h_start.elapsed().as_secs_f64();
        for ((&p, gathered), spaced) in needy.iter().zip(&gathered).zip(spaced) {
            placed.counts.rays_e += gathered.tally.rays;
            placed.counts.rays_h += spaced.tally.rays;
            let hit = self.hit(p);
            let mut unclamped = spaced.radius;
            if self.params.neighbour_clamp {
                let clamp = |pixel, r| self.clamped(r, self.hit(pixel));
                unclamped = placed
                    .neighbours
                    .clamp(&mut placed.records, hit.point, unclamped, clamp);
                placed.neighbours.insert(hit.point, unclamped);
            }
            let record = Record {
                pixel: p,
                point: hit.point,
                normal: hit.normal,
                e: gathered.e,
                radius: self.clamped(unclamped, hit),
                level,
                gradients: gathered.gradients,
            };
            placed.index.insert(placed.records.len() as u32, &record);
            placed.records.push(record);
        }
        Ok(())
    }

    /// The surface pixels of the grid of `stride` that no record covers, in pixel order.
    fn uncovered(&self, stride: u32, records: &[Record], index: &RecordIndex) -> Vec<u32> {
        let (w, h) = (self.gbuffer.width, self.gbuffer.height);
        let grid: Vec<u32> = (0..h)
            .step_by(stride as usize)
            .flat_map(|y| (0..w).step_by(stride as usize).map(move |x| y * w + x))
            .collect();
        grid.into_par_iter()
            .filter(|&p| {
                self.gbuffer.points[p as usize]
                    .as_ref()
                    .is_some_and(|hit| !index.covers(records, p, hit.point, hit.normal))
            })
            .collect()
    }

    /// The irradiance at pixels `needy` (the level of `stride`), with what their own rays saw.
    fn gather(&self, needy: &[u32], stride: u32, progress: &dyn Progress) -> Result<Vec<Gathered>> {
        progress.start(&format!("records, stride {stride}"), needy.len() as u64);
        let gathered = needy
            .par_iter()
            .map(|&p| {
                let c = self.context;
                let key = (c.seed, p as u64);
                let mut own = OwnRays::new(c.clamp);
                let params = &self.params.irradiance;
                let mut cells = self.params.gradients.then(|| GradientRays::new(params, key));
                let (e, tally) = if crate::interrupt::requested() {
                    (f32::NAN, Tally::default())
                } else {
                    let observe = |t, w, term| {
                        own.add(t, w);
                        if let Some(cells) = &mut cells {
                            cells.add(t, w, term);
                        }
                    };
                    self.irradiance
                        .at(c.accel, &self.light, self.hit(p), key, c.clamp.max, observe)
                };
                progress.advance(1);
                let frame = || GatherStart::at_hit(self.hit(p)).frame;
                let gradients = cells.map(|cells| cells.gradients(&frame()));
                Gathered {
                    e,
                    tally,
                    own,
                    gradients,
                }
            })
            .collect();
        progress.finish();
        crate::interrupt::check()?;
        Ok(gathered)
    }

    /// The records' radii (before clamping) at pixels `needy` whose own rays are in
    /// `gathered`, and the rays each cost beyond them.
    fn radii(&self, needy: &[u32], gathered: &[Gathered]) -> Result<Vec<Spaced>> {
        let spacing = &self.params.spacing;
        let free = |radius| Spaced {
            radius,
            tally: Tally::default(),
        };
        let found: Vec<Spaced> = match self.source {
            Source::Own => gathered
                .iter()
                .map(|g| free(g.own.radius(spacing).expect("a source of the own rays")))
                .collect(),
            Source::Image(hmd, _) => needy.iter().map(|&p| free(hmd[p as usize])).collect(),
            Source::Job(job, _) => needy
                .par_iter()
                .map_init(
                    || job.worker(&Silent),
                    |worker, &p| {
                        let (mut tally, mut aov) = (Tally::default(), AovSample::default());
                        let radius = worker.pixel(self.hit(p), p as u64, &mut tally, &mut aov);
                        Spaced { radius, tally }
                    },
                )
                .collect(),
        };
        crate::interrupt::check()?;
        // No H from the source (a photon-map hole): the record's own rays'.
        Ok(found
            .into_iter()
            .zip(gathered)
            .map(|(spaced, g)| Spaced {
                radius: if spaced.radius.is_nan() {
                    g.own.hmd()
                } else {
                    spaced.radius
                },
                ..spaced
            })
            .collect())
    }

    /// `radius` clamped as asked, at `hit` (its distance from the camera sets the footprint).
    fn clamped(&self, radius: f32, hit: &Hit) -> f32 {
        let mut r = radius;
        if let Some(range) = self.params.clamp_pixels {
            r = range.apply(r, hit.t * self.pixel_size);
        }
        if let Some(range) = self.params.clamp_scene {
            r = range.apply(r, self.l_diag);
        }
        r
    }

    /// Every pixel's E from the records, and how many records it used.
    fn interpolate(
        &self,
        records: &[Record],
        index: &RecordIndex,
        progress: &dyn Progress,
    ) -> Result<(Vec<f32>, Vec<f32>)> {
        let pixels = self.gbuffer.points.len();
        progress.start("interpolate", pixels as u64);
        let (image, used): (Vec<f32>, Vec<f32>) = (0..pixels)
            .into_par_iter()
            .map_init(Vec::new, |covering, p| {
                progress.advance(1);
                match &self.gbuffer.points[p] {
                    None => (f32::NAN, f32::NAN),
                    Some(hit) => {
                        index.covering(records, p as u32, hit.point, hit.normal, covering);
                        let e = interpolate(records, covering, hit.point, hit.normal);
                        (e, covering.len() as f32)
                    }
                }
            })
            .unzip();
        progress.finish();
        crate::interrupt::check()?;
        Ok((image, used))
    }
}
