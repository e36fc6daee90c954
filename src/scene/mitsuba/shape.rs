//! Mitsuba's shapes as triangles: mesh files (OBJ, PLY) and the built-in shapes
//! (rectangle, cube, disk, sphere), with `to_world`, normals as Mitsuba computes them.

use super::*;

impl<'a> Loader<'a> {
    pub(super) fn shape(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("shape", kind) {
            return Err(format!("{}: unknown shape plugin '{kind}'", el.at));
        }
        match kind {
            "shapegroup" => return self.shape_group(el).map(|_| ()),
            "instance" => return self.instance(el),
            _ => {}
        }
        let supported = matches!(
            kind,
            "obj"
                | "ply"
                | "serialized"
                | "rectangle"
                | "cube"
                | "sphere"
                | "disk"
                | "cylinder"
                | "sdfgrid"
        );
        if !supported {
            self.mark_all(el);
            self.warn(
                &format!("shape {kind}"),
                format!(
                    "{}: unsupported shape '{kind}': left out of the scene",
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
        if kind == "sdfgrid" {
            if let Some(e) = emitter_el {
                return Err(format!(
                    "{}: an sdfgrid cannot be an area emitter (as in Mitsuba)",
                    e.at
                ));
            }
            return self.sdfgrid(el, mat);
        }
        if let Some(e) = emitter_el {
            if e.kind() != "area" {
                return Err(format!(
                    "{}: a shape's emitter must be 'area', not '{}'",
                    e.at,
                    e.kind()
                ));
            }
            let (radiance, texture) = self.area_radiance(e)?;
            self.unused(e, "emitter 'area'");
            let mut m = self.desc.materials[mat as usize].clone();
            m.name = format!(
                "{}+emitter@{}",
                m.name,
                e.at.rsplit(':').next().unwrap_or("")
            );
            m.ke = radiance;
            m.ke_texture = texture;
            m.source = Some(e.at.clone());
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
        let mut xf = self.transform(el, "to_world")?;
        let mut flip = self.boolean(el, "flip_normals")?.unwrap_or(false);
        let face_normals = self.boolean(el, "face_normals")?.unwrap_or(false);
        // Mitsuba flips an OBJ's texture coordinates by default, not a PLY's
        let flip_tex = self
            .boolean(el, "flip_tex_coords")?
            .unwrap_or(kind != "ply");
        // local mesh: positions, triangles, optional normals and uvs (kalos' v: up)
        let mesh = match kind {
            "obj" | "ply" => {
                let f = self
                    .string(el, "filename")?
                    .ok_or_else(|| format!("{}: {kind} shape without a filename", el.at))?;
                let path = self.path(&f);
                let mut m = if kind == "ply" {
                    crate::scene::ply::load_ply(&path).map_err(|e| format!("{}: {e}", el.at))?
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
                crate::scene::ply::PlyMesh {
                    positions: p.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
                    normals: None,
                    uvs: Some(
                        p.iter()
                            .map(|&(x, y)| Vec2::new((x + 1.0) * 0.5, (1.0 - y) * 0.5))
                            .collect(),
                    ),
                    triangles: vec![[0, 1, 2], [0, 2, 3]],
                    attributes: Vec::new(),
                }
            }
            "serialized" => {
                let f = self
                    .string(el, "filename")?
                    .ok_or_else(|| format!("{}: serialized shape without a filename", el.at))?;
                let index = self.int(el, "shape_index")?.unwrap_or(0);
                crate::scene::serialized::load_serialized(&self.path(&f), index)
                    .map_err(|e| format!("{}: {e}", el.at))?
            }
            "cylinder" => {
                let (m, place, f) = self.cylinder(el, xf, flip)?;
                (xf, flip) = (place, f);
                m
            }
            "cube" => cube(),
            "disk" => disk(128, 16),
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
        let smooth =
            matches!(kind, "obj" | "ply" | "serialized") && mesh.normals.is_none() && !face_normals;
        self.push_mesh(&mesh, xf, flip, face_normals, smooth, mat);
        Ok(())
    }

    /// An OBJ file's triangles as Mitsuba reads them: its materials are not used.
    pub(super) fn obj_mesh(&self, path: &Path) -> R<crate::scene::ply::PlyMesh> {
        let text = crate::input::read_text_lossy(path)?;
        let mut d = SceneDesc::default();
        let empty = |_: &str| Some("");
        crate::scene::obj::load_obj_text(
            &text,
            &path.display().to_string(),
            crate::scene::obj::MtlSource::Embedded(&empty),
            Mat4::IDENTITY,
            &mut d,
        )?;
        let mut m = crate::scene::ply::PlyMesh::default();
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

    pub(super) fn push_mesh(
        &mut self,
        m: &crate::scene::ply::PlyMesh,
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
        for (f, t) in m.triangles.iter().enumerate() {
            let i = order.map(|k| t[k] as usize);
            let v = i.map(|k| pos[k]);
            let n = nrm.as_ref().and_then(|ns| {
                let n = i.map(|k| ns[k]);
                n.iter().all(|x| x.length_squared() > 0.5).then_some(n)
            });
            let uv = m.uvs.as_ref().map(|uv| i.map(|k| uv[k]));
            let tri = self.desc.positions.len();
            self.desc.push_triangle(v, n, uv, mat);
            if !m.attributes.is_empty() && self.desc.positions.len() > tri {
                self.desc.push_attributes(&m.attributes, tri, i, f);
            }
        }
    }
}

/// Mitsuba's cube, [-1, 1]^3, with its uvs: on each face an affine map of the position,
/// ((a_u . p) + 1/2, (a_v . p) + 1/2) in Mitsuba's uv (v down the image), as Mitsuba's
/// `ray_intersect` gives them (checked to 1e-7 at random points of every face); the
/// face's two axes matter once the cube is scaled unevenly (a flat box's thin sides).
pub(super) fn cube() -> crate::scene::ply::PlyMesh {
    let mut m = crate::scene::ply::PlyMesh {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    // (outward normal, a_u, a_v)
    let faces = [
        (Vec3::X, Vec3::Y * 0.5, Vec3::Z * -0.5),
        (-Vec3::X, Vec3::Y * 0.5, Vec3::Z * 0.5),
        (Vec3::Y, Vec3::X * -0.5, Vec3::Z * -0.5),
        (-Vec3::Y, Vec3::Z * 0.5, Vec3::X * 0.5),
        (Vec3::Z, Vec3::Y * 0.5, Vec3::X * 0.5),
        (-Vec3::Z, Vec3::Y * -0.5, Vec3::X * 0.5),
    ];
    for (n, a_u, a_v) in faces {
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let b = m.positions.len() as u32;
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let p = n + u * x + v * y;
            m.positions.push(p);
            // kalos' v points up the image
            let uv = Vec2::new(a_u.dot(p) + 0.5, 0.5 - a_v.dot(p));
            m.uvs.as_mut().unwrap().push(uv);
        }
        m.triangles.push([b, b + 1, b + 2]);
        m.triangles.push([b, b + 2, b + 3]);
    }
    m
}

/// Mitsuba's unit disk in the plane z = 0 with its polar uv (r, phi / 2 pi): `segs`
/// sectors of `rings` rings, the seam's vertices doubled (phi 0 and 1) and each sector's
/// centre vertex at the sector's middle angle, so that the interpolated uv follows the
/// polar one (one centre vertex for all would give every sector's inner triangle the
/// angle 0).
pub(super) fn disk(segs: u32, rings: u32) -> crate::scene::ply::PlyMesh {
    let mut m = crate::scene::ply::PlyMesh {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    let vertex = |m: &mut crate::scene::ply::PlyMesh, r: f32, t: f32| {
        let phi = std::f32::consts::TAU * t;
        m.positions
            .push(Vec3::new(r * phi.cos(), r * phi.sin(), 0.0));
        // kalos' v points up the image
        m.uvs.as_mut().unwrap().push(Vec2::new(r, 1.0 - t));
        m.positions.len() as u32 - 1
    };
    // grid[j][i]: ring j + 1 (radius (j + 1) / rings), angle i / segs
    let mut grid = Vec::new();
    for j in 1..=rings {
        let r = j as f32 / rings as f32;
        let ring: Vec<u32> = (0..=segs)
            .map(|i| vertex(&mut m, r, i as f32 / segs as f32))
            .collect();
        grid.push(ring);
    }
    for i in 0..segs as usize {
        let c = vertex(&mut m, 0.0, (i as f32 + 0.5) / segs as f32);
        m.triangles.push([c, grid[0][i], grid[0][i + 1]]);
        for j in 0..rings as usize - 1 {
            let (a, b) = (grid[j][i], grid[j + 1][i]);
            let (cc, d) = (grid[j + 1][i + 1], grid[j][i + 1]);
            m.triangles.push([a, b, cc]);
            m.triangles.push([a, cc, d]);
        }
    }
    m
}

/// A unit sphere of `rings` x `segs` quads with exact normals (Mitsuba's uv: phi / 2 pi,
/// theta / pi).
pub(super) fn sphere(rings: u32, segs: u32) -> crate::scene::ply::PlyMesh {
    let mut m = crate::scene::ply::PlyMesh {
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

/// Vertex normals of a mesh that has none, as Mitsuba recomputes them (in world space,
/// after `to_world`): each face's unit normal added to its corners weighted by the
/// corner's angle (Thuermer and Wuthrich 1998), then normalised; a vertex whose sum
/// vanishes gets zero (its triangles keep their face normal).
pub(super) fn vertex_normals(pos: &[Vec3], tris: &[[u32; 3]], order: [usize; 3]) -> Vec<Vec3> {
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
