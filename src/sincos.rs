//! Sine and cosine of an `f32` angle, eight at a time: the gather's azimuths (`φ = 2πv`).
//!
//! The same bits as glibc's `sincosf` (checked against glibc 2.36, in the build of it that
//! glibc picks on CPUs with FMA and AVX2): the argument widened to `f64`, reduced by the
//! nearest multiple of π/2 with one fused multiply-add, and two polynomials evaluated in
//! `f64` with fused multiply-adds in the order glibc's compiled code performs them (read from
//! its disassembly), then rounded to `f32`. Written out here so that a block of eight rays
//! makes its sines and cosines in two AVX2 passes of four `f64` lanes instead of eight calls
//! into libm (about 50 instructions a ray), and so that every platform computes the same
//! directions: where the CPU has no FMA the fused operations are computed exactly in
//! software (`f64::mul_add`), and a libm other than glibc's no longer changes the images.
//! Checked against the C library's `sincosf` on every `f32` in `[0, 2π)` once, and on a
//! stride of them in the unit tests. (An `f64` operation done unfused instead changes no
//! `f32` result among those: the `f32` rounding hides it; a coefficient off by 0.1 % fails.)
//!
//! Only `|x| < 120` takes this path (glibc's fast range; the gather's angles lie in
//! `[0, 2π)`); larger or non-finite angles go to the standard library's `sin_cos`.

/// `2/π · 2²⁴`: the reduction's quadrant is `(⌊x · HPI_INV⌋ + 2²³) >> 24`, the nearest
/// integer to `x / (π/2)`, without a rounding instruction.
const HPI_INV: f64 = f64::from_bits(0x4164_5f30_6dc9_c883);
/// π/2 in `f64`.
const HPI: f64 = f64::from_bits(0x3ff9_21fb_5444_2d18);
/// The cosine polynomial `c0 + c1 x² + c2 x⁴ + c3 x⁶ + c4 x⁸` (glibc's; negated in the
/// quadrants where the cosine is).
const C: [f64; 5] = [
    1.0,
    f64::from_bits(0xbfdf_ffff_fd0c_621c),
    f64::from_bits(0x3fa5_5553_e106_8f19),
    f64::from_bits(0xbf56_c087_e89a_359d),
    f64::from_bits(0x3ef9_9343_027b_f8c3),
];
/// The sine polynomial `x + s1 x³ + s2 x⁵ + s3 x⁷` (glibc's).
const S: [f64; 3] = [
    f64::from_bits(0xbfc5_5554_5995_a603),
    f64::from_bits(0x3f81_1076_0523_0bc4),
    f64::from_bits(0xbf29_94eb_3774_cf24),
];
/// Angles whose magnitude's bits are below this (2⁻¹²) return `(x, 1)`, as glibc does.
const TINY_BITS: u32 = 0x3980_0000;
/// Angles whose magnitude's bits are below this (120.0) take the fast path.
const FAST_BITS: u32 = 0x42f0_0000;

/// `(sin x, cos x)`; see the module docs.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has FMA.
        return unsafe { sin_cos_fma(x) };
    }
    sin_cos_with(x)
}

/// [`sin_cos`] of eight angles: `(sines, cosines)`.
#[inline]
pub fn sin_cos_lanes(x: &[f32; 8]) -> ([f32; 8], [f32; 8]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA.
        return unsafe { lanes_avx2(x) };
    }
    let (mut sin, mut cos) = ([0.0; 8], [0.0; 8]);
    for l in 0..8 {
        (sin[l], cos[l]) = sin_cos(x[l]);
    }
    (sin, cos)
}

/// [`sin_cos_with`] compiled with FMA, so that `mul_add` is one instruction.
///
/// # Safety
/// The CPU must support FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn sin_cos_fma(x: f32) -> (f32, f32) {
    sin_cos_with(x)
}

/// The scalar computation (`mul_add` is a fused multiply-add, in hardware or software).
#[inline(always)]
fn sin_cos_with(y: f32) -> (f32, f32) {
    let magnitude = y.to_bits() & 0x7fff_ffff;
    if magnitude < TINY_BITS {
        return (y, 1.0);
    }
    if magnitude >= FAST_BITS {
        return y.sin_cos();
    }
    let x = y as f64;
    // The quadrant, and x reduced by it to [−π/4, π/4] (for |x| < 0.75, where glibc skips the
    // reduction, n = 0 and r = x exactly).
    let n = ((x * HPI_INV) as i32 + 0x80_0000) >> 24;
    let r = (-(n as f64)).mul_add(HPI, x);
    // Quadrants 1 and 2 negate the sine's argument, 2 and 3 the cosine polynomial.
    let r_signed = if (n ^ (n >> 1)) & 1 != 0 { -r } else { r };
    let c = if n & 2 != 0 { C.map(|c| -c) } else { C };
    let x2 = r * r;
    let x3 = x2 * r_signed;
    let x4 = x2 * x2;
    let x5 = x2 * x3;
    let x6 = x2 * x4;
    let s1 = x2.mul_add(S[2], S[1]);
    let c2 = x2.mul_add(c[4], c[3]);
    let c1 = x2.mul_add(c[1], c[0]);
    let sine = x3.mul_add(S[0], r_signed);
    let cosine = x4.mul_add(c[2], c1);
    let (sine, cosine) = (s1.mul_add(x5, sine) as f32, c2.mul_add(x6, cosine) as f32);
    if n & 1 != 0 {
        (cosine, sine)
    } else {
        (sine, cosine)
    }
}

/// [`sin_cos_lanes`] in AVX2 and FMA: two passes of four `f64` lanes, the scalar
/// computation's operations lane by lane.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn lanes_avx2(y: &[f32; 8]) -> ([f32; 8], [f32; 8]) {
    use std::arch::x86_64::*;
    let (mut sin, mut cos) = ([0.0f32; 8], [0.0f32; 8]);
    let splat = |v: f64| _mm256_set1_pd(v);
    let sign = _mm256_set1_pd(-0.0);
    for half in 0..2 {
        let yf = _mm_loadu_ps(y.as_ptr().add(4 * half));
        let x = _mm256_cvtps_pd(yf);
        let n = _mm_srai_epi32::<24>(_mm_add_epi32(
            _mm256_cvttpd_epi32(_mm256_mul_pd(x, splat(HPI_INV))),
            _mm_set1_epi32(0x80_0000),
        ));
        let r = _mm256_fnmadd_pd(_mm256_cvtepi32_pd(n), splat(HPI), x);
        // Sign bits (bit 63 of each f64 lane) from the quadrant's bits: bit 0 of n ^ (n >> 1)
        // for the sine's argument, bit 1 of n for the cosine polynomial.
        let n64 = _mm256_cvtepi32_epi64(n);
        let sine_negated = _mm256_castsi256_pd(_mm256_slli_epi64::<63>(_mm256_xor_si256(
            n64,
            _mm256_srli_epi64::<1>(n64),
        )));
        let r_signed = _mm256_xor_pd(r, sine_negated);
        let flip = _mm256_and_pd(_mm256_castsi256_pd(_mm256_slli_epi64::<62>(n64)), sign);
        let c = |k: usize| _mm256_xor_pd(splat(C[k]), flip);
        let x2 = _mm256_mul_pd(r, r);
        let x3 = _mm256_mul_pd(x2, r_signed);
        let x4 = _mm256_mul_pd(x2, x2);
        let x5 = _mm256_mul_pd(x2, x3);
        let x6 = _mm256_mul_pd(x2, x4);
        let s1 = _mm256_fmadd_pd(x2, splat(S[2]), splat(S[1]));
        let c2 = _mm256_fmadd_pd(x2, c(4), c(3));
        let c1 = _mm256_fmadd_pd(x2, c(1), c(0));
        let sine = _mm256_fmadd_pd(x3, splat(S[0]), r_signed);
        let cosine = _mm256_fmadd_pd(x4, c(2), c1);
        let sine = _mm256_cvtpd_ps(_mm256_fmadd_pd(s1, x5, sine));
        let cosine = _mm256_cvtpd_ps(_mm256_fmadd_pd(c2, x6, cosine));
        // Odd quadrants swap the two; tiny angles give (x, 1).
        let odd = _mm_castsi128_ps(_mm_slli_epi32::<31>(n));
        let (sine, cosine) = (_mm_blendv_ps(sine, cosine, odd), _mm_blendv_ps(cosine, sine, odd));
        let magnitude = _mm_and_si128(_mm_castps_si128(yf), _mm_set1_epi32(0x7fff_ffff));
        let tiny = _mm_castsi128_ps(_mm_cmplt_epi32(magnitude, _mm_set1_epi32(TINY_BITS as i32)));
        _mm_storeu_ps(sin.as_mut_ptr().add(4 * half), _mm_blendv_ps(sine, yf, tiny));
        _mm_storeu_ps(
            cos.as_mut_ptr().add(4 * half),
            _mm_blendv_ps(cosine, _mm_set1_ps(1.0), tiny),
        );
    }
    // Angles outside the fast range (never the gather's) as the scalar path takes them.
    for l in 0..8 {
        if y[l].to_bits() & 0x7fff_ffff >= FAST_BITS {
            (sin[l], cos[l]) = y[l].sin_cos();
        }
    }
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The C library's `sincosf`, as `f32::sin_cos` calls it.
    fn libm(x: f32) -> (f32, f32) {
        x.sin_cos()
    }

    /// Every `stride`-th `f32` from 0 up to 2π, and the boundaries of the paths.
    fn angles(stride: u32) -> impl Iterator<Item = f32> {
        let end = std::f32::consts::TAU.to_bits();
        let edges = [
            0.0f32,
            -0.0,
            1e-40,
            2.4e-4,
            2.5e-4,
            0.75,
            0.749_999_94,
            std::f32::consts::FRAC_PI_4,
            119.99,
            120.0,
        ];
        (0..end)
            .step_by(stride as usize)
            .map(f32::from_bits)
            .chain(edges.into_iter().flat_map(|e| [e, -e]))
            .chain([
                std::f32::consts::TAU - f32::EPSILON * 4.0,
                1e6,
                f32::INFINITY,
                f32::NAN,
            ])
    }

    fn same(a: (f32, f32), b: (f32, f32)) -> bool {
        a.0.to_bits() == b.0.to_bits() && a.1.to_bits() == b.1.to_bits()
    }

    /// On glibc, the same bits as the C library's `sincosf`.
    #[test]
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn matches_glibc_sincosf() {
        let mut lanes = [0.0f32; 8];
        let mut tested = 0usize;
        for (i, x) in angles(97).enumerate() {
            let want = libm(x);
            assert!(
                same(sin_cos(x), want) || x.is_nan(),
                "sin_cos({x:e}) = {:?}, libm {want:?}",
                sin_cos(x)
            );
            assert!(same(sin_cos_with(x), want) || x.is_nan(), "software FMA at {x:e}");
            lanes[i % 8] = x;
            if i % 8 == 7 {
                let (s, c) = sin_cos_lanes(&lanes);
                for l in 0..8 {
                    assert!(
                        same((s[l], c[l]), libm(lanes[l])) || lanes[l].is_nan(),
                        "lanes at {:e}",
                        lanes[l]
                    );
                }
            }
            tested += 1;
        }
        assert!(tested > 10_000_000);
    }

    /// Closed forms: exact at 0, and within a few ulps of the true values elsewhere
    /// (checked in `f64`), on any platform.
    #[test]
    fn close_to_the_true_values() {
        assert!(same(sin_cos(0.0), (0.0, 1.0)));
        for x in angles(1009).filter(|x| x.is_finite()) {
            let (s, c) = sin_cos(x);
            let (ts, tc) = (x as f64).sin_cos();
            assert!((s as f64 - ts).abs() <= 1e-7, "sin {x}: {s} vs {ts}");
            assert!((c as f64 - tc).abs() <= 1e-7, "cos {x}: {c} vs {tc}");
        }
    }

    /// All bits of the quadrant logic: the lanes and the scalar path agree at every quadrant
    /// boundary and between.
    #[test]
    fn lanes_equal_the_scalar_path() {
        let quarter = std::f32::consts::FRAC_PI_4;
        let xs: Vec<f32> = (0..4096).map(|k| k as f32 * quarter / 64.0).collect();
        for chunk in xs.chunks_exact(8) {
            let lanes: [f32; 8] = chunk.try_into().unwrap();
            let (s, c) = sin_cos_lanes(&lanes);
            for l in 0..8 {
                assert!(same((s[l], c[l]), sin_cos_with(lanes[l])), "at {}", lanes[l]);
            }
        }
    }
}
