//! Thin dielectric slab (Mitsuba 3's `thindielectric`): two parallel smooth interfaces of
//! relative index eta, so close that a ray leaves where it entered, undeflected. With
//! R = F(|cos theta_o|, eta) the reflectance of one interface and T = 1 - R, the light
//! bouncing between them sums to
//!   R_slab = R + T^2 R / (1 - R^2),   T_slab = 1 - R_slab,
//! reflected about the normal or passed straight through (wi = -wo). Both lobes are Dirac;
//! it is sampled with these probabilities and weight 1. No radiance scaling: the ray ends
//! in the medium it started in.

use super::dielectric::{fresnel_dielectric, Tint};
use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    pub eta: f32,
    pub tint: Tint,
}

impl ThinDielectric {
    /// R_slab at incidence cosine `cos`.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> f32 {
        let r = fresnel_dielectric(cos.abs(), self.eta).0;
        if r < 1.0 {
            r + (1.0 - r) * (1.0 - r) * r / (1.0 - r * r)
        } else {
            1.0
        }
    }

    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3, u: f32) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        let (wi, pdf, tint) = if u < r {
            (Vec3::new(-wo.x, -wo.y, wo.z), r, self.tint.reflect)
        } else {
            (-wo, 1.0 - r, self.tint.transmit)
        };
        Some(BsdfSample {
            wi,
            weight: Spectrum::from_rgb(tint),
            pdf,
            delta: true,
        })
    }
}
