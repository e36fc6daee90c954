//! Built-in scenes (`kalos scenes` lists them).
//!
//! - `cornell`: exactly Mitsuba 3's `cornell_box()` (its OBJ/MTL export is embedded), camera
//!   at (0, 0, 3.9) looking at the origin, 39.3077 degrees, 256x256.
//! - `furnace`: a closed room whose walls have diffuse albedo a and emission 1 - a on every
//!   band, each wall a different permutation of (1.0, 0.5, 0.2): radiance is exactly 1
//!   everywhere for every correct estimator (the test scene of the roulette paper).

use super::obj::{load_obj_text, MtlSource};
use super::{CameraDesc, MaterialDesc, RenderDefaults, SceneDesc};
use glam::{Mat4, Vec3};

pub const NAMES: &[&str] = &["cornell", "furnace"];

/// One line per built-in scene, for `kalos scenes`.
pub fn describe() -> Vec<(&'static str, &'static str)> {
    vec![
        (
            "cornell",
            "Mitsuba 3's Cornell box (cornell_box()), 256x256: the peer-comparison scene",
        ),
        (
            "furnace",
            "closed room, albedo + emission = 1 on every band: radiance is exactly 1",
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
    let mut d = SceneDesc {
        name: "cornell".into(),
        ..Default::default()
    };
    let mtl = |name: &str| (name == "cornell-box.mtl").then_some(CORNELL_MTL);
    load_obj_text(
        CORNELL_OBJ,
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

fn furnace() -> SceneDesc {
    let mut d = SceneDesc {
        name: "furnace".into(),
        ..Default::default()
    };
    let perms = [
        [1.0, 0.5, 0.2],
        [1.0, 0.2, 0.5],
        [0.5, 1.0, 0.2],
        [0.5, 0.2, 1.0],
        [0.2, 1.0, 0.5],
        [0.2, 0.5, 1.0],
    ];
    let mut mats = [0u32; 6];
    for (i, a) in perms.iter().enumerate() {
        let mut m = MaterialDesc::named(&format!("wall{i}"));
        m.kd = *a;
        m.ke = [1.0 - a[0], 1.0 - a[1], 1.0 - a[2]];
        d.materials.push(m);
        mats[i] = i as u32;
    }
    inward_box(&mut d, mats, 1);
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
        "furnace" => Some(furnace()),
        _ => None,
    })
}
