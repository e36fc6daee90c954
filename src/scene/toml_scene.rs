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
//!
//! [materials.ball]       # a Mitsuba surface model instead of the MTL one
//! model = { type = "roughplastic", eta = 1.49, alpha = 0.1 }   # kd: the base
//! # conductor / roughconductor: eta, k (RGB, default the perfect mirror 0 + 1i),
//! #   specular, alpha; plastic / roughplastic: eta, specular, alpha, nonlinear;
//! # dielectric / roughdielectric: eta, alpha; thindielectric: eta.
//! # (alpha defaults to 0.1 for the rough ones, as in Mitsuba; the rough ones also take
//! # distribution = "ggx" (the default here) or "beckmann" (Mitsuba's default))
//!
//! [environment]          # light from far away (Mitsuba's constant / envmap)
//! radiance = [1, 1, 1]   # constant radiance, or the scale of the map
//! map = "sky.exr"        # optional: equirectangular EXR, HDR or PNG, Mitsuba's uv
//! rotate = [0, 90, 0]    # degrees about x, then y, then z (Mitsuba's to_world)
//!
//! [[point_lights]]
//! position = [0, 2, 0]
//! intensity = [10, 10, 10]   # W/sr
//! ```

use super::{CameraDesc, RenderDefaults, SceneDesc};
use crate::material::dielectric::Tint;
use crate::material::Distribution;
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
    environment: Option<EnvironmentSection>,
    #[serde(default)]
    point_lights: Vec<PointLightSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentSection {
    radiance: Option<[f32; 3]>,
    map: Option<String>,
    rotate: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightSection {
    position: [f32; 3],
    intensity: [f32; 3],
}

/// Mitsuba's surface models by plugin name.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum ModelSection {
    Conductor {
        eta: Option<[f32; 3]>,
        k: Option<[f32; 3]>,
        specular: Option<[f32; 3]>,
    },
    RoughConductor {
        eta: Option<[f32; 3]>,
        k: Option<[f32; 3]>,
        specular: Option<[f32; 3]>,
        alpha: Option<f32>,
        distribution: Option<Distribution>,
    },
    Plastic {
        eta: Option<f32>,
        specular: Option<[f32; 3]>,
        nonlinear: Option<bool>,
    },
    RoughPlastic {
        eta: Option<f32>,
        specular: Option<[f32; 3]>,
        alpha: Option<f32>,
        distribution: Option<Distribution>,
        nonlinear: Option<bool>,
    },
    Dielectric {
        eta: Option<f32>,
    },
    RoughDielectric {
        eta: Option<f32>,
        alpha: Option<f32>,
        distribution: Option<Distribution>,
    },
    ThinDielectric {
        eta: Option<f32>,
    },
}

/// Mitsuba's default roughness.
const DEFAULT_ALPHA: f32 = 0.1;
/// The distribution of a rough model that names none (GGX, kalos' first one; Mitsuba's
/// XML default is Beckmann, which the Mitsuba reader keeps).
const DEFAULT_DISTRIBUTION: Distribution = Distribution::Ggx;

impl ModelSection {
    fn model(&self) -> super::SurfaceModel {
        use super::SurfaceModel as M;
        let one = Some([1.0f32; 3]);
        match *self {
            ModelSection::Conductor { eta, k, specular } => M::Conductor {
                eta: eta.unwrap_or([0.0; 3]),
                k: k.unwrap_or([1.0; 3]),
                specular: specular.or(one).unwrap(),
                alpha: 0.0,
                distribution: DEFAULT_DISTRIBUTION,
            },
            ModelSection::RoughConductor {
                eta,
                k,
                specular,
                alpha,
                distribution,
            } => M::Conductor {
                eta: eta.unwrap_or([0.0; 3]),
                k: k.unwrap_or([1.0; 3]),
                specular: specular.or(one).unwrap(),
                alpha: alpha.unwrap_or(DEFAULT_ALPHA),
                distribution: distribution.unwrap_or(DEFAULT_DISTRIBUTION),
            },
            ModelSection::Plastic {
                eta,
                specular,
                nonlinear,
            } => M::Plastic {
                eta: eta.unwrap_or(1.49),
                specular: specular.or(one).unwrap(),
                alpha: 0.0,
                distribution: DEFAULT_DISTRIBUTION,
                nonlinear: nonlinear.unwrap_or(false),
            },
            ModelSection::RoughPlastic {
                eta,
                specular,
                alpha,
                distribution,
                nonlinear,
            } => M::Plastic {
                eta: eta.unwrap_or(1.49),
                specular: specular.or(one).unwrap(),
                alpha: alpha.unwrap_or(DEFAULT_ALPHA),
                distribution: distribution.unwrap_or(DEFAULT_DISTRIBUTION),
                nonlinear: nonlinear.unwrap_or(false),
            },
            ModelSection::Dielectric { eta } => M::Dielectric {
                eta: eta.unwrap_or(1.5),
                alpha: 0.0,
                distribution: DEFAULT_DISTRIBUTION,
                tint: Tint::NONE,
            },
            ModelSection::RoughDielectric {
                eta,
                alpha,
                distribution,
            } => M::Dielectric {
                eta: eta.unwrap_or(1.5),
                alpha: alpha.unwrap_or(DEFAULT_ALPHA),
                distribution: distribution.unwrap_or(DEFAULT_DISTRIBUTION),
                tint: Tint::NONE,
            },
            ModelSection::ThinDielectric { eta } => M::ThinDielectric {
                eta: eta.unwrap_or(1.5),
                tint: Tint::NONE,
            },
        }
    }

    /// A rough model's alpha must be positive (0 is the smooth plugin).
    fn check(&self) -> Result<(), String> {
        match *self {
            ModelSection::RoughConductor { alpha: Some(a), .. }
            | ModelSection::RoughPlastic { alpha: Some(a), .. }
            | ModelSection::RoughDielectric { alpha: Some(a), .. }
                if a.is_nan() || a <= 0.0 =>
            {
                Err(format!(
                    "alpha {a}: a rough model needs alpha > 0 (use the smooth model for 0)"
                ))
            }
            _ => Ok(()),
        }
    }
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
    model: Option<ModelSection>,
}

pub fn load(path: &Path) -> Result<SceneDesc, String> {
    let file = path.display().to_string();
    let text = crate::input::read_text(path)?;
    parse(&text, &file, path.parent().unwrap_or(Path::new(".")))
}

/// The 1-based number of the `nth` line (0-based) whose trimmed text satisfies `pred`.
fn nth_line(text: &str, nth: usize, pred: impl Fn(&str) -> bool) -> Option<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| pred(l.trim()))
        .nth(nth)
        .map(|(i, _)| i + 1)
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
    // content errors name the line of their table or key (`file:line`)
    let at = |line: Option<usize>| match line {
        Some(l) => format!("{file}:{l}"),
        None => file.to_string(),
    };
    let header = |h: &str, nth: usize| at(nth_line(text, nth, |l| l.starts_with(h)));
    let material_at = |name: &str| {
        let keys = [name.to_string(), format!("\"{name}\"")];
        at(nth_line(text, 0, |l| {
            let l = l.trim_start_matches('[');
            let l = l.strip_prefix("materials.").unwrap_or(l);
            keys.iter().any(|k| {
                l.strip_prefix(k.as_str())
                    .is_some_and(|r| r.trim_start().starts_with(['=', ']', '.']))
            })
        }))
    };
    for (i, o) in sf.objects.iter().enumerate() {
        let o_at = header("[[objects]]", i);
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
                "{o_at}: object {}: transform values must be finite and scale non-zero",
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
            .map_err(|e| format!("{o_at}: object file {e}"))?;
        // an OBJ reader takes any text for an empty mesh: other files are named
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let other = match ext.as_deref() {
            Some("xml") => Some("a Mitsuba XML scene"),
            Some("toml") => Some("a TOML scene"),
            Some("ply") => Some("a PLY mesh"),
            Some("mtl") => Some("a material library"),
            Some("exr" | "png" | "jpg" | "jpeg" | "hdr" | "pfm") => Some("an image"),
            _ => None,
        };
        if let Some(what) = other {
            return Err(format!(
                "{o_at}: object file {}: is {what}, not an OBJ file ([[objects]] files are OBJ meshes)",
                p.display()
            ));
        }
        super::obj::load_obj_file(&p, xf, &mut desc)?;
    }
    for (name, ov) in &sf.materials {
        let m_at = material_at(name);
        let mut found = false;
        for m in desc.materials.iter_mut().filter(|m| &m.name == name) {
            found = true;
            let check = |v: &[f32], what: &str| -> Result<(), String> {
                if v.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    Err(format!(
                        "{m_at}: materials.{name}.{what}: values must be finite and non-negative"
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
                // its emission is this file's: errors about it name this line
                m.source = Some(format!("{m_at}: materials.{name}"));
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
            if let Some(model) = &ov.model {
                model
                    .check()
                    .map_err(|e| format!("{m_at}: materials.{name}.model: {e}"))?;
                let model = model.model();
                // the same validation the scene build applies, reported with the file
                super::bsdf_of_model(&model, m.kd)
                    .map_err(|e| format!("{m_at}: materials.{name}.model: {e}"))?;
                m.model = Some(model);
                if m.source.is_none() {
                    m.source = Some(format!("{file} materials.{name}"));
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
                "{m_at}: materials.{name}: no material of that name in the scene"
            ));
        }
    }
    let env_at = header("[environment]", 0);
    if let Some(e) = &sf.environment {
        let radiance = e.radiance.unwrap_or([1.0; 3]);
        if radiance.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(format!(
                "{env_at}: [environment] radiance: values must be finite and non-negative"
            ));
        }
        let r = e.rotate.unwrap_or([0.0; 3]);
        if r.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "{env_at}: [environment] rotate: values must be finite"
            ));
        }
        let q = Quat::from_euler(
            EulerRot::ZYX,
            r[2].to_radians(),
            r[1].to_radians(),
            r[0].to_radians(),
        );
        let map = match &e.map {
            Some(m) => {
                let p = super::mtl::normalise_path(dir, m);
                crate::input::check_regular_file(&p, crate::input::max_input_bytes()?)
                    .map_err(|err| format!("{env_at}: [environment] map: {err}"))?;
                crate::image_io::check_readable(&p)
                    .map_err(|err| format!("{env_at}: [environment] map: {err}"))?;
                Some(p)
            }
            None => None,
        };
        desc.environment = Some(super::EnvironmentDesc {
            radiance,
            map,
            to_world: glam::Mat3::from_quat(q),
            source: Some(format!("{env_at} [environment]")),
        });
    }
    for (i, p) in sf.point_lights.iter().enumerate() {
        let p_at = header("[[point_lights]]", i);
        let ok = |v: &[f32; 3]| v.iter().all(|x| x.is_finite());
        if !ok(&p.position) || !ok(&p.intensity) || p.intensity.iter().any(|v| *v < 0.0) {
            return Err(format!(
                "{p_at}: point_lights[{i}]: position and intensity must be finite, intensity non-negative"
            ));
        }
        desc.point_lights.push(super::PointLightDesc {
            position: Vec3::from(p.position),
            intensity: p.intensity,
            shape: Default::default(),
            source: Some(format!("{p_at} point_lights[{i}]")),
        });
    }
    if let Some(c) = sf.camera {
        c.validate()
            .map_err(|e| format!("{}: [camera]: {e}", header("[camera]", 0)))?;
        desc.camera = Some(c);
    }
    let r_at = header("[render]", 0);
    if let Some(r) = sf.render {
        if let Some([w, h]) = r.res {
            crate::film::check_resolution(w, h)
                .map_err(|e| format!("{r_at}: [render] res: {e}"))?;
        }
        if r.spp == Some(0) {
            return Err(format!("{r_at}: [render] spp: must be at least 1"));
        }
        if let Some(d) = r.max_depth {
            if d < -1 || d == 0 {
                return Err(format!(
                    "{r_at}: [render] max_depth: {d}: must be -1 (unlimited) or at least 1"
                ));
            }
        }
        desc.defaults = RenderDefaults {
            res: r.res.map(|[w, h]| (w, h)),
            spp: r.spp,
            max_depth: r.max_depth,
            rr_min_depth: None,
            integrator: None,
        };
    }
    Ok(desc)
}
