//! Mitsuba's `mesh_attribute` texture and the parameters of materials that vary over a
//! surface ([`Param`]: a constant, an image or procedural texture, or a mesh attribute).
//!
//! A mesh attribute (`vertex_color`, `face_weight`, ...) is read from the mesh's file;
//! the texture names it and scales it. Per vertex, its value at a hit is the blend of its
//! triangle's three corners by the hit's barycentrics; per face, the face's value.
//! Evaluating one needs the scene's attribute storage, which lies above this module: the
//! caller passes the value of an attribute slot ([`Param::eval`]'s `attribute`).

use super::Texture;
use std::sync::Arc;

/// A reference to a mesh attribute by name, times `scale`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// `vertex_...` or `face_...` (Mitsuba's naming, checked by the reader).
    pub name: String,
    pub scale: f32,
    /// The attribute's index in the scene's storage (set when the scene is built).
    pub slot: u32,
}

/// A material parameter: RGB, or one value repeated.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Const([f32; 3]),
    /// Looked up at the hit's texture coordinates.
    Texture(Arc<Texture>),
    Attribute(MeshAttribute),
}

impl Param {
    /// The value at texture coordinates (u, v); `attribute(slot)` is a mesh attribute's
    /// value at the hit.
    #[inline]
    pub fn eval(&self, u: f32, v: f32, attribute: &dyn Fn(u32) -> [f32; 3]) -> [f32; 3] {
        match self {
            Param::Const(c) => *c,
            Param::Texture(t) => t.lookup(u, v),
            Param::Attribute(a) => attribute(a.slot).map(|x| x * a.scale),
        }
    }

    /// Mitsuba's `eval_1`: the luminance (a grey value's value).
    #[inline]
    pub fn eval_1(&self, u: f32, v: f32, attribute: &dyn Fn(u32) -> [f32; 3]) -> f32 {
        luminance(self.eval(u, v, attribute))
    }

    /// A single value standing for the parameter where one is needed (albedo bounds):
    /// the constant, or a texture's mean texel; an attribute's is unknown here (1).
    pub fn mean(&self) -> [f32; 3] {
        match self {
            Param::Const(c) => *c,
            Param::Texture(t) => t.mean(),
            Param::Attribute(a) => [a.scale; 3],
        }
    }

    pub fn is_const(&self) -> bool {
        matches!(self, Param::Const(_))
    }
}

/// Rec. 709 luminance, as Mitsuba's `luminance` of linear RGB.
#[inline]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_evaluate_constants_textures_and_scaled_attributes() {
        let attr = |slot: u32| [slot as f32, 0.5, 0.25];
        assert_eq!(
            Param::Const([0.1, 0.2, 0.3]).eval(0.3, 0.4, &attr),
            [0.1, 0.2, 0.3]
        );
        let t = Texture::checkerboard([0.8; 3], [0.2; 3], [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let p = Param::Texture(Arc::new(t));
        // Mitsuba's uv (0.25, 0.25) is kalos' (0.25, 0.75): color0
        assert_eq!(p.eval_1(0.25, 0.75, &attr), 0.8);
        assert_eq!(p.mean(), [0.5; 3]);
        let a = Param::Attribute(MeshAttribute {
            name: "vertex_color".into(),
            scale: 2.0,
            slot: 3,
        });
        assert_eq!(a.eval(0.0, 0.0, &attr), [6.0, 1.0, 0.5]);
        assert!((a.eval_1(0.0, 0.0, &attr) - luminance([6.0, 1.0, 0.5])).abs() < 1e-6);
    }
}
