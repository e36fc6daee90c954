//! PLY meshes (ASCII, binary little and big endian) read with the `ply-rs-bw` crate:
//! positions, optional normals (`nx ny nz`) and texture coordinates (`u v`, `s t`,
//! `texture_u texture_v`, `texture_s texture_t`), faces as index lists of any length
//! (fan-triangulated). Other elements and properties (colours, ...) are read and ignored.
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
}

#[derive(Default)]
struct Vertex {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
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
            _ => return PropertyAccessResult::Ignored,
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
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
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
    };
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
