//! Generates the built-in test scene `assets/scenes/room.obj` + `room.mtl`: an architectural
//! interior like the paper's (large homogeneous walls, a glossy floor with Ks 0.6 and
//! Ns 15, a few pieces of furniture, two ceiling area lights).
//!
//!     cargo run --release --example gen_room -- [OUT_DIR] [--preview preview.png]
//!
//! OUT_DIR defaults to assets/scenes. `--preview` also ray casts the suggested camera view
//! (flat shading; faces seen from their back side in red) to check the view and windings.
//!
//! Conventions: metres, y up, room x 0..6, y 0..3, z 0..5. Every triangle is wound
//! counter-clockwise as seen from the side its normal (b - a) x (c - a) points to, and every
//! normal points into the room's air (walls inward, furniture outward). Emitters (`Ke`)
//! emit on that side only. The generator checks both before writing.

use std::fmt::Write as _;
use std::path::PathBuf;

type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn normalize(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

const X: V3 = [1.0, 0.0, 0.0];
const Y: V3 = [0.0, 1.0, 0.0];
const Z: V3 = [0.0, 0.0, 1.0];

/// Suggested camera (written into the OBJ header).
const EYE: V3 = [5.5, 1.6, 4.7];
const TARGET: V3 = [1.2, 0.9, 0.9];
const VFOV_DEG: f64 = 60.0;
const ASPECT: f64 = 4.0 / 3.0;

const ROOM: V3 = [6.0, 3.0, 5.0];
/// Target edge length of the wall, floor and ceiling grid cells.
const CELL: f64 = 0.25;

struct Group {
    name: String,
    material: &'static str,
    faces: Vec<[usize; 3]>,
    /// Per face: the furniture box it belongs to (an index into `Mesh::solids`).
    owner: Vec<Option<usize>>,
}

#[derive(Default)]
struct Mesh {
    verts: Vec<V3>,
    groups: Vec<Group>,
    /// Solid furniture boxes (min, max), for the air test.
    solids: Vec<(V3, V3)>,
}

impl Mesh {
    fn group(&mut self, name: &str, material: &'static str) {
        self.groups.push(Group {
            name: name.to_string(),
            material,
            faces: Vec::new(),
            owner: Vec::new(),
        });
    }

    /// A rectangle o + s u + t v (s, t in 0..1) split into nu x nv cells, two triangles
    /// each, wound so that the normal is u x v, which must point along `normal`.
    fn rect(&mut self, o: V3, u: V3, v: V3, nu: usize, nv: usize, normal: V3) {
        self.rect_of(o, u, v, nu, nv, normal, None)
    }

    #[allow(clippy::too_many_arguments)]
    fn rect_of(
        &mut self,
        o: V3,
        u: V3,
        v: V3,
        nu: usize,
        nv: usize,
        normal: V3,
        owner: Option<usize>,
    ) {
        let n = normalize(cross(u, v));
        assert!(
            dot(n, normal) > 0.999,
            "rect at {o:?}: u x v = {n:?}, wanted {normal:?}"
        );
        let base = self.verts.len();
        for j in 0..=nv {
            for i in 0..=nu {
                let p = add(
                    o,
                    add(
                        scale(u, i as f64 / nu as f64),
                        scale(v, j as f64 / nv as f64),
                    ),
                );
                self.verts.push(p);
            }
        }
        let id = |i: usize, j: usize| base + j * (nu + 1) + i;
        let g = self.groups.last_mut().expect("a group");
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                g.faces.push([a, b, c]);
                g.faces.push([a, c, d]);
                g.owner.extend([owner, owner]);
            }
        }
    }

    /// A wall-like rectangle subdivided into cells of about CELL metres.
    fn grid(&mut self, o: V3, u: V3, v: V3, normal: V3) {
        let cells = |e: V3| ((dot(e, e).sqrt() / CELL).round() as usize).max(1);
        self.rect(o, u, v, cells(u), cells(v), normal);
    }

    /// An axis-aligned box with outward normals; `skip` names faces that are hidden
    /// against something else ("-y" bottom, "+y" top, "-x", "+x", "-z", "+z").
    fn cuboid(&mut self, lo: V3, hi: V3, skip: &[&str]) {
        let d = sub(hi, lo);
        let (dx, dy, dz) = (scale(X, d[0]), scale(Y, d[1]), scale(Z, d[2]));
        let faces: [(&str, V3, V3, V3, V3); 6] = [
            ("-y", lo, dx, dz, scale(Y, -1.0)),
            ("+y", [lo[0], hi[1], lo[2]], dz, dx, Y),
            ("-z", lo, dy, dx, scale(Z, -1.0)),
            ("+z", [lo[0], lo[1], hi[2]], dx, dy, Z),
            ("-x", lo, dz, dy, scale(X, -1.0)),
            ("+x", [hi[0], lo[1], lo[2]], dy, dz, X),
        ];
        let id = self.solids.len();
        self.solids.push((lo, hi));
        for (name, o, u, v, n) in faces {
            if !skip.contains(&name) {
                self.rect_of(o, u, v, 1, 1, n, Some(id));
            }
        }
    }

    fn triangles(&self) -> impl Iterator<Item = (&Group, usize, [V3; 3])> {
        self.groups.iter().flat_map(move |g| {
            g.faces
                .iter()
                .enumerate()
                .map(move |(i, f)| (g, i, [self.verts[f[0]], self.verts[f[1]], self.verts[f[2]]]))
        })
    }

    /// Every normal must point into the air: a point 1 cm off each triangle's centroid
    /// along its normal lies inside the room and, for furniture, outside its own box.
    fn check_normals(&self) {
        for (g, i, [a, b, c]) in self.triangles() {
            let n = normalize(cross(sub(b, a), sub(c, a)));
            let p = add(scale(add(add(a, b), c), 1.0 / 3.0), scale(n, 0.01));
            let in_room = (0..3).all(|k| p[k] > 0.0 && p[k] < ROOM[k]);
            let in_own_box = g.owner[i].is_some_and(|s| {
                let (lo, hi) = self.solids[s];
                (0..3).all(|k| p[k] > lo[k] && p[k] < hi[k])
            });
            assert!(
                in_room && !in_own_box,
                "{}: triangle {a:?} {b:?} {c:?} faces away from the room",
                g.name
            );
        }
    }
}

fn build() -> Mesh {
    let mut m = Mesh::default();
    let [w, h, d] = ROOM;
    let o = [0.0; 3];

    // Shell: normals into the room.
    m.group("floor", "floor");
    m.grid(o, scale(Z, d), scale(X, w), Y);
    m.group("ceiling", "ceiling");
    m.grid([0.0, h, 0.0], scale(X, w), scale(Z, d), scale(Y, -1.0));
    m.group("wall_back", "wall");
    m.grid(o, scale(X, w), scale(Y, h), Z);
    m.group("wall_front", "wall");
    m.grid([0.0, 0.0, d], scale(Y, h), scale(X, w), scale(Z, -1.0));
    m.group("wall_left", "wall_accent");
    m.grid(o, scale(Y, h), scale(Z, d), X);
    m.group("wall_right", "wall");
    m.grid([w, 0.0, 0.0], scale(Z, d), scale(Y, h), scale(X, -1.0));

    // Table: 1.6 x 0.9 top at 0.75 m, four legs.
    m.group("table", "wood");
    m.cuboid([2.2, 0.71, 2.15], [3.8, 0.75, 3.05], &[]);
    for (x, z) in [(2.25, 2.2), (3.69, 2.2), (2.25, 2.94), (3.69, 2.94)] {
        m.cuboid([x, 0.0, z], [x + 0.06, 0.71, z + 0.06], &["-y", "+y"]);
    }

    // Two chairs facing the table from the left and from the right.
    for (i, (x0, z0, back_low_x)) in [(1.55, 2.35, true), (4.0, 2.45, false)]
        .into_iter()
        .enumerate()
    {
        m.group(&format!("chair_{}", i + 1), "chair");
        let (x1, z1) = (x0 + 0.45, z0 + 0.45);
        m.cuboid([x0, 0.41, z0], [x1, 0.45, z1], &[]);
        for (lx, lz) in [
            (x0, z0),
            (x1 - 0.04, z0),
            (x0, z1 - 0.04),
            (x1 - 0.04, z1 - 0.04),
        ] {
            m.cuboid([lx, 0.0, lz], [lx + 0.04, 0.41, lz + 0.04], &["-y", "+y"]);
        }
        let bx = if back_low_x { x0 } else { x1 - 0.04 };
        m.cuboid([bx, 0.45, z0], [bx + 0.04, 0.95, z1], &["-y"]);
    }

    // Cabinet against the back wall (1 cm off it, no coplanar faces).
    m.group("cabinet", "cabinet");
    m.cuboid([0.6, 0.0, 0.01], [1.8, 1.9, 0.51], &["-y", "-z"]);

    // Wall shelf on the left wall with two boxes on it.
    m.group("shelf", "wood");
    m.cuboid([0.01, 1.5, 1.2], [0.31, 1.53, 2.6], &["-x"]);
    m.group("box_red", "box_red");
    m.cuboid([0.05, 1.53, 1.35], [0.27, 1.75, 1.65], &["-y"]);
    m.group("box_white", "cabinet");
    m.cuboid([0.06, 1.53, 2.0], [0.26, 1.65, 2.4], &["-y"]);

    // Two 1.0 x 0.5 m area lights 2 cm below the ceiling, emitting downwards:
    // counter-clockwise as seen from below.
    for (i, x) in [2.0, 4.0].into_iter().enumerate() {
        m.group(&format!("light_{}", i + 1), "light");
        m.rect(
            [x - 0.5, h - 0.02, 2.35],
            scale(X, 1.0),
            scale(Z, 0.5),
            1,
            1,
            scale(Y, -1.0),
        );
    }
    m.check_normals();
    m
}

const MTL: &str = "\
# kalos room scene materials (generated by examples/gen_room.rs)
# Ke: emitted radiance; a face emits on the side its counter-clockwise winding faces.

newmtl wall
illum 1
Kd 0.72 0.70 0.65

newmtl wall_accent
illum 1
Kd 0.50 0.60 0.72

newmtl ceiling
illum 1
Kd 0.80 0.80 0.80

# Glossy floor as in the paper (specular 0.6, shininess 15).
newmtl floor
illum 2
Kd 0.30 0.20 0.12
Ks 0.60 0.60 0.60
Ns 15

newmtl wood
illum 1
Kd 0.45 0.28 0.15

newmtl chair
illum 1
Kd 0.15 0.25 0.45

newmtl cabinet
illum 1
Kd 0.66 0.63 0.56

newmtl box_red
illum 1
Kd 0.60 0.12 0.10

newmtl light
illum 1
Kd 0.00 0.00 0.00
Ke 12.0 12.0 10.5
";

fn write_obj(m: &Mesh) -> String {
    let tris: usize = m.groups.iter().map(|g| g.faces.len()).sum();
    let mut s = String::new();
    let v3 = |v: V3| format!("{} {} {}", v[0], v[1], v[2]);
    let _ = writeln!(
        s,
        "# kalos room scene: generated by examples/gen_room.rs, do not edit by hand.\n\
         # Metres, y up; room x 0..6, y 0..3, z 0..5; {} vertices, {tris} triangles.\n\
         # All faces are counter-clockwise as seen from the room (normals point into the air).\n\
         # Suggested camera (shows the back and left walls, floor, furniture, some ceiling):\n\
         # camera eye {}\n\
         # camera target {}\n\
         # camera up 0 1 0\n\
         # camera vfov {VFOV_DEG}\n\
         # camera aspect {ASPECT:.4}\n\
         mtllib room.mtl",
        m.verts.len(),
        v3(EYE),
        v3(TARGET)
    );
    for v in &m.verts {
        let r = |x: f64| (x * 1e4).round() / 1e4;
        let _ = writeln!(s, "v {} {} {}", r(v[0]), r(v[1]), r(v[2]));
    }
    for g in &m.groups {
        let _ = writeln!(s, "o {}\nusemtl {}", g.name, g.material);
        for f in &g.faces {
            let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
        }
    }
    s
}

/// Flat-shaded ray cast of the suggested view; back faces in red.
fn preview(m: &Mesh, path: &PathBuf) {
    let (w, h) = (320u32, 240u32);
    let fwd = normalize(sub(TARGET, EYE));
    let right = normalize(cross(fwd, Y));
    let up = cross(right, fwd);
    let t = (VFOV_DEG.to_radians() * 0.5).tan();
    let tris: Vec<(&Group, [V3; 3])> = m.triangles().map(|(g, _, t)| (g, t)).collect();
    let kd = |mat: &str| -> V3 {
        match mat {
            "wall" => [0.72, 0.70, 0.65],
            "wall_accent" => [0.50, 0.60, 0.72],
            "ceiling" => [0.8; 3],
            "floor" => [0.45, 0.32, 0.2],
            "wood" => [0.45, 0.28, 0.15],
            "chair" => [0.15, 0.25, 0.45],
            "box_red" => [0.6, 0.12, 0.1],
            "light" => [1.0, 1.0, 0.9],
            _ => [0.66, 0.63, 0.56],
        }
    };
    let mut img = image::RgbImage::new(w, h);
    for py in 0..h {
        for px in 0..w {
            let sx = (2.0 * (px as f64 + 0.5) / w as f64 - 1.0) * t * ASPECT;
            let sy = (1.0 - 2.0 * (py as f64 + 0.5) / h as f64) * t;
            let dir = normalize(add(fwd, add(scale(right, sx), scale(up, sy))));
            let mut best = (f64::INFINITY, [0.0; 3]);
            for (g, [a, b, c]) in &tris {
                // Moller-Trumbore
                let (e1, e2) = (sub(*b, *a), sub(*c, *a));
                let p = cross(dir, e2);
                let det = dot(e1, p);
                if det.abs() < 1e-12 {
                    continue;
                }
                let tv = sub(EYE, *a);
                let u = dot(tv, p) / det;
                let q = cross(tv, e1);
                let v = dot(dir, q) / det;
                let dist = dot(e2, q) / det;
                if u < 0.0 || v < 0.0 || u + v > 1.0 || dist <= 1e-6 || dist >= best.0 {
                    continue;
                }
                let n = normalize(cross(e1, e2));
                let cos = -dot(n, dir);
                let col = if cos < 0.0 {
                    [1.0, 0.0, 0.0]
                } else {
                    scale(kd(g.material), 0.35 + 0.65 * cos)
                };
                best = (dist, col);
            }
            let c = best
                .1
                .map(|x| (x.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8);
            img.put_pixel(px, py, image::Rgb(c));
        }
    }
    img.save(path).expect("write preview");
    eprintln!("preview: {}", path.display());
}

fn main() {
    let mut out = PathBuf::from("assets/scenes");
    let mut preview_path = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--preview" {
            preview_path = Some(PathBuf::from(args.next().expect("--preview FILE.png")));
        } else {
            out = PathBuf::from(a);
        }
    }
    let m = build();
    std::fs::create_dir_all(&out).expect("create output folder");
    let obj = write_obj(&m);
    std::fs::write(out.join("room.obj"), &obj).expect("write room.obj");
    std::fs::write(out.join("room.mtl"), MTL).expect("write room.mtl");
    let tris: usize = m.groups.iter().map(|g| g.faces.len()).sum();
    eprintln!(
        "{}: {} vertices, {tris} triangles, {} bytes",
        out.join("room.obj").display(),
        m.verts.len(),
        obj.len()
    );
    // Read the files back the way the renderer will (tobj), as a check.
    let (models, mats) =
        tobj::load_obj(out.join("room.obj"), &tobj::GPU_LOAD_OPTIONS).expect("tobj reads room.obj");
    let mats = mats.expect("tobj reads room.mtl");
    let n: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    assert_eq!(n, tris, "tobj triangle count");
    let light = mats.iter().find(|m| m.name == "light").expect("light");
    assert_eq!(light.emissive, Some([12.0, 12.0, 10.5]));
    let floor = mats.iter().find(|m| m.name == "floor").expect("floor");
    assert_eq!(
        (floor.specular, floor.shininess),
        (Some([0.6; 3]), Some(15.0))
    );

    if let Some(p) = preview_path {
        preview(&m, &p);
    }
}
