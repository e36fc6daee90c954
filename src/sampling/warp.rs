//! Warps from [0,1)^2 to directions and points, each with its pdf.
//! Directions are in a local frame with the normal along +z.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// Cosine-weighted hemisphere (Malley's method over a concentric disk).
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_concentric_disk(u);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

#[inline]
pub fn pdf_cosine_hemisphere(w: Vec3) -> f32 {
    if w.z > 0.0 {
        w.z * FRAC_1_PI
    } else {
        0.0
    }
}

/// Shirley-Chiu concentric map to the unit disk.
#[inline]
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // theta = a in the first case, pi/2 - a in the second, with |a| <= pi/4 in both:
    // (cos, sin) of pi/2 - a are (sin a, cos a).
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_quarter((PI / 4.0) * (o.y / o.x));
        Vec2::new(o.x * c, o.x * s)
    } else {
        let (s, c) = sin_cos_quarter((PI / 4.0) * (o.x / o.y));
        Vec2::new(o.y * s, o.y * c)
    }
}

/// (sin a, cos a) for |a| <= pi/4, by the minimax polynomials of Cephes' `sinf` and
/// `cosf` on that range (within 2 ulp of the true values; no range reduction, so a few
/// multiply-adds instead of a call to libm's `sincosf`, and the same bits on every
/// machine).
#[inline(always)]
pub fn sin_cos_quarter(a: f32) -> (f32, f32) {
    debug_assert!(a.abs() <= PI / 4.0 + 1e-6);
    let z = a * a;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * a + a;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
}

#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub const PDF_UNIFORM_SPHERE: f32 = 1.0 / (4.0 * PI);

/// Uniform point on a triangle, as barycentrics (b1, b2) of v1 and v2.
#[inline]
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

/// Direction around +z with density (n + 1)/(2 pi) cos^n(alpha): the Phong lobe.
#[inline]
pub fn square_to_cos_power(u: Vec2, n: f32) -> Vec3 {
    let cos_a = u.x.powf(1.0 / (n + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a)
}

#[inline]
pub fn pdf_cos_power(cos_a: f32, n: f32) -> f32 {
    if cos_a <= 0.0 {
        0.0
    } else {
        (n + 1.0) * (0.5 * FRAC_1_PI) * cos_a.powf(n)
    }
}

/// Power heuristic with beta = 2 for one-sample MIS.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a == 0.0 {
        0.0
    } else if a.is_infinite() {
        1.0
    } else {
        a / (a + b)
    }
}

/// A discrete distribution sampled by inverting its CDF.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// Normalised cumulative sums, cdf[i] = P(X < i), length n + 1.
    cdf: Vec<f32>,
    /// Probability of each entry.
    pmf: Vec<f32>,
    total: f64,
    /// cdf[1..] of a distribution of up to [`SMALL`] entries, the rest NaN (which no u
    /// passes), for `index_of` to count at once.
    head: [f32; SMALL],
}

/// Entries up to which `Distribution1D::index_of` counts the cdf values at or below u in
/// one vector comparison instead of bisecting.
const SMALL: usize = 8;

impl Distribution1D {
    /// From non-negative weights; all-zero weights give an empty distribution.
    pub fn new(weights: &[f32]) -> Self {
        let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if total <= 0.0 || !total.is_finite() {
            return Distribution1D {
                cdf: vec![0.0],
                pmf: vec![0.0; weights.len()],
                total: 0.0,
                head: [f32::NAN; SMALL],
            };
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut pmf = Vec::with_capacity(weights.len());
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            let w = w.max(0.0) as f64;
            acc += w;
            cdf.push((acc / total) as f32);
            pmf.push((w / total) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let mut head = [f32::NAN; SMALL];
        if weights.len() <= SMALL {
            head[..weights.len()].copy_from_slice(&cdf[1..]);
        }
        Distribution1D {
            cdf,
            pmf,
            total,
            head,
        }
    }
    pub fn is_empty(&self) -> bool {
        self.total == 0.0
    }
    pub fn len(&self) -> usize {
        self.pmf.len()
    }
    pub fn total(&self) -> f64 {
        self.total
    }
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }
    /// Returns (index, pmf, u rescaled to [0,1) within the chosen entry).
    #[inline(always)]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let n = self.pmf.len();
        let i = self.index_of(u).min(n - 1);
        let p = self.pmf[i];
        let ur = if p > 0.0 {
            ((u - self.cdf[i]) / p).clamp(0.0, super::rng::ONE_MINUS_EPS)
        } else {
            0.0
        };
        (i, p, ur)
    }

    /// The first index i with cdf[i+1] > u (n if none): the number of entries whose
    /// cdf[i+1] <= u, as the cdf does not decrease. Up to [`SMALL`] entries that number
    /// is counted in one vector comparison; past it, a bisection whose steps depend on n
    /// alone, each choosing its half by a conditional move. (With u random, the
    /// bisection's branch per step was mispredicted about every other time: a light
    /// sample of the furnished room's eight ceiling triangles was 4.6% of its render
    /// time, most of it there.)
    #[inline(always)]
    fn index_of(&self, u: f32) -> usize {
        let n = self.pmf.len();
        if n <= SMALL {
            return self.head.iter().map(|&c| (c <= u) as usize).sum();
        }
        let upper = &self.cdf[1..];
        let (mut base, mut size) = (0, n);
        while size > 1 {
            let half = size / 2;
            let mid = base + half;
            base = std::hint::select_unpredictable(upper[mid] <= u, mid, base);
            size -= half;
        }
        base + (upper[base] <= u) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distribution_samples_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        let mut counts = [0usize; 3];
        for i in 0..4000 {
            let (k, p, ur) = d.sample((i as f32 + 0.5) / 4000.0);
            assert!(p > 0.0 && (0.0..1.0).contains(&ur));
            counts[k] += 1;
        }
        assert_eq!(counts[1], 0);
        assert!((counts[0] as f32 / 4000.0 - 0.25).abs() < 0.01);
    }

    /// The polynomial sine and cosine within 2 ulp (relative: 2 |x| eps) of the
    /// double-precision values over the whole quarter range, endpoints too.
    #[test]
    fn sin_cos_quarter_is_accurate() {
        let n = 200_000;
        for i in 0..=n {
            let a = (i as f32 / n as f32 * 2.0 - 1.0) * (PI / 4.0);
            let (s, c) = sin_cos_quarter(a);
            let (se, ce) = (a as f64).sin_cos();
            let ulp = |x: f64| (x.abs() * f32::EPSILON as f64).max(f32::MIN_POSITIVE as f64);
            assert!(
                (s as f64 - se).abs() <= 2.0 * ulp(se),
                "sin({a}) = {s}, not {se}"
            );
            assert!(
                (c as f64 - ce).abs() <= 2.0 * ulp(ce),
                "cos({a}) = {c}, not {ce}"
            );
        }
    }

    /// The bisection without branches finds the index of the one with them (the first
    /// i with cdf[i+1] > u, the index `sample` took until 2026-12-06), over sizes 1 to
    /// 40 (counted up to 8, bisected past), with zero weights (repeated cdf values) and
    /// at the cdf's own values, 0, 1 - eps, 1, infinity, NaN and below 0.
    #[test]
    fn the_index_is_the_first_past_u() {
        let mut rng = crate::sampling::SeqRng::new(7);
        for n in 1..=40usize {
            let w: Vec<f32> = (0..n)
                .map(|k| {
                    if k % 3 == 1 {
                        0.0
                    } else {
                        rng.next_f32() + 0.01
                    }
                })
                .collect();
            let d = Distribution1D::new(&w);
            let want = |u: f32| {
                let (mut lo, mut hi) = (0, n);
                while lo < hi {
                    let mid = (lo + hi) / 2;
                    if d.cdf[mid + 1] <= u {
                        lo = mid + 1;
                    } else {
                        hi = mid;
                    }
                }
                lo
            };
            let mut us: Vec<f32> = d.cdf.clone();
            let ends = [0.0, super::super::rng::ONE_MINUS_EPS, 1.0, f32::INFINITY];
            us.extend(ends.into_iter().chain([f32::NAN, -1.0]));
            us.extend((0..200).map(|_| rng.next_f32()));
            for u in us {
                assert_eq!(d.index_of(u), want(u), "{n} entries, u {u}");
                let (i, p, _) = d.sample(u);
                assert_eq!((i, p), (want(u).min(n - 1), d.pmf[want(u).min(n - 1)]));
            }
        }
    }

    #[test]
    fn empty_distribution() {
        let d = Distribution1D::new(&[0.0, 0.0]);
        assert!(d.is_empty());
    }
}
