//! Tests of the bidirectional path tracer: the MIS weights of all strategies of a path sum
//! to 1 (and equal the explicit balance / power heuristic), the furnace rooms give 1, light
//! tracing alone and BDPT agree with the path tracer (z-tests on means with standard
//! errors estimated from independent passes over the image).

use super::*;

use crate::sampling::{SamplerConfig, SamplerKind};
use crate::scene::{self, Scene};
use passes::{render, render_bdpt, render_path, settings, Img};

/// Paths built from a camera and a light subpath; for each, the weights of all its
/// strategies computed by `mis_weight` from subpaths re-cut at every split.
#[test]
fn mis_weights_of_a_path_sum_to_one() {
    let scene = scene::load("cornell").unwrap();
    let cam = Camera::new(scene.camera, 32, 32);
    let set = settings(RrMode::Off, 6);
    let rr = roulette(&set);
    let cfg = SamplerConfig::default();
    let mut checked = [0usize; 8];
    for k in 0..3000u32 {
        let mut rs = SampleStream::new(&cfg, 7, k, k as u64);
        let mut c = Counters::default();
        rs.set_dimension(0);
        let u = rs.next_2d();
        let raster = Vec2::new(u.x * 32.0, u.y * 32.0);
        let mut camp: Vec<Vertex<3>> = Vec::new();
        let mut light: Vec<Vertex<3>> = Vec::new();
        camera_subpath(&scene, &cam, raster, 5, &mut rs, &rr, &mut c, &mut camp);
        light_subpath(&scene, 4, &mut rs, &rr, &mut c, &mut light);
        if camp.len() < 2 {
            continue;
        }
        // The full path x_0 (camera) .. x_{n-1} (emitter): camera vertices, then the
        // light subpath reversed; or a camera subpath that ended on the emitter.
        let t0 = 2 + (k as usize % (camp.len() - 1));
        let mut x: Vec<Vertex<3>> = camp[..t0].to_vec();
        if k % 3 == 0 {
            if x[t0 - 1].light == NO_LIGHT
                || connect(&scene, &cam, &light, &camp, 0, t0, &mut rs, &mut c).is_none()
            {
                continue;
            }
        } else {
            if light.len() < 2 {
                continue;
            }
            let s0 = 2 + (k as usize / 3 % (light.len() - 1));
            if connect(&scene, &cam, &light, &camp, s0, t0, &mut rs, &mut c).is_none() {
                continue;
            }
            x.extend(light[..s0].iter().rev().cloned());
        }
        let n = x.len();
        if n == 2 {
            continue; // (0, 2) alone: weight 1
        }
        // Both roles of every point: camera side (A) and light side (B).
        let as_surface = |v: &Vertex<3>| -> Vertex<3> {
            let mut v = v.clone();
            if v.kind == Kind::Light {
                let tri = scene.lights.get(v.light).tri;
                v.kind = Kind::Surface;
                v.bsdf = scene.material_of(tri).bsdf.clone();
            }
            v
        };
        let a: Vec<Vertex<3>> = (0..n)
            .map(|i| {
                if i == 0 {
                    x[0].clone()
                } else {
                    as_surface(&x[i])
                }
            })
            .collect();
        let b: Vec<Vertex<3>> = (0..n)
            .map(|i| {
                if i == n - 1 {
                    let mut v = x[n - 1].clone();
                    v.kind = Kind::Light;
                    v.pdf_fwd = scene.lights.pdf_position(v.light);
                    v
                } else {
                    a[i].clone()
                }
            })
            .collect();
        // Area densities of each point generated from the camera side and the light side.
        let mut pc = vec![1.0f32; n];
        let mut pl = vec![0.0f32; n];
        for i in 1..n {
            pc[i] = a[i - 1].pdf(&cam, (i >= 2).then(|| &a[i - 2]), &a[i]);
        }
        pl[n - 1] = scene.lights.pdf_position(x[n - 1].light);
        for i in (0..n - 1).rev() {
            pl[i] = b[i + 1].pdf(&cam, (i + 2 < n).then(|| &b[i + 2]), &b[i]);
        }
        // K: light-tracing paths per camera sample (multi-sample MIS, n_i p_i)
        let lt_k = [1.0f32, 0.3, 4.0][k as usize % 3];
        for heuristic in [MisHeuristic::Balance, MisHeuristic::Power] {
            let e = if heuristic == MisHeuristic::Power {
                2
            } else {
                1
            };
            let explicit = |tt: usize| -> f64 {
                let mut p = if tt == 1 { lt_k as f64 } else { 1.0f64 };
                for &q in &pc[1..tt] {
                    p *= q as f64;
                }
                for &q in &pl[tt..n] {
                    p *= q as f64;
                }
                p.powi(e)
            };
            let total: f64 = (1..=n).map(explicit).sum();
            let mut sum = 0.0f64;
            for tt in 1..=n {
                let ss = n - tt;
                let cp: Vec<Vertex<3>> = (0..tt)
                    .map(|i| {
                        let mut v = a[i].clone();
                        v.pdf_fwd = pc[i];
                        v.pdf_rev = pl[i];
                        v
                    })
                    .collect();
                let lp: Vec<Vertex<3>> = (0..ss)
                    .map(|j| {
                        let i = n - 1 - j;
                        let mut v = b[i].clone();
                        v.pdf_fwd = pl[i];
                        v.pdf_rev = pc[i];
                        v
                    })
                    .collect();
                let sampled = if ss == 1 {
                    Some(lp[0].clone())
                } else if tt == 1 {
                    Some(cp[0].clone())
                } else {
                    None
                };
                let w = mis_weight(
                    &scene,
                    &cam,
                    &lp,
                    &cp,
                    sampled.as_ref(),
                    ss,
                    tt,
                    heuristic,
                    lt_k,
                );
                let want = explicit(tt) / total;
                assert!(
                    (w as f64 - want).abs() < 1e-4,
                    "path {k} ({n} vertices), strategy ({ss}, {tt}), {heuristic:?}, K {lt_k}: recurrence {w}, explicit {want}"
                );
                sum += w as f64;
            }
            assert!(
                (sum - 1.0).abs() < 1e-5,
                "path {k} {heuristic:?} K {lt_k}: sum {sum}"
            );
        }
        checked[n.min(7)] += 1;
    }
    // paths of 3 .. 7+ vertices were all exercised
    assert!(checked[3] > 0, "{checked:?}");
    for (n, &k) in checked.iter().enumerate().skip(4) {
        assert!(k >= 20, "only {k} paths of {n} vertices: {checked:?}");
    }
}

fn assert_furnace(img: &Img, what: &str) {
    for c in 0..3 {
        let (m, se) = (img.img_mean[c], img.img_se[c]);
        assert!(se > 0.0, "{what}: zero variance");
        assert!(
            (m - 1.0).abs() <= 3.0 * se,
            "{what}: channel {c} mean {m} se {se} ({:.2} se off)",
            (m - 1.0).abs() / se
        );
    }
}

#[test]
fn furnace_is_one() {
    for name in ["furnace", "furnace-glossy"] {
        let scene = scene::load(name).unwrap();
        for (k, mode) in [RrMode::Classic, RrMode::Spectral].into_iter().enumerate() {
            let set = settings(mode, -1);
            let o = BdptOptions::default();
            let seed = 10 + k as u64;
            let img = render_bdpt::<3>(&scene, 8, 8, 48, seed, &set, o.clone());
            assert_furnace(&img, &format!("{name} rgb {mode:?}"));
            let img = render_bdpt::<8>(&scene, 8, 8, 48, seed, &set, o.clone());
            assert_furnace(&img, &format!("{name} 8 bands {mode:?}"));
            let img = render_bdpt::<16>(&scene, 8, 8, 48, seed, &set, o);
            assert_furnace(&img, &format!("{name} 16 bands {mode:?}"));
        }
        // the power heuristic too
        let o = BdptOptions {
            heuristic: MisHeuristic::Power,
            ..Default::default()
        };
        let img = render_bdpt::<3>(&scene, 8, 8, 48, 20, &settings(RrMode::Classic, -1), o);
        assert_furnace(&img, &format!("{name} power heuristic"));
        // a lobe selection of the roulette paper (the MIS densities stay the mixture's)
        let mut set = settings(RrMode::Spectral, -1);
        set.roulette.select = crate::integrator::BsdfSelect::Mis;
        let img = render_bdpt::<8>(&scene, 8, 8, 48, 21, &set, BdptOptions::default());
        assert_furnace(&img, &format!("{name} 8 bands, spectral, bsdf-select mis"));
    }
}

/// z-test of two images' means over a set of pixels, per channel.
fn region_z(a: &Img, b: &Img, x0: u32, y0: u32, x1: u32, y1: u32) -> [f64; 3] {
    let mut z = [0.0; 3];
    for (c, zc) in z.iter_mut().enumerate() {
        let (mut da, mut va) = (0.0, 0.0);
        for y in y0..y1 {
            for x in x0..x1 {
                let i = (y * a.w + x) as usize;
                da += a.mean[i][c] - b.mean[i][c];
                va += a.var[i][c] + b.var[i][c];
            }
        }
        *zc = if va > 0.0 { da / va.sqrt() } else { 0.0 };
    }
    z
}

#[test]
fn light_tracing_agrees_with_the_path_tracer() {
    // Light tracing alone (t = 1, plus emitters seen directly) converges to the path
    // tracer's image: the camera importance is normalised right and the raster mapping
    // is the inverse of the camera rays (quadrants: a mirrored image would fail).
    let scene = scene::load("cornell").unwrap();
    let set = settings(RrMode::Classic, -1);
    let lt = BdptOptions {
        strategies: Strategies::LightTracing,
        ..Default::default()
    };
    let (w, h) = (8, 8);
    let a = render_bdpt::<3>(&scene, w, h, 512, 1, &set, lt);
    let b = render_path::<3>(&scene, w, h, 256, 2, &set);
    assert_means_agree("light tracing vs path", &a, &b, 3.0);
    for (x0, y0) in [(0, 0), (w / 2, 0), (0, h / 2), (w / 2, h / 2)] {
        let z = region_z(&a, &b, x0, y0, x0 + w / 2, y0 + h / 2);
        assert!(
            z.iter().all(|z| z.abs() < 4.0),
            "quadrant ({x0}, {y0}): z {z:?}"
        );
    }
}

/// BDPT at `spp` against the path tracer at 16 x `spp` (a reference with its own seed: the
/// path tracer's skewed pixel distributions at equal spp make its low tail too rare for a
/// fair per-pixel test): per-pixel z-tests with a multiple-comparison bound, and the
/// image mean within 3 standard errors.
fn agree_per_pixel(name: &str, w: u32, h: u32, spp: u32) {
    agree_per_pixel_on(&scene::load(name).unwrap(), w, h, spp);
}

fn agree_per_pixel_on(scene: &Scene, w: u32, h: u32, spp: u32) {
    let name = &scene.info.name;
    let set = settings(RrMode::Classic, -1);
    let a = render_bdpt::<3>(scene, w, h, spp, 3, &set, BdptOptions::default());
    let b = render_path::<3>(scene, w, h, 16 * spp, 4, &set);
    assert_agree(name, &a, &b);
}

#[test]
fn bdpt_agrees_with_the_path_tracer_per_pixel() {
    agree_per_pixel("cornell", 16, 16, 128);
    agree_per_pixel("cornell-glossy", 8, 8, 128);
}

#[test]
fn caustic_agrees_with_the_path_tracer() {
    // Glass with smooth shading normals, Dirac vertices on both subpaths: image means of
    // BDPT and of the path tracer at 16x the samples (about 8x the time).
    let scene = scene::load("caustic").unwrap();
    let set = settings(RrMode::Classic, -1);
    let a = render_bdpt::<3>(&scene, 8, 8, 256, 3, &set, BdptOptions::default());
    let b = render_path::<3>(&scene, 8, 8, 16 * 256, 4, &set);
    for c in 0..3 {
        let z =
            (a.img_mean[c] - b.img_mean[c]) / (a.img_se[c].powi(2) + b.img_se[c].powi(2)).sqrt();
        assert!(
            z.abs() < 3.0,
            "channel {c}: bdpt {} +- {}, path {} +- {}",
            a.img_mean[c],
            a.img_se[c],
            b.img_mean[c],
            b.img_se[c]
        );
        // and BDPT's error is well below the path tracer's at 1/16 of the samples
        assert!(
            a.img_se[c] < 0.6 * b.img_se[c],
            "{:?} vs {:?}",
            a.img_se,
            b.img_se
        );
    }
}

#[test]
fn unweighted_strategies_converge_to_the_same_image() {
    // For a fixed path length every strategy alone (unweighted) estimates the same light:
    // on cornell, paths of 3 vertices (direct light) and of 4 (one bounce), the image mean
    // of each strategy (s, t) with s + t = k agrees with the others' (z-tests).
    let scene = scene::load("cornell").unwrap();
    let (w, h, spp) = (8u32, 8u32, 384u32);
    let cam = Camera::new(scene.camera, w, h);
    let set = settings(RrMode::Off, 3);
    let cfg = SamplerConfig {
        kind: SamplerKind::Random,
        seed: 17,
        dependent: false,
    };
    let npix = (w * h) as f64;
    // per (s, t): sum and sum of squares of the passes' image means
    let mut acc: std::collections::HashMap<(u32, u32), (f64, f64)> = Default::default();
    for j in 0..spp {
        let mut pass: std::collections::HashMap<(u32, u32), f64> = Default::default();
        for y in 0..h {
            for x in 0..w {
                let mut s = SampleStream::new(&cfg, 0, y * w + x, j as u64);
                let mut c = Counters::default();
                sample_pixel_with::<3>(
                    &scene,
                    &cam,
                    x,
                    y,
                    &mut s,
                    &set,
                    &BdptOptions::default(),
                    &mut c,
                    &mut |_, _| {},
                    Some(&mut |st: StrategySample| {
                        let v = st.unweighted.iter().sum::<f32>() as f64 / 3.0;
                        *pass.entry((st.s, st.t)).or_default() += v / npix;
                    }),
                );
            }
        }
        for k in 3..=4u32 {
            for t in 1..=k {
                let e = acc.entry((k - t, t)).or_default();
                let v = pass.get(&(k - t, t)).copied().unwrap_or(0.0);
                e.0 += v;
                e.1 += v * v;
            }
        }
    }
    let n = spp as f64;
    let stat = |st: (u32, u32)| {
        let (s1, s2) = acc[&st];
        let m = s1 / n;
        (m, ((s2 / n - m * m) / (n - 1.0)).max(0.0).sqrt())
    };
    for k in 3..=4u32 {
        let strategies: Vec<(u32, u32)> = (1..=k)
            .map(|t| (k - t, t))
            .filter(|&(s, t)| !(s == 1 && t == 1))
            .collect();
        for &a in &strategies {
            eprintln!("length {k} {a:?}: {:?}", stat(a));
        }
        for (i, &a) in strategies.iter().enumerate() {
            for &b in &strategies[i + 1..] {
                let ((ma, sa), (mb, sb)) = (stat(a), stat(b));
                assert!(ma > 0.0 && mb > 0.0, "{a:?} {ma} {b:?} {mb}");
                let z = (ma - mb) / (sa * sa + sb * sb).sqrt();
                assert!(
                    z.abs() < 3.5,
                    "length {k}: {a:?} {ma} +- {sa} vs {b:?} {mb} +- {sb} (z {z:.2})"
                );
            }
        }
    }
}

/// A white room with a coarse (48-triangle) diffuse sphere whose interpolated normals
/// differ from the facets' by up to 30 degrees: the adjoint BSDF's shading-normal
/// correction matters on every light-subpath vertex on it.
fn smooth_sphere_room() -> Scene {
    use crate::scene::builtin::{inward_box, push_quad, push_sphere};
    use crate::scene::{CameraDesc, FovAxis, MaterialDesc, SceneDesc};
    let mut d = SceneDesc {
        name: "smooth-sphere".into(),
        ..Default::default()
    };
    let mut white = MaterialDesc::named("white");
    white.kd = [0.6; 3];
    let mut light = MaterialDesc::named("light");
    light.kd = [0.0; 3];
    light.ke = [4.0; 3];
    let mut ball = MaterialDesc::named("ball");
    ball.kd = [0.8, 0.7, 0.5];
    d.materials = vec![white, light, ball];
    inward_box(&mut d, [0; 6], 1);
    let (a, y) = (0.3, 0.99);
    push_quad(
        &mut d,
        [
            Vec3::new(-a, y, -a),
            Vec3::new(a, y, -a),
            Vec3::new(a, y, a),
            Vec3::new(-a, y, a),
        ],
        1,
    );
    push_sphere(&mut d, Vec3::new(0.1, -0.45, -0.3), 0.5, 5, 8, 2);
    d.camera = Some(CameraDesc {
        origin: [0.0, 0.1, 0.95],
        target: [0.1, -0.45, -0.3],
        up: [0.0, 1.0, 0.0],
        fov: 35.0,
        fov_axis: FovAxis::Y,
        ..Default::default()
    });
    Scene::build(d, 0.0).unwrap()
}

#[test]
fn shading_normals_adjoint() {
    // Light tracing alone (every contribution through the adjoint BSDF) and BDPT agree
    // with the path tracer on a sphere with strongly interpolated normals.
    let scene = smooth_sphere_room();
    let set = settings(RrMode::Classic, -1);
    let lt = BdptOptions {
        strategies: Strategies::LightTracing,
        ..Default::default()
    };
    let (w, h) = (8, 8);
    let a = render_bdpt::<3>(&scene, w, h, 2048, 1, &set, lt);
    let b = render_path::<3>(&scene, w, h, 8192, 2, &set);
    assert_means_agree("light tracing vs path", &a, &b, 3.0);
    let mut zs = Vec::new();
    for (x0, y0) in [(0, 0), (w / 2, 0), (0, h / 2), (w / 2, h / 2)] {
        let z = region_z(&a, &b, x0, y0, x0 + w / 2, y0 + h / 2);
        zs.push(z);
        assert!(
            z.iter().all(|z| z.abs() < 4.0),
            "quadrant ({x0}, {y0}): z {z:?}"
        );
    }
    eprintln!("light tracing vs path, quadrant z: {zs:?}");
    agree_per_pixel_on(&scene, 8, 8, 256);
}

#[test]
fn max_depth_limits_the_whole_path() {
    // max_depth 2 = direct light only: BDPT and the path tracer agree on it, and
    // max_depth 1 shows only the emitter.
    let scene = scene::load("cornell").unwrap();
    let set = settings(RrMode::Classic, 2);
    let a = render_bdpt::<3>(&scene, 8, 8, 128, 5, &set, BdptOptions::default());
    let b = render_path::<3>(&scene, 8, 8, 128, 6, &set);
    assert_means_agree("depth 2", &a, &b, 3.0);
    let set = settings(RrMode::Classic, 1);
    let a = render_bdpt::<3>(&scene, 8, 8, 16, 5, &set, BdptOptions::default());
    let b = render_path::<3>(&scene, 8, 8, 16, 5, &set);
    for i in 0..64 {
        for c in 0..3 {
            assert!(
                (a.mean[i][c] - b.mean[i][c]).abs() < 1e-4,
                "depth 1 pixel {i}"
            );
        }
    }
}

#[test]
fn strategies_add_up_to_the_sample() {
    // The debug layers' weighted contributions add up to the returned value and splats.
    let scene = scene::load("cornell").unwrap();
    let cam = Camera::new(scene.camera, 8, 8);
    let set = settings(RrMode::Classic, -1);
    let cfg = SamplerConfig::default();
    let mut seen = std::collections::HashSet::new();
    for k in 0..200u32 {
        let mut s = SampleStream::new(&cfg, 0, k % 64, k as u64);
        let mut c = Counters::default();
        let mut splat_sum = [0.0f32; 3];
        let mut strat_sum = [0.0f32; 3];
        let v = sample_pixel_with::<3>(
            &scene,
            &cam,
            k % 8,
            (k / 8) % 8,
            &mut s,
            &set,
            &BdptOptions::default(),
            &mut c,
            &mut |_, rgb| (0..3).for_each(|i| splat_sum[i] += rgb[i]),
            Some(&mut |st: StrategySample| {
                seen.insert((st.s, st.t));
                (0..3).for_each(|i| strat_sum[i] += st.weighted[i]);
            }),
        );
        for i in 0..3 {
            let want = v[i] + splat_sum[i];
            assert!((strat_sum[i] - want).abs() <= 1e-4 * want.abs().max(1.0));
        }
    }
    for st in [(0, 2), (1, 2), (2, 1), (1, 3), (2, 2), (3, 1)] {
        assert!(seen.contains(&st), "strategy {st:?} never contributed");
    }
}

#[test]
fn caustic_light_leaves_only_through_the_sphere() {
    // Emission rays of the `caustic` light first hit the glass sphere or the black lamp
    // housing, never the room directly (bar a leak below 1%).
    let scene = scene::load("caustic").unwrap();
    assert!(scene.info.triangles < 5000, "{}", scene.info.triangles);
    assert_eq!(scene.info.skipped_degenerate, 0);
    let mut rng = crate::sampling::SeqRng::new(3);
    let (mut glass, mut room) = (0, 0);
    for _ in 0..20_000 {
        let ls = scene
            .lights
            .sample_position(rng.next_f32(), rng.next_2d())
            .unwrap();
        let (d, _) = scene.lights.sample_direction(ls.light, rng.next_2d());
        let ray = Ray::new(offset_origin(ls.p, ls.n, d), d);
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            continue;
        };
        match scene.material_of(hit.prim).name.as_str() {
            "glass" => glass += 1,
            "housing" => {}
            _ => room += 1,
        }
    }
    eprintln!("glass {glass} room {room}");
    assert!(glass > 1000, "glass {glass} room {room}");
    assert!(
        (room as f64) < 0.01 * glass as f64,
        "glass {glass} room {room}"
    );
}

/// The white room with a rough glass sphere (GGX alpha 0.3, eta 1.5) and a rough plastic
/// floor patch under it: light reaches the camera through rough refractions, where the
/// light subpaths carry importance (the radiance scaling undone by `Bsdf::adjoint_scale`).
fn rough_glass_room() -> Scene {
    use crate::scene::builtin::{inward_box, push_quad, push_sphere};
    use crate::scene::{CameraDesc, FovAxis, MaterialDesc, SceneDesc, SurfaceModel};
    let mut d = SceneDesc {
        name: "rough-glass".into(),
        ..Default::default()
    };
    let mut white = MaterialDesc::named("white");
    white.kd = [0.6; 3];
    let mut light = MaterialDesc::named("light");
    light.kd = [0.0; 3];
    light.ke = [4.0; 3];
    let mut ball = MaterialDesc::named("ball");
    ball.model = Some(SurfaceModel::Dielectric {
        eta: 1.5,
        alpha: 0.3,
        distribution: crate::material::Distribution::Ggx,
        tint: crate::material::dielectric::Tint::NONE,
    });
    let mut floor = MaterialDesc::named("floor");
    floor.kd = [0.7, 0.4, 0.2];
    floor.model = Some(SurfaceModel::Plastic {
        eta: 1.5,
        specular: [1.0; 3],
        alpha: 0.2,
        distribution: crate::material::Distribution::Ggx,
        nonlinear: false,
    });
    d.materials = vec![white, light, ball, floor];
    inward_box(&mut d, [0; 6], 1);
    let (a, y) = (0.3, 0.99);
    push_quad(
        &mut d,
        [
            Vec3::new(-a, y, -a),
            Vec3::new(a, y, -a),
            Vec3::new(a, y, a),
            Vec3::new(-a, y, a),
        ],
        1,
    );
    let f = -0.995;
    push_quad(
        &mut d,
        [
            Vec3::new(-0.6, f, 0.3),
            Vec3::new(0.6, f, 0.3),
            Vec3::new(0.6, f, -0.9),
            Vec3::new(-0.6, f, -0.9),
        ],
        3,
    );
    push_sphere(&mut d, Vec3::new(0.1, -0.5, -0.3), 0.45, 16, 32, 2);
    d.camera = Some(CameraDesc {
        origin: [0.0, 0.1, 0.95],
        target: [0.1, -0.5, -0.3],
        up: [0.0, 1.0, 0.0],
        fov: 40.0,
        fov_axis: FovAxis::Y,
        ..Default::default()
    });
    Scene::build(d, 0.0).unwrap()
}

#[test]
fn rough_glass_adjoint() {
    // Light tracing alone (every contribution through the adjoint BSDF, refractions
    // included) and BDPT agree with the path tracer through rough glass.
    let scene = rough_glass_room();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let set = settings(RrMode::Classic, -1);
    let lt = BdptOptions {
        strategies: Strategies::LightTracing,
        ..Default::default()
    };
    let (w, h) = (8, 8);
    let a = render_bdpt::<3>(&scene, w, h, 1024, 1, &set, lt);
    let b = render_path::<3>(&scene, w, h, 4096, 2, &set);
    assert_means_agree("light tracing vs path", &a, &b, 3.5);
    agree_per_pixel_on(&scene, 8, 8, 256);
}

/// K[p] varying over the image (0.25 .. 8 by pixel): the weights of a path still sum to 1
/// whatever K, so any K must leave the image unbiased.
fn uneven_lt_ratio(w: u32, h: u32) -> std::sync::Arc<LtRatio> {
    std::sync::Arc::new(LtRatio {
        width: w,
        height: h,
        k: (0..w * h).map(|i| 0.25 * (1 << (i % 6)) as f32).collect(),
    })
}

/// `render_bdpt` with light paths of their own: pass j gives every pixel one camera sample
/// (with the MIS weights of `k`) and traces `extra` light paths per pixel for light tracing
/// alone (`light_path_sample`); every splat of the pass counts 1 / (1 + extra), the film's
/// splat sum x P / light paths.
#[allow(clippy::too_many_arguments)]
fn render_bdpt_lt<const N: usize>(
    scene: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
    set: &IntegratorSettings,
    k: std::sync::Arc<LtRatio>,
    extra: u32,
    heuristic: MisHeuristic,
) -> Img {
    let opts = BdptOptions {
        heuristic,
        lt_ratio: Some(k),
        ..Default::default()
    };
    let scale = 1.0 / (1 + extra) as f32;
    let mut c = Counters::default();
    render(scene, w, h, spp, seed, |cam, x, y, s, splat| {
        let mut scaled = |r: Vec2, v: [f32; 3]| splat(r, v.map(|x| x * scale));
        for e in 0..extra {
            let mut ls = s.decorrelated(0x11_0000 + e as u64);
            light_path_sample::<N>(scene, cam, &mut ls, set, &opts, &mut c, &mut scaled);
        }
        sample_pixel_with::<N>(scene, cam, x, y, s, set, &opts, &mut c, &mut scaled, None)
    })
}

/// Light paths of their own with K in the MIS weights keep the furnace at 1, with K right
/// (3 light paths per camera sample) or far off (`uneven_lt_ratio`), for both heuristics.
#[test]
fn furnace_with_light_paths_of_their_own_is_one() {
    for name in ["furnace", "furnace-glossy"] {
        let scene = scene::load(name).unwrap();
        let set = settings(RrMode::Classic, -1);
        let right = std::sync::Arc::new(LtRatio {
            width: 8,
            height: 8,
            k: vec![3.0; 64],
        });
        for (i, (k, heuristic)) in [
            (right.clone(), MisHeuristic::Balance),
            (uneven_lt_ratio(8, 8), MisHeuristic::Balance),
            (uneven_lt_ratio(8, 8), MisHeuristic::Power),
        ]
        .into_iter()
        .enumerate()
        {
            let img = render_bdpt_lt::<3>(&scene, 8, 8, 48, 30 + i as u64, &set, k, 2, heuristic);
            assert_furnace(&img, &format!("{name} light paths of their own, case {i}"));
        }
    }
}

/// Per-pixel z-tests of two images and their image means within 3 standard errors. 0.27%
/// of the tests land beyond 3 sigma by chance (3x that + 2 are allowed); Bonferroni at 1%
/// for the worst: 4.4 sigma for 768 tests (4.8 allowed).
fn assert_agree(name: &str, a: &Img, b: &Img) {
    let n = a.mean.len();
    let tests = (n * 3) as f64;
    let (mut big, mut worst) = (0, 0.0f64);
    for i in 0..n {
        for c in 0..3 {
            let v = a.var[i][c] + b.var[i][c];
            let z = if v > 0.0 {
                (a.mean[i][c] - b.mean[i][c]) / v.sqrt()
            } else {
                0.0
            };
            worst = worst.max(z.abs());
            if z.abs() > 3.0 {
                big += 1;
            }
        }
    }
    let allowed = (3.0 * 0.0027 * tests) as usize + 2;
    assert!(
        big <= allowed && worst < 4.8,
        "{name}: {big} of {tests} beyond 3 se (allowed {allowed}), worst {worst}"
    );
    assert_means_agree(name, a, b, 3.0);
}

/// BDPT with light paths of their own and K in the MIS weights against plain BDPT (another
/// seed), per pixel: on `cornell` and on `caustic`, whose caustic comes from light tracing.
#[test]
fn light_paths_of_their_own_agree_with_plain_bdpt_per_pixel() {
    let set = settings(RrMode::Classic, -1);
    for (name, spp) in [("cornell", 64), ("caustic", 96)] {
        let scene = scene::load(name).unwrap();
        let (w, h) = (16, 16);
        let a = render_bdpt_lt::<3>(
            &scene,
            w,
            h,
            spp,
            5,
            &set,
            uneven_lt_ratio(w, h),
            2,
            MisHeuristic::Balance,
        );
        let b = render_bdpt::<3>(&scene, w, h, 2 * spp, 6, &set, BdptOptions::default());
        assert_agree(name, &a, &b);
    }
}

/// More light paths with the right K lower light tracing's noise where it carries the
/// image (the caustic): the image mean's standard error at equal camera samples falls.
#[test]
fn light_paths_of_their_own_lower_the_caustics_noise() {
    let scene = scene::load("caustic").unwrap();
    let set = settings(RrMode::Classic, -1);
    let (w, h) = (16, 16);
    let k = |v: f32| {
        std::sync::Arc::new(LtRatio {
            width: w,
            height: h,
            k: vec![v; (w * h) as usize],
        })
    };
    let one = render_bdpt_lt::<3>(&scene, w, h, 64, 7, &set, k(1.0), 0, MisHeuristic::Balance);
    let four = render_bdpt_lt::<3>(&scene, w, h, 64, 7, &set, k(4.0), 3, MisHeuristic::Balance);
    let var = |a: &Img| a.var.iter().map(|v| v.iter().sum::<f64>()).sum::<f64>();
    assert!(
        var(&four) < 0.6 * var(&one),
        "summed pixel variance: K = 4 {} against K = 1 {}",
        var(&four),
        var(&one)
    );
}

/// The two images' means agree per channel within `z_max` standard errors.
fn assert_means_agree(what: &str, a: &Img, b: &Img, z_max: f64) {
    for c in 0..3 {
        let z =
            (a.img_mean[c] - b.img_mean[c]) / (a.img_se[c].powi(2) + b.img_se[c].powi(2)).sqrt();
        assert!(
            z.abs() < z_max,
            "{what}, channel {c}: image means {} +- {} vs {} +- {} (z {z})",
            a.img_mean[c],
            a.img_se[c],
            b.img_mean[c],
            b.img_se[c]
        );
    }
}
