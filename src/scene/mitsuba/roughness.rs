//! A `roughconductor`'s anisotropic or textured roughness (`alpha_u`, `alpha_v`, each a
//! float or a texture) as `MaterialDesc::roughness`, which the scene applies per hit.

use super::*;
use crate::material::roughness::{Alpha, Roughness};
use crate::texture::Texture;
use std::sync::Arc;

impl<'a> Loader<'a> {
    /// The roughness of a `roughconductor` element when one constant alpha does not
    /// describe it: alpha_u != alpha_v, or either given as a texture; None otherwise
    /// (and for `alpha`, whose checks are `Loader::alpha`'s).
    pub(super) fn conductor_roughness(&self, el: &'a El) -> R<Option<Roughness>> {
        if self.prop(el, "alpha_u").is_none() || self.prop(el, "alpha_v").is_none() {
            return Ok(None);
        }
        let u = self.alpha_param(el, "alpha_u")?;
        let v = self.alpha_param(el, "alpha_v")?;
        if let (Alpha::Value(a), Alpha::Value(b)) = (&u, &v) {
            if a == b {
                return Ok(None);
            }
        }
        Ok(Some(Roughness {
            alpha_u: u,
            alpha_v: v,
        }))
    }

    /// One roughness parameter: a float, or a texture read as Mitsuba's `eval_1` reads it.
    fn alpha_param(&self, el: &'a El, name: &str) -> R<Alpha> {
        let missing = || format!("{}: roughconductor needs {name}", el.at);
        let p = self.prop(el, name).ok_or_else(missing)?;
        let at = p.at.clone();
        let texture = match p.tag.as_str() {
            "float" | "integer" => None,
            _ => match self.color_of(p, Use::Unbounded)?.scalar_lookup() {
                Color::Rgb(c) => return self.checked_alpha(name, &at, c[0]).map(Alpha::Value),
                Color::Bitmap(path, sampling) => {
                    let mut t =
                        Texture::load(&path).map_err(|e| format!("{at}: {name} texture: {e}"))?;
                    t.sampling = sampling;
                    Some(t)
                }
                Color::Procedural(t) => Some(t),
                Color::Attribute(_) => {
                    return Err(format!(
                        "{at}: {name}: a mesh attribute as a roughness is not supported; give a float or a texture"
                    ))
                }
            },
        };
        match texture {
            None => {
                let a = self.float(el, name)?.ok_or_else(missing)?;
                self.checked_alpha(name, &at, a).map(Alpha::Value)
            }
            Some(t) => {
                let t = Roughness::scalar_map(t);
                if let Some(bad) = t.texels.iter().find(|c| !(0.0..=10.0).contains(&c[0])) {
                    return Err(format!(
                        "{at}: roughconductor {name}: a texel of {}: must be in [0, 10]",
                        bad[0]
                    ));
                }
                Ok(Alpha::Map(Arc::new(t)))
            }
        }
    }

    fn checked_alpha(&self, name: &str, at: &str, a: f32) -> R<f32> {
        if (0.0..=10.0).contains(&a) {
            Ok(a)
        } else {
            Err(format!(
                "{at}: roughconductor {name} {a}: must be in [0, 10]"
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn conductor(alphas: &str) -> Result<SceneDesc, String> {
        parse(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"rectangle\"><bsdf type=\"roughconductor\">\n{alphas}\n</bsdf></shape>\n</scene>"
            ),
            "r.xml",
            Path::new("."),
        )
    }

    #[test]
    fn anisotropic_and_textured_roughness_is_read_and_not_warned() {
        let d = conductor(
            r#"<float name="alpha_u" value="0.25"/><float name="alpha_v" value="0.05"/>"#,
        )
        .unwrap();
        assert_eq!(
            d.materials[0].roughness,
            Some(Roughness {
                alpha_u: Alpha::Value(0.25),
                alpha_v: Alpha::Value(0.05)
            })
        );
        assert!(
            d.warnings.iter().all(|w| !w.contains("anisotropic")),
            "{:?}",
            d.warnings
        );
        // equal constants: the one isotropic alpha, nothing per hit
        let d =
            conductor(r#"<float name="alpha_u" value="0.2"/><float name="alpha_v" value="0.2"/>"#)
                .unwrap();
        assert_eq!(d.materials[0].roughness, None);
        // a checkerboard, read as Mitsuba's eval_1 reads it (color0 where the checks of u
        // and v differ)
        let d = conductor(
            r#"<texture name="alpha_u" type="checkerboard">
                <float name="color0" value="0.05"/><float name="color1" value="0.3"/></texture>
               <float name="alpha_v" value="0.1"/>"#,
        )
        .unwrap();
        let Some(Roughness {
            alpha_u: Alpha::Map(t),
            alpha_v: Alpha::Value(v),
        }) = &d.materials[0].roughness
        else {
            panic!("{:?}", d.materials[0].roughness)
        };
        assert_eq!(*v, 0.1);
        // Mitsuba's uv (0.25, 0.25) is kalos' (0.25, 0.75): both checks below 1/2
        assert_eq!(t.lookup(0.25, 0.75)[0], 0.3);
        assert_eq!(t.lookup(0.75, 0.75)[0], 0.05);
    }

    #[test]
    fn bad_roughness_is_one_line_naming_the_place() {
        for (alphas, needle) in [
            (
                r#"<float name="alpha_u" value="0.2"/><float name="alpha_v" value="x"/>"#,
                "r.xml:3: <float name=\"alpha_v\" value=\"x\">: not a number",
            ),
            (
                r#"<float name="alpha_u" value="0.2"/><float name="alpha_v" value="-1"/>"#,
                "must be in [0, 10]",
            ),
            (
                r#"<texture name="alpha_u" type="checkerboard"><float name="color0" value="20"/></texture><float name="alpha_v" value="0.1"/>"#,
                "must be in [0, 10]",
            ),
            (
                r#"<texture name="alpha_u" type="bitmap"><string name="filename" value="no-such.png"/></texture><float name="alpha_v" value="0.1"/>"#,
                "no-such.png",
            ),
            (
                r#"<texture name="alpha_u" type="mesh_attribute"><string name="name" value="vertex_alpha"/></texture><float name="alpha_v" value="0.1"/>"#,
                "alpha_u: a mesh attribute as a roughness is not supported",
            ),
        ] {
            let e = conductor(alphas).unwrap_err();
            assert!(e.contains(needle) && !e.contains('\n'), "{alphas}: {e}");
        }
    }
}
