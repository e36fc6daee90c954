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
            return Err(format!(
                "{}: mesh_attribute scale {scale}: not finite",
                p.at
            ));
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
                let mut t =
                    crate::texture::Texture::load(&path).map_err(|e| format!("{at}: {e}"))?;
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
            (None, Some(p), _) => {
                Some(self.mean_rgb(Color::Bitmap(p.clone(), d.kd_sampling), &at)?)
            }
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

    /// `principled` (or `principledthin` when `thin`): its parameters (values, textures or
    /// mesh attributes), `eta` or `specular` (principledthin: `eta`), the sampling rates.
    pub(super) fn principled(&self, el: &'a El, m: &mut MaterialDesc, thin: bool) -> R<()> {
        use crate::material::principled::eta_of_specular;
        use crate::material::varying::{PrincipledParams, NOT_THIN, PRINCIPLED_VALUES};
        let param = |name: &str, default: f32| -> R<Param> {
            match self.color(el, name, Use::Unbounded)? {
                None => Ok(Param::Const([default; 3])),
                // the colour by Mitsuba's `eval`, the scalars by its `eval_1`
                Some(c) if name == "base_color" => self.param(c, &el.at),
                Some(c) => self.param(c.scalar_lookup(), &el.at),
            }
        };
        let base_color = param("base_color", 0.5)?;
        let mut values = Vec::new();
        for (name, default) in PRINCIPLED_VALUES {
            let theirs = if thin {
                !NOT_THIN.contains(&name)
            } else {
                name != "diff_trans"
            };
            values.push(if theirs {
                param(name, default)?
            } else {
                Param::Const([default; 3])
            });
        }
        let values: [Param; 11] = values.try_into().expect("eleven values");
        // Mitsuba's flag: spec_trans given and not a float 0
        let spec_trans = &values[9];
        let has_trans =
            self.prop(el, "spec_trans").is_some() && *spec_trans != Param::Const([0.0; 3]);
        let kind = if thin { "principledthin" } else { "principled" };
        let eta = match (self.float(el, "eta")?, self.float(el, "specular")?) {
            (e, _) if thin => e.unwrap_or(1.5),
            (Some(_), Some(_)) => {
                return Err(format!(
                    "{}: principled: give either eta or specular, not both",
                    el.at
                ))
            }
            (Some(e), None) if has_trans && e == 1.0 => 1.001,
            (Some(e), None) => e,
            (None, s) => {
                let s = s.unwrap_or(0.5);
                eta_of_specular(if has_trans && s == 0.0 { 1e-3 } else { s })
            }
        };
        if !(eta.is_finite() && eta > 0.0) {
            return Err(format!(
                "{}: {kind}: eta {eta}: must be a positive number",
                el.at
            ));
        }
        let mut rates = [1.0f32; 4];
        let rate_names = if thin {
            [
                "specular_reflectance_sampling_rate",
                "specular_transmittance_sampling_rate",
                "diffuse_reflectance_sampling_rate",
                "diffuse_transmittance_sampling_rate",
            ]
        } else {
            [
                "main_specular_sampling_rate",
                "clearcoat_sampling_rate",
                "diffuse_reflectance_sampling_rate",
                "",
            ]
        };
        for (r, name) in rates.iter_mut().zip(rate_names) {
            if let Some(v) = self.float(el, name)? {
                *r = v;
            }
        }
        let p = PrincipledParams {
            base_color,
            values,
            eta,
            rates,
            thin,
        };
        m.kd = p.base_color.mean();
        m.model = Some(SurfaceModel::Principled(Box::new(p)));
        Ok(())
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

#[cfg(test)]
#[path = "principled_tests.rs"]
mod principled_tests;

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(body: &str) -> Result<SceneDesc, String> {
        parse(
            &format!("<scene version=\"3.0.0\">\n{body}\n</scene>"),
            "t.xml",
            Path::new("."),
        )
    }

    const SHAPE: &str = "<shape type=\"rectangle\"><ref id=\"b\"/></shape>";

    /// A blendbsdf reads its weight (a value, a texture or a mesh attribute) and its two
    /// nested BSDFs in the file's order; a diffuse reflectance may be a mesh attribute.
    #[test]
    fn blendbsdf_and_mesh_attribute_are_read() {
        let d = scene(&format!(
            "<bsdf type=\"blendbsdf\" id=\"b\"><float name=\"weight\" value=\"0.3\"/>\
             <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0 0.5 0.5\"/></bsdf>\
             <bsdf type=\"roughconductor\"/></bsdf>{SHAPE}"
        ))
        .unwrap();
        let Some(SurfaceModel::Blend { weight, bsdfs }) = &d.materials[0].model else {
            panic!("{:?}", d.materials[0].model)
        };
        assert_eq!(*weight, Param::Const([0.3; 3]));
        assert_eq!(bsdfs[0].kd, [0.0, 0.5, 0.5]);
        assert!(matches!(
            bsdfs[1].model,
            Some(SurfaceModel::Conductor { .. })
        ));
        let d = scene(&format!(
            "<texture type=\"mesh_attribute\" id=\"t\"><string name=\"name\" value=\"face_weight\"/>\
             <float name=\"scale\" value=\"2\"/></texture>\
             <bsdf type=\"blendbsdf\" id=\"b\"><ref name=\"weight\" id=\"t\"/>\
             <bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>{SHAPE}"
        ))
        .unwrap();
        let Some(SurfaceModel::Blend { weight, .. }) = &d.materials[0].model else {
            panic!()
        };
        let Param::Attribute(a) = weight else {
            panic!("{weight:?}")
        };
        assert_eq!((a.name.as_str(), a.scale), ("face_weight", 2.0));
        let d = scene(&format!(
            "<bsdf type=\"diffuse\" id=\"b\"><texture type=\"mesh_attribute\" name=\"reflectance\">\
             <string name=\"name\" value=\"vertex_color\"/></texture></bsdf>{SHAPE}"
        ))
        .unwrap();
        assert_eq!(
            d.materials[0].kd_attribute.as_ref().unwrap().name,
            "vertex_color"
        );
    }

    /// Bad input: one line naming the place and what is wrong.
    #[test]
    fn bad_blends_and_attributes_are_refused() {
        for (body, needle) in [
            (
                "<bsdf type=\"blendbsdf\" id=\"b\"><bsdf type=\"diffuse\"/></bsdf>",
                "needs two nested bsdfs, it has 1",
            ),
            (
                "<bsdf type=\"diffuse\" id=\"b\"><texture type=\"mesh_attribute\" name=\"reflectance\">\
                 <string name=\"name\" value=\"color\"/></texture></bsdf>",
                "must start with \"vertex_\" or \"face_\"",
            ),
            (
                "<bsdf type=\"diffuse\" id=\"b\"><texture type=\"mesh_attribute\" name=\"reflectance\"/></bsdf>",
                "mesh_attribute texture without a name",
            ),
            (
                "<bsdf type=\"blendbsdf\" id=\"b\"><float name=\"weight\" value=\"x\"/>\
                 <bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>",
                "t.xml:",
            ),
        ] {
            let e = scene(&format!("{body}{SHAPE}")).unwrap_err();
            assert!(e.contains(needle) && e.starts_with("t.xml:") && !e.contains('\n'), "{e}");
        }
        // an attribute no mesh has: refused when the scene is built
        let d = scene(&format!(
            "<bsdf type=\"diffuse\" id=\"b\"><texture type=\"mesh_attribute\" name=\"reflectance\">\
             <string name=\"name\" value=\"vertex_color\"/></texture></bsdf>{SHAPE}"
        ))
        .unwrap();
        let e = crate::scene::Scene::build(d, 0.0).err().unwrap();
        assert!(
            e.contains("mesh_attribute \"vertex_color\": no mesh of the scene has this attribute")
                && e.starts_with("t.xml:"),
            "{e}"
        );
    }
}
