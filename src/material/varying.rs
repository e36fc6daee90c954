//! Materials whose parameters vary over a surface beyond a diffuse texture: the BSDF at
//! a hit is made from the parameters' values there ([`Varying::bsdf`]).

use super::{Blend, Bsdf};
use crate::texture::mesh_attribute::Param;

/// What of a material varies, and how the BSDF at a hit is made.
#[derive(Clone, Debug, PartialEq)]
pub enum Varying {
    /// The diffuse reflectance (the material's BSDF with this kd).
    Kd(Param),
    /// A `blendbsdf`'s weight (the material's BSDF is the blend).
    BlendWeight(Param),
}

impl Varying {
    /// The BSDF of a material whose BSDF is `base` at texture coordinates (u, v), with
    /// `attribute(slot)` the value of a mesh attribute at the hit.
    #[inline]
    pub fn bsdf(&self, base: Bsdf, u: f32, v: f32, attribute: &dyn Fn(u32) -> [f32; 3]) -> Bsdf {
        match (self, base) {
            (Varying::Kd(p), b) => b.with_kd(p.eval(u, v, attribute)),
            (Varying::BlendWeight(w), Bsdf::Blend(b)) => {
                Bsdf::Blend(Blend::new(b.pair, w.eval_1(u, v, attribute)))
            }
            (_, b) => b,
        }
    }
}
