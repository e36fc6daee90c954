//! Reading Mitsuba XML files into element trees: `$name` substitution from `<default>`,
//! `<include>` spliced in, Mitsuba 0.x names upgraded, and the plugin names Mitsuba knows.

use super::*;

/// Mitsuba's `<include>` nesting limit (its parser's `max_include_depth`).
pub(super) const MAX_INCLUDE_DEPTH: usize = 15;

/// An XML element with its attributes after `$name` substitution.
#[derive(Debug)]
pub(super) struct El {
    pub(super) tag: String,
    pub(super) attrs: Vec<(String, String)>,
    pub(super) children: Vec<El>,
    /// `file:line`, for messages.
    pub(super) at: String,
    pub(super) used: Cell<bool>,
}

impl El {
    pub(super) fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    pub(super) fn name(&self) -> Option<&str> {
        self.attr("name")
    }
    pub(super) fn kind(&self) -> &str {
        self.attr("type").unwrap_or("")
    }
}

// ----------------------------------------------------------------------------------------
// Reading files into element trees
// ----------------------------------------------------------------------------------------

/// The text of roxmltree's error without its trailing "at line:col".
pub(super) fn xml_error(file: &str, e: &roxmltree::Error) -> String {
    let p = e.pos();
    let msg = e.to_string();
    let msg = msg
        .strip_suffix(&format!(" at {}:{}", p.row, p.col))
        .unwrap_or(&msg);
    format!("{file}:{}:{}: malformed XML: {msg}", p.row, p.col)
}

/// Mitsuba 3's upgrade of 0.x names: camelCase -> snake_case (`intIOR` -> `int_ior`).
pub(super) fn snake_case(s: &str) -> String {
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
pub(super) fn diffuse_reflectance_alias(attrs: &[(String, String)], children: &mut [El]) {
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

pub(super) struct Reader {
    pub(super) defaults: HashMap<String, String>,
    /// Warnings found while reading (unknown version, ...).
    pub(super) warnings: Vec<String>,
    /// `<path>` folders in the order read: a file name is looked up in the last first.
    pub(super) search: Vec<PathBuf>,
    /// Parameter names the files declare (`<default>`) or use (`$name`): a define must
    /// name one of them.
    pub(super) declared: HashSet<String>,
}

/// Where Mitsuba's file resolver finds `name`: in the `<path>` folders, the one read last
/// first, then beside the scene file (`dir`); a name found nowhere is kept relative to `dir`
/// (so that its error names that place).
pub(super) fn resolve(search: &[PathBuf], dir: &Path, name: &str) -> PathBuf {
    let here = crate::scene::mtl::normalise_path(dir, name);
    if Path::new(name.trim()).is_absolute() {
        return here;
    }
    search
        .iter()
        .rev()
        .map(|d| crate::scene::mtl::normalise_path(d, name))
        .find(|p| p.exists())
        .unwrap_or(here)
}

impl Reader {
    /// A reader whose `<default>`s are overridden by `defines` (Mitsuba's `-D key=value`).
    pub(super) fn new(defines: &[(String, String)]) -> Reader {
        Reader {
            defaults: defines.iter().cloned().collect(),
            warnings: Vec::new(),
            search: Vec::new(),
            declared: HashSet::new(),
        }
    }

    /// Refuse a define that names no parameter of the scene (a typo would be ignored).
    pub(super) fn check_defines(
        &self,
        defines: &[(String, String)],
        file: &str,
    ) -> Result<(), String> {
        for (k, v) in defines {
            if !self.declared.contains(k) {
                return Err(format!(
                    "-D {k}={v}: {file} has no <default name=\"{k}\"> and no ${k}"
                ));
            }
        }
        Ok(())
    }

    /// Substitute `$name` parameters.
    pub(super) fn substitute(&mut self, v: &str, at: &str) -> Result<String, String> {
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
            if !key.is_empty() {
                self.declared.insert(key.to_string());
            }
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
    pub(super) fn read_file(&mut self, path: &Path, depth: usize) -> Result<Vec<El>, String> {
        let text = crate::input::read_text(path)?;
        let file = path.display().to_string();
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        self.read_text(&text, &file, &dir, depth)
    }

    pub(super) fn read_text(
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
                self.declared.insert(k.to_string());
                self.defaults
                    .entry(k.to_string())
                    .or_insert_with(|| v.to_string());
            }
        }
        let mut out = Vec::new();
        for n in root.children().filter(|n| n.is_element()) {
            match n.tag_name().name() {
                "default" => {}
                "path" => {
                    let here = at(&n);
                    let value = n
                        .attribute("value")
                        .ok_or_else(|| format!("{here}: <path> needs a value attribute"))?;
                    let value = self.substitute(value, &here)?;
                    let p = crate::scene::mtl::normalise_path(dir, &value);
                    if !p.is_dir() {
                        return Err(format!(
                            "{here}: <path value=\"{value}\">: {} is not a folder",
                            p.display()
                        ));
                    }
                    self.search.push(p);
                }
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
                    let p = resolve(&self.search, dir, &name);
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

    pub(super) fn convert(
        &mut self,
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

pub(super) fn known_plugin(tag: &str, kind: &str) -> bool {
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
