//! A surface's material ready for shading: its BSDF, its emission (one-sided, on the
//! counter-clockwise side) and an optional diffuse texture.

use super::{AlbedoTable, Bsdf};
use std::sync::Arc;

/// A material ready for shading.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub bsdf: Bsdf,
    /// Emitted radiance (linear RGB) on the front side (counter-clockwise winding); with
    /// `emission_table`, its cosine-weighted average (so power = pi x area x emission).
    pub emission: [f32; 3],
    /// Directional emission L_e(w) = 1 - a(cos theta), a the directional albedo.
    pub emission_table: Option<Arc<AlbedoTable>>,
    /// A texture of emitted radiance (Mitsuba's textured area emitter; `emission` is its
    /// mean), read at a hit's uv by `emitted_at`.
    pub emission_texture: Option<Arc<crate::texture::Texture>>,
    pub kd_texture: Option<u32>,
    /// Black on the back side (the geometric normal's): see `MaterialDesc::one_sided`.
    pub one_sided: bool,
    /// The share of light the surface stops, in [0, 1] (times `opacity_texture`'s value);
    /// the rest passes through it unchanged (a cut-out).
    pub opacity: f32,
    pub opacity_texture: Option<u32>,
    /// The shading normal from a texture (Mitsuba's `normalmap`, `bumpmap`).
    pub normal_map: Option<crate::texture::normal::NormalMap>,
    /// A rough conductor's roughness per hit (anisotropic or textured; see `roughness`).
    pub roughness: Option<super::roughness::Roughness>,
    /// Parameters that vary over the surface beyond `kd_texture` (the BSDF at a hit is
    /// made from them; see `Scene::bsdf_at`).
    pub varying: Option<std::sync::Arc<super::varying::Varying>>,
}

impl Material {
    /// Light passes through it somewhere (opacity below 1, or a map of it).
    pub fn is_cutout(&self) -> bool {
        self.opacity < 1.0 || self.opacity_texture.is_some()
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0)
    }

    /// Emitted radiance towards a direction at cosine `cos` to the front-side normal.
    #[inline]
    pub fn emitted(&self, cos: f32) -> [f32; 3] {
        match &self.emission_table {
            None => self.emission,
            Some(t) => t.complement(cos),
        }
    }

    /// [`Material::emitted`] at texture coordinates `uv` (the texture's radiance there
    /// for a textured emitter).
    #[inline]
    pub fn emitted_at(&self, cos: f32, uv: glam::Vec2) -> [f32; 3] {
        match &self.emission_texture {
            None => self.emitted(cos),
            Some(t) => t.lookup(uv.x, uv.y),
        }
    }
}
