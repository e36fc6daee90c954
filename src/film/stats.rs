//! Per-pixel statistics kept exactly: the count n and, per channel, the sums of the
//! samples and of their squares as fixed-point integers. Integer sums are associative, so
//! merging two pixels (or two films, or two shards) gives the same bits whatever the order.

/// Fixed-point scale of the sample sums: a value x is stored as trunc(x * 2^40). Values
/// below 2^-40 (1e-12) vanish; the sum of 2^32 samples stays in range up to |x| = 2^54.
pub const FIXED: f64 = (1u64 << 40) as f64;
/// Fixed-point scale of the sums of squares: x^2 as trunc(x^2 * 2^56), so the second
/// moment is resolved to 2^-56 (1.4e-17). A term is capped at 2^94 (so 2^32 of them fit
/// an i128): samples above |x| = 2^19 (524288) count as 2^19 in the second moment only,
/// which still marks their pixel as far from converged; the mean stays exact.
pub const FIXED_SQ: f64 = (1u64 << 56) as f64;
/// Largest single term, so 2^32 of them never overflow an i128.
pub const TERM_MAX: f64 = 1.9e28; // < 2^94 = 1.98e28

#[inline]
fn fixed(x: f64, scale: f64) -> i128 {
    // `as` saturates and maps NaN to 0; samples are finite here. Terms that fit an i64
    // (nearly all) take the one-instruction conversion; both truncate, so the value is
    // the same.
    let y = x * scale;
    if y.abs() < I64_RANGE {
        y as i64 as i128
    } else {
        y.clamp(-TERM_MAX, TERM_MAX) as i128
    }
}

/// Magnitudes below this convert exactly through an i64 (2^63).
const I64_RANGE: f64 = 9_223_372_036_854_775_808.0;

/// Statistics of the samples of one pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelStats {
    pub n: u32,
    /// Sum of the samples, fixed point (`FIXED`).
    pub sum: [i128; 3],
    /// Sum of the squared samples, fixed point (`FIXED_SQ`).
    pub sum_sq: [i128; 3],
}

impl PixelStats {
    /// Add one sample. The caller has checked it is finite.
    #[inline]
    pub fn push(&mut self, v: [f32; 3]) {
        self.n += 1;
        for (c, &x) in v.iter().enumerate() {
            let x = x as f64;
            self.sum[c] += fixed(x, FIXED);
            self.sum_sq[c] += fixed(x * x, FIXED_SQ);
        }
    }

    /// Statistics with a given count, mean and sum of squared deviations M2 (tests and
    /// synthetic films).
    pub fn from_moments(n: u32, mean: [f64; 3], m2: [f64; 3]) -> PixelStats {
        let mut p = PixelStats {
            n,
            ..Default::default()
        };
        for c in 0..3 {
            let nf = n as f64;
            p.sum[c] = fixed(mean[c] * nf, FIXED);
            p.sum_sq[c] = fixed(m2[c] + nf * mean[c] * mean[c], FIXED_SQ);
        }
        p
    }

    /// Add another pixel's statistics (exact).
    #[inline]
    pub fn merge_from(&mut self, o: &PixelStats) {
        self.n += o.n;
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sum_sq[c] += o.sum_sq[c];
        }
    }

    /// The two sets of statistics together.
    pub fn merge(&self, o: &PixelStats) -> PixelStats {
        let mut r = *self;
        r.merge_from(o);
        r
    }

    /// Mean per channel (0 without samples).
    #[inline]
    pub fn mean(&self) -> [f64; 3] {
        if self.n == 0 {
            return [0.0; 3];
        }
        let k = 1.0 / (FIXED * self.n as f64);
        self.sum.map(|s| s as f64 * k)
    }

    /// Sum of squared deviations from the mean per channel (M2 = sum x^2 - n mean^2).
    pub fn m2(&self) -> [f64; 3] {
        let mean = self.mean();
        let n = self.n as f64;
        [0, 1, 2].map(|c| (self.sum_sq[c] as f64 / FIXED_SQ - n * mean[c] * mean[c]).max(0.0))
    }

    /// Sample variance per channel (n - 1 denominator); 0 with fewer than two samples.
    #[inline]
    pub fn variance(&self) -> [f64; 3] {
        if self.n < 2 {
            return [0.0; 3];
        }
        let k = 1.0 / (self.n - 1) as f64;
        self.m2().map(|m| m * k)
    }

    /// Variance of the mean per channel (sigma^2 / n).
    #[inline]
    pub fn variance_of_mean(&self) -> [f64; 3] {
        let v = self.variance();
        let n = self.n.max(1) as f64;
        v.map(|x| x / n)
    }

    #[inline]
    pub fn mean_f32(&self) -> [f32; 3] {
        self.mean().map(|v| v as f32)
    }
}

/// The largest sample magnitude a pixel takes: the fixed-point sums hold values up to
/// `TERM_MAX / FIXED` (1.7e16) exactly, and a larger one would be clamped in silence.
pub const SAMPLE_MAX: f32 = 1e16;

/// Counts of samples that were caught before reaching a pixel.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize, PartialEq, Eq)]
pub struct Rejections {
    pub nan: u64,
    /// Infinite, or finite beyond `SAMPLE_MAX`.
    pub infinite: u64,
}

impl Rejections {
    pub fn total(&self) -> u64 {
        self.nan + self.infinite
    }
    pub fn add(&mut self, o: &Rejections) {
        self.nan += o.nan;
        self.infinite += o.infinite;
    }
    /// Returns true if the sample may go into a pixel; counts it otherwise.
    #[inline]
    pub fn check(&mut self, v: &[f32; 3]) -> bool {
        // false for NaN too
        if v.iter().all(|x| x.abs() <= SAMPLE_MAX) {
            return true;
        }
        if v.iter().any(|x| x.is_nan()) {
            self.nan += 1;
        } else {
            self.infinite += 1;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NaN, infinite and finite samples beyond what the fixed-point sums hold are counted
    /// and kept out of the pixel (a 1e20 sample was clamped to 1.7e16 in silence).
    #[test]
    fn samples_beyond_the_sums_range_are_rejected() {
        let mut r = Rejections::default();
        assert!(r.check(&[SAMPLE_MAX, -SAMPLE_MAX, 0.0]));
        assert!(!r.check(&[0.0, 1e20, 0.0]));
        assert!(!r.check(&[f32::INFINITY, 0.0, 0.0]));
        assert!(!r.check(&[f32::NAN, 1e20, 0.0]));
        assert_eq!((r.nan, r.infinite), (1, 2));
        // the largest accepted sample sums exactly
        let mut p = PixelStats::default();
        p.push([SAMPLE_MAX; 3]);
        assert_eq!(p.sum[0], (SAMPLE_MAX as f64 * FIXED) as i128);
    }

    /// The i64 shortcut gives the terms of the i128 conversion it replaced, on both sides
    /// of 2^63, at the cap, for negative values and for NaN.
    #[test]
    fn fixed_terms_are_those_of_the_i128_conversion() {
        let old = |x: f64, s: f64| (x * s).clamp(-TERM_MAX, TERM_MAX) as i128;
        let mut xs = vec![
            0.0, -0.0, 1e-13, 0.5, 1.0, 3.7, 11.3, 11.4, 2e6, 8.4e6, 8.5e6, 1e30,
        ];
        // Around the i64 boundary for both scales.
        for s in [FIXED, FIXED_SQ] {
            let b = I64_RANGE / s;
            for k in -3..=3 {
                xs.push(b * (1.0 + k as f64 * f64::EPSILON));
            }
        }
        xs.push(f64::NAN);
        for &x in &xs {
            for x in [x, -x] {
                for s in [FIXED, FIXED_SQ] {
                    assert_eq!(fixed(x, s), old(x, s), "x = {x:e}, scale {s:e}");
                }
            }
        }
    }
}
