//! The GGX (Trowbridge-Reitz) microfacet distribution, isotropic roughness alpha, with
//! Smith's separable shadowing-masking G(wo, wi, m) = G1(wo, m) G1(wi, m) (the form Mitsuba 3
//! uses) and the sampling of visible normals of Heitz, "Sampling the GGX distribution of
//! visible normals" (JCGT 2018).
//!
//! Symbols: m the microfacet normal, theta_m its angle to the macro normal (+z),
//!   D(m)      = 1 / (pi alpha^2 cos^4 theta_m (1 + tan^2 theta_m / alpha^2)^2)
//!             = 1 / (pi alpha^2 (m_x^2 / alpha^2 + m_y^2 / alpha^2 + m_z^2)^2),
//!   Lambda(v) = (-1 + sqrt(1 + alpha^2 tan^2 theta_v)) / 2,
//!   G1(v, m)  = 1 / (1 + Lambda(v)) = 2 / (1 + sqrt(1 + alpha^2 tan^2 theta_v)),
//!               0 where v sees the back of m ((v.m) cos theta_v <= 0),
//!   D_v(m)    = G1(v, m) max(0, v.m) D(m) / cos theta_v: the density of the normals
//!               visible from v, which `sample_visible` draws exactly.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Roughness below this is treated as this (the smooth interfaces are separate models).
pub const MIN_ALPHA: f32 = 1e-4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    #[inline]
    pub fn new(alpha: f32) -> Ggx {
        Ggx {
            alpha: alpha.max(MIN_ALPHA),
        }
    }

    /// D(m), per unit solid angle of m (projected: integral of D(m) cos theta_m = 1).
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
        let d = 1.0 / (PI * a2 * t * t);
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
        let xy2 = self.alpha * self.alpha * (v.x * v.x + v.y * v.y);
        if xy2 == 0.0 {
            return 1.0;
        }
        let tan2_alpha2 = xy2 / (v.z * v.z);
        2.0 / (1.0 + (1.0 + tan2_alpha2).sqrt())
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

    /// A normal drawn from D_v (Heitz 2018, listing 1); v must have v.z > 0.
    #[inline]
    pub fn sample_visible(&self, v: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha;
        // 1. the view direction in the hemisphere configuration (stretched to alpha = 1)
        let vh = Vec3::new(a * v.x, a * v.y, v.z).normalize();
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
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-7)).normalize()
    }
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

    #[test]
    fn d_is_normalised_and_visible_normals_integrate_to_one() {
        // integral of D(m) cos theta_m dm = 1 and integral of D_v(m) dm = 1 (midpoint rule
        // over the hemisphere in (cos theta, phi)).
        for alpha in [0.05f32, 0.3, 0.8] {
            let g = Ggx::new(alpha);
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
            assert!((s1 - 1.0).abs() < 2e-3, "alpha {alpha}: int D cos = {s1}");
            assert!((s2 - 1.0).abs() < 2e-3, "alpha {alpha}: int D_v = {s2}");
        }
    }

    #[test]
    fn chi2_visible_normals() {
        for (k, alpha) in [0.2f32, 0.5, 1.0].into_iter().enumerate() {
            let g = Ggx::new(alpha);
            for (j, deg) in [0.0f32, 45.0, 80.0].into_iter().enumerate() {
                let t = deg.to_radians();
                let v = Vec3::new(t.sin(), 0.0, t.cos());
                let r = chi2_sphere(
                    |_, u| Some(g.sample_visible(v, u)),
                    |m| g.pdf_visible(v, m),
                    200_000,
                    500 + (k * 10 + j) as u64,
                );
                assert_chi2(&format!("GGX visible normals alpha {alpha} at {deg}"), &r);
            }
        }
        let _ = TestRng::new(1);
    }
}
