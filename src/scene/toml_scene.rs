//! TOML scene files: OBJ files with optional transforms, a camera, material overrides
//! by name and render defaults.
//!
//! ```toml
//! [camera]
//! origin = [0, 0, 3.9]
//! target = [0, 0, 0]
//! up = [0, 1, 0]
//! fov = 39.3077
//!
//! [render]
//! res = [256, 256]
//! spp = 64
//! max_depth = -1
//!
//! [[objects]]
//! file = "cornell-box.obj"
//! translate = [0, 0, 0]
//! rotate = [0, 30, 0]   # degrees about x, then y, then z
//! scale = 1.0           # or [sx, sy, sz]
//!
//! [materials.white]      # override fields of the material named "white"
//! kd = [0.8, 0.8, 0.8]
//! ks = [0.2, 0.2, 0.2]
//! ns = 30
//! ```

use super::{CameraDesc, RenderDefaults, SceneDesc};
use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: Option<CameraDesc>,
    render: Option<RenderSection>,
    #[serde(default)]
    objects: Vec<ObjectSection>,
    #[serde(default)]
    materials: BTreeMap<String, MaterialOverride>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderSection {
    res: Option<[u32; 2]>,
    spp: Option<u32>,
    max_depth: Option<i32>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectSection {
    file: String,
    translate: Option<[f32; 3]>,
    rotate: Option<[f32; 3]>,
    scale: Option<Scale>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialOverride {
    kd: Option<[f32; 3]>,
    ks: Option<[f32; 3]>,
    ke: Option<[f32; 3]>,
    ns: Option<f32>,
    ni: Option<f32>,
    illum: Option<u8>,
}

pub fn load(path: &Path) -> Result<SceneDesc, String> {
    let file = path.display().to_string();
    let text = crate::input::read_text(path)?;
    parse(&text, &file, path.parent().unwrap_or(Path::new(".")))
}

/// First line of a TOML error, with the file name and line.
/// One-line message for a TOML error: `file:line: message`.
pub fn toml_error(file: &str, text: &str, e: toml::de::Error) -> String {
    // 1 + the newlines before the span (the span may start a line, or not be on a
    // char boundary, so count bytes rather than `lines()` of a slice)
    let line = e.span().map(|s| {
        let before = &text.as_bytes()[..s.start.min(text.len())];
        before.iter().filter(|&&b| b == b'\n').count() + 1
    });
    let msg = e.message().replace('\n', " ");
    match line {
        Some(l) => format!("{file}:{l}: {msg}"),
        None => format!("{file}: {msg}"),
    }
}

pub fn parse(text: &str, file: &str, dir: &Path) -> Result<SceneDesc, String> {
    let text = &*crate::input::clean_text(text);
    let sf: SceneFile = toml::from_str(text).map_err(|e| toml_error(file, text, e))?;
    if sf.objects.is_empty() {
        return Err(format!(
            "{file}: no [[objects]]: a scene needs at least one OBJ file"
        ));
    }
    let mut desc = SceneDesc {
        name: Path::new(file)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(file)
            .to_string(),
        ..Default::default()
    };
    for o in &sf.objects {
        let t = Vec3::from(o.translate.unwrap_or([0.0; 3]));
        let r = o.rotate.unwrap_or([0.0; 3]);
        let s = match o.scale {
            None => Vec3::ONE,
            Some(Scale::Uniform(k)) => Vec3::splat(k),
            Some(Scale::Axes(a)) => Vec3::from(a),
        };
        if !(t.is_finite() && s.is_finite() && r.iter().all(|x| x.is_finite()))
            || s.abs().min_element() == 0.0
        {
            return Err(format!(
                "{file}: object {}: transform values must be finite and scale non-zero",
                o.file
            ));
        }
        let q = Quat::from_euler(
            EulerRot::ZYX,
            r[2].to_radians(),
            r[1].to_radians(),
            r[0].to_radians(),
        );
        let xf = Mat4::from_scale_rotation_translation(s, q, t);
        let p = super::mtl::normalise_path(dir, &o.file);
        crate::input::check_regular_file(&p, crate::input::max_input_bytes()?)
            .map_err(|e| format!("{file}: object file {e}"))?;
        super::obj::load_obj_file(&p, xf, &mut desc)?;
    }
    for (name, ov) in &sf.materials {
        let mut found = false;
        for m in desc.materials.iter_mut().filter(|m| &m.name == name) {
            found = true;
            let check = |v: &[f32], what: &str| -> Result<(), String> {
                if v.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    Err(format!(
                        "{file}: materials.{name}.{what}: values must be finite and non-negative"
                    ))
                } else {
                    Ok(())
                }
            };
            if let Some(v) = ov.kd {
                check(&v, "kd")?;
                m.kd = v;
            }
            if let Some(v) = ov.ks {
                check(&v, "ks")?;
                m.ks = v;
            }
            if let Some(v) = ov.ke {
                check(&v, "ke")?;
                m.ke = v;
            }
            if let Some(v) = ov.ns {
                check(&[v], "ns")?;
                m.ns = v;
            }
            if let Some(v) = ov.ni {
                check(&[v], "ni")?;
                m.ni = v;
            }
            if let Some(v) = ov.illum {
                m.illum = v;
                if v > 10 {
                    m.notes.push(format!(
                        "illum {v} (from {file} materials.{name}) is not an MTL illumination model (0 to 10): rendered as diffuse + glossy from Kd and Ks"
                    ));
                }
            }
            if (ov.illum.is_some() || ov.ni.is_some()) && m.illum == 7 && m.ni <= 0.0 {
                m.notes.push(format!(
                    "glass (illum 7) with Ni {} (from {file} materials.{name}): an index of refraction must be positive; rendered with 1.5",
                    m.ni
                ));
            }
        }
        if !found {
            return Err(format!(
                "{file}: materials.{name}: no material of that name in the scene"
            ));
        }
    }
    if let Some(c) = sf.camera {
        c.validate().map_err(|e| format!("{file}: [camera]: {e}"))?;
        desc.camera = Some(c);
    }
    if let Some(r) = sf.render {
        if let Some([w, h]) = r.res {
            crate::film::check_resolution(w, h)
                .map_err(|e| format!("{file}: [render] res: {e}"))?;
        }
        if r.spp == Some(0) {
            return Err(format!("{file}: [render] spp: must be at least 1"));
        }
        if let Some(d) = r.max_depth {
            if d < -1 || d == 0 {
                return Err(format!(
                    "{file}: [render] max_depth: {d}: must be -1 (unlimited) or at least 1"
                ));
            }
        }
        desc.defaults = RenderDefaults {
            res: r.res.map(|[w, h]| (w, h)),
            spp: r.spp,
            max_depth: r.max_depth,
        };
    }
    Ok(desc)
}
