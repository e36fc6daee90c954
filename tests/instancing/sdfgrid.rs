//! Mitsuba's `sdfgrid` read by kalos: a grid volume of a sphere's distances traced where the
//! sphere is (within the grid's interpolation error), placed alone or through an instance,
//! with its normals and material; bad grid volumes are one line naming the file.

use kalos::math::{Ray, Vec3};
use kalos::scene::{mitsuba, Scene};
use std::path::{Path, PathBuf};

/// A single-channel grid volume of `n`^3 samples of the distance to a sphere of radius
/// `r` about the centre of the unit cube.
fn sphere_vol(n: u32, r: f32) -> Vec<u8> {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, n, n, n, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let s = 1.0 / (n - 1) as f32;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, y as f32, z as f32) * s;
                let d = (p - Vec3::splat(0.5)).length() - r;
                b.extend_from_slice(&d.to_le_bytes());
            }
        }
    }
    b
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-sdfgrid-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scene(d: &Path, body: &str) -> Result<Scene, String> {
    let text = format!(r#"<scene version="3.0.0"><emitter type="constant"/>{body}</scene>"#);
    Scene::build(mitsuba::parse(&text, "t.xml", d)?, 0.0)
}

const SHAPE: &str = r#"<shape type="sdfgrid"><string name="filename" value="s.vol"/>
    <transform name="to_world"><scale value="4"/><translate x="-2" y="-2" z="-2"/></transform>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.7 0.1 0.1"/></bsdf></shape>"#;

/// A sphere of radius 0.3 x 4 = 1.2 about the origin, on a 33^3 grid scaled by 4 (h = 0.125).
#[test]
fn a_sphere_grid_is_hit_where_the_sphere_is() {
    let d = dir("sphere");
    std::fs::write(d.join("s.vol"), sphere_vol(33, 0.3)).unwrap();
    let alone = scene(&d, SHAPE).unwrap();
    let grouped = scene(
        &d,
        &format!(
            r#"<shape type="shapegroup" id="g">{SHAPE}</shape>
               <shape type="instance"><ref id="g"/><transform name="to_world"><translate x="10"/></transform></shape>"#
        ),
    )
    .unwrap();
    let h = 0.125f32;
    // the trilinear interpolant's error bound (see accel/sdf_tests.rs), in world units
    let bound = h * h / 8.0 * 3.0 / (1.2 - 3.0f32.sqrt() * h);
    for k in 0..64 {
        let a = k as f32 * 0.7;
        let target = Vec3::new(0.5 * a.cos(), 0.5 * a.sin(), 0.3 * (0.3 * a).sin());
        let o = Vec3::new(8.0 * (0.4 * a).cos(), 8.0 * (0.4 * a).sin(), 3.0 - 0.1 * a);
        for (s, shift) in [(&alone, 0.0), (&grouped, 10.0)] {
            let off = Vec3::new(shift, 0.0, 0.0);
            let ray = Ray::new(o + off, target - o);
            let hit = s
                .intersect(&ray, f32::INFINITY)
                .expect("aimed at the sphere");
            let p = hit.p - off;
            assert!(
                (p.length() - 1.2).abs() < bound,
                "{p}: {} from the centre",
                p.length()
            );
            assert!((ray.at(hit.t) - hit.p).length() < 1e-4);
            // the normals point out of the sphere within the angle of a voxel
            let n = p.normalize();
            assert!(hit.ng.dot(n) > (h / 1.2).cos(), "{} {n}", hit.ng);
            assert!(hit.ns.dot(n) > (h / 1.2).cos(), "{} {n}", hit.ns);
            assert_eq!(s.material_of(hit.prim).name, "red");
            // Mitsuba's grid has no texture coordinates: (0, 0), kalos' (0, 1)
            assert_eq!((hit.uv.x, hit.uv.y), (0.0, 1.0));
            assert!(s.occluded(&ray, hit.t * 1.001));
            assert!(!s.occluded(&ray, hit.t * 0.999));
        }
    }
    // rays past the sphere miss it
    for s in [&alone, &grouped] {
        let ray = Ray::new(Vec3::new(-8.0, 1.3, 0.0), Vec3::X);
        assert!(s.intersect(&ray, f32::INFINITY).is_none());
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_grid_volumes_are_one_line_naming_the_file() {
    let d = dir("bad");
    let good = sphere_vol(5, 0.3);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("short", good[..good.len() - 4].to_vec(), "needs 548"),
        ("header", good[..20].to_vec(), "header"),
        (
            "lying",
            {
                let mut b = good.clone();
                b[8..12].copy_from_slice(&100_000u32.to_le_bytes());
                b
            },
            "100000 x 5 x 5 samples",
        ),
        (
            "channels",
            {
                let mut b = sphere_vol(5, 0.3);
                b[20] = 2;
                b
            },
            "",
        ),
        ("empty", sphere_vol(5, 0.9), "never change sign"),
        (
            "text",
            b"VOX3 not a volume".to_vec(),
            "does not start with 'VOL'",
        ),
    ];
    for (name, bytes, what) in cases {
        let f = format!("{name}.vol");
        std::fs::write(d.join(&f), bytes).unwrap();
        let body = SHAPE.replace("s.vol", &f);
        let e = scene(&d, &body).err().unwrap();
        assert!(e.contains(&f) && e.contains(what), "{name}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    let e = scene(&d, &SHAPE.replace("s.vol", "missing.vol"))
        .err()
        .unwrap();
    assert!(e.contains("missing.vol"), "{e}");
    let e = scene(
        &d,
        &SHAPE.replace(
            "<transform",
            r#"<string name="normals" value="flat"/><transform"#,
        ),
    )
    .err()
    .unwrap();
    assert!(e.contains("normals 'flat'"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
