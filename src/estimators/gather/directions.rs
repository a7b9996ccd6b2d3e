//! The gather's directions: the jittered grid of a round (one ray at a time, or a 4 × 2 block
//! of strata as lanes), the progressive sequences' rounds, and how a round's rays are grouped
//! into packets.

use glam::{Vec2, Vec3};

use crate::accel::PACKET;
use crate::sampling::{
    hemisphere, hemisphere_lanes, in_stratum, in_stratum_lanes, strata, Frame, Progressive, Sampler, Stream,
    Weighting,
};

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
    pub(super) weighting: Weighting,
    pub(super) random: Stream,
    pub(super) grid: (u32, u32),
    /// The next ray's stratum `(i, k)`.
    pub(super) stratum: (u32, u32),
    pub(super) counter: u64,
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
pub(super) struct GridBlocks {
    pub(super) weighting: Weighting,
    pub(super) random: Stream,
    pub(super) grid: (u32, u32),
    /// The counter of the round's first ray.
    pub(super) first: u64,
    pub(super) frame: Frame,
}

impl GridBlocks {
    pub(super) fn new(
        weighting: Weighting,
        (seed, key): (u64, u64),
        round: u32,
        n: u32,
        frame: Frame,
    ) -> Self {
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
    pub(super) fn lane_offset(&self, column: u32, q: usize) -> usize {
        (q / 4) * self.grid.0 as usize + column as usize + q % 4
    }

    /// The directions of strata `(column + q mod 4, row + q div 4)`, lane `q` (`column` a
    /// multiple of 4 below `a`, `row` an even row), and their local z (cos θ).
    #[inline(always)]
    pub(super) fn block(&self, column: u32, row: u32) -> ([[f32; PACKET]; 3], [f32; PACKET]) {
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
pub(super) enum Directions<G, S> {
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
    pub(super) a: u32,
    pub(super) blocks: bool,
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
    pub(super) index: [u32; PACKET],
    pub(super) len: usize,
}

impl Packet {
    /// The rays' indices.
    pub(super) fn rays(&self) -> &[u32] {
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

/// The `n` points of `sequence` from point `first` (a net: `n` a power of two, at least 8,
/// and `first` a multiple of `n`, so the points are an aligned block of the sequence) into
/// `points`, and their indices from `first` ordered by the net's elementary box
/// ([`Progressive::net_box`]), 8 to a box: neighbouring directions, cast as one packet
/// ([`NetPackets::packet`] makes their directions).
pub(super) fn net_order(sequence: &Progressive, (first, n): (u32, u32), points: &mut [Vec2]) -> Vec<u32> {
    debug_assert!(first.is_multiple_of(n));
    let mut cells = Vec::with_capacity(n as usize);
    let mut start = vec![0u32; (n / 8) as usize + 1];
    for (j, point) in points[..n as usize].iter_mut().enumerate() {
        let bits = sequence.bits(first + j as u32);
        *point = Progressive::to_point(bits);
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

/// The world directions of a net's packets, eight at a time as lanes, as the grid's blocks
/// ([`GridBlocks`]): the hemisphere, its sines and cosines, and the frame a vector at a time
/// (one at a time, they took about a sixth of a `render` of `cube` at 256 rays). The same bits
/// as [`sampler_directions`]'s, ray by ray, mapped by [`Frame::to_world`].
pub(super) struct NetPackets {
    pub(super) weighting: Weighting,
    pub(super) frame: Frame,
}

impl NetPackets {
    /// The world directions (lanes x, y, z) and local z (cos θ) of the eight rays `rays`
    /// (indices into `points`).
    #[inline(always)]
    pub(super) fn packet(&self, points: &[Vec2], rays: &[u32]) -> ([[f32; PACKET]; 3], [f32; PACKET]) {
        const { assert!(PACKET == 8) };
        debug_assert_eq!(rays.len(), PACKET);
        let mut u = [[0.0f32; PACKET]; 2];
        for (q, &j) in rays.iter().enumerate() {
            let point = points[j as usize];
            (u[0][q], u[1][q]) = (point.x, point.y);
        }
        let local = hemisphere_lanes(self.weighting, &u);
        (self.frame.to_world_lanes(&local), local[2])
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
    fn a_nets_packets_are_the_sequences_world_directions_bit_for_bit() {
        // Every packet `net_order` and `NetPackets` make, for nets of 8 … 65,536 points, both
        // weightings, replicates and aligned blocks further on, several frames: 8 rays of one
        // elementary box, each ray once, lane q the direction of its ray as
        // `sampler_directions` makes it, in world coordinates.
        let normals = [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize()];
        let mut checked = 0;
        for n in [8, 256, 4_096, 65_536] {
            for (weighting, replicate, first) in [
                (Weighting::Cosine, 0, 0),
                (Weighting::Uniform, 3, 0),
                (Weighting::Cosine, 1, 2 * n),
            ] {
                let sequence = Progressive::new(Stream::new(5, 9), replicate);
                let mut points = vec![Vec2::ZERO; n as usize];
                let order = net_order(&sequence, (first, n), &mut points);
                let mut seen = vec![false; n as usize];
                for normal in normals.iter().take(if n == 65_536 { 1 } else { 4 }) {
                    let frame = Frame::from_normal(*normal);
                    let packets = NetPackets { weighting, frame };
                    for rays in order.chunks(PACKET) {
                        let boxes: Vec<u32> = rays
                            .iter()
                            .map(|&j| Progressive::net_box(n, sequence.bits(first + j)).unwrap())
                            .collect();
                        assert!(
                            boxes.iter().all(|&b| b == boxes[0]),
                            "n = {n}: a packet of boxes {boxes:?}"
                        );
                        let (world, z) = packets.packet(&points, rays);
                        for (q, &j) in rays.iter().enumerate() {
                            let local = hemisphere(weighting, sequence.point(first + j));
                            let got = (
                                [world[0][q], world[1][q], world[2][q]].map(f32::to_bits),
                                z[q].to_bits(),
                            );
                            let expected = (
                                frame.to_world(local).to_array().map(f32::to_bits),
                                local.z.to_bits(),
                            );
                            assert_eq!(got, expected, "n = {n}, {weighting:?}, normal {normal}, ray {j}");
                            seen[j as usize] = true;
                            checked += 1;
                        }
                    }
                }
                assert!(seen.iter().all(|&s| s), "n = {n}: every ray in one packet");
            }
        }
        assert!(checked > 200_000, "{checked}");
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
