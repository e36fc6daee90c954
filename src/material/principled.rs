//! Mitsuba 3's `principled` BSDF (Burley's Disney BSDF as Mitsuba's principled.cpp and
//! principledhelpers.h write it), formula for formula:
//!
//! - a main GGX lobe of alpha = max(0.001, roughness^2) reflecting with the blended
//!   Fresnel term F_p = (1 - metallic)(1 - spec_tint) F(eta) + metallic S(base_color) +
//!   (1 - metallic) spec_tint S(tint R0(eta)), S Schlick's approximation, F the
//!   dielectric's; on the back side bsdf F(eta), bsdf = (1 - metallic) spec_trans;
//! - a GGX transmission lobe of weight sqrt(base_color) bsdf (1 - F) (radiance scaled by
//!   1 / eta_path^2);
//! - a clearcoat of weight clearcoat / 4: Schlick's F with R0 0.04, the GTR1 distribution
//!   of alpha lerp(0.1, 0.001, clearcoat_gloss), Smith's GGX G of alpha 0.25, and (as
//!   Mitsuba has it) no 1 / (4 cos_i cos_o);
//! - Burley's diffuse with retro-reflection, (1 - metallic)(1 - spec_trans) base_color / pi
//!   (f_diff + f_retro), blended towards Hanrahan-Krueger's fake subsurface by flatness;
//! - a sheen sheen (1 - metallic) Schlick(cos_d) lerp(1, tint, sheen_tint).
//!
//! Sampling picks the diffuse (cosine), clearcoat (GTR1 normals), transmission or
//! reflection (GGX visible normals) with Mitsuba's probabilities: on the front side
//! brdf r_d, clearcoat r_c / 4, bsdf (1 - F) r_s and (1 - bsdf (1 - F)) r_s normalized
//! (r_* its `*_sampling_rate`s), on the back F and 1 - F; `pdf` is their mixture.
//!
//! The main lobe (reflection and transmission) is anisotropic as Mitsuba's: GGX of
//! (alpha_x, alpha_y) = (max(0.001, r^2 / a), max(0.001, r^2 a)), a = sqrt(1 - 0.9
//! anisotropic), alpha_x along the surface's tangent (dp/du made orthogonal to the shading
//! normal, as Mitsuba's shading frame; `tangent`, set per hit by the scene): directions
//! are turned about the normal into the tangent's frame, where Mitsuba's formulas apply.

use super::dielectric::fresnel_dielectric;
use super::microfacet::{reflect, sample_turned, turned, Distribution, Microfacet};
use super::BsdfSample;
use crate::sampling::{pdf_cosine_hemisphere, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// The parameters at a surface point (textures looked up), each as Mitsuba names it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    pub base_color: [f32; 3],
    pub roughness: f32,
    pub anisotropic: f32,
    pub metallic: f32,
    pub specular_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    pub spec_trans: f32,
    /// Relative index (from `eta`, or `specular` by 2 / (1 - sqrt(0.08 specular)) - 1).
    pub eta: f32,
    /// Mitsuba's `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`.
    pub rates: [f32; 3],
    /// (cos, sin) of the tangent's angle to the local frame's x axis: the main lobe's
    /// alpha_x lies along it (used only where the lobe is anisotropic).
    pub tangent: [f32; 2],
}

impl Default for Principled {
    /// Mitsuba's defaults.
    fn default() -> Self {
        Principled {
            base_color: [0.5; 3],
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            spec_trans: 0.0,
            eta: eta_of_specular(0.5),
            rates: [1.0; 3],
            tangent: [1.0, 0.0],
        }
    }
}

/// Mitsuba's index from `specular`: 2 / (1 - sqrt(0.08 specular)) - 1.
pub fn eta_of_specular(specular: f32) -> f32 {
    2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
}

/// Schlick's weight (1 - cos)^5, the cosine clamped to [0, 1].
#[inline]
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// Mitsuba's `calc_schlick`: R0 + (1 - R0) w, w at the incident cosine from the denser
/// side's view (the transmitted cosine when light enters the rarer medium).
#[inline]
pub fn calc_schlick(r0: f32, cos_i: f32, eta: f32) -> f32 {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti)
        .max(0.0)
        .sqrt();
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        schlick_weight(cos_t)
    };
    w * (1.0 - r0) + r0
}

/// Mitsuba's `fresnel` (F, cos_t, eta_ti): the dielectric's, exactly 0 where the index is
/// matched (eta 1, as `specular` 0 gives without `spec_trans`), where the formula leaves a
/// rounding residue that would switch on the main lobe (its metallic part included).
#[inline]
fn fresnel_m(cos_i: f32, eta: f32) -> (f32, f32, f32) {
    let r = fresnel_dielectric(cos_i, eta);
    if eta == 1.0 {
        (0.0, r.1, r.2)
    } else {
        r
    }
}

/// ((eta - 1) / (eta + 1))^2.
#[inline]
pub fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Mitsuba's `mac_mic_compatibility`: both directions on the sides of the micronormal m
/// (turned to the side of wi) that a reflection (or a refraction) needs.
#[inline]
pub fn compatible(m: Vec3, wi: Vec3, wo: Vec3, cos_i: f32, reflection: bool) -> bool {
    let m = if cos_i < 0.0 { -m } else { m };
    wi.dot(m) > 0.0
        && if reflection {
            wo.dot(m) > 0.0
        } else {
            wo.dot(-m) > 0.0
        }
}

/// The GTR1 distribution of the clearcoat (isotropic, alpha).
#[derive(Clone, Copy, Debug)]
pub struct Gtr1 {
    pub alpha: f32,
}

impl Gtr1 {
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c2));
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }
    #[inline]
    pub fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.d(m)
        }
    }
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (s, c) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin_t = (1.0 - cos2).max(0.0).sqrt();
        Vec3::new(c * sin_t, s * sin_t, cos2.max(0.0).sqrt())
    }
}

/// Smith's GGX G1 of the clearcoat (Mitsuba's `smith_ggx1`).
#[inline]
pub fn smith_ggx1(v: Vec3, wh: Vec3, alpha: f32) -> f32 {
    if v.dot(wh) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Rec. 709 luminance.
#[inline]
fn luminance(c: [f32; 3]) -> f32 {
    crate::texture::mesh_attribute::luminance(c)
}

/// base_color / its luminance (1 where it is black).
#[inline]
pub(super) fn tint(base: [f32; 3]) -> [f32; 3] {
    let l = luminance(base);
    if l > 0.0 {
        base.map(|c| c / l)
    } else {
        [1.0; 3]
    }
}

/// Mitsuba's `calc_dist_params`: GGX's (alpha_x, alpha_y) of a roughness and an
/// anisotropy.
#[inline]
pub fn dist_params(anisotropic: f32, roughness: f32) -> (f32, f32) {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

/// Lobe probabilities: (specular reflection, transmission, clearcoat, diffuse).
type Probs = [f32; 4];

impl Principled {
    /// Mitsuba's `calc_dist_params`, the main lobe's (alpha_x, alpha_y).
    #[inline]
    pub fn alphas(&self) -> (f32, f32) {
        dist_params(self.anisotropic, self.roughness)
    }

    /// The main lobe's GGX distribution, alpha_x along the tangent.
    #[inline]
    fn mf(&self) -> Microfacet {
        let (ax, ay) = self.alphas();
        Microfacet::anisotropic(Distribution::Ggx, ax, ay)
    }

    /// The main lobe's roughness differs along the tangent and the bitangent (its frame
    /// is then the tangent's: `tangent`).
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        let (ax, ay) = self.alphas();
        ax != ay
    }

    /// The tangent where the main lobe is anisotropic (else directions stay local).
    #[inline]
    fn frame(&self) -> Option<[f32; 2]> {
        self.is_anisotropic().then_some(self.tangent)
    }

    #[inline]
    fn weights(&self) -> (f32, f32) {
        let m = 1.0 - self.metallic;
        (m * (1.0 - self.spec_trans), m * self.spec_trans)
    }

    /// The transmission lobe is not empty.
    #[inline]
    pub fn transmits(&self) -> bool {
        self.weights().1 > 0.0
    }

    #[inline]
    fn probs(&self, front: bool, f: f32) -> Probs {
        let (brdf, bsdf) = self.weights();
        let [rs, rc, rd] = self.rates;
        let p = if front {
            [
                rs * (1.0 - bsdf * (1.0 - f)),
                rs * bsdf * (1.0 - f),
                0.25 * self.clearcoat * rc,
                brdf * rd,
            ]
        } else {
            [f, if bsdf > 0.0 { 1.0 - f } else { 0.0 }, 0.0, 0.0]
        };
        let s = p[0] + p[1] + p[2] + p[3];
        if s > 0.0 {
            p.map(|x| x / s)
        } else {
            [0.0; 4]
        }
    }

    /// The half vector of (wi, wo) in Mitsuba's sense (wi towards the viewer), turned up.
    #[inline]
    fn half(&self, wi: Vec3, wo: Vec3) -> (Vec3, bool, f32) {
        let reflect = wi.z * wo.z > 0.0;
        let eta_path = if wi.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let wh = (wi + wo * if reflect { 1.0 } else { eta_path }).normalize();
        let wh = if wh.z < 0.0 { -wh } else { wh };
        (wh, reflect, eta_path)
    }

    /// f(wo, wi) (kalos' directions: wo towards the viewer), without the cosine.
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let v = turned(self.frame(), wo, wi, |wo, wi| self.eval_cos(wo, wi));
        Spectrum::from_rgb(v) * (1.0 / wi.z.abs().max(1e-30))
    }

    /// Mitsuba's eval: f |cos theta_o|, in Mitsuba's naming (wi = kalos' wo), directions
    /// in the tangent's frame (Mitsuba's shading frame).
    pub fn eval_cos(&self, wi: Vec3, wo: Vec3) -> [f32; 3] {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i == 0.0 || cos_o == 0.0 || !wo.is_finite() {
            return [0.0; 3];
        }
        let base = self.base_color;
        let (brdf, bsdf) = self.weights();
        let front = cos_i > 0.0;
        let (wh, reflect, eta_path) = self.half(wi, wo);
        let (f, _, _) = fresnel_m(wi.dot(wh), self.eta);
        let mf = self.mf();
        let d = mf.d(wh);
        let g = mf.g(wi, wo, wh);
        let mut v = [0.0f32; 3];
        let add = |v: &mut [f32; 3], c: [f32; 3], k: f32| {
            for i in 0..3 {
                v[i] += c[i] * k;
            }
        };
        let refl_ok = compatible(wh, wi, wo, cos_i, true);
        if reflect && refl_ok && f > 0.0 {
            let fp = self.fresnel(f, base, wi.dot(wh), front, bsdf);
            add(&mut v, fp, d * g / (4.0 * cos_i.abs()));
        }
        if bsdf > 0.0 && !reflect && compatible(wh, wi, wo, cos_i, false) && f < 1.0 {
            let scale = 1.0 / (eta_path * eta_path);
            let (dih, doh) = (wi.dot(wh), wo.dot(wh));
            let den = dih + eta_path * doh;
            let k = (scale * (1.0 - f) * d * g * eta_path * eta_path * dih * doh
                / (cos_i * den * den))
                .abs();
            add(&mut v, base.map(|c| c.max(0.0).sqrt()), bsdf * k);
        }
        if self.clearcoat > 0.0 && reflect && refl_ok && front {
            let fcc = calc_schlick(0.04, wi.dot(wh), self.eta);
            let dcc = self.clearcoat_dist().d(wh);
            let gcc = smith_ggx1(wi, wh, 0.25) * smith_ggx1(wo, wh, 0.25);
            let k = self.clearcoat * 0.25 * fcc * dcc * gcc * cos_o.abs();
            add(&mut v, [1.0; 3], k);
        }
        if reflect && front {
            let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i.abs()));
            let cos_d = wh.dot(wo);
            if brdf > 0.0 {
                let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
                let rr = 2.0 * self.roughness * cos_d * cos_d;
                let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
                let mut lobe = f_diff + f_retro;
                if self.flatness != 0.0 {
                    let fss90 = rr / 2.0;
                    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
                    let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
                    let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i.abs()) - 0.5) + 0.5);
                    lobe = lerp(lobe, f_ss, self.flatness);
                }
                add(&mut v, base, brdf * cos_o.abs() * FRAC_1_PI * lobe);
            }
            if self.sheen > 0.0 && self.metallic < 1.0 {
                let fd = schlick_weight(cos_d.abs());
                let t = tint(base);
                let c = t.map(|t| 1.0 + (t - 1.0) * self.sheen_tint);
                add(
                    &mut v,
                    c,
                    self.sheen * (1.0 - self.metallic) * fd * cos_o.abs(),
                );
            }
        }
        v
    }

    /// Mitsuba's `principled_fresnel`.
    #[inline]
    fn fresnel(&self, f: f32, base: [f32; 3], cos_h: f32, front: bool, bsdf: f32) -> [f32; 3] {
        if !front {
            return [bsdf * f; 3];
        }
        let eta_it = if cos_h >= 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let (m, st) = (self.metallic, self.specular_tint);
        let t = tint(base);
        let r0 = schlick_r0(eta_it);
        [0, 1, 2].map(|i| {
            let metal = m * calc_schlick(base[i], cos_h, self.eta);
            let tinted = (1.0 - m) * st * calc_schlick(t[i] * r0, cos_h, self.eta);
            (1.0 - m) * (1.0 - st) * f + metal + tinted
        })
    }

    #[inline]
    fn clearcoat_dist(&self) -> Gtr1 {
        Gtr1 {
            alpha: 0.1 + (0.001 - 0.1) * self.clearcoat_gloss,
        }
    }

    /// Density of `sample` (kalos' directions).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        turned(self.frame(), wo, wi, |wo, wi| self.pdf_m(wo, wi))
    }

    /// Mitsuba's pdf in its naming (directions in the tangent's frame).
    fn pdf_m(&self, wi: Vec3, wo: Vec3) -> f32 {
        let cos_i = wi.z;
        if cos_i == 0.0 || wo.z == 0.0 {
            return 0.0;
        }
        let front = cos_i > 0.0;
        let (wh, reflect, eta_path) = self.half(wi, wo);
        let f = fresnel_m(wi.dot(wh), self.eta).0;
        let [ps, pt, pc, pd] = self.probs(front, f);
        let (dih, doh) = (wi.dot(wh), wo.dot(wh));
        let dwh_dwo = if reflect {
            (1.0 / (4.0 * doh)).abs()
        } else {
            (eta_path * eta_path * doh / ((dih + eta_path * doh) * (dih + eta_path * doh))).abs()
        };
        let wi_up = if cos_i < 0.0 { -wi } else { wi };
        let mut pdf = 0.0;
        let refl_ok = reflect && compatible(wh, wi, wo, cos_i, true);
        if refl_ok && (ps > 0.0 || pc > 0.0) {
            pdf += ps * self.mf().pdf_visible(wi_up, wh) * dwh_dwo;
            if pc > 0.0 {
                pdf += pc * self.clearcoat_dist().pdf(wh) * dwh_dwo;
            }
        }
        if reflect && pd > 0.0 {
            pdf += pd * pdf_cosine_hemisphere(wo);
        }
        if pt > 0.0 && !reflect && compatible(wh, wi, wo, cos_i, false) {
            pdf += pt * self.mf().pdf_visible(wi_up, wh) * dwh_dwo;
        }
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Sample a direction as Mitsuba does (kalos' directions).
    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        sample_turned(self.frame(), wo, |wo| self.sample_m(wo, u_lobe, u))
    }

    /// Mitsuba's sample (directions in the tangent's frame).
    fn sample_m<const N: usize>(&self, wi: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return None;
        }
        let front = cos_i > 0.0;
        let (_, bsdf) = self.weights();
        if !front && bsdf <= 0.0 {
            return None;
        }
        let wi_up = if front { wi } else { -wi };
        let m = self.mf().sample_visible(wi_up, u);
        let (f, cos_t, eta_ti) = fresnel_m(wi.dot(m), self.eta);
        let [_, pt, pc, pd] = self.probs(front, f);
        let wo = if u_lobe < pd {
            let wo = square_to_cosine_hemisphere(u);
            if cos_i * wo.z <= 0.0 {
                return None;
            }
            wo
        } else if u_lobe < pd + pc {
            let mc = self.clearcoat_dist().sample(u);
            let wo = reflect(wi, mc);
            if !(compatible(mc, wi, wo, cos_i, true) && cos_i * wo.z > 0.0) {
                return None;
            }
            wo
        } else if u_lobe < pd + pc + pt {
            // Mitsuba's refract: m (wi.m eta_ti + cos_t) - wi eta_ti, cos_t signed
            // against wi's side
            if f >= 1.0 {
                return None;
            }
            let cos_t = if wi.dot(m) >= 0.0 { -cos_t } else { cos_t };
            let wo = m * (wi.dot(m) * eta_ti + cos_t) - wi * eta_ti;
            if !(compatible(m, wi, wo, cos_i, false) && cos_i * wo.z < 0.0) {
                return None;
            }
            wo
        } else {
            let wo = reflect(wi, m);
            if !(compatible(m, wi, wo, cos_i, true) && cos_i * wo.z > 0.0) {
                return None;
            }
            wo
        };
        let pdf = self.pdf_m(wi, wo);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let v = self.eval_cos(wi, wo);
        Some(BsdfSample {
            wi: wo,
            weight: Spectrum::from_rgb(v) * (1.0 / pdf),
            pdf,
            delta: false,
        })
    }

    /// A rough bound of the albedo for roulette: the lobes' weights summed, capped at 1.
    pub fn albedo_rgb(&self) -> [f32; 3] {
        let (brdf, bsdf) = self.weights();
        let rest = self.metallic + 0.08 + 0.25 * self.clearcoat + self.sheen;
        self.base_color
            .map(|c| (brdf * c + bsdf * c.max(0.0).sqrt() + rest).min(1.0))
    }
}

#[cfg(test)]
#[path = "principled_tests.rs"]
pub(crate) mod tests;
