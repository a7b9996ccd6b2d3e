//! The harmonic mean of distances, spec §1 equation (2): `H = N / Σ 1/d_i`.

/// How sample distances are clamped before they enter the mean (spec §1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceClamp {
    /// `d_min = 1e-6 · l_diag`: a grazing self-hit cannot drive H to zero.
    pub min: f32,
    /// `--max-distance`: distances above it, escapes included, count as it. `+inf` for none.
    pub max: f32,
}

impl DistanceClamp {
    /// The clamp of spec §1 for a scene with bounding-box diagonal `l_diag`.
    pub fn for_diagonal(l_diag: f32, max_distance: Option<f32>) -> Self {
        DistanceClamp {
            min: 1e-6 * l_diag,
            max: max_distance.unwrap_or(f32::INFINITY),
        }
    }
}

/// Accumulates `1/d` over samples; f64 so that 65,536 samples sum without loss.
#[derive(Clone, Copy, Debug, Default)]
pub struct HarmonicMean {
    inverse_sum: f64,
    count: u32,
}

impl HarmonicMean {
    /// Adds one sample distance (`+inf` for an escape, which adds `1/d = 0` unless clamped).
    #[inline(always)]
    pub fn add(&mut self, d: f32, clamp: DistanceClamp) {
        self.add_inverse(d, clamp);
    }

    /// Adds one sample distance, as [`HarmonicMean::add`], and returns the `1/d` it added.
    #[inline(always)]
    pub fn add_inverse(&mut self, d: f32, clamp: DistanceClamp) -> f64 {
        let d = d.min(clamp.max).max(clamp.min);
        let inverse = 1.0 / d as f64;
        self.inverse_sum += inverse;
        self.count += 1;
        inverse
    }

    /// Adds `count` samples whose `1/d` (clamped) sum to `inverse_sum`.
    #[inline]
    pub fn add_sum(&mut self, inverse_sum: f64, count: u32) {
        self.inverse_sum += inverse_sum;
        self.count += count;
    }

    /// `N / Σ 1/d`: `+inf` if every sample escaped, NaN if there were none.
    pub fn value(&self) -> f32 {
        if self.count == 0 {
            f32::NAN
        } else {
            (self.count as f64 / self.inverse_sum) as f32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NONE: DistanceClamp = DistanceClamp {
        min: 0.0,
        max: f32::INFINITY,
    };

    #[test]
    fn harmonic_mean_of_one_and_three_is_three_halves() {
        let mut h = HarmonicMean::default();
        h.add(1.0, NONE);
        h.add(3.0, NONE);
        assert_eq!(h.value(), 1.5);
    }

    #[test]
    fn escapes_add_nothing_to_the_inverse_sum() {
        let mut h = HarmonicMean::default();
        h.add(2.0, NONE);
        h.add(f32::INFINITY, NONE);
        assert_eq!(h.value(), 4.0);
        let mut all_escaped = HarmonicMean::default();
        all_escaped.add(f32::INFINITY, NONE);
        assert_eq!(all_escaped.value(), f32::INFINITY);
        assert!(HarmonicMean::default().value().is_nan());
    }

    #[test]
    fn clamps_apply_at_both_ends() {
        let clamp = DistanceClamp { min: 0.5, max: 4.0 };
        let mut h = HarmonicMean::default();
        h.add(0.0, clamp);
        h.add(f32::INFINITY, clamp);
        assert_eq!(h.value(), 2.0 / (2.0 + 0.25));
    }
}
