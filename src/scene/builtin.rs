//! Built-in scenes (`kalos scenes` lists them).
//!
//! - `cornell`: exactly Mitsuba 3's `cornell_box()` (its OBJ/MTL export is embedded), camera
//!   at (0, 0, 3.9) looking at the origin, 39.3077 degrees, 256x256.
//! - `furnace`: a closed room whose walls have diffuse albedo a and emission 1 - a on every
//!   band, each wall a different permutation of (1.0, 0.5, 0.2): radiance is exactly 1
//!   everywhere for every correct estimator (the test scene of the roulette paper).
//! - `furnace-glossy`: the same room with combined diffuse + normalized Phong walls whose
//!   diffuse and glossy colours differ, emitting L_e(w) = 1 - a(w), a the directional
//!   albedo (tabulated at load): radiance again exactly 1 everywhere (Szirmay-Kalos,
//!   Kovacs and Abbas, "Testing global illumination algorithms with analytically
//!   computable scenes", 2001).
//! - `cornell-glossy`: `cornell` with diffuse + normalized Phong boxes and floor (the
//!   combined BRDFs of the roulette paper's lobe-selection comparison).

use super::obj::{load_obj_text, MtlSource};
use super::{CameraDesc, MaterialDesc, RenderDefaults, SceneDesc};
use glam::{Mat4, Vec3};

pub const NAMES: &[&str] = &["cornell", "cornell-glossy", "furnace", "furnace-glossy"];

/// One line per built-in scene, for `kalos scenes`.
pub fn describe() -> Vec<(&'static str, &'static str)> {
    vec![
        (
            "cornell",
            "Mitsuba 3's Cornell box (cornell_box()), 256x256: the peer-comparison scene",
        ),
        (
            "cornell-glossy",
            "cornell with glossy (diffuse + normalized Phong) boxes and floor",
        ),
        (
            "furnace",
            "closed room, albedo + emission = 1 on every band: radiance is exactly 1",
        ),
        (
            "furnace-glossy",
            "closed room, diffuse + Phong walls emitting 1 - albedo(w): radiance is exactly 1",
        ),
    ]
}

const CORNELL_OBJ: &str = include_str!("../../assets/scenes/cornell-box.obj");
const CORNELL_MTL: &str = include_str!("../../assets/scenes/cornell-box.mtl");

pub fn cornell_camera() -> CameraDesc {
    CameraDesc {
        origin: [0.0, 0.0, 3.9],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fov: 39.3077,
    }
}

fn cornell() -> Result<SceneDesc, String> {
    cornell_from("cornell", CORNELL_OBJ, CORNELL_MTL)
}

/// `cornell`'s materials and the glossy ones of `cornell-glossy` (Kd + Ks <= 1 per channel).
const CORNELL_GLOSSY_MTL: &str = concat!(
    include_str!("../../assets/scenes/cornell-box.mtl"),
    "
newmtl glossy-floor
Kd 0.3 0.24 0.22
Ks 0.6 0.6 0.6
Ns 15
illum 2

newmtl glossy-box
Kd 0.45 0.35 0.33
Ks 0.45 0.45 0.45
Ns 60
illum 2
"
);

fn cornell_glossy() -> Result<SceneDesc, String> {
    // The same geometry, with the floor and both boxes switched to the glossy materials.
    let mut obj = String::with_capacity(CORNELL_OBJ.len() + 64);
    let mut object = "";
    for line in CORNELL_OBJ.lines() {
        if let Some(o) = line.strip_prefix("o ") {
            object = o.trim();
        }
        match (line.trim(), object) {
            ("usemtl white", "floor") => obj.push_str("usemtl glossy-floor"),
            ("usemtl white", "small-box" | "large-box") => obj.push_str("usemtl glossy-box"),
            _ => obj.push_str(line),
        }
        obj.push('\n');
    }
    cornell_from("cornell-glossy", &obj, CORNELL_GLOSSY_MTL)
}

fn cornell_from(name: &str, obj: &str, mtl_text: &'static str) -> Result<SceneDesc, String> {
    let mut d = SceneDesc {
        name: name.into(),
        ..Default::default()
    };
    let mtl = |name: &str| (name == "cornell-box.mtl").then_some(mtl_text);
    load_obj_text(
        obj,
        "cornell-box.obj",
        MtlSource::Embedded(&mtl),
        Mat4::IDENTITY,
        &mut d,
    )?;
    d.camera = Some(cornell_camera());
    d.defaults = RenderDefaults {
        res: Some((256, 256)),
        spp: None,
        max_depth: None,
    };
    Ok(d)
}

/// Add a quad (v0, v1, v2, v3) counter-clockwise as seen from the side it faces.
pub fn push_quad(d: &mut SceneDesc, v: [Vec3; 4], mat: u32) {
    d.push_triangle([v[0], v[1], v[2]], None, None, mat);
    d.push_triangle([v[0], v[2], v[3]], None, None, mat);
}

/// The six walls of the box [-1,1]^3, facing inwards, in the order
/// -x, +x, -y, +y, -z, +z, each split into `k` x `k` quads.
pub fn inward_box(d: &mut SceneDesc, mats: [u32; 6], k: u32) {
    // For each wall: inward normal n, and axes (a, b) with a x b = n.
    let walls = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    for (w, (n, a, b)) in walls.iter().enumerate() {
        debug_assert!((a.cross(*b) - *n).length() < 1e-6);
        let c = -*n; // the wall lies at -n (inward normal n)
        let step = 2.0 / k as f32;
        for i in 0..k {
            for j in 0..k {
                let s0 = -1.0 + i as f32 * step;
                let t0 = -1.0 + j as f32 * step;
                let p = |s: f32, t: f32| c + *a * s + *b * t;
                push_quad(
                    d,
                    [
                        p(s0, t0),
                        p(s0 + step, t0),
                        p(s0 + step, t0 + step),
                        p(s0, t0 + step),
                    ],
                    mats[w],
                );
            }
        }
    }
}

/// The albedo permutations of the furnace walls (the roulette paper's saturated colours).
const PERMS: [[f32; 3]; 6] = [
    [1.0, 0.5, 0.2],
    [1.0, 0.2, 0.5],
    [0.5, 1.0, 0.2],
    [0.5, 0.2, 1.0],
    [0.2, 1.0, 0.5],
    [0.2, 0.5, 1.0],
];

fn furnace() -> SceneDesc {
    let mut d = furnace_room("furnace");
    for (i, a) in PERMS.iter().enumerate() {
        let mut m = MaterialDesc::named(&format!("wall{i}"));
        m.kd = *a;
        m.ke = [1.0 - a[0], 1.0 - a[1], 1.0 - a[2]];
        d.materials.push(m);
    }
    d
}

/// Wall i: diffuse 0.6 x permutation i, glossy 0.4 x permutation i + 1 (so the lobes have
/// different colours and Kd + Ks <= 1), a different Phong exponent per wall, emission
/// 1 - a(w).
fn furnace_glossy() -> SceneDesc {
    let mut d = furnace_room("furnace-glossy");
    let exponents = [3.0, 10.0, 30.0, 5.0, 60.0, 15.0];
    for (i, a) in PERMS.iter().enumerate() {
        let b = PERMS[(i + 1) % 6];
        let mut m = MaterialDesc::named(&format!("wall{i}"));
        m.kd = a.map(|v| 0.6 * v);
        m.ks = b.map(|v| 0.4 * v);
        m.ns = exponents[i];
        m.emit_one_minus_albedo = true;
        d.materials.push(m);
    }
    d
}

/// The furnace room: walls 0..6 use materials 0..6 (the caller adds them).
fn furnace_room(name: &str) -> SceneDesc {
    let mut d = SceneDesc {
        name: name.into(),
        ..Default::default()
    };
    inward_box(&mut d, [0, 1, 2, 3, 4, 5], 1);
    d.camera = Some(CameraDesc {
        origin: [0.3, -0.2, 0.8],
        target: [-0.5, 0.3, -1.0],
        up: [0.0, 1.0, 0.0],
        fov: 70.0,
    });
    d.defaults = RenderDefaults {
        res: Some((64, 64)),
        spp: None,
        max_depth: None,
    };
    d
}

/// The description of a built-in scene, or None if `name` is not one.
pub fn load(name: &str) -> Result<Option<SceneDesc>, String> {
    Ok(match name {
        "cornell" => Some(cornell()?),
        "cornell-glossy" => Some(cornell_glossy()?),
        "furnace" => Some(furnace()),
        "furnace-glossy" => Some(furnace_glossy()),
        _ => None,
    })
}
