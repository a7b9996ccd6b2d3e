//! Random numbers and hemisphere sampling (spec §2 determinism, §3.1 stratification).
//!
//! Random numbers are a pure function of (seed, stream, counter): a pixel's gather rays use
//! stream = pixel index and counter = sample index, a photon path uses stream = path index.
//! Nothing depends on thread count or scheduling.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// The direction weighting of spec §1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Weighting {
    /// pdf `cos θ / π`: what final gathering and diffuse photon paths sample.
    #[default]
    Cosine,
    /// pdf `1 / 2π`.
    Uniform,
}

impl Weighting {
    /// The name the CLI and the report use.
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Cosine => "cosine",
            Weighting::Uniform => "uniform",
        }
    }
}

/// How a point's gather directions fill the unit square: the jittered grid of spec §3.1, or
/// a progressive sequence whose every prefix of `2^k` rays is stratified. The default is
/// Sobol, which gives 14–29 % lower f_diff than the grid at equal N on `cube` and `hall`
/// (docs/benchmarks.md); the paper's experiments name the grid, spec §3.1's sampling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// A jittered `a × b` grid of all N rays (docs/spec.md §3.1): one ray per stratum.
    Grid,
    /// Owen-scrambled Sobol (0,2) points: every prefix of `2^k` rays has one ray in each
    /// elementary box of area `2^-k` (each `2^a × 2^b` grid with `a + b = k`), for any N.
    #[default]
    Sobol,
}

impl Sampler {
    /// The name the CLI and the report use.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Grid => "grid",
            Sampler::Sobol => "sobol",
        }
    }

    /// Whether this is the grid (reports written before the sampler was part of the
    /// parameters object leave it out).
    pub fn is_grid(&self) -> bool {
        *self == Sampler::Grid
    }

    /// The grid: what a stored report or key that names no sampler was made with (the
    /// default before Sobol).
    pub fn unnamed() -> Sampler {
        Sampler::Grid
    }
}

/// Laine and Karras's hash-based permutation: output bit `k` depends on input bits `0..=k`
/// only (Burley 2020, "Practical Hash-based Owen Scrambling", with his constants).
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen's nested uniform scramble of a binary fraction `x` (bit 31 first): each bit is
/// flipped or not by a hash of `seed` and the bits above it, so it keeps every elementary
/// box whole (Burley 2020).
#[inline(always)]
fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The second Sobol dimension's generator matrix applied to `i`, bit by bit: the column of
/// bit `k` is Pascal's triangle mod 2 (`v ← v ⊕ v >> 1` from `v = 2^31`).
const fn sobol_dim1_slow(i: u32) -> u32 {
    let (mut y, mut v, mut bits) = (0u32, 1u32 << 31, i);
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= v;
        }
        bits >>= 1;
        v ^= v >> 1;
    }
    y
}

/// [`sobol_dim1_slow`] of each byte value at each of the four byte positions, its bits
/// reversed (as [`owen_scramble`] wants them), so that the matrix product is four lookups
/// (the index is a scrambled 32-bit number: a loop over its bits would branch unpredictably
/// up to 32 times).
static SOBOL_DIM1_REVERSED_BYTES: [[u32; 256]; 4] = {
    let mut table = [[0u32; 256]; 4];
    let mut position = 0;
    while position < 4 {
        let mut byte = 0;
        while byte < 256 {
            table[position][byte] = sobol_dim1_slow((byte as u32) << (8 * position)).reverse_bits();
            byte += 1;
        }
        position += 1;
    }
    table
};

/// The second dimension of the Sobol sequence at index `i` (the one whose generator matrix
/// is Pascal's triangle mod 2), its bits reversed. (The first is the van der Corput
/// sequence, `i` reversed.)
#[inline(always)]
fn sobol_dim1_reversed(i: u32) -> u32 {
    let t = &SOBOL_DIM1_REVERSED_BYTES;
    t[0][(i & 0xff) as usize]
        ^ t[1][((i >> 8) & 0xff) as usize]
        ^ t[2][((i >> 16) & 0xff) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// One scrambled progressive sequence of points in the unit square: Owen-scrambled Sobol
/// (0,2) points, its index order shuffled by a scramble too, so that the first `2^k` points
/// are an aligned block of `2^k` Sobol points (a (0,k,2)-net: one point per elementary box
/// of area `2^-k`), scrambled (Burley 2020). Keyed by the stream's random bits: a point's
/// replicates are independent sequences.
#[derive(Clone, Copy, Debug)]
pub struct Progressive {
    shuffle: u32,
    scramble: (u32, u32),
}

/// Counters of a [`Stream`] that key progressive sequences: far above any grid's ray index.
const PROGRESSIVE_COUNTER: u64 = 1 << 62;

impl Progressive {
    /// Replicate `replicate` of the point whose random numbers are `stream`.
    #[inline]
    pub fn new(stream: Stream, replicate: u32) -> Self {
        let a = stream.bits(PROGRESSIVE_COUNTER + 2 * replicate as u64);
        let b = stream.bits(PROGRESSIVE_COUNTER + 2 * replicate as u64 + 1);
        Progressive {
            shuffle: a as u32,
            scramble: ((a >> 32) as u32, b as u32),
        }
    }

    /// Point `j` as binary fractions (bit 31 first): Sobol point `i` = the scrambled `j`,
    /// each coordinate Owen-scrambled. The scramble reverses its input's bits, which undoes
    /// the van der Corput reversal and the reversed table's, so four reversals are left of
    /// seven (`cube` 64² × 256: about 13 instructions a ray fewer, of some 130).
    #[inline(always)]
    pub fn bits(&self, j: u32) -> (u32, u32) {
        let i = owen_scramble(j, self.shuffle);
        (
            laine_karras(i, self.scramble.0).reverse_bits(),
            laine_karras(sobol_dim1_reversed(i), self.scramble.1).reverse_bits(),
        )
    }

    /// Point `j` in `[0, 1)²` (24 bits a coordinate, as [`Stream::pair`]).
    #[inline(always)]
    pub fn point(&self, j: u32) -> Vec2 {
        Self::to_point(self.bits(j))
    }

    /// Binary fractions from [`Progressive::bits`] as a point of `[0, 1)²`.
    #[inline(always)]
    pub fn to_point((x, y): (u32, u32)) -> Vec2 {
        let scale = 1.0 / (1u32 << 24) as f32;
        Vec2::new((x >> 8) as f32 * scale, (y >> 8) as f32 * scale)
    }

    /// Whether the first `n` points are a net whose elementary boxes hold 8 points each:
    /// `n = 2^m` with `m ≥ 3`.
    #[inline(always)]
    pub fn is_net(n: u32) -> bool {
        n.is_power_of_two() && n >= 8
    }

    /// Of the first `n = 2^m` points (`m ≥ 3`), the box of the `2^a × 2^b` grid (`a + b =
    /// m − 3`, `b ≥ a`) that point `(x, y)` lies in, row by row: each box holds exactly 8 of
    /// them, the prefix being a (0,m,2)-net. `None` where `n` is not such a power of two.
    #[inline(always)]
    pub fn net_box(n: u32, (x, y): (u32, u32)) -> Option<u32> {
        if !Self::is_net(n) {
            return None;
        }
        let k = n.trailing_zeros() - 3;
        let (a, b) = (k / 2, k - k / 2);
        let column = x.checked_shr(32 - a).unwrap_or(0);
        let row = y.checked_shr(32 - b).unwrap_or(0);
        Some((row << a) | column)
    }
}

/// A 64-bit finaliser with full avalanche (Pelle Evensen's "moremur", a SplitMix64 variant).
#[inline(always)]
fn mix64(mut x: u64) -> u64 {
    x ^= x >> 27;
    x = x.wrapping_mul(0x3C79_AC49_2BA7_B653);
    x ^= x >> 33;
    x = x.wrapping_mul(0x1C69_B3F7_4AC4_AE35);
    x ^ (x >> 27)
}

/// 64 random bits keyed by (seed, stream, counter): a counter-based generator.
#[inline(always)]
pub fn random_bits(seed: u64, stream: u64, counter: u64) -> u64 {
    Stream::new(seed, stream).bits(counter)
}

/// Two independent uniforms in [0, 1) from one draw of 64 bits.
#[inline(always)]
pub fn random_pair(seed: u64, stream: u64, counter: u64) -> Vec2 {
    Stream::new(seed, stream).pair(counter)
}

/// One stream of [`random_bits`] (seed and stream fixed), its key mixed once: the same
/// numbers for less work where one stream gives many (a point's gather rays).
#[derive(Clone, Copy, Debug)]
pub struct Stream(u64);

impl Stream {
    /// The stream `stream` of seed `seed`.
    #[inline(always)]
    pub fn new(seed: u64, stream: u64) -> Self {
        Stream(mix64(mix64(seed ^ 0x9E37_79B9_7F4A_7C15) ^ stream))
    }

    /// [`random_bits`]`(seed, stream, counter)`.
    #[inline(always)]
    pub fn bits(self, counter: u64) -> u64 {
        mix64(self.0.wrapping_add(counter.wrapping_mul(0x9E37_79B9_7F4A_7C15)))
    }

    /// [`random_pair`]`(seed, stream, counter)`.
    #[inline(always)]
    pub fn pair(self, counter: u64) -> Vec2 {
        let bits = self.bits(counter);
        let scale = 1.0 / (1u32 << 24) as f32;
        Vec2::new(
            (bits >> 40) as f32 * scale,
            ((bits >> 8) & 0xFF_FFFF) as f32 * scale,
        )
    }
}

/// The `a × b` stratification grid for `n` samples: the most nearly square factorisation,
/// `a ≤ b` (`a = b = √n` for perfect squares). A prime `n` gives `1 × n`.
pub fn strata(n: u32) -> (u32, u32) {
    let mut a = (n as f64).sqrt() as u32;
    while a > 1 && !n.is_multiple_of(a) {
        a -= 1;
    }
    let a = a.max(1);
    (a, n / a)
}

/// Point `j` of `n` jittered-stratified points in the unit square, strata `(a, b)` from
/// [`strata`]: stratum `(j mod a, j div a)`, jittered by `xi`.
#[inline(always)]
pub fn stratified(j: u32, (a, b): (u32, u32), xi: Vec2) -> Vec2 {
    in_stratum((j % a, j / a), (a, b), xi)
}

/// The point of stratum `(i, k)` of the `a × b` grid jittered by `xi`: [`stratified`] for a
/// caller that knows the stratum.
#[inline(always)]
pub fn in_stratum((i, k): (u32, u32), (a, b): (u32, u32), xi: Vec2) -> Vec2 {
    // Keep the sample strictly below 1 so the map never produces the horizon exactly.
    Vec2::new(
        ((i as f32 + xi.x) / a as f32).min(1.0 - f32::EPSILON),
        ((k as f32 + xi.y) / b as f32).min(1.0 - f32::EPSILON),
    )
}

/// [`in_stratum`] of eight strata `(strata[0][l], strata[1][l])` jittered by
/// `(xi[0][l], xi[1][l])`, as lanes (x, then y): the same bits, in a loop the compiler
/// vectorises.
#[inline(always)]
pub fn in_stratum_lanes(strata: &[[u32; 8]; 2], (a, b): (u32, u32), xi: &[[f32; 8]; 2]) -> [[f32; 8]; 2] {
    let mut u = [[0.0f32; 8]; 2];
    for l in 0..8 {
        u[0][l] = ((strata[0][l] as f32 + xi[0][l]) / a as f32).min(1.0 - f32::EPSILON);
        u[1][l] = ((strata[1][l] as f32 + xi[1][l]) / b as f32).min(1.0 - f32::EPSILON);
    }
    u
}

/// `v` made unit length, or `None` where it is zero or not finite. Where its squared length
/// would overflow or underflow f32 (components beyond about 1e19 or below 1e-19) it is
/// scaled by its largest component first; otherwise this is `v.normalize()`, bit for bit.
pub fn unit(v: Vec3) -> Option<Vec3> {
    if !v.is_finite() {
        return None;
    }
    let length_squared = v.length_squared();
    if (1e-30..=1e30).contains(&length_squared) {
        return Some(v.normalize());
    }
    let largest = v.abs().max_element();
    (largest > 0.0).then(|| (v / largest).normalize())
}

/// A unit direction in the local frame (z = normal) from a point of the unit square.
/// Cosine: `θ = asin √u, φ = 2πv`. Uniform: `cos θ = 1 − u, φ = 2πv`.
#[inline(always)]
pub fn hemisphere(weighting: Weighting, u: Vec2) -> Vec3 {
    let (sin_theta, cos_theta) = match weighting {
        Weighting::Cosine => (u.x.sqrt(), (1.0 - u.x).sqrt()),
        Weighting::Uniform => {
            let c = 1.0 - u.x;
            ((1.0 - c * c).max(0.0).sqrt(), c)
        }
    };
    let (sin_phi, cos_phi) = crate::sincos::sin_cos(2.0 * PI * u.y);
    Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
}

/// [`hemisphere`] of eight points of the unit square at once, `u[0]` their x and `u[1]` their
/// y, as lanes (x, y, z): the same bits. The square roots and products run a vector at a time
/// (plain loops that the compiler vectorises: the same IEEE operations lane by lane), the
/// sines and cosines eight at a time ([`crate::sincos::sin_cos_lanes`]).
#[inline(always)]
pub fn hemisphere_lanes(weighting: Weighting, u: &[[f32; 8]; 2]) -> [[f32; 8]; 3] {
    let (mut sin_theta, mut cos_theta) = ([0.0f32; 8], [0.0f32; 8]);
    match weighting {
        Weighting::Cosine => {
            for l in 0..8 {
                sin_theta[l] = u[0][l].sqrt();
                cos_theta[l] = (1.0 - u[0][l]).sqrt();
            }
        }
        Weighting::Uniform => {
            for l in 0..8 {
                let c = 1.0 - u[0][l];
                sin_theta[l] = (1.0 - c * c).max(0.0).sqrt();
                cos_theta[l] = c;
            }
        }
    }
    let mut phi = [0.0f32; 8];
    for l in 0..8 {
        phi[l] = 2.0 * PI * u[1][l];
    }
    let (sin_phi, cos_phi) = crate::sincos::sin_cos_lanes(&phi);
    let mut v = [[0.0f32; 8]; 3];
    for l in 0..8 {
        v[0][l] = cos_phi[l] * sin_theta[l];
        v[1][l] = sin_phi[l] * sin_theta[l];
        v[2][l] = cos_theta[l];
    }
    v
}

/// An orthonormal frame around a unit normal (Duff et al. 2017, "Building an Orthonormal
/// Basis, Revisited"): `to_world` maps local (x, y, z = normal) to world.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Tangent: the local x axis.
    pub t: Vec3,
    /// Bitangent: the local y axis.
    pub b: Vec3,
    /// The unit normal: the local z axis.
    pub n: Vec3,
}

impl Frame {
    /// The frame around the unit normal `n`.
    #[inline]
    pub fn from_normal(n: Vec3) -> Frame {
        let sign = 1f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            b: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// Local `v` (x along `t`, y along `b`, z along `n`) in world coordinates.
    #[inline(always)]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }

    /// [`Frame::to_world`] of eight local vectors as lanes (x, y, z): the same bits.
    #[inline(always)]
    pub fn to_world_lanes(&self, v: &[[f32; 8]; 3]) -> [[f32; 8]; 3] {
        let mut world = [[0.0f32; 8]; 3];
        for (axis, world) in world.iter_mut().enumerate() {
            let (t, b, n) = (self.t[axis], self.b[axis], self.n[axis]);
            for l in 0..8 {
                world[l] = v[0][l] * t + v[1][l] * b + v[2][l] * n;
            }
        }
        world
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_vectors_neither_overflow_nor_underflow() {
        assert_eq!(unit(Vec3::new(0.0, -3e19, 0.0)), Some(Vec3::NEG_Y));
        assert_eq!(
            unit(Vec3::new(1e30, 0.0, 1e30)),
            Some(Vec3::new(1.0, 0.0, 1.0).normalize())
        );
        assert_eq!(unit(Vec3::new(1e-15, 0.0, 0.0)), Some(Vec3::X));
        assert_eq!(unit(Vec3::new(0.0, 1e-40, 0.0)), Some(Vec3::Y));
        let v = Vec3::new(0.3, -1.0, 0.2);
        assert_eq!(
            unit(v),
            Some(v.normalize()),
            "an ordinary vector: normalize's bits"
        );
        for bad in [
            Vec3::ZERO,
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(f32::NAN, 1.0, 0.0),
        ] {
            assert_eq!(unit(bad), None, "{bad}");
        }
    }

    #[test]
    fn strata_are_the_most_nearly_square_factorisation() {
        assert_eq!(strata(256), (16, 16));
        assert_eq!(strata(512), (16, 32));
        assert_eq!(strata(12), (3, 4));
        assert_eq!(strata(13), (1, 13));
        assert_eq!(strata(1), (1, 1));
    }

    #[test]
    fn stratified_points_fill_each_stratum_once() {
        let (a, b) = strata(24);
        let mut seen = [0; 24];
        for j in 0..24 {
            let u = stratified(j, (a, b), random_pair(1, 2, j as u64));
            seen[((u.y * b as f32) as u32 * a + (u.x * a as f32) as u32) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn every_power_of_two_prefix_of_a_progressive_sequence_is_a_net() {
        // The first 2^k points of any replicate: one point in each box of every 2^a × 2^b
        // grid with a + b = k, for k up to 12 and many keys.
        for key in 0..24u64 {
            let sequence = Progressive::new(Stream::new(7, key), (key % 5) as u32);
            for k in 0..=12u32 {
                for a in 0..=k {
                    let b = k - a;
                    let mut seen = vec![false; 1 << k];
                    for j in 0..1u32 << k {
                        let (x, y) = sequence.bits(j);
                        let (bx, by) = (
                            x.checked_shr(32 - a).unwrap_or(0),
                            y.checked_shr(32 - b).unwrap_or(0),
                        );
                        let cell = ((by << a) | bx) as usize;
                        assert!(!seen[cell], "key {key}, k = {k}, {a} × {b}: box {cell} twice");
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    #[test]
    fn the_sobol_tables_are_the_generator_matrix() {
        for i in (0..1u32 << 16).chain([u32::MAX, 0x8000_0001, 0xdead_beef, 0x1234_5678]) {
            assert_eq!(
                sobol_dim1_reversed(i).reverse_bits(),
                sobol_dim1_slow(i),
                "{i:#x}"
            );
        }
    }

    #[test]
    fn a_point_is_the_owen_scrambled_sobol_point_of_the_scrambled_index() {
        // The definition, written out with every reversal (as it was computed until
        // 2026-12-07): the points, and so every sobol image, are unchanged.
        let definition = |p: &Progressive, j: u32| {
            let i = owen_scramble(j, p.shuffle);
            (
                owen_scramble(i.reverse_bits(), p.scramble.0),
                owen_scramble(sobol_dim1_slow(i), p.scramble.1),
            )
        };
        for key in 0..20u64 {
            let p = Progressive::new(Stream::new(7, key), key as u32 % 3);
            for j in (0..4_096).chain([65_535, 1 << 20, u32::MAX]) {
                assert_eq!(p.bits(j), definition(&p, j), "key {key}, point {j}");
            }
        }
    }

    #[test]
    fn a_nets_boxes_hold_eight_points_each() {
        for m in 3..=12u32 {
            let n = 1 << m;
            let sequence = Progressive::new(Stream::new(3, m as u64), 1);
            let mut count = vec![0u32; (n / 8) as usize];
            for j in 0..n {
                count[Progressive::net_box(n, sequence.bits(j)).unwrap() as usize] += 1;
            }
            assert!(count.iter().all(|&c| c == 8), "n = {n}: {count:?}");
        }
        assert_eq!(Progressive::net_box(12, (0, 0)), None);
        assert_eq!(Progressive::net_box(4, (0, 0)), None);
    }

    #[test]
    fn progressive_sequences_are_keyed_and_their_points_in_the_unit_square() {
        let s = |seed, key, r| Progressive::new(Stream::new(seed, key), r);
        assert_ne!(s(1, 2, 0).bits(0), s(1, 3, 0).bits(0));
        assert_ne!(s(1, 2, 0).bits(0), s(2, 2, 0).bits(0));
        assert_ne!(s(1, 2, 0).bits(5), s(1, 2, 1).bits(5));
        assert_eq!(s(1, 2, 3).bits(9), s(1, 2, 3).bits(9));
        let n = 1 << 16;
        let mean: Vec2 = (0..n).map(|j| s(4, 4, 0).point(j)).sum::<Vec2>() / n as f32;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 1e-3, "{mean}");
        assert!((0..n).all(|j| {
            let p = s(4, 4, 0).point(j);
            (0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y)
        }));
    }

    #[test]
    fn random_pairs_are_uniform_and_keyed() {
        let n = 100_000;
        let mean: Vec2 = (0..n).map(|i| random_pair(7, 3, i)).sum::<Vec2>() / n as f32;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.005);
        assert_ne!(random_bits(7, 3, 0), random_bits(8, 3, 0));
        assert_ne!(random_bits(7, 3, 0), random_bits(7, 4, 0));
        assert_eq!(random_bits(7, 3, 5), random_bits(7, 3, 5));
    }

    #[test]
    fn cosine_directions_have_mean_cosine_two_thirds() {
        // E[cos θ] under pdf cos θ/π is 2/3; under the uniform pdf it is 1/2.
        for (w, expected) in [(Weighting::Cosine, 2.0 / 3.0), (Weighting::Uniform, 0.5)] {
            let n = 65_536;
            let s = strata(n);
            let mean: f32 = (0..n)
                .map(|j| hemisphere(w, stratified(j, s, random_pair(1, 0, j as u64))).z)
                .sum::<f32>()
                / n as f32;
            assert!((mean - expected).abs() < 1e-3, "{w:?}: {mean}");
        }
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(0.0, 0.0, -0.9999).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!(f.t.dot(f.b).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5 && f.b.dot(n).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5 && (f.b.length() - 1.0).abs() < 1e-5);
        }
    }
}
