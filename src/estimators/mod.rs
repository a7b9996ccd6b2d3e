//! The HMD estimators of spec §3, behind one interface, and the registry that names them.
//!
//! The render driver ([`crate::render`]) finds each pixel's surface point with a primary ray
//! and owns the loop over pixels: rows in parallel, progress, ray and hole counts, timings
//! (pbrt-v4's `ImageTileIntegrator` owns tiles in the same way). An [`Estimator`] says what
//! happens at one pixel ([`PixelWorker`]), after an optional whole-image preparation (the
//! photon map build) in [`Estimator::prepare`]. An estimator that must work on the whole
//! image at once (the GPU hemicube, which rasterises batches of pixels) returns its finished
//! [`Estimate`] from `prepare` instead.
//!
//! The names, in the order a render meets them: [`Estimator::prepare`] gives a [`Prepared`]
//! (a [`PixelJob`] over the image's pixels, or the finished [`Estimate`]); the job gives each
//! thread a [`PixelWorker`], which evaluates one pixel at a time and adds to its [`Tally`];
//! the driver sums the tallies into a [`PixelPass`] and hands the job's [`Estimate`] back.
//!
//! **Adding a sixth estimator** is one new module implementing [`Estimator`] (its pixel in a
//! [`PixelWorker`]) with its parameter struct ([`MethodParams`]), plus one line in
//! [`registry::METHODS`]; the CLI's `--method` and flags, Python's keywords, the experiments
//! and the report pick it up from there.
//!
//! One method computes something other than H with the same machinery: `irradiance`, the
//! one-bounce irradiance an irradiance cache stores ([`Estimator::channel`] names its image).
//!
//! Conventions: distances in scene units; a pixel's normal faces the camera (surfaces are
//! two-sided); H is `+inf` where every sample escaped and NaN for background pixels and holes.

pub mod adaptive;
pub mod aov;
pub mod cubemap;
pub mod gather;
mod harmonic;
pub mod irradiance;
pub mod params;
pub mod pass;
pub mod photon;
pub mod registry;

pub use crate::backend::Backend;
pub use adaptive::{Adaptive, AdaptiveParams};
pub use aov::{Aov, AovImage, AovSample};
pub use cubemap::{Cubemap, CubemapParams};
pub use gather::{Gather, GatherParams};
pub use harmonic::{DistanceClamp, HarmonicMean};
pub use irradiance::{Irradiance, IrradianceParams};
pub use photon::{PhotonEstimator, PhotonParams};
pub use registry::{MethodEntry, MethodParams, METHODS};

use crate::accel::{Accel, Hit};
use crate::error::Result;
use crate::progress::Progress;
use crate::report::{Details, Parameters, PhaseSeconds};

/// The EXR channel of an image of H (spec §7).
pub const HMD_CHANNEL: &str = "Y";

/// Each pixel's first surface hit, normal flipped to face the camera; `None` for background.
pub struct GBuffer {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Row-major, row 0 at the top.
    pub points: Vec<Option<Hit>>,
}

impl GBuffer {
    /// Pixels whose camera ray met nothing.
    pub fn background_pixels(&self) -> usize {
        self.points.iter().filter(|p| p.is_none()).count()
    }

    /// Pixels with a surface point.
    pub fn surface_pixels(&self) -> u64 {
        (self.points.len() - self.background_pixels()) as u64
    }

    /// The image of `values`, one per pixel of `pixels` (surface pixels, as [`GBuffer::starts`]
    /// lists them), NaN elsewhere.
    #[cfg(feature = "gpu")]
    pub(crate) fn image_of(&self, pixels: &[usize], values: impl IntoIterator<Item = f32>) -> Vec<f32> {
        let mut image = vec![f32::NAN; self.points.len()];
        for (&pixel, value) in pixels.iter().zip(values) {
            image[pixel] = value;
        }
        image
    }

    /// The surface pixels' indices and the starts of their gather rays (or hemicubes), in
    /// pixel order: what the GPU backends take.
    #[cfg(feature = "gpu")]
    pub(crate) fn starts(&self) -> (Vec<usize>, Vec<crate::accel::GatherStart>) {
        self.points
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.as_ref().map(|hit| (i, crate::accel::GatherStart::at_hit(hit))))
            .unzip()
    }
}

/// What every estimator may use besides the G-buffer.
pub struct EstimateContext<'a> {
    /// The scene's BVH.
    pub accel: &'a Accel,
    /// The scene being rendered.
    pub scene: &'a crate::scene::Scene,
    /// Counter-based random numbers are keyed by this seed (spec §2).
    pub seed: u64,
    /// How sample distances are clamped (spec §1).
    pub clamp: DistanceClamp,
    /// The AOVs asked for (each one in [`Estimator::aovs`]).
    pub aovs: &'a [Aov],
    /// Whether every row is rendered (not a shard): whole-image statistics such as the
    /// median of H are only known then.
    pub whole_image: bool,
    /// The BVH preset `accel` was built with (its closest hits can differ, at exact ties,
    /// from another preset's: a photon map records it).
    pub bvh: crate::accel::BuildQuality,
}

/// The rays an estimator cast through the scene (primary rays not included), for the report's
/// `rays_cast`, `escaped_rays` and `mrays_per_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayCount {
    /// Rays cast.
    pub cast: u64,
    /// Rays that hit nothing (within `max_distance`, where the estimator's rays stop there).
    pub escaped: u64,
    /// Seconds of the phase that cast them.
    pub seconds: f64,
}

/// An estimator's output: H per pixel (row-major, row 0 at the top) and what it cost.
pub struct Estimate {
    /// H per pixel; NaN for background and holes.
    pub hmd: Vec<f32>,
    /// The rays cast; `None` for an estimator that casts none (the GPU cube map rasterises).
    pub rays: Option<RayCount>,
    /// The estimator's own phases, in the report's `seconds`.
    pub phases: PhaseSeconds,
    /// The AOVs asked for, in the order asked.
    pub aovs: Vec<AovImage>,
    /// Method-specific figures for the report.
    pub details: Details,
}

/// What one pixel (or a whole pass) counted, summed by the driver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Rays cast.
    pub rays: u64,
    /// Rays that met nothing.
    pub escaped: u64,
    /// Cube-map lookups whose texel holds no surface within `max_distance`.
    pub escaped_lookups: u64,
    /// Surface pixels whose H is NaN (no sample: a photon-map hole). Counted by the driver.
    pub holes: u64,
}

impl std::ops::Add for Tally {
    type Output = Tally;
    fn add(self, o: Tally) -> Tally {
        Tally {
            rays: self.rays + o.rays,
            escaped: self.escaped + o.escaped,
            escaped_lookups: self.escaped_lookups + o.escaped_lookups,
            holes: self.holes + o.holes,
        }
    }
}

/// What a pixel pass measured: the sums of its [`Tally`]s and its seconds.
#[derive(Clone, Copy, Debug)]
pub struct PixelPass {
    /// Counts summed over every surface pixel.
    pub tally: Tally,
    /// Surface pixels evaluated.
    pub pixels: u64,
    /// Seconds of the pass.
    pub seconds: f64,
}

/// What [`Estimator::prepare`] gives the driver for one image: a job over its pixels, or the
/// finished estimate.
pub enum Prepared<'a> {
    /// A per-pixel job for the driver's loop, after a preparation that took `phases` and cast
    /// `rays` (the photon trace; `None` where nothing was prepared).
    Pixels {
        /// Evaluates pixels, one [`PixelWorker`] per thread.
        job: Box<dyn PixelJob + 'a>,
        /// Seconds of the preparation's phases.
        phases: PhaseSeconds,
        /// Rays the preparation cast.
        rays: Option<RayCount>,
    },
    /// The whole image, already estimated.
    Done(Box<Estimate>),
}

/// An estimator's job over the pixels of one image, shared by the threads: each thread asks
/// it for a [`PixelWorker`] with its own scratch.
pub trait PixelJob: Sync {
    /// The progress bar's label for the pixel pass.
    fn label(&self) -> &'static str;

    /// Whether the pixel pass casts the rays that the report counts (`gather` and the CPU
    /// cube map do; the photon gather looks up a map instead).
    fn casts_rays(&self) -> bool;

    /// Records the pixel pass's seconds under the estimator's own phase name, if it has one.
    fn record_phase(&self, _phases: &mut PhaseSeconds, _seconds: f64) {}

    /// Progress steps per surface pixel: 1, which the driver counts as each pixel is done;
    /// or more (`gather`: its rays), which the worker counts itself as it goes, exactly this
    /// many per pixel, so that a pass whose pixels take long still shows its rate and ETA.
    fn progress_per_pixel(&self) -> u64 {
        1
    }

    /// A worker for one thread, with its own scratch (the CPU cube map's texel cache), and
    /// the pass's `progress` where [`PixelJob::progress_per_pixel`] is above 1.
    fn worker<'w>(&'w self, progress: &'w dyn Progress) -> Box<dyn PixelWorker + 'w>;

    /// The method-specific figures of the report, once every pixel is done.
    fn details(&self, pass: &PixelPass) -> Details;
}

/// Evaluates pixels one at a time on one thread.
pub trait PixelWorker {
    /// H at the surface point `hit` of pixel `pixel` (row-major index, the random numbers'
    /// key); adds what it cast to `tally` and sets the AOVs it measures in `aov`.
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, aov: &mut AovSample) -> f32;
}

/// How many independent rays a pixel's H averages: what the denoiser's noise model needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Samples {
    /// The same number at every pixel (`gather`, the cube map's lookups).
    Fixed(u32),
    /// Each pixel's own number, its `rays` AOV (`adaptive`).
    PerPixel,
    /// The filter does not suit the estimator, for the reason given.
    Unsuited(&'static str),
}

/// One way of computing H per pixel.
pub trait Estimator: Sync {
    /// The method's name as the registry spells it (`gather`, `cubemap`, ...).
    fn method(&self) -> &'static str;

    /// The method's parameters, for the report.
    fn parameters(&self) -> Parameters;

    /// The name of the image's EXR channel: `Y` for H (spec §7); `E` for `irradiance`, whose
    /// image is irradiance, not H.
    fn channel(&self) -> &'static str {
        HMD_CHANNEL
    }

    /// The grey picture's default scale for an image of `scene` (grey = clamp(scale · value)):
    /// the scene's own for H (spec §4); `irradiance` scales by the scene's size.
    fn display_scale(&self, scene: &crate::scene::Scene) -> f32 {
        scene.display_scale
    }

    /// The AOVs it can measure; asking for another is refused before the render.
    fn aovs(&self) -> &'static [Aov] {
        &[]
    }

    /// How many independent rays each pixel's H averages, for `--denoise`
    /// ([`crate::denoise`]); the default refuses the filter, saying why.
    fn samples(&self) -> Samples {
        Samples::Unsuited("its pixels are not means of their own rays")
    }

    /// About how many rays the estimator will cast for an image of `pixels` surface pixels
    /// (primary rays not included): chooses the BVH preset ([`crate::accel::BuildQuality`]).
    fn expected_rays(&self, pixels: u64) -> u64;

    /// Prepares the image: whatever must be built for the whole image first, then the
    /// per-pixel work for the driver (or the finished estimate).
    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        gbuffer: &'a GBuffer,
        progress: &dyn Progress,
    ) -> Result<Prepared<'a>>;
}
