//! One point's gather, round by round: the rays cast (as packets), the harmonic mean and its
//! error bar, and the AOVs.

use glam::Vec3;

use super::directions::*;
use crate::accel::{GatherStart, RayCaster, RayLanes, PACKET};
use crate::estimators::{AovSample, DistanceClamp, HarmonicMean, Tally};
use crate::progress::Progress;
use crate::sampling::{Progressive, Sampler, Stream, Weighting};

/// The largest progressive round cast as one net ([`PointGather::round_counted`]): its
/// directions, distances and order held at once, 1.5 MB a thread.
const LARGEST_NET: u32 = 1 << 16;

/// One point's gather so far, round by round: H, its error bar and the AOVs.
pub(crate) struct PointGather {
    pub(super) weighting: Weighting,
    pub(super) sampler: Sampler,
    pub(super) sequence_rounds: Rounds,
    pub(super) ao_radius: Option<f32>,
    /// Every ray, in ray order: H.
    pub mean: HarmonicMean,
    /// Rounds cast, and the running mean and sum of squared deviations of their means of
    /// `1/d` (Welford).
    pub(super) rounds: u32,
    pub(super) round_mean: f64,
    pub(super) round_m2: f64,
    pub rays: u32,
    pub escaped: u32,
    pub(super) dmin: f32,
    /// Cosine weights of the directions that met nothing within the AO radius, and of all.
    pub(super) ao_open: f64,
    pub(super) ao_total: f64,
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
    /// distances are summed in ray order, so H is the same bits as one ray at a time. One
    /// function of ~120 lines: one loop over spans of ray indices (cast, then summed in
    /// order), the per-ray hot path that docs/engine.md measures.
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
        // points of each of its elementary boxes (neighbouring directions), in one span. Up
        // to `LARGEST_NET` rays: a larger round is cast in spans in ray order (the same
        // distances, so the same H), which keeps its memory small and polls the interrupt.
        let part = self.sequence_rounds.part(self.rounds, n);
        let net = (self.sampler == Sampler::Sobol && Progressive::is_net(n) && n <= LARGEST_NET)
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
        let local_len = if blocks.is_some() || net.is_some() {
            0
        } else {
            span
        };
        let (mut distances, mut local) = (vec![0.0f32; span], vec![Vec3::ZERO; local_len]);
        // A net's points of the unit square, made into directions eight at a time.
        let mut points = vec![glam::Vec2::ZERO; if net.is_some() { span } else { 0 }];
        let net_packets = NetPackets {
            weighting: self.weighting,
            frame: start.frame,
        };
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
            } else if let Some(sequence) = &net {
                let order = net_order(sequence, (part.first, n), &mut points);
                for rays in order.chunks(PACKET) {
                    let (world, z) = net_packets.packet(&points, rays);
                    lanes.direction = world;
                    let mut t = [0.0f32; PACKET];
                    accel.hit_distances_of_lanes(&lanes, PACKET, start.leaving, clamp.max, &mut t);
                    for (q, &j) in rays.iter().enumerate() {
                        distances[j as usize] = t[q];
                        cos_theta[j as usize] = z[q];
                    }
                }
            } else {
                for (w, next) in local[..count].iter_mut().zip(&mut directions) {
                    *w = next;
                }
                for packet in grouping.within(base, count as u32) {
                    cast(packet.rays(), base, &local, &mut distances);
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
    pub(super) fn end_round(&mut self, inverse_sum: f64, n: u32) {
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
            e_direct: f32::NAN,
        };
    }
}
