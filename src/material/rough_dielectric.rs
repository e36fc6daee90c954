//! Rough dielectric interface (Walter, Marschner, Li and Torrance, "Microfacet models for
//! refraction through rough surfaces", EGSR 2007; Mitsuba 3's `roughdielectric`), GGX or Beckmann with
//! Smith's separable G, reflection and refraction. Not two-sided: wo.z > 0 is outside
//! (index 1), wo.z < 0 inside (index eta).
//!
//! With eta_o, eta_i the indices on the sides of wo and wi:
//! - reflection (wo, wi on one side): h_r = sign(cos theta_o) (wo + wi) / |wo + wi|,
//!   f_r = F(wo.h_r) D(h_r) G(wo, wi, h_r) / (4 |cos theta_o| |cos theta_i|);
//! - refraction: h_t = -(eta_o wo + eta_i wi) / |..| turned to +z,
//!   f_t = |wi.h_t| |wo.h_t| eta_o^2 (1 - F(wo.h_t)) D(h_t) G(wo, wi, h_t)
//!   / (|cos theta_i| |cos theta_o| (eta_i wi.h_t + eta_o wo.h_t)^2)
//!   (Walter's eq. 21 with the light arriving along wi and leaving along wo: it carries
//!   radiance, scaled by (eta_o / eta_i)^2 across the interface; importance is not, and
//!   the light subpaths of BDPT undo the factor, see `Bsdf::adjoint_scale`).
//!
//! Sampling: a visible normal m ~ D_{wo'} (wo' = wo turned to +z), reflection with
//! probability F(wo.m), else refraction; the densities are
//!   p_r = D_{wo'}(h_r) F / (4 |wo.h_r|),
//!   p_t = D_{wo'}(h_t) (1 - F) eta_i^2 |wi.h_t| / (eta_i wi.h_t + eta_o wo.h_t)^2.

use super::dielectric::{fresnel_dielectric, Tint};
use super::microfacet::{reflect, Distribution, Microfacet};
use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Index inside relative to outside.
    pub eta: f32,
    pub alpha: f32,
    pub dist: Distribution,
    pub tint: Tint,
}

/// Which half vector and what the densities need, for one pair of directions.
struct Config {
    h: Vec3,
    reflect: bool,
    /// eta_i / eta_o (1 for reflection).
    eta_io: f32,
}

impl RoughDielectric {
    #[inline]
    fn mf(&self) -> Microfacet {
        Microfacet::new(self.dist, self.alpha)
    }

    /// eta_i / eta_o for a refraction from the side of wo.
    #[inline]
    fn eta_io(&self, wo: Vec3) -> f32 {
        if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        }
    }

    /// The half vector of (wo, wi), on +z; None where no microfacet joins them.
    #[inline]
    fn config(&self, wo: Vec3, wi: Vec3) -> Option<Config> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflect = wo.z * wi.z > 0.0;
        let eta_io = if reflect { 1.0 } else { self.eta_io(wo) };
        let h = wo + wi * eta_io;
        if h.length_squared() <= 1e-20 {
            return None;
        }
        let mut h = h.normalize();
        if h.z < 0.0 {
            h = -h;
        }
        // both directions must see the front of h on their own side
        if h.dot(wo) * wo.z <= 0.0 || h.dot(wi) * wi.z <= 0.0 {
            return None;
        }
        Some(Config { h, reflect, eta_io })
    }

    /// f(wo, wi), radiance transport.
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let Some(c) = self.config(wo, wi) else {
            return Spectrum::ZERO;
        };
        let g = self.mf();
        let dg = g.d(c.h) * g.g(wo, wi, c.h);
        if dg <= 0.0 {
            return Spectrum::ZERO;
        }
        let f = fresnel_dielectric(wo.dot(c.h), self.eta).0;
        if c.reflect {
            let v = f * dg / (4.0 * (wo.z * wi.z).abs());
            Spectrum::from_rgb(self.tint.reflect) * v
        } else {
            // eta_o = 1 and eta_i = eta_io in units of eta_o
            let den = c.eta_io * wi.dot(c.h) + wo.dot(c.h);
            let v = (wi.dot(c.h) * wo.dot(c.h)).abs() * (1.0 - f) * dg
                / ((wi.z * wo.z).abs() * den * den);
            Spectrum::from_rgb(self.tint.transmit) * v
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(c) = self.config(wo, wi) else {
            return 0.0;
        };
        let g = self.mf();
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        // D_{wo'}(h): the density of h among the normals visible from wo turned to +z
        let dv = g.pdf_visible(wo_up, c.h);
        let f = fresnel_dielectric(wo.dot(c.h), self.eta).0;
        if c.reflect {
            dv * f / (4.0 * wo.dot(c.h).abs())
        } else {
            let den = c.eta_io * wi.dot(c.h) + wo.dot(c.h);
            dv * (1.0 - f) * c.eta_io * c.eta_io * wi.dot(c.h).abs() / (den * den)
        }
    }

    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let g = self.mf();
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        let m = g.sample_visible(wo_up, u);
        let c = wo.dot(m);
        let (f, cos_t, eta_r) = fresnel_dielectric(c, self.eta);
        let wi = if u_lobe < f {
            let wi = reflect(wo, m);
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            wi
        } else {
            // Snell about m: wi = -eta_r wo + (eta_r |c| - cos_t) sign(c) m
            let s = c.signum();
            let wi = (-eta_r * wo + (eta_r * c.abs() - cos_t) * s * m).normalize();
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            wi
        };
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let f = self.eval::<N>(wo, wi);
        Some(BsdfSample {
            wi,
            weight: f * (wi.z.abs() / pdf),
            pdf,
            delta: false,
        })
    }
}
