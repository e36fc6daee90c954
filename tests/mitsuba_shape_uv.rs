//! Texture coordinates of Mitsuba's shapes as Mitsuba 3.9.1 gives them
//! (bench/mitsuba-shape-uv.py, `ray_intersect` on the same rays): the disk's polar
//! (r, phi / 2 pi), the cube's per-face axes, a PLY's texture coordinates as stored and an
//! OBJ's flipped (Mitsuba's `flip_tex_coords` defaults differ by format). A checkerboard
//! on these shapes (`various_shapes`) shows any difference along its edges.

use kalos::math::{Ray, Vec3};

type Case = ([f32; 3], [f32; 3], [f32; 2]);

/// Load a scene of one shape (`shape`: its XML) from a temporary folder holding `files`,
/// and compare the uv of each ray's hit, in Mitsuba's convention (v down the image),
/// with Mitsuba's, within `tol`.
fn check(name: &str, shape: &str, files: &[(&str, &str)], cases: &[Case], tol: f32) {
    let dir = std::env::temp_dir().join(format!("kalos-shape-uv-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (f, text) in files {
        std::fs::write(dir.join(f), text).unwrap();
    }
    let xml = format!(r#"<scene version="3.0.0"><emitter type="constant"/>{shape}</scene>"#);
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let scene = kalos::scene::load(path.to_str().unwrap());
    std::fs::remove_dir_all(&dir).ok();
    let scene = scene.unwrap();
    for (o, d, want) in cases {
        let ray = Ray::new(Vec3::from(*o), Vec3::from(*d));
        let hit = scene
            .intersect(&ray, f32::INFINITY)
            .unwrap_or_else(|| panic!("{name}: the ray from {o:?} misses"));
        let got = [hit.uv.x, 1.0 - hit.uv.y];
        assert!(
            (got[0] - want[0]).abs() <= tol && (got[1] - want[1]).abs() <= tol,
            "{name}: ray from {o:?}: uv {got:?}, Mitsuba's {want:?}"
        );
    }
}

#[test]
fn disk_uv_is_polar() {
    let down = [0.0, 0.0, -1.0];
    // the mesh's chords (128 sectors) leave the radius within 3e-4
    check(
        "disk",
        r#"<shape type="disk"/>"#,
        &[],
        &[
            ([0.5, 0.0, 1.0], down, [0.5, 0.0]),
            ([0.0, 0.5, 1.0], down, [0.5, 0.25]),
            ([-0.3, 0.0, 1.0], down, [0.3, 0.5]),
            ([0.0, -0.9, 1.0], down, [0.9, 0.75]),
            ([0.6, -0.1, 1.0], down, [0.608276, 0.973716]),
            ([-0.08, 0.06, 1.0], down, [0.1, 0.397584]),
        ],
        1e-3,
    );
}

#[test]
fn cube_uv_per_face() {
    check(
        "cube",
        r#"<shape type="cube"/>"#,
        &[],
        &[
            ([3.0, 0.3, -0.6], [-1.0, 0.0, 0.0], [0.65, 0.8]),
            ([-3.0, 0.3, -0.6], [1.0, 0.0, 0.0], [0.65, 0.2]),
            ([0.3, 3.0, -0.6], [0.0, -1.0, 0.0], [0.35, 0.8]),
            ([0.3, -3.0, -0.6], [0.0, 1.0, 0.0], [0.2, 0.65]),
            ([0.3, -0.6, 3.0], [0.0, 0.0, -1.0], [0.2, 0.65]),
            ([0.3, -0.6, -3.0], [0.0, 0.0, 1.0], [0.8, 0.65]),
        ],
        1e-5,
    );
}

const VERTS: [[f32; 5]; 4] = [
    [-2.85, 0.0, -7.6, 0.950589, 0.988416],
    [-2.85, 0.0, 0.6, 0.025105, 0.988416],
    [2.85, 0.0, 0.6, 0.025105, 0.689127],
    [2.85, 0.0, -7.6, 0.950589, 0.689127],
];

#[test]
fn ply_uv_unflipped_obj_uv_flipped() {
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty float u\nproperty float v\nelement face 2\n\
         property list uchar int vertex_indices\nend_header\n",
    );
    let mut obj = String::new();
    for v in VERTS {
        ply += &format!("{} {} {} {} {}\n", v[0], v[1], v[2], v[3], v[4]);
        obj += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for v in VERTS {
        obj += &format!("vt {} {}\n", v[3], v[4]);
    }
    ply += "3 0 1 2\n3 0 2 3\n";
    obj += "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    let down = [0.0, -1.0, 0.0];
    let at = [[1.0, 5.0, -3.0], [-2.0, 5.0, 0.0]];
    for (kind, text, uv) in [
        ("ply", &ply, [[0.431415, 0.786265], [0.092823, 0.943785]]),
        ("obj", &obj, [[0.431415, 0.213735], [0.092823, 0.056215]]),
    ] {
        let file = format!("rect.{kind}");
        let shape =
            format!(r#"<shape type="{kind}"><string name="filename" value="{file}"/></shape>"#);
        let cases: Vec<Case> = (0..2).map(|i| (at[i], down, uv[i])).collect();
        check(
            kind,
            &shape,
            &[(file.as_str(), text.as_str())],
            &cases,
            1e-5,
        );
    }
}
