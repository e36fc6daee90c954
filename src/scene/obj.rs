//! Wavefront OBJ loading with tobj: triangles, quads and n-gons (fan-triangulated),
//! negative (relative) indices, optional vn/vt, mtllib/usemtl, backslash paths, a
//! byte-order mark and any line ends; mirroring transforms keep the front side.
//! A validation pass first reports bad lines as `file:line: ...` (tobj itself gives
//! no line numbers), so no input reaches tobj that could make it fail obscurely.

use super::mtl::{normalise_path, parse_mtl};
use super::{MaterialDesc, SceneDesc};
use glam::{Mat4, Vec2, Vec3};
use std::io::BufReader;
use std::path::Path;

/// What the validation pass hands on to tobj and the triangle assembly.
struct Checked {
    /// (line, name) of every mtllib, in order.
    mtllibs: Vec<(usize, String)>,
    /// (line, name) of every `usemtl`, to warn about names no MTL defines.
    usemtls: Vec<(usize, String)>,
    /// The OBJ rewritten in the form tobj reads reliably: comments stripped, single
    /// spaces, vertex data first, face indices absolute, no mtllib/l/p statements.
    text: String,
    /// Per triangle, in the order tobj emits them: (all corners have vt, all have vn).
    tri_has: Vec<(bool, bool)>,
}

/// Check every statement tobj will act on and rewrite the file for it, so tobj never
/// fails (or panics) on anything without a line number: it does not strip trailing
/// comments, rejects tabs in `usemtl`, divides by a `w` of 0, resolves forward
/// references only within a group, treats `l` lines of 3+ vertices as faces, and gives
/// faces without vn/vt the normal/uv of another face.
fn validate(text: &str, file: &str) -> Result<Checked, String> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    // totals first: positive indices may refer to any vertex of the file
    for line in text.lines() {
        match line
            .split('#')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .next()
        {
            Some("v") => nv += 1,
            Some("vt") => nt += 1,
            Some("vn") => nn += 1,
            _ => {}
        }
    }
    let (tv, tt, tn) = (nv, nt, nn);
    let (mut sv, mut st, mut sn) = (0i64, 0i64, 0i64);
    let mut out = Checked {
        mtllibs: Vec::new(),
        usemtls: Vec::new(),
        text: String::new(),
        tri_has: Vec::new(),
    };
    let mut verts = String::new();
    let mut body = String::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        if raw.contains('\0') {
            return Err(format!(
                "{file}:{line_no}: binary data (a NUL byte): not an OBJ text file"
            ));
        }
        let line = raw.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, rest)) = words.split_first() else {
            continue;
        };
        let number = |w: &str, what: &str| -> Result<f32, String> {
            let v: f32 = w
                .parse()
                .map_err(|_| format!("{file}:{line_no}: {what}: {w:?} is not a number"))?;
            if !v.is_finite() {
                return Err(format!("{file}:{line_no}: {what}: value {w} is not finite"));
            }
            Ok(v)
        };
        let floats = |n: usize, what: &str| -> Result<(), String> {
            if rest.len() < n {
                return Err(format!(
                    "{file}:{line_no}: {what} needs {n} numbers, found {}",
                    rest.len()
                ));
            }
            for w in &rest[..n] {
                number(w, what)?;
            }
            Ok(())
        };
        match key {
            "v" => {
                floats(3, "vertex")?;
                // x y z, x y z w, or x y z r g b (colours are not used)
                let n = if rest.len() == 4 {
                    if number(rest[3], "vertex w")? == 0.0 {
                        return Err(format!("{file}:{line_no}: vertex w must not be 0"));
                    }
                    4
                } else {
                    3
                };
                verts.push_str(&format!("v {}\n", rest[..n].join(" ")));
                sv += 1;
            }
            "vt" => {
                floats(1, "texture coordinate")?;
                let v = match rest.get(1) {
                    Some(w) => {
                        number(w, "texture coordinate")?;
                        w
                    }
                    None => "0",
                };
                verts.push_str(&format!("vt {} {v}\n", rest[0]));
                st += 1;
            }
            "vn" => {
                floats(3, "normal")?;
                verts.push_str(&format!("vn {}\n", rest[..3].join(" ")));
                sn += 1;
            }
            "f" => {
                if rest.len() < 3 {
                    return Err(format!(
                        "{file}:{line_no}: face has {} vertices, a face needs at least 3",
                        rest.len()
                    ));
                }
                let (mut all_t, mut all_n) = (true, true);
                body.push('f');
                for w in rest {
                    let parts: Vec<&str> = w.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(format!("{file}:{line_no}: malformed face vertex {w:?}"));
                    }
                    all_t &= parts.len() > 1 && !parts[1].is_empty();
                    all_n &= parts.len() > 2 && !parts[2].is_empty();
                    let kinds = [
                        ("vertex", "vertices", sv, tv),
                        ("texture coordinate", "texture coordinates", st, tt),
                        ("normal", "normals", sn, tn),
                    ];
                    body.push(' ');
                    for (k, p) in parts.iter().enumerate() {
                        if k > 0 {
                            body.push('/');
                        }
                        if p.is_empty() {
                            continue;
                        }
                        let (what, plural, so_far, total) = kinds[k];
                        let idx: i64 = p.parse().map_err(|_| {
                            format!("{file}:{line_no}: malformed face vertex {w:?}")
                        })?;
                        let ok = if idx > 0 {
                            idx <= total
                        } else {
                            idx < 0 && -idx <= so_far
                        };
                        if !ok {
                            let have = if idx > 0 { total } else { so_far };
                            return Err(format!(
                                "{file}:{line_no}: face references {what} {idx}, but {have} {plural} are defined{}",
                                if idx < 0 { " before it" } else { "" }
                            ));
                        }
                        // absolute, 1-based: vertex data is moved to the top for tobj
                        let abs = if idx > 0 { idx } else { so_far + idx + 1 };
                        body.push_str(&abs.to_string());
                    }
                }
                body.push('\n');
                let tris = rest.len() - 2;
                out.tri_has
                    .extend(std::iter::repeat_n((all_t, all_n), tris));
            }
            "mtllib" => {
                let name = rest.join(" ");
                if name.is_empty() {
                    return Err(format!("{file}:{line_no}: mtllib without a file name"));
                }
                out.mtllibs.push((line_no, name));
            }
            "usemtl" => {
                let name = rest.join(" ");
                if name.is_empty() {
                    // no material: a name no MTL can define ('#' starts a comment there)
                    body.push_str("usemtl #none\n");
                } else {
                    body.push_str(&format!("usemtl {name}\n"));
                    out.usemtls.push((line_no, name));
                }
            }
            "o" | "g" => body.push_str("g\n"),
            _ => {} // l, p, s, curves, ...: not rendered
        }
    }
    // one mtllib line makes tobj ask for all materials before any usemtl
    out.text = format!("mtllib kalos\n{verts}{body}");
    Ok(out)
}

/// Where the MTL files of an OBJ come from.
pub enum MtlSource<'a> {
    /// Files beside the OBJ on disk.
    Dir(&'a Path),
    /// Text supplied by the caller (built-in scenes): name -> text.
    Embedded(&'a dyn Fn(&str) -> Option<&'static str>),
}

/// Load OBJ text into a scene description (appending to `desc`), applying `xf`.
pub fn load_obj_text(
    text: &str,
    file: &str,
    mtl: MtlSource,
    xf: Mat4,
    desc: &mut SceneDesc,
) -> Result<(), String> {
    // a byte-order mark and CR-only line ends (Blender, old Mac tools) are not content
    let text = crate::input::clean_text(text);
    let checked = validate(&text, file)?;
    // Materials: our own parser, with line numbers.
    let mut mats: Vec<MaterialDesc> = Vec::new();
    // `mtllib a.mtl b.mtl` names two files, but a name may contain spaces too: a
    // name with spaces that does not exist as a whole is taken as several names
    let exists = |name: &str| match &mtl {
        MtlSource::Dir(dir) => normalise_path(dir, name).is_file(),
        MtlSource::Embedded(f) => f(name).is_some(),
    };
    let mut libs: Vec<(usize, &str)> = Vec::new();
    for (line_no, name) in &checked.mtllibs {
        if name.contains(' ') && !exists(name) {
            libs.extend(name.split(' ').map(|n| (*line_no, n)));
        } else {
            libs.push((*line_no, name));
        }
    }
    for (line_no, lib) in libs {
        let (mtl_text, mtl_name, dir) = match &mtl {
            MtlSource::Dir(dir) => {
                let p = normalise_path(dir, lib);
                let t = crate::input::read_text_lossy(&p)
                    .map_err(|e| format!("{file}:{line_no}: mtllib: {e}"))?;
                let parent = p.parent().unwrap_or(dir).to_path_buf();
                (t, p.display().to_string(), parent)
            }
            MtlSource::Embedded(f) => {
                let t =
                    f(lib).ok_or_else(|| format!("{file}:{line_no}: mtllib {lib}: not found"))?;
                (t.to_string(), lib.to_string(), Path::new(".").to_path_buf())
            }
        };
        let (read, note) = parse_mtl(&mtl_text, &mtl_name, &dir)?;
        mats.extend(read);
        desc.warnings.extend(note);
    }
    let mut unknown: Vec<&str> = Vec::new();
    for (line_no, name) in &checked.usemtls {
        if !mats.iter().any(|m| &m.name == name) && !unknown.contains(&name.as_str()) {
            unknown.push(name);
            desc.warnings.push(format!(
                "{file}:{line_no}: usemtl {name}: no material of that name in the mtllib files; using grey"
            ));
        }
    }
    let names: Vec<tobj::Material> = mats
        .iter()
        .map(|m| tobj::Material {
            name: m.name.clone(),
            ..Default::default()
        })
        .collect();
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let loaded = std::panic::catch_unwind(|| {
        let mut reader = BufReader::new(checked.text.as_bytes());
        tobj::load_obj_buf(&mut reader, &opts, |_p| {
            let map = names
                .iter()
                .enumerate()
                .map(|(i, m)| (m.name.clone(), i))
                .collect();
            Ok((names.clone(), map))
        })
    });
    let (models, tmats) = match loaded {
        Ok(Ok((m, t))) => (m, t.unwrap_or_default()),
        Ok(Err(e)) => return Err(format!("{file}: cannot parse OBJ: {e}")),
        Err(_) => return Err(format!("{file}: malformed OBJ (the parser gave up)")),
    };

    // Map tobj's material ids to scene material indices (by name; later files win).
    let base = desc.materials.len() as u32;
    desc.materials.extend(mats.iter().cloned());
    let mut default_mat: Option<u32> = None;
    let nxf = Mat4::from_mat3(glam::Mat3::from_mat4(xf).inverse().transpose());
    // A transform that swaps handedness (a mirror: negative determinant) turns every
    // counter-clockwise triangle clockwise: the front side, where emitters emit, would
    // face the other way. Swap two corners to keep it where the transformed normals
    // point (pbrt flips orientation the same way).
    let mirrored = glam::Mat3::from_mat4(xf).determinant() < 0.0;
    let order = |c: [usize; 3]| if mirrored { [c[0], c[2], c[1]] } else { c };
    let mut tri_index = 0;
    for model in &models {
        let mesh = &model.mesh;
        let mat = match mesh.material_id {
            Some(id) if id < tmats.len() => {
                let name = &tmats[id].name;
                base + mats.iter().rposition(|m| &m.name == name).unwrap_or(0) as u32
            }
            _ => *default_mat.get_or_insert_with(|| {
                desc.materials.push(MaterialDesc::named("kalos-default"));
                desc.materials.len() as u32 - 1
            }),
        };
        let p = &mesh.positions;
        let pos = |i: u32| -> Vec3 {
            let i = i as usize * 3;
            xf.transform_point3(Vec3::new(p[i], p[i + 1], p[i + 2]))
        };
        let has_n = !mesh.normals.is_empty() && mesh.normal_indices.len() == mesh.indices.len();
        let has_t = !mesh.texcoords.is_empty() && mesh.texcoord_indices.len() == mesh.indices.len();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let v = [pos(tri[0]), pos(tri[1]), pos(tri[2])];
            // tobj invents vn/vt for corners that have none: use only the face's own
            let (face_t, face_n) = checked.tri_has.get(tri_index).copied().unwrap_or_default();
            tri_index += 1;
            let n = if has_n && face_n {
                let nrm = |k: usize| {
                    let i = mesh.normal_indices[t * 3 + k] as usize * 3;
                    let nn = &mesh.normals;
                    nxf.transform_vector3(Vec3::new(nn[i], nn[i + 1], nn[i + 2]))
                        .normalize_or_zero()
                };
                let ns = [nrm(0), nrm(1), nrm(2)];
                ns.iter().all(|x| x.length_squared() > 0.5).then_some(ns)
            } else {
                None
            };
            let uv = if has_t && face_t {
                let tc = |k: usize| {
                    let i = mesh.texcoord_indices[t * 3 + k] as usize * 2;
                    let tt = &mesh.texcoords;
                    Vec2::new(tt[i], *tt.get(i + 1).unwrap_or(&0.0))
                };
                Some([tc(0), tc(1), tc(2)])
            } else {
                None
            };
            let k = order([0, 1, 2]);
            let v = k.map(|i| v[i]);
            let n = n.map(|n| k.map(|i| n[i]));
            let uv = uv.map(|uv| k.map(|i| uv[i]));
            desc.push_triangle(v, n, uv, mat);
        }
    }
    debug_assert_eq!(tri_index, checked.tri_has.len(), "tobj triangle count");
    Ok(())
}

/// Load an OBJ file from disk.
pub fn load_obj_file(path: &Path, xf: Mat4, desc: &mut SceneDesc) -> Result<(), String> {
    let text = crate::input::read_text_lossy(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    load_obj_text(
        &text,
        &path.display().to_string(),
        MtlSource::Dir(dir),
        xf,
        desc,
    )
}
