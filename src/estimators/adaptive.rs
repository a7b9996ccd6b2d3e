//! `adaptive`: final gathering that stops when H is known well enough (issue #12; the paper's
//! future work asks how many rays a pixel really needs).
//!
//! Per pixel, rounds of `min_rays / 8` rays are cast: first 8, then one more at a time until
//! the standard error of H from the rounds' spread is below `(tolerance · H + abs_tolerance ·
//! l_diag) · (N / min_rays)^loosen` after N rays (relative, absolute in units of the scene's
//! diagonal, as f_diff; with `loosen` 1 a pixel stops where another round would buy less
//! error per ray than at its first check, which spends the rays where they lower the mean
//! error most), or another round would pass `max_rays`. A pixel's rounds depend only on its
//! own rays: the image is the same for any thread count.
//!
//! With the Sobol sampler (the default of `AdaptiveParams`, so of the CLI and Python) the
//! rounds are consecutive blocks of one Owen-scrambled Sobol sequence (`Rounds::Blocks` in
//! `gather/directions.rs`): a pixel that stops at N rays has the H of `gather --rays N`, so
//! going on costs no stratification; the blocks' spread overstates the error (a
//! conservative stop). With `--sampler grid` (and [`Adaptive::new`]'s default) each round
//! is its own jittered stratified grid, as `gather`'s rounds: a pixel that stops at N rays
//! has the H of `gather --sampler grid --rays N --rounds N/(min_rays/8)`.

use super::gather::PointGather;
use super::gather::Rounds;
use super::{
    Aov, AovSample, EstimateContext, Estimator, GBuffer, PixelJob, PixelPass, PixelWorker, Prepared, Tally,
};
use crate::accel::GatherStart;
use crate::accel::Hit;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{Details, Parameters};
use crate::sampling::{Sampler, Weighting};

/// Default relative standard error of H at which a pixel stops.
pub const DEFAULT_TOLERANCE: f32 = 0.02;
/// Default rays before the first check: 8 rounds of 8.
pub const DEFAULT_MIN_RAYS: u32 = 64;
/// Default most rays per pixel.
pub const DEFAULT_MAX_RAYS: u32 = 4096;
/// Rounds before the first check.
pub const FIRST_ROUNDS: u32 = 8;

/// `adaptive`'s parameters: the CLI's flags, Python's keywords and the registry's build all
/// come from this one list.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct AdaptiveParams {
    /// Direction weighting over the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Weighting::Cosine))]
    pub weighting: Weighting,
    /// How the directions fill the hemisphere: rounds that are each a jittered grid, or
    /// consecutive blocks of one progressive Owen-scrambled Sobol sequence.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Sampler::Sobol))]
    pub sampler: Sampler,
    /// A pixel stops once the standard error of its H is below T · H + A · l_diag (T
    /// relative, A absolute in units of the scene's diagonal), loosened by --loosen.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "T", default_value_t = DEFAULT_TOLERANCE, help_heading = "AOVs and adaptive")
    )]
    pub tolerance: f32,
    /// The absolute part A of the stop, in units of the scene's diagonal l_diag (f_diff's
    /// unit: A = 0.001 is 0.1 % of l_diag).
    #[cfg_attr(
        feature = "cli",
        arg(
            long,
            value_name = "A",
            default_value_t = 0.0,
            help_heading = "AOVs and adaptive"
        )
    )]
    pub abs_tolerance: f32,
    /// Rays before the first check, as 8 rounds (a multiple of 8).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "m", default_value_t = DEFAULT_MIN_RAYS, help_heading = "AOVs and adaptive")
    )]
    pub min_rays: u32,
    /// The stop loosens as a pixel's rays N grow: σ_H < (T·H + A·l_diag)·(N/m)^G. 0: a fixed
    /// error; 1: stop where another round buys less error per ray than the first check did
    /// (the least mean error for the rays: use it with --abs-tolerance for f_diff).
    #[cfg_attr(
        feature = "cli",
        arg(
            long,
            value_name = "G",
            default_value_t = 0.0,
            help_heading = "AOVs and adaptive"
        )
    )]
    pub loosen: f32,
    /// A pixel never casts more rays than this.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "M", default_value_t = DEFAULT_MAX_RAYS, help_heading = "AOVs and adaptive")
    )]
    pub max_rays: u32,
    /// Radius of the ao AOV [default: the median of the image's H; needed for adaptive].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "R", help_heading = "AOVs and adaptive")
    )]
    pub ao_radius: Option<f32>,
}

impl Default for AdaptiveParams {
    fn default() -> Self {
        AdaptiveParams {
            weighting: Weighting::default(),
            sampler: Sampler::default(),
            tolerance: DEFAULT_TOLERANCE,
            abs_tolerance: 0.0,
            loosen: 0.0,
            min_rays: DEFAULT_MIN_RAYS,
            max_rays: DEFAULT_MAX_RAYS,
            ao_radius: None,
        }
    }
}

impl super::params::MethodParams for AdaptiveParams {}

impl AdaptiveParams {
    /// The adaptive gather these parameters name, checked.
    pub fn build(&self) -> Result<Adaptive> {
        Adaptive::new(self.weighting, self.tolerance, self.min_rays, self.max_rays)?
            .with_abs_tolerance(self.abs_tolerance)?
            .with_loosen(self.loosen)?
            .with_ao_radius(self.ao_radius)
            .map(|a| a.with_sampler(self.sampler))
    }
}

/// Adaptive final gathering.
#[derive(Clone, Copy, Debug)]
pub struct Adaptive {
    weighting: Weighting,
    sampler: Sampler,
    tolerance: f32,
    abs_tolerance: f32,
    loosen: f32,
    min_rays: u32,
    max_rays: u32,
    ao_radius: Option<f32>,
}

impl Adaptive {
    /// Stops a pixel at relative standard error `tolerance` (positive, or 0 with an absolute
    /// tolerance) or before passing `max_rays`; rounds of `min_rays / 8` rays, `min_rays` a
    /// positive multiple of 8 and at most `max_rays`.
    pub fn new(weighting: Weighting, tolerance: f32, min_rays: u32, max_rays: u32) -> Result<Self> {
        if !(tolerance >= 0.0 && tolerance.is_finite()) {
            let message = format!("must be a finite number, at least 0, not {tolerance}");
            return Err(Error::invalid("tolerance", message));
        }
        if min_rays == 0 || !min_rays.is_multiple_of(FIRST_ROUNDS) {
            let message = format!("must be a positive multiple of {FIRST_ROUNDS}, not {min_rays}");
            return Err(Error::invalid("min_rays", message));
        }
        if max_rays < min_rays {
            let message = format!("must be at least min_rays ({min_rays}), not {max_rays}");
            return Err(Error::invalid("max_rays", message));
        }
        Ok(Adaptive {
            weighting,
            sampler: Sampler::Grid,
            tolerance,
            abs_tolerance: 0.0,
            loosen: 0.0,
            min_rays,
            max_rays,
            ao_radius: None,
        })
    }

    /// Adds an absolute part to the stop: `abs_tolerance` (at least 0) times the scene's
    /// diagonal. The relative and absolute parts must not both be 0.
    pub fn with_abs_tolerance(self, abs_tolerance: f32) -> Result<Self> {
        if !(abs_tolerance >= 0.0 && abs_tolerance.is_finite()) {
            let message = format!("must be a finite number, at least 0, not {abs_tolerance}");
            return Err(Error::invalid("abs_tolerance", message));
        }
        if abs_tolerance == 0.0 && self.tolerance == 0.0 {
            let message = "is 0, and so is the absolute tolerance: give one of them, or a pixel never stops before max_rays";
            return Err(Error::invalid("tolerance", message));
        }
        Ok(Adaptive {
            abs_tolerance,
            ..self
        })
    }

    /// The stop loosened as a pixel's rays grow: by `(rays / min_rays)^loosen` (at least 0;
    /// 0, the default, keeps it fixed).
    pub fn with_loosen(self, loosen: f32) -> Result<Self> {
        if !(loosen >= 0.0 && loosen.is_finite()) {
            let message = format!("must be a finite number, at least 0, not {loosen}");
            return Err(Error::invalid("loosen", message));
        }
        Ok(Adaptive { loosen, ..self })
    }

    /// The directions drawn by `sampler`: rounds of jittered grids ([`Sampler::Grid`], this
    /// builder's default, spec §3.1) or consecutive blocks of one progressive sequence
    /// ([`Sampler::Sobol`], the default of [`AdaptiveParams`] and so of the CLI and Python).
    pub fn with_sampler(self, sampler: Sampler) -> Self {
        Adaptive { sampler, ..self }
    }

    /// The `ao` AOV's radius (positive); without one, the AO AOV is refused.
    pub fn with_ao_radius(self, ao_radius: Option<f32>) -> Result<Self> {
        Error::check_positive("ao_radius", ao_radius)?;
        Ok(Adaptive { ao_radius, ..self })
    }

    /// The parameters this gather is built from ([`AdaptiveParams::build`]).
    pub fn params(&self) -> AdaptiveParams {
        AdaptiveParams {
            weighting: self.weighting,
            sampler: self.sampler,
            tolerance: self.tolerance,
            abs_tolerance: self.abs_tolerance,
            loosen: self.loosen,
            min_rays: self.min_rays,
            max_rays: self.max_rays,
            ao_radius: self.ao_radius,
        }
    }

    /// Rays per round: `min_rays / 8`.
    pub fn per_round(&self) -> u32 {
        self.min_rays / FIRST_ROUNDS
    }

    /// The relative error below which a pixel of H `hmd` stops after `rays` rays: the stop
    /// `σ_H < (T·H + A·l_diag)·(rays/min_rays)^loosen` divided by H, `abs_error` being
    /// `A·l_diag`.
    #[inline]
    fn bound(&self, rays: u32, hmd: f32, abs_error: f32) -> f32 {
        let fixed = self.tolerance + abs_error / hmd;
        match self.loosen {
            0.0 => fixed,
            g => fixed * (rays as f32 / self.min_rays as f32).powf(g),
        }
    }
}

impl Estimator for Adaptive {
    fn method(&self) -> &'static str {
        "adaptive"
    }

    fn parameters(&self) -> Parameters {
        Parameters::of(&self.params(), &["ao_radius"])
    }

    fn aovs(&self) -> &'static [Aov] {
        &Aov::OF_GATHER
    }

    fn samples(&self) -> super::Samples {
        super::Samples::PerPixel
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        pixels * self.min_rays as u64 * 4
    }

    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        _: &'a GBuffer,
        _: &dyn Progress,
    ) -> Result<Prepared<'a>> {
        match (self.ao_radius, context.aovs.contains(&Aov::Ao)) {
            (None, true) => {
                return Err(Error::invalid(
                    "ao_radius",
                    "is needed for the ao AOV of adaptive",
                ))
            }
            (Some(_), false) => return Err(Error::invalid("ao_radius", super::gather::AO_RADIUS_UNREAD)),
            _ => {}
        }
        Ok(Prepared::Pixels {
            job: Box::new(AdaptivePixels {
                adaptive: self,
                context,
                abs_error: self.abs_tolerance * context.scene.diagonal(),
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}

/// `adaptive` on one image.
#[derive(Clone, Copy)]
struct AdaptivePixels<'a> {
    adaptive: &'a Adaptive,
    context: &'a EstimateContext<'a>,
    /// The absolute part of the stop, in the scene's units.
    abs_error: f32,
}

impl PixelJob for AdaptivePixels<'_> {
    fn label(&self) -> &'static str {
        "adaptive"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn worker<'w>(&'w self, _: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        Box::new(*self)
    }

    fn details(&self, pass: &PixelPass) -> Details {
        Details {
            ao_radius: self.adaptive.ao_radius,
            mean_rays_per_pixel: Some(pass.tally.rays as f64 / pass.pixels.max(1) as f64),
            ..Details::default()
        }
    }
}

impl PixelWorker for AdaptivePixels<'_> {
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, aov: &mut AovSample) -> f32 {
        let (a, c) = (self.adaptive, self.context);
        let start = GatherStart::at_hit(hit);
        let mut point = PointGather::new(a.weighting, a.ao_radius)
            .with_sampler(a.sampler)
            .with_rounds(Rounds::Blocks);
        let n = a.per_round();
        for _ in 0..FIRST_ROUNDS {
            point.round(c.accel, &start, c.seed, pixel, n, c.clamp);
        }
        // The stop (see `bound`). relerr is NaN where every ray escaped (H = ∞: nothing more
        // to learn there), and the comparison false.
        while point.rays + n <= a.max_rays
            && point.relerr() >= a.bound(point.rays, point.mean.value(), self.abs_error)
        {
            point.round(c.accel, &start, c.seed, pixel, n, c.clamp);
        }
        point.finish(tally, aov);
        point.mean.value()
    }
}
