//! `gather`: ray-traced final gathering (SPEC §3.1; paper §3.1).
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

use glam::Vec3;

use super::{
    Aov, AovSample, DistanceClamp, EstimateContext, Estimator, GBuffer, HarmonicMean, PixelJob, PixelPass,
    PixelWorker, Prepared, Tally,
};
use crate::accel::{GatherStart, Hit, RayCaster, RayLanes, PACKET};
use crate::backend::Backend;
pub use crate::backend::DispatchSplit;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{Details, DeviceDetails, GatherParameters, Parameters};
use crate::sampling::{
    hemisphere, hemisphere_lanes, in_stratum, in_stratum_lanes, strata, Frame, Progressive, Sampler, Stream,
    Weighting,
};

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

/// Why a sampler other than the grid is refused on the GPU.
const SAMPLER_ON_GPU: &str =
    "sobol runs on the CPU backend only (the GPU gather makes grid directions): use --backend cpu";

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
    /// How the directions fill the hemisphere: one jittered grid of the N rays, or a
    /// progressive Owen-scrambled Sobol sequence (each round its own; CPU backend only).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Sampler::Grid))]
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

    /// The directions drawn by `sampler` ([`Sampler::Grid`] by default). The GPU gather makes
    /// grid directions only: [`Sampler::Sobol`] on [`Backend::Gpu`] or
    /// [`Backend::GpuSoftware`] is refused, and [`Backend::Auto`] runs it on the CPU.
    pub fn with_sampler(self, sampler: Sampler) -> Result<Self> {
        let backend = match (sampler, self.backend) {
            (Sampler::Sobol, Backend::Auto) => Backend::Cpu,
            (Sampler::Sobol, b) if b.is_gpu() => return Err(Error::invalid("sampler", SAMPLER_ON_GPU)),
            (_, b) => b,
        };
        Ok(Gather {
            sampler,
            backend,
            ..self
        })
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
        if self.sampler != Sampler::Grid {
            // The GPU gather makes grid directions only: see `with_sampler`.
            return match self.backend.is_gpu() {
                true => Err(Error::invalid("sampler", SAMPLER_ON_GPU)),
                false => Ok(None),
            };
        }
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
    /// map, which looks the same directions up in its hemicube (SPEC §3.2). The GPU cube
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

    /// This gather's entries in the report.
    pub(crate) fn report_parameters(&self) -> GatherParameters {
        let grid = strata(self.rays / self.rounds);
        GatherParameters {
            weighting: self.weighting,
            strata: [grid.0, grid.1],
            rounds: self.rounds,
            sampler: self.sampler,
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

    fn aovs(&self) -> &'static [Aov] {
        &Aov::ALL
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

/// Why a radius given without the `ao` AOV is refused: nothing would read it (SPEC §8).
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

/// The directions of round `round` (of `n` rays) of the point keyed `key`, in its local frame:
/// a jittered stratified grid of `n` rays, ray indices `round·n …`.
#[inline]
pub(crate) fn round_directions(
    weighting: Weighting,
    seed: u64,
    key: u64,
    round: u32,
    n: u32,
) -> GridDirections {
    GridDirections {
        weighting,
        random: Stream::new(seed, key),
        grid: strata(n),
        stratum: (0, 0),
        counter: round as u64 * n as u64,
    }
}

/// [`round_directions`]: ray `j = k·a + i` is stratum `(i, k)`, rows of the grid in turn
/// (`stratified`'s order, without its division per ray), drawn with counter `round·n + j`.
/// A plain iterator rather than a chain of adapters: the chain cost ~40 instructions a ray.
pub(crate) struct GridDirections {
    weighting: Weighting,
    random: Stream,
    grid: (u32, u32),
    /// The next ray's stratum `(i, k)`.
    stratum: (u32, u32),
    counter: u64,
}

impl Iterator for GridDirections {
    type Item = Vec3;

    #[inline(always)]
    fn next(&mut self) -> Option<Vec3> {
        let (i, k) = self.stratum;
        if k == self.grid.1 {
            return None;
        }
        let direction = hemisphere(
            self.weighting,
            in_stratum((i, k), self.grid, self.random.pair(self.counter)),
        );
        self.counter += 1;
        self.stratum = if i + 1 == self.grid.0 {
            (0, k + 1)
        } else {
            (i + 1, k)
        };
        Some(direction)
    }
}

/// [`round_directions`] a 4 × 2 block of strata at a time, in world coordinates (`frame`) as
/// lanes: the same bits as `frame.to_world` of the grid's directions, in less work (the
/// stratum arithmetic, square roots and the frame a vector at a time, the sines eight at a
/// time ([`crate::sincos`]); the random bits one lane at a time).
///
/// Compiled as it is, for the baseline x86-64 (SSE2): a copy of [`GridBlocks::block`] compiled
/// with AVX2 (no FMA, so the same bits) and chosen at run time was about 1 % *slower* on
/// `render` of `cube` 256² × 256 (7 interleaved pairs, slower in each, 2026-12-05); likely
/// because it is no longer inlined and returns its lanes through memory, where the loops were
/// already vectorised four lanes wide.
struct GridBlocks {
    weighting: Weighting,
    random: Stream,
    grid: (u32, u32),
    /// The counter of the round's first ray.
    first: u64,
    frame: Frame,
}

impl GridBlocks {
    fn new(weighting: Weighting, (seed, key): (u64, u64), round: u32, n: u32, frame: Frame) -> Self {
        GridBlocks {
            weighting,
            random: Stream::new(seed, key),
            grid: strata(n),
            first: round as u64 * n as u64,
            frame,
        }
    }

    /// Lane `q` of the block at `column`: its ray's index counted from the first ray of the
    /// block's first row, `(q div 4)·a + column + q mod 4`.
    #[inline(always)]
    fn lane_offset(&self, column: u32, q: usize) -> usize {
        (q / 4) * self.grid.0 as usize + column as usize + q % 4
    }

    /// The directions of strata `(column + q mod 4, row + q div 4)`, lane `q` (`column` a
    /// multiple of 4 below `a`, `row` an even row), and their local z (cos θ).
    #[inline(always)]
    fn block(&self, column: u32, row: u32) -> ([[f32; PACKET]; 3], [f32; PACKET]) {
        const { assert!(PACKET == 8) };
        let a = self.grid.0;
        let (mut strata, mut xi) = ([[0u32; PACKET]; 2], [[0.0f32; PACKET]; 2]);
        for q in 0..PACKET {
            let (i, k) = (column + q as u32 % 4, row + q as u32 / 4);
            let pair = self.random.pair(self.first + k as u64 * a as u64 + i as u64);
            (strata[0][q], strata[1][q], xi[0][q], xi[1][q]) = (i, k, pair.x, pair.y);
        }
        let local = hemisphere_lanes(self.weighting, &in_stratum_lanes(&strata, self.grid, &xi));
        (self.frame.to_world_lanes(&local), local[2])
    }
}

/// The directions of round `round` (of `n` rays) of the point keyed `key` drawn by `sampler`:
/// [`round_directions`]'s grid, or `n` points of one of the point's progressive sequences,
/// from `rounds`' [`SequencePart`] of round `round`.
#[inline]
pub(crate) fn sampler_directions(
    sampler: Sampler,
    weighting: Weighting,
    (seed, key): (u64, u64),
    (rounds, round): (Rounds, u32),
    n: u32,
) -> impl Iterator<Item = Vec3> {
    match sampler {
        Sampler::Grid => Directions::Grid(round_directions(weighting, seed, key, round, n)),
        Sampler::Sobol => {
            let part = rounds.part(round, n);
            let sequence = Progressive::new(Stream::new(seed, key), part.replicate);
            let first = part.first;
            Directions::Sobol((0..n).map(move |j| hemisphere(weighting, sequence.point(first + j))))
        }
    }
}

/// How a point's rounds of progressive directions relate: what `--rounds` means for
/// `gather --sampler sobol`, and how `adaptive --sampler sobol` goes on (issue #25).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rounds {
    /// Each round the first points of its own independently scrambled sequence: replicates,
    /// whose spread is an unbiased error of their mean, each a coarser net than one sequence
    /// of all the rays.
    Replicates,
    /// Round k the k-th block of one sequence: all the rays are the first N points of one
    /// sequence, as accurate as `gather --sampler sobol --rays N`; the blocks' spread
    /// overstates the error of their mean (consecutive blocks of a net are negatively
    /// correlated), so it is an error bound rather than an error bar.
    Blocks,
}

/// Which points of which sequence a round draws.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SequencePart {
    /// The replicate (the sequence's scramble).
    pub replicate: u32,
    /// Its first point's index.
    pub first: u32,
}

impl Rounds {
    /// The points round `round` of `n` rays draws (every round of `n`).
    #[inline]
    pub fn part(self, round: u32, n: u32) -> SequencePart {
        match self {
            Rounds::Replicates => SequencePart {
                replicate: round,
                first: 0,
            },
            Rounds::Blocks => SequencePart {
                replicate: 0,
                first: round * n,
            },
        }
    }
}

/// The directions of one of the samplers.
enum Directions<G, S> {
    Grid(G),
    Sobol(S),
}

impl<G: Iterator<Item = Vec3>, S: Iterator<Item = Vec3>> Iterator for Directions<G, S> {
    type Item = Vec3;

    #[inline(always)]
    fn next(&mut self) -> Option<Vec3> {
        match self {
            Directions::Grid(g) => g.next(),
            Directions::Sobol(s) => s.next(),
        }
    }
}

/// How a round's rays are grouped into packets for [`RayCaster::hit_distances`]: spans of
/// consecutive ray indices (`span` rays: two rows of the strata grid, or [`PACKET`]), each
/// cast as packets of up to [`PACKET`] rays: 4 × 2 blocks of neighbouring strata where the
/// grid's `a × b` allow (`a` a multiple of 4, `b` of 2), else runs of 8 in ray order. Ray
/// `j` is stratum `(j mod a, j div a)`, so two grid rows are consecutive indices.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Packets {
    a: u32,
    blocks: bool,
    /// Rays per span.
    pub span: u32,
}

/// The packets of `n` rays drawn by `sampler`: the grid's 4 × 2 blocks ([`packets`]), or,
/// for a progressive sequence that is not a net (see [`Progressive::is_net`]), runs of 8 in
/// ray order (the packets of a `1 × n` grid).
pub(crate) fn sampler_packets(sampler: Sampler, n: u32) -> Packets {
    match sampler {
        Sampler::Grid => packets(strata(n)),
        Sampler::Sobol => packets((1, n)),
    }
}

/// The packets of an `a × b` strata grid; see [`Packets`].
pub(crate) fn packets((a, b): (u32, u32)) -> Packets {
    let blocks = a.is_multiple_of(4) && b.is_multiple_of(2) && a >= 4;
    Packets {
        a,
        blocks,
        span: if blocks { 2 * a } else { PACKET as u32 },
    }
}

/// A packet: up to [`PACKET`] ray indices.
pub(crate) struct Packet {
    index: [u32; PACKET],
    len: usize,
}

impl Packet {
    /// The rays' indices.
    fn rays(&self) -> &[u32] {
        &self.index[..self.len]
    }
}

impl Packets {
    /// The packets of the span of `count` rays from ray `base` (a multiple of `span`).
    pub fn within(self, base: u32, count: u32) -> impl Iterator<Item = Packet> {
        let (a, blocks) = (self.a, self.blocks);
        let packets = if blocks { count / PACKET as u32 } else { 1 };
        (0..packets).map(move |p| {
            if blocks {
                // Block p covers columns 4p .. 4p + 3 of the span's two rows.
                let index = std::array::from_fn(|q| base + (q / 4) as u32 * a + 4 * p + (q % 4) as u32);
                Packet { index, len: PACKET }
            } else {
                let index = std::array::from_fn(|q| base + q as u32);
                Packet {
                    index,
                    len: count as usize,
                }
            }
        })
    }
}

/// The `n` directions of `sequence` from point `first` (a net: `n` a power of two, at least
/// 8, and `first` a multiple of `n`, so the points are an aligned block of the sequence) into
/// `local`, and their indices from `first` ordered by the net's elementary box
/// ([`Progressive::net_box`]), 8 to a box: neighbouring directions, cast as one packet. The
/// directions are [`sampler_directions`]'s, bit for bit.
fn net_order(
    sequence: &Progressive,
    weighting: Weighting,
    (first, n): (u32, u32),
    local: &mut [Vec3],
) -> Vec<u32> {
    debug_assert!(first.is_multiple_of(n));
    let mut cells = Vec::with_capacity(n as usize);
    let mut start = vec![0u32; (n / 8) as usize + 1];
    for (j, w) in local[..n as usize].iter_mut().enumerate() {
        let bits = sequence.bits(first + j as u32);
        *w = hemisphere(weighting, Progressive::to_point(bits));
        let cell = Progressive::net_box(n, bits).expect("a net") as usize;
        start[cell + 1] += 1;
        cells.push(cell as u32);
    }
    for c in 1..start.len() {
        start[c] += start[c - 1];
    }
    let mut order = vec![0u32; n as usize];
    for (j, &cell) in cells.iter().enumerate() {
        let slot = &mut start[cell as usize];
        order[*slot as usize] = j as u32;
        *slot += 1;
    }
    order
}

/// One point's gather so far, round by round: H, its error bar and the AOVs.
pub(crate) struct PointGather {
    weighting: Weighting,
    sampler: Sampler,
    sequence_rounds: Rounds,
    ao_radius: Option<f32>,
    /// Every ray, in ray order: H.
    pub mean: HarmonicMean,
    /// Rounds cast, and the running mean and sum of squared deviations of their means of
    /// `1/d` (Welford).
    rounds: u32,
    round_mean: f64,
    round_m2: f64,
    pub rays: u32,
    pub escaped: u32,
    dmin: f32,
    /// Cosine weights of the directions that met nothing within the AO radius, and of all.
    ao_open: f64,
    ao_total: f64,
}

impl PointGather {
    pub fn new(weighting: Weighting, ao_radius: Option<f32>) -> Self {
        PointGather {
            weighting,
            sampler: Sampler::Grid,
            sequence_rounds: Rounds::Replicates,
            ao_radius,
            mean: HarmonicMean::default(),
            rounds: 0,
            round_mean: 0.0,
            round_m2: 0.0,
            rays: 0,
            escaped: 0,
            dmin: f32::INFINITY,
            ao_open: 0.0,
            ao_total: 0.0,
        }
    }

    /// This point's rounds drawn by `sampler` (default [`Sampler::Grid`]).
    pub fn with_sampler(self, sampler: Sampler) -> Self {
        PointGather { sampler, ..self }
    }

    /// How its progressive rounds relate (default [`Rounds::Replicates`]; the grid's rounds
    /// are each their own grid either way).
    pub fn with_rounds(self, sequence_rounds: Rounds) -> Self {
        PointGather {
            sequence_rounds,
            ..self
        }
    }

    /// Casts the next round, of `n` rays.
    #[inline]
    pub fn round<R: RayCaster>(
        &mut self,
        accel: &R,
        start: &GatherStart,
        seed: u64,
        key: u64,
        n: u32,
        clamp: DistanceClamp,
    ) {
        self.round_counted(accel, start, (seed, key), n, clamp, &crate::progress::Silent);
    }

    /// [`PointGather::round`], adding its `n` rays to `progress` as it goes (every
    /// [`crate::interrupt::POLL_RAYS`] rays, where it also looks at the interrupt flag).
    ///
    /// The rays are cast as packets of [`PACKET`] neighbouring strata (4 × 2 blocks of the
    /// grid where it divides so, else runs of 8 in ray order: see [`packets`]); their
    /// distances are summed in ray order, so H is the same bits as one ray at a time.
    #[inline]
    pub fn round_counted<R: RayCaster>(
        &mut self,
        accel: &R,
        start: &GatherStart,
        (seed, key): (u64, u64),
        n: u32,
        clamp: DistanceClamp,
        progress: &dyn Progress,
    ) {
        let grouping = sampler_packets(self.sampler, n);
        let round = (self.sequence_rounds, self.rounds);
        let mut directions = sampler_directions(self.sampler, self.weighting, (seed, key), round, n);
        // A progressive round of a power of two rays is a net: cast as packets of the 8
        // points of each of its elementary boxes (neighbouring directions), in one span.
        let part = self.sequence_rounds.part(self.rounds, n);
        let net = (self.sampler == Sampler::Sobol && Progressive::is_net(n))
            .then(|| Progressive::new(Stream::new(seed, key), part.replicate));
        let mut inverse_sum = 0.0f64;
        let poll = crate::interrupt::POLL_RAYS as u64;
        let mut pending = 0u64;
        // Distances and local directions of the rays of one span of ray indices.
        let span = if net.is_some() {
            n as usize
        } else {
            grouping.span as usize
        };
        // The grid in 4 × 2 blocks (nearly always): each block's directions made as lanes
        // and cast as they are, without `local`.
        let blocks = (self.sampler == Sampler::Grid && grouping.blocks)
            .then(|| GridBlocks::new(self.weighting, (seed, key), self.rounds, n, start.frame));
        let local_len = if blocks.is_some() { 0 } else { span };
        let (mut distances, mut local) = (vec![0.0f32; span], vec![Vec3::ZERO; local_len]);
        // The rays' local z (cos θ), for the AO weights.
        let mut cos_theta = vec![0.0f32; span];
        let (origins, leaving) = ([start.origin; PACKET], [start.leaving; PACKET]);
        let mut lanes = RayLanes {
            origin: start.origin.to_array().map(|o| [o; PACKET]),
            direction: [[0.0; PACKET]; 3],
        };
        let cast = |rays: &[u32], base: u32, local: &[Vec3], distances: &mut [f32]| {
            let mut world = [Vec3::ZERO; PACKET];
            for (world, &j) in world.iter_mut().zip(rays) {
                *world = start.frame.to_world(local[(j - base) as usize]);
            }
            let mut t = [0.0f32; PACKET];
            let k = rays.len();
            accel.hit_distances(&origins[..k], &world[..k], &leaving[..k], clamp.max, &mut t);
            for (&t, &j) in t.iter().zip(rays) {
                distances[(j - base) as usize] = t;
            }
        };
        for (base, count) in (0..n)
            .step_by(span)
            .map(|base| (base, span.min((n - base) as usize)))
        {
            if let Some(blocks) = &blocks {
                let row = base / grouping.a;
                for column in (0..grouping.a).step_by(4) {
                    let (world, z) = blocks.block(column, row);
                    lanes.direction = world;
                    let mut t = [0.0f32; PACKET];
                    accel.hit_distances_of_lanes(&lanes, PACKET, start.leaving, clamp.max, &mut t);
                    for q in 0..PACKET {
                        let j = blocks.lane_offset(column, q);
                        distances[j] = t[q];
                        cos_theta[j] = z[q];
                    }
                }
            } else {
                if let Some(sequence) = &net {
                    let order = net_order(sequence, self.weighting, (part.first, n), &mut local);
                    for rays in order.chunks(PACKET) {
                        cast(rays, 0, &local, &mut distances);
                    }
                } else {
                    for (w, next) in local[..count].iter_mut().zip(&mut directions) {
                        *w = next;
                    }
                    for packet in grouping.within(base, count as u32) {
                        cast(packet.rays(), base, &local, &mut distances);
                    }
                }
                for (z, w) in cos_theta[..count].iter_mut().zip(&local[..count]) {
                    *z = w.z;
                }
            }
            // The sums kept in locals, and the AO's in a loop of their own: written on `self`
            // in one loop, some builds kept them in memory (7 instructions a ray more).
            let (mut escaped, mut dmin, mut mean) = (self.escaped, self.dmin, self.mean);
            for &d in &distances[..count] {
                escaped += d.is_infinite() as u32;
                dmin = dmin.min(d);
                inverse_sum += mean.add_inverse(d, clamp);
            }
            (self.escaped, self.dmin, self.mean) = (escaped, dmin, mean);
            if let Some(radius) = self.ao_radius {
                for (&d, &z) in distances[..count].iter().zip(&cos_theta[..count]) {
                    // Cosine-weighted: cosine-distributed directions weigh 1, uniform ones cos θ.
                    let weight = match self.weighting {
                        Weighting::Cosine => 1.0,
                        Weighting::Uniform => z as f64,
                    };
                    self.ao_total += weight;
                    if d > radius {
                        self.ao_open += weight;
                    }
                }
            }
            pending += count as u64;
            if pending >= poll {
                if crate::interrupt::requested() {
                    break; // the pass ends with Error::Interrupted; this H is never seen
                }
                while pending >= poll {
                    progress.advance(poll);
                    pending -= poll;
                }
            }
        }
        progress.advance(pending);
        self.end_round(inverse_sum, n);
    }

    /// Counts a round of `n` rays whose `1/d` summed to `inverse_sum`.
    fn end_round(&mut self, inverse_sum: f64, n: u32) {
        self.rays += n;
        self.rounds += 1;
        let m = inverse_sum / n as f64;
        let delta = m - self.round_mean;
        self.round_mean += delta / self.rounds as f64;
        self.round_m2 += delta * (m - self.round_mean);
    }

    /// A point gathered elsewhere (on the GPU): the sums of `1/d` of its rounds of `n` rays
    /// each, in order; its escaped rays, smallest distance, and AO weights (open, total).
    #[cfg_attr(not(feature = "gpu"), allow(dead_code))]
    pub fn from_rounds(
        weighting: Weighting,
        ao_radius: Option<f32>,
        round_sums: impl IntoIterator<Item = f64>,
        n: u32,
        (escaped, dmin): (u32, f32),
        (ao_open, ao_total): (f64, f64),
    ) -> Self {
        let mut point = PointGather::new(weighting, ao_radius);
        for sum in round_sums {
            point.mean.add_sum(sum, n);
            point.end_round(sum, n);
        }
        point.escaped = escaped;
        point.dmin = dmin;
        point.ao_open = ao_open;
        point.ao_total = ao_total;
        point
    }

    /// Relative standard error of H: that of the mean of `1/d` over the rounds; NaN with
    /// fewer than 2 rounds or where every ray escaped.
    pub fn relerr(&self) -> f32 {
        if self.rounds < 2 || self.round_mean <= 0.0 {
            return f32::NAN;
        }
        let variance_of_mean = self.round_m2 / (self.rounds - 1) as f64 / self.rounds as f64;
        (variance_of_mean.sqrt() / self.round_mean) as f32
    }

    /// The AOVs, and what was cast into `tally`.
    pub fn finish(&self, tally: &mut Tally, aov: &mut AovSample) {
        tally.rays += self.rays as u64;
        tally.escaped += self.escaped as u64;
        *aov = AovSample {
            relerr: self.relerr(),
            rays: self.rays as f32,
            dmin: self.dmin,
            ao: if self.ao_total > 0.0 {
                (self.ao_open / self.ao_total) as f32
            } else {
                f32::NAN
            },
            escaped: self.escaped as f32 / self.rays.max(1) as f32,
        };
    }
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
    use crate::sampling::{random_pair, stratified};

    #[test]
    fn a_rounds_grid_directions_are_the_stratified_points_in_ray_order() {
        // Ray j of round r: stratum (j mod a, j div a), counter r·n + j, whatever the grid's
        // shape (square, oblong, 1 × n for a prime n, one ray).
        for n in [256, 12, 13, 1, 4_096] {
            for (weighting, round) in [(Weighting::Cosine, 0), (Weighting::Uniform, 3)] {
                let expected: Vec<[u32; 3]> = (0..n)
                    .map(|j| {
                        let xi = random_pair(5, 9, round as u64 * n as u64 + j as u64);
                        hemisphere(weighting, stratified(j, strata(n), xi))
                            .to_array()
                            .map(f32::to_bits)
                    })
                    .collect();
                let got: Vec<[u32; 3]> = round_directions(weighting, 5, 9, round, n)
                    .map(|d| d.to_array().map(f32::to_bits))
                    .collect();
                assert_eq!(got, expected, "n = {n}, {weighting:?}, round {round}");
            }
        }
    }

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

    #[test]
    fn grid_blocks_are_the_rounds_world_directions_bit_for_bit() {
        // Every 4 × 2 block of grids that `packets` casts in blocks (square, oblong, the
        // reference's 256 × 256), both weightings, several rounds and frames (normals along
        // and against the axes and oblique): lane q of block (column, row) is ray
        // (row + q div 4)·a + column + q mod 4 of the round, in world coordinates.
        let normals = [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize()];
        let mut checked = 0;
        for n in [16, 256, 512, 4_096, 65_536] {
            let (a, b) = strata(n);
            assert!(packets((a, b)).blocks, "n = {n}");
            for (weighting, round) in [
                (Weighting::Cosine, 0),
                (Weighting::Uniform, 3),
                (Weighting::Cosine, 7),
            ] {
                for normal in normals {
                    let frame = Frame::from_normal(normal);
                    let expected: Vec<Vec3> = round_directions(weighting, 5, 9, round, n)
                        .map(|w| frame.to_world(w))
                        .collect();
                    let local_z: Vec<f32> =
                        round_directions(weighting, 5, 9, round, n).map(|w| w.z).collect();
                    let blocks = GridBlocks::new(weighting, (5, 9), round, n, frame);
                    // The reference's grid in part (its first and last rows), the others whole.
                    for row in (0..b)
                        .step_by(2)
                        .filter(|&row| n < 65_536 || row < 4 || row + 4 > b)
                    {
                        for column in (0..a).step_by(4) {
                            let (world, z) = blocks.block(column, row);
                            for q in 0..PACKET {
                                let j = ((row + q as u32 / 4) * a + column + q as u32 % 4) as usize;
                                let got = [world[0][q], world[1][q], world[2][q]].map(f32::to_bits);
                                assert_eq!(
                                    (got, z[q].to_bits()),
                                    (expected[j].to_array().map(f32::to_bits), local_z[j].to_bits()),
                                    "n = {n}, {weighting:?}, round {round}, normal {normal}, ray {j}"
                                );
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 50_000);
    }
}
