//! Wavefront OBJ loading with tobj: triangles, quads and n-gons (fan-triangulated),
//! negative (relative) indices, optional vn/vt, mtllib/usemtl, backslash paths.
//! A validation pass first reports bad lines as `file:line: ...` (tobj itself gives
//! no line numbers), so no input reaches tobj that could make it fail obscurely.

use super::mtl::{normalise_path, parse_mtl};
use super::{MaterialDesc, SceneDesc};
use glam::{Mat4, Vec2, Vec3};
use std::io::BufReader;
use std::path::Path;

/// Check every statement tobj will act on; returns the mtllib names in order.
fn validate(text: &str, file: &str) -> Result<Vec<String>, String> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    // totals first: positive indices may refer to any vertex of the file
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => nv += 1,
            Some("vt") => nt += 1,
            Some("vn") => nn += 1,
            _ => {}
        }
    }
    let (tv, tt, tn) = (nv, nt, nn);
    let (mut sv, mut st, mut sn) = (0i64, 0i64, 0i64);
    let mut mtllibs = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, rest)) = words.split_first() else {
            continue;
        };
        let floats = |n: usize, what: &str| -> Result<(), String> {
            if rest.len() < n {
                return Err(format!(
                    "{file}:{line_no}: {what} needs {n} numbers, found {}",
                    rest.len()
                ));
            }
            for w in &rest[..n] {
                let v: f32 = w
                    .parse()
                    .map_err(|_| format!("{file}:{line_no}: {what}: {w:?} is not a number"))?;
                if !v.is_finite() {
                    return Err(format!("{file}:{line_no}: {what}: value {w} is not finite"));
                }
            }
            Ok(())
        };
        match key {
            "v" => {
                floats(3, "vertex")?;
                sv += 1;
            }
            "vt" => {
                floats(1, "texture coordinate")?;
                st += 1;
            }
            "vn" => {
                floats(3, "normal")?;
                sn += 1;
            }
            "f" => {
                if rest.len() < 3 {
                    return Err(format!(
                        "{file}:{line_no}: face has {} vertices, a face needs at least 3",
                        rest.len()
                    ));
                }
                for w in rest {
                    let parts: Vec<&str> = w.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(format!("{file}:{line_no}: malformed face vertex {w:?}"));
                    }
                    let kinds = [
                        ("vertex", sv, tv),
                        ("texture coordinate", st, tt),
                        ("normal", sn, tn),
                    ];
                    for (k, p) in parts.iter().enumerate() {
                        if p.is_empty() {
                            continue;
                        }
                        let (what, so_far, total) = kinds[k];
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
                                "{file}:{line_no}: face references {what} {idx}, but {have} {what}s are defined{}",
                                if idx < 0 { " before it" } else { "" }
                            ));
                        }
                    }
                }
            }
            "mtllib" => {
                let name = rest.join(" ");
                if name.is_empty() {
                    return Err(format!("{file}:{line_no}: mtllib without a file name"));
                }
                mtllibs.push(name);
            }
            _ => {}
        }
    }
    Ok(mtllibs)
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
    let mtllibs = validate(text, file)?;
    // Materials: our own parser, with line numbers.
    let mut mats: Vec<MaterialDesc> = Vec::new();
    for lib in &mtllibs {
        let (mtl_text, mtl_name, dir) = match &mtl {
            MtlSource::Dir(dir) => {
                let p = normalise_path(dir, lib);
                let t = std::fs::read_to_string(&p)
                    .map_err(|e| format!("{file}: mtllib {}: {e}", p.display()))?;
                let parent = p.parent().unwrap_or(dir).to_path_buf();
                (t, p.display().to_string(), parent)
            }
            MtlSource::Embedded(f) => {
                let t = f(lib).ok_or_else(|| format!("{file}: mtllib {lib}: not found"))?;
                (t.to_string(), lib.clone(), Path::new(".").to_path_buf())
            }
        };
        mats.extend(parse_mtl(&mtl_text, &mtl_name, &dir)?);
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
        ..Default::default()
    };
    let loaded = std::panic::catch_unwind(|| {
        let mut reader = BufReader::new(text.as_bytes());
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
    for model in &models {
        let mesh = &model.mesh;
        let mat = match mesh.material_id {
            Some(id) if id < tmats.len() => {
                let name = &tmats[id].name;
                base + mats.iter().rposition(|m| &m.name == name).unwrap_or(0) as u32
            }
            _ => *default_mat.get_or_insert_with(|| {
                if !models.is_empty() && mesh.material_id.is_some() {
                    desc.warnings.push(format!(
                        "{file}: a usemtl names no material of its mtllib; using grey"
                    ));
                }
                desc.materials.push(MaterialDesc::named("kalos-default"));
                desc.materials.len() as u32 - 1
            }),
        };
        let p = &mesh.positions;
        let pos = |i: u32| -> Vec3 {
            let i = i as usize * 3;
            xf.transform_point3(Vec3::new(p[i] as f32, p[i + 1] as f32, p[i + 2] as f32))
        };
        let has_n = !mesh.normals.is_empty() && mesh.normal_indices.len() == mesh.indices.len();
        let has_t = !mesh.texcoords.is_empty() && mesh.texcoord_indices.len() == mesh.indices.len();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let v = [pos(tri[0]), pos(tri[1]), pos(tri[2])];
            let n = if has_n {
                let nrm = |k: usize| {
                    let i = mesh.normal_indices[t * 3 + k] as usize * 3;
                    let nn = &mesh.normals;
                    nxf.transform_vector3(Vec3::new(
                        nn[i] as f32,
                        nn[i + 1] as f32,
                        nn[i + 2] as f32,
                    ))
                    .normalize_or_zero()
                };
                let ns = [nrm(0), nrm(1), nrm(2)];
                ns.iter().all(|x| x.length_squared() > 0.5).then_some(ns)
            } else {
                None
            };
            let uv = if has_t {
                let tc = |k: usize| {
                    let i = mesh.texcoord_indices[t * 3 + k] as usize * 2;
                    let tt = &mesh.texcoords;
                    Vec2::new(tt[i] as f32, *tt.get(i + 1).unwrap_or(&0.0) as f32)
                };
                Some([tc(0), tc(1), tc(2)])
            } else {
                None
            };
            desc.push_triangle(v, n, uv, mat);
        }
    }
    Ok(())
}

/// Load an OBJ file from disk.
pub fn load_obj_file(path: &Path, xf: Mat4, desc: &mut SceneDesc) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let text = String::from_utf8_lossy(&bytes);
    let dir = path.parent().unwrap_or(Path::new("."));
    load_obj_text(
        &text,
        &path.display().to_string(),
        MtlSource::Dir(dir),
        xf,
        desc,
    )
}
