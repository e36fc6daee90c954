//! OBJ/MTL/TOML loading as real tools and archives write these files: polygons, relative
//! indices, optional vn/vt, backslash paths, emitters, mirror/glass, degenerate faces,
//! CRLF, comments, groups, TOML scenes with transforms and overrides, and TOML errors.

use glam::{Mat4, Vec3};
use kalos::material::Bsdf;
use kalos::scene::obj::{load_obj_text, MtlSource};
use kalos::scene::{self, SceneDesc};
use std::path::{Path, PathBuf};

/// A fresh directory under the system temp dir, unique per test and process.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-obj-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    if let Some(parent) = p.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&p, text).unwrap();
    p
}

fn no_mtl(_: &str) -> Option<&'static str> {
    None
}

/// Load OBJ text without any MTL files.
fn load_text(text: &str) -> Result<SceneDesc, String> {
    let mut d = SceneDesc::default();
    load_obj_text(
        text,
        "test.obj",
        MtlSource::Embedded(&no_mtl),
        Mat4::IDENTITY,
        &mut d,
    )?;
    Ok(d)
}

/// Load OBJ text with one embedded MTL file named `m.mtl`.
fn load_with_mtl(obj: &str, mtl: &'static str) -> Result<SceneDesc, String> {
    let f = move |name: &str| (name == "m.mtl").then_some(mtl);
    let mut d = SceneDesc::default();
    load_obj_text(
        obj,
        "test.obj",
        MtlSource::Embedded(&f),
        Mat4::IDENTITY,
        &mut d,
    )?;
    Ok(d)
}

fn area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

fn total_area(d: &SceneDesc) -> f32 {
    d.positions.iter().map(area).sum()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

/// A unit square (quad), a regular hexagon of radius 1 and a regular pentagon of
/// radius 1 (n-gons), one object each, all in planes z = const.
fn polygons_obj(relative: bool) -> String {
    let mut s = String::from("# polygons\n");
    // quad
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        s += &format!("v {x} {y} 0\n");
    }
    s += if relative {
        "f -4 -3 -2 -1\n"
    } else {
        "f 1 2 3 4\n"
    };
    for (n, z, first) in [(6, 1.0, 5), (5, 2.0, 11)] {
        for k in 0..n {
            let a = std::f32::consts::TAU * k as f32 / n as f32;
            s += &format!("v {} {} {z}\n", a.cos(), a.sin());
        }
        s += "f";
        for k in 0..n {
            if relative {
                s += &format!(" {}", k - n);
            } else {
                s += &format!(" {}", first + k);
            }
        }
        s += "\n";
    }
    s
}

#[test]
fn quads_and_ngons_are_triangulated_with_the_right_area() {
    let d = load_text(&polygons_obj(false)).unwrap();
    assert_eq!(d.positions.len(), 2 + 4 + 3);
    assert_eq!(d.skipped_degenerate, 0);
    let quad: f32 = d.positions[..2].iter().map(area).sum();
    let hex: f32 = d.positions[2..6].iter().map(area).sum();
    let pent: f32 = d.positions[6..].iter().map(area).sum();
    assert!(close(quad, 1.0, 1e-5), "quad area {quad}");
    let hex_area = 1.5 * 3f32.sqrt();
    assert!(close(hex, hex_area, 1e-5), "hexagon area {hex}");
    let pent_area = 2.5 * (std::f32::consts::TAU / 5.0).sin();
    assert!(close(pent, pent_area, 1e-5), "pentagon area {pent}");
    assert!(close(total_area(&d), 1.0 + hex_area + pent_area, 1e-5));
    // every triangle lies in its polygon's plane
    for (i, t) in d.positions.iter().enumerate() {
        let z = if i < 2 {
            0.0
        } else if i < 6 {
            1.0
        } else {
            2.0
        };
        assert!(t.iter().all(|v| v.z == z));
    }
}

#[test]
fn negative_indices_resolve_like_positive_ones() {
    let abs = load_text(&polygons_obj(false)).unwrap();
    let rel = load_text(&polygons_obj(true)).unwrap();
    assert_eq!(abs.positions, rel.positions);
    // mixed: relative indices for vt/vn too
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                f -3/-3/-1 -2/-2/-1 -1/-1/-1\nf 1/1/1 2/2/1 3/3/1\n";
    let d = load_text(text).unwrap();
    assert_eq!(d.positions.len(), 2);
    assert_eq!(d.positions[0], d.positions[1]);
    assert_eq!(d.uvs[0], d.uvs[1]);
    assert_eq!(d.normals[0], d.normals[1]);
}

#[test]
fn normals_and_uvs_are_per_triangle_where_given() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n\
                vn 0 0 2\nvn 0.6 0 0.8\n\
                f 1/1/1 2/2/2 3/3/1\n\
                f 2/2 4/4 3/3\n\
                f 1//1 2//1 3//2\n";
    let d = load_text(text).unwrap();
    assert_eq!(d.positions.len(), 3);
    let n = d.normals[0].expect("vn given: shading normals");
    assert!((n[0] - Vec3::Z).length() < 1e-6, "normals are normalised");
    assert!((n[1] - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6);
    let uv = d.uvs[0].expect("vt given: uvs");
    assert_eq!(uv[1], glam::Vec2::new(1.0, 0.0));
    assert_eq!(uv[2], glam::Vec2::new(0.0, 1.0));
    // the second face has uvs but no normals: flat shading
    assert!(d.normals[1].is_none(), "face without vn got normals");
    assert_eq!(d.uvs[1].unwrap()[1], glam::Vec2::new(1.0, 1.0));
    // the third has normals but no uvs
    assert!(d.normals[2].is_some());
    assert!(d.uvs[2].is_none(), "face without vt got uvs");

    let flat = load_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert!(flat.normals[0].is_none() && flat.uvs[0].is_none());
}

/// A 2x2 RGB PNG: red, green / blue, white.
fn write_png(path: &Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let px = [255u8, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
    image::RgbImage::from_raw(2, 2, px.to_vec())
        .unwrap()
        .save(path)
        .unwrap();
}

#[test]
fn backslash_paths_in_mtllib_and_map_kd_load() {
    let dir = temp_dir("backslash");
    write_png(&dir.join("sub").join("tex").join("checker.png"));
    write(
        &dir,
        "sub/mats.mtl",
        "newmtl tex\nKd 1 1 1\nmap_Kd -s 1 1 1 tex\\checker.png\n\
         newmtl light\nKd 0 0 0\nKe 5 5 5\n",
    );
    let obj = write(
        &dir,
        "scene.obj",
        "mtllib sub\\mats.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl tex\nf 1/1 2/2 3/3\nusemtl light\nf 1 3 2\n",
    );
    let s = scene::load(obj.to_str().unwrap()).unwrap();
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width, t.height), (2, 2));
    // sRGB-decoded: 255 -> 1, 0 -> 0
    assert_eq!(t.texels[0], [1.0, 0.0, 0.0]);
    assert_eq!(t.texels[3], [1.0, 1.0, 1.0]);
    let m = s.material_of(0);
    assert_eq!(m.name, "tex");
    assert_eq!(m.kd_texture, Some(0));
    assert_eq!(s.lights.len(), 1);
}

#[test]
fn emitters_mirrors_and_glass_come_from_the_mtl() {
    let mtl = "newmtl lamp\nKd 0 0 0\nKe 10 10 10\n\
               newmtl mirror\nKs 0.9 0.9 0.9\nillum 5\n\
               newmtl glass\nNi 1.33\nillum 7\n\
               newmtl plastic\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nNs 50\nillum 2\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
               usemtl lamp\nf 1 2 3 4\nusemtl mirror\nf 1 2 3\nusemtl glass\nf 1 3 4\n\
               usemtl plastic\nf 4 3 2 1\n";
    let d = load_with_mtl(obj, mtl).unwrap();
    assert_eq!(d.positions.len(), 6);
    let s = scene::Scene::build(d, 0.0).unwrap();
    assert_eq!(
        s.lights.len(),
        2,
        "the emissive quad is two light triangles"
    );
    assert_eq!(s.info.emitters, 2);
    assert!(s.material_of(0).is_emissive());
    assert_eq!(s.material_of(0).emission, [10.0; 3]);
    assert!(matches!(s.material_of(2).bsdf, Bsdf::Mirror(_)));
    match &s.material_of(3).bsdf {
        Bsdf::Dielectric(g) => assert_eq!(g.eta, 1.33),
        b => panic!("illum 7 gave {b:?}"),
    }
    assert!(matches!(s.material_of(4).bsdf, Bsdf::DiffuseGlossy(..)));
    assert!(matches!(s.material_of(5).bsdf, Bsdf::DiffuseGlossy(..)));
}

#[test]
fn zero_area_faces_are_skipped_and_counted() {
    let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n\
                f 1 2 3\nf 1 1 4\nf 1 2 4\nf 4 4 4\n";
    let d = load_text(text).unwrap();
    assert_eq!(d.positions.len(), 1);
    assert_eq!(d.skipped_degenerate, 3);
    let s = scene::Scene::build(d, 0.0).unwrap();
    assert_eq!(s.info.skipped_degenerate, 3);
    assert!(s.warnings.iter().any(|w| w.contains("3 zero-area")));
}

#[test]
fn faces_without_usemtl_get_the_default_material() {
    let mtl = "newmtl red\nKd 0.8 0.1 0.1\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl red\nf 1 3 2\n";
    let d = load_with_mtl(obj, mtl).unwrap();
    assert_eq!(d.positions.len(), 2);
    assert_eq!(d.materials[d.material[0] as usize].name, "kalos-default");
    assert_eq!(d.materials[d.material[1] as usize].name, "red");
    assert_eq!(d.materials[d.material[1] as usize].kd, [0.8, 0.1, 0.1]);

    let d = load_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(d.materials.len(), 1);
    assert_eq!(d.materials[0].kd, [0.5; 3]);
}

#[test]
fn multiple_objects_and_groups_keep_their_materials() {
    let mtl = "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\nnewmtl c\nKd 0 0 1\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
               o first\nusemtl a\nf 1 2 3\ng part\nf 2 4 3\nusemtl b\nf 1 2 4\n\
               o second\nusemtl c\nf 1 3 4\ng\nf 1 2 3 4\n";
    let d = load_with_mtl(obj, mtl).unwrap();
    let names: Vec<&str> = d
        .material
        .iter()
        .map(|&m| d.materials[m as usize].name.as_str())
        .collect();
    // a material stays in effect across o/g until the next usemtl
    assert_eq!(names, ["a", "a", "b", "c", "c", "c"]);
}

#[test]
fn crlf_comments_blank_lines_and_tabs_are_accepted() {
    let mtl = "# materials\r\n\r\nnewmtl  white \r\nKd 0.7 0.7 0.7 # grey\r\n";
    let lf = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl white\nf 1 2 3 4\n";
    let crlf = "# exported by hand\r\n\r\nmtllib m.mtl\r\nv 0 0 0 # origin\r\nv\t1 0 0\r\n\
                v 0 1 0\r\n  v 1 1 0\r\n\r\n# faces\r\n  usemtl white\r\nf 1 2 3 4 # quad\r\n";
    let a = load_with_mtl(lf, mtl).unwrap();
    let b = load_with_mtl(crlf, mtl).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(b.positions.len(), 2);
    assert_eq!(b.materials[b.material[0] as usize].name, "white");
    assert_eq!(b.materials[b.material[0] as usize].kd, [0.7; 3]);
}

#[test]
fn statements_tools_write_that_tobj_alone_gets_wrong() {
    let mtl = "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n";
    // vertex colours, `w`, 1D texture coordinates, usemtl before mtllib and indented
    // with a tab, polylines of three points (not faces), a face using vertices defined
    // after a later `o` (forward references), trailing comments everywhere
    let obj = "o first # name\nv 0 0 0 1 0 0\nv 2 0 0 1 0 0\nv 0 2 0 2 # w = 2\n\
               vt 0.5 # 1D\n\tusemtl\tb\nmtllib m.mtl # late\nf 1/1 2/1 3/1 # tri\n\
               l 1 2 3\np 1\no second\nusemtl a\nf 4 5 6\nv 0 0 1\nv 1 0 1\nv 0 1 1\n";
    let d = load_with_mtl(obj, mtl).unwrap();
    assert_eq!(d.positions.len(), 2, "the polyline is not a face");
    assert_eq!(d.positions[0][2], Vec3::new(0.0, 1.0, 0.0), "w divides");
    assert_eq!(d.positions[1][1], Vec3::new(1.0, 0.0, 1.0));
    assert_eq!(d.uvs[0].unwrap()[0], glam::Vec2::new(0.5, 0.0));
    assert_eq!(d.materials[d.material[0] as usize].name, "b");
    assert_eq!(d.materials[d.material[1] as usize].name, "a");
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);

    // an unknown usemtl falls back to grey, with a warning naming the line
    let d = load_with_mtl(
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl c\nf 1 2 3\n",
        mtl,
    )
    .unwrap();
    assert_eq!(d.materials[d.material[0] as usize].name, "kalos-default");
    assert_eq!(d.warnings.len(), 1);
    assert!(
        d.warnings[0].starts_with("test.obj:5: usemtl c"),
        "{:?}",
        d.warnings
    );
}

#[test]
fn mtllib_may_name_several_files_or_one_with_spaces() {
    let dir = temp_dir("mtllibs");
    write(&dir, "one.mtl", "newmtl a\nKd 1 0 0\n");
    write(&dir, "two.mtl", "newmtl b\nKd 0 1 0\n");
    write(&dir, "my mats.mtl", "newmtl c\nKd 0 0 1\n");
    let obj = write(
        &dir,
        "s.obj",
        "mtllib one.mtl two.mtl\nmtllib my mats.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
         usemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\nusemtl c\nf 2 1 3\n",
    );
    let d = scene::load_desc(obj.to_str().unwrap()).unwrap();
    let kd: Vec<[f32; 3]> = d
        .material
        .iter()
        .map(|&m| d.materials[m as usize].kd)
        .collect();
    assert_eq!(kd, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let obj = write(&dir, "t.obj", "v 0 0 0\nmtllib one.mtl gone.mtl\n");
    let e = scene::load_desc(obj.to_str().unwrap()).unwrap_err();
    assert!(
        e.contains("t.obj:2: mtllib") && e.contains("gone.mtl"),
        "{e}"
    );
}

#[test]
fn obj_errors_name_file_and_line() {
    let cases = [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 99\n", "test.obj:5:"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "test.obj:4:"),
        ("v 0 0 0\nv 1 nan 0\n", "test.obj:2:"),
        (
            "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 -4\r\n",
            "test.obj:4:",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "test.obj:4:"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nf 1/1 2/1 3/1\n", "ok"),
        ("v 0 0 0 0\n", "test.obj:1:"),
        ("v 0 0 0 x\n", "test.obj:1:"),
    ];
    for (text, want) in cases {
        match load_text(text) {
            Ok(_) => assert_eq!(want, "ok", "{text:?} loaded"),
            Err(e) => {
                assert!(e.starts_with(want), "{text:?}: {e}");
                assert!(!e.contains('\n'), "{e}");
            }
        }
    }
}

/// A square in the xy plane, [0,1]^2 at z = 0, facing +z.
const SQUARE: &str =
    "mtllib square.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl white\nf 1 2 3 4\n";
const SQUARE_MTL: &str = "newmtl white\nKd 0.8 0.8 0.8\n";
/// A small emitting triangle around (0, 0, 5) facing -z.
const LAMP: &str =
    "mtllib lamp.mtl\nv -0.5 -0.5 5\nv 0 0.5 5\nv 0.5 -0.5 5\nusemtl lamp\nf 1 2 3\n";
const LAMP_MTL: &str = "newmtl lamp\nKd 0 0 0\nKe 4 4 4\n";

#[test]
fn toml_scene_with_transforms_overrides_camera_and_defaults() {
    let dir = temp_dir("toml");
    write(&dir, "square.obj", SQUARE);
    write(&dir, "square.mtl", SQUARE_MTL);
    write(&dir, "parts/lamp.obj", LAMP);
    write(&dir, "parts/lamp.mtl", LAMP_MTL);
    let toml = write(
        &dir,
        "scene.toml",
        r#"# a test scene
[camera]
origin = [0, 0, 10]
target = [0, 0, 0]
up = [0, 1, 0]
fov = 40

[render]
res = [16, 8]
spp = 4
max_depth = 3

[[objects]]
file = "square.obj"
scale = 2
rotate = [0, 90, 0]
translate = [10, 0, 0]

[[objects]]
file = 'parts\lamp.obj'

[materials.white]
kd = [0.1, 0.2, 0.3]
ns = 20
"#,
    );
    let d = scene::load_desc(toml.to_str().unwrap()).unwrap();
    assert_eq!(d.name, "scene");
    assert_eq!(d.positions.len(), 3);
    // the square: scaled to [0,2]^2, rotated +90 degrees about y (x -> -z), moved to x = 10
    let mut b = kalos::math::Bounds3::EMPTY;
    for t in &d.positions[..2] {
        for v in t {
            b.grow(*v);
        }
    }
    assert!(
        (b.min - Vec3::new(10.0, 0.0, -2.0)).abs().max_element() < 1e-5,
        "{b:?}"
    );
    assert!(
        (b.max - Vec3::new(10.0, 2.0, 0.0)).abs().max_element() < 1e-5,
        "{b:?}"
    );
    // the lamp is untransformed
    assert_eq!(d.positions[2][0], Vec3::new(-0.5, -0.5, 5.0));
    let white = d.materials.iter().find(|m| m.name == "white").unwrap();
    assert_eq!(white.kd, [0.1, 0.2, 0.3]);
    assert_eq!(white.ns, 20.0);
    let cam = d.camera.unwrap();
    assert_eq!(cam.origin, [0.0, 0.0, 10.0]);
    assert_eq!(cam.fov, 40.0);
    assert_eq!(d.defaults.res, Some((16, 8)));
    assert_eq!(d.defaults.spp, Some(4));
    assert_eq!(d.defaults.max_depth, Some(3));
    let s = scene::Scene::build(d, 0.0).unwrap();
    assert_eq!(s.lights.len(), 1);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn toml_errors_name_the_file_and_line() {
    let dir = temp_dir("toml-errors");
    write(&dir, "square.obj", SQUARE);
    write(&dir, "square.mtl", SQUARE_MTL);
    let obj = "[[objects]]\nfile = \"square.obj\"\n";
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown.toml",
            format!("{obj}\n[render]\nspp = 4\nfoo = 1\n"),
            ":6:",
        ),
        ("unknown-top.toml", format!("{obj}bogus = 1\n"), ":3:"),
        ("syntax.toml", format!("{obj}[render\nspp = 4\n"), ":3:"),
        (
            "missing.toml",
            "[[objects]]\nfile = \"nope.obj\"\n".into(),
            "nope.obj",
        ),
        (
            "override.toml",
            format!("{obj}[materials.gold]\nkd = [1, 1, 0]\n"),
            "gold",
        ),
        (
            "negative.toml",
            format!("{obj}[materials.white]\nkd = [1, -1, 0]\n"),
            "kd",
        ),
        ("noobjects.toml", "[render]\nspp = 1\n".into(), "objects"),
        ("spp0.toml", format!("{obj}[render]\nspp = 0\n"), "spp"),
        (
            "res0.toml",
            format!("{obj}[render]\nres = [0, 10]\n"),
            "res",
        ),
        (
            "depth0.toml",
            format!("{obj}[render]\nmax_depth = 0\n"),
            "max_depth",
        ),
        (
            "camera.toml",
            format!(
                "{obj}[camera]\norigin = [0, 0, 1]\ntarget = [0, 0, 1]\nup = [0, 1, 0]\nfov = 40\n"
            ),
            "camera",
        ),
        (
            "scale0.toml",
            "[[objects]]\nfile = \"square.obj\"\nscale = [-1, 0, 1]\n".into(),
            "scale",
        ),
    ];
    for (name, text, want) in cases {
        let p = write(&dir, name, &text);
        let spec = p.to_str().unwrap();
        let e = match scene::load_desc(spec) {
            Ok(_) => panic!("{name} loaded"),
            Err(e) => e,
        };
        assert!(e.starts_with(spec), "{name}: {e}");
        assert!(e.contains(want), "{name}: {e} (wanted {want})");
        assert!(!e.contains('\n'), "{name}: multi-line: {e}");
    }
}

#[test]
fn missing_and_bad_files_are_errors_naming_the_file() {
    let dir = temp_dir("missing");
    let nope = dir.join("nope.obj");
    let e = scene::load_desc(nope.to_str().unwrap()).unwrap_err();
    assert!(e.contains("nope.obj"), "{e}");
    let obj = write(
        &dir,
        "a.obj",
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = scene::load_desc(obj.to_str().unwrap()).unwrap_err();
    assert!(e.contains("a.obj") && e.contains("gone.mtl"), "{e}");
    write(&dir, "t.mtl", "newmtl t\nmap_Kd missing.png\n");
    let obj = write(
        &dir,
        "t.obj",
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl t\nf 1 2 3\n",
    );
    let e = scene::load(obj.to_str().unwrap()).err().unwrap();
    assert!(e.contains("missing.png"), "{e}");
    write(&dir, "bad.mtl", "newmtl a\n\nKs -1 0 0\n");
    let obj = write(
        &dir,
        "b.obj",
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = scene::load_desc(obj.to_str().unwrap()).unwrap_err();
    assert!(e.contains("bad.mtl:3:"), "{e}");
    let bin = dir.join("x.obj");
    std::fs::write(&bin, [0u8, 159, 146, 150, 0, 1, 2, 255, 10, 0, 0]).unwrap();
    let e = scene::load_desc(bin.to_str().unwrap()).unwrap_err();
    assert!(e.contains("x.obj"), "{e}");
}

// ---- hostile and careless input ------------------------------------------------------

/// Geometric normal of a triangle from its winding: (v1 - v0) x (v2 - v0).
fn winding_normal(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize()
}

/// A unit quad in z = 0, counter-clockwise seen from +z, with vn (0, 0, 1) at every corner,
/// emitting towards +z (the front side).
const FRONT_QUAD: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n\
usemtl lamp\nf 1//1 2//1 3//1 4//1\n";
const LAMP_ONLY: &str = "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n";

#[test]
fn mirroring_transforms_keep_the_front_side_and_the_normals() {
    // (transform, the quad's front normal after it): a mirror maps the front +z of the
    // quad to the mirrored +z; pbrt flips the winding when a transform swaps handedness
    let cases = [
        (Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)), Vec3::Z),
        (Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0)), -Vec3::Z),
        (Mat4::from_scale(Vec3::new(-1.0, -1.0, 1.0)), Vec3::Z), // a rotation: det > 0
        (Mat4::from_scale(Vec3::new(-2.0, -3.0, -0.5)), -Vec3::Z),
    ];
    for (xf, front) in cases {
        let f = move |name: &str| (name == "m.mtl").then_some(LAMP_ONLY);
        let mut d = SceneDesc::default();
        load_obj_text(FRONT_QUAD, "q.obj", MtlSource::Embedded(&f), xf, &mut d).unwrap();
        assert_eq!(d.positions.len(), 2);
        for (t, n) in d.positions.iter().zip(&d.normals) {
            let g = winding_normal(t);
            assert!(
                g.dot(front) > 0.999,
                "{xf:?}: winding normal {g} (front {front})"
            );
            for v in n.expect("vn given") {
                assert!(
                    v.dot(front) > 0.999,
                    "{xf:?}: shading normal {v} (front {front})"
                );
            }
        }
    }
}

#[test]
fn a_mirrored_toml_object_still_lights_the_scene() {
    // the lamp faces -z towards a floor at z = -1; mirrored in x it must still face -z
    let dir = temp_dir("mirror");
    write(
        &dir,
        "m.mtl",
        "newmtl lamp\nKd 0 0 0\nKe 4 4 4\nnewmtl floor\nKd 0.5 0.5 0.5\n",
    );
    write(
        &dir,
        "lamp.obj",
        "mtllib m.mtl\nv 0 0 0\nv 0 1 0\nv 1 1 0\nv 1 0 0\nusemtl lamp\nf 1 2 3 4\n",
    );
    write(
        &dir,
        "floor.obj",
        "mtllib m.mtl\nv -5 -5 -1\nv 5 -5 -1\nv 5 5 -1\nv -5 5 -1\nusemtl floor\nf 1 2 3 4\n",
    );
    for scale in ["1", "[-1, 1, 1]"] {
        let toml = write(
            &dir,
            "s.toml",
            &format!(
                "[[objects]]\nfile = \"floor.obj\"\n[[objects]]\nfile = \"lamp.obj\"\nscale = {scale}\n"
            ),
        );
        let d = scene::load_desc(toml.to_str().unwrap()).unwrap();
        for (t, &m) in d.positions.iter().zip(&d.material) {
            if d.materials[m as usize].name == "lamp" {
                let g = winding_normal(t);
                assert!(g.z < -0.999, "scale {scale}: the lamp faces {g}");
            }
        }
    }
}

#[test]
fn a_byte_order_mark_is_not_part_of_the_first_line() {
    // the first `v` must not be lost (every later index would shift)
    let d = load_text("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(d.positions.len(), 1);
    assert_eq!(d.positions[0][0], Vec3::ZERO);
    // nor the mtllib (every material lost), nor the MTL's first newmtl
    let d = load_with_mtl(
        "\u{feff}mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        "\u{feff}newmtl a\nKd 0.1 0.2 0.3\n",
    )
    .unwrap();
    assert_eq!(d.materials[d.material[0] as usize].kd, [0.1, 0.2, 0.3]);
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    // and from files on disk
    let dir = temp_dir("bom");
    write(&dir, "b.mtl", "\u{feff}newmtl b\r\nKd 0.25 0.5 0.75\r\n");
    let obj = write(
        &dir,
        "b.obj",
        "\u{feff}mtllib b.mtl\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nusemtl b\r\nf 1 2 3\r\n",
    );
    let d = scene::load_desc(obj.to_str().unwrap()).unwrap();
    assert_eq!(d.materials[d.material[0] as usize].kd, [0.25, 0.5, 0.75]);
    let toml = write(&dir, "b.toml", "\u{feff}[[objects]]\nfile = \"b.obj\"\n");
    assert_eq!(
        scene::load_desc(toml.to_str().unwrap())
            .unwrap()
            .positions
            .len(),
        1
    );
}

#[test]
fn old_mac_line_ends_are_line_ends() {
    let d = load_with_mtl(
        "mtllib m.mtl\rv 0 0 0\rv 1 0 0\rv 0 1 0\rusemtl a\rf 1 2 3\r",
        "newmtl a\rKd 0.1 0.2 0.3\r",
    )
    .unwrap();
    assert_eq!(d.positions.len(), 1);
    assert_eq!(d.materials[d.material[0] as usize].kd, [0.1, 0.2, 0.3]);
    // line numbers count CR-only lines too
    let e = load_text("v 0 0 0\rv 1 0 0\r\rf 1 2 3\r").unwrap_err();
    assert!(e.starts_with("test.obj:4:"), "{e}");
}

#[test]
fn map_kd_file_names_with_spaces_after_options() {
    let dir = Path::new("/d");
    let cases = [
        ("map_Kd my tex.png", "/d/my tex.png"),
        ("map_Kd  my  tex.png  ", "/d/my  tex.png"),
        ("map_Kd -s 1 1 1 my tex.png", "/d/my tex.png"),
        ("map_Kd -s 2 -o 0.5 0.5 tex.png", "/d/tex.png"),
        (
            "map_Kd -clamp on -bm 0.5 -blendu off -blendv on my tex.png",
            "/d/my tex.png",
        ),
        (
            "map_Kd -mm 0 1 -texres 512 -imfchan l -type sphere -cc off -boost 2 a b.png",
            "/d/a b.png",
        ),
        (
            "map_Kd -o 1 -t 0.1 0.2 0.3 dir\\my tex.png",
            "/d/dir/my tex.png",
        ),
        (
            "map_Kd \"C:\\Textures\\my wood.png\"",
            "/d/C:/Textures/my wood.png",
        ),
    ];
    for (line, want) in cases {
        let (m, _) = kalos::scene::mtl::parse_mtl(&format!("newmtl a\n{line}\n"), "x.mtl", dir)
            .unwrap_or_else(|e| panic!("{line}: {e}"));
        assert_eq!(m[0].map_kd.as_deref(), Some(Path::new(want)), "{line}");
    }
    for line in [
        "map_Kd",
        "map_Kd -s 1 1 1",
        "map_Kd -clamp on",
        "map_Kd -bogus x.png",
    ] {
        let e =
            kalos::scene::mtl::parse_mtl(&format!("newmtl a\n{line}\n"), "x.mtl", dir).unwrap_err();
        assert!(e.starts_with("x.mtl:2: map_Kd"), "{line}: {e}");
    }
    // a texture named with spaces loads
    let dir = temp_dir("spaces");
    write_png(&dir.join("my tex.png"));
    write(
        &dir,
        "my mats.mtl",
        "newmtl t\nKd 1 1 1\nmap_Kd -s 1 1 1 -clamp on my tex.png\n",
    );
    let obj = write(
        &dir,
        "my scene.obj",
        "mtllib my mats.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\n",
    );
    let s = scene::load(obj.to_str().unwrap()).unwrap();
    assert_eq!(s.textures.len(), 1);
}

/// Warnings of a loaded scene that name material `name`.
fn warnings_naming<'a>(w: &'a [String], name: &str) -> Vec<&'a String> {
    w.iter()
        .filter(|w| w.contains(&format!("'{name}'")))
        .collect()
}

#[test]
fn out_of_range_material_values_warn_once_per_material_with_file_and_line() {
    let mtl = "newmtl hot\nKd 2 2 2\nKs 1e30 0 0\n\
               newmtl glass\nNi 0\nillum 7\n\
               newmtl odd\nKd 0.5 0.5 0.5\nillum 99\n\
               newmtl fine\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nillum 2\n\
               newmtl fine\nKd 0.1 0.1 0.1\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl hot\nf 1 2 3\n";
    let d = load_with_mtl(obj, mtl).unwrap();
    let s = scene::Scene::build(d, 0.0).unwrap();
    let w: Vec<String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("material '"))
        .cloned()
        .collect();
    let w = &w;
    let hot = warnings_naming(w, "hot");
    assert_eq!(hot.len(), 1, "{w:?}");
    assert!(
        hot[0].starts_with("m.mtl:1:") && hot[0].contains("Kd") && hot[0].contains("Ks"),
        "{w:?}"
    );
    let glass = warnings_naming(w, "glass");
    assert_eq!(glass.len(), 1, "{w:?}");
    assert!(
        glass[0].starts_with("m.mtl:4:") && glass[0].contains("Ni"),
        "{w:?}"
    );
    let odd = warnings_naming(w, "odd");
    assert_eq!(odd.len(), 1, "{w:?}");
    assert!(
        odd[0].starts_with("m.mtl:7:") && odd[0].contains("illum 99"),
        "{w:?}"
    );
    let fine = warnings_naming(w, "fine");
    assert_eq!(fine.len(), 1, "{w:?}");
    assert!(
        fine[0].starts_with("m.mtl:14:") && fine[0].contains("duplicate"),
        "{w:?}"
    );
    assert_eq!(w.len(), 4, "{w:?}");
}

#[test]
fn kd_plus_ks_above_one_is_scaled_to_one_with_one_warning() {
    use kalos::spectrum::Spectrum;
    let dir = temp_dir("energy");
    // mean texel (1, 1, 1)/2 + (1, 0, 0)/4 + (0, 1, 0)/4 + (0, 0, 1)/4: 0.5 per channel
    write_png(&dir.join("t.png"));
    write(
        &dir,
        "m.mtl",
        "newmtl bright\nKd 0.8 0.5 0.5\nKs 0.6 0.2 0.2\nNs 20\n\
         newmtl textured\nKd 1 1 1\nKs 0.75 0.75 0.75\nmap_Kd t.png\n\
         newmtl mirror\nKs 1.5 1 1\nillum 5\n\
         newmtl ok\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\n",
    );
    let obj = write(
        &dir,
        "s.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl bright\nf 1 2 3\nusemtl textured\nf 1/1 2/2 3/3\nusemtl mirror\nf 1 3 2\nusemtl ok\nf 2 1 3\n",
    );
    let s = scene::load(obj.to_str().unwrap()).unwrap();
    for name in ["bright", "textured", "mirror"] {
        assert_eq!(
            warnings_naming(&s.warnings, name).len(),
            1,
            "{name}: {:?}",
            s.warnings
        );
    }
    assert!(
        warnings_naming(&s.warnings, "ok").is_empty(),
        "{:?}",
        s.warnings
    );
    for m in &s.materials {
        let b = match m.kd_texture {
            Some(t) => m.bsdf.clone().with_kd(s.textures[t as usize].mean()),
            None => m.bsdf.clone(),
        };
        let a = b
            .albedo::<16>()
            .max_value()
            .max(b.albedo::<3>().max_value());
        assert!(a <= 1.0 + 1e-5, "{}: albedo {a}", m.name);
        assert!(
            a >= 1.0 - 1e-3 || m.name == "ok",
            "{}: scaled below 1: {a}",
            m.name
        );
        let _ = Spectrum::<8>::ONE;
    }
    // the ratio Kd : Ks is kept: bright was (0.8 + 0.6) = 1.4 in red
    match &s.material_of(0).bsdf {
        Bsdf::DiffuseGlossy(l, p) => {
            assert!((l.kd[0] / p.ks[0] - 0.8 / 0.6).abs() < 1e-4, "{l:?} {p:?}");
        }
        b => panic!("{b:?}"),
    }
    // the built-in furnaces are left exactly as they are
    for name in ["furnace", "furnace-glossy", "cornell", "cornell-glossy"] {
        let s = scene::load(name).unwrap();
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
}

#[test]
fn toml_material_overrides_warn_like_mtl_values() {
    let dir = temp_dir("toml-notes");
    write(&dir, "square.obj", SQUARE);
    write(&dir, "square.mtl", SQUARE_MTL);
    let toml = write(
        &dir,
        "n.toml",
        "[[objects]]\nfile = \"square.obj\"\n[materials.white]\nillum = 99\nkd = [0.9, 0.9, 0.9]\nks = [0.3, 0.3, 0.3]\n",
    );
    let s = scene::load(toml.to_str().unwrap()).unwrap();
    let w = warnings_naming(&s.warnings, "white");
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(
        w[0].contains("illum 99") && w[0].contains("n.toml"),
        "{w:?}"
    );
    assert!(w[0].contains("scaled"), "{w:?}");
    let toml = write(
        &dir,
        "g.toml",
        "[[objects]]\nfile = \"square.obj\"\n[materials.white]\nillum = 7\nni = 0\n",
    );
    let s = scene::load(toml.to_str().unwrap()).unwrap();
    let w = warnings_naming(&s.warnings, "white");
    assert!(w.len() == 1 && w[0].contains("Ni 0"), "{:?}", s.warnings);
}

/// The values Blender's OBJ exporters write (`Ks 0` with `illum 2`, `Ni 1.0`, `Ni 0`, no
/// `Ni`, `Pr 0`, `Pm 1`) build into the surfaces Blender renders, never an error: a coat
/// of specular level 0 or of IOR 1 reflects nothing, so the base is diffuse alone.
#[test]
fn blender_mtl_values_render_as_blender_does() {
    let mtl = "# Blender 4.2.0 MTL File: 'room.blend'\n# www.blender.org\n\n\
               newmtl BackLight\nNs 250.0\nKa 1.0 1.0 1.0\nKd 0.8 0.8 0.8\nKs 0.000000 0.000000 0.000000\nKe 0 0 0\nNi 1.45\nd 1.0\nillum 2\n\n\
               newmtl IorOne\nNs 250.0\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNi 1.000000\nillum 2\n\n\
               newmtl IorZero\nNs 250.0\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNi 0.000000\nillum 2\n\n\
               newmtl NoIor\nNs 250.0\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nillum 2\n\n\
               newmtl Smooth\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNi 1.5\nPr 0.0\nillum 2\n\n\
               newmtl Metal\nKd 0.9 0.6 0.0\nKs 0.5 0.5 0.5\nNi 1.5\nPr 0.2\nPm 1.0\nillum 3\n\n\
               newmtl Lamp\nKd 0.8 0.8 0.8\nKs 0 0 0\nKe 5 5 5\nillum 2\n";
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\n");
    for m in [
        "BackLight",
        "IorOne",
        "IorZero",
        "NoIor",
        "Smooth",
        "Metal",
        "Lamp",
    ] {
        obj.push_str(&format!("usemtl {m}\nf 1 2 3\n"));
    }
    let d = load_with_mtl(&obj, mtl).unwrap();
    let s = scene::Scene::build(d, 0.0).unwrap_or_else(|e| panic!("refused: {e}"));
    for (i, what) in ["Ks 0", "Ni 1", "Ni 0"].iter().enumerate() {
        match &s.material_of(i as u32).bsdf {
            Bsdf::Diffuse(l) => assert_eq!(l.kd, [0.8; 3], "{what}"),
            b => panic!("{what}: {b:?}"),
        }
    }
    // no Ni: Blender 4 keeps IOR 1.5, level 0.5 -> F0 0.04, eta 1.5
    match &s.material_of(3).bsdf {
        Bsdf::Plastic(p) => assert!((p.coat.eta - 1.5).abs() < 1e-4, "{}", p.coat.eta),
        b => panic!("no Ni: {b:?}"),
    }
    match &s.material_of(4).bsdf {
        Bsdf::Plastic(p) => assert!(p.coat.alpha == 0.0 && (p.coat.eta - 1.5).abs() < 1e-4),
        b => panic!("Pr 0: {b:?}"),
    }
    match &s.material_of(5).bsdf {
        Bsdf::Conductor(c) => assert!((c.alpha - 0.04).abs() < 1e-6, "{}", c.alpha),
        b => panic!("Pm 1: {b:?}"),
    }
    assert!(s.material_of(6).is_emissive());
}
