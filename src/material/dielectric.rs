//! Smooth dielectric (MTL illum 7, index Ni): Fresnel reflection or refraction, chosen
//! with probability F. Radiance is scaled by (eta_o / eta_i)^2 across the interface.
//! wo.z > 0 means wo is outside (on the side the normal points to).

use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction inside relative to outside.
    pub eta: f32,
    pub tint: Tint,
}

/// Factors on a dielectric's reflected and transmitted light (Mitsuba's
/// `specular_reflectance` and `specular_transmittance`; 1 is physical). They scale the
/// lobes' values, not how the lobes are sampled, as in Mitsuba.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tint {
    pub reflect: [f32; 3],
    pub transmit: [f32; 3],
}

impl Tint {
    pub const NONE: Tint = Tint {
        reflect: [1.0; 3],
        transmit: [1.0; 3],
    };
}

/// Unpolarised Fresnel reflectance; `cos_i` > 0 on the side of the normal, `eta` = inside/outside.
/// Returns (F, cos_t, eta_ratio) where eta_ratio = eta_i / eta_t for this crossing.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32, f32) {
    let (cos_i, eta_r) = if cos_i >= 0.0 {
        (cos_i, 1.0 / eta)
    } else {
        (-cos_i, eta)
    };
    // eta_r = eta_incident / eta_transmitted
    let sin2_t = eta_r * eta_r * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0, eta_r);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta_r * cos_i - cos_t) / (eta_r * cos_i + cos_t);
    let rp = (cos_i - eta_r * cos_t) / (cos_i + eta_r * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t, eta_r)
}

impl Dielectric {
    /// Probability of reflection for wo (the rest refracts).
    #[inline]
    pub fn reflectance(&self, wo: Vec3) -> f32 {
        fresnel_dielectric(wo.z, self.eta).0
    }

    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3, u: f32) -> Option<BsdfSample<N>> {
        let (f, cos_t, eta_r) = fresnel_dielectric(wo.z, self.eta);
        if u < f {
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Spectrum::from_rgb(self.tint.reflect),
                pdf: f,
                delta: true,
            });
        }
        // Refraction: wi = -eta_r wo + (eta_r cos_i - cos_t) n, on the other side.
        let sign = if wo.z >= 0.0 { 1.0 } else { -1.0 };
        let wi = Vec3::new(-eta_r * wo.x, -eta_r * wo.y, -sign * cos_t);
        // Radiance scaling: L_o = L_i (eta_o/eta_i)^2, with eta_o/eta_i = eta_r.
        Some(BsdfSample {
            wi: wi.normalize(),
            weight: Spectrum::from_rgb(self.tint.transmit) * (eta_r * eta_r),
            pdf: 1.0 - f,
            delta: true,
        })
    }
}
