//! Conductors (Mitsuba 3's `conductor` and `roughconductor`): reflection only, with the
//! exact unpolarised Fresnel reflectance of a complex index of refraction eta + i k per RGB
//! channel, times a `specular` reflectance.
//!
//! Smooth (alpha = 0): a Dirac mirror lobe of weight specular F(cos theta_o).
//! Rough: the microfacet BRDF of Walter et al. (2007) with GGX or Beckmann's D,
//!   f(wo, wi) = specular F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos theta_o cos theta_i),
//!   h = (wo + wi) / |wo + wi|,
//! sampled by drawing a visible normal m from D_wo and reflecting wo about it; then
//!   p(wi) = D_wo(h) / (4 wo.h) = D(h) G1(wo, h) / (4 cos theta_o),
//!   f cos theta_i / p = specular F(wo.h) G1(wi, h).
//!
//! Anisotropic (Mitsuba's alpha_u != alpha_v): alpha along the surface's tangent (dp/du
//! made orthogonal to the shading normal, as Mitsuba's shading frame), alpha_v along the
//! bitangent. The tangent's direction in the local frame the integrators build
//! (`Anisotropy::tangent`) is set per hit by the scene; directions are turned about the
//! normal into the tangent's frame and the microfacet model is evaluated there.

use super::microfacet::{in_local_frame, in_tangent_frame, reflect, Distribution, Microfacet};
use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// The material's optical constants (shared: a conductor is one of the common BSDFs,
    /// whose size is the `Bsdf` enum's).
    pub optics: &'static Optics,
    /// Microfacet roughness (alpha_u when anisotropic); 0: the smooth conductor.
    pub alpha: f32,
    pub dist: Distribution,
    /// None: isotropic roughness `alpha`.
    pub aniso: Option<Anisotropy>,
}

/// A conductor's complex index of refraction eta + i k and reflectance scale, per RGB
/// channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optics {
    /// Real part of the relative index of refraction.
    pub eta: [f32; 3],
    /// Imaginary part (absorption).
    pub k: [f32; 3],
    pub specular: [f32; 3],
}

/// The second roughness of an anisotropic conductor and the frame it applies in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anisotropy {
    /// Roughness along the bitangent.
    pub alpha_v: f32,
    /// (cos, sin) of the tangent's angle to the local frame's x axis (its s vector).
    pub tangent: [f32; 2],
}

impl Anisotropy {
    /// A local direction in the tangent's frame (x along the tangent).
    #[inline]
    fn in_tangent_frame(&self, v: Vec3) -> Vec3 {
        in_tangent_frame(self.tangent, v)
    }

    /// The inverse of [`Anisotropy::in_tangent_frame`].
    #[inline]
    fn in_local_frame(&self, v: Vec3) -> Vec3 {
        in_local_frame(self.tangent, v)
    }
}

/// Unpolarised Fresnel reflectance of a conductor of index eta + i k at incidence cosine
/// `cos_i` (>= 0): the exact expressions for r_s and r_p (Born and Wolf; as in Mitsuba's
/// `fresnel_conductor`), with a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2)
/// and a = sqrt((a^2 + b^2 + eta^2 - k^2 - sin^2) / 2):
///   R_s = (a^2 + b^2 + cos^2 - 2 a cos) / (a^2 + b^2 + cos^2 + 2 a cos),
///   R_p = R_s (cos^2 (a^2 + b^2) + sin^4 - 2 a cos sin^2) / (cos^2 (a^2 + b^2) + sin^4 + 2 a cos sin^2).
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = (cos_i * cos_i).min(1.0);
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - s2;
    let a2pb2 = (t1 * t1 + 4.0 * eta * eta * k * k).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + t1)).max(0.0).sqrt();
    let term1 = a2pb2 + c2;
    let term2 = 2.0 * cos_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    let r = 0.5 * (rs + rp);
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

impl Conductor {
    /// An isotropic conductor of index eta + i k, reflectance scale `specular` and
    /// roughness `alpha` (0: smooth).
    pub fn new(
        eta: [f32; 3],
        k: [f32; 3],
        specular: [f32; 3],
        alpha: f32,
        dist: Distribution,
    ) -> Conductor {
        Conductor {
            optics: super::intern::intern(Optics { eta, k, specular }),
            alpha,
            dist,
            aniso: None,
        }
    }

    #[inline]
    pub fn is_smooth(&self) -> bool {
        self.alpha <= 0.0
    }

    #[inline]
    fn mf(&self) -> Microfacet {
        Microfacet::new(self.dist, self.alpha)
    }

    /// The anisotropic conductor's microfacet model and frame (None when isotropic).
    #[inline]
    fn aniso_mf(&self) -> Option<(Microfacet, Anisotropy)> {
        let a = self.aniso?;
        Some((Microfacet::anisotropic(self.dist, self.alpha, a.alpha_v), a))
    }

    /// specular F(cos) per RGB channel.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> [f32; 3] {
        let o = self.optics;
        std::array::from_fn(|c| o.specular[c] * fresnel_conductor(cos, o.eta[c], o.k[c]))
    }

    /// f(wo, wi) of the rough conductor (0 for the smooth one: a Dirac lobe).
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return Spectrum::ZERO;
        }
        if let Some((g, a)) = self.aniso_mf() {
            return self.eval_in(&g, a.in_tangent_frame(wo), a.in_tangent_frame(wi));
        }
        self.eval_in(&self.mf(), wo, wi)
    }

    /// f(wo, wi) with microfacet model `g` (directions in its frame, above the surface).
    #[inline(always)]
    fn eval_in<const N: usize>(&self, g: &Microfacet, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let h = (wo + wi).normalize();
        let dg = g.d(h) * g.g(wo, wi, h);
        if dg <= 0.0 {
            return Spectrum::ZERO;
        }
        Spectrum::from_rgb(self.reflectance(wo.dot(h))) * (dg / (4.0 * wo.z * wi.z))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        match self.aniso_mf() {
            Some((g, a)) => Self::pdf_in(&g, a.in_tangent_frame(wo), a.in_tangent_frame(wi)),
            None => Self::pdf_in(&self.mf(), wo, wi),
        }
    }

    #[inline(always)]
    fn pdf_in(g: &Microfacet, wo: Vec3, wi: Vec3) -> f32 {
        let h = (wo + wi).normalize();
        g.d(h) * g.g1(wo, h) / (4.0 * wo.z)
    }

    #[inline]
    pub fn sample_dir(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if self.is_smooth() || wo.z <= 0.0 {
            return None;
        }
        let wi = match self.aniso_mf() {
            Some((g, a)) => {
                let wo = a.in_tangent_frame(wo);
                a.in_local_frame(reflect(wo, g.sample_visible(wo, u)))
            }
            None => reflect(wo, self.mf().sample_visible(wo, u)),
        };
        (wi.z > 0.0).then_some(wi)
    }

    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z <= 0.0 {
            return None;
        }
        if self.is_smooth() {
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Spectrum::from_rgb(self.reflectance(wo.z)),
                pdf: 1.0,
                delta: true,
            });
        }
        match self.aniso_mf() {
            Some((g, a)) => {
                let mut s = self.sample_in(&g, a.in_tangent_frame(wo), u)?;
                s.wi = a.in_local_frame(s.wi);
                Some(s)
            }
            None => self.sample_in(&self.mf(), wo, u),
        }
    }

    #[inline(always)]
    fn sample_in<const N: usize>(
        &self,
        g: &Microfacet,
        wo: Vec3,
        u: Vec2,
    ) -> Option<BsdfSample<N>> {
        let m = g.sample_visible(wo, u);
        let wi = reflect(wo, m);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = g.d(m) * g.g1(wo, m) / (4.0 * wo.z);
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: Spectrum::from_rgb(self.reflectance(wo.dot(m))) * g.g1(wi, m),
            pdf,
            delta: false,
        })
    }

    /// specular F at normal incidence: the selection weight of the lobe (its albedo is
    /// close to it for the common metals, and at most max(specular)).
    #[inline]
    pub fn albedo_rgb(&self) -> [f32; 3] {
        self.reflectance(1.0)
    }
}
