//! `gather`: ray-traced final gathering (spec §3.1; paper §3.1).
//!
//! `N` rays per pixel, stratified on the most nearly square `a × b` grid, jittered, mapped to
//! the hemisphere around the camera-facing normal by the chosen weighting; `H = N / Σ 1/d`.
//! Random numbers are keyed by (seed, key, ray index), the key being the pixel index in an
//! image, so the image is the same whatever the thread count or tiling; and H at a list of
//! points ([`crate::points`]) keyed by pixel index is the image's H.
//!
//! **Rounds.** With `rounds` R > 1 the N rays are cast as R independent rounds, each its own
//! jittered stratified grid of N/R rays (ray indices continue from round to round, so R = 1
//! is the single grid). H is still `N / Σ 1/d` over all rays; the spread of the rounds' means
//! of `1/d` gives its standard error (batch means: each round is an unbiased estimate of the
//! mean of `1/d`, and rounds are independent, so their sample variance over R is the variance
//! of the overall mean; the plain sample variance of the N stratified rays would overstate
//! it). The relative standard error of H is that of the mean of `1/d` (delta method).
//!
//! This file holds the estimator (its parameters, the pixel pass, the GPU glue, the `ao`
//! radius); `directions.rs` the directions (the grid, its 4 × 2 blocks as lanes, the
//! progressive sequences' rounds, the packets) and `point.rs` one point's gather, round by
//! round, which `adaptive` and H at points share.

mod directions;
mod point;

use glam::Vec3;

use super::{
    Aov, AovSample, DistanceClamp, EstimateContext, Estimator, GBuffer, PixelJob, PixelPass, PixelWorker,
    Prepared, Tally,
};
use crate::accel::{GatherStart, Hit, RayCaster, PACKET};
use crate::backend::Backend;
pub use crate::backend::DispatchSplit;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{Details, DeviceDetails, Parameters};
use crate::sampling::{strata, Sampler, Weighting};
pub(crate) use directions::Rounds;
use directions::{packets, sampler_directions, GridBlocks};
pub(crate) use point::PointGather;

/// Default gather rays per pixel for `hmdist render`: an 8 × 8 stratified grid, a clean
/// picture of `cube` at 1024² in about 10 s on 2 cores. The paper's reference uses 65,536;
/// its accuracy levels off from about 1,024.
pub const DEFAULT_RAYS: u32 = 64;

/// Final gathering with `rays` rays per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Gather {
    rays: u32,
    weighting: Weighting,
    rounds: u32,
    ao_radius: Option<f32>,
    backend: Backend,
    sampler: Sampler,
    #[cfg_attr(not(feature = "gpu"), allow(dead_code))]
    split: Option<DispatchSplit>,
}

/// Rounds of gather rays when the `relerr` AOV is asked for and no rounds are named.
pub const DEFAULT_ERROR_ROUNDS: u32 = 8;

/// `gather`'s parameters: the CLI's flags (`--rays`), Python's keywords and the registry's
/// build all come from this one list.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct GatherParams {
    /// Gather rays per pixel N (the paper's reference is 65536).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = DEFAULT_RAYS))]
    pub rays: u32,
    /// Direction weighting over the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Weighting::Cosine))]
    pub weighting: Weighting,
    /// How the directions fill the hemisphere: a progressive Owen-scrambled Sobol sequence
    /// (each round its own; 14–29 % lower f_diff at equal N on `cube` and `hall`), or one
    /// jittered grid of the N rays (docs/spec.md §3.1, the paper's experiments), on either backend.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Sampler::Sobol))]
    pub sampler: Sampler,
    /// Cast the rays as R independent rounds (R divides N), for the relerr AOV
    /// [default: 1; 8 with --aov relerr].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "R", help_heading = "AOVs and adaptive")
    )]
    pub rounds: Option<u32>,
    /// Radius of the ao AOV [default: the median of the image's H; needed for adaptive].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "R", help_heading = "AOVs and adaptive")
    )]
    pub ao_radius: Option<f32>,
    /// Where the rays are cast (or the hemicubes built).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Backend::Auto))]
    pub backend: Backend,
}

impl Default for GatherParams {
    fn default() -> Self {
        GatherParams {
            rays: DEFAULT_RAYS,
            weighting: Weighting::default(),
            sampler: Sampler::default(),
            rounds: None,
            ao_radius: None,
            backend: Backend::default(),
        }
    }
}

impl super::params::MethodParams for GatherParams {
    fn on_backend(&mut self, backend: Backend, _: crate::backend::GpuFill) {
        self.backend = backend;
    }

    fn for_aovs(&mut self, aovs: &[super::Aov]) {
        if aovs.contains(&super::Aov::Relerr) {
            self.rounds.get_or_insert(DEFAULT_ERROR_ROUNDS);
        }
    }
}

impl GatherParams {
    /// The gather these parameters name, checked.
    pub fn build(&self) -> Result<Gather> {
        let gather = Gather::new(self.rays, self.weighting)?.with_rounds(self.rounds.unwrap_or(1))?;
        gather
            .with_ao_radius(self.ao_radius)?
            .with_backend(self.backend)
            .with_sampler(self.sampler)
    }
}

impl Gather {
    /// `rays` gather rays per point (at least 1), weighted by `weighting`.
    pub fn new(rays: u32, weighting: Weighting) -> Result<Self> {
        if rays == 0 {
            return Err(Error::invalid("rays", "must be at least 1, not 0"));
        }
        Ok(Gather {
            rays,
            weighting,
            rounds: 1,
            ao_radius: None,
            backend: Backend::Cpu,
            sampler: Sampler::Grid,
            split: None,
        })
    }

    /// The same rays cast as `rounds` independent rounds of `rays / rounds` rays each, for
    /// the `relerr` AOV; `rounds` must divide the rays.
    pub fn with_rounds(self, rounds: u32) -> Result<Self> {
        if rounds == 0 || !self.rays.is_multiple_of(rounds) {
            let message = format!(
                "must divide the rays ({}) into whole rounds, not {rounds}",
                self.rays
            );
            return Err(Error::invalid("rounds", message));
        }
        Ok(Gather { rounds, ..self })
    }

    /// The `ao` AOV's radius (positive); without one, the median of the image's H.
    pub fn with_ao_radius(self, ao_radius: Option<f32>) -> Result<Self> {
        Error::check_positive("ao_radius", ao_radius)?;
        Ok(Gather { ao_radius, ..self })
    }

    /// The rays cast by `backend`: [`Backend::Gpu`] traces them in a compute shader
    /// ([`crate::gpu`]), [`Backend::Auto`] does so where there is a hardware GPU. The default
    /// is [`Backend::Cpu`] (`hmdist render`'s default is `auto`).
    pub fn with_backend(self, backend: Backend) -> Self {
        Gather { backend, ..self }
    }

    /// The directions drawn by `sampler` on either backend: this builder's default is
    /// [`Sampler::Grid`] (spec §3.1); [`GatherParams`]' default, so the CLI's and Python's,
    /// is [`Sampler::Sobol`].
    pub fn with_sampler(self, sampler: Sampler) -> Result<Self> {
        Ok(Gather { sampler, ..self })
    }

    /// How the directions are drawn.
    pub fn sampler(&self) -> Sampler {
        self.sampler
    }

    /// On the GPU, the work split into dispatches of at most `split`'s points and rays
    /// instead of dispatches of about half a second. The result is the same: this is for
    /// tests that check so.
    pub fn with_dispatch_split(self, split: DispatchSplit) -> Self {
        Gather {
            split: Some(split),
            ..self
        }
    }

    /// The backend the rays are cast by.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The GPU to cast on, or `None` for the CPU: see [`Gather::with_backend`].
    #[cfg(feature = "gpu")]
    pub(crate) fn gpu(&self, accel: &crate::accel::Accel) -> Result<Option<crate::gpu::GpuScene>> {
        crate::gpu::open_for(self.backend, |software| {
            crate::gpu::GpuScene::new(accel, software)
        })
    }

    /// The job a GPU gather does for this gather.
    #[cfg(feature = "gpu")]
    pub(crate) fn gpu_job(
        &self,
        seed: u64,
        clamp: DistanceClamp,
        ao_radius: Option<f32>,
    ) -> crate::gpu::gather::GatherJob {
        crate::gpu::gather::GatherJob {
            rays: self.rays,
            rounds: self.rounds,
            weighting: self.weighting,
            seed,
            d_min: clamp.min,
            t_max: clamp.max,
            ao_radius,
            split: self.split,
            cube_res: 0,
            sampler: self.sampler,
        }
    }

    /// The point's figures from a GPU gather of this gather with `ao_radius`.
    #[cfg(feature = "gpu")]
    pub(crate) fn point_from_gpu(
        &self,
        ao_radius: Option<f32>,
        gpu: crate::gpu::gather::GpuPoint,
    ) -> PointGather {
        PointGather::from_rounds(
            self.weighting,
            ao_radius,
            gpu.round_sums.iter().copied(),
            self.rays / self.rounds,
            (gpu.escaped, gpu.dmin),
            gpu.ao,
        )
    }

    /// Independent rounds the rays are cast in.
    pub fn rounds(&self) -> u32 {
        self.rounds
    }

    /// Gather rays per point.
    pub fn rays_per_point(&self) -> u32 {
        self.rays
    }

    /// The direction weighting.
    pub fn weighting(&self) -> Weighting {
        self.weighting
    }

    /// The gather directions of the point keyed `key`, in its local frame (z = normal), as one
    /// round of all its rays (one stratified grid, or the first N points of the progressive
    /// sequence): the one definition shared by `gather` (with one round) and the CPU cube
    /// map, which looks the same directions up in its hemicube (spec §3.2). The GPU cube
    /// map's shader mirrors the grid.
    #[inline]
    pub fn directions(&self, seed: u64, key: u64) -> impl Iterator<Item = Vec3> + '_ {
        sampler_directions(
            self.sampler,
            self.weighting,
            (seed, key),
            (Rounds::Replicates, 0),
            self.rays,
        )
    }

    /// The gather rays of pixel `pixel` from its surface point: the origin (offset off the
    /// surface) and the world-space directions of one stratified grid.
    #[inline]
    pub fn rays(&self, hit: &Hit, seed: u64, pixel: u64) -> (Vec3, impl Iterator<Item = Vec3> + '_) {
        let start = GatherStart::at_hit(hit);
        let frame = start.frame;
        (
            start.origin,
            self.directions(seed, pixel).map(move |w| frame.to_world(w)),
        )
    }

    /// The gather rays of pixel `pixel` ([`Gather::rays`]) as `render` makes and casts them
    /// where its grid splits into 4 × 2 blocks of strata (nearly always): the origin, and per
    /// block the world directions as lanes (lane `q` of the block at `(column, row)` is ray
    /// `(row + q div 4)·a + column + q mod 4` of the `a × b` grid) with the rays' indices.
    /// `None` where the gather is not cast in such blocks (a Sobol sampler, or a grid that
    /// does not split into them). What `cargo bench --bench gather` times apart.
    pub fn ray_blocks(
        &self,
        hit: &Hit,
        seed: u64,
        pixel: u64,
    ) -> Option<(
        Vec3,
        impl Iterator<Item = ([[f32; PACKET]; 3], [u32; PACKET])> + '_,
    )> {
        let (a, b) = strata(self.rays);
        if self.sampler != Sampler::Grid || !packets((a, b)).blocks {
            return None;
        }
        let start = GatherStart::at_hit(hit);
        let blocks = GridBlocks::new(self.weighting, (seed, pixel), 0, self.rays, start.frame);
        let corners = (0..b)
            .step_by(2)
            .flat_map(move |row| (0..a).step_by(4).map(move |column| (column, row)));
        Some((
            start.origin,
            corners.map(move |(column, row)| {
                let index = std::array::from_fn(|q| row * a + blocks.lane_offset(column, q) as u32);
                (blocks.block(column, row).0, index)
            }),
        ))
    }

    /// The parameters this gather is built from ([`GatherParams::build`]), its rounds filled in.
    pub fn params(&self) -> GatherParams {
        GatherParams {
            rays: self.rays,
            weighting: self.weighting,
            sampler: self.sampler,
            rounds: Some(self.rounds),
            ao_radius: self.ao_radius,
            backend: self.backend,
        }
    }

    /// H from `start` with the random numbers of `key`, and how many of its rays escaped.
    pub(crate) fn at<R: RayCaster>(
        &self,
        accel: &R,
        start: &GatherStart,
        seed: u64,
        key: u64,
        clamp: DistanceClamp,
    ) -> (f32, u32) {
        let mut point = PointGather::new(self.weighting, None).with_sampler(self.sampler);
        let per_round = self.rays / self.rounds;
        for _ in 0..self.rounds {
            point.round(accel, start, seed, key, per_round, clamp);
        }
        (point.mean.value(), point.escaped)
    }
}

impl Estimator for Gather {
    fn method(&self) -> &'static str {
        "gather"
    }

    fn parameters(&self) -> Parameters {
        Parameters::of(&self.params(), &["backend", "ao_radius"])
    }

    fn aovs(&self) -> &'static [Aov] {
        &Aov::OF_GATHER
    }

    fn samples(&self) -> super::Samples {
        super::Samples::Fixed(self.rays)
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        pixels * self.rays as u64
    }

    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        gbuffer: &'a GBuffer,
        progress: &dyn Progress,
    ) -> Result<Prepared<'a>> {
        if context.aovs.contains(&Aov::Relerr) && self.rounds < 2 {
            let message = format!(
                "of {} cannot give the relerr AOV: it needs at least 2",
                self.rounds
            );
            return Err(Error::invalid("rounds", message));
        }
        let ao = self.ao_radius(context)?;
        #[cfg(feature = "gpu")]
        if let Some(gpu) = self.gpu(context.accel)? {
            return estimate_on_gpu(&gpu, self, context, gbuffer, ao, progress)
                .map(|e| Prepared::Done(Box::new(e)));
        }
        #[cfg(not(feature = "gpu"))]
        if self.backend.is_gpu() {
            return Err(Backend::unavailable());
        }
        let ao_radius = match ao {
            AoRadius::Given(r) => Some(r),
            // The default radius is the median of H: a first pass finds it.
            AoRadius::Median => Some(median_hmd(self, context, gbuffer, progress)?),
            AoRadius::None => None,
        };
        Ok(Prepared::Pixels {
            job: Box::new(GatherPixels {
                gather: self,
                context,
                ao_radius,
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}

/// `gather` on the GPU over the whole image: H, the AOVs asked for, and what it took.
#[cfg(feature = "gpu")]
fn estimate_on_gpu(
    scene: &crate::gpu::GpuScene,
    gather: &Gather,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    ao: AoRadius,
    progress: &dyn Progress,
) -> Result<super::Estimate> {
    use crate::gpu::gather::gather_points;
    use crate::report::PhaseSeconds;

    let (pixels, starts) = gbuffer.starts();
    let key = |i: usize| pixels[i] as u64;
    let mut extra = 0.0;
    let ao_radius = match ao {
        AoRadius::None => None,
        AoRadius::Given(r) => Some(r),
        AoRadius::Median => {
            // The default radius is the median of H: a first pass finds it.
            let job = gather.gpu_job(context.seed, context.clamp, None);
            let first = gather_points(scene, &job, &starts, key, progress, |p| {
                gather.point_from_gpu(None, p).mean.value()
            })?;
            extra = first.trace_seconds;
            Some(median_finite(first.points))
        }
    };
    let job = gather.gpu_job(context.seed, context.clamp, ao_radius);
    let done = gather_points(scene, &job, &starts, key, progress, |p| {
        gather.point_from_gpu(ao_radius, p)
    })?;

    let mut hmd = vec![f32::NAN; gbuffer.points.len()];
    let mut samples = vec![AovSample::default(); if context.aovs.is_empty() { 0 } else { hmd.len() }];
    let mut tally = Tally::default();
    let mut scratch = AovSample::default();
    for (&pixel, point) in pixels.iter().zip(&done.points) {
        hmd[pixel] = point.mean.value();
        let aov = samples.get_mut(pixel).unwrap_or(&mut scratch);
        point.finish(&mut tally, aov);
    }
    let aovs = super::AovImage::channels(context.aovs, &samples);
    let trace_seconds = done.trace_seconds + extra;
    Ok(super::Estimate {
        hmd,
        rays: Some(super::RayCount {
            cast: tally.rays,
            escaped: tally.escaped,
            seconds: done.trace_seconds,
        }),
        phases: PhaseSeconds {
            gpu_upload: Some(scene.upload_seconds + done.upload_seconds),
            gpu_trace: Some(trace_seconds),
            gpu_readback: Some(done.readback_seconds),
            ..PhaseSeconds::default()
        },
        aovs,
        details: Details {
            ao_radius,
            device: Some(DeviceDetails::gpu(scene.adapter(), scene.device.software)),
            grays_per_s: Some(tally.rays as f64 / done.trace_seconds.max(1e-9) / 1e9),
            ..Details::default()
        },
    })
}

/// The `ao` AOV's radius, where it is asked for.
#[derive(Clone, Copy, Debug)]
pub(crate) enum AoRadius {
    /// The AOV is not asked for.
    None,
    /// As given.
    Given(f32),
    /// The median of the image's H, from a first pass without AOVs.
    Median,
}

/// Why a radius given without the `ao` AOV is refused: nothing would read it (spec §8).
pub(crate) const AO_RADIUS_UNREAD: &str =
    "is read only by the ao AOV: ask for that AOV too, or leave the radius out";

impl Gather {
    fn ao_radius(&self, context: &EstimateContext) -> Result<AoRadius> {
        Ok(match (self.ao_radius, context.aovs.contains(&Aov::Ao)) {
            (Some(r), true) => AoRadius::Given(r),
            (None, true) if context.whole_image => AoRadius::Median,
            (None, true) => {
                let message =
                    "is needed for the ao AOV of a shard: the default, the median of H, is the whole image's";
                return Err(Error::invalid("ao_radius", message));
            }
            (Some(_), false) => return Err(Error::invalid("ao_radius", AO_RADIUS_UNREAD)),
            (None, false) => AoRadius::None,
        })
    }
}

/// The median of the finite values of `hmd` (+inf where none is finite).
pub(crate) fn median_finite(hmd: impl IntoIterator<Item = f32>) -> f32 {
    let mut finite: Vec<f32> = hmd.into_iter().filter(|h| h.is_finite()).collect();
    if finite.is_empty() {
        return f32::INFINITY;
    }
    let middle = finite.len() / 2;
    *finite.select_nth_unstable_by(middle, f32::total_cmp).1
}

/// The median of the finite H of the image, from a pass without AOVs (the `ao` AOV's default
/// radius; +inf where no pixel has a finite H).
fn median_hmd(
    gather: &Gather,
    context: &EstimateContext,
    gbuffer: &GBuffer,
    progress: &dyn Progress,
) -> Result<f32> {
    let first = EstimateContext {
        aovs: &[],
        ..*context
    };
    let pass = GatherPixels {
        gather,
        context: &first,
        ao_radius: None,
    };
    let (hmd, _, _) = super::pass::pixel_pass(&pass, gbuffer, &[], progress)?;
    Ok(median_finite(hmd))
}

/// `gather` on one image: no scratch, no preparation (but the AO radius's first pass).
#[derive(Clone, Copy)]
struct GatherPixels<'a> {
    gather: &'a Gather,
    context: &'a EstimateContext<'a>,
    /// The `ao` AOV's radius, where it was asked for.
    ao_radius: Option<f32>,
}

impl PixelJob for GatherPixels<'_> {
    fn label(&self) -> &'static str {
        "gather"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn progress_per_pixel(&self) -> u64 {
        self.gather.rays as u64
    }

    fn worker<'w>(&'w self, progress: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        Box::new(GatherWorker {
            pixels: *self,
            progress,
        })
    }

    fn details(&self, _: &PixelPass) -> Details {
        Details {
            ao_radius: self.ao_radius,
            device: Some(DeviceDetails::cpu()),
            ..Details::default()
        }
    }
}

/// One thread's `gather` pixels, counting their rays as progress.
struct GatherWorker<'w> {
    pixels: GatherPixels<'w>,
    progress: &'w dyn Progress,
}

impl PixelWorker for GatherWorker<'_> {
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, aov: &mut AovSample) -> f32 {
        let (c, g) = (self.pixels.context, self.pixels.gather);
        let start = GatherStart::at_hit(hit);
        let mut point = PointGather::new(g.weighting, self.pixels.ao_radius).with_sampler(g.sampler);
        let per_round = g.rays / g.rounds;
        for _ in 0..g.rounds {
            point.round_counted(
                c.accel,
                &start,
                (c.seed, pixel),
                per_round,
                c.clamp,
                self.progress,
            );
        }
        point.finish(tally, aov);
        point.mean.value()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_blocks_are_the_pixels_rays_bit_for_bit() {
        // What the gather benchmark casts (`Gather::ray_blocks`) against `Gather::rays`: the
        // same origin, and every ray once, in its lane, with its index.
        let hit = Hit {
            t: 1.0,
            triangle: 3,
            point: Vec3::new(0.5, -1.0, 2.0),
            point_error: Vec3::splat(1e-7),
            normal: Vec3::new(0.3, -0.5, 0.8).normalize(),
        };
        for (n, weighting) in [
            (256, Weighting::Cosine),
            (4_096, Weighting::Uniform),
            (32, Weighting::Cosine),
        ] {
            let gather = Gather::new(n, weighting).unwrap();
            let (origin, rays) = gather.rays(&hit, 7, 11);
            let expected: Vec<Vec3> = rays.collect();
            let (block_origin, blocks) = gather.ray_blocks(&hit, 7, 11).expect("a grid in 4 × 2 blocks");
            assert_eq!(
                block_origin.to_array().map(f32::to_bits),
                origin.to_array().map(f32::to_bits)
            );
            let mut seen = vec![false; n as usize];
            for (world, index) in blocks {
                for (q, &j) in index.iter().enumerate() {
                    let got = [world[0][q], world[1][q], world[2][q]].map(f32::to_bits);
                    assert_eq!(
                        got,
                        expected[j as usize].to_array().map(f32::to_bits),
                        "n = {n}, ray {j}"
                    );
                    assert!(
                        !std::mem::replace(&mut seen[j as usize], true),
                        "n = {n}: ray {j} twice"
                    );
                }
            }
            assert!(seen.iter().all(|&s| s), "n = {n}: a ray missing");
        }
        // Not in blocks: 1,000 rays (a 25 × 40 grid), and a Sobol net.
        assert!(Gather::new(1_000, Weighting::Cosine)
            .unwrap()
            .ray_blocks(&hit, 7, 11)
            .is_none());
        let sobol = Gather::new(256, Weighting::Cosine)
            .unwrap()
            .with_sampler(Sampler::Sobol)
            .unwrap();
        assert!(sobol.ray_blocks(&hit, 7, 11).is_none());
    }
}
