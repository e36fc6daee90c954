//! Mitsuba 3 XML scenes (and Mitsuba 0.6 files, whose camelCase parameter names are
//! upgraded as Mitsuba 3 does): the subset research scenes use, read into a `SceneDesc`.
//!
//! - `<scene version>`, `<default>` and `$name` substitution, `<include>`, `id` / `ref`;
//! - shapes `obj`, `ply`, `rectangle`, `cube`, `sphere` (tessellated), `disk`, with
//!   `to_world` (`matrix`, `translate`, `rotate`, `scale`, `lookat`, composed in order: each
//!   step left-multiplies), `flip_normals`, `face_normals`, `flip_tex_coords`;
//! - BSDFs `diffuse`, `conductor`, `roughconductor`, `plastic`, `roughplastic`,
//!   `dielectric`, `roughdielectric`, `thindielectric` (into `MaterialDesc.model`, rough
//!   ones with their `distribution`, Beckmann unless it says ggx; the MTL fields are set
//!   close to them too), `twosided`, `mask`,
//!   `bumpmap`, `normalmap` (the nested BSDF; opacity and bumps warned), Mitsuba 0.6's
//!   `phong` and `roughdiffuse`;
//! - `rgb`, `srgb`, `spectrum` (a constant, `wavelength:value` lists and `.spd` files,
//!   integrated against the CIE 1931 curves as Mitsuba's RGB mode does: reflectances under
//!   D65, emission as an equal-energy spectrum), `bitmap` textures (`map_kd` for diffuse
//!   reflectances; the texture's mean, warned, in other slots);
//! - emitters `area` (on a shape: `ke`), `point`, `constant`, `envmap`;
//! - the `perspective` sensor (`fov`, `fov_axis`, `focal_length`, `to_world`) into
//!   `CameraDesc`, `hdrfilm` width and height, the integrator's `max_depth` and the
//!   sampler's `sample_count` into `RenderDefaults`.
//!
//! Camera convention: Mitsuba's camera looks along +z of its `to_world`, +y is up and the
//! image's x axis runs along -x; kalos' right vector is forward x up, the same direction
//! for any rotation (a mirroring `to_world` is warned).
//!
//! A Mitsuba plugin kalos cannot represent is reported once per kind with its file and line
//! ("unsupported bsdf 'hair' at scene.xml:40, rendered as diffuse grey"), as is every
//! parameter that was not read; a plugin name Mitsuba does not know is an error. Files are
//! read through `input` (regular files, size limit, byte-order mark).

use super::{
    CameraDesc, EnvironmentDesc, FovAxis, MaterialDesc, PointLightDesc, SceneDesc, SurfaceModel,
};
use crate::material::Distribution;
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Mitsuba's `<include>` nesting limit (its parser's `max_include_depth`).
const MAX_INCLUDE_DEPTH: usize = 15;

/// An XML element with its attributes after `$name` substitution.
#[derive(Debug)]
struct El {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<El>,
    /// `file:line`, for messages.
    at: String,
    used: Cell<bool>,
}

impl El {
    fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    fn name(&self) -> Option<&str> {
        self.attr("name")
    }
    fn kind(&self) -> &str {
        self.attr("type").unwrap_or("")
    }
}

// ----------------------------------------------------------------------------------------
// Reading files into element trees
// ----------------------------------------------------------------------------------------

/// The text of roxmltree's error without its trailing "at line:col".
fn xml_error(file: &str, e: &roxmltree::Error) -> String {
    let p = e.pos();
    let msg = e.to_string();
    let msg = msg
        .strip_suffix(&format!(" at {}:{}", p.row, p.col))
        .unwrap_or(&msg);
    format!("{file}:{}:{}: malformed XML: {msg}", p.row, p.col)
}

/// Mitsuba 3's upgrade of 0.x names: camelCase -> snake_case (`intIOR` -> `int_ior`).
fn snake_case(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 4);
    let mut prev_lower = false;
    for c in s.chars() {
        if c.is_ascii_uppercase() && prev_lower {
            out.push('_');
        }
        prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// Mitsuba 0.6's `diffuse` and `roughdiffuse` read `diffuseReflectance` when it is given
/// and `reflectance` otherwise (scenes of that era use both, e.g. the bedroom scenes of
/// "Neural complex luminaires"); Mitsuba 3 knows only `reflectance`. So in a 0.x file the
/// upgraded `diffuse_reflectance` becomes `reflectance`, and a `reflectance` beside it is
/// renamed so that it is warned as unused, as 0.6 ignored it.
fn diffuse_reflectance_alias(attrs: &[(String, String)], children: &mut [El]) {
    let kind = attrs
        .iter()
        .find(|(k, _)| k == "type")
        .map(|(_, v)| v.as_str());
    if !matches!(kind, Some("diffuse" | "roughdiffuse")) {
        return;
    }
    let named = |c: &El, n: &str| c.attrs.iter().any(|(k, v)| k == "name" && v == n);
    if !children.iter().any(|c| named(c, "diffuse_reflectance")) {
        return;
    }
    for c in children.iter_mut() {
        for (k, v) in c.attrs.iter_mut() {
            if k == "name" {
                if v == "reflectance" {
                    *v = "reflectance (overridden by diffuseReflectance)".into();
                } else if v == "diffuse_reflectance" {
                    *v = "reflectance".into();
                }
            }
        }
    }
}

struct Reader {
    defaults: HashMap<String, String>,
    /// Warnings found while reading (unknown version, ...).
    warnings: Vec<String>,
}

impl Reader {
    /// Substitute `$name` parameters.
    fn substitute(&self, v: &str, at: &str) -> Result<String, String> {
        if !v.contains('$') {
            return Ok(v.to_string());
        }
        let mut out = String::with_capacity(v.len());
        let mut rest = v;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let n = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let key = &after[..n];
            if key.is_empty() {
                out.push('$');
            } else {
                match self.defaults.get(key) {
                    Some(val) => out.push_str(val),
                    None => {
                        return Err(format!(
                            "{at}: undefined parameter ${key} (no <default name=\"{key}\" value=\"...\"/>)"
                        ))
                    }
                }
            }
            rest = &after[n..];
        }
        out.push_str(rest);
        Ok(out)
    }

    /// Read `path` (a `<scene>`), returning its children with includes spliced in.
    fn read_file(&mut self, path: &Path, depth: usize) -> Result<Vec<El>, String> {
        let text = crate::input::read_text(path)?;
        let file = path.display().to_string();
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        self.read_text(&text, &file, &dir, depth)
    }

    fn read_text(
        &mut self,
        text: &str,
        file: &str,
        dir: &Path,
        depth: usize,
    ) -> Result<Vec<El>, String> {
        let text = crate::input::clean_text(text);
        // no DTDs (Mitsuba files have none; entity expansion is not worth the risk)
        let doc = roxmltree::Document::parse(&text).map_err(|e| xml_error(file, &e))?;
        let root = doc.root_element();
        let at = |n: &roxmltree::Node| format!("{file}:{}", doc.text_pos_at(n.range().start).row);
        if root.tag_name().name() != "scene" {
            return Err(format!(
                "{}: the root element is <{}>: a Mitsuba scene is a <scene version=\"...\"> element",
                at(&root),
                root.tag_name().name()
            ));
        }
        let upgrade = match root.attribute("version") {
            None => {
                self.warnings.push(format!(
                    "{}: <scene> has no version attribute: read as Mitsuba 3",
                    at(&root)
                ));
                false
            }
            Some(v) => {
                let major = v.split('.').next().unwrap_or("").trim().parse::<u32>();
                match major {
                    Ok(m) => m < 2,
                    Err(_) => {
                        return Err(format!(
                            "{}: <scene version=\"{v}\">: not a version number like 3.0.0",
                            at(&root)
                        ))
                    }
                }
            }
        };
        // <default> first: a parameter may be used before its default in document order
        for n in root.children().filter(|n| n.is_element()) {
            if n.tag_name().name() == "default" {
                let (Some(k), Some(v)) = (n.attribute("name"), n.attribute("value")) else {
                    return Err(format!(
                        "{}: <default> needs both name and value attributes",
                        at(&n)
                    ));
                };
                self.defaults
                    .entry(k.to_string())
                    .or_insert_with(|| v.to_string());
            }
        }
        let mut out = Vec::new();
        for n in root.children().filter(|n| n.is_element()) {
            match n.tag_name().name() {
                "default" => {}
                "include" => {
                    let here = at(&n);
                    let name = n
                        .attribute("filename")
                        .ok_or_else(|| format!("{here}: <include> needs a filename attribute"))?;
                    let name = self.substitute(name, &here)?;
                    if depth + 1 > MAX_INCLUDE_DEPTH {
                        return Err(format!(
                            "{here}: <include filename=\"{name}\">: includes nested more than {MAX_INCLUDE_DEPTH} deep (a cycle?)"
                        ));
                    }
                    let p = super::mtl::normalise_path(dir, &name);
                    let children = self
                        .read_file(&p, depth + 1)
                        .map_err(|e| format!("{here}: <include>: {e}"))?;
                    out.extend(children);
                }
                _ => out.push(self.convert(n, &doc, file, upgrade)?),
            }
        }
        Ok(out)
    }

    fn convert(
        &self,
        n: roxmltree::Node,
        doc: &roxmltree::Document,
        file: &str,
        upgrade: bool,
    ) -> Result<El, String> {
        let at = format!("{file}:{}", doc.text_pos_at(n.range().start).row);
        let mut tag = n.tag_name().name().to_string();
        if tag == "lookAt" {
            tag = "lookat".into();
        }
        let mut attrs = Vec::new();
        for a in n.attributes() {
            let mut v = self.substitute(a.value(), &at)?;
            if upgrade && a.name() == "name" {
                v = snake_case(&v);
            }
            attrs.push((a.name().to_string(), v));
        }
        let mut children = Vec::new();
        for c in n.children().filter(|c| c.is_element()) {
            children.push(self.convert(c, doc, file, upgrade)?);
        }
        if upgrade && tag == "bsdf" {
            diffuse_reflectance_alias(&attrs, &mut children);
        }
        Ok(El {
            tag,
            attrs,
            children,
            at,
            used: Cell::new(false),
        })
    }
}

// ----------------------------------------------------------------------------------------
// Plugin names (Mitsuba 3 and 0.6): anything else is an error
// ----------------------------------------------------------------------------------------

fn known_plugin(tag: &str, kind: &str) -> bool {
    let list: &[&str] = match tag {
        "bsdf" => &[
            "diffuse",
            "conductor",
            "roughconductor",
            "plastic",
            "roughplastic",
            "dielectric",
            "roughdielectric",
            "thindielectric",
            "twosided",
            "mask",
            "bumpmap",
            "normalmap",
            "blendbsdf",
            "null",
            "principled",
            "principledthin",
            "pplastic",
            "hair",
            "measured",
            "measured_polarized",
            "polarizer",
            "retarder",
            "circular",
            "phong",
            "ward",
            "coating",
            "roughcoating",
            "roughdiffuse",
            "difftrans",
            "irawan",
            "hk",
            "mixturebsdf",
            "sssbrdf",
        ],
        "shape" => &[
            "obj",
            "ply",
            "serialized",
            "rectangle",
            "cube",
            "sphere",
            "disk",
            "cylinder",
            "shapegroup",
            "instance",
            "bsplinecurve",
            "linearcurve",
            "sdfgrid",
            "ellipsoids",
            "ellipsoidsmesh",
            "merge",
            "heightfield",
            "hair",
        ],
        "emitter" => &[
            "area",
            "point",
            "constant",
            "envmap",
            "directional",
            "spot",
            "projector",
            "sunsky",
            "directionalarea",
            "sky",
            "sun",
            "collimator",
        ],
        "sensor" => &[
            "perspective",
            "thinlens",
            "orthographic",
            "radiancemeter",
            "irradiancemeter",
            "distant",
            "batch",
            "spherical",
            "telecentric",
            "fluencemeter",
        ],
        "texture" => &[
            "bitmap",
            "checkerboard",
            "mesh_attribute",
            "volume",
            "gridtexture",
            "scale",
            "vertexcolors",
            "wireframe",
            "curvature",
        ],
        "integrator" => &[
            "path",
            "volpath",
            "volpathmis",
            "direct",
            "aov",
            "depth",
            "moment",
            "stokes",
            "ptracer",
            "prb",
            "prb_basic",
            "direct_projective",
            "prb_projective",
            "prbvolpath",
            "bdpt",
            "pssmlt",
            "mlt",
            "erpt",
            "photonmapper",
            "sppm",
            "ppm",
            "vpl",
            "ao",
            "volpath_simple",
            "irrcache",
            "adaptive",
            "multichannel",
            "field",
        ],
        "film" => &["hdrfilm", "specfilm", "ldrfilm", "mfilm"],
        "sampler" => &[
            "independent",
            "stratified",
            "multijitter",
            "orthogonal",
            "ldsampler",
            "halton",
            "hammersley",
            "sobol",
        ],
        "rfilter" => &[
            "box",
            "tent",
            "gaussian",
            "mitchell",
            "catmullrom",
            "lanczos",
        ],
        "medium" => &["homogeneous", "heterogeneous"],
        "phase" => &[
            "isotropic",
            "hg",
            "rayleigh",
            "sggx",
            "tabphase",
            "blendphase",
        ],
        "volume" => &["constvolume", "gridvolume"],
        _ => return true,
    };
    list.contains(&kind)
}

// ----------------------------------------------------------------------------------------
// Values
// ----------------------------------------------------------------------------------------

/// Numbers in an attribute: separated by commas and/or white space.
fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect()
}

/// What a colour is for: Mitsuba's RGB mode turns spectra into RGB differently for each.
#[derive(Clone, Copy, PartialEq)]
enum Use {
    /// Reflectances and other bounded values: the spectrum under D65.
    Reflectance,
    /// Radiance, intensity, eta, k: an unbounded spectrum (equal-energy white).
    Unbounded,
}

/// A colour-valued parameter.
enum Color {
    Rgb([f32; 3]),
    /// A bitmap texture: its file.
    Bitmap(PathBuf),
}

/// CIE 15:2004 illuminant D65, 300..830 nm in 5 nm steps (normalised to 100 at 560 nm).
const D65: [f32; 107] = [
    0.0341, 1.6643, 3.2945, 11.7652, 20.236, 28.6447, 37.0535, 38.5011, 39.9488, 42.4302, 44.9117,
    45.775, 46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549,
    87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023, 100.0,
    98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991,
    88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146,
    81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054, 46.4182, 56.6118,
    66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4518, 55.7054, 51.959, 54.6998,
    57.4406, 58.8765, 60.3125,
];

fn d65(l: f64) -> f64 {
    let x = (l - 300.0) / 5.0;
    if !(0.0..=106.0).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(105);
    let f = x - i as f64;
    D65[i] as f64 * (1.0 - f) + D65[i + 1] as f64 * f
}

/// Piecewise-linear spectrum (sorted wavelengths in nm) to linear sRGB, as Mitsuba 3's
/// RGB variants do: integrated against CIE 1931 over 360..830 nm (kalos' multi-lobe fit of
/// the curves), under D65 and normalised to white = 1 for reflectances; as an
/// equal-energy spectrum (Y normalised) for emission.
pub fn spectrum_to_rgb(wl: &[f32], val: &[f32], reflectance: bool) -> [f32; 3] {
    let at = |l: f64| -> f64 {
        if wl.is_empty() || l < wl[0] as f64 || l > wl[wl.len() - 1] as f64 {
            return 0.0;
        }
        let i = wl
            .partition_point(|&w| (w as f64) <= l)
            .clamp(1, wl.len() - 1);
        let (l0, l1) = (wl[i - 1] as f64, wl[i] as f64);
        let f = if l1 > l0 { (l - l0) / (l1 - l0) } else { 0.0 };
        val[i - 1] as f64 * (1.0 - f) + val[i] as f64 * f
    };
    let (mut xyz, mut norm) = ([0.0f64; 3], 0.0f64);
    let steps = 940;
    let dl = (830.0 - 360.0) / steps as f64;
    for k in 0..steps {
        let l = 360.0 + (k as f64 + 0.5) * dl;
        let c = crate::spectrum::cie_xyz(l);
        let w = if reflectance { d65(l) } else { 1.0 };
        let s = at(l) * w;
        for j in 0..3 {
            xyz[j] += c[j] * s;
        }
        norm += c[1] * w;
    }
    let m = [
        [3.2404542, -1.5371385, -0.4985314],
        [-0.9692660, 1.8760108, 0.0415560],
        [0.0556434, -0.2040259, 1.0572252],
    ];
    let xyz = xyz.map(|v| v / norm);
    let mut rgb = [0.0f32; 3];
    for c in 0..3 {
        let v: f64 = (0..3).map(|j| m[c][j] * xyz[j]).sum();
        rgb[c] = if reflectance {
            v.max(0.0) as f32
        } else {
            v as f32
        };
    }
    rgb
}

/// Named indices of refraction (Mitsuba 3's list).
const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Mitsuba 3's named conductors as its RGB variants see them (eta, k per channel, as
/// `mi.traverse` reports them for `conductor` with `material` set, Mitsuba 3.9.1).
const METALS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("none", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.828354, 3.122222, 2.146901],
    ),
    (
        "Al",
        [1.657501, 0.880405, 0.521244],
        [9.223811, 6.269502, 4.837004],
    ),
    (
        "AlAs",
        [3.605296, 3.232938, 2.216319],
        [0.000679, 0.0, 0.007513],
    ),
    ("AlSb", [0.0, 4.139375, 4.669254], [0.0, 0.094009, 1.30057]),
    (
        "Au",
        [0.143036, 0.375307, 1.442045],
        [3.982997, 2.385556, 1.603359],
    ),
    (
        "Be",
        [4.185012, 3.185029, 2.784061],
        [3.835466, 3.010122, 2.868994],
    ),
    (
        "Cr",
        [4.369668, 2.916505, 1.654905],
        [5.206547, 4.231306, 3.754699],
    ),
    ("CsI", [2.1449, 1.702319, 1.662427], [0.0, 0.0, 0.0]),
    (
        "Cu",
        [0.201005, 0.92375, 1.102215],
        [3.913262, 2.453045, 2.14209],
    ),
    (
        "Cu2O",
        [3.551773, 2.94987, 2.751875],
        [0.114207, 0.193897, 0.606134],
    ),
    (
        "CuO",
        [3.247541, 2.447805, 2.21022],
        [0.52109, 0.570031, 0.722179],
    ),
    (
        "Hg",
        [2.398939, 1.440028, 0.90957],
        [6.327587, 4.371925, 3.421764],
    ),
    (
        "HgTe",
        [4.77904, 3.231196, 2.659901],
        [1.631613, 1.58081, 1.729287],
    ),
    (
        "Ir",
        [3.0863, 2.082191, 1.617915],
        [5.592153, 4.067088, 3.267312],
    ),
    (
        "K",
        [0.064043, 0.04641, 0.038185],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "Li",
        [0.265791, 0.195618, 0.220949],
        [3.540155, 2.311123, 1.668607],
    ),
    ("MgO", [2.089584, 1.650723, 1.594879], [0.0, 0.0, 0.0]),
    (
        "Mo",
        [4.483974, 3.525131, 2.77631],
        [4.111437, 3.420827, 3.150607],
    ),
    (
        "Na",
        [0.060269, 0.056141, 0.061988],
        [3.179273, 2.11249, 1.579041],
    ),
    (
        "Nb",
        [3.420074, 2.790093, 2.395629],
        [3.441395, 2.737666, 2.579746],
    ),
    (
        "Ni",
        [2.367305, 1.663373, 1.467078],
        [4.498812, 3.050153, 2.345439],
    ),
    (
        "Rh",
        [2.585793, 1.860216, 1.554263],
        [6.78226, 4.702987, 3.976073],
    ),
    (
        "Se",
        [4.058311, 2.842935, 2.820853],
        [0.75405, 0.638444, 0.521808],
    ),
    (
        "Se-e",
        [5.722849, 4.165736, 4.081338],
        [0.871136, 1.105157, 1.56532],
    ),
    (
        "SiC",
        [3.172342, 2.525972, 2.479371],
        [0.000001, 0.0, 0.00001],
    ),
    ("SnTe", [4.52425, 1.981645, 1.281591], [0.0, 0.0, 0.0]),
    (
        "Ta",
        [2.062721, 2.392939, 2.627929],
        [2.40836, 1.741486, 1.947028],
    ),
    (
        "Te",
        [7.390234, 4.482105, 2.637106],
        [3.256022, 3.527059, 3.292054],
    ),
    (
        "Te-e",
        [7.508907, 4.296429, 2.369988],
        [5.583929, 4.947205, 3.997592],
    ),
    ("ThF4", [1.830714, 1.442229, 1.387648], [0.0, 0.0, 0.0]),
    (
        "TiC",
        [3.700528, 2.837422, 2.582287],
        [3.265635, 2.351589, 2.172791],
    ),
    (
        "TiN",
        [1.64845, 1.150516, 1.379823],
        [3.368328, 1.943498, 1.102068],
    ),
    (
        "TiO2",
        [3.45661, 2.801736, 2.905175],
        [0.000105, 0.0, 0.000653],
    ),
    (
        "TiO2-e",
        [3.106565, 2.513168, 2.582444],
        [0.00003, 0.0, 0.000183],
    ),
    (
        "V",
        [4.277582, 3.512949, 2.761071],
        [3.491301, 2.889455, 3.111522],
    ),
    (
        "VC",
        [3.657566, 2.752736, 2.532672],
        [3.068301, 2.198687, 1.963193],
    ),
    (
        "VN",
        [2.865602, 2.119189, 1.940091],
        [3.032243, 2.056116, 1.616306],
    ),
    (
        "W",
        [4.370817, 3.300246, 2.998407],
        [3.500641, 2.604874, 2.273233],
    ),
    (
        "a-C",
        [2.944046, 2.227136, 1.968162],
        [0.887465, 0.799299, 0.81529],
    ),
    ("d-C", [2.70872, 2.318826, 2.228898], [0.0, 0.0, 0.0]),
];

/// Unpolarised Fresnel reflectance of a conductor at normal incidence.
fn conductor_r0(eta: f32, k: f32) -> f32 {
    ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k)
}

/// Unpolarised Fresnel reflectance of a dielectric interface (relative index `eta`,
/// light arriving from the outside at cosine `c`).
fn fresnel_dielectric(c: f32, eta: f32) -> f32 {
    let s2 = (1.0 - c * c).max(0.0) / (eta * eta);
    if s2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - s2).sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}

/// Hemispherical (cosine-weighted) Fresnel reflectance, from the side of index ratio eta.
fn fresnel_diffuse(eta: f32) -> f32 {
    let n = 256;
    (0..n)
        .map(|i| {
            let c = (i as f32 + 0.5) / n as f32;
            2.0 * c * fresnel_dielectric(c, eta) / n as f32
        })
        .sum()
}

/// A normalized-Phong exponent with about the spread of a GGX lobe of roughness alpha.
fn phong_exponent(alpha: f32) -> f32 {
    (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 10000.0)
}

// ----------------------------------------------------------------------------------------
// The scene loader
// ----------------------------------------------------------------------------------------

struct Loader<'a> {
    dir: PathBuf,
    desc: SceneDesc,
    ids: HashMap<&'a str, &'a El>,
    /// Material index of a BSDF element (by address: a shared `id` is one material).
    materials: HashMap<*const El, u32>,
    /// Warning keys -> (index in desc.warnings, how often).
    warned: RefCell<HashMap<String, (usize, usize)>>,
    warnings: RefCell<Vec<String>>,
    sensor_seen: bool,
    default_material: Option<u32>,
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

    fn resolve(&self, el: &'a El) -> R<&'a El> {
        if el.tag != "ref" {
            return Ok(el);
        }
        let id = el
            .attr("id")
            .ok_or_else(|| format!("{}: <ref> without an id", el.at))?;
        self.ids
            .get(id)
            .copied()
            .ok_or_else(|| format!("{}: <ref id=\"{id}\">: no element has that id", el.at))
    }

    /// The property child named `name` (marked as read).
    fn prop(&self, el: &'a El, name: &str) -> Option<&'a El> {
        let c = el.children.iter().find(|c| c.name() == Some(name))?;
        c.used.set(true);
        Some(c)
    }

    fn value<'b>(&self, p: &'b El) -> R<&'b str> {
        p.attr("value").ok_or_else(|| {
            format!(
                "{}: <{} name=\"{}\"> has no value attribute",
                p.at,
                p.tag,
                p.name().unwrap_or("")
            )
        })
    }

    fn float(&self, el: &'a El, name: &str) -> R<Option<f32>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        match p.tag.as_str() {
            "float" | "integer" => {}
            // a texture or spectrum where a number is expected: its mean
            "rgb" | "spectrum" | "texture" | "ref" | "srgb" => {
                let c = self.color_of(p, Use::Unbounded)?;
                let rgb = self.mean_rgb(c, &p.at)?;
                return Ok(Some((rgb[0] + rgb[1] + rgb[2]) / 3.0));
            }
            t => {
                return Err(format!(
                    "{}: <{t} name=\"{name}\">: expected a <float>",
                    p.at
                ))
            }
        }
        let v = self.value(p)?;
        let f: f32 = v.trim().parse().map_err(|_| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not a number",
                p.at, p.tag
            )
        })?;
        if !f.is_finite() {
            return Err(format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not a finite number",
                p.at, p.tag
            ));
        }
        Ok(Some(f))
    }

    fn int(&self, el: &'a El, name: &str) -> R<Option<i64>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        let v = self.value(p)?;
        v.trim().parse::<i64>().map(Some).map_err(|_| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not an integer",
                p.at, p.tag
            )
        })
    }

    fn boolean(&self, el: &'a El, name: &str) -> R<Option<bool>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        let v = self.value(p)?;
        // Mitsuba lower-cases the value first (Python writes True and False)
        match v.trim().to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(Some(true)),
            "false" | "0" => Ok(Some(false)),
            _ => Err(format!(
                "{}: <boolean name=\"{name}\" value=\"{v}\">: expected true or false",
                p.at
            )),
        }
    }

    fn string(&self, el: &'a El, name: &str) -> R<Option<String>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.value(p)?.to_string())),
            None => Ok(None),
        }
    }

    fn vec3_attr(&self, p: &El, what: &str) -> R<Vec3> {
        if let Some(v) = p.attr("value") {
            let n = numbers(v).filter(|n| n.len() == 3 || n.len() == 1);
            return match n.as_deref() {
                Some([x, y, z]) => Ok(Vec3::new(*x, *y, *z)),
                Some([s]) => Ok(Vec3::splat(*s)),
                _ => Err(format!(
                    "{}: <{}> {what}: value \"{v}\" is not 1 or 3 finite numbers",
                    p.at, p.tag
                )),
            };
        }
        let c = |k: &str, d: f32| -> R<f32> {
            match p.attr(k) {
                None => Ok(d),
                Some(s) => s
                    .trim()
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        format!(
                            "{}: <{}> {what}: {k}=\"{s}\" is not a finite number",
                            p.at, p.tag
                        )
                    }),
            }
        };
        let d = if p.tag == "scale" { 1.0 } else { 0.0 };
        Ok(Vec3::new(c("x", d)?, c("y", d)?, c("z", d)?))
    }

    fn point(&self, el: &'a El, name: &str) -> R<Option<Vec3>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.vec3_attr(p, name)?)),
            None => Ok(None),
        }
    }

    /// `to_world` (or another transform property): identity if absent.
    fn transform(&self, el: &'a El, name: &str) -> R<Mat4> {
        let Some(t) = self.prop(el, name) else {
            return Ok(Mat4::IDENTITY);
        };
        if t.tag != "transform" {
            return Err(format!(
                "{}: <{} name=\"{name}\">: expected a <transform>",
                t.at, t.tag
            ));
        }
        let mut m = Mat4::IDENTITY;
        for op in &t.children {
            let step = match op.tag.as_str() {
                "translate" => Mat4::from_translation(self.vec3_attr(op, "translate")?),
                "scale" => {
                    let s = self.vec3_attr(op, "scale")?;
                    Mat4::from_scale(s)
                }
                "rotate" => {
                    let axis = if op.attr("value").is_some() {
                        self.vec3_attr(op, "rotate")?
                    } else {
                        let c = |k: &str| op.attr(k).map(|s| s.trim().parse::<f32>());
                        let f = |k: &str| -> R<f32> {
                            match c(k) {
                                None => Ok(0.0),
                                Some(Ok(v)) if v.is_finite() => Ok(v),
                                _ => Err(format!("{}: <rotate> {k}: not a finite number", op.at)),
                            }
                        };
                        Vec3::new(f("x")?, f("y")?, f("z")?)
                    };
                    let angle = op
                        .attr("angle")
                        .ok_or_else(|| format!("{}: <rotate> needs an angle (degrees)", op.at))?;
                    let angle: f32 = angle
                        .trim()
                        .parse()
                        .ok()
                        .filter(|a: &f32| a.is_finite())
                        .ok_or_else(|| format!("{}: <rotate angle=\"{angle}\">: not a number", op.at))?;
                    if axis.length_squared() == 0.0 {
                        return Err(format!("{}: <rotate>: the axis is zero", op.at));
                    }
                    Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
                }
                "matrix" => {
                    let v = op
                        .attr("value")
                        .ok_or_else(|| format!("{}: <matrix> needs a value", op.at))?;
                    match numbers(v) {
                        Some(n) if n.len() == 16 => {
                            Mat4::from_cols_array(&n.try_into().unwrap()).transpose()
                        }
                        Some(n) if n.len() == 9 => Mat4::from_mat3(
                            Mat3::from_cols_array(&n.try_into().unwrap()).transpose(),
                        ),
                        _ => {
                            return Err(format!(
                                "{}: <matrix value=\"...\">: expected 16 (or 9) finite numbers, row by row",
                                op.at
                            ))
                        }
                    }
                }
                "lookat" => {
                    let get = |k: &str| -> R<Option<Vec3>> {
                        match op.attr(k) {
                            None => Ok(None),
                            Some(s) => match numbers(s).as_deref() {
                                Some([x, y, z]) => Ok(Some(Vec3::new(*x, *y, *z))),
                                _ => Err(format!(
                                    "{}: <lookat {k}=\"{s}\">: expected 3 finite numbers",
                                    op.at
                                )),
                            },
                        }
                    };
                    let o = get("origin")?
                        .ok_or_else(|| format!("{}: <lookat> needs an origin", op.at))?;
                    let t = get("target")?
                        .ok_or_else(|| format!("{}: <lookat> needs a target", op.at))?;
                    let dir = (t - o).normalize_or_zero();
                    if dir == Vec3::ZERO {
                        return Err(format!("{}: <lookat>: origin and target coincide", op.at));
                    }
                    // no (or a zero) up: Mitsuba's coordinate_system(dir).first, the first
                    // of Duff et al.'s pair, which glam's any_orthonormal_pair computes
                    let up = match get("up")? {
                        Some(u) if u != Vec3::ZERO => u,
                        _ => dir.any_orthonormal_pair().0,
                    };
                    let left = up.cross(dir).normalize_or_zero();
                    if left == Vec3::ZERO {
                        return Err(format!(
                            "{}: <lookat>: up is parallel to the view direction (or zero)",
                            op.at
                        ));
                    }
                    let new_up = dir.cross(left);
                    Mat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        o.extend(1.0),
                    )
                }
                t => {
                    return Err(format!(
                        "{}: <{t}> inside <transform>: expected translate, rotate, scale, matrix or lookat",
                        op.at
                    ))
                }
            };
            m = step * m;
        }
        if !m.is_finite() || m.determinant() == 0.0 {
            return Err(format!(
                "{}: <transform name=\"{name}\"> is singular or not finite",
                t.at
            ));
        }
        Ok(m)
    }

    /// Resolve a relative file name of the scene.
    fn path(&self, name: &str) -> PathBuf {
        super::mtl::normalise_path(&self.dir, name)
    }

    /// A colour property (rgb, srgb, spectrum, float, texture or ref to a texture).
    fn color(&self, el: &'a El, name: &str, use_: Use) -> R<Option<Color>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.color_of(p, use_)?)),
            None => Ok(None),
        }
    }

    fn color_of(&self, p: &'a El, use_: Use) -> R<Color> {
        let p = self.resolve(p)?;
        let name = p.name().unwrap_or("");
        let bad = |v: &str, what: &str| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: {what}",
                p.at, p.tag
            )
        };
        match p.tag.as_str() {
            "rgb" | "srgb" | "color" => {
                let v = self.value(p)?;
                let mut rgb = if let Some(hex) = v.trim().strip_prefix('#') {
                    let h = u32::from_str_radix(hex, 16)
                        .ok()
                        .filter(|_| hex.len() == 6)
                        .ok_or_else(|| bad(v, "not a #rrggbb colour"))?;
                    [(h >> 16) & 255, (h >> 8) & 255, h & 255].map(|c| c as f32 / 255.0)
                } else {
                    match numbers(v).as_deref() {
                        Some([r, g, b]) => [*r, *g, *b],
                        Some([s]) => [*s; 3],
                        _ => return Err(bad(v, "expected 3 (or 1) finite numbers")),
                    }
                };
                if p.tag == "srgb" || v.trim().starts_with('#') {
                    rgb = rgb.map(crate::image_io::srgb_decode);
                }
                Ok(Color::Rgb(rgb))
            }
            "float" => {
                let v = self.value(p)?;
                match numbers(v).as_deref() {
                    Some([s]) => Ok(Color::Rgb([*s; 3])),
                    _ => Err(bad(v, "not a finite number")),
                }
            }
            "spectrum" => {
                if let Some(t) = p.attr("type") {
                    self.warn(
                        &format!("spectrum {t}"),
                        format!(
                            "{}: spectrum plugin '{t}' is not supported: rendered as 1 (white)",
                            p.at
                        ),
                    );
                    self.mark_all(p);
                    return Ok(Color::Rgb([1.0; 3]));
                }
                let (wl, val) = if let Some(f) = p.attr("filename") {
                    let path = self.path(f);
                    let text = crate::input::read_text(&path)
                        .map_err(|e| format!("{}: <spectrum filename>: {e}", p.at))?;
                    let mut wl = Vec::new();
                    let mut val = Vec::new();
                    for (i, line) in text.lines().enumerate() {
                        let line = line.split('#').next().unwrap_or("").trim();
                        if line.is_empty() {
                            continue;
                        }
                        match numbers(line).as_deref() {
                            Some([l, v]) => {
                                wl.push(*l);
                                val.push(*v);
                            }
                            _ => {
                                return Err(format!(
                                    "{}:{}: expected a wavelength and a value",
                                    path.display(),
                                    i + 1
                                ))
                            }
                        }
                    }
                    (wl, val)
                } else {
                    let v = self.value(p)?;
                    if !v.contains(':') {
                        let s = match numbers(v).as_deref() {
                            Some([s]) => *s,
                            _ => return Err(bad(v, "expected a number or wavelength:value pairs")),
                        };
                        // a constant: a reflectance stays s; emission is equal-energy white
                        return Ok(Color::Rgb(match use_ {
                            Use::Reflectance => [s; 3],
                            Use::Unbounded => spectrum_to_rgb(&[360.0, 830.0], &[s, s], false),
                        }));
                    }
                    let mut wl = Vec::new();
                    let mut val = Vec::new();
                    // Mitsuba tokenizes on commas and whitespace: "400:0.1, 500:0.5" or
                    // "400:0.1 500:0.5"
                    for pair in v
                        .split(|c: char| c == ',' || c.is_whitespace())
                        .filter(|s| !s.is_empty())
                    {
                        let (l, x) = pair
                            .split_once(':')
                            .ok_or_else(|| bad(v, "expected wavelength:value pairs"))?;
                        let (Ok(l), Ok(x)) = (l.trim().parse::<f32>(), x.trim().parse::<f32>())
                        else {
                            return Err(bad(v, "expected wavelength:value pairs of numbers"));
                        };
                        if !(l.is_finite() && x.is_finite()) {
                            return Err(bad(v, "values must be finite"));
                        }
                        wl.push(l);
                        val.push(x);
                    }
                    (wl, val)
                };
                if wl.is_empty() || wl.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(format!(
                        "{}: <spectrum name=\"{name}\">: wavelengths must be given in increasing order",
                        p.at
                    ));
                }
                Ok(Color::Rgb(spectrum_to_rgb(
                    &wl,
                    &val,
                    use_ == Use::Reflectance,
                )))
            }
            "texture" => {
                let kind = p.kind();
                if !known_plugin("texture", kind) {
                    return Err(format!("{}: unknown texture plugin '{kind}'", p.at));
                }
                match kind {
                    "bitmap" => {
                        let f = self.string(p, "filename")?.ok_or_else(|| {
                            format!("{}: bitmap texture without a filename", p.at)
                        })?;
                        let path = self.path(&f);
                        crate::input::check_regular_file(&path, crate::input::max_input_bytes()?)
                            .map_err(|e| format!("{}: bitmap texture: {e}", p.at))?;
                        for k in ["filter_type", "wrap_mode", "raw", "format"] {
                            if let Some(c) = self.prop(p, k) {
                                let v = c.attr("value").unwrap_or("");
                                let fine = matches!(
                                    (k, v),
                                    ("filter_type", "bilinear")
                                        | ("wrap_mode", "repeat")
                                        | ("raw", "false")
                                );
                                if !fine {
                                    self.warn(
                                        &format!("bitmap {k}"),
                                        format!(
                                            "{}: bitmap {k} '{v}' is not supported: bilinear, repeating, sRGB-decoded 8-bit or linear EXR",
                                            c.at
                                        ),
                                    );
                                }
                            }
                        }
                        if let Some(t) = self.prop(p, "to_uv") {
                            t.used.set(true);
                            self.warn(
                                "bitmap to_uv",
                                format!("{}: bitmap to_uv is not supported: ignored", t.at),
                            );
                        }
                        self.unused(p, "texture 'bitmap'");
                        Ok(Color::Bitmap(path))
                    }
                    "checkerboard" => {
                        let a = self.color(p, "color0", use_)?;
                        let b = self.color(p, "color1", use_)?;
                        let a = match a {
                            Some(c) => self.mean_rgb(c, &p.at)?,
                            None => [0.4; 3],
                        };
                        let b = match b {
                            Some(c) => self.mean_rgb(c, &p.at)?,
                            None => [0.2; 3],
                        };
                        self.mark_all(p);
                        self.warn(
                            "texture checkerboard",
                            format!(
                                "{}: checkerboard texture is not supported: rendered as the mean of its colours",
                                p.at
                            ),
                        );
                        Ok(Color::Rgb([0, 1, 2].map(|i| 0.5 * (a[i] + b[i]))))
                    }
                    k => {
                        self.mark_all(p);
                        self.warn(
                            &format!("texture {k}"),
                            format!(
                                "{}: unsupported texture '{k}': rendered as 0.5 (grey)",
                                p.at
                            ),
                        );
                        Ok(Color::Rgb([0.5; 3]))
                    }
                }
            }
            t => Err(format!(
                "{}: <{t} name=\"{name}\">: expected a colour (rgb, spectrum, float or texture)",
                p.at
            )),
        }
    }

    /// The mean of a colour (a bitmap's mean texel).
    fn mean_rgb(&self, c: Color, at: &str) -> R<[f32; 3]> {
        match c {
            Color::Rgb(v) => Ok(v),
            Color::Bitmap(p) => super::Texture::load(&p)
                .map(|t| t.mean())
                .map_err(|e| format!("{at}: {e}")),
        }
    }

    /// A colour used where kalos takes a constant: a texture gives its mean, warned.
    fn constant(&self, el: &'a El, name: &str, use_: Use, plugin: &str) -> R<Option<[f32; 3]>> {
        match self.color(el, name, use_)? {
            None => Ok(None),
            Some(Color::Rgb(v)) => Ok(Some(v)),
            Some(c @ Color::Bitmap(_)) => {
                self.warn(
                    &format!("texture in {plugin} {name}"),
                    format!(
                        "{}: a texture as {plugin} '{name}' is not supported: rendered with its mean",
                        el.at
                    ),
                );
                Ok(Some(self.mean_rgb(c, &el.at)?))
            }
        }
    }

    fn mark_all(&self, el: &El) {
        for c in &el.children {
            c.used.set(true);
        }
    }

    /// Warn (once per plugin and name) about parameters that were never read.
    fn unused(&self, el: &El, plugin: &str) {
        const QUIET: &[&str] = &[
            "near_clip",
            "far_clip",
            "focus_distance",
            "pixel_format",
            "component_format",
            "file_format",
            "id",
            "sample_visible",
            "banner",
            "high_quality_edges",
            "specular_sampling_weight",
            "seed",
        ];
        for c in &el.children {
            if c.used.get() {
                continue;
            }
            let n = c.name().unwrap_or(c.tag.as_str());
            if QUIET.contains(&n) {
                continue;
            }
            self.warn(
                &format!("unused {plugin} {n}"),
                format!(
                    "{}: parameter '{n}' of {plugin} is not supported: ignored",
                    c.at
                ),
            );
        }
    }

    // ------------------------------------------------------------------------------------
    // BSDFs
    // ------------------------------------------------------------------------------------

    fn ior(&self, el: &'a El, name: &str, default: &str) -> R<f32> {
        let Some(p) = self.prop(el, name) else {
            return Ok(IORS.iter().find(|(n, _)| *n == default).unwrap().1);
        };
        let v = self.value(p)?;
        if p.tag == "string" {
            return IORS
                .iter()
                .find(|(n, _)| n.eq_ignore_ascii_case(v.trim()))
                .map(|(_, x)| *x)
                .ok_or_else(|| {
                    format!(
                        "{}: {name} \"{v}\": not a number nor one of Mitsuba's named indices ({})",
                        p.at,
                        IORS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                    )
                });
        }
        let x: f32 = v
            .trim()
            .parse()
            .ok()
            .filter(|x: &f32| x.is_finite() && *x > 0.0)
            .ok_or_else(|| format!("{}: {name} \"{v}\": not a positive number", p.at))?;
        Ok(x)
    }

    /// Roughness and microfacet distribution of a rough plugin (alpha, or alpha_u / alpha_v:
    /// their geometric mean; `distribution` Beckmann unless it says ggx, as in Mitsuba).
    fn alpha(&self, el: &'a El, plugin: &str) -> R<(f32, Distribution)> {
        let dist = match self.string(el, "distribution")? {
            None => Distribution::Beckmann,
            Some(d) => Distribution::from_name(d.trim()).ok_or_else(|| {
                format!(
                    "{}: {plugin} distribution \"{d}\": must be \"beckmann\" or \"ggx\"",
                    el.at
                )
            })?,
        };
        // Mitsuba's switch between visible-normal and plain D sampling: the same image
        // (kalos always samples visible normals)
        let _ = self.boolean(el, "sample_visible")?;
        let a = self.float(el, "alpha")?;
        let (u, v) = (self.float(el, "alpha_u")?, self.float(el, "alpha_v")?);
        let alpha = match (a, u, v) {
            // Mitsuba refuses both forms at once, and one of alpha_u, alpha_v alone
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(format!(
                    "{}: {plugin}: give either alpha or alpha_u and alpha_v, not both",
                    el.at
                ))
            }
            (None, Some(_), None) | (None, None, Some(_)) => {
                return Err(format!(
                    "{}: {plugin}: alpha_u and alpha_v must be given together",
                    el.at
                ))
            }
            (Some(a), None, None) => a,
            (None, Some(u), Some(v)) => {
                if u != v {
                    self.warn(
                        "anisotropic",
                        format!(
                            "{}: anisotropic roughness (alpha_u {u}, alpha_v {v}): rendered isotropic with alpha {}",
                            el.at,
                            (u * v).sqrt()
                        ),
                    );
                }
                (u * v).sqrt()
            }
            _ => 0.1,
        };
        if !(0.0..=10.0).contains(&alpha) {
            return Err(format!(
                "{}: {plugin} alpha {alpha}: must be in [0, 10]",
                el.at
            ));
        }
        Ok((alpha.max(1e-4), dist))
    }

    /// Set `kd`/`map_kd` from a diffuse reflectance.
    fn set_diffuse(&self, m: &mut MaterialDesc, c: Option<Color>, default: f32) {
        match c {
            None => m.kd = [default; 3],
            Some(Color::Rgb(v)) => m.kd = v,
            Some(Color::Bitmap(p)) => {
                m.kd = [1.0; 3];
                m.map_kd = Some(p);
            }
        }
    }

    /// A BSDF element (inline or referenced) as a material description.
    fn bsdf(&self, el: &'a El) -> R<MaterialDesc> {
        let el = self.resolve(el)?;
        if el.tag != "bsdf" {
            return Err(format!(
                "{}: <{}> where a <bsdf> was expected",
                el.at, el.tag
            ));
        }
        let kind = el.kind();
        if !known_plugin("bsdf", kind) {
            return Err(format!("{}: unknown bsdf plugin '{kind}'", el.at));
        }
        let name = el
            .attr("id")
            .map(str::to_string)
            .unwrap_or_else(|| format!("{kind}@{}", el.at.rsplit(':').next().unwrap_or("")));
        let mut m = MaterialDesc::named(&name);
        m.source = Some(el.at.clone());
        let nested = || -> R<Option<&'a El>> {
            let mut it = el.children.iter().filter(|c| {
                c.tag == "bsdf"
                    || (c.tag == "ref" && self.resolve(c).map(|r| r.tag == "bsdf").unwrap_or(false))
            });
            let first = it.next();
            if let Some(f) = first {
                f.used.set(true);
            }
            for extra in it {
                extra.used.set(true);
                if kind == "twosided" {
                    self.warn(
                        "twosided two bsdfs",
                        format!(
                            "{}: twosided with a different bsdf per side: kalos renders the first on both sides",
                            extra.at
                        ),
                    );
                }
            }
            Ok(first)
        };
        match kind {
            "diffuse" | "roughdiffuse" => {
                let c = self.color(el, "reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                if kind == "roughdiffuse" {
                    self.mark_all(el);
                    self.warn(
                        "bsdf roughdiffuse",
                        format!(
                            "{}: roughdiffuse (Oren-Nayar) is rendered as Lambertian diffuse",
                            el.at
                        ),
                    );
                }
            }
            "conductor" | "roughconductor" => {
                let (alpha, distribution) = if kind == "roughconductor" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let material = self.string(el, "material")?;
                let (mut eta, mut k) = match &material {
                    Some(n) => {
                        let find = |n: &str| METALS.iter().find(|(m, _, _)| *m == n);
                        // Mitsuba's documented list (and 0.6's files) also name Palik's
                        // measurements, "Cu_palik", "Ni_palik": the element's data stands in
                        let palik = n.strip_suffix("_palik").and_then(find);
                        let f = find(n).or(palik).ok_or_else(|| {
                            format!(
                                "{}: conductor material \"{n}\": not one of Mitsuba's named conductors ({})",
                                el.at,
                                METALS.iter().map(|(m, _, _)| *m).collect::<Vec<_>>().join(", ")
                            )
                        })?;
                        if find(n).is_none() {
                            self.warn(
                                &format!("palik {n}"),
                                format!(
                                    "{}: conductor material \"{n}\": rendered with \"{}\" (Palik's tables are not bundled; the two differ by a few percent)",
                                    el.at, f.0
                                ),
                            );
                        }
                        (f.1, f.2)
                    }
                    None => ([0.0; 3], [1.0; 3]),
                };
                if let Some(e) = self.constant(el, "eta", Use::Unbounded, kind)? {
                    eta = e;
                }
                if let Some(x) = self.constant(el, "k", Use::Unbounded, kind)? {
                    k = x;
                }
                let specular = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([1.0; 3]);
                let r0: [f32; 3] = [0, 1, 2].map(|i| conductor_r0(eta[i], k[i]) * specular[i]);
                m.kd = [0.0; 3];
                m.ks = r0;
                if alpha == 0.0 {
                    m.illum = 5;
                } else {
                    m.illum = 2;
                    m.ns = phong_exponent(alpha);
                }
                m.model = Some(SurfaceModel::Conductor {
                    eta,
                    k,
                    specular,
                    alpha: if kind == "conductor" { 0.0 } else { alpha },
                    distribution,
                });
            }
            "plastic" | "roughplastic" => {
                let (alpha, distribution) = if kind == "roughplastic" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let eta =
                    self.ior(el, "int_ior", "polypropylene")? / self.ior(el, "ext_ior", "air")?;
                let c = self.color(el, "diffuse_reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                let specular = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([1.0; 3]);
                let nonlinear = self.boolean(el, "nonlinear")?.unwrap_or(false);
                // Mitsuba's diffuse term: R (1 - F_i)(1 - F_o) / (eta^2 (1 - {R or 1} Fdr_int))
                let f0 = fresnel_dielectric(1.0, eta);
                let fdr_int = fresnel_diffuse(1.0 / eta);
                let t = (1.0 - f0) * (1.0 - f0) / (eta * eta);
                let scale = |r: f32| {
                    let d = 1.0 - if nonlinear { r } else { 1.0 } * fdr_int;
                    if d > 0.0 {
                        t / d
                    } else {
                        1.0
                    }
                };
                if m.map_kd.is_none() {
                    m.kd = m.kd.map(|r| r * scale(r));
                }
                m.ks = specular.map(|s| s * f0);
                m.ns = if alpha == 0.0 {
                    10000.0
                } else {
                    phong_exponent(alpha)
                };
                m.model = Some(SurfaceModel::Plastic {
                    eta,
                    specular,
                    alpha: if kind == "plastic" { 0.0 } else { alpha },
                    distribution,
                    nonlinear,
                });
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let (alpha, distribution) = if kind == "roughdielectric" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let eta = self.ior(el, "int_ior", "bk7")? / self.ior(el, "ext_ior", "air")?;
                for k in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = self.constant(el, k, Use::Reflectance, kind)? {
                        if c != [1.0; 3] {
                            self.warn(
                                &format!("{kind} {k}"),
                                format!(
                                    "{}: {kind} {k} other than 1 is not supported: rendered as 1",
                                    el.at
                                ),
                            );
                        }
                    }
                }
                m.kd = [0.0; 3];
                m.illum = 7;
                if kind == "thindielectric" {
                    // no refraction of the direction: an index of 1 (see-through) is closest
                    m.ni = 1.0;
                    m.model = Some(SurfaceModel::ThinDielectric { eta });
                } else {
                    m.ni = eta;
                    m.model = Some(SurfaceModel::Dielectric {
                        eta,
                        alpha,
                        distribution,
                    });
                }
            }
            "phong" => {
                let c = self.color(el, "diffuse_reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                m.ks = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([0.2; 3]);
                m.ns = self.float(el, "exponent")?.unwrap_or(30.0);
            }
            "twosided" | "mask" | "bumpmap" | "normalmap" => {
                let inner =
                    nested()?.ok_or_else(|| format!("{}: {kind} needs a nested <bsdf>", el.at))?;
                let mut inner_m = self.bsdf(inner)?;
                match kind {
                    "mask" => {
                        let op = self.prop(el, "opacity");
                        self.mark_all(el);
                        self.warn(
                            "bsdf mask",
                            format!(
                                "{}: mask (opacity{}) is not supported: rendered opaque",
                                el.at,
                                op.and_then(|o| o.attr("value"))
                                    .map(|v| format!(" {v}"))
                                    .unwrap_or_default()
                            ),
                        );
                    }
                    "bumpmap" | "normalmap" => {
                        self.mark_all(el);
                        self.warn(
                            &format!("bsdf {kind}"),
                            format!("{}: {kind} is not supported: rendered without it", el.at),
                        );
                    }
                    _ => {}
                }
                if el.attr("id").is_some() {
                    inner_m.name = name;
                }
                if kind == "twosided" {
                    inner_m.one_sided = false;
                }
                self.unused(el, &format!("bsdf '{kind}'"));
                return Ok(inner_m);
            }
            "blendbsdf" | "mixturebsdf" => {
                let inner = nested()?;
                self.mark_all(el);
                self.warn(
                    &format!("bsdf {kind}"),
                    format!(
                        "{}: {kind} is not supported: rendered as its first bsdf",
                        el.at
                    ),
                );
                if let Some(i) = inner {
                    let mut im = self.bsdf(i)?;
                    if el.attr("id").is_some() {
                        im.name = name;
                    }
                    return Ok(im);
                }
            }
            "principled" | "principledthin" => {
                let c = self.color(el, "base_color", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                self.mark_all(el);
                self.warn(
                    &format!("bsdf {kind}"),
                    format!(
                        "{}: unsupported bsdf '{kind}': rendered as diffuse base_color",
                        el.at
                    ),
                );
            }
            "null" => {
                m.kd = [0.0; 3];
                m.notes
                    .push("null bsdf: kalos renders it black (it should let light through)".into());
            }
            k => {
                self.mark_all(el);
                self.warn(
                    &format!("bsdf {k}"),
                    format!(
                        "{}: unsupported bsdf '{k}': rendered as diffuse grey (0.5)",
                        el.at
                    ),
                );
            }
        }
        // Mitsuba's BSDFs reflect on the front only, unless wrapped in `twosided` (above);
        // a thin slab is symmetric
        m.one_sided = !matches!(kind, "thindielectric" | "null");
        self.unused(el, &format!("bsdf '{kind}'"));
        Ok(m)
    }

    /// The material index of a BSDF element (a referenced one is built once).
    fn material(&mut self, el: &'a El) -> R<u32> {
        let target = self.resolve(el)?;
        let key = target as *const El;
        if let Some(&i) = self.materials.get(&key) {
            return Ok(i);
        }
        let m = self.bsdf(target)?;
        self.desc.materials.push(m);
        let i = self.desc.materials.len() as u32 - 1;
        self.materials.insert(key, i);
        Ok(i)
    }

    fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        // Mitsuba's default: a one-sided diffuse of reflectance 0.5
        let mut m = MaterialDesc::named("mitsuba-default-diffuse");
        m.one_sided = true;
        self.desc.materials.push(m);
        let i = self.desc.materials.len() as u32 - 1;
        self.default_material = Some(i);
        i
    }

    // ------------------------------------------------------------------------------------
    // Shapes
    // ------------------------------------------------------------------------------------

    fn shape(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("shape", kind) {
            return Err(format!("{}: unknown shape plugin '{kind}'", el.at));
        }
        let supported = matches!(
            kind,
            "obj" | "ply" | "rectangle" | "cube" | "sphere" | "disk"
        );
        if !supported {
            self.mark_all(el);
            let why = if kind == "serialized" {
                " (Mitsuba's own binary mesh format; convert it to PLY, e.g. with Mitsuba's Python API)"
            } else {
                ""
            };
            self.warn(
                &format!("shape {kind}"),
                format!(
                    "{}: unsupported shape '{kind}'{why}: left out of the scene",
                    el.at
                ),
            );
            return Ok(());
        }
        // the material: a nested or referenced bsdf, or Mitsuba's default diffuse 0.5
        let mut bsdf_el = None;
        let mut emitter_el = None;
        for c in &el.children {
            let t = if c.tag == "ref" { self.resolve(c)? } else { c };
            match t.tag.as_str() {
                "bsdf" => {
                    c.used.set(true);
                    if bsdf_el.is_some() {
                        return Err(format!("{}: a shape takes one bsdf", c.at));
                    }
                    bsdf_el = Some(c);
                }
                "emitter" => {
                    c.used.set(true);
                    emitter_el = Some(t);
                }
                "medium" => {
                    c.used.set(true);
                    self.warn(
                        "medium",
                        format!("{}: participating media are not supported: ignored", c.at),
                    );
                }
                _ => {}
            }
        }
        let mut mat = match bsdf_el {
            Some(b) => self.material(b)?,
            None => self.default_material(),
        };
        let null_bsdf = bsdf_el
            .map(|b| self.resolve(b).map(|r| r.kind() == "null"))
            .transpose()?
            .unwrap_or(false);
        if let Some(e) = emitter_el {
            if e.kind() != "area" {
                return Err(format!(
                    "{}: a shape's emitter must be 'area', not '{}'",
                    e.at,
                    e.kind()
                ));
            }
            let radiance = self
                .constant(e, "radiance", Use::Unbounded, "area emitter")?
                .ok_or_else(|| format!("{}: area emitter without a radiance", e.at))?;
            self.unused(e, "emitter 'area'");
            let mut m = self.desc.materials[mat as usize].clone();
            m.name = format!(
                "{}+emitter@{}",
                m.name,
                e.at.rsplit(':').next().unwrap_or("")
            );
            m.ke = radiance;
            self.desc.materials.push(m);
            mat = self.desc.materials.len() as u32 - 1;
        } else if null_bsdf {
            self.warn(
                "null shape",
                format!(
                    "{}: a shape with a null bsdf and no emitter is invisible: left out",
                    el.at
                ),
            );
            self.mark_all(el);
            return Ok(());
        }
        let xf = self.transform(el, "to_world")?;
        let flip = self.boolean(el, "flip_normals")?.unwrap_or(false);
        let face_normals = self.boolean(el, "face_normals")?.unwrap_or(false);
        let flip_tex = self.boolean(el, "flip_tex_coords")?.unwrap_or(true);
        // local mesh: positions, triangles, optional normals and uvs (kalos' v: up)
        let mesh = match kind {
            "obj" | "ply" => {
                let f = self
                    .string(el, "filename")?
                    .ok_or_else(|| format!("{}: {kind} shape without a filename", el.at))?;
                let path = self.path(&f);
                let mut m = if kind == "ply" {
                    super::ply::load_ply(&path).map_err(|e| format!("{}: {e}", el.at))?
                } else {
                    self.obj_mesh(&path)
                        .map_err(|e| format!("{}: {e}", el.at))?
                };
                if !flip_tex {
                    if let Some(uv) = &mut m.uvs {
                        for t in uv.iter_mut() {
                            t.y = 1.0 - t.y;
                        }
                    }
                }
                m
            }
            "rectangle" => {
                let p = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                super::ply::PlyMesh {
                    positions: p.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
                    normals: None,
                    uvs: Some(
                        p.iter()
                            .map(|&(x, y)| Vec2::new((x + 1.0) * 0.5, (1.0 - y) * 0.5))
                            .collect(),
                    ),
                    triangles: vec![[0, 1, 2], [0, 2, 3]],
                }
            }
            "cube" => cube(),
            "disk" => disk(128),
            "sphere" => {
                let c = self.point(el, "center")?.unwrap_or(Vec3::ZERO);
                let r = self.float(el, "radius")?.unwrap_or(1.0);
                if r <= 0.0 {
                    return Err(format!("{}: sphere radius {r}: must be positive", el.at));
                }
                let mut m = sphere(64, 128);
                for p in m.positions.iter_mut() {
                    *p = c + *p * r;
                }
                m
            }
            _ => unreachable!(),
        };
        self.unused(el, &format!("shape '{kind}'"));
        // a mesh file without normals is smooth-shaded in Mitsuba unless face_normals
        let smooth = matches!(kind, "obj" | "ply") && mesh.normals.is_none() && !face_normals;
        self.push_mesh(&mesh, xf, flip, face_normals, smooth, mat);
        Ok(())
    }

    /// An OBJ file's triangles as Mitsuba reads them: its materials are not used.
    fn obj_mesh(&self, path: &Path) -> R<super::ply::PlyMesh> {
        let text = crate::input::read_text_lossy(path)?;
        let mut d = SceneDesc::default();
        let empty = |_: &str| Some("");
        super::obj::load_obj_text(
            &text,
            &path.display().to_string(),
            super::obj::MtlSource::Embedded(&empty),
            Mat4::IDENTITY,
            &mut d,
        )?;
        let mut m = super::ply::PlyMesh::default();
        let has_n = d.normals.iter().all(|n| n.is_some()) && !d.normals.is_empty();
        let has_uv = d.uvs.iter().all(|n| n.is_some()) && !d.uvs.is_empty();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        // Without normals or uvs, corners at one position are one vertex, as Mitsuba's OBJ
        // loader shares a `v` index: its recomputed normals are smooth across them.
        let weld = !has_n && !has_uv;
        let mut index: HashMap<[u32; 3], u32> = HashMap::new();
        for (i, t) in d.positions.iter().enumerate() {
            if weld {
                let tri = t.map(|p| {
                    *index
                        .entry(p.to_array().map(f32::to_bits))
                        .or_insert_with(|| {
                            m.positions.push(p);
                            m.positions.len() as u32 - 1
                        })
                });
                m.triangles.push(tri);
                continue;
            }
            let b = m.positions.len() as u32;
            m.positions.extend_from_slice(t);
            if has_n {
                normals.extend_from_slice(&d.normals[i].unwrap());
            }
            if has_uv {
                uvs.extend_from_slice(&d.uvs[i].unwrap());
            }
            m.triangles.push([b, b + 1, b + 2]);
        }
        m.normals = has_n.then_some(normals);
        m.uvs = has_uv.then_some(uvs);
        Ok(m)
    }

    fn push_mesh(
        &mut self,
        m: &super::ply::PlyMesh,
        xf: Mat4,
        flip: bool,
        face_normals: bool,
        smooth: bool,
        mat: u32,
    ) {
        let nxf = Mat3::from_mat4(xf).inverse().transpose();
        // a mirroring transform turns the winding: keep the front where the normals go
        let mirrored = Mat3::from_mat4(xf).determinant() < 0.0;
        let order = if mirrored != flip {
            [0, 2, 1]
        } else {
            [0, 1, 2]
        };
        let sign = if flip { -1.0 } else { 1.0 };
        let pos: Vec<Vec3> = m
            .positions
            .iter()
            .map(|p| xf.transform_point3(*p))
            .collect();
        let nrm: Option<Vec<Vec3>> = if smooth {
            Some(vertex_normals(&pos, &m.triangles, order))
        } else {
            (!face_normals)
                .then(|| {
                    m.normals.as_ref().map(|ns| {
                        ns.iter()
                            .map(|n| (nxf * *n).normalize_or_zero() * sign)
                            .collect()
                    })
                })
                .flatten()
        };
        for t in &m.triangles {
            let i = order.map(|k| t[k] as usize);
            let v = i.map(|k| pos[k]);
            let n = nrm.as_ref().and_then(|ns| {
                let n = i.map(|k| ns[k]);
                n.iter().all(|x| x.length_squared() > 0.5).then_some(n)
            });
            let uv = m.uvs.as_ref().map(|uv| i.map(|k| uv[k]));
            self.desc.push_triangle(v, n, uv, mat);
        }
    }

    // ------------------------------------------------------------------------------------
    // Emitters, sensor, integrator
    // ------------------------------------------------------------------------------------

    fn emitter(&mut self, el: &'a El) -> R<()> {
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
                    .unwrap_or_else(|| spectrum_to_rgb(&[360.0, 830.0], &[1.0, 1.0], false));
                self.desc.point_lights.push(PointLightDesc {
                    position: p,
                    intensity,
                    source: Some(el.at.clone()),
                });
            }
            "constant" | "envmap" => {
                let xf = self.transform(el, "to_world")?;
                let (radiance, map) = if kind == "constant" {
                    let r = self
                        .constant(el, "radiance", Use::Unbounded, "constant emitter")?
                        .unwrap_or_else(|| spectrum_to_rgb(&[360.0, 830.0], &[1.0, 1.0], false));
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

    fn sensor(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("sensor", kind) {
            return Err(format!("{}: unknown sensor plugin '{kind}'", el.at));
        }
        if self.sensor_seen {
            self.mark_all(el);
            self.warn(
                "second sensor",
                format!("{}: more than one sensor: kalos uses the first", el.at),
            );
            return Ok(());
        }
        self.sensor_seen = true;
        // film and sampler first: the field of view may depend on the aspect ratio
        let (mut w, mut h) = (768u32, 576u32);
        for c in &el.children {
            let t = if c.tag == "ref" { self.resolve(c)? } else { c };
            match t.tag.as_str() {
                "film" => {
                    c.used.set(true);
                    if !known_plugin("film", t.kind()) {
                        return Err(format!("{}: unknown film plugin '{}'", t.at, t.kind()));
                    }
                    if let Some(x) = self.int(t, "width")? {
                        w = u32::try_from(x).map_err(|_| format!("{}: film width {x}", t.at))?;
                    }
                    if let Some(x) = self.int(t, "height")? {
                        h = u32::try_from(x).map_err(|_| format!("{}: film height {x}", t.at))?;
                    }
                    crate::film::check_resolution(w, h)
                        .map_err(|e| format!("{}: film: {e}", t.at))?;
                    for r in t.children.iter().filter(|r| r.tag == "rfilter") {
                        r.used.set(true);
                        if !known_plugin("rfilter", r.kind()) {
                            return Err(format!("{}: unknown rfilter plugin '{}'", r.at, r.kind()));
                        }
                        if r.kind() != "box" {
                            self.warn(
                                "rfilter",
                                format!(
                                    "{}: pixel filter '{}': kalos uses a box filter (the same mean, sharper edges, more noise)",
                                    r.at,
                                    r.kind()
                                ),
                            );
                        }
                        self.mark_all(r);
                    }
                    for k in [
                        "crop_offset_x",
                        "crop_offset_y",
                        "crop_width",
                        "crop_height",
                    ] {
                        if self.prop(t, k).is_some() {
                            self.warn(
                                "crop",
                                format!("{}: film cropping is not supported: the whole image is rendered", t.at),
                            );
                        }
                    }
                    self.unused(t, &format!("film '{}'", t.kind()));
                }
                "sampler" => {
                    c.used.set(true);
                    if !known_plugin("sampler", t.kind()) {
                        return Err(format!("{}: unknown sampler plugin '{}'", t.at, t.kind()));
                    }
                    if let Some(n) = self.int(t, "sample_count")? {
                        let n = u32::try_from(n).ok().filter(|n| *n >= 1).ok_or_else(|| {
                            format!("{}: sample_count {n}: must be at least 1", t.at)
                        })?;
                        self.desc.defaults.spp = Some(n);
                    }
                    self.mark_all(t);
                }
                _ => {}
            }
        }
        self.desc.defaults.res = Some((w, h));
        if !matches!(kind, "perspective" | "thinlens") {
            self.mark_all(el);
            self.warn(
                &format!("sensor {kind}"),
                format!(
                    "{}: unsupported sensor '{kind}': kalos uses its default camera",
                    el.at
                ),
            );
            return Ok(());
        }
        if kind == "thinlens" {
            self.warn(
                "thinlens",
                format!(
                    "{}: thinlens sensor rendered as a pinhole (no depth of field)",
                    el.at
                ),
            );
            for k in ["aperture_radius", "focus_distance"] {
                self.prop(el, k);
            }
        }
        let axis = self.string(el, "fov_axis")?.unwrap_or_else(|| "x".into());
        let (fov, axis) = match (self.float(el, "fov")?, self.string(el, "focal_length")?) {
            (Some(f), _) => (f, axis),
            (None, fl) => {
                let fl = fl.unwrap_or_else(|| "50mm".into());
                let mm: f32 = fl
                    .trim()
                    .trim_end_matches("mm")
                    .trim()
                    .parse()
                    .ok()
                    .filter(|v: &f32| *v > 0.0 && v.is_finite())
                    .ok_or_else(|| {
                        format!("{}: focal_length \"{fl}\": expected e.g. 50mm", el.at)
                    })?;
                let film = match axis.as_str() {
                    "y" => 24.0f32,
                    "diagonal" => 36.0f32.hypot(24.0),
                    _ => 36.0,
                };
                ((2.0 * (film / (2.0 * mm)).atan()).to_degrees(), axis)
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(format!("{}: fov {fov}: must be in (0, 180) degrees", el.at));
        }
        let fov_axis = FovAxis::parse(&axis).ok_or_else(|| {
            format!(
                "{}: fov_axis \"{axis}\": expected x, y, diagonal, smaller or larger",
                el.at
            )
        })?;
        let xf = self.transform(el, "to_world")?;
        let origin = xf.transform_point3(Vec3::ZERO);
        let fwd = xf.transform_vector3(Vec3::Z).normalize_or_zero();
        let up = xf.transform_vector3(Vec3::Y).normalize_or_zero();
        if Mat3::from_mat4(xf).determinant() < 0.0 {
            self.warn(
                "mirrored sensor",
                format!(
                    "{}: the sensor's to_world mirrors the image (negative determinant): kalos renders it unmirrored",
                    el.at
                ),
            );
        }
        let cam = CameraDesc {
            origin: origin.into(),
            target: (origin + fwd).into(),
            up: up.into(),
            fov,
            fov_axis,
        };
        cam.validate()
            .map_err(|e| format!("{}: sensor: {e}", el.at))?;
        self.desc.camera = Some(cam);
        self.unused(el, &format!("sensor '{kind}'"));
        Ok(())
    }

    fn integrator(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("integrator", kind) {
            return Err(format!("{}: unknown integrator plugin '{kind}'", el.at));
        }
        match kind {
            "path" | "volpath" | "volpathmis" | "prb" | "prbvolpath" | "bdpt" => {
                if kind != "path" {
                    self.warn(
                        "integrator",
                        format!("{}: integrator '{kind}': kalos renders the same image with its own estimator (see --integrator)", el.at),
                    );
                }
                if let Some(d) = self.int(el, "max_depth")? {
                    if d < -1 || d == 0 {
                        return Err(format!(
                            "{}: max_depth {d}: must be -1 (unlimited) or at least 1",
                            el.at
                        ));
                    }
                    self.desc.defaults.max_depth = Some(d.min(i32::MAX as i64) as i32);
                }
                // Mitsuba's roulette starts at depth rr_depth (default 5), counting the
                // first hit as 1; kalos' --rr-min-depth counts the reflections before it.
                let rr_depth = self.int(el, "rr_depth")?.unwrap_or(5);
                self.desc.defaults.rr_min_depth =
                    Some(rr_depth.saturating_sub(1).clamp(0, u32::MAX as i64) as u32);
                if self.boolean(el, "hide_emitters")? == Some(true) {
                    self.warn(
                        "hide_emitters",
                        format!(
                            "{}: hide_emitters is not supported: emitters are visible",
                            el.at
                        ),
                    );
                }
                self.unused(el, &format!("integrator '{kind}'"));
            }
            "direct" => {
                self.mark_all(el);
                self.desc.defaults.max_depth = Some(2);
                self.warn(
                    "integrator",
                    format!(
                        "{}: integrator 'direct': rendered as the path tracer with max_depth 2",
                        el.at
                    ),
                );
            }
            // Mitsuba's AOV integrator: the radiance is its nested integrator's
            "aov" => {
                self.mark_all(el);
                self.warn(
                    "integrator aov",
                    format!(
                        "{}: integrator 'aov': kalos renders the radiance of the nested integrator, without the AOVs (see --aovs)",
                        el.at
                    ),
                );
                for c in el.children.iter().filter(|c| c.tag == "integrator") {
                    self.integrator(c)?;
                }
            }
            k => {
                self.mark_all(el);
                self.warn(
                    "integrator",
                    format!("{}: unsupported integrator '{k}': kalos renders radiance with its path tracer", el.at),
                );
            }
        }
        Ok(())
    }
}

/// Refuse an environment map that is not an image kalos or Mitsuba reads (by its first
/// bytes: EXR, Radiance HDR, PFM, PNG, JPEG).
fn check_image(path: &Path) -> R<()> {
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

fn cube() -> super::ply::PlyMesh {
    let mut m = super::ply::PlyMesh {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let b = m.positions.len() as u32;
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push(n + u * x + v * y);
            m.uvs
                .as_mut()
                .unwrap()
                .push(Vec2::new((x + 1.0) * 0.5, (y + 1.0) * 0.5));
        }
        m.triangles.push([b, b + 1, b + 2]);
        m.triangles.push([b, b + 2, b + 3]);
    }
    m
}

fn disk(n: u32) -> super::ply::PlyMesh {
    let mut m = super::ply::PlyMesh {
        uvs: Some(vec![Vec2::new(0.0, 1.0)]),
        positions: vec![Vec3::ZERO],
        ..Default::default()
    };
    for i in 0..n {
        let phi = std::f32::consts::TAU * i as f32 / n as f32;
        m.positions.push(Vec3::new(phi.cos(), phi.sin(), 0.0));
        m.uvs
            .as_mut()
            .unwrap()
            .push(Vec2::new(1.0, 1.0 - i as f32 / n as f32));
        m.triangles.push([0, 1 + i, 1 + (i + 1) % n]);
    }
    m
}

/// A unit sphere of `rings` x `segs` quads with exact normals (Mitsuba's uv: phi / 2 pi,
/// theta / pi).
fn sphere(rings: u32, segs: u32) -> super::ply::PlyMesh {
    let mut m = super::ply::PlyMesh {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segs {
            let phi = std::f32::consts::TAU * s as f32 / segs as f32;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            m.positions.push(p);
            m.normals.as_mut().unwrap().push(p);
            m.uvs.as_mut().unwrap().push(Vec2::new(
                s as f32 / segs as f32,
                1.0 - r as f32 / rings as f32,
            ));
        }
    }
    let idx = |r: u32, s: u32| r * (segs + 1) + s;
    for r in 0..rings {
        for s in 0..segs {
            let (a, b, c, d) = (idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1));
            // outward: counter-clockwise seen from outside (theta grows towards -z)
            if r != 0 {
                m.triangles.push([a, b, d]);
            }
            if r + 1 != rings {
                m.triangles.push([b, c, d]);
            }
        }
    }
    m
}

/// Load a Mitsuba XML scene file.
pub fn load(path: &Path) -> Result<SceneDesc, String> {
    let text = crate::input::read_text(path)?;
    parse(
        &text,
        &path.display().to_string(),
        path.parent().unwrap_or(Path::new(".")),
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
    let mut d = parse_inner(text, file, dir).map_err(one_line)?;
    d.warnings = d.warnings.into_iter().map(one_line).collect();
    Ok(d)
}

fn parse_inner(text: &str, file: &str, dir: &Path) -> Result<SceneDesc, String> {
    let mut reader = Reader {
        defaults: HashMap::new(),
        warnings: Vec::new(),
    };
    let top = reader.read_text(text, file, dir, 0)?;
    let mut ld = Loader {
        dir: dir.to_path_buf(),
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
            "path" | "alias" => ld.warn(
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
    if desc.positions.is_empty() {
        return Err(format!("{file}: the scene has no shapes kalos can render"));
    }
    Ok(desc)
}

/// Vertex normals of a mesh that has none, as Mitsuba recomputes them (in world space,
/// after `to_world`): each face's unit normal added to its corners weighted by the
/// corner's angle (Thuermer and Wuthrich 1998), then normalised; a vertex whose sum
/// vanishes gets zero (its triangles keep their face normal).
fn vertex_normals(pos: &[Vec3], tris: &[[u32; 3]], order: [usize; 3]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; pos.len()];
    for t in tris {
        let i = order.map(|k| t[k] as usize);
        let v = i.map(|k| pos[k]);
        let face = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        if face == Vec3::ZERO {
            continue;
        }
        for j in 0..3 {
            let a = (v[(j + 1) % 3] - v[j]).normalize_or_zero();
            let b = (v[(j + 2) % 3] - v[j]).normalize_or_zero();
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            n[i[j]] += face * angle;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

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

    /// Mitsuba's path integrator starts its roulette at depth rr_depth (5 by default, the
    /// first hit counting 1): kalos' --rr-min-depth default becomes rr_depth - 1.
    #[test]
    fn rr_depth_becomes_the_roulette_default() {
        let shape = r#"<shape type="rectangle"><bsdf type="diffuse"/></shape>"#;
        assert_eq!(scene(shape).unwrap().defaults.rr_min_depth, Some(4));
        let d = scene(&format!(
            r#"<integrator type="path"><integer name="rr_depth" value="3"/></integrator>{shape}"#
        ))
        .unwrap();
        assert_eq!(d.defaults.rr_min_depth, Some(2));
        assert!(
            d.warnings.iter().all(|w| !w.contains("rr_depth")),
            "{:?}",
            d.warnings
        );
        let d = scene(&format!(r#"<integrator type="path"/>{shape}"#)).unwrap();
        assert_eq!(d.defaults.rr_min_depth, Some(4));
    }

    /// Mitsuba 0.6's diffuse reads `diffuseReflectance` before `reflectance`; a 3.x file
    /// has no such alias (the parameter is warned as unused).
    #[test]
    fn diffuse_reflectance_is_the_06_alias_of_reflectance() {
        let body = r#"<shape type="rectangle"><bsdf type="diffuse">
            <rgb name="diffuseReflectance" value="0.2 0.4 0.6"/>
            <rgb name="reflectance" value="0.9 0.9 0.9"/></bsdf></shape>"#;
        let old = parse(
            &format!("<scene version=\"0.5.0\">{body}</scene>"),
            "t.xml",
            Path::new("."),
        )
        .unwrap();
        assert_eq!(old.materials.last().unwrap().kd, [0.2, 0.4, 0.6]);
        assert!(
            old.warnings
                .iter()
                .any(|w| w.contains("overridden by diffuseReflectance")),
            "{:?}",
            old.warnings
        );
        let new = scene(&body.replace("diffuseReflectance", "diffuse_reflectance")).unwrap();
        assert_eq!(new.materials.last().unwrap().kd, [0.9; 3]);
        assert!(
            new.warnings
                .iter()
                .any(|w| w.contains("'diffuse_reflectance'")),
            "{:?}",
            new.warnings
        );
    }

    #[test]
    fn snake_case_matches_mitsuba() {
        assert_eq!(snake_case("intIOR"), "int_ior");
        assert_eq!(snake_case("toWorld"), "to_world");
        assert_eq!(snake_case("specularReflectance"), "specular_reflectance");
        assert_eq!(snake_case("max_depth"), "max_depth");
    }

    #[test]
    fn spectra_match_mitsuba_rgb_mode() {
        // values printed by Mitsuba 3.9.1 scalar_rgb (mi.traverse) for the same spectra
        let wl = [400.0, 500.0, 600.0, 700.0];
        let v = [0.1, 0.8, 0.2, 0.1];
        let r = spectrum_to_rgb(&wl, &v, true);
        let e = spectrum_to_rgb(&wl, &v, false);
        let want_r = [0.0139056, 0.584234, 0.47694];
        let want_e = [0.071468, 0.551986, 0.424139];
        for c in 0..3 {
            assert!((r[c] - want_r[c]).abs() < 0.02, "{r:?}");
            assert!((e[c] - want_e[c]).abs() < 0.02, "{e:?}");
        }
        let white = spectrum_to_rgb(&[360.0, 830.0], &[1.0, 1.0], true);
        assert!(white.iter().all(|w| (w - 1.0).abs() < 0.01), "{white:?}");
        let ee = spectrum_to_rgb(&[360.0, 830.0], &[0.3, 0.3], false);
        let want = [0.361438, 0.284487, 0.272675];
        for c in 0..3 {
            assert!((ee[c] - want[c]).abs() < 0.005, "{ee:?}");
        }
    }

    #[test]
    fn transforms_compose_in_mitsuba_order() {
        let d = scene(
            r#"<shape type="rectangle"><transform name="to_world">
                 <scale value="2"/><rotate x="1" angle="90"/><translate y="1"/>
               </transform></shape>"#,
        )
        .unwrap();
        // scale, then rotate the z=0 plane about x (to y = 0), then lift to y = 1
        let b = d.bounds();
        assert!(
            (b.min - Vec3::new(-2.0, 1.0, -2.0)).length() < 1e-5,
            "{b:?}"
        );
        assert!((b.max - Vec3::new(2.0, 1.0, 2.0)).length() < 1e-5, "{b:?}");
        // normal +z rotated by +90 degrees about x is -y
        let t = d.positions[0];
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        assert!((n - Vec3::NEG_Y).length() < 1e-5, "{n}");
    }

    #[test]
    fn defaults_refs_and_materials() {
        let d = scene(
            r#"<default name="r" value="0.25"/>
               <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/>
                 <float name="alpha" value="$r"/><string name="distribution" value="ggx"/></bsdf>
               <bsdf type="twosided" id="glassy"><bsdf type="dielectric">
                 <string name="int_ior" value="water"/></bsdf></bsdf>
               <shape type="cube"><ref id="gold"/></shape>
               <shape type="sphere"><ref name="bsdf" id="glassy"/>
                 <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>"#,
        )
        .unwrap();
        let gold = &d.materials[d.material[0] as usize];
        match gold.model {
            Some(SurfaceModel::Conductor {
                alpha,
                eta,
                distribution,
                ..
            }) => {
                assert_eq!(alpha, 0.25);
                assert_eq!(distribution, Distribution::Ggx);
                assert_eq!(eta[0], 0.143036);
            }
            ref m => panic!("{m:?}"),
        }
        assert_eq!(gold.illum, 2);
        let last = &d.materials[*d.material.last().unwrap() as usize];
        assert_eq!(last.ke, [1.0, 2.0, 3.0]);
        match last.model {
            Some(SurfaceModel::Dielectric { eta, alpha, .. }) => {
                assert!((eta - 1.333 / 1.000277).abs() < 1e-5);
                assert_eq!(alpha, 0.0);
            }
            ref m => panic!("{m:?}"),
        }
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    }

    #[test]
    fn errors_are_one_line_with_position() {
        for (body, needle) in [
            ("<shape type=\"cube\"", "t.xml:"),
            ("<shape type=\"cube\"><ref id=\"nope\"/></shape>", "t.xml:2: <ref id=\"nope\">"),
            ("<shape type=\"teapot\"/>", "unknown shape plugin 'teapot'"),
            ("<bsdf type=\"fancy\" id=\"a\"/><shape type=\"cube\"/>", "unknown bsdf plugin 'fancy'"),
            ("<shape type=\"cube\"><float name=\"x\" value=\"$nope\"/></shape>", "undefined parameter $nope"),
            ("<shape type=\"sphere\"><float name=\"radius\" value=\"abc\"/></shape>", "not a number"),
            ("<sensor type=\"perspective\"><float name=\"fov\" value=\"200\"/></sensor><shape type=\"cube\"/>", "fov 200"),
            ("<shape type=\"cube\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"phong\"/></bsdf></shape>",
             "t.xml:2: roughconductor distribution \"phong\": must be \"beckmann\" or \"ggx\""),
        ] {
            let e = scene(body).unwrap_err();
            assert!(e.contains(needle) && !e.contains('\n'), "{body}: {e}");
        }
        let e = parse(
            "<scene version=\"3.0.0\">\n  <shape>\n</scene>",
            "m.xml",
            Path::new("."),
        )
        .unwrap_err();
        assert!(e.starts_with("m.xml:3:"), "{e}");
    }

    #[test]
    fn unsupported_things_are_warned_once_with_the_line() {
        let d = scene(
            r#"<bsdf type="hair" id="h"/>
               <shape type="cube"><ref id="h"/></shape>
               <shape type="cube"><ref id="h"/><float name="wobble" value="1"/></shape>
               <shape type="serialized"><string name="filename" value="x.serialized"/></shape>"#,
        )
        .unwrap();
        let w = d.warnings.join("\n");
        assert!(w.contains("t.xml:2: unsupported bsdf 'hair'"), "{w}");
        assert!(w.contains("t.xml:4: parameter 'wobble'"), "{w}");
        assert!(w.contains("t.xml:5: unsupported shape 'serialized'"), "{w}");
        assert_eq!(d.warnings.len(), 3, "{w}");
    }

    /// Forms real files use that Mitsuba reads: a texture as a roughness, spectra split by
    /// spaces, Python's booleans, Palik's conductor names, a lookat without up.
    #[test]
    fn mitsubas_lenient_forms_are_read() {
        let d = scene(
            r#"<bsdf type="roughconductor" id="m"><texture type="bitmap" name="alpha">
                 <string name="filename" value="scenes/mitsuba/textures/floor.png"/></texture>
                 <string name="material" value="Ni_palik"/></bsdf>
               <shape type="rectangle"><ref id="m"/></shape>
               <shape type="rectangle"><bsdf type="diffuse"><spectrum name="reflectance"
                 value="400:0.5 500:0.5  600:0.5,700:0.5"/></bsdf></shape>
               <shape type="rectangle"><boolean name="flip_normals" value="True"/>
                 <bsdf type="diffuse"/></shape>"#,
        )
        .unwrap();
        let m = &d.materials[d.materials.len() - 3];
        let ni = METALS.iter().find(|(n, _, _)| *n == "Ni").unwrap();
        match &m.model {
            Some(SurfaceModel::Conductor { eta, alpha, .. }) => {
                assert_eq!(*eta, ni.1);
                // the texture's mean
                assert!(*alpha > 0.0 && *alpha < 1.0, "{alpha}");
            }
            other => panic!("{other:?}"),
        }
        let w = d.warnings.join("\n");
        assert!(w.contains("\"Ni_palik\": rendered with \"Ni\""), "{w}");
        let kd = d.materials[d.materials.len() - 2].kd;
        assert!(kd.iter().all(|c| (c - 0.5).abs() < 0.02), "{kd:?}");
        let e = scene(
            r#"<shape type="cube"><bsdf type="conductor">
                 <string name="material" value="Xx_palik"/></bsdf></shape>"#,
        )
        .unwrap_err();
        assert!(e.contains("\"Xx_palik\": not one of"), "{e}");
        // lookat without up: Mitsuba's coordinate_system(dir).first, +x looking down -z
        let d = scene(
            r#"<sensor type="perspective"><transform name="to_world">
                 <lookat origin="0, 0, 5" target="0, 0, 0"/></transform></sensor>
               <shape type="cube"/>"#,
        )
        .unwrap();
        assert!((Vec3::from(d.camera.unwrap().up) - Vec3::X).length() < 1e-6);
        // an aov integrator's radiance is its nested integrator's, with its max_depth
        let d = scene(
            r#"<integrator type="aov"><string name="aovs" value="nn:sh_normal"/>
                 <integrator type="path" name="radiance"><integer name="max_depth" value="2"/>
                 <boolean name="hide_emitters" value="False"/></integrator></integrator>
               <shape type="cube"/>"#,
        )
        .unwrap();
        assert_eq!(d.defaults.max_depth, Some(2));
        assert!(d.warnings.iter().any(|w| w.contains("integrator 'aov'")));
        // one of alpha_u, alpha_v alone, or with alpha: refused as Mitsuba does
        for p in [
            r#"<float name="alpha_u" value="0.4"/>"#,
            r#"<float name="alpha" value="0.4"/><float name="alpha_v" value="0.4"/>"#,
        ] {
            let e = scene(&format!(
                r#"<shape type="cube"><bsdf type="roughconductor">{p}</bsdf></shape>"#
            ))
            .unwrap_err();
            assert!(e.contains("t.xml:2: roughconductor: "), "{e}");
        }
    }

    #[test]
    fn camera_follows_mitsuba_conventions() {
        let d = scene(
            r#"<sensor type="perspective"><float name="fov" value="90"/>
                 <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
                 <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film>
               </sensor><shape type="cube"/>"#,
        )
        .unwrap();
        let c = d.camera.unwrap();
        assert_eq!(c.origin, [1.0, 2.0, 3.0]);
        assert!((Vec3::from(c.target) - Vec3::new(1.0, 2.0, 2.0)).length() < 1e-6);
        assert!((Vec3::from(c.up) - Vec3::Y).length() < 1e-6);
        // fov_axis x (Mitsuba's default): 90 degrees across 200 pixels, so tan(v/2) = 1/2
        assert_eq!((c.fov, c.fov_axis), (90.0, FovAxis::X));
        assert!((c.tan_half_vertical(200, 100) - 0.5).abs() < 1e-6);
        let v = c.vertical(200, 100);
        assert!(
            (v.fov - 2.0 * 0.5f32.atan().to_degrees()).abs() < 1e-3,
            "{}",
            v.fov
        );
        // another resolution (--res) keeps the 90 degrees across, as Mitsuba's -D resx/resy
        assert!((c.tan_half_vertical(100, 300) - 3.0).abs() < 1e-5);
        assert_eq!(d.defaults.res, Some((200, 100)));
        // the other axes, resolved at the render's resolution
        let axis = |a: &str| {
            let d = scene(&format!(
                r#"<sensor type="perspective"><float name="fov" value="90"/>
                     <string name="fov_axis" value="{a}"/></sensor><shape type="cube"/>"#
            ))
            .unwrap();
            let c = d.camera.unwrap();
            [(200, 100), (100, 200)].map(|(w, h)| c.tan_half_vertical(w, h))
        };
        let near = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-5;
        assert!(near(axis("y"), [1.0, 1.0]));
        assert!(near(axis("x"), [0.5, 2.0]));
        assert!(near(axis("smaller"), [1.0, 2.0]));
        assert!(near(axis("larger"), [0.5, 1.0]));
        let d = 5f32.sqrt();
        assert!(near(axis("diagonal"), [1.0 / d, 2.0 / d]));
        let e = scene(r#"<sensor type="perspective"><string name="fov_axis" value="z"/></sensor>"#);
        assert!(e.unwrap_err().contains("fov_axis \"z\""));
    }
}
