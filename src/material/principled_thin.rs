//! Mitsuba 3's `principledthin` BSDF (Burley's thin-surface BSDF as Mitsuba's
//! principledthin.cpp and principledhelpers.h write it), formula for formula. A thin
//! surface is symmetric: a direction from the back side is turned to the front (all three
//! components negated, as Mitsuba's `mulsign`), evaluated there and turned back. With
//! spec_trans s, diff_trans d (Mitsuba's value halved, in [0, 1]), eta the film's index:
//!
//! - a GGX reflection lobe s F_thin D G / (4 cos_i), F_thin = lerp(F(eta), S(tint
//!   R0(eta)), spec_tint), S Schlick's approximation, (alpha_x, alpha_y) Mitsuba's
//!   `calc_dist_params` of (anisotropic, roughness);
//! - a transmission lobe s base_color (1 - F) D' G' / (4 cos_i): a reflection about the
//!   microfacet turned to the other side (no bending), of roughness (0.65 eta - 0.35)
//!   roughness (Burley 2015, fig. 15);
//! - Burley's diffuse and retro-reflection (1 - s)(1 - d) base_color / pi (f_diff +
//!   f_retro), blended towards the fake subsurface by flatness, and the sheen, on the
//!   side of the incident direction;
//! - a Lambertian transmission (1 - s) d base_color / pi.
//!
//! Sampling picks a lobe with Mitsuba's probabilities s r_sr / 2, s r_st / 2,
//! r_dr (1 - s)(1 - d) and r_dt (1 - s) d normalized (r_* the four `*_sampling_rate`s):
//! visible GGX normals for the glossy lobes, the cosine for the diffuse ones; `pdf` is
//! their mixture. Anisotropy lies along the surface's tangent as principled's.

use super::dielectric::fresnel_dielectric;
use super::microfacet::{reflect, sample_turned, turned, Distribution, Microfacet};
use super::principled::{calc_schlick, compatible, dist_params, schlick_r0, schlick_weight, tint};
use super::BsdfSample;
use crate::sampling::{pdf_cosine_hemisphere, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// The parameters at a surface point (textures looked up), each as Mitsuba names it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    pub base_color: [f32; 3],
    pub roughness: f32,
    pub anisotropic: f32,
    pub spec_trans: f32,
    pub specular_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    /// Mitsuba's `diff_trans`, in [0, 2] (halved in the formulas).
    pub diff_trans: f32,
    /// The film's index of refraction.
    pub eta: f32,
    /// Mitsuba's `specular_reflectance_sampling_rate`,
    /// `specular_transmittance_sampling_rate`, `diffuse_reflectance_sampling_rate`,
    /// `diffuse_transmittance_sampling_rate`.
    pub rates: [f32; 4],
    /// (cos, sin) of the tangent's angle to the local frame's x axis (alpha_x along it).
    pub tangent: [f32; 2],
}

impl Default for PrincipledThin {
    /// Mitsuba's defaults.
    fn default() -> Self {
        PrincipledThin {
            base_color: [0.5; 3],
            roughness: 0.5,
            anisotropic: 0.0,
            spec_trans: 0.0,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            diff_trans: 0.0,
            eta: 1.5,
            rates: [1.0; 4],
            tangent: [1.0, 0.0],
        }
    }
}

/// Mitsuba's `lerp(a, b, t)`.
#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// `v` turned to the side of positive `sign` (Mitsuba's `mulsign`).
#[inline]
fn mulsign(v: Vec3, sign: f32) -> Vec3 {
    if sign < 0.0 {
        -v
    } else {
        v
    }
}

impl PrincipledThin {
    /// The reflection lobe's and the transmission lobe's distributions.
    #[inline]
    fn dists(&self) -> (Microfacet, Microfacet) {
        let (ax, ay) = dist_params(self.anisotropic, self.roughness);
        let scaled = (0.65 * self.eta - 0.35) * self.roughness;
        let (tx, ty) = dist_params(self.anisotropic, scaled);
        (
            Microfacet::anisotropic(Distribution::Ggx, ax, ay),
            Microfacet::anisotropic(Distribution::Ggx, tx, ty),
        )
    }

    /// The main lobes' roughness differs along the tangent and the bitangent.
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        let (ax, ay) = dist_params(self.anisotropic, self.roughness);
        ax != ay
    }

    #[inline]
    fn frame(&self) -> Option<[f32; 2]> {
        self.is_anisotropic().then_some(self.tangent)
    }

    /// diff_trans in [0, 1].
    #[inline]
    fn dt(&self) -> f32 {
        self.diff_trans / 2.0
    }

    /// A lobe is not empty on the other side of the surface.
    #[inline]
    pub fn transmits(&self) -> bool {
        self.spec_trans > 0.0 || (self.spec_trans < 1.0 && self.dt() > 0.0)
    }

    /// Lobe probabilities: specular reflection, specular transmission, diffuse
    /// reflection, diffuse transmission.
    #[inline]
    fn probs(&self) -> [f32; 4] {
        let (s, d) = (self.spec_trans, self.dt());
        let [rsr, rst, rdr, rdt] = self.rates;
        let p = [
            s * rsr / 2.0,
            s * rst / 2.0,
            rdr * (1.0 - s) * (1.0 - d),
            rdt * (1.0 - s) * d,
        ];
        let r = 1.0 / (p[0] + p[1] + p[2] + p[3]);
        p.map(|x| x * r)
    }

    /// f(wo, wi) (kalos' directions: wo towards the viewer), without the cosine.
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let v = turned(self.frame(), wo, wi, |wo, wi| self.eval_cos(wo, wi));
        Spectrum::from_rgb(v) * (1.0 / wi.z.abs().max(1e-30))
    }

    /// Density of `sample` (kalos' directions).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        turned(self.frame(), wo, wi, |wo, wi| self.pdf_m(wo, wi))
    }

    /// Sample a direction as Mitsuba does (kalos' directions).
    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        sample_turned(self.frame(), wo, |wo| self.sample_m(wo, u_lobe, u))
    }

    /// Mitsuba's eval: f |cos theta_o|, in Mitsuba's naming (wi = kalos' wo), directions
    /// in the tangent's frame.
    pub fn eval_cos(&self, wi: Vec3, wo: Vec3) -> [f32; 3] {
        let cos_i = wi.z;
        if cos_i == 0.0 || !wo.is_finite() {
            return [0.0; 3];
        }
        let (s, d, base) = (self.spec_trans, self.dt(), self.base_color);
        let wi = mulsign(wi, cos_i);
        let wo_t = mulsign(wo, cos_i);
        let cos_i = cos_i.abs();
        let cos_o = wo_t.z;
        let (reflect, refract) = (cos_o > 0.0, cos_o < 0.0);
        let wo_r = Vec3::new(wo_t.x, wo_t.y, wo_t.z.abs());
        let wh = (wi + wo_r).normalize();
        let mut v = [0.0f32; 3];
        let add = |v: &mut [f32; 3], c: [f32; 3], k: f32| {
            for i in 0..3 {
                v[i] += c[i] * k;
            }
        };
        if s > 0.0 {
            let f = fresnel_dielectric(wi.dot(wh), self.eta).0;
            let (refl, trans) = self.dists();
            if reflect && compatible(wh, wi, wo_t, wi.z, true) {
                let st = self.specular_tint;
                let r0 = schlick_r0(self.eta);
                let t = tint(base);
                let f_thin = t.map(|t| lerp(f, calc_schlick(t * r0, wi.dot(wh), self.eta), st));
                let dg = refl.d(wh) * refl.g(wi, wo_t, wh);
                add(&mut v, f_thin, s * dg / (4.0 * cos_i));
            }
            if refract && compatible(wh, wi, wo_t, wi.z, false) {
                let dg = trans.d(wh) * trans.g(wi, wo_t, wh);
                add(&mut v, base, s * (1.0 - f) * dg / (4.0 * cos_i));
            }
        }
        if reflect && s < 1.0 && d < 1.0 {
            let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i));
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let cos_d = wh.dot(wo_t);
            let rr = 2.0 * self.roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let mut lobe = f_diff + f_retro;
            if self.flatness != 0.0 {
                let fss90 = rr / 2.0;
                let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
                let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i) - 0.5) + 0.5);
                lobe = lerp(lobe, f_ss, self.flatness);
            }
            add(
                &mut v,
                base,
                (1.0 - s) * cos_o * FRAC_1_PI * (1.0 - d) * lobe,
            );
            if self.sheen > 0.0 {
                let fd = schlick_weight(cos_d.abs());
                let c = tint(base).map(|t| lerp(1.0, t, self.sheen_tint));
                add(
                    &mut v,
                    c,
                    self.sheen * (1.0 - s) * fd * (1.0 - d) * cos_o.abs(),
                );
            }
        }
        if refract && s < 1.0 && d > 0.0 {
            add(&mut v, base, (1.0 - s) * d * FRAC_1_PI * cos_o.abs());
        }
        v
    }

    /// Mitsuba's pdf in its naming (directions in the tangent's frame).
    fn pdf_m(&self, wi: Vec3, wo: Vec3) -> f32 {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return 0.0;
        }
        let wi = mulsign(wi, cos_i);
        let wo_t = mulsign(wo, cos_i);
        let (reflect, refract) = (wo_t.z > 0.0, wo_t.z < 0.0);
        let [psr, pst, pdr, pdt] = self.probs();
        let mut pdf = 0.0;
        if self.spec_trans > 0.0 {
            let wo_r = Vec3::new(wo_t.x, wo_t.y, wo_t.z.abs());
            let wh = (wi + wo_r).normalize();
            let dwh_dwo = (1.0 / (4.0 * wo_r.dot(wh))).abs();
            let (refl, trans) = self.dists();
            if reflect && compatible(wh, wi, wo_t, wi.z, true) {
                pdf += psr * refl.pdf_visible(wi, wh) * dwh_dwo;
            }
            if refract && compatible(wh, wi, wo_t, wi.z, false) {
                pdf += pst * trans.pdf_visible(wi, wh) * dwh_dwo;
            }
        }
        if reflect {
            pdf += pdr * pdf_cosine_hemisphere(wo_t);
        }
        if refract {
            pdf += pdt * pdf_cosine_hemisphere(-wo_t);
        }
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Mitsuba's sample (directions in the tangent's frame).
    fn sample_m<const N: usize>(&self, wi_s: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let cos_i = wi_s.z;
        if cos_i == 0.0 {
            return None;
        }
        let wi = mulsign(wi_s, cos_i);
        let [psr, pst, pdr, _] = self.probs();
        let wo = if u_lobe < psr {
            let m = self.dists().0.sample_visible(wi, u);
            let wo = reflect(wi, m);
            if !(compatible(m, wi, wo, wi.z, true) && wo.z > 0.0) {
                return None;
            }
            wo
        } else if u_lobe < psr + pst {
            let m = self.dists().1.sample_visible(wi, u);
            let r = reflect(wi, m);
            let wo = Vec3::new(r.x, r.y, -r.z);
            if !(compatible(m, wi, wo, wi.z, false) && wo.z < 0.0) {
                return None;
            }
            wo
        } else if u_lobe < psr + pst + pdr {
            square_to_cosine_hemisphere(u)
        } else {
            -square_to_cosine_hemisphere(u)
        };
        let wo = mulsign(wo, cos_i);
        let pdf = self.pdf_m(wi_s, wo);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let v = self.eval_cos(wi_s, wo);
        Some(BsdfSample {
            wi: wo,
            weight: Spectrum::from_rgb(v) * (1.0 / pdf),
            pdf,
            delta: false,
        })
    }

    /// A rough bound of the albedo for roulette: the lobes' weights summed, capped at 1.
    pub fn albedo_rgb(&self) -> [f32; 3] {
        let s = self.spec_trans;
        self.base_color
            .map(|c| (s * c.max(1.0) + (1.0 - s) * (c + self.sheen)).min(1.0))
    }
}

#[cfg(test)]
#[path = "principled_thin_tests.rs"]
mod tests;
