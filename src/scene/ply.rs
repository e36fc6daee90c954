//! PLY meshes (ASCII, binary little and big endian) read with the `ply-rs-bw` crate:
//! positions, optional normals (`nx ny nz`) and texture coordinates (`u v`, `s t`,
//! `texture_u texture_v`, `texture_s texture_t`), faces as index lists of any length
//! (fan-triangulated), and the other vertex and face properties as Mitsuba's mesh
//! attributes (see [`attribute_groups`]). Other elements are read and ignored.
//! Errors are one line naming the file (and the header line where the crate knows it);
//! short data, an index past the last vertex and a missing `x`/`y`/`z` are refused.
//!
//! (`src/radiosity/ply.rs` is a separate PLY *writer* for radiosity solutions; the crate
//! could write PLY too, but that module has no need of it.)

use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};
use std::path::Path;

/// A triangle mesh as a PLY file holds it.
#[derive(Clone, Debug, Default)]
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    /// Per vertex, when the file has `nx ny nz`.
    pub normals: Option<Vec<Vec3>>,
    /// Per vertex, when the file has texture coordinates (as written: v up, like OBJ).
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles (polygons fan-triangulated), indices checked against `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Mitsuba's mesh attributes (`vertex_color`, `face_weight`, ...): none unless the
    /// file has such properties.
    pub attributes: Vec<PlyAttribute>,
}

/// A named mesh attribute: 1 or 3 values per vertex or per face (one value is
/// repeated to three).
#[derive(Clone, Debug, PartialEq)]
pub struct PlyAttribute {
    /// `vertex_...` or `face_...`, as Mitsuba names it.
    pub name: String,
    /// Per triangle (a polygon's value on each of its triangles) instead of per vertex.
    pub per_face: bool,
    pub values: Vec<[f32; 3]>,
}

#[derive(Default)]
struct Vertex {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
    /// The attribute properties' values, in the order of `EXTRA`'s vertex names.
    extra: Vec<f32>,
}

thread_local! {
    /// The names of the vertex and face properties read as attributes by the parse
    /// running on this thread (the crate's `PropertyAccess::new` takes no context).
    static EXTRA: std::cell::RefCell<[Vec<String>; 2]> = Default::default();
}

/// Store `p` in `extra` at the slot of property `name` among the attribute properties
/// of element kind `k` (0 vertex, 1 face), if it is one.
fn set_extra(k: usize, extra: &mut Vec<f32>, name: &str, p: &Property) -> PropertyAccessResult {
    EXTRA.with(|e| {
        let names = &e.borrow()[k];
        let Some(i) = names.iter().position(|n| n == name) else {
            return PropertyAccessResult::Ignored;
        };
        let Some(v) = attribute_value(p) else {
            return PropertyAccessResult::UnsupportedType;
        };
        if extra.len() < names.len() {
            extra.resize(names.len(), 0.0);
        }
        extra[i] = v;
        PropertyAccessResult::Set
    })
}

/// An attribute value as Mitsuba converts it: floats as they are, integers normalized
/// to [0, 1] by their type's range and sRGB-decoded (its `Normalized | Gamma` fields).
fn attribute_value(p: &Property) -> Option<f32> {
    let norm = |v: f64, max: f64| crate::image_io::srgb_decode((v / max) as f32);
    Some(match *p {
        Property::Char(v) => norm(v as f64, i8::MAX as f64),
        Property::UChar(v) => norm(v as f64, u8::MAX as f64),
        Property::Short(v) => norm(v as f64, i16::MAX as f64),
        Property::UShort(v) => norm(v as f64, u16::MAX as f64),
        Property::Int(v) => norm(v as f64, i32::MAX as f64),
        Property::UInt(v) => norm(v as f64, u32::MAX as f64),
        Property::Float(v) => v,
        Property::Double(v) => v as f32,
        _ => return None,
    })
}

/// Mitsuba's grouping of an element's other properties into attributes: `r g b` (or
/// `red green blue`) make `{kind}color`; otherwise consecutive properties
/// `{prefix}_{c}` whose one-letter postfixes run through one of `x y z`, `r g b`,
/// `0 1 2`, `1 2 3` make `{kind}{prefix}` (`{kind}{prefix}_color` for `r g b`), kept
/// when they are 1 or 3. Returns each attribute's name and its properties' names.
pub fn attribute_groups(kind: &str, props: &[&str]) -> Vec<(String, Vec<String>)> {
    const RESERVED: [&str; 20] = [
        "x",
        "y",
        "z",
        "nx",
        "ny",
        "nz",
        "u",
        "v",
        "s",
        "t",
        "texture_u",
        "texture_v",
        "texture_s",
        "texture_t",
        "vertex_indices",
        "vertex_index",
        "r",
        "g",
        "b",
        "a",
    ];
    const POSTFIX: [&str; 4] = ["xr01", "yg12", "zb23", "wa34"];
    let mut out = Vec::new();
    for rgb in [["r", "g", "b"], ["red", "green", "blue"]] {
        if rgb.iter().all(|c| props.contains(c)) {
            out.push((format!("{kind}color"), rgb.map(String::from).to_vec()));
            break;
        }
    }
    let mut flush = |prefix: &str, cat: usize, fields: &mut Vec<String>| {
        if fields.len() == 1 || fields.len() == 3 {
            let name = format!("{kind}{prefix}{}", if cat == 1 { "_color" } else { "" });
            if !out.iter().any(|(n, _)| *n == name) {
                out.push((name, std::mem::take(fields)));
            }
        }
        fields.clear();
    };
    // the attribute being read: its prefix, postfix category and fields
    let mut cur: Option<(String, usize)> = None;
    let mut fields: Vec<String> = Vec::new();
    for &name in props {
        if RESERVED.contains(&name) || ["red", "green", "blue", "alpha"].contains(&name) {
            continue;
        }
        let split = name
            .rsplit_once('_')
            .filter(|(_, post)| post.chars().count() == 1);
        let Some((prefix, post)) = split else {
            if let Some((p, c)) = cur.take() {
                flush(&p, c, &mut fields);
            }
            continue;
        };
        let ch = post.chars().next().unwrap_or(' ');
        if let Some((p, c)) = &cur {
            let next = POSTFIX.get(fields.len()).and_then(|s| s.chars().nth(*c));
            if p == prefix && next == Some(ch) {
                fields.push(name.to_string());
                continue;
            }
            let (p, c) = cur.take().unwrap();
            flush(&p, c, &mut fields);
        }
        if let Some(c) = POSTFIX[0].chars().position(|x| x == ch) {
            cur = Some((prefix.to_string(), c));
            fields.push(name.to_string());
        }
    }
    if let Some((p, c)) = cur.take() {
        flush(&p, c, &mut fields);
    }
    out
}

fn scalar(p: &Property) -> Option<f32> {
    match *p {
        Property::Char(v) => Some(v as f32),
        Property::UChar(v) => Some(v as f32),
        Property::Short(v) => Some(v as f32),
        Property::UShort(v) => Some(v as f32),
        Property::Int(v) => Some(v as f32),
        Property::UInt(v) => Some(v as f32),
        Property::Float(v) => Some(v),
        Property::Double(v) => Some(v as f32),
        _ => None,
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            "u" | "s" | "texture_u" | "texture_s" => &mut self.uv[0],
            "v" | "t" | "texture_v" | "texture_t" => &mut self.uv[1],
            _ => return set_extra(0, &mut self.extra, name, &p),
        };
        match scalar(&p) {
            Some(v) => {
                *slot = v;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

#[derive(Default)]
struct Face {
    /// Indices as signed 64-bit, so negative values from signed lists can be refused.
    idx: Vec<i64>,
    /// The attribute properties' values, in the order of `EXTRA`'s face names.
    extra: Vec<f32>,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return set_extra(1, &mut self.extra, name, &p);
        }
        self.idx = match p {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// Any other element: read (the payload must be walked past) and dropped.
struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Ignored
    }
}

/// Read a PLY file through `input` (regular files within the size limit).
pub fn load_ply(path: &Path) -> Result<PlyMesh, String> {
    let bytes = crate::input::read_bytes(path)?;
    parse_ply(&bytes, &path.display().to_string())
}

/// One line from the crate's error (which may span lines).
fn one_line(e: &impl std::fmt::Display) -> String {
    let s = e.to_string();
    let s: String = s.split_whitespace().collect::<Vec<_>>().join(" ");
    if s.len() > 200 {
        let mut cut = 200;
        while !s.is_char_boundary(cut) {
            cut -= 1;
        }
        format!("{}...", &s[..cut])
    } else {
        s
    }
}

/// A message without the parser's debug text (`ParseIntError { kind: InvalidDigit }`,
/// `String: '...' Error: ...`): what comes before it.
fn plain(s: &str) -> String {
    let cut = [
        " String: ",
        " Error: ",
        " {",
        "ParseIntError",
        "ParseFloatError",
    ]
    .iter()
    .filter_map(|m| s.find(m))
    .min()
    .unwrap_or(s.len());
    let t = s[..cut].trim_end_matches([':', ' ', '.']);
    if t.is_empty() {
        "malformed data".into()
    } else {
        t.to_string()
    }
}

/// Parse PLY bytes; `file` names the source in errors.
pub fn parse_ply(bytes: &[u8], file: &str) -> Result<PlyMesh, String> {
    if !bytes.starts_with(b"ply") {
        return Err(format!(
            "{file}: not a PLY file (it must start with the line \"ply\")"
        ));
    }
    // the crate is not known to panic, but a mesh is untrusted input: never let it
    let r = std::panic::catch_unwind(|| parse_inner(bytes, file));
    match r {
        Ok(r) => r,
        Err(_) => Err(format!("{file}: malformed PLY (the parser gave up)")),
    }
}

fn parse_inner(bytes: &[u8], file: &str) -> Result<PlyMesh, String> {
    let mut reader = Reader::new(bytes);
    let vparser = Parser::<Vertex>::new();
    let header = vparser
        .read_header(&mut reader)
        .map_err(|e| match e.line() {
            Some(l) => format!(
                "{file}:{l}: bad PLY header: {}",
                one_line(&e).trim_start_matches(&format!("Line {l}: "))
            ),
            None => format!("{file}: bad PLY header: {}", one_line(&e)),
        })?;
    let vdef = header.elements.get("vertex").ok_or_else(|| {
        format!("{file}: PLY header has no 'vertex' element: not a mesh this reader knows")
    })?;
    for c in ["x", "y", "z"] {
        if !vdef.properties.contains_key(c) {
            return Err(format!(
                "{file}: PLY 'vertex' element has no property '{c}'"
            ));
        }
    }
    let has = |names: &[&str]| names.iter().any(|n| vdef.properties.contains_key(*n));
    let has_n = has(&["nx"]) && has(&["ny"]) && has(&["nz"]);
    let has_uv =
        has(&["u", "s", "texture_u", "texture_s"]) && has(&["v", "t", "texture_v", "texture_t"]);
    // the other properties that make attributes, their names in the parse's slots
    let groups = |el: &str, kind: &str| {
        let props: Vec<&str> = header
            .elements
            .get(el)
            .map(|d| d.properties.keys().map(String::as_str).collect())
            .unwrap_or_default();
        attribute_groups(kind, &props)
    };
    let (vgroups, fgroups) = (groups("vertex", "vertex_"), groups("face", "face_"));
    let flat = |g: &[(String, Vec<String>)]| g.iter().flat_map(|(_, f)| f.clone()).collect();
    EXTRA.with(|e| *e.borrow_mut() = [flat(&vgroups), flat(&fgroups)]);
    let fparser = Parser::<Face>::new();
    let iparser = Parser::<Ignored>::new();
    let mut verts: Vec<Vertex> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut have_faces = false;
    for (name, def) in &header.elements {
        // the crate's messages carry its parser's debug text: say what is wrong instead
        let fail = |e: ply_rs_bw::parser::ParseError| {
            match e.line() {
            Some(l) => format!(
                "{file}:{l}: PLY element '{name}' ({} declared): the line does not match the header's properties (a value missing, extra or not a number)",
                def.count
            ),
            None => format!(
                "{file}: PLY element '{name}' ({} declared): {}",
                def.count,
                plain(&one_line(&e))
            ),
        }
        };
        match name.as_str() {
            "vertex" => {
                verts = vparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(fail)?
            }
            "face" => {
                have_faces = true;
                faces = fparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(fail)?
            }
            _ => {
                iparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(fail)?;
            }
        }
    }
    if reader.get_ref().iter().any(|b| !b.is_ascii_whitespace()) {
        let counts: Vec<String> = header
            .elements
            .iter()
            .map(|(n, d)| format!("{} {n}", d.count))
            .collect();
        return Err(format!(
            "{file}: PLY data goes on after the elements its header declares ({}): the counts in the header are wrong",
            counts.join(", ")
        ));
    }
    if !have_faces {
        return Err(format!(
            "{file}: PLY header has no 'face' element: a point cloud, not a mesh"
        ));
    }
    let nv = verts.len() as i64;
    let mut mesh = PlyMesh {
        positions: Vec::with_capacity(verts.len()),
        normals: has_n.then(|| Vec::with_capacity(verts.len())),
        uvs: has_uv.then(|| Vec::with_capacity(verts.len())),
        triangles: Vec::with_capacity(faces.len()),
        attributes: Vec::new(),
    };
    // per vertex: each group's 1 or 3 slots, one value repeated to three
    let values = |extra: &[f32], start: usize, n: usize| -> [f32; 3] {
        let v = |i: usize| extra.get(start + i.min(n - 1)).copied().unwrap_or(0.0);
        [v(0), v(1), v(2)]
    };
    let mut start = 0;
    for (name, fields) in &vgroups {
        mesh.attributes.push(PlyAttribute {
            name: name.clone(),
            per_face: false,
            values: verts
                .iter()
                .map(|v| values(&v.extra, start, fields.len()))
                .collect(),
        });
        start += fields.len();
    }
    let first_face_attr = mesh.attributes.len();
    for (name, _) in &fgroups {
        mesh.attributes.push(PlyAttribute {
            name: name.clone(),
            per_face: true,
            values: Vec::with_capacity(faces.len()),
        });
    }
    for (i, v) in verts.iter().enumerate() {
        let p = Vec3::from(v.p);
        if !p.is_finite() {
            return Err(format!(
                "{file}: PLY vertex {i} has a non-finite position {p}"
            ));
        }
        mesh.positions.push(p);
        if let Some(n) = &mut mesh.normals {
            n.push(Vec3::from(v.n));
        }
        if let Some(t) = &mut mesh.uvs {
            t.push(Vec2::from(v.uv));
        }
    }
    for (f, face) in faces.iter().enumerate() {
        if face.idx.len() < 3 {
            if face.idx.is_empty() {
                return Err(format!(
                    "{file}: PLY face {f} has no 'vertex_indices' (or 'vertex_index') list"
                ));
            }
            continue; // a point or a line: not a surface
        }
        if let Some(&bad) = face.idx.iter().find(|&&i| i < 0 || i >= nv) {
            return Err(format!(
                "{file}: PLY face {f} references vertex {bad}, but the file has {nv} vertices"
            ));
        }
        for k in 1..face.idx.len() - 1 {
            mesh.triangles.push([
                face.idx[0] as u32,
                face.idx[k] as u32,
                face.idx[k + 1] as u32,
            ]);
            let mut start = 0;
            for (g, (_, fields)) in fgroups.iter().enumerate() {
                let v = values(&face.extra, start, fields.len());
                mesh.attributes[first_face_attr + g].values.push(v);
                start += fields.len();
            }
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";

    fn binary(big: bool) -> Vec<u8> {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = format!("ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n").into_bytes();
        let f = |b: &mut Vec<u8>, v: f32| {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            })
        };
        for p in [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]] {
            for c in p {
                f(&mut b, c);
            }
            b.push(200);
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(if big {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        b
    }

    #[test]
    fn ascii_quad_with_normals_and_uvs() {
        let m = parse_ply(ASCII.as_bytes(), "q.ply").unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.as_ref().unwrap()[2], Vec3::Z);
        assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    }

    #[test]
    fn binary_both_endians() {
        for big in [false, true] {
            let m = parse_ply(&binary(big), "b.ply").unwrap();
            assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
            assert_eq!(m.positions[2], Vec3::new(0.0, 3.0, 0.0));
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
            assert!(m.normals.is_none() && m.uvs.is_none());
        }
    }

    /// Properties beyond positions, normals and uvs group into Mitsuba's attributes:
    /// `color_0..2` per vertex is `vertex_color`, `weight_0` per face `face_weight`,
    /// `red green blue` (8-bit: normalized, sRGB-decoded) `face_color`; a face's values
    /// go to each of its triangles.
    #[test]
    fn vertex_and_face_properties_are_attributes() {
        let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float color_0\nproperty float color_1\nproperty float color_2\nelement face 2\nproperty list uchar int vertex_indices\nproperty float weight_0\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n0 0 0 0.1 0.2 0.3\n1 0 0 0.4 0.5 0.6\n1 1 0 0.7 0.8 0.9\n0 1 0 1 1 1\n4 0 1 2 3 0.25 255 0 128\n3 0 1 2 0.75 0 0 0\n";
        let m = parse_ply(ply.as_bytes(), "a.ply").unwrap();
        assert_eq!(m.triangles.len(), 3);
        let names: Vec<&str> = m.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["vertex_color", "face_color", "face_weight"]);
        let c = &m.attributes[0];
        assert!(!c.per_face);
        assert_eq!(c.values[1], [0.4, 0.5, 0.6]);
        let w = &m.attributes[2];
        assert!(w.per_face);
        assert_eq!(w.values, vec![[0.25; 3], [0.25; 3], [0.75; 3]]);
        let mid = crate::image_io::srgb_decode(128.0 / 255.0);
        assert_eq!(m.attributes[1].values[0], [1.0, 0.0, mid]);
        // Mitsuba's postfix schemes, and groups of 2 or 4 are not attributes
        let g = attribute_groups(
            "vertex_",
            &[
                "x", "nx", "foo_x", "foo_y", "foo_z", "bar_r", "bar_g", "bar_b", "w_1", "uv_0",
                "uv_1", "q",
            ],
        );
        let names: Vec<&str> = g.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["vertex_foo", "vertex_bar_color", "vertex_w"]);
        // a mesh without such properties has none
        assert!(parse_ply(ASCII.as_bytes(), "q.ply")
            .unwrap()
            .attributes
            .is_empty());
    }

    #[test]
    fn bad_files_give_one_line_errors() {
        let b = binary(false);
        for (bytes, needle) in [
            (b"obj\n".to_vec(), "not a PLY"),
            (
                b"ply\nformat ascii 1.0\nelement vertex x\nend_header\n".to_vec(),
                "bad PLY header",
            ),
            (b[..b.len() - 3].to_vec(), "element 'face'"),
            (b[..b.len() - 30].to_vec(), "element 'vertex'"),
            (
                ASCII.replace("4 0 1 2 3", "4 0 1 2 9").into_bytes(),
                "references vertex 9",
            ),
            (
                ASCII.replace("property float z\n", "").into_bytes(),
                "no property 'z'",
            ),
        ] {
            let e = parse_ply(&bytes, "m.ply").unwrap_err();
            assert!(
                e.contains(needle) && e.starts_with("m.ply") && !e.contains('\n'),
                "{e}"
            );
        }
    }
}
