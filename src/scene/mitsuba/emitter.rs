//! Mitsuba's emitters: area (on a shape), point, spot, directional, constant and envmap.

use super::*;

/// An emitter's radiance or intensity when the file gives none: Mitsuba's default 1.0
/// (its `texture_d65`, which in RGB mode is white (1, 1, 1), not an equal-energy spectrum).
pub(super) const UNIT_EMISSION: [f32; 3] = [1.0; 3];

impl<'a> Loader<'a> {
    /// Mitsuba's projector: a point light at the origin of `to_world` that projects its
    /// `irradiance` (a bitmap, or a constant over the whole frustum) through a pinhole of
    /// field of view `fov` (or `focal_length`) along `fov_axis` of the image, times
    /// `scale`; a spot whose cone is the frustum (see `light::Spot`).
    fn projector(&mut self, el: &'a El) -> R<()> {
        let xf = self.transform(el, "to_world")?;
        let scale = self.float(el, "scale")?.unwrap_or(1.0);
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!(
                "{}: projector emitter: scale {scale}: must be a finite number >= 0",
                el.at
            ));
        }
        let (intensity, texture, (w, h)) = match self.color(el, "irradiance", Use::Unbounded)? {
            None => (UNIT_EMISSION, None, (1, 1)),
            Some(Color::Rgb(c)) => (c, None, (1, 1)),
            Some(Color::Procedural(_) | Color::Attribute(_)) => {
                return Err(format!(
                    "{}: projector emitter: irradiance: a bitmap or a constant is expected",
                    el.at
                ))
            }
            Some(Color::Bitmap(p, _)) => {
                let t = crate::scene::Texture::load(&p)
                    .map_err(|e| format!("{}: projector emitter: {e}", el.at))?;
                (UNIT_EMISSION, Some(p), (t.width, t.height))
            }
        };
        // the image's field of view, as a camera of the image's resolution has it
        let (fov, fov_axis) = self.fov(el, w, h)?;
        let cam = CameraDesc {
            fov,
            fov_axis,
            ..CameraDesc::default()
        };
        let ty = cam.tan_half_vertical(w, h);
        let tx = ty * w as f32 / h as f32;
        let rot = Mat3::from_mat4(xf);
        if rot.determinant().abs() < 1e-12 {
            return Err(format!(
                "{}: projector emitter: its to_world is not invertible",
                el.at
            ));
        }
        self.desc.point_lights.push(PointLightDesc {
            position: xf.transform_point3(Vec3::ZERO),
            intensity: intensity.map(|c| c * scale),
            shape: PointLightShape::Spot {
                to_world: rot,
                cutoff: 90.0,
                beam_width: 90.0,
                texture,
                frustum: Some([tx, ty]),
            },
            source: Some(el.at.clone()),
        });
        Ok(())
    }

    /// An area emitter's radiance: a constant, or a bitmap or checkerboard looked up at
    /// the shape's uv (with its mean, for the choice among lights by power); a mesh
    /// attribute is rendered with its scale, warned.
    pub(super) fn area_radiance(
        &mut self,
        e: &'a El,
    ) -> R<([f32; 3], Option<std::sync::Arc<crate::scene::Texture>>)> {
        let texture = match self.color(e, "radiance", Use::Unbounded)? {
            None => return Err(format!("{}: area emitter without a radiance", e.at)),
            Some(Color::Rgb(v)) => return Ok((v, None)),
            Some(Color::Bitmap(p, sampling)) => {
                let mut t = crate::scene::Texture::load(&p)
                    .map_err(|m| format!("{}: area emitter: {m}", e.at))?;
                t.sampling = sampling;
                t
            }
            Some(Color::Procedural(t)) => t,
            Some(c @ Color::Attribute(_)) => {
                self.warn(
                    "texture in area emitter radiance",
                    format!(
                        "{}: a mesh attribute as area emitter 'radiance' is not supported: rendered with its scale",
                        e.at
                    ),
                );
                return Ok((self.mean_rgb(c, &e.at)?, None));
            }
        };
        Ok((texture.mean(), Some(std::sync::Arc::new(texture))))
    }

    pub(super) fn emitter(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("emitter", kind) {
            return Err(format!("{}: unknown emitter plugin '{kind}'", el.at));
        }
        match kind {
            "point" => {
                let xf = self.transform(el, "to_world")?;
                let p = self
                    .point(el, "position")?
                    .unwrap_or_else(|| xf.transform_point3(Vec3::ZERO));
                let intensity = self
                    .constant(el, "intensity", Use::Unbounded, "point emitter")?
                    .unwrap_or(UNIT_EMISSION);
                self.desc.point_lights.push(PointLightDesc {
                    position: p,
                    intensity,
                    shape: PointLightShape::Isotropic,
                    source: Some(el.at.clone()),
                });
            }
            "spot" => {
                use crate::light::Spot;
                let xf = self.transform(el, "to_world")?;
                let intensity = self
                    .constant(el, "intensity", Use::Unbounded, "spot emitter")?
                    .unwrap_or(UNIT_EMISSION);
                let cutoff = self
                    .float(el, "cutoff_angle")?
                    .unwrap_or(Spot::DEFAULT_CUTOFF_DEGREES);
                let beam_width = self
                    .float(el, "beam_width")?
                    .unwrap_or(cutoff * Spot::DEFAULT_BEAM_SHARE);
                let texture = match self.color(el, "texture", Use::Reflectance)? {
                    None => None,
                    Some(Color::Bitmap(p, _)) => Some(p),
                    Some(Color::Rgb(c)) => {
                        return Err(format!(
                            "{}: spot emitter: texture {c:?}: a bitmap is expected (scale the intensity instead)",
                            el.at
                        ))
                    }
                    Some(Color::Procedural(_) | Color::Attribute(_)) => {
                        return Err(format!(
                            "{}: spot emitter: texture: a bitmap is expected",
                            el.at
                        ))
                    }
                };
                self.desc.point_lights.push(PointLightDesc {
                    position: xf.transform_point3(Vec3::ZERO),
                    intensity,
                    shape: PointLightShape::Spot {
                        to_world: Mat3::from_mat4(xf),
                        cutoff,
                        beam_width,
                        texture,
                        frustum: None,
                    },
                    source: Some(el.at.clone()),
                });
            }
            "projector" => self.projector(el)?,
            "directional" => {
                let xf = self.transform(el, "to_world")?;
                let irradiance = self
                    .constant(el, "irradiance", Use::Unbounded, "directional emitter")?
                    .unwrap_or(UNIT_EMISSION);
                // Mitsuba: `direction` if given, else +z of to_world
                let dir = match self.prop(el, "direction") {
                    Some(p) => self.vec3_attr(p, "direction")?,
                    None => xf.transform_vector3(Vec3::Z),
                };
                if !(dir.length_squared() > 0.0 && dir.is_finite()) {
                    return Err(format!(
                        "{}: directional emitter: the direction {dir} has no length",
                        el.at
                    ));
                }
                self.desc.point_lights.push(PointLightDesc {
                    position: Vec3::ZERO,
                    intensity: irradiance,
                    shape: PointLightShape::Directional(dir.normalize()),
                    source: Some(el.at.clone()),
                });
            }
            "constant" | "envmap" => {
                let xf = self.transform(el, "to_world")?;
                let (radiance, map) = if kind == "constant" {
                    let r = self
                        .constant(el, "radiance", Use::Unbounded, "constant emitter")?
                        .unwrap_or(UNIT_EMISSION);
                    (r, None)
                } else {
                    let f = self
                        .string(el, "filename")?
                        .ok_or_else(|| format!("{}: envmap without a filename", el.at))?;
                    let path = self.path(&f);
                    check_image(&path).map_err(|e| format!("{}: envmap: {e}", el.at))?;
                    let s = self.float(el, "scale")?.unwrap_or(1.0);
                    (([s; 3]), Some(path))
                };
                let rot = Mat3::from_mat4(xf);
                let env = EnvironmentDesc {
                    radiance,
                    map,
                    to_world: rot,
                    source: Some(el.at.clone()),
                };
                if self.desc.environment.is_some() {
                    self.warn(
                        "second environment",
                        format!(
                            "{}: a second environment emitter: kalos keeps the first",
                            el.at
                        ),
                    );
                } else {
                    self.desc.environment = Some(env);
                }
            }
            "area" => {
                return Err(format!(
                    "{}: an area emitter must be inside a <shape>",
                    el.at
                ))
            }
            k => {
                self.mark_all(el);
                self.warn(
                    &format!("emitter {k}"),
                    format!(
                        "{}: unsupported emitter '{k}': left out of the scene",
                        el.at
                    ),
                );
                return Ok(());
            }
        }
        self.unused(el, &format!("emitter '{kind}'"));
        Ok(())
    }
}

/// Refuse an environment map that is not an image kalos or Mitsuba reads (by its first
/// bytes: EXR, Radiance HDR, PFM, PNG, JPEG).
pub(super) fn check_image(path: &Path) -> R<()> {
    crate::input::check_regular_file(path, crate::input::max_input_bytes()?)?;
    let mut head = [0u8; 16];
    let n = {
        use std::io::Read;
        let mut f = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        f.read(&mut head)
            .map_err(|e| format!("{}: {e}", path.display()))?
    };
    let h = &head[..n];
    let ok = h.starts_with(&[0x76, 0x2f, 0x31, 0x01])
        || h.starts_with(b"#?RADIANCE")
        || h.starts_with(b"#?RGBE")
        || h.starts_with(b"PF\n")
        || h.starts_with(b"Pf\n")
        || h.starts_with(b"\x89PNG")
        || h.starts_with(&[0xff, 0xd8, 0xff]);
    if ok {
        Ok(())
    } else {
        Err(format!(
            "{}: not an image (expected EXR, HDR, PFM, PNG or JPEG data)",
            path.display()
        ))
    }
}
