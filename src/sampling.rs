//! Random numbers and hemisphere sampling (SPEC §2 determinism, §3.1 stratification).
//!
//! Random numbers are a pure function of (seed, stream, counter): a pixel's gather rays use
//! stream = pixel index and counter = sample index, a photon path uses stream = path index.
//! Nothing depends on thread count or scheduling.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// The direction weighting of SPEC §1.
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
    let (sin_phi, cos_phi) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
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
}

#[cfg(test)]
mod tests {
    use super::*;

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
