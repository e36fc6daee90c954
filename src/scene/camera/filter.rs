//! The film's reconstruction filter, applied by filter importance sampling (pbrt-v4,
//! `FilterSampler`): a camera sample's film position is drawn from the filter centred on
//! its pixel, and the sample counts with weight 1 (the filters here are positive). Its
//! expectation is Mitsuba's splatted weighted average `sum w L / sum w`: the filter-weighted
//! mean of the radiance around the pixel centre. Mitsuba places samples inside the image
//! only (`hdrfilm`'s `sample_border` false), so a pixel at the edge averages over the part
//! of its filter inside the image; the sampler here draws from that truncated filter.
//!
//! The filters are separable (Mitsuba's `w(dx) w(dy)`), so each axis is drawn on its own:
//! the tent by its inverse CDF, the windowed Gaussian (`exp(-x^2 / 2 sigma^2) - exp(-8)`,
//! radius 4 sigma, Mitsuba's default with sigma 0.5) from a table of its exact CDF over
//! 4,096 bins of the unit shape (the density is constant within a bin of width 1/512
//! sigma; bin masses are exact). The box keeps kalos' `pixel + u` placement bit for bit.

use std::sync::OnceLock;

/// A film's reconstruction filter (Mitsuba's `<rfilter>`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum PixelFilter {
    /// One pixel wide: every sample counts for its own pixel only (kalos' own scenes).
    #[default]
    Box,
    /// `max(0, 1 - |x| / radius)`, radius in pixels (Mitsuba's default 1).
    Tent { radius: f32 },
    /// Mitsuba's windowed Gaussian, cut off at 4 standard deviations (pixels).
    Gaussian { stddev: f32 },
}

/// Bins of the unit Gaussian's table over [-4, 4].
const BINS: usize = 4096;
/// The Gaussian's cut-off in standard deviations.
const CUTOFF: f64 = 4.0;

/// The windowed unit Gaussian's CDF (unnormalised) at x in [-4, 4].
fn gaussian_cdf(x: f64) -> f64 {
    let s2 = std::f64::consts::SQRT_2;
    let bias = (-0.5 * CUTOFF * CUTOFF).exp();
    (std::f64::consts::PI / 2.0).sqrt() * (libm::erf(x / s2) - libm::erf(-CUTOFF / s2))
        - bias * (x + CUTOFF)
}

/// The windowed unit Gaussian's CDF at the bin edges, normalised to end at 1.
fn gaussian_table() -> &'static [f64] {
    static TABLE: OnceLock<Vec<f64>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let total = gaussian_cdf(CUTOFF);
        (0..=BINS)
            .map(|i| gaussian_cdf(-CUTOFF + 2.0 * CUTOFF * i as f64 / BINS as f64) / total)
            .collect()
    })
}

impl PixelFilter {
    /// Mitsuba's default film filter: the Gaussian of standard deviation 0.5 pixels.
    pub const MITSUBA_DEFAULT: PixelFilter = PixelFilter::Gaussian { stddev: 0.5 };

    /// Mitsuba's name of the filter.
    pub fn name(&self) -> &'static str {
        match self {
            PixelFilter::Box => "box",
            PixelFilter::Tent { .. } => "tent",
            PixelFilter::Gaussian { .. } => "gaussian",
        }
    }

    pub fn is_box(&self) -> bool {
        matches!(self, PixelFilter::Box)
    }

    /// Half the filter's support, in pixels.
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian { stddev } => CUTOFF as f32 * stddev,
        }
    }

    /// The filter's weight at offset `x` pixels from the pixel centre (one axis).
    pub fn eval(&self, x: f32) -> f32 {
        match *self {
            PixelFilter::Box => (x.abs() <= 0.5) as u8 as f32,
            PixelFilter::Tent { radius } => (1.0 - (x / radius).abs()).max(0.0),
            PixelFilter::Gaussian { stddev } => {
                let bias = (-0.5 * CUTOFF * CUTOFF).exp() as f32;
                ((-0.5 * (x / stddev).powi(2)).exp() - bias).max(0.0)
            }
        }
    }

    /// A one-line error if the parameters make no filter.
    pub fn validate(&self) -> Result<(), String> {
        let (name, v) = match *self {
            PixelFilter::Box => return Ok(()),
            PixelFilter::Tent { radius } => ("tent radius", radius),
            PixelFilter::Gaussian { stddev } => ("gaussian stddev", stddev),
        };
        if v.is_finite() && v > 0.0 && v <= 64.0 {
            Ok(())
        } else {
            Err(format!("{name} {v}: must be a number of pixels in (0, 64]"))
        }
    }

    /// CDF of the normalised unit shape (support [-1, 1] for the tent, [-4, 4] for the
    /// Gaussian) at `x`, and its inverse.
    fn unit_cdf(&self, x: f64) -> f64 {
        match self {
            PixelFilter::Tent { .. } => {
                let x = x.clamp(-1.0, 1.0);
                if x < 0.0 {
                    0.5 * (1.0 + x) * (1.0 + x)
                } else {
                    1.0 - 0.5 * (1.0 - x) * (1.0 - x)
                }
            }
            _ => {
                let t = gaussian_table();
                let f = ((x + CUTOFF) / (2.0 * CUTOFF) * BINS as f64).clamp(0.0, BINS as f64);
                let i = (f as usize).min(BINS - 1);
                t[i] + (t[i + 1] - t[i]) * (f - i as f64)
            }
        }
    }

    fn unit_inverse(&self, u: f64) -> f64 {
        match self {
            PixelFilter::Tent { .. } => {
                if u < 0.5 {
                    (2.0 * u).sqrt() - 1.0
                } else {
                    1.0 - (2.0 * (1.0 - u)).max(0.0).sqrt()
                }
            }
            _ => {
                let t = gaussian_table();
                // the last edge <= u
                let i = t.partition_point(|&c| c <= u).clamp(1, BINS) - 1;
                let w = t[i + 1] - t[i];
                let f = if w > 0.0 {
                    ((u - t[i]) / w).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                -CUTOFF + 2.0 * CUTOFF * (i as f64 + f) / BINS as f64
            }
        }
    }

    /// Film coordinate (pixels) of a sample of pixel `p` along an axis of `size` pixels,
    /// from uniform `u` in [0, 1): `p + u` for the box; otherwise the pixel centre plus an
    /// offset drawn from the filter restricted to the image [0, size).
    #[inline]
    pub fn film_coordinate(&self, p: u32, size: u32, u: f32) -> f32 {
        let scale = match *self {
            PixelFilter::Box => return p as f32 + u,
            PixelFilter::Tent { radius } => radius as f64,
            PixelFilter::Gaussian { stddev } => stddev as f64,
        };
        let centre = p as f64 + 0.5;
        let lo = self.unit_cdf(-centre / scale);
        let hi = self.unit_cdf((size as f64 - centre) / scale);
        let x = centre + scale * self.unit_inverse(lo + (hi - lo) * u as f64);
        // inside the image: [0, size)
        (x as f32).clamp(0.0, (size as f32).next_down())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::TestRng;
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    /// Chi-square test of `film_coordinate` for pixel `p` of `size` against the filter's
    /// own weights integrated over 64 cells of the (truncated) support.
    fn chi2_axis(f: PixelFilter, p: u32, size: u32) -> f64 {
        chi2_of(f, |p, size, u| f.film_coordinate(p, size, u), p, size)
    }

    /// The same for any sampler of film coordinates.
    fn chi2_of(f: PixelFilter, sample: impl Fn(u32, u32, f32) -> f32, p: u32, size: u32) -> f64 {
        const CELLS: usize = 64;
        const N: usize = 200_000;
        let r = f.radius() as f64;
        let centre = p as f64 + 0.5;
        let (a, b) = ((centre - r).max(0.0), (centre + r).min(size as f64));
        let cell = (b - a) / CELLS as f64;
        let mut obs = [0f64; CELLS];
        let mut rng = TestRng::new(17 + p as u64);
        for _ in 0..N {
            let x = sample(p, size, rng.next_f32()) as f64;
            if !(x >= a - 1e-4 && x <= b + 1e-4) {
                return 0.0; // a sample where the filter has no weight
            }
            obs[(((x - a) / cell).max(0.0) as usize).min(CELLS - 1)] += 1.0;
        }
        // expected: the filter's weight integrated over each cell (Simpson, 16 sub-cells)
        let mut exp = [0f64; CELLS];
        for (i, e) in exp.iter_mut().enumerate() {
            let h = cell / 16.0;
            for k in 0..16 {
                let x0 = a + i as f64 * cell + k as f64 * h - centre;
                let w = |x: f64| f.eval(x as f32) as f64;
                *e += (w(x0) + 4.0 * w(x0 + 0.5 * h) + w(x0 + h)) / 6.0 * h;
            }
        }
        let total: f64 = exp.iter().sum();
        let mut stat = 0.0;
        let mut dof = 0;
        for (o, e) in obs.iter().zip(exp.iter()) {
            let e = e / total * N as f64;
            if e >= 5.0 {
                stat += (o - e) * (o - e) / e;
                dof += 1;
            } else if *o >= 20.0 {
                return 0.0; // many samples where the filter has almost no weight
            }
        }
        1.0 - ChiSquared::new((dof - 1) as f64).unwrap().cdf(stat)
    }

    #[test]
    fn chi2_filter_sampling_inside_and_at_the_edges() {
        use crate::sampling::chi2::ALPHA;
        for f in [
            PixelFilter::MITSUBA_DEFAULT,
            PixelFilter::Gaussian { stddev: 1.3 },
            PixelFilter::Tent { radius: 1.0 },
            PixelFilter::Tent { radius: 2.5 },
        ] {
            // an inner pixel, the first, the last, one near the edge, a 1-pixel image
            for (p, size) in [(20, 48), (0, 48), (47, 48), (1, 48), (0, 1)] {
                let pv = chi2_axis(f, p, size);
                assert!(pv > ALPHA, "{f:?} pixel {p} of {size}: p = {pv:.3e}");
            }
        }
    }

    #[test]
    fn the_chi2_test_rejects_wrong_samplers() {
        use crate::sampling::chi2::ALPHA;
        let g = PixelFilter::MITSUBA_DEFAULT;
        // a Gaussian 10% too wide
        let wide = PixelFilter::Gaussian { stddev: 0.55 };
        let pv = chi2_of(g, |p, s, u| wide.film_coordinate(p, s, u), 20, 48);
        assert!(pv < ALPHA, "{pv}");
        // the edge pixel's filter drawn whole and clamped into the image (not truncated)
        let whole = |p, s, u| g.film_coordinate(p + 10, s + 20, u) - 10.0;
        let pv = chi2_of(g, |p, s, u| whole(p, s, u).max(0.0), 0, 48);
        assert!(pv < ALPHA, "{pv}");
        // the tent for the Gaussian
        let tent = PixelFilter::Tent { radius: 1.2 };
        let pv = chi2_of(g, |p, s, u| tent.film_coordinate(p, s, u), 20, 48);
        assert!(pv < ALPHA, "{pv}");
    }

    #[test]
    fn box_is_the_pixel_plus_u_bit_for_bit() {
        let mut rng = TestRng::new(5);
        for _ in 0..1000 {
            let (p, u) = ((rng.next_f32() * 100.0) as u32, rng.next_f32());
            assert_eq!(
                PixelFilter::Box.film_coordinate(p, 100, u).to_bits(),
                (p as f32 + u).to_bits()
            );
        }
    }

    #[test]
    fn known_answers() {
        // Mitsuba's Gaussian: radius 2 pixels, weight exp(-2 x^2) - exp(-8)
        let g = PixelFilter::MITSUBA_DEFAULT;
        assert_eq!(g.radius(), 2.0);
        assert!((g.eval(0.5) - ((-0.5f32).exp() - (-8f32).exp())).abs() < 1e-6);
        assert_eq!(g.eval(2.5), 0.0);
        // the median of an inner pixel is its centre; u = 0.8413 is one sigma out
        assert!((g.film_coordinate(10, 30, 0.5) - 10.5).abs() < 1e-3);
        assert!((g.film_coordinate(10, 30, 0.841_345) - 11.0).abs() < 2e-3);
        // the tent's quartile: (1 + x)^2 / 2 = 1/4 at x = sqrt(1/2) - 1
        let t = PixelFilter::Tent { radius: 1.0 };
        assert!((t.film_coordinate(5, 10, 0.25) - (5.5 + 0.5f32.sqrt() - 1.0)).abs() < 1e-5);
        // pixel 0's filter is cut at the image's edge: nothing below 0, and its median
        // lies right of the centre
        assert!(g.film_coordinate(0, 30, 0.0) >= 0.0);
        assert!(g.film_coordinate(0, 30, 0.5) > 0.5);
        assert!(PixelFilter::Tent { radius: 0.0 }.validate().is_err());
        assert!(PixelFilter::Gaussian { stddev: f32::NAN }
            .validate()
            .is_err());
    }
}
