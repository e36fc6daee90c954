//! Known answers for area lights whose radiance is a texture (Mitsuba's area emitter with
//! a bitmap `radiance`): a square light at height 1 over a diffuse floor, its left half
//! of radiance c0 and its right half c1 (a 2 x 1 texture, nearest texels). A floor point
//! p receives E(p) = c0 I_left(p) + c1 I_right(p), I the integral of h^2 / r^4 over each
//! half (computed here by quadrature), and sends kd E / pi: every estimator must read the
//! texture where it samples or hits the light, which the texture's mean (the light's
//! power) does not give (the halves differ 8x in red and blue). The light seen directly is
//! its texel; a Mitsuba file with a 2 x 2 bitmap (tests/data/textured-area-light/) gives
//! the quadrants Mitsuba renders (bench/textured-area-light.py).

mod common;
use common::*;
use kalos::integrator::IntegratorKind;
use kalos::math::{Vec2, Vec3};
use kalos::scene::{CameraDesc, FovAxis, MaterialDesc, Scene, SceneDesc, Texture};
use kalos::texture::Sampling;
use std::sync::Arc;

const C0: [f32; 3] = [4.0, 1.0, 0.5];
const C1: [f32; 3] = [0.5, 1.0, 4.0];
const KD: f32 = 0.5;

/// The light (radiance C0 for x < 0, C1 for x > 0, facing down at z = 1 over
/// [-1, 1]^2) over a floor of reflectance KD at z = 0, seen by `camera`.
fn scene(camera: CameraDesc) -> Scene {
    let mut light = MaterialDesc::named("light");
    light.kd = [0.0; 3];
    let texture = Texture {
        width: 2,
        height: 1,
        texels: vec![C0, C1],
        sampling: Sampling {
            nearest: true,
            ..Sampling::default()
        },
    };
    light.ke = texture.mean();
    light.ke_texture = Some(Arc::new(texture));
    let mut floor = MaterialDesc::named("floor");
    floor.kd = [KD; 3];
    let mut d = SceneDesc {
        name: "textured-light".into(),
        materials: vec![light, floor],
        camera: Some(camera),
        ..Default::default()
    };
    let (x0, x1) = (-1.0, 1.0);
    let corner = |x: f32, y: f32| {
        (
            Vec3::new(x, y, 1.0),
            Vec2::new((x + 1.0) / 2.0, (y + 1.0) / 2.0),
        )
    };
    // counter-clockwise seen from below: the light faces -z
    let q = [
        corner(x0, x0),
        corner(x0, x1),
        corner(x1, x1),
        corner(x1, x0),
    ];
    for t in [[0, 1, 2], [0, 2, 3]] {
        let v = t.map(|i| q[i].0);
        let uv = t.map(|i| q[i].1);
        d.push_triangle(v, None, Some(uv), 0);
    }
    push_floor(&mut d, 1);
    Scene::build(d, 0.0).unwrap()
}

/// The integral of h^2 / r^4 (h = 1) over [x0, x1] x [-1, 1] of the light plane, seen
/// from the floor point (px, 0, 0) (midpoint rule, 1000 x 1000).
fn kernel(px: f64, x0: f64, x1: f64) -> f64 {
    let n = 1000;
    let (dx, dy) = ((x1 - x0) / n as f64, 2.0 / n as f64);
    let mut s = 0.0;
    for i in 0..n {
        let x = x0 + (i as f64 + 0.5) * dx - px;
        for j in 0..n {
            let y = -1.0 + (j as f64 + 0.5) * dy;
            let r2 = x * x + y * y + 1.0;
            s += 1.0 / (r2 * r2);
        }
    }
    s * dx * dy
}

/// The floor's radiance at (px, 0, 0).
fn floor_radiance(px: f64) -> [f64; 3] {
    let (l, r) = (kernel(px, -1.0, 0.0), kernel(px, 0.0, 1.0));
    let k = KD as f64 / std::f64::consts::PI;
    std::array::from_fn(|c| k * (C0[c] as f64 * l + C1[c] as f64 * r))
}

/// A narrow camera looking at the floor point (px, 0, 0) from 45 degrees (below the light).
fn floor_camera(px: f32) -> CameraDesc {
    CameraDesc {
        origin: [px + 0.7, 0.0, 0.7],
        target: [px, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        fov: 0.5,
        fov_axis: FovAxis::Y,
        ..Default::default()
    }
}

fn render(scene: &Scene, kind: IntegratorKind, spp: u32) -> kalos::film::Film {
    let mut set = settings(scene, 8, 8);
    set.integrator.kind = kind;
    render_spp(scene, &set, spp)
}

#[test]
fn floor_under_a_textured_light() {
    for px in [-0.5f32, 0.5] {
        let want = floor_radiance(px as f64);
        // the mean texture would give the same red and blue under both halves
        assert!((want[0] - want[2]).abs() > 0.2 * want[0], "{want:?}");
        let s = scene(floor_camera(px));
        for kind in [IntegratorKind::Path, IntegratorKind::Bdpt] {
            let film = render(&s, kind, 256);
            assert_mean(&film, want, 4.0, &format!("{kind:?} at x = {px}"));
        }
    }
}

#[test]
fn textured_light_seen_directly() {
    for (px, c) in [(-0.5f32, C0), (0.5, C1)] {
        let s = scene(CameraDesc {
            origin: [px, 0.0, 0.2],
            target: [px, 0.0, 1.0],
            up: [0.0, 1.0, 0.0],
            fov: 1.0,
            fov_axis: FovAxis::Y,
            ..Default::default()
        });
        let want = c.map(f64::from);
        // the path tracer sees the texel itself; BDPT adds light-tracing splats
        let film = render(&s, IntegratorKind::Path, 4);
        assert_mean(&film, want, 0.0, &format!("path at x = {px}"));
        let film = render(&s, IntegratorKind::Bdpt, 64);
        assert_mean(&film, want, 4.0, &format!("bdpt at x = {px}"));
    }
}

#[test]
fn mitsuba_quadrants() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/textured-area-light/scene.xml"
    );
    let s = kalos::scene::load(path).unwrap();
    assert!(
        s.warnings.iter().all(|w| !w.contains("mean")),
        "{:?}",
        s.warnings
    );
    let film = render(&s, IntegratorKind::Path, 4);
    // Mitsuba 3.9.1's image (bench/textured-area-light.py)
    for (x, y, c) in [
        (3, 3, [1.0, 0.0, 0.0]),
        (4, 3, [0.0, 1.0, 0.0]),
        (3, 4, [0.0, 0.0, 1.0]),
        (4, 4, [1.0, 1.0, 0.0]),
    ] {
        let m = film.pixels[y * 8 + x].mean();
        assert_eq!(m, c, "pixel ({x}, {y})");
    }
}
