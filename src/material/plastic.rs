//! Plastic as Mitsuba 3 defines it (`plastic`, `roughplastic`): a diffuse base of
//! reflectance kd under a dielectric coat of relative index eta, reflection only.
//!
//! The coat reflects specular R(wo, wi): for the smooth coat a Dirac mirror lobe of weight
//! specular F(cos theta_o), for the rough coat the microfacet BRDF (GGX or Beckmann's D and G1)
//!   f_c(wo, wi) = specular F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos theta_o cos theta_i).
//! Light crosses the coat into the base with probability t(cos theta_i), is reflected
//! diffusely, and leaves with t(cos theta_o); in between it bounces under the coat, which
//! reflects back the fraction r_int of a diffuse (cosine-weighted) flux. Summing that
//! geometric series gives the base lobe
//!   f_b(wo, wi) = kd' t(cos theta_i) t(cos theta_o) / (pi eta^2),
//!   kd' = kd / (1 - r_int)         (Mitsuba's default, `nonlinear` = false),
//!   kd' = kd / (1 - kd r_int)      (`nonlinear` = true: the series in kd itself),
//! where 1/eta^2 is the radiance scaling of leaving the coat.
//! - smooth: t(mu) = 1 - F(mu, eta) and r_int = Fdr(1/eta), the diffuse Fresnel
//!   reflectance by the fits Mitsuba uses (Egan and Hilgeman 1973 below eta 1, d'Eon and
//!   Irving 2011 above);
//! - rough: t(mu) = the rough coat's single-scattering transmittance
//!   E_{m ~ D_wo}[(1 - F(wo.m)) G1(wt, m)] (wt the refracted direction) and r_int the
//!   cosine-weighted average of the internal rough reflectance (index 1/eta), both
//!   tabulated at build time over 64 cosines as Mitsuba does.
//!
//! Sampling (Mitsuba's): the coat with probability
//!   P_c = (1 - t_o) w / ((1 - t_o) w + t_o (1 - w)),  w = mean(specular) / (mean(kd) + mean(specular)),
//! else the base (cosine-weighted).

use super::dielectric::fresnel_dielectric;
use super::microfacet::{reflect, Distribution, Microfacet};
use super::BsdfSample;
use crate::sampling::{pdf_cosine_hemisphere, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::FRAC_1_PI;
use std::sync::{Mutex, OnceLock};

/// Cosines at which the rough coat is tabulated (Mitsuba's MI_ROUGH_TRANSMITTANCE_RES).
pub const COAT_RES: usize = 64;

/// What the coat does, for one (eta, alpha, distribution): shared by every material that uses it.
#[derive(Debug, PartialEq)]
pub struct CoatTable {
    pub eta: f32,
    pub alpha: f32,
    pub dist: Distribution,
    /// t(mu) on mu = i / (COAT_RES - 1) (rough coat; unused for the smooth one).
    pub t: [f32; COAT_RES],
    /// r_int: diffuse internal reflectance.
    pub r_int: f32,
    /// 2 int t(mu) mu dmu: the share of diffuse light that crosses the coat.
    pub t_hem: f32,
    /// 2 int R(mu) mu dmu: the coat's cosine-weighted reflectance (without `specular`).
    pub r_hem: f32,
}

/// Diffuse Fresnel reflectance Fdr(eta), 2 int F(mu, eta) mu dmu, by the fits Mitsuba's
/// `fresnel_diffuse_reflectance` uses.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        // Egan and Hilgeman (1973)
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // d'Eon and Irving (2011)
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881f32];
        c.iter().rev().fold(0.0, |acc, &ci| acc * inv + ci)
    }
}

/// Rough coat reflectance R(mu) and transmittance t(mu) for incidence cosine mu (the
/// relative index eta): the expectations over visible normals m ~ D_wo of F(wo.m) G1(wr, m)
/// and (1 - F(wo.m)) G1(wt, m), on a midpoint grid of `n` x `n` cells of the sample square.
pub fn rough_coat_rt(mf: &Microfacet, eta: f32, mu: f32, n: usize) -> (f64, f64) {
    let mu = mu.max(1e-6);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let (mut r, mut t) = (0.0f64, 0.0f64);
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let m = mf.sample_visible(wo, u);
            let c = wo.dot(m);
            let (f, cos_t, eta_r) = fresnel_dielectric(c, eta);
            let wr = reflect(wo, m);
            if wr.z > 0.0 {
                r += (f * mf.g1(wr, m)) as f64;
            }
            if f < 1.0 {
                // refracted: -eta_r wo + (eta_r c - cos_t) m (c > 0 here)
                let wt = (-eta_r * wo + (eta_r * c - cos_t) * m).normalize();
                if wt.z < 0.0 {
                    t += ((1.0 - f) * mf.g1(wt, m)) as f64;
                }
            }
        }
    }
    let k = 1.0 / (n * n) as f64;
    (r * k, t * k)
}

impl CoatTable {
    fn compute(eta: f32, alpha: f32, dist: Distribution) -> CoatTable {
        let mut t = [0.0f32; COAT_RES];
        let h = 1.0 / (COAT_RES - 1) as f64;
        let (mut t_hem, mut r_hem, mut r_int) = (0.0f64, 0.0f64, 0.0f64);
        if alpha > 0.0 {
            let mf = Microfacet::new(dist, alpha);
            for (i, ti) in t.iter_mut().enumerate() {
                let mu = (i as f64 * h) as f32;
                let (r_ext, t_ext) = rough_coat_rt(&mf, eta, mu, 48);
                // the internal side sees total internal reflection: a finer grid
                let (r_in, _) = rough_coat_rt(&mf, 1.0 / eta, mu, 96);
                *ti = t_ext as f32;
                // Mitsuba: r_int = 2 mean over the nodes of R_int(mu) mu
                r_int += r_in * mu.max(1e-6) as f64 / COAT_RES as f64 * 2.0;
                let w = if i == 0 || i == COAT_RES - 1 {
                    0.5
                } else {
                    1.0
                };
                t_hem += 2.0 * w * h * mu as f64 * t_ext;
                r_hem += 2.0 * w * h * mu as f64 * r_ext;
            }
        } else {
            r_int = fresnel_diffuse_reflectance(1.0 / eta) as f64;
            let n = 4096;
            for i in 0..n {
                let mu = (i as f64 + 0.5) / n as f64;
                let f = fresnel_dielectric(mu as f32, eta).0 as f64;
                t_hem += 2.0 * mu * (1.0 - f) / n as f64;
                r_hem += 2.0 * mu * f / n as f64;
            }
        }
        CoatTable {
            eta,
            alpha,
            dist,
            t,
            r_int: r_int as f32,
            t_hem: t_hem as f32,
            r_hem: r_hem as f32,
        }
    }

    /// The table for (eta, alpha, distribution), computed once per process and shared.
    pub fn get(eta: f32, alpha: f32, dist: Distribution) -> &'static CoatTable {
        type Key = (u32, u32, Distribution);
        static CACHE: OnceLock<Mutex<HashMap<Key, &'static CoatTable>>> = OnceLock::new();
        let key = (eta.to_bits(), alpha.to_bits(), dist);
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().unwrap().get(&key) {
            return t;
        }
        // computed outside the lock (a few ms); a race computes it twice, harmlessly
        let table: &'static CoatTable = Box::leak(Box::new(CoatTable::compute(eta, alpha, dist)));
        cache.lock().unwrap().entry(key).or_insert(table)
    }

    /// t(mu): the probability of crossing the coat at incidence cosine mu.
    #[inline]
    pub fn transmittance(&self, mu: f32) -> f32 {
        if self.alpha <= 0.0 {
            return 1.0 - fresnel_dielectric(mu.max(0.0), self.eta).0;
        }
        // linear interpolation between the nodes (Mitsuba's lerp_gather)
        let x = mu.clamp(0.0, 1.0) * (COAT_RES - 1) as f32;
        let i = (x as usize).min(COAT_RES - 2);
        let w = x - i as f32;
        self.t[i] * (1.0 - w) + self.t[i + 1] * w
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Diffuse reflectance of the base.
    pub kd: [f32; 3],
    /// Scale of the coat's reflection.
    pub specular: [f32; 3],
    pub nonlinear: bool,
    /// w: how often the coat is sampled (from the means of specular and kd).
    pub specular_weight: f32,
    pub coat: &'static CoatTable,
}

impl Plastic {
    pub fn new(
        kd: [f32; 3],
        specular: [f32; 3],
        eta: f32,
        alpha: f32,
        dist: Distribution,
        nonlinear: bool,
    ) -> Self {
        let mean = |c: [f32; 3]| (c[0] + c[1] + c[2]) / 3.0;
        let (d, s) = (mean(kd), mean(specular));
        Plastic {
            kd,
            specular,
            nonlinear,
            specular_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
            coat: CoatTable::get(eta, alpha.max(0.0), dist),
        }
    }

    #[inline]
    pub fn is_smooth(&self) -> bool {
        self.coat.alpha <= 0.0
    }

    #[inline]
    fn mf(&self) -> Microfacet {
        Microfacet::new(self.coat.dist, self.coat.alpha)
    }

    /// kd' / eta^2: the base's reflectance after the series of internal bounces and the
    /// radiance scaling of leaving the coat.
    #[inline]
    fn base_rgb(&self) -> [f32; 3] {
        let inv_eta2 = 1.0 / (self.coat.eta * self.coat.eta);
        let r = self.coat.r_int;
        self.kd.map(|k| {
            let den = if self.nonlinear { 1.0 - k * r } else { 1.0 - r };
            if den > 0.0 {
                k / den * inv_eta2
            } else {
                0.0
            }
        })
    }

    /// The base lobe f_b(wo, wi).
    #[inline]
    pub fn eval_base<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Spectrum::ZERO;
        }
        let t = self.coat.transmittance(wo.z) * self.coat.transmittance(wi.z);
        Spectrum::from_rgb(self.base_rgb()) * (t * FRAC_1_PI)
    }

    /// The rough coat's lobe f_c(wo, wi) (0 for the smooth coat).
    #[inline]
    pub fn eval_coat<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return Spectrum::ZERO;
        }
        let h = (wo + wi).normalize();
        let g = self.mf();
        let v = g.d(h) * g.g(wo, wi, h) * fresnel_dielectric(wo.dot(h), self.coat.eta).0
            / (4.0 * wo.z * wi.z);
        Spectrum::from_rgb(self.specular) * v
    }

    /// Density of the rough coat's own sampling (visible normals, reflected).
    #[inline]
    pub fn pdf_coat(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let g = self.mf();
        g.d(h) * g.g1(wo, h) / (4.0 * wo.z)
    }

    #[inline]
    pub fn sample_coat_dir(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if self.is_smooth() || wo.z <= 0.0 {
            return None;
        }
        let wi = reflect(wo, self.mf().sample_visible(wo, u));
        (wi.z > 0.0).then_some(wi)
    }

    /// P_c, the probability of sampling the coat at wo.
    #[inline]
    fn p_coat(&self, wo: Vec3) -> f32 {
        let t = self.coat.transmittance(wo.z);
        let w = self.specular_weight;
        let (c, b) = ((1.0 - t) * w, t * (1.0 - w));
        if c + b > 0.0 {
            c / (c + b)
        } else {
            0.0
        }
    }

    /// f(wo, wi) without the smooth coat's Dirac lobe.
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        self.eval_base(wo, wi) + self.eval_coat(wo, wi)
    }

    /// Density of `sample` for a non-Dirac wi.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let pc = self.p_coat(wo);
        (1.0 - pc) * pdf_cosine_hemisphere(wi) + pc * self.pdf_coat(wo, wi)
    }

    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z <= 0.0 {
            return None;
        }
        let pc = self.p_coat(wo);
        if u_lobe < pc && self.is_smooth() {
            // the coat's mirror: specular F / P_c
            let f = fresnel_dielectric(wo.z, self.coat.eta).0;
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Spectrum::from_rgb(self.specular) * (f / pc),
                pdf: pc,
                delta: true,
            });
        }
        let wi = if u_lobe < pc {
            self.sample_coat_dir(wo, u)?
        } else {
            let wi = square_to_cosine_hemisphere(u);
            if wi.z <= 0.0 {
                return None;
            }
            wi
        };
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval::<N>(wo, wi) * (wi.z / pdf),
            pdf,
            delta: false,
        })
    }

    /// The base lobe's albedo at normal incidence, kd' t(1) t_hem / eta^2 (its largest).
    #[inline]
    pub fn base_albedo_rgb(&self) -> [f32; 3] {
        let k = self.coat.transmittance(1.0) * self.coat.t_hem;
        self.base_rgb().map(|v| v * k)
    }

    /// The coat's cosine-weighted average albedo, specular r_hem.
    #[inline]
    pub fn coat_albedo_rgb(&self) -> [f32; 3] {
        self.specular.map(|v| v * self.coat.r_hem)
    }
}
