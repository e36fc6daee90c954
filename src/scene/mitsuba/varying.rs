//! Mitsuba's plugins whose parameters vary over a surface: the `mesh_attribute` texture
//! and `blendbsdf`.

use super::*;
use crate::texture::mesh_attribute::{MeshAttribute, Param};

impl<'a> Loader<'a> {
    /// A `mesh_attribute` texture element: its attribute's name and scale.
    pub(super) fn mesh_attribute(&self, p: &'a El) -> R<MeshAttribute> {
        let name = self
            .string(p, "name")?
            .ok_or_else(|| format!("{}: mesh_attribute texture without a name", p.at))?;
        if !(name.starts_with("vertex_") || name.starts_with("face_")) {
            return Err(format!(
                "{}: mesh_attribute name \"{name}\": must start with \"vertex_\" or \"face_\"",
                p.at
            ));
        }
        let scale = self.float(p, "scale")?.unwrap_or(1.0);
        if !scale.is_finite() {
            return Err(format!("{}: mesh_attribute scale {scale}: not finite", p.at));
        }
        self.unused(p, "texture 'mesh_attribute'");
        Ok(MeshAttribute {
            name,
            scale,
            slot: u32::MAX,
        })
    }

    /// A colour or value as a per-hit parameter (a bitmap is read now).
    pub(super) fn param(&self, c: Color, at: &str) -> R<Param> {
        Ok(match c {
            Color::Rgb(v) => Param::Const(v),
            Color::Procedural(t) => Param::Texture(std::sync::Arc::new(t)),
            Color::Bitmap(path, sampling) => {
                let mut t = crate::texture::Texture::load(&path).map_err(|e| format!("{at}: {e}"))?;
                t.sampling = sampling;
                Param::Texture(std::sync::Arc::new(t))
            }
            Color::Attribute(a) => Param::Attribute(a),
        })
    }

    /// A nested BSDF as constants: a texture gives its mean (noted on `outer`).
    fn constant_nested(&self, mut d: MaterialDesc, outer: &mut MaterialDesc) -> R<MaterialDesc> {
        let at = d.source.clone().unwrap_or_default();
        let mean = match (&d.kd_procedural, &d.map_kd, &d.kd_attribute) {
            (Some(t), _, _) => Some(t.mean()),
            (None, Some(p), _) => Some(self.mean_rgb(Color::Bitmap(p.clone(), d.kd_sampling), &at)?),
            (None, None, Some(a)) => Some([a.scale; 3]),
            _ => None,
        };
        if let Some(m) = mean {
            d.kd = [0, 1, 2].map(|i| d.kd[i] * m[i]);
            (d.kd_procedural, d.map_kd, d.kd_attribute) = (None, None, None);
            outer.notes.push(format!(
                "{at}: a texture in a blendbsdf's nested bsdf is rendered with its mean"
            ));
        }
        Ok(d)
    }

    /// `blendbsdf`: two nested BSDFs (in the file's order) and a weight.
    pub(super) fn blend(&self, el: &'a El, name: String) -> R<MaterialDesc> {
        let nested: Vec<&'a El> = el
            .children
            .iter()
            .filter(|c| {
                c.tag == "bsdf"
                    || (c.tag == "ref" && self.resolve(c).map(|r| r.tag == "bsdf").unwrap_or(false))
            })
            .collect();
        if nested.len() != 2 {
            return Err(format!(
                "{}: blendbsdf needs two nested bsdfs, it has {}",
                el.at,
                nested.len()
            ));
        }
        let mut m = MaterialDesc::named(&name);
        m.source = Some(el.at.clone());
        let mut bsdfs = Vec::new();
        for c in nested {
            c.used.set(true);
            let d = self.bsdf(c)?;
            bsdfs.push(self.constant_nested(d, &mut m)?);
        }
        let weight = match self.color(el, "weight", Use::Reflectance)? {
            None => Param::Const([0.5; 3]),
            Some(c) => self.param(c, &el.at)?,
        };
        m.kd = [0.0; 3];
        m.one_sided = bsdfs.iter().all(|b| b.one_sided);
        let [a, b]: [MaterialDesc; 2] = bsdfs.try_into().expect("two nested bsdfs");
        m.model = Some(SurfaceModel::Blend {
            weight,
            bsdfs: Box::new([a, b]),
        });
        self.unused(el, "bsdf 'blendbsdf'");
        Ok(m)
    }
}
