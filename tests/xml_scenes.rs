//! Mitsuba XML scenes and PLY meshes: Mitsuba's own Cornell box (written out by Mitsuba
//! 3.9.1) against Mitsuba's reference image, a scene assembled from `<include>`, `<default>`,
//! a binary PLY and a Wavefront OBJ, and the interior case: a closed room without a camera
//! renders lit (the default camera is moved inside).

mod common;
use common::*;
use kalos::image_io::{read_image, RgbImage};
use kalos::material::Distribution;
use kalos::scene::{self, Scene, SurfaceModel};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-xml-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn rmse(a: &RgbImage, b: &RgbImage) -> f64 {
    let mut s = 0.0;
    for (p, q) in a.data.iter().zip(b.data.iter()) {
        for c in 0..3 {
            s += ((p[c] - q[c]) as f64).powi(2);
        }
    }
    (s / (3 * a.data.len()) as f64).sqrt()
}

#[test]
fn mitsubas_cornell_box_xml_agrees_with_mitsubas_reference() {
    let reference = read_image(Path::new("assets/reference/cornell-256-reference.exr")).unwrap();
    let scene = scene::load("scenes/mitsuba/cornell-box.xml").unwrap();
    // the same triangles as the built-in copy of mi.cornell_box()
    let builtin = scene::load("cornell").unwrap();
    assert_eq!(scene.tris.len(), builtin.tris.len());
    assert_eq!(scene.info.bounds_min, builtin.info.bounds_min);
    assert_eq!(scene.defaults.res, Some((256, 256)));
    assert_eq!(scene.defaults.spp, Some(64));
    assert_eq!(scene.defaults.max_depth, Some(8));
    // the file asks for Mitsuba's Gaussian; the reference was rendered with a box filter
    assert_eq!(
        scene.camera.filter,
        kalos::scene::camera::PixelFilter::Gaussian { stddev: 0.5 }
    );
    let mut set = settings(&scene, 256, 256);
    set.camera.filter = kalos::scene::camera::PixelFilter::Box;
    set.integrator.max_depth = -1; // the reference is unlimited
    let ref_mean: f64 = reference.mean().iter().sum::<f64>() / 3.0;
    let mut errors = Vec::new();
    let mut last = f64::INFINITY;
    for spp in [4u32, 16, 64] {
        let film = render_spp(&scene, &set, spp);
        let img = RgbImage::new(256, 256, film.mean_rgb());
        let e = rmse(&img, &reference);
        let mean: f64 = img.mean().iter().sum::<f64>() / 3.0;
        errors.push((spp, e, mean));
        // orientation, camera and fov all right: the error falls as 1/sqrt(spp)
        assert!(e < last / 1.6, "RMSE stalls: {errors:?}");
        last = e;
        if spp == 64 {
            let rel = (mean - ref_mean).abs() / ref_mean;
            assert!(rel < 0.005, "mean {mean} vs reference {ref_mean}");
        }
    }
    eprintln!("(spp, rmse, mean) {errors:?}");
}

/// A binary little-endian PLY quad (two triangles) in the z = 0 plane, [0,1]^2, normal +z.
fn ply_quad() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for v in [x, y, 0.0, 0.0, 0.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
    }
    b.push(4);
    for i in [0i32, 1, 2, 3] {
        b.extend(i.to_le_bytes());
    }
    b
}

#[test]
fn includes_defaults_ply_and_obj_shapes() {
    let d = temp_dir("parts");
    std::fs::create_dir_all(d.join("meshes")).unwrap();
    std::fs::write(d.join("meshes/quad.ply"), ply_quad()).unwrap();
    std::fs::write(
        d.join("meshes/tri.obj"),
        "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl whatever\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        d.join("materials.xml"),
        r#"<scene version="3.0.0">
  <bsdf type="roughplastic" id="plastic">
    <rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/>
    <float name="alpha" value="$rough"/>
  </bsdf>
</scene>"#,
    )
    .unwrap();
    std::fs::write(
        d.join("scene.xml"),
        r#"<?xml version="1.0" encoding="utf-8"?>
<scene version="0.6.0">
  <default name="rough" value="0.3"/>
  <include filename="materials.xml"/>
  <shape type="ply">
    <string name="filename" value="meshes/quad.ply"/>
    <transform name="toWorld"><scale value="2"/><translate z="1"/></transform>
    <ref id="plastic"/>
  </shape>
  <shape type="obj">
    <string name="filename" value="meshes/tri.obj"/>
    <boolean name="flipNormals" value="true"/>
    <emitter type="area"><spectrum name="radiance" value="2"/></emitter>
  </shape>
  <emitter type="point"><point name="position" x="0" y="0" z="3"/>
    <rgb name="intensity" value="5"/></emitter>
</scene>"#,
    )
    .unwrap();
    let desc = scene::load_desc(d.join("scene.xml").to_str().unwrap()).unwrap();
    assert_eq!(desc.positions.len(), 3);
    // the PLY quad: scaled to [0,2]^2 at z = 1, with its normals
    assert!(desc.positions[..2]
        .iter()
        .flatten()
        .all(|v| v.z == 1.0 && v.x <= 2.0 && v.y <= 2.0));
    assert!(desc.normals[0].is_some());
    let m = &desc.materials[desc.material[0] as usize];
    assert_eq!(
        m.model,
        Some(SurfaceModel::Plastic {
            eta: 1.49 / 1.000277,
            specular: [1.0; 3],
            alpha: 0.3,
            // no distribution given: Mitsuba's default
            distribution: Distribution::Beckmann,
            nonlinear: false
        })
    );
    // the OBJ's own materials are not Mitsuba's: the emitter is the XML's, and flipped
    let t = desc.positions[2];
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    assert!(n.z < 0.0, "flip_normals turns the winding: {n}");
    let e = &desc.materials[desc.material[2] as usize];
    assert!(
        e.ke[0] > 2.0 && e.ke[2] < 2.0,
        "equal-energy white: {:?}",
        e.ke
    );
    assert_eq!(desc.point_lights.len(), 1);
    assert_eq!(desc.point_lights[0].intensity, [5.0; 3]);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
}

/// A mesh file without normals is smooth-shaded, as Mitsuba recomputes its vertex normals
/// (angle-weighted, over shared vertices: a PLY's indices, an OBJ's positions), unless
/// `face_normals` is set: a roof and a wall meeting at a shared edge get 45-degree
/// normals there (Sionna's Munich scene showed kalos 3x brighter on such roofs).
#[test]
fn meshes_without_normals_are_smooth_unless_face_normals() {
    let d = temp_dir("smooth");
    // a roof (z = 1, facing +z) and a wall (x = 1, facing +x) sharing the edge x = 1, z = 1
    std::fs::write(
        d.join("bent.obj"),
        "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 2 4 5\nf 2 5 3\n",
    )
    .unwrap();
    let xml = |extra: &str| {
        format!(
            r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="bent.obj"/>{extra}</shape></scene>"#
        )
    };
    std::fs::write(d.join("smooth.xml"), xml("")).unwrap();
    std::fs::write(
        d.join("flat.xml"),
        xml(r#"<boolean name="face_normals" value="true"/>"#),
    )
    .unwrap();
    let smooth = scene::load_desc(d.join("smooth.xml").to_str().unwrap()).unwrap();
    let ns = smooth.normals[0].expect("recomputed vertex normals");
    // the roof's corner (0, 0, 1) is only the roof's: +z
    assert!((ns[0] - glam::Vec3::Z).length() < 1e-5, "{ns:?}");
    // (1, 0, 1) is shared by the roof (angle 90) and the wall (angle 90 + 45): tilted
    let shared = ns[1];
    assert!(
        shared.x > 0.3 && shared.z > 0.3 && shared.y.abs() < 0.35,
        "{shared}"
    );
    assert!((shared.length() - 1.0).abs() < 1e-5);
    let flat = scene::load_desc(d.join("flat.xml").to_str().unwrap()).unwrap();
    assert!(flat.normals.iter().all(|n| n.is_none()));
}

/// A closed 6 x 3 x 4 room (walls facing in), a lamp panel under the ceiling, a table.
fn closed_room_obj() -> String {
    let mut s = String::from("mtllib room.mtl\n");
    let mut nv = 0;
    let mut quad = |s: &mut String, c: [[f32; 3]; 4], m: &str| {
        for v in c {
            s.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str(&format!(
            "usemtl {m}\nf {} {} {} {}\n",
            nv + 1,
            nv + 2,
            nv + 3,
            nv + 4
        ));
        nv += 4;
    };
    let (x, y, z) = (3.0, 3.0, 2.0);
    // counter-clockwise seen from inside
    quad(
        &mut s,
        [[-x, 0.0, -z], [-x, 0.0, z], [x, 0.0, z], [x, 0.0, -z]],
        "wall",
    ); // floor, +y
    quad(
        &mut s,
        [[-x, y, -z], [x, y, -z], [x, y, z], [-x, y, z]],
        "wall",
    ); // ceiling, -y
    quad(
        &mut s,
        [[-x, 0.0, -z], [x, 0.0, -z], [x, y, -z], [-x, y, -z]],
        "wall",
    ); // back, +z
    quad(
        &mut s,
        [[-x, 0.0, z], [-x, y, z], [x, y, z], [x, 0.0, z]],
        "wall",
    ); // front, -z
    quad(
        &mut s,
        [[-x, 0.0, -z], [-x, y, -z], [-x, y, z], [-x, 0.0, z]],
        "wall",
    ); // left, +x
    quad(
        &mut s,
        [[x, 0.0, -z], [x, 0.0, z], [x, y, z], [x, y, -z]],
        "wall",
    ); // right, -x
    let ly = y - 0.01;
    quad(
        &mut s,
        [
            [-0.5, ly, -0.5],
            [0.5, ly, -0.5],
            [0.5, ly, 0.5],
            [-0.5, ly, 0.5],
        ],
        "lamp",
    );
    quad(
        &mut s,
        [
            [1.0, 0.8, -1.0],
            [1.0, 0.8, 0.0],
            [2.0, 0.8, 0.0],
            [2.0, 0.8, -1.0],
        ],
        "wall",
    );
    s
}

#[test]
fn a_closed_room_without_a_camera_renders_lit() {
    let d = temp_dir("room");
    std::fs::write(d.join("room.obj"), closed_room_obj()).unwrap();
    std::fs::write(
        d.join("room.mtl"),
        "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n",
    )
    .unwrap();
    let scene: Scene = scene::load(d.join("room.obj").to_str().unwrap()).unwrap();
    let w = scene.warnings_for(false).join("\n");
    assert!(w.contains("closed room") && w.contains("--camera"), "{w}");
    // A render with its own camera is not told where the default one went.
    let w = scene.warnings_for(true).join("\n");
    assert!(
        !w.contains("closed room") && !w.contains("no camera"),
        "{w}"
    );
    let room = d.join("room.obj");
    let kalos = |camera: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_kalos"))
            .args([
                "render",
                room.to_str().unwrap(),
                "--res",
                "8x8",
                "--spp",
                "1",
            ])
            .args(camera)
            .arg("-o")
            .arg(d.join("room.exr"))
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    assert!(kalos(&[]).contains("no camera given"));
    let given = kalos(&["--camera", "0,1,0,1,1,0,0,1,0,60"]);
    assert!(!given.contains("no camera given"), "{given}");
    assert!(
        scene.info.camera_from.contains("inside"),
        "{}",
        scene.info.camera_from
    );
    let o = glam::Vec3::from(scene.camera.origin);
    assert!(
        o.x.abs() < 3.0 && o.y > 0.0 && o.y < 3.0 && o.z.abs() < 2.0,
        "{o}"
    );
    let set = settings(&scene, 32, 32);
    let film = render_spp(&scene, &set, 8);
    let img = film.mean_rgb();
    let lit = img.iter().filter(|p| p[1] > 0.01).count();
    assert!(
        lit > img.len() * 9 / 10,
        "{lit} of {} pixels lit",
        img.len()
    );

    // an open scene keeps the framing camera
    let open = scene::load("scenes/mitsuba/cornell-box.xml").unwrap();
    assert_eq!(open.info.camera_from, "scene file");
    let mut desc = scene::load_desc("cornell").unwrap();
    desc.camera = None;
    let s = Scene::build(desc, 0.0).unwrap();
    assert!(
        s.info.camera_from.contains("framing"),
        "{}",
        s.info.camera_from
    );
    assert!(!s
        .warnings_for(false)
        .iter()
        .any(|w| w.contains("closed room")));
}

#[test]
fn info_prints_the_default_camera() {
    let d = temp_dir("info");
    std::fs::write(d.join("room.obj"), closed_room_obj()).unwrap();
    std::fs::write(
        d.join("room.mtl"),
        "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKe 10 10 10\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args(["info", d.join("room.obj").to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().find(|l| l.starts_with("camera")).unwrap();
    // the roomiest point sees the lamp; the camera backs off towards -x, looks along +x
    assert!(
        line.contains("--camera -2.") && line.contains("along +x"),
        "{line}"
    );
}

/// Mitsuba's BSDFs reflect on the front only: a rectangle turned away from the camera and
/// the light is black unless its BSDF is wrapped in `twosided`, for the path tracer and
/// for BDPT; seen from the front, one-sided and two-sided render the same image.
#[test]
fn bsdfs_outside_twosided_are_black_on_the_back() {
    let d = temp_dir("onesided");
    let xml = |flip: bool, twosided: bool| {
        let bsdf = if twosided {
            r#"<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>"#
        } else {
            r#"<bsdf type="diffuse"/>"#
        };
        format!(
            r#"<scene version="3.0.0">
                 <sensor type="perspective"><float name="fov" value="30"/><transform name="to_world">
                   <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
                 <shape type="rectangle"><transform name="to_world"><scale value="0.3"/>
                   <lookat origin="1.5, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
                   <emitter type="area"><rgb name="radiance" value="40"/></emitter></shape>
                 <shape type="rectangle"><boolean name="flip_normals" value="{flip}"/>{bsdf}</shape>
               </scene>"#
        )
    };
    let mut means = Vec::new();
    for kind in [
        kalos::integrator::IntegratorKind::Path,
        kalos::integrator::IntegratorKind::Bdpt,
    ] {
        for (flip, twosided) in [(true, false), (true, true), (false, false), (false, true)] {
            let f = d.join(format!("r-{flip}-{twosided}.xml"));
            std::fs::write(&f, xml(flip, twosided)).unwrap();
            let s = scene::load(f.to_str().unwrap()).unwrap();
            let mut set = settings(&s, 24, 24);
            set.integrator.kind = kind;
            // the image's mean with BDPT's light-tracing splats (`Film::value`)
            let film = render_spp(&s, &set, 16);
            let n = film.pixels.len();
            means.push((0..n).map(|i| film.value(i)[0]).sum::<f64>() / n as f64);
        }
        let [back1, back2, front1, front2] = means[means.len() - 4..] else {
            unreachable!()
        };
        assert_eq!(back1, 0.0, "{kind:?}: the back of a one-sided diffuse");
        assert!(back2 > 0.05, "{kind:?}: {back2}");
        assert!(
            front1 > 0.05 && front1 == front2,
            "{kind:?}: {front1} {front2}"
        );
        // the same surface from either side when two-sided
        assert!(
            (back2 - front2).abs() < 0.05 * front2,
            "{kind:?}: {back2} {front2}"
        );
    }
    // and the two estimators agree
    assert!((means[1] - means[5]).abs() < 0.03 * means[1], "{means:?}");
}

/// A living room as Blender 5.0's OBJ exporter writes it (`scenes/blender/`, made by its
/// script with Blender as a Python module): it loads without a refusal, its Principled
/// materials read as physically based surfaces, and the camera kalos places inside looks
/// at the furnished side of the room (not at the window's sky panel), lit.
#[test]
fn a_blender_living_room_renders_from_the_view_that_shows_it() {
    let scene = scene::load("scenes/blender/living_room.obj").unwrap();
    let w = scene.warnings_for(false).join("\n");
    assert!(w.contains("Principled BSDF export"), "{w}");
    assert!(
        scene
            .info
            .camera_from
            .contains("inside the closed room, looking along -x"),
        "{}",
        scene.info.camera_from
    );
    let set = settings(&scene, 32, 24);
    let img = render_spp(&scene, &set, 16).mean_rgb();
    let lit = img.iter().filter(|p| p[1] > 0.02).count();
    assert!(
        lit > img.len() * 9 / 10,
        "{lit} of {} pixels lit",
        img.len()
    );
}
