//! Materials whose parameters vary over a surface beyond a diffuse texture: the BSDF at
//! a hit is made from the parameters' values there ([`Varying::bsdf`]).

use super::{Blend, Bsdf, Principled, PrincipledThin};
use crate::texture::mesh_attribute::{luminance, Param};

/// The scalar parameters of `principled` and `principledthin`, in
/// [`PrincipledParams::values`]' order, with Mitsuba's defaults (`metallic`, `clearcoat`
/// and `clearcoat_gloss` are principled's only, `diff_trans` principledthin's).
pub const PRINCIPLED_VALUES: [(&str, f32); 11] = [
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
    ("diff_trans", 0.0),
];

/// The names of [`PRINCIPLED_VALUES`] that `principledthin` does not have.
pub const NOT_THIN: [&str; 3] = ["metallic", "clearcoat", "clearcoat_gloss"];

/// A `principled` (or `principledthin`) material's parameters, each a value, a texture or
/// a mesh attribute.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledParams {
    pub base_color: Param,
    /// As [`PRINCIPLED_VALUES`] names them.
    pub values: [Param; 11],
    pub eta: f32,
    /// principled's [`Principled::rates`] and a 1, or principledthin's
    /// [`PrincipledThin::rates`].
    pub rates: [f32; 4],
    /// `principledthin`.
    pub thin: bool,
}

impl PrincipledParams {
    /// The BSDF from the parameters' values `v(param)` (scalars by their luminance).
    fn with(&self, v: impl Fn(&Param) -> [f32; 3]) -> Bsdf {
        let x: [f32; 11] = std::array::from_fn(|i| luminance(v(&self.values[i])));
        if self.thin {
            return Bsdf::PrincipledThin(Box::new(PrincipledThin {
                base_color: v(&self.base_color),
                roughness: x[0],
                anisotropic: x[1],
                specular_tint: x[3],
                sheen: x[4],
                sheen_tint: x[5],
                flatness: x[6],
                spec_trans: x[9],
                diff_trans: x[10],
                eta: self.eta,
                rates: self.rates,
                tangent: [1.0, 0.0],
            }));
        }
        Bsdf::Principled(Box::new(Principled {
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
            rates: [self.rates[0], self.rates[1], self.rates[2]],
            tangent: [1.0, 0.0],
        }))
    }

    /// At texture coordinates (u, v), `attribute(slot)` a mesh attribute's value there,
    /// `tangent()` the surface's tangent (where the main lobe is anisotropic).
    #[inline]
    pub fn at(
        &self,
        (u, v): (f32, f32),
        attribute: &dyn Fn(u32) -> [f32; 3],
        tangent: &dyn Fn() -> [f32; 2],
    ) -> Bsdf {
        let mut b = self.with(|p| p.eval(u, v, attribute));
        match &mut b {
            Bsdf::Principled(p) if p.is_anisotropic() => p.tangent = tangent(),
            Bsdf::PrincipledThin(p) if p.is_anisotropic() => p.tangent = tangent(),
            _ => {}
        }
        b
    }

    /// With each texture's mean (the material's BSDF where one value is needed).
    pub fn mean(&self) -> Bsdf {
        self.with(Param::mean)
    }

    /// `anisotropic` is not the constant 0 (the main lobe needs the surface's tangent).
    pub fn is_anisotropic(&self) -> bool {
        self.values[1] != Param::Const([0.0; 3])
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
            thin: self.thin,
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
    /// `attribute(slot)` the value of a mesh attribute at the hit and `tangent()` the
    /// (cos, sin) of the surface's tangent in the local frame (asked only where an
    /// anisotropic BSDF needs it).
    #[inline]
    pub fn bsdf(
        &self,
        base: &Bsdf,
        (u, v): (f32, f32),
        attribute: &dyn Fn(u32) -> [f32; 3],
        tangent: &dyn Fn() -> [f32; 2],
    ) -> Bsdf {
        match (self, base) {
            (Varying::Kd(p), b) => b.clone().with_kd(p.eval(u, v, attribute)),
            (Varying::BlendWeight(w), Bsdf::Blend(b)) => {
                Bsdf::Blend(Blend::new(b.pair, w.eval_1(u, v, attribute)))
            }
            (Varying::Principled(p), _) => p.at((u, v), attribute, tangent),
            (_, b) => b.clone(),
        }
    }
}
