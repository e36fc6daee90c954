//! Energy-conserving normalized Phong lobe (Lewis 1994, Lafortune and Willems 1994):
//! f = ks (n + 2) / (2 pi) cos^n(alpha), alpha the angle between wi and the mirror
//! direction of wo. Its albedo is ks at normal incidence and less elsewhere. Sampled with
//! the cos^n lobe around the mirror direction, density (n + 1)/(2 pi) cos^n(alpha);
//! directions below the surface are rejected (their probability is lost, not renormalised).

use crate::math::Frame;
use crate::sampling::{pdf_cos_power, square_to_cos_power};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    pub ks: [f32; 3],
    /// Shininess (Ns).
    pub n: f32,
}

#[inline]
fn mirror(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

impl Phong {
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Spectrum::ZERO;
        }
        let cos_a = mirror(wo).dot(wi);
        if cos_a <= 0.0 {
            return Spectrum::ZERO;
        }
        Spectrum::from_rgb(self.ks) * ((self.n + 2.0) / (2.0 * PI) * cos_a.powf(self.n))
    }
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        pdf_cos_power(mirror(wo).dot(wi), self.n)
    }
    #[inline]
    pub fn sample_dir(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if wo.z <= 0.0 {
            return None;
        }
        let r = mirror(wo);
        let local = square_to_cos_power(u, self.n);
        let wi = Frame::from_normal(r).to_world(local);
        (wi.z > 0.0).then_some(wi)
    }
}
