//! BSDFs in a local shading frame (normal = +z; wo and wi point away from the surface).
//!
//! Each BSDF is a small `Copy` struct with `eval`, `pdf` and `sample` in pairs; `Bsdf` is
//! the enum the integrators match on. Combined BRDFs (diffuse + normalized Phong, the
//! combined BRDF of the Russian-roulette paper) keep their elementary lobes visible:
//! `Bsdf::lobes` gives each lobe with its own sample/pdf/albedo, so a roulette or a
//! lobe-selection strategy can choose among them. A rough plastic is such a combined
//! BRDF (its diffuse base and its GGX coat), and a rough conductor a single glossy lobe.
//!
//! The microfacet models follow Mitsuba 3's plugins (`conductor`, `roughconductor`,
//! `plastic`, `roughplastic`, `dielectric`, `roughdielectric`, `thindielectric`), with the
//! GGX distribution of `microfacet`. Transmission (`Bsdf::transmits`) evaluates and samples
//! directions on the other side of the surface; its radiance scaling is undone on light
//! subpaths with `Bsdf::adjoint_scale`.

pub mod albedo;
pub mod blend;
pub mod conductor;
pub mod dielectric;
mod intern;
pub mod lambert;
pub mod microfacet;
pub mod mirror;
pub mod phong;
pub mod plastic;
pub mod principled;
pub mod principled_thin;
pub mod rough_dielectric;
pub mod roughness;
mod surface;
pub mod thin_dielectric;
pub mod varying;
pub use surface::Material;

pub use albedo::AlbedoTable;
pub use blend::Blend;
pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use lambert::Lambert;
pub use microfacet::Distribution;
pub use mirror::Mirror;
pub use phong::Phong;
pub use plastic::Plastic;
pub use principled::Principled;
pub use principled_thin::PrincipledThin;
pub use rough_dielectric::RoughDielectric;
pub use thin_dielectric::ThinDielectric;

use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};

/// Result of sampling a direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample<const N: usize> {
    pub wi: Vec3,
    /// f * |cos theta_i| / pdf (for delta lobes: the lobe's weight).
    pub weight: Spectrum<N>,
    /// Solid-angle density of wi (1 for a delta lobe by convention).
    pub pdf: f32,
    /// The sampled direction came from a Dirac delta lobe.
    pub delta: bool,
}

/// An elementary lobe of a combined BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    Diffuse(Lambert),
    Glossy(Phong),
    /// A rough conductor (its only lobe).
    Conductor(Conductor),
    /// A rough plastic's diffuse base (under the coat).
    PlasticBase(Plastic),
    /// A rough plastic's GGX coat reflection.
    PlasticCoat(Plastic),
}

impl Lobe {
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        match self {
            Lobe::Diffuse(l) => l.eval(wo, wi),
            Lobe::Glossy(p) => p.eval(wo, wi),
            Lobe::Conductor(c) => c.eval(wo, wi),
            Lobe::PlasticBase(p) => p.eval_base(wo, wi),
            Lobe::PlasticCoat(p) => p.eval_coat(wo, wi),
        }
    }
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Lobe::Diffuse(l) => l.pdf(wo, wi),
            Lobe::Glossy(p) => p.pdf(wo, wi),
            Lobe::Conductor(c) => c.pdf(wo, wi),
            Lobe::PlasticBase(_) => {
                if wo.z <= 0.0 {
                    0.0
                } else {
                    crate::sampling::pdf_cosine_hemisphere(wi)
                }
            }
            Lobe::PlasticCoat(p) => p.pdf_coat(wo, wi),
        }
    }
    /// A direction from this lobe's own density (None if it fell below the surface).
    #[inline]
    pub fn sample_dir(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        match self {
            Lobe::Diffuse(l) => l.sample_dir(wo, u),
            Lobe::Glossy(p) => p.sample_dir(wo, u),
            Lobe::Conductor(c) => c.sample_dir(wo, u),
            Lobe::PlasticBase(_) => Lambert { kd: [1.0; 3] }.sample_dir(wo, u),
            Lobe::PlasticCoat(p) => p.sample_coat_dir(wo, u),
        }
    }
    /// Reflectance parameter of the lobe (kd or ks: an upper bound of its albedo; for the
    /// microfacet lobes the albedo at normal incidence, or the coat's average).
    #[inline]
    pub fn albedo_rgb(&self) -> [f32; 3] {
        match self {
            Lobe::Diffuse(l) => l.kd,
            Lobe::Glossy(p) => p.ks,
            Lobe::Conductor(c) => c.albedo_rgb(),
            Lobe::PlasticBase(p) => p.base_albedo_rgb(),
            Lobe::PlasticCoat(p) => p.coat_albedo_rgb(),
        }
    }
}

/// The scattering model of a surface.
///
/// Its size is what every hit moves around, so the common variants (diffuse, plastic,
/// dielectric, conductor) stay small and a large, rare one (principled's 17 parameters)
/// lives behind a box.
#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Absorbs everything (e.g. a pure emitter with Kd = 0).
    Black,
    Diffuse(Lambert),
    /// Sum of a diffuse and a normalized Phong lobe.
    DiffuseGlossy(Lambert, Phong),
    Mirror(Mirror),
    Dielectric(Dielectric),
    /// Smooth (Dirac) or rough (GGX) conductor.
    Conductor(Conductor),
    /// Diffuse base under a smooth or rough dielectric coat.
    Plastic(Plastic),
    /// Rough dielectric interface: reflection and refraction.
    RoughDielectric(RoughDielectric),
    /// Thin dielectric slab (Dirac reflection and straight transmission).
    ThinDielectric(ThinDielectric),
    /// Mitsuba's `blendbsdf`: two BSDFs blended by a weight.
    Blend(Blend),
    /// Mitsuba's `principled` (Burley's BSDF).
    Principled(Box<Principled>),
    /// Mitsuba's `principledthin` (Burley's thin-surface BSDF).
    PrincipledThin(Box<PrincipledThin>),
}

/// Luminance of an RGB triple (lobe selection weights).
#[inline]
fn lum(c: [f32; 3]) -> f32 {
    crate::spectrum::Spectrum::<3>(c).luminance().max(0.0)
}

impl Bsdf {
    /// A BSDF from MTL-style parameters. `illum` 5 = mirror, 7 = glass.
    pub fn from_mtl(kd: [f32; 3], ks: [f32; 3], ns: f32, ni: f32, illum: u8) -> Bsdf {
        match illum {
            5 => Bsdf::Mirror(Mirror {
                ks: if ks == [0.0; 3] { [1.0; 3] } else { ks },
            }),
            7 => Bsdf::Dielectric(Dielectric {
                eta: if ni > 0.0 { ni } else { 1.5 },
                tint: dielectric::Tint::NONE,
            }),
            _ => {
                let d = kd != [0.0; 3];
                let g = ks != [0.0; 3];
                match (d, g) {
                    (false, false) => Bsdf::Black,
                    (true, false) => Bsdf::Diffuse(Lambert { kd }),
                    (_, true) => Bsdf::DiffuseGlossy(Lambert { kd }, Phong { ks, n: ns.max(0.0) }),
                }
            }
        }
    }

    /// Replace the diffuse reflectance (texture lookups).
    #[inline]
    pub fn with_kd(self, kd: [f32; 3]) -> Bsdf {
        match self {
            Bsdf::Diffuse(_) => Bsdf::Diffuse(Lambert { kd }),
            Bsdf::DiffuseGlossy(_, p) => Bsdf::DiffuseGlossy(Lambert { kd }, p),
            Bsdf::Plastic(p) => Bsdf::Plastic(Plastic { kd, ..p }),
            b => b,
        }
    }

    /// Opaque BSDFs are two-sided (the frame is flipped towards wo); glass is not (a thin
    /// slab is symmetric, so it is).
    #[inline]
    pub fn is_two_sided(&self) -> bool {
        match self {
            Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_) | Bsdf::Principled(_) => false,
            Bsdf::Blend(b) => b.is_two_sided(),
            _ => true,
        }
    }

    /// Only Dirac lobes: next-event estimation is useless here.
    #[inline]
    pub fn is_delta(&self) -> bool {
        match self {
            Bsdf::Mirror(_) | Bsdf::Dielectric(_) | Bsdf::Black | Bsdf::ThinDielectric(_) => true,
            Bsdf::Conductor(c) => c.is_smooth(),
            Bsdf::Blend(b) => b.is_delta(),
            _ => false,
        }
    }

    /// `eval` and `pdf` are non-zero for directions on the other side of the surface
    /// (wi.z < 0 < wo.z or the reverse): next-event estimation and BDPT connections must
    /// try them.
    #[inline]
    pub fn transmits(&self) -> bool {
        match self {
            Bsdf::RoughDielectric(_) => true,
            Bsdf::Principled(p) => p.transmits(),
            Bsdf::PrincipledThin(p) => p.transmits(),
            Bsdf::Blend(b) => b.transmits(),
            _ => false,
        }
    }

    /// The factor that turns a sampled weight f(wo, wi) |cos theta_i| / p, which carries
    /// radiance from wi to wo, into the weight of importance (or light particles) going
    /// from wo to wi, f(wi, wo) |cos theta_i| / p: (eta_i / eta_o)^2 for a refraction,
    /// eta_i and eta_o the indices on the sides of wi and wo; 1 otherwise.
    #[inline]
    pub fn adjoint_scale(&self, wo: Vec3, wi: Vec3) -> f32 {
        let eta = match self {
            Bsdf::Dielectric(d) => d.eta,
            Bsdf::RoughDielectric(d) => d.eta,
            Bsdf::Principled(p) => p.eta,
            // the first of the two that refracts (a blend of two refracting interfaces of
            // different indices is scaled as the first)
            Bsdf::Blend(b) => {
                let s = b.pair.iter().map(|x| x.adjoint_scale(wo, wi));
                return s.into_iter().find(|&s| s != 1.0).unwrap_or(1.0);
            }
            _ => return 1.0,
        };
        if wo.z * wi.z >= 0.0 {
            return 1.0;
        }
        // eta_r = eta_o / eta_i for a crossing from the side of wo
        let eta_r = dielectric::fresnel_dielectric(wo.z, eta).2;
        1.0 / (eta_r * eta_r)
    }

    /// Elementary lobes and their count.
    #[inline]
    pub fn lobe_array(&self) -> ([Lobe; 2], usize) {
        let zero = Lobe::Diffuse(Lambert { kd: [0.0; 3] });
        match *self {
            Bsdf::Diffuse(l) => ([Lobe::Diffuse(l), zero], 1),
            Bsdf::DiffuseGlossy(l, p) => ([Lobe::Diffuse(l), Lobe::Glossy(p)], 2),
            Bsdf::Conductor(c) if !c.is_smooth() => ([Lobe::Conductor(c), zero], 1),
            Bsdf::Plastic(p) if !p.is_smooth() => ([Lobe::PlasticBase(p), Lobe::PlasticCoat(p)], 2),
            // smooth coats and transmission are no elementary reflection lobes: the
            // lobe-selection methods fall back to the mixture there
            _ => ([zero, zero], 0),
        }
    }

    /// f(wo, wi) (without the cosine).
    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        match self {
            Bsdf::Diffuse(l) => l.eval(wo, wi),
            Bsdf::DiffuseGlossy(l, p) => l.eval(wo, wi) + p.eval(wo, wi),
            Bsdf::Conductor(c) => c.eval(wo, wi),
            Bsdf::Plastic(p) => p.eval(wo, wi),
            Bsdf::RoughDielectric(d) => d.eval(wo, wi),
            Bsdf::Blend(b) => b.eval(wo, wi),
            Bsdf::Principled(p) => p.eval(wo, wi),
            Bsdf::PrincipledThin(p) => p.eval(wo, wi),
            _ => Spectrum::ZERO,
        }
    }

    /// Probabilities of choosing the diffuse and glossy lobes when sampling (by albedo).
    #[inline]
    fn lobe_probs(l: &Lambert, p: &Phong) -> (f32, f32) {
        let a = lum(l.kd);
        let b = lum(p.ks);
        if a + b <= 0.0 {
            (0.5, 0.5)
        } else {
            (a / (a + b), b / (a + b))
        }
    }

    /// Solid-angle density of `sample` producing wi.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(l) => l.pdf(wo, wi),
            Bsdf::DiffuseGlossy(l, p) => {
                let (pd, pg) = Self::lobe_probs(l, p);
                pd * l.pdf(wo, wi) + pg * p.pdf(wo, wi)
            }
            Bsdf::Conductor(c) => c.pdf(wo, wi),
            Bsdf::Plastic(p) => p.pdf(wo, wi),
            Bsdf::RoughDielectric(d) => d.pdf(wo, wi),
            Bsdf::Blend(b) => b.pdf(wo, wi),
            Bsdf::Principled(p) => p.pdf(wo, wi),
            Bsdf::PrincipledThin(p) => p.pdf(wo, wi),
            _ => 0.0,
        }
    }

    /// Sample wi given wo; `u_lobe` chooses a lobe (or reflection vs refraction), `u` the direction.
    #[inline(always)]
    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        match self {
            Bsdf::Black => None,
            Bsdf::Diffuse(l) => l.sample(wo, u),
            Bsdf::DiffuseGlossy(l, p) => {
                // One-sample mixture of the lobes; the pdf is the mixture density.
                let (pd, _) = Self::lobe_probs(l, p);
                let wi = if u_lobe < pd {
                    l.sample_dir(wo, u)?
                } else {
                    p.sample_dir(wo, u)?
                };
                let pdf = self.pdf(wo, wi);
                if pdf <= 0.0 || wi.z <= 0.0 {
                    return None;
                }
                let f: Spectrum<N> = self.eval(wo, wi);
                Some(BsdfSample {
                    wi,
                    weight: f * (wi.z / pdf),
                    pdf,
                    delta: false,
                })
            }
            Bsdf::Mirror(m) => m.sample(wo),
            Bsdf::Dielectric(d) => d.sample(wo, u_lobe),
            Bsdf::Conductor(c) => c.sample(wo, u),
            Bsdf::Plastic(p) => p.sample(wo, u_lobe, u),
            Bsdf::RoughDielectric(d) => d.sample(wo, u_lobe, u),
            Bsdf::ThinDielectric(d) => d.sample(wo, u_lobe),
            Bsdf::Blend(b) => b.sample(wo, u_lobe, u),
            Bsdf::Principled(p) => p.sample(wo, u_lobe, u),
            Bsdf::PrincipledThin(p) => p.sample(wo, u_lobe, u),
        }
    }

    /// The local albedo used by classic Russian roulette (upper bound, per band).
    #[inline]
    pub fn albedo<const N: usize>(&self) -> Spectrum<N> {
        match self {
            Bsdf::Black => Spectrum::ZERO,
            Bsdf::Diffuse(l) => Spectrum::from_rgb(l.kd),
            Bsdf::DiffuseGlossy(l, p) => Spectrum::from_rgb(l.kd) + Spectrum::from_rgb(p.ks),
            Bsdf::Mirror(m) => Spectrum::from_rgb(m.ks),
            Bsdf::Dielectric(_) => Spectrum::ONE,
            Bsdf::Conductor(c) => Spectrum::from_rgb(c.albedo_rgb()),
            Bsdf::Plastic(p) => {
                Spectrum::from_rgb(p.base_albedo_rgb()) + Spectrum::from_rgb(p.coat_albedo_rgb())
            }
            Bsdf::RoughDielectric(_) | Bsdf::ThinDielectric(_) => Spectrum::ONE,
            Bsdf::Blend(b) => b.albedo(),
            Bsdf::Principled(p) => Spectrum::from_rgb(p.albedo_rgb()),
            Bsdf::PrincipledThin(p) => Spectrum::from_rgb(p.albedo_rgb()),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
