//! Mitsuba 3 XML scenes (and Mitsuba 0.6 files, whose camelCase parameter names are
//! upgraded as Mitsuba 3 does): the subset research scenes use, read into a `SceneDesc`.
//!
//! - `<scene version>`, `<default>` and `$name` substitution (a define, `-D key=value` or
//!   `kalos.load(path, key=value)`, replaces the `<default>` of its name; one the file never
//!   names is an error), `<include>`, `id` / `ref`, `<path>` search folders (every file
//!   name is looked up in them, the one read last first, then beside the scene file);
//! - `shapegroup` / `instance` (instanced: see `instance.rs`);
//! - shapes `obj`, `ply`, `serialized`, `rectangle`, `cube`, `sphere` and `cylinder`
//!   (tessellated), `disk`, with
//!   `to_world` (`matrix`, `translate`, `rotate`, `scale`, `lookat`, composed in order: each
//!   step left-multiplies), `flip_normals`, `face_normals`, `flip_tex_coords`;
//! - BSDFs `diffuse`, `conductor`, `roughconductor`, `plastic`, `roughplastic`,
//!   `dielectric`, `roughdielectric`, `thindielectric` (into `MaterialDesc.model`, rough
//!   ones with their `distribution`, Beckmann unless it says ggx; dielectrics with their
//!   `specular_reflectance` / `specular_transmittance` tints; the MTL fields are set
//!   close to them too), `twosided`, `mask` (its `opacity`, a constant or a bitmap: a
//!   cut-out that rays pass through, on any shape), `bumpmap` and `normalmap` (the nested
//!   BSDF shaded with the normal from a raw bitmap or a constant, see
//!   `scene::texture_normal`), Mitsuba 0.6's `phong` and `roughdiffuse`;
//! - `rgb`, `srgb`, `spectrum` (a constant, `wavelength:value` lists and `.spd` files,
//!   integrated against the CIE 1931 curves as Mitsuba's RGB mode does: reflectances under
//!   D65, emission as an equal-energy spectrum), `bitmap` textures with `filter_type`
//!   (bilinear, nearest), `wrap_mode` (repeat, mirror, clamp) and `to_uv`, and
//!   `checkerboard` (`color0`, `color1`, `to_uv`) (`map_kd` for diffuse reflectances, a
//!   mask's opacity; the texture's mean, warned, in other slots);
//! - emitters `area` (on a shape: `ke`), `point`, `spot` (`cutoff_angle`, `beam_width`,
//!   a bitmap `texture` projected over the cone), `projector` (`irradiance`, a constant or
//!   a bitmap, `scale`, `fov` / `focal_length` / `fov_axis`), `directional` (`irradiance`,
//!   `direction` or +z of `to_world`), `constant`, `envmap`; unset radiance and intensity
//!   are white (1, 1, 1) as in Mitsuba's RGB mode;
//! - the `perspective` sensor (`fov`, `fov_axis`, `focal_length`, `to_world`) and the
//!   `orthographic` one (`to_world`'s scale, `near_clip`) into `CameraDesc`, `hdrfilm`
//!   width, height and `rfilter` (box, tent `radius`, gaussian `stddev`; Mitsuba's default
//!   Gaussian when the film names none), the integrator's `max_depth` and the sampler's
//!   `sample_count` into `RenderDefaults`;
//! - integrators: `path` and `bdpt` select kalos' estimator of that name (`--integrator`
//!   overrides), `direct` is the path tracer at max_depth 2 (the same estimator: emitter and
//!   BSDF sampling with MIS), `moment` and `aov` are read as their nested integrator,
//!   `ptracer`, `volpath` and the others are rendered by the path tracer, and said so.
//!
//! Camera convention: Mitsuba's camera looks along +z of its `to_world`, +y is up and the
//! image's x axis runs along -x; kalos' right vector is forward x up, the same direction
//! for any rotation (a mirroring `to_world` is warned).
//!
//! A Mitsuba plugin kalos cannot represent is reported once per kind with its file and line
//! ("unsupported bsdf 'hair' at scene.xml:40, rendered as diffuse grey"), as is every
//! parameter that was not read; a plugin name Mitsuba does not know is an error. Files are

mod bsdf;
mod cylinder;
mod emitter;
mod instance;
mod properties;
mod reader;
mod roughness;
mod sdfgrid;
mod sensor;
#[cfg(test)]
mod shading_tests;
mod shape;
mod spectra;
#[cfg(test)]
mod tests;
mod varying;
pub mod vol;

use super::camera::{PixelFilter, Projection};
use super::{
    CameraDesc, EnvironmentDesc, FovAxis, MaterialDesc, PointLightDesc, PointLightShape, SceneDesc,
    SurfaceModel,
};
use crate::material::Distribution;
use glam::{Mat3, Mat4, Vec2, Vec3};
use properties::*;
use reader::*;
pub use spectra::spectrum_to_rgb;
use spectra::*;
use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

struct Loader<'a> {
    dir: PathBuf,
    /// The `<path>` folders (see `reader::resolve`).
    search: Vec<PathBuf>,
    desc: SceneDesc,
    ids: HashMap<&'a str, &'a El>,
    /// Material index of a BSDF element (by address: a shared `id` is one material).
    materials: HashMap<*const El, u32>,
    /// Warning keys -> (index in desc.warnings, how often).
    warned: RefCell<HashMap<String, (usize, usize)>>,
    warnings: RefCell<Vec<String>>,
    sensor_seen: bool,
    default_material: Option<u32>,
    /// The BSDFs and textures being built, innermost last: a `<ref>` back to one of them
    /// is a cycle.
    building: RefCell<Vec<*const El>>,
    /// Group index of a `shapegroup` element already read (see `instance.rs`).
    groups: HashMap<*const El, u32>,
    /// A shapegroup's shapes are being read.
    in_group: bool,
    /// The signed-distance grids of the shapegroup being read.
    group_sdfs: Vec<crate::scene::instance::sdf::SdfDesc>,
}

type R<T> = Result<T, String>;

impl<'a> Loader<'a> {
    /// Warn once per `key`; later occurrences are counted.
    fn warn(&self, key: &str, msg: String) {
        let mut w = self.warned.borrow_mut();
        match w.get_mut(key) {
            Some((_, n)) => *n += 1,
            None => {
                let mut ws = self.warnings.borrow_mut();
                ws.push(msg);
                w.insert(key.to_string(), (ws.len() - 1, 1));
            }
        }
    }
}

/// Load a Mitsuba XML scene file.
pub fn load(path: &Path) -> Result<SceneDesc, String> {
    load_with(path, &[])
}

/// Load a Mitsuba XML scene file with parameters set as Mitsuba's `-D key=value` and
/// `mi.load_file(path, key=value)` set them: each replaces the `<default>` of that name.
pub fn load_with(path: &Path, defines: &[(String, String)]) -> Result<SceneDesc, String> {
    let text = crate::input::read_text(path)?;
    parse_with(
        &text,
        &path.display().to_string(),
        path.parent().unwrap_or(Path::new(".")),
        defines,
    )
}

/// A message on one line: control characters (a newline in an attribute written as
/// `&#10;`, one quoted by the XML parser) are escaped.
fn one_line(s: String) -> String {
    if !s.chars().any(char::is_control) {
        return s;
    }
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_debug().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Parse Mitsuba XML text; relative file names resolve against `dir`.
pub fn parse(text: &str, file: &str, dir: &Path) -> Result<SceneDesc, String> {
    parse_with(text, file, dir, &[])
}

/// [`parse`] with defines (see [`load_with`]).
pub fn parse_with(
    text: &str,
    file: &str,
    dir: &Path,
    defines: &[(String, String)],
) -> Result<SceneDesc, String> {
    let mut d = parse_inner(text, file, dir, defines).map_err(one_line)?;
    d.warnings = d.warnings.into_iter().map(one_line).collect();
    Ok(d)
}

fn parse_inner(
    text: &str,
    file: &str,
    dir: &Path,
    defines: &[(String, String)],
) -> Result<SceneDesc, String> {
    let top_file = Path::new(file);
    let mut reader = Reader::new(defines);
    reader.chain.push(
        top_file
            .canonicalize()
            .unwrap_or_else(|_| top_file.to_path_buf()),
    );
    reader.bytes = text.len() as u64;
    let top = reader.read_text(text, file, dir)?;
    reader.check_defines(defines, file)?;
    let mut ld = Loader {
        dir: dir.to_path_buf(),
        search: std::mem::take(&mut reader.search),
        desc: SceneDesc {
            name: Path::new(file)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or(file)
                .to_string(),
            // Mitsuba's default integrator (path) starts its roulette at rr_depth 5
            defaults: crate::scene::RenderDefaults {
                rr_min_depth: Some(4),
                ..Default::default()
            },
            ..Default::default()
        },
        ids: HashMap::new(),
        materials: HashMap::new(),
        warned: RefCell::new(HashMap::new()),
        warnings: RefCell::new(reader.warnings),
        sensor_seen: false,
        default_material: None,
        building: RefCell::new(Vec::new()),
        groups: HashMap::new(),
        in_group: false,
        group_sdfs: Vec::new(),
    };
    // every element with an id, at any depth
    fn collect<'a>(els: &'a [El], ids: &mut HashMap<&'a str, &'a El>) -> R<()> {
        for e in els {
            if let Some(id) = e.attr("id") {
                if e.tag != "ref" {
                    if let Some(prev) = ids.insert(id, e) {
                        return Err(format!(
                            "{}: id \"{id}\" is already used at {}",
                            e.at, prev.at
                        ));
                    }
                }
            }
            collect(&e.children, ids)?;
        }
        Ok(())
    }
    collect(&top, &mut ld.ids)?;
    for el in &top {
        match el.tag.as_str() {
            "shape" => ld.shape(el)?,
            "bsdf" | "texture" | "spectrum" | "rgb" | "float" | "medium" | "volume" | "phase" => {
                if !known_plugin(&el.tag, el.kind()) {
                    return Err(format!("{}: unknown {} plugin '{}'", el.at, el.tag, el.kind()));
                }
                if el.attr("id").is_none() {
                    ld.warn(
                        &format!("lone {}", el.tag),
                        format!("{}: a top-level <{}> without an id is never used", el.at, el.tag),
                    );
                }
                if matches!(el.tag.as_str(), "medium" | "volume" | "phase") {
                    ld.warn(
                        "medium",
                        format!("{}: participating media are not supported: ignored", el.at),
                    );
                }
            }
            "emitter" => ld.emitter(el)?,
            "sensor" => ld.sensor(el)?,
            "integrator" => ld.integrator(el)?,
            "alias" => ld.warn(
                &el.tag,
                format!("{}: <{}> is not supported: ignored", el.at, el.tag),
            ),
            t => {
                return Err(format!(
                    "{}: unknown element <{t}> in a scene (expected shape, bsdf, emitter, sensor, integrator, texture, ...)",
                    el.at
                ))
            }
        }
    }
    let mut desc = ld.desc;
    let counts = ld.warned.into_inner();
    let mut warnings = ld.warnings.into_inner();
    for (_, (i, n)) in counts {
        if n > 1 {
            warnings[i].push_str(&format!(" ({} more like it)", n - 1));
        }
    }
    desc.warnings.extend(warnings);
    if desc.positions.is_empty() && desc.instances.is_empty() {
        // name what was left out, where: that is why the scene is empty
        let why = desc
            .warnings
            .iter()
            .find(|w| w.contains("left out"))
            .map(|w| format!(" ({w})"))
            .unwrap_or_default();
        return Err(format!(
            "{file}: the scene has no shapes kalos can render{why}"
        ));
    }
    Ok(desc)
}
