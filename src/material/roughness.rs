//! A rough conductor's roughness per hit: Mitsuba's `alpha_u` / `alpha_v`, each a constant
//! or a texture (a bitmap's luminance, a checkerboard), applied to the material's BSDF where
//! a ray hits it (`Scene::bsdf_at`). Materials with one isotropic constant roughness have
//! none of this: their BSDF is built once.

use super::conductor::Anisotropy;
use super::Bsdf;
use crate::math::Vec2;
use crate::texture::Texture;
use std::sync::Arc;

/// One roughness parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Alpha {
    Value(f32),
    /// A scalar map (every texel's channels equal: `Roughness::scalar_map`).
    Map(Arc<Texture>),
}

impl Alpha {
    #[inline]
    fn at(&self, uv: Vec2) -> f32 {
        match self {
            Alpha::Value(a) => *a,
            Alpha::Map(t) => t.lookup(uv.x, uv.y)[0],
        }
    }

    /// Its mean over the texture (the value where one constant stands in).
    pub fn mean(&self) -> f32 {
        match self {
            Alpha::Value(a) => *a,
            Alpha::Map(t) => t.mean()[0],
        }
    }
}

/// Roughness along the tangent (`alpha_u`) and the bitangent (`alpha_v`).
#[derive(Clone, Debug, PartialEq)]
pub struct Roughness {
    pub alpha_u: Alpha,
    pub alpha_v: Alpha,
}

impl Roughness {
    /// A texture as a scalar map, as Mitsuba's `eval_1` reads it: its value where the
    /// channels agree (a checkerboard of floats, a grey bitmap), else the luminance.
    pub fn scalar_map(mut t: Texture) -> Texture {
        for c in &mut t.texels {
            if !(c[0] == c[1] && c[1] == c[2]) {
                *c = [0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; 3];
            }
        }
        t
    }

    /// The (alpha_u, alpha_v) at texture coordinates `uv`.
    #[inline]
    pub fn at(&self, uv: Vec2) -> (f32, f32) {
        (self.alpha_u.at(uv), self.alpha_v.at(uv))
    }

    /// `bsdf` (a rough conductor; other BSDFs are returned unchanged) with the roughness
    /// at `uv`; `tangent()` gives the (cos, sin) of the tangent's angle in the local frame,
    /// asked only where the roughness is anisotropic there.
    #[inline]
    pub fn apply(&self, bsdf: Bsdf, uv: Vec2, tangent: impl FnOnce() -> [f32; 2]) -> Bsdf {
        let Bsdf::Conductor(mut c) = bsdf else {
            return bsdf;
        };
        let (au, av) = self.at(uv);
        let (au, av) = (
            au.max(super::microfacet::MIN_ALPHA),
            av.max(super::microfacet::MIN_ALPHA),
        );
        c.alpha = au;
        c.aniso = (au != av).then(|| Anisotropy {
            alpha_v: av,
            tangent: tangent(),
        });
        Bsdf::Conductor(c)
    }
}

#[cfg(test)]
#[path = "roughness_tests.rs"]
mod tests;
