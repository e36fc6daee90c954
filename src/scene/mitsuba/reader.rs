//! Reading Mitsuba XML files into element trees: `$name` substitution from `<default>`,
//! `<include>` spliced in, Mitsuba 0.x names upgraded, and the plugin names Mitsuba knows.

use super::*;

/// Mitsuba's `<include>` nesting limit (its parser's `max_include_depth`).
pub(super) const MAX_INCLUDE_DEPTH: usize = 15;

/// How deep elements may nest. Mitsuba's deepest real forms (a shape holding a twosided
/// around a bumpmap around a bsdf holding a texture with a transform) stay under 12.
pub(super) const MAX_ELEMENT_DEPTH: usize = 64;

/// How many `<include>`s a whole scene may read, counting repeats: includes nested
/// `MAX_INCLUDE_DEPTH` deep may still fan out exponentially (each file including the next
/// several times).
pub(super) const MAX_INCLUDES: usize = 4096;

/// How many attributes one element may have (Mitsuba's have at most a handful).
pub(super) const MAX_ATTRIBUTES: usize = 256;

/// Refuse an element with more than `MAX_ATTRIBUTES` attributes before roxmltree reads
/// the text: its check for duplicate attributes compares each with all before it, so an
/// element of 200,000 attributes would take hours. One pass over the bytes, counting the
/// `=` outside quotes of each tag (comments, CDATA, declarations and processing
/// instructions skipped); malformed text is left for the parser to report.
fn check_attribute_counts(text: &str, file: &str) -> Result<(), String> {
    let b = text.as_bytes();
    let (mut i, mut line) = (0usize, 1usize);
    let skip_to = |from: usize, end: &str| {
        text[from..]
            .find(end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    while i < b.len() {
        match b[i] {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'<' => {
                let rest = &text[i..];
                let end = if rest.starts_with("<!--") {
                    Some("-->")
                } else if rest.starts_with("<![CDATA[") {
                    Some("]]>")
                } else if rest.starts_with("<?") {
                    Some("?>")
                } else if rest.starts_with("<!") {
                    Some(">")
                } else {
                    None
                };
                if let Some(end) = end {
                    let j = skip_to(i, end);
                    line += text[i..j].matches('\n').count();
                    i = j;
                    continue;
                }
                let (start_line, mut quote, mut count) = (line, 0u8, 0usize);
                i += 1;
                while i < b.len() && !(quote == 0 && b[i] == b'>') {
                    match b[i] {
                        b'\n' => line += 1,
                        b'"' | b'\'' if quote == 0 => quote = b[i],
                        q if q == quote => quote = 0,
                        b'=' if quote == 0 => count += 1,
                        _ => {}
                    }
                    i += 1;
                }
                if count > MAX_ATTRIBUTES {
                    return Err(format!(
                        "{file}:{start_line}: an element with {count} attributes (at most {MAX_ATTRIBUTES})"
                    ));
                }
            }
            _ => i += 1,
        }
    }
    Ok(())
}

/// Line numbers by binary search over the text's line starts: roxmltree's `text_pos_at`
/// scans from the start of the text, which made reading N elements take time N^2.
struct Lines(Vec<usize>);

impl Lines {
    fn new(text: &str) -> Self {
        Lines(text.match_indices('\n').map(|(i, _)| i).collect())
    }
    /// The 1-based line of byte offset `pos`.
    fn row(&self, pos: usize) -> usize {
        self.0.partition_point(|&nl| nl < pos) + 1
    }
}

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
    /// The files being read, outermost first (canonical paths): a cycle is refused.
    pub(super) chain: Vec<PathBuf>,
    /// Includes read so far, and the bytes of every file read.
    pub(super) includes: usize,
    pub(super) bytes: u64,
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
            chain: Vec::new(),
            includes: 0,
            bytes: 0,
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

    /// The elements of an included file (`what` names the `<include>` for messages). The
    /// include chain, the number of includes and the bytes read are bounded: a cycle, a
    /// chain deeper than Mitsuba's, or a fan-out past the totals is one clear error.
    fn include(&mut self, path: &Path, what: &str) -> Result<Vec<El>, String> {
        let real = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if let Some(i) = self.chain.iter().position(|c| *c == real) {
            let cycle: Vec<String> = self.chain[i..]
                .iter()
                .chain([&real])
                .map(|c| {
                    c.file_name()
                        .unwrap_or_default()
                        .to_string_lossy()
                        .into_owned()
                })
                .collect();
            return Err(format!(
                "{what}: the file includes itself ({})",
                cycle.join(" -> ")
            ));
        }
        if self.chain.len() >= MAX_INCLUDE_DEPTH {
            return Err(format!(
                "{what}: includes nested more than {MAX_INCLUDE_DEPTH} deep"
            ));
        }
        self.includes += 1;
        if self.includes > MAX_INCLUDES {
            return Err(format!(
                "{what}: the scene reads more than {MAX_INCLUDES} includes (counting repeats)"
            ));
        }
        let text = crate::input::read_text(path).map_err(|e| format!("{what}: {e}"))?;
        self.bytes += text.len() as u64;
        let limit = crate::input::max_input_bytes()?;
        if self.bytes > limit {
            return Err(format!(
                "{what}: the scene's files total more than the input limit of {}",
                crate::input::human_size(limit)
            ));
        }
        let file = path.display().to_string();
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        self.chain.push(real);
        let els = self.read_text(&text, &file, &dir);
        self.chain.pop();
        els
    }

    /// The elements of a `<scene>`'s text, includes spliced in; `file` names it in
    /// messages and relative names resolve against `dir`.
    pub(super) fn read_text(
        &mut self,
        text: &str,
        file: &str,
        dir: &Path,
    ) -> Result<Vec<El>, String> {
        let text = crate::input::clean_text(text);
        check_attribute_counts(&text, file)?;
        // no DTDs (Mitsuba files have none; entity expansion is not worth the risk)
        let doc = roxmltree::Document::parse(&text).map_err(|e| xml_error(file, &e))?;
        let root = doc.root_element();
        let lines = Lines::new(&text);
        let at = |n: &roxmltree::Node| format!("{file}:{}", lines.row(n.range().start));
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
                    let p = resolve(&self.search, dir, &name);
                    out.extend(
                        self.include(&p, &format!("{here}: <include filename=\"{name}\">"))?,
                    );
                }
                _ => out.push(self.convert(n, &lines, file, upgrade, 1)?),
            }
        }
        Ok(out)
    }

    fn convert(
        &mut self,
        n: roxmltree::Node,
        lines: &Lines,
        file: &str,
        upgrade: bool,
        depth: usize,
    ) -> Result<El, String> {
        let at = format!("{file}:{}", lines.row(n.range().start));
        if depth > MAX_ELEMENT_DEPTH {
            return Err(format!(
                "{at}: <{}>: elements nested more than {MAX_ELEMENT_DEPTH} deep",
                n.tag_name().name()
            ));
        }
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
            children.push(self.convert(c, lines, file, upgrade, depth + 1)?);
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
            "rawconstant",
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
