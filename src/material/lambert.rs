//! Lambertian reflection: f = kd / pi, sampled with the cosine-weighted hemisphere.

use super::BsdfSample;
use crate::sampling::{pdf_cosine_hemisphere, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub kd: [f32; 3],
}

impl Lambert {
    #[inline(always)]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Spectrum::ZERO;
        }
        Spectrum::from_rgb(self.kd) * FRAC_1_PI
    }
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        pdf_cosine_hemisphere(wi)
    }
    #[inline(always)]
    pub fn sample_dir(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u);
        (wi.z > 0.0).then_some(wi)
    }
    #[inline(always)]
    pub fn sample<const N: usize>(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample<N>> {
        let s = self.sample_any(u);
        Self::takes_sample(wo, &s).then_some(s)
    }
    /// Whether [`Self::sample`] keeps `s` from [`Self::sample_any`]: wo above the
    /// surface, wi strictly above.
    #[inline(always)]
    pub fn takes_sample<const N: usize>(wo: Vec3, s: &BsdfSample<N>) -> bool {
        wo.z > 0.0 && s.wi.z > 0.0
    }
    /// [`Self::sample`] before its checks (wo above the surface, wi strictly above).
    #[inline(always)]
    pub fn sample_any<const N: usize>(&self, u: Vec2) -> BsdfSample<N> {
        let wi = square_to_cosine_hemisphere(u);
        // f cos / pdf = (kd/pi) cos / (cos/pi) = kd
        BsdfSample {
            wi,
            weight: Spectrum::from_rgb(self.kd),
            pdf: pdf_cosine_hemisphere(wi),
            delta: false,
        }
    }
}
