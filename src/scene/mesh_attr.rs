//! Mesh attributes in a scene (Mitsuba's `vertex_*` and `face_*` attributes, read from
//! PLY files): per attribute name, its three corner values on the triangles whose mesh
//! has it ([`TriAttr`]: nothing stored for the others; a scene without attributes stores
//! nothing at all).

use super::tri_attr::TriAttr;
use super::SceneDesc;
use crate::scene::ply::PlyAttribute;

/// An attribute as the scene files give it, on the description's triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AttributeDesc {
    pub name: String,
    pub per_face: bool,
    /// (triangle index in the description, corner values).
    pub tris: Vec<(u32, [[f32; 3]; 3])>,
}

/// The scene's attributes, looked up by slot (a `MeshAttribute`'s index).
#[derive(Clone, Debug, Default)]
pub struct Attributes {
    pub names: Vec<String>,
    per_face: Vec<bool>,
    values: Vec<TriAttr<[[f32; 3]; 3]>>,
}

impl Attributes {
    pub fn new(descs: &[AttributeDesc], triangles: usize) -> Attributes {
        let mut a = Attributes::default();
        for d in descs {
            let mut per_tri = vec![None; triangles];
            for &(t, v) in &d.tris {
                if let Some(slot) = per_tri.get_mut(t as usize) {
                    *slot = Some(v);
                }
            }
            a.names.push(d.name.clone());
            a.per_face.push(d.per_face);
            a.values.push(TriAttr::from_options(per_tri));
        }
        a
    }

    /// The slot of attribute `name`, if some mesh has it.
    pub fn slot(&self, name: &str) -> Option<u32> {
        self.names.iter().position(|n| n == name).map(|i| i as u32)
    }

    /// Attribute `slot` on triangle `prim` at barycentrics (b1, b2); 0 on a triangle
    /// whose mesh lacks it.
    #[inline]
    pub fn eval(&self, slot: u32, prim: u32, b1: f32, b2: f32) -> [f32; 3] {
        let Some(c) = self
            .values
            .get(slot as usize)
            .and_then(|v| v.get(prim as usize))
        else {
            return [0.0; 3];
        };
        if self.per_face[slot as usize] {
            return c[0];
        }
        let b0 = 1.0 - b1 - b2;
        [0, 1, 2].map(|k| b0 * c[0][k] + b1 * c[1][k] + b2 * c[2][k])
    }
}

impl SceneDesc {
    /// Record a mesh's attributes on the description's triangle `tri`, made of the mesh's
    /// vertices `corners` (in the triangle's order) and its triangle `face`.
    pub fn push_attributes(
        &mut self,
        attrs: &[PlyAttribute],
        tri: usize,
        corners: [usize; 3],
        face: usize,
    ) {
        for a in attrs {
            let i = match self.attributes.iter().position(|d| d.name == a.name) {
                Some(i) => i,
                None => {
                    self.attributes.push(AttributeDesc {
                        name: a.name.clone(),
                        per_face: a.per_face,
                        tris: Vec::new(),
                    });
                    self.attributes.len() - 1
                }
            };
            let get = |k: usize| a.values.get(k).copied().unwrap_or([0.0; 3]);
            let v = if a.per_face {
                [get(face); 3]
            } else {
                corners.map(get)
            };
            self.attributes[i].tris.push((tri as u32, v));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertex attributes blend by the barycentrics, face attributes are constant, a
    /// triangle of a mesh without the attribute reads 0.
    #[test]
    fn vertex_attributes_interpolate_and_face_attributes_are_constant() {
        let mut d = SceneDesc::default();
        let colours = PlyAttribute {
            name: "vertex_color".into(),
            per_face: false,
            values: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let weight = PlyAttribute {
            name: "face_weight".into(),
            per_face: true,
            values: vec![[0.25; 3]],
        };
        d.push_attributes(&[colours, weight], 1, [0, 2, 1], 0);
        let a = Attributes::new(&d.attributes, 2);
        let (c, w) = (
            a.slot("vertex_color").unwrap(),
            a.slot("face_weight").unwrap(),
        );
        // corners in the triangle's order: v0 red, v1 blue (vertex 2), v2 green
        let v = a.eval(c, 1, 0.25, 0.5);
        assert_eq!(v, [0.25, 0.5, 0.25]);
        assert_eq!(a.eval(w, 1, 0.3, 0.3), [0.25; 3]);
        assert_eq!(a.eval(c, 0, 0.3, 0.3), [0.0; 3], "triangle 0 has none");
        assert!(a.slot("vertex_normal").is_none());
    }
}
