//! `adaptive`: final gathering that stops when H is known well enough (issue #12; the paper's
//! future work asks how many rays a pixel really needs).
//!
//! Per pixel, rounds of `min_rays / 8` rays (each its own jittered stratified grid, as
//! `gather`'s rounds) are cast: first 8, then one more at a time until the relative standard
//! error of H from the rounds' spread is below `tolerance`, or another round would pass
//! `max_rays`. A pixel's rounds depend only on its own rays: the image is the same for any
//! thread count. Random numbers are `gather`'s: with the same rounds, a pixel that stops at N
//! rays has the H of `gather --rays N --rounds N/(min_rays/8)`.

use super::gather::PointGather;
use super::{
    Aov, AovSample, EstimateContext, Estimator, GBuffer, PixelJob, PixelPass, PixelWorker, Prepared, Tally,
};
use crate::accel::GatherStart;
use crate::accel::Hit;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{AdaptiveParameters, Details, GatherParameters, Parameters};
use crate::sampling::{strata, Weighting};

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
    /// A pixel stops once the relative standard error of its H is below T.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "T", default_value_t = DEFAULT_TOLERANCE, help_heading = "AOVs and adaptive")
    )]
    pub tolerance: f32,
    /// Rays before the first check, as 8 rounds (a multiple of 8).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "m", default_value_t = DEFAULT_MIN_RAYS, help_heading = "AOVs and adaptive")
    )]
    pub min_rays: u32,
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
            tolerance: DEFAULT_TOLERANCE,
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
            .with_ao_radius(self.ao_radius)
    }
}

/// Adaptive final gathering.
#[derive(Clone, Copy, Debug)]
pub struct Adaptive {
    weighting: Weighting,
    tolerance: f32,
    min_rays: u32,
    max_rays: u32,
    ao_radius: Option<f32>,
}

impl Adaptive {
    /// Stops a pixel at relative standard error `tolerance` (positive) or before passing
    /// `max_rays`; rounds of `min_rays / 8` rays, `min_rays` a positive multiple of 8 and at
    /// most `max_rays`.
    pub fn new(weighting: Weighting, tolerance: f32, min_rays: u32, max_rays: u32) -> Result<Self> {
        Error::check_positive("tolerance", Some(tolerance))?;
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
            tolerance,
            min_rays,
            max_rays,
            ao_radius: None,
        })
    }

    /// The `ao` AOV's radius (positive); without one, the AO AOV is refused.
    pub fn with_ao_radius(self, ao_radius: Option<f32>) -> Result<Self> {
        Error::check_positive("ao_radius", ao_radius)?;
        Ok(Adaptive { ao_radius, ..self })
    }

    fn per_round(&self) -> u32 {
        self.min_rays / FIRST_ROUNDS
    }
}

impl Estimator for Adaptive {
    fn method(&self) -> &'static str {
        "adaptive"
    }

    fn parameters(&self) -> Parameters {
        let grid = strata(self.per_round());
        Parameters {
            // The rays per pixel vary: see rays_cast and the rays AOV.
            rays: None,
            gather: Some(GatherParameters {
                weighting: self.weighting,
                strata: [grid.0, grid.1],
                rounds: FIRST_ROUNDS,
                sampler: Default::default(),
            }),
            adaptive: Some(AdaptiveParameters {
                tolerance: self.tolerance,
                min_rays: self.min_rays,
                max_rays: self.max_rays,
                rays_per_round: self.per_round(),
            }),
            ..Parameters::default()
        }
    }

    fn aovs(&self) -> &'static [Aov] {
        &Aov::ALL
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
        if context.aovs.contains(&Aov::Ao) && self.ao_radius.is_none() {
            return Err(Error::invalid(
                "ao_radius",
                "is needed for the ao AOV of adaptive",
            ));
        }
        Ok(Prepared::Pixels {
            job: Box::new(AdaptivePixels {
                adaptive: self,
                context,
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
        let mut point = PointGather::new(a.weighting, a.ao_radius);
        let n = a.per_round();
        for _ in 0..FIRST_ROUNDS {
            point.round(c.accel, &start, c.seed, pixel, n, c.clamp);
        }
        // relerr is NaN where every ray escaped: nothing more to learn there.
        while point.rays + n <= a.max_rays && point.relerr() >= a.tolerance {
            point.round(c.accel, &start, c.seed, pixel, n, c.clamp);
        }
        point.finish(tally, aov);
        point.mean.value()
    }
}
