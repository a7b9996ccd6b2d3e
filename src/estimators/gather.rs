//! `gather`: ray-traced final gathering (SPEC §3.1; paper §3.1).
//!
//! `N` rays per pixel, stratified on the most nearly square `a × b` grid, jittered, mapped to
//! the hemisphere around the camera-facing normal by the chosen weighting; `H = N / Σ 1/d`.
//! Random numbers are keyed by (seed, key, ray index), the key being the pixel index in an
//! image, so the image is the same whatever the thread count or tiling; and H at a list of
//! points ([`crate::points`]) keyed by pixel index is the image's H.

use glam::Vec3;

use super::{
    EstimateContext, Estimator, GBuffer, HarmonicMean, PixelPass, PixelWork, PixelWorker, Tally, Work,
};
use crate::accel::{Hit, RayCaster};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{Details, GatherParameters, Parameters};
use crate::sampling::{hemisphere, random_pair, strata, stratified, Frame, Weighting};

/// Default gather rays per pixel for `hmdist render`: an 8 × 8 stratified grid, a clean
/// picture of `cube` at 1024² in about 10 s on 2 cores. The paper's reference uses 65,536;
/// its accuracy levels off from about 1,024.
pub const DEFAULT_RAYS: u32 = 64;

/// Final gathering with `rays` rays per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Gather {
    rays: u32,
    weighting: Weighting,
}

/// A gather's start: the origin offset off the surface, the normal whose hemisphere is
/// sampled, and the triangle the rays leave (`None` where it is not known).
#[derive(Clone, Copy, Debug)]
pub(crate) struct GatherStart {
    pub origin: Vec3,
    pub normal: Vec3,
    pub leaving: Option<u32>,
}

impl GatherStart {
    /// The start at a primary hit, its normal already facing the camera.
    pub fn at_hit(hit: &Hit) -> Self {
        GatherStart {
            origin: hit.spawn_origin(hit.normal),
            normal: hit.normal,
            leaving: Some(hit.triangle),
        }
    }
}

impl Gather {
    /// `rays` gather rays per point (at least 1), weighted by `weighting`.
    pub fn new(rays: u32, weighting: Weighting) -> Result<Self> {
        if rays == 0 {
            return Err(Error::invalid("rays", "must be at least 1, not 0"));
        }
        Ok(Gather { rays, weighting })
    }

    /// Gather rays per point.
    pub fn rays_per_point(&self) -> u32 {
        self.rays
    }

    /// The direction weighting.
    pub fn weighting(&self) -> Weighting {
        self.weighting
    }

    /// The gather directions of the point keyed `key`, in its local frame (z = normal): the
    /// one definition shared by `gather` and the CPU cube map, which looks the same
    /// directions up in its hemicube (SPEC §3.2). The GPU cube map's shader mirrors it.
    #[inline]
    pub fn directions(&self, seed: u64, key: u64) -> impl Iterator<Item = Vec3> + '_ {
        let grid = strata(self.rays);
        (0..self.rays).map(move |j| {
            let u = stratified(j, grid, random_pair(seed, key, j as u64));
            hemisphere(self.weighting, u)
        })
    }

    /// The gather rays of pixel `pixel` from its surface point: the origin (offset off the
    /// surface) and the world-space directions, exactly the rays the estimator casts.
    #[inline]
    pub fn rays(&self, hit: &Hit, seed: u64, pixel: u64) -> (Vec3, impl Iterator<Item = Vec3> + '_) {
        let start = GatherStart::at_hit(hit);
        let frame = Frame::from_normal(start.normal);
        (
            start.origin,
            self.directions(seed, pixel).map(move |w| frame.to_world(w)),
        )
    }

    /// H from `start` with the random numbers of `key`, and how many of its rays escaped.
    pub(crate) fn at<R: RayCaster>(
        &self,
        accel: &R,
        start: &GatherStart,
        seed: u64,
        key: u64,
        clamp: super::DistanceClamp,
    ) -> (f32, u32) {
        let frame = Frame::from_normal(start.normal);
        let mut mean = HarmonicMean::default();
        let mut escaped = 0;
        for w in self.directions(seed, key) {
            let d = accel.hit_distance(start.origin, frame.to_world(w), clamp.max, start.leaving);
            escaped += d.is_infinite() as u32;
            mean.add(d, clamp);
        }
        (mean.value(), escaped)
    }

    /// This gather's entries in the report.
    pub(crate) fn report_parameters(&self) -> GatherParameters {
        let grid = strata(self.rays);
        GatherParameters {
            weighting: self.weighting,
            strata: [grid.0, grid.1],
        }
    }
}

impl Estimator for Gather {
    fn method(&self) -> &'static str {
        "gather"
    }

    fn parameters(&self) -> Parameters {
        Parameters {
            rays: Some(self.rays),
            gather: Some(self.report_parameters()),
            ..Parameters::default()
        }
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        pixels * self.rays as u64
    }

    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        _: &'a GBuffer,
        _: &dyn Progress,
    ) -> Result<Work<'a>> {
        Ok(Work::Pixels {
            work: Box::new(GatherPixels {
                gather: self,
                context,
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}

/// `gather` on one image: no scratch, no preparation.
#[derive(Clone, Copy)]
struct GatherPixels<'a> {
    gather: &'a Gather,
    context: &'a EstimateContext<'a>,
}

impl PixelWork for GatherPixels<'_> {
    fn label(&self) -> &'static str {
        "gather"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn worker(&self) -> Box<dyn PixelWorker + '_> {
        Box::new(*self)
    }

    fn details(&self, _: &PixelPass) -> Details {
        Details::default()
    }
}

impl PixelWorker for GatherPixels<'_> {
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally) -> f32 {
        let c = self.context;
        let (h, escaped) = self
            .gather
            .at(c.accel, &GatherStart::at_hit(hit), c.seed, pixel, c.clamp);
        tally.rays += self.gather.rays as u64;
        tally.escaped += escaped as u64;
        h
    }
}
