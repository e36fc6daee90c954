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
            _ => match self.color_of(p, Use::Unbounded)? {
                Color::Rgb(c) => return self.checked_alpha(name, &at, c[0]).map(Alpha::Value),
                Color::Bitmap(path, sampling) => {
                    let mut t =
                        Texture::load(&path).map_err(|e| format!("{at}: {name} texture: {e}"))?;
                    t.sampling = sampling;
                    Some(t)
                }
                // Mitsuba's checkerboard (the one procedural texture): its eval_1, which a
                // roughness reads, takes color0 where its colour lookup takes color1
                Color::Procedural(t) if t.texels.len() == 4 => Some(Texture::checkerboard(
                    t.texels[1],
                    t.texels[0],
                    t.sampling.to_uv,
                )),
                Color::Procedural(t) => Some(t),
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
            Err(format!("{at}: roughconductor {name} {a}: must be in [0, 10]"))
        }
    }
}
