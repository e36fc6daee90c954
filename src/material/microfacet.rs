//! The microfacet distributions of Mitsuba's rough plugins, of roughness alpha_u along
//! the local x axis (the tangent) and alpha_v along y (isotropic: both alpha): GGX
//! (Trowbridge-Reitz) and Beckmann, each with Smith's separable shadowing-masking
//! G(wo, wi, m) = G1(wo, m) G1(wi, m) (the form Mitsuba 3 uses) and exact sampling of the
//! normals visible from a direction.
//!
//! Symbols: m the microfacet normal, theta_m its angle to the macro normal (+z), v a
//! direction, a = 1 / (alpha_v' tan theta_v), where alpha_v'^2 = (alpha_u^2 v_x^2 +
//! alpha_v^2 v_y^2) / (v_x^2 + v_y^2) is the roughness seen along v's azimuth (alpha when
//! isotropic).
//!
//! GGX (Walter et al. 2007; Heitz, "Sampling the GGX distribution of visible normals",
//! JCGT 2018):
//!   D(m)      = 1 / (pi alpha_u alpha_v (m_x^2 / alpha_u^2 + m_y^2 / alpha_v^2 + m_z^2)^2),
//!   Lambda(v) = (-1 + sqrt(1 + 1 / a^2)) / 2.
//!
//! Beckmann (Walter et al. 2007, eq. 25 and 27; Heitz and d'Eon, "Importance sampling
//! microfacet-based BSDFs using the distribution of visible normals", EGSR 2014):
//!   D(m)      = exp(-(m_x^2 / alpha_u^2 + m_y^2 / alpha_v^2) / m_z^2)
//!               / (pi alpha_u alpha_v cos^4 theta_m),
//!   Lambda(v) = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi))   (exact Smith;
//!               Mitsuba uses a rational fit of 1 / (1 + Lambda) within 0.35% of it).
//!
//! Both:
//!   G1(v, m)  = 1 / (1 + Lambda(v)), 0 where v sees the back of m ((v.m) cos theta_v <= 0),
//!   D_v(m)    = G1(v, m) max(0, v.m) D(m) / cos theta_v: the density of the normals
//!               visible from v, which `sample_visible` draws exactly.
//!
//! Visible normals are drawn in the stretched configuration (alpha = 1, the view
//! v' = (alpha_u v_x, alpha_v v_y, v_z) / |..|) and unstretched by (alpha_u, alpha_v), as
//! Mitsuba's `MicrofacetDistribution::sample` with `sample_visible`. GGX: Heitz's projected-disk construction.
//! Beckmann: in slope space (x~, y~) = (-m_x / m_z, -m_y / m_z) the visible slopes seen
//! from v' at angle theta (azimuth 0) have the density
//!   (1 - x~ tan theta)^+ exp(-x~^2 - y~^2) / (pi C(cot theta)),
//!   C(x) = (1 + erf(x)) / 2 + tan theta exp(-x^2) / (2 sqrt(pi))   (the CDF of x~; C(cot theta) = 1 + Lambda),
//! so y~ ~ N(0, 1/2) on its own and x~ solves C(x~) = u C(cot theta) (Newton's method
//! kept inside a bisection bracket); the slopes are turned by v's azimuth, scaled by
//! (alpha_u, alpha_v) and made a normal.
//!
//! The isotropic case keeps its own expressions of D and G1 (one comparison chooses),
//! so that its values do not change by a rounding.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Roughness below this is treated as this (the smooth interfaces are separate models).
pub const MIN_ALPHA: f32 = 1e-4;

/// Mitsuba's `distribution` parameter of the rough plugins (its default is Beckmann).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    #[default]
    Beckmann,
    Ggx,
}

impl Distribution {
    /// Mitsuba's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Distribution::Beckmann => "beckmann",
            Distribution::Ggx => "ggx",
        }
    }

    pub fn from_name(s: &str) -> Option<Distribution> {
        match s {
            "beckmann" => Some(Distribution::Beckmann),
            "ggx" => Some(Distribution::Ggx),
            _ => None,
        }
    }
}

/// A local direction in the frame of a tangent at angle (cos, sin) `tangent` to the local
/// x axis (x along the tangent, the normal kept): where anisotropic roughness applies.
#[inline]
pub fn in_tangent_frame(tangent: [f32; 2], v: Vec3) -> Vec3 {
    let [c, s] = tangent;
    Vec3::new(c * v.x + s * v.y, c * v.y - s * v.x, v.z)
}

/// The inverse of [`in_tangent_frame`].
#[inline]
pub fn in_local_frame(tangent: [f32; 2], v: Vec3) -> Vec3 {
    let [c, s] = tangent;
    Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// `f(wo, wi)` with both directions in the frame of `tangent` (unturned where None).
#[inline]
pub fn turned<T>(
    tangent: Option<[f32; 2]>,
    wo: Vec3,
    wi: Vec3,
    f: impl FnOnce(Vec3, Vec3) -> T,
) -> T {
    match tangent {
        None => f(wo, wi),
        Some(t) => f(in_tangent_frame(t, wo), in_tangent_frame(t, wi)),
    }
}

/// A sample `f(wo)` drawn in the frame of `tangent`, its direction turned back.
#[inline]
pub fn sample_turned<const N: usize>(
    tangent: Option<[f32; 2]>,
    wo: Vec3,
    f: impl FnOnce(Vec3) -> Option<super::BsdfSample<N>>,
) -> Option<super::BsdfSample<N>> {
    match tangent {
        None => f(wo),
        Some(t) => {
            let mut s = f(in_tangent_frame(t, wo))?;
            s.wi = in_local_frame(t, s.wi);
            Some(s)
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub dist: Distribution,
    /// Roughness along the local x axis (alpha_u; the isotropic alpha).
    pub alpha: f32,
    /// Roughness along the local y axis (alpha_v; equal to `alpha` when isotropic).
    pub alpha_v: f32,
}

const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

impl Microfacet {
    #[inline]
    pub fn new(dist: Distribution, alpha: f32) -> Microfacet {
        let alpha = alpha.max(MIN_ALPHA);
        Microfacet {
            dist,
            alpha,
            alpha_v: alpha,
        }
    }

    /// Roughness `alpha_u` along the local x axis, `alpha_v` along y.
    #[inline]
    pub fn anisotropic(dist: Distribution, alpha_u: f32, alpha_v: f32) -> Microfacet {
        Microfacet {
            dist,
            alpha: alpha_u.max(MIN_ALPHA),
            alpha_v: alpha_v.max(MIN_ALPHA),
        }
    }

    #[inline(always)]
    fn is_isotropic(&self) -> bool {
        self.alpha == self.alpha_v
    }

    /// D(m), per unit solid angle of m (projected: integral of D(m) cos theta_m = 1).
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let d = if self.is_isotropic() {
            let a2 = self.alpha * self.alpha;
            match self.dist {
                Distribution::Ggx => {
                    let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
                    1.0 / (PI * a2 * t * t)
                }
                Distribution::Beckmann => {
                    let c2 = m.z * m.z;
                    let tan2 = (m.x * m.x + m.y * m.y) / c2;
                    (-tan2 / a2).exp() / (PI * a2 * c2 * c2)
                }
            }
        } else {
            let (x, y) = (m.x / self.alpha, m.y / self.alpha_v);
            let auv = self.alpha * self.alpha_v;
            match self.dist {
                Distribution::Ggx => {
                    let t = x * x + y * y + m.z * m.z;
                    1.0 / (PI * auv * t * t)
                }
                Distribution::Beckmann => {
                    let c2 = m.z * m.z;
                    (-(x * x + y * y) / c2).exp() / (PI * auv * c2 * c2)
                }
            }
        };
        // as Mitsuba: drop values that underflow with the cosine
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Smith's G1(v, m).
    #[inline]
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy2 = if self.is_isotropic() {
            self.alpha * self.alpha * (v.x * v.x + v.y * v.y)
        } else {
            let (x, y) = (self.alpha * v.x, self.alpha_v * v.y);
            x * x + y * y
        };
        if xy2 == 0.0 {
            return 1.0;
        }
        // 1 / a^2 = alpha^2 tan^2 theta_v
        let tan2_alpha2 = xy2 / (v.z * v.z);
        match self.dist {
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + tan2_alpha2).sqrt()),
            Distribution::Beckmann => {
                let a = 1.0 / (tan2_alpha2 as f64).sqrt();
                (1.0 / (1.0 + beckmann_lambda(a))) as f32
            }
        }
    }

    /// Separable G(wo, wi, m) = G1(wo, m) G1(wi, m).
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3, m: Vec3) -> f32 {
        self.g1(wo, m) * self.g1(wi, m)
    }

    /// D_v(m): density of the visible normal m seen from v (v in the upper hemisphere).
    #[inline]
    pub fn pdf_visible(&self, v: Vec3, m: Vec3) -> f32 {
        if v.z <= 0.0 {
            return 0.0;
        }
        self.g1(v, m) * v.dot(m).max(0.0) * self.d(m) / v.z
    }

    /// A normal drawn from D_v; v must have v.z > 0.
    #[inline]
    pub fn sample_visible(&self, v: Vec3, u: Vec2) -> Vec3 {
        match self.dist {
            Distribution::Ggx => self.sample_visible_ggx(v, u),
            Distribution::Beckmann => self.sample_visible_beckmann(v, u),
        }
    }

    /// Heitz 2018, listing 1.
    fn sample_visible_ggx(&self, v: Vec3, u: Vec2) -> Vec3 {
        let (au, av) = (self.alpha, self.alpha_v);
        // 1. the view direction in the hemisphere configuration (stretched to alpha = 1)
        let vh = Vec3::new(au * v.x, av * v.y, v.z).normalize();
        // 2. an orthonormal basis (T1, T2, vh)
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // 3. a point on the projected disk, its lower half squeezed by (1 + vh.z) / 2
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        // 4. reprojected onto the hemisphere
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        // 5. back to the ellipsoid configuration
        Vec3::new(au * nh.x, av * nh.y, nh.z.max(1e-7)).normalize()
    }

    /// Heitz and d'Eon 2014 (see the module's notes): slopes in the stretched
    /// configuration, in f64.
    fn sample_visible_beckmann(&self, v: Vec3, u: Vec2) -> Vec3 {
        let (au, av) = (self.alpha as f64, self.alpha_v as f64);
        // 1. stretch: v' = (alpha_u v_x, alpha_v v_y, v_z) / |..|, its angle and azimuth
        let (sx, sy, sz) = (au * v.x as f64, av * v.y as f64, v.z as f64);
        let sin_t = (sx * sx + sy * sy).sqrt();
        let (cos_phi, sin_phi) = if sin_t > 0.0 {
            (sx / sin_t, sy / sin_t)
        } else {
            (1.0, 0.0)
        };
        // tan theta of v' (the stretch leaves the azimuth alone)
        let tan_t = sin_t / sz.max(1e-12);
        // 2. the slopes seen from v' at azimuth 0
        let (x, y) = beckmann_visible_slopes(tan_t, u.x as f64, u.y as f64);
        // 3. turned by the azimuth, 4. unstretched
        let xr = (cos_phi * x - sin_phi * y) * au;
        let yr = (sin_phi * x + cos_phi * y) * av;
        // 5. the normal of slopes (x~, y~)
        Vec3::new(-xr as f32, -yr as f32, 1.0).normalize()
    }
}

/// Smith's Lambda of the Beckmann distribution at a = 1 / (alpha tan theta) > 0
/// (erfc(a) for 1 - erf(a), which keeps the digits where both are small).
#[inline]
fn beckmann_lambda(a: f64) -> f64 {
    0.5 * (INV_SQRT_PI * (-a * a).exp() / a - libm::erfc(a))
}

/// Slopes (x~, y~) of a normal visible from the direction of tan theta = `tan_t` at azimuth
/// 0 under the Beckmann distribution of alpha = 1, from two uniform numbers.
fn beckmann_visible_slopes(tan_t: f64, u1: f64, u2: f64) -> (f64, f64) {
    // Beyond +-6 the Gaussian's tail is below 1e-16 of its mass.
    const LIM: f64 = 6.0;
    let e = |x: f64| (-x * x).exp();
    // y~: (1 + erf(y)) / 2 = u2
    let y = solve_increasing(
        |y| 0.5 * (1.0 + libm::erf(y)),
        |y| INV_SQRT_PI * e(y),
        u2,
        -LIM,
        LIM,
    );
    // x~: C(x) = u1 C(cot theta) on x < cot theta, C' = (1 - x tan) exp(-x^2) / sqrt(pi)
    let cdf = |x: f64| 0.5 * (1.0 + libm::erf(x)) + 0.5 * tan_t * INV_SQRT_PI * e(x);
    let hi = if tan_t > 0.0 {
        (1.0 / tan_t).min(LIM)
    } else {
        LIM
    };
    let total = if tan_t > 0.0 { cdf(1.0 / tan_t) } else { 1.0 };
    let x = solve_increasing(
        cdf,
        |x| (1.0 - x * tan_t).max(0.0) * INV_SQRT_PI * e(x),
        u1 * total,
        -LIM,
        hi,
    );
    (x, y)
}

/// The x in [lo, hi] with f(x) = target for an increasing f with derivative df: Newton's
/// steps, each kept inside the bracket that the values so far leave (bisection where a
/// step would leave it), to a step below 1e-9.
fn solve_increasing(
    f: impl Fn(f64) -> f64,
    df: impl Fn(f64) -> f64,
    target: f64,
    mut lo: f64,
    mut hi: f64,
) -> f64 {
    if target <= f(lo) {
        return lo;
    }
    if target >= f(hi) {
        return hi;
    }
    let mut x = 0.5 * (lo + hi);
    for _ in 0..64 {
        let r = f(x) - target;
        if r > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let d = df(x);
        let newton = x - r / d;
        let next = if d > 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - x).abs() < 1e-9 {
            return next;
        }
        x = next;
    }
    x
}

/// The mirror direction of v about m: 2 (v.m) m - v.
#[inline]
pub fn reflect(v: Vec3, m: Vec3) -> Vec3 {
    2.0 * v.dot(m) * m - v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};

    const BOTH: [Distribution; 2] = [Distribution::Ggx, Distribution::Beckmann];

    #[test]
    fn d_is_normalised_and_visible_normals_integrate_to_one() {
        // integral of D(m) cos theta_m dm = 1 and integral of D_v(m) dm = 1 (midpoint rule
        // over the hemisphere in (cos theta, phi)).
        for (dist, alpha) in BOTH.into_iter().flat_map(|d| {
            [
                (0.05f32, 0.05),
                (0.3, 0.3),
                (0.8, 0.8),
                (0.25, 0.05),
                (0.1, 0.6),
            ]
            .map(|a| (d, a))
        }) {
            let g = Microfacet::anisotropic(dist, alpha.0, alpha.1);
            let v = Vec3::new(0.6, 0.2, 0.5).normalize();
            let (n_t, n_p) = (4000, 64);
            let (mut s1, mut s2) = (0.0f64, 0.0f64);
            for i in 0..n_t {
                // cos theta = 1 - x^2 concentrates nodes near the pole (sharp lobes)
                let x = (i as f64 + 0.5) / n_t as f64;
                let c = 1.0 - x * x;
                let jac = 2.0 * x / n_t as f64;
                let s = (1.0 - c * c).max(0.0).sqrt();
                for j in 0..n_p {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n_p as f64;
                    let m = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                    let w = jac * 2.0 * std::f64::consts::PI / n_p as f64;
                    s1 += g.d(m) as f64 * c * w;
                    s2 += g.pdf_visible(v, m) as f64 * w;
                }
            }
            assert!(
                (s1 - 1.0).abs() < 2e-3,
                "{dist:?} alpha {alpha:?}: int D cos = {s1}"
            );
            assert!(
                (s2 - 1.0).abs() < 2e-3,
                "{dist:?} alpha {alpha:?}: int D_v = {s2}"
            );
        }
    }

    #[test]
    fn chi2_visible_normals() {
        // isotropic, and anisotropic seen at an azimuth off both axes (lobes no sharper
        // than the grid of the test resolves)
        let cases = BOTH.into_iter().flat_map(|d| {
            [
                (0.2f32, 0.2),
                (0.5, 0.5),
                (1.0, 1.0),
                (0.6, 0.2),
                (0.2, 0.8),
            ]
            .map(|a| (d, a))
        });
        for (k, (dist, alpha)) in cases.enumerate() {
            let g = Microfacet::anisotropic(dist, alpha.0, alpha.1);
            let phi = if alpha.0 == alpha.1 { 0.0f32 } else { 0.6 };
            for (j, deg) in [0.0f32, 45.0, 80.0].into_iter().enumerate() {
                let t = deg.to_radians();
                let v = Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
                let r = chi2_sphere(
                    |_, u| Some(g.sample_visible(v, u)),
                    |m| g.pdf_visible(v, m),
                    200_000,
                    500 + (k * 10 + j) as u64,
                );
                assert_chi2(
                    &format!("{dist:?} visible normals alpha {alpha:?} at {deg}"),
                    &r,
                );
            }
        }
        let _ = TestRng::new(1);
    }

    #[test]
    fn beckmann_smith_g1_against_mitsubas_fit_and_known_values() {
        // Mitsuba's rational fit of 1 / (1 + Lambda(a)) (within 0.35% by its comment)
        let fit = |a: f64| {
            if a >= 1.6 {
                1.0
            } else {
                (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
            }
        };
        let g = Microfacet::new(Distribution::Beckmann, 0.5);
        for deg in [5.0f32, 30.0, 60.0, 75.0, 85.0, 89.0] {
            let t = deg.to_radians();
            let v = Vec3::new(t.sin(), 0.0, t.cos());
            let a = 1.0 / (0.5 * t.tan() as f64);
            let exact = g.g1(v, Vec3::Z) as f64;
            assert!(
                (exact - fit(a)).abs() <= 4e-3 * exact,
                "at {deg}: G1 {exact} vs Mitsuba's fit {}",
                fit(a)
            );
        }
        // at a = 1: (erf(1) - 1) / 2 + e^-1 / (2 sqrt(pi)) = 0.0251273...; Lambda -> 0 as a grows
        assert!((beckmann_lambda(1.0) - 0.025_127_3).abs() < 1e-6);
        assert!(beckmann_lambda(8.0).abs() < 1e-20);
    }

    #[test]
    fn beckmann_slopes_invert_their_cdf() {
        // C(x~) = u C(cot theta): the solver's root, checked at the extremes of u and theta
        for tan_t in [0.0f64, 0.1, 1.0, 10.0, 1e4] {
            for u in [1e-7f64, 0.25, 0.5, 0.999_999] {
                let (x, y) = beckmann_visible_slopes(tan_t, u, u);
                let c = |x: f64| {
                    0.5 * (1.0 + libm::erf(x)) + 0.5 * tan_t * INV_SQRT_PI * (-x * x).exp()
                };
                let total = if tan_t > 0.0 { c(1.0 / tan_t) } else { 1.0 };
                assert!(
                    (c(x) - u * total).abs() < 1e-6 * total.max(1.0),
                    "tan {tan_t} u {u}"
                );
                assert!(tan_t == 0.0 || x <= 1.0 / tan_t + 1e-12);
                assert!((0.5 * (1.0 + libm::erf(y)) - u).abs() < 1e-6);
            }
        }
    }
}
