//! Materials whose parameters vary over a surface beyond a diffuse texture: the BSDF at
//! a hit is made from the parameters' values there ([`Varying::bsdf`]).

use super::{Blend, Bsdf, Principled};
use crate::texture::mesh_attribute::{luminance, Param};

/// The scalar parameters of `principled`, in [`PrincipledParams::values`]' order, with
/// Mitsuba's defaults.
pub const PRINCIPLED_VALUES: [(&str, f32); 10] = [
    ("roughness", 0.5),
    ("anisotropic", 0.0),
    ("metallic", 0.0),
    ("spec_tint", 0.0),
    ("sheen", 0.0),
    ("sheen_tint", 0.0),
    ("flatness", 0.0),
    ("clearcoat", 0.0),
    ("clearcoat_gloss", 0.0),
    ("spec_trans", 0.0),
];

/// A `principled` material's parameters, each a value, a texture or a mesh attribute.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledParams {
    pub base_color: Param,
    /// As [`PRINCIPLED_VALUES`] names them.
    pub values: [Param; 10],
    pub eta: f32,
    pub rates: [f32; 3],
}

impl PrincipledParams {
    /// The BSDF from the parameters' values `v(param)` (scalars by their luminance).
    fn with(&self, v: impl Fn(&Param) -> [f32; 3]) -> Principled {
        let x: [f32; 10] = std::array::from_fn(|i| luminance(v(&self.values[i])));
        Principled {
            base_color: v(&self.base_color),
            roughness: x[0],
            anisotropic: x[1],
            metallic: x[2],
            specular_tint: x[3],
            sheen: x[4],
            sheen_tint: x[5],
            flatness: x[6],
            clearcoat: x[7],
            clearcoat_gloss: x[8],
            spec_trans: x[9],
            eta: self.eta,
            rates: self.rates,
        }
    }

    /// At texture coordinates (u, v), `attribute(slot)` a mesh attribute's value there.
    #[inline]
    pub fn at(&self, u: f32, v: f32, attribute: &dyn Fn(u32) -> [f32; 3]) -> Principled {
        self.with(|p| p.eval(u, v, attribute))
    }

    /// With each texture's mean (the material's BSDF where one value is needed).
    pub fn mean(&self) -> Principled {
        self.with(Param::mean)
    }

    /// No parameter varies.
    pub fn is_const(&self) -> bool {
        self.base_color.is_const() && self.values.iter().all(Param::is_const)
    }

    /// Each parameter through `f` (resolving mesh attributes).
    pub fn try_map<E>(&self, f: impl Fn(&Param) -> Result<Param, E>) -> Result<Self, E> {
        let mut values = self.values.clone();
        for v in values.iter_mut() {
            *v = f(v)?;
        }
        Ok(PrincipledParams {
            base_color: f(&self.base_color)?,
            values,
            eta: self.eta,
            rates: self.rates,
        })
    }
}

/// What of a material varies, and how the BSDF at a hit is made.
#[derive(Clone, Debug, PartialEq)]
pub enum Varying {
    /// The diffuse reflectance (the material's BSDF with this kd).
    Kd(Param),
    /// A `blendbsdf`'s weight (the material's BSDF is the blend).
    BlendWeight(Param),
    /// A `principled` material's parameters.
    Principled(Box<PrincipledParams>),
}

impl Varying {
    /// The BSDF of a material whose BSDF is `base` at texture coordinates (u, v), with
    /// `attribute(slot)` the value of a mesh attribute at the hit.
    #[inline]
    pub fn bsdf(&self, base: &Bsdf, u: f32, v: f32, attribute: &dyn Fn(u32) -> [f32; 3]) -> Bsdf {
        match (self, base) {
            (Varying::Kd(p), b) => b.clone().with_kd(p.eval(u, v, attribute)),
            (Varying::BlendWeight(w), Bsdf::Blend(b)) => {
                Bsdf::Blend(Blend::new(b.pair, w.eval_1(u, v, attribute)))
            }
            (Varying::Principled(p), _) => Bsdf::Principled(Box::new(p.at(u, v, attribute))),
            (_, b) => b.clone(),
        }
    }
}
