//! Known answers of the radiosity preprocess: form factors between unit squares, the
//! furnace room (B / pi = 1 everywhere), determinism across thread counts, bad input.

use super::mesh;
use super::solve::{element_to_element, mirror_factor, source_pattern, MirrorTri, Patterns};
use super::{RadiositySettings, Solution};
use crate::accel::Bvh;
use crate::math::Vec3;
use crate::scene::builtin::push_quad;
use crate::scene::{MaterialDesc, Scene, SceneDesc};

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// F(A1 -> A2) between two quads (given counter-clockwise as seen from their fronts),
/// each meshed at `level`: the area-weighted mean over A1's element centroids of the
/// point-to-area factor to every element of A2.
fn quad_form_factor(q1: [Vec3; 4], q2: [Vec3; 4], level: u32) -> f64 {
    let mut d = SceneDesc::default();
    push_quad(&mut d, q1, 0);
    push_quad(&mut d, q2, 1);
    let levels = vec![Some(level); 4];
    let m = mesh::build(&d.positions, &levels, &d.material, 2.0);
    let bvh = Bvh::build(&d.positions);
    let pat = Patterns::new(1);
    let (mut num, mut area) = (0.0f64, 0.0f64);
    for r in m.elems.iter().filter(|e| e.prim < 2) {
        let mut f = 0.0f64;
        for s in m.elems.iter().filter(|e| e.prim >= 2) {
            let (fs, _) = element_to_element(&bvh, r, s, s.n, &pat);
            f += fs[0] as f64;
        }
        num += r.area as f64 * f;
        area += r.area as f64;
    }
    num / area
}

#[test]
fn form_factor_parallel_unit_squares() {
    // Analytic: two coaxial parallel unit squares at distance 1 (Howell's catalogue C-11).
    let x = 1.0f64;
    let y = 1.0f64;
    let xx = (1.0 + x * x).sqrt();
    let yy = (1.0 + y * y).sqrt();
    let exact = 2.0 / (std::f64::consts::PI * x * y)
        * (((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y))
            .sqrt()
            .ln()
            + x * yy * (x / yy).atan()
            + y * xx * (y / xx).atan()
            - x * x.atan()
            - y * y.atan());
    let f = quad_form_factor(
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
        4,
    );
    let rel = (f - exact).abs() / exact;
    println!("parallel: F = {f:.5}, exact {exact:.5}, rel err {rel:.2e}");
    assert!((exact - 0.19982).abs() < 1e-4);
    assert!(rel < 0.01, "F = {f}, exact {exact}");
}

#[test]
fn form_factor_through_a_mirror_is_the_images() {
    // A unit square receiver on z = 0 facing up, a unit square source on the same spot
    // (another object, left out of the BVH) and a large mirror on z = 0.5 facing down:
    // through the mirror the receiver sees the source's image, a coaxial parallel square
    // at distance 1 facing it, so F equals the analytic 0.19982 of Howell's C-11 (the
    // mirror itself, in the BVH, must not shadow its own reflection).
    let mut d = SceneDesc::default();
    let sq = [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)];
    push_quad(&mut d, sq, 0);
    push_quad(&mut d, sq, 1);
    let mirror = [
        v(-1., -1., 0.5),
        v(-1., 2., 0.5),
        v(2., 2., 0.5),
        v(2., -1., 0.5),
    ];
    push_quad(&mut d, mirror, 2);
    let m = mesh::build(&d.positions[..4], &[Some(4); 4], &d.material[..4], 2.0);
    let bvh = Bvh::build(&d.positions[4..]);
    let mirrors: Vec<MirrorTri> = d.positions[4..]
        .iter()
        .map(|t| {
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            MirrorTri {
                p0: t[0],
                e1,
                e2,
                n: e1.cross(e2).normalize(),
                ks: vec![1.0; 3],
            }
        })
        .collect();
    let pat = source_pattern(1);
    let (mut num, mut area) = (0.0f64, 0.0f64);
    for r in m.elems.iter().filter(|e| e.prim < 2) {
        let mut f = 0.0f64;
        for s in m.elems.iter().filter(|e| e.prim >= 2) {
            for mt in &mirrors {
                let (fs, _) = mirror_factor(&bvh, r.c, r.n, s, s.n, mt, &pat);
                f += fs[0] as f64;
            }
        }
        num += r.area as f64 * f;
        area += r.area as f64;
    }
    let f = num / area;
    let exact = 0.199825;
    println!("F through the mirror {f:.5}, analytic {exact}");
    assert!((f - exact).abs() / exact < 0.01, "{f} vs {exact}");
}

#[test]
fn form_factor_perpendicular_unit_squares() {
    // Analytic: perpendicular unit squares with a shared edge (Howell C-14, H = W = 1).
    let (h, w) = (1.0f64, 1.0f64);
    let pi = std::f64::consts::PI;
    let a = (1.0 + h * h) * (1.0 + w * w) / (1.0 + h * h + w * w);
    let b = w * w * (1.0 + h * h + w * w) / ((1.0 + w * w) * (h * h + w * w));
    let c = h * h * (1.0 + h * h + w * w) / ((1.0 + h * h) * (h * h + w * w));
    let exact = 1.0 / (pi * w)
        * (w * (1.0 / w).atan() + h * (1.0 / h).atan()
            - (h * h + w * w).sqrt() * (1.0 / (h * h + w * w).sqrt()).atan()
            + 0.25 * (a * b.powf(w * w) * c.powf(h * h)).ln());
    let f = quad_form_factor(
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
        4,
    );
    let rel = (f - exact).abs() / exact;
    println!("perpendicular: F = {f:.5}, exact {exact:.5}, rel err {rel:.2e}");
    assert!((exact - 0.20004).abs() < 1e-4);
    assert!(rel < 0.01, "F = {f}, exact {exact}");
}

#[test]
fn grid_indices_are_dense() {
    for level in 0..4 {
        let n = 1u32 << level;
        let mut seen = vec![false; (n * n) as usize];
        for j in 0..n {
            for i in 0..n - j {
                seen[mesh::cell_index(n, i, j, false) as usize] = true;
                if i + j + 2 <= n {
                    seen[mesh::cell_index(n, i, j, true) as usize] = true;
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
        let last = mesh::grid_index(n, 0, n);
        assert_eq!(last + 1, (n + 1) * (n + 2) / 2);
    }
}

#[test]
fn furnace_solution_is_one_everywhere() {
    let scene = crate::scene::load("furnace").unwrap();
    let set = RadiositySettings {
        max_area: Some(2.0 / 64.0),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap();
    println!("{:?}", sol.stats);
    assert!(sol.stats.converged);
    let mut worst = 0.0f32;
    for (t, tri) in scene.tris.iter().enumerate() {
        for a in 0..=8 {
            for b in 0..=(8 - a) {
                let p = tri[0]
                    + (tri[1] - tri[0]) * (a as f32 / 8.0)
                    + (tri[2] - tri[0]) * (b as f32 / 8.0);
                // (B - E)/pi + E/pi on the inside (the front of the inward walls)
                let r = sol.reflected::<3>(t as u32, p, true).unwrap();
                let e = scene.material_of(t as u32).emission;
                for c in 0..3 {
                    let l = r[c] + e[c];
                    worst = worst.max((l - 1.0).abs());
                }
                let full = sol.radiance::<3>(t as u32, p, true).unwrap();
                for c in 0..3 {
                    assert!((full[c] - r[c] - e[c]).abs() < 1e-5);
                }
            }
        }
    }
    println!("furnace: worst |L - 1| = {worst:.2e}");
    assert!(worst < 0.005, "worst deviation {worst}");
}

#[test]
fn furnace_solution_spectral() {
    let scene = crate::scene::load("furnace").unwrap();
    let set = RadiositySettings {
        max_area: Some(2.0 / 16.0),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 8, &crate::progress::Silent).unwrap();
    let tri = scene.tris[5];
    let p = (tri[0] + tri[1] + tri[2]) / 3.0;
    let l = sol.radiance::<8>(5, p, true).unwrap();
    for c in 0..8 {
        assert!((l[c] - 1.0).abs() < 0.01, "band {c}: {}", l[c]);
    }
}

/// Cornell's boxes go 0.01 through the floor and its light hangs 0.01 below the ceiling:
/// receivers nearly touching their sources. The solve must converge there.
#[test]
fn cornell_converges() {
    let scene = crate::scene::load("cornell").unwrap();
    let set = RadiositySettings {
        max_area: Some(0.1),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap();
    println!("{:?}", sol.stats);
    assert!(sol.stats.converged && sol.stats.residual_unshot <= 1e-3);
    // B/pi of the ceiling beside the light is of the order of the path-traced value
    let b = sol
        .radiance::<3>(4, crate::math::Vec3::new(0.5, 1.0, 0.5), false)
        .unwrap();
    let f = sol
        .radiance::<3>(4, crate::math::Vec3::new(0.5, 1.0, 0.5), true)
        .unwrap();
    let l = b[0].max(f[0]);
    assert!(l > 0.1 && l < 2.0, "{b:?} {f:?}");
}

#[test]
fn solver_identical_on_1_and_3_threads() {
    let scene = crate::scene::load("cornell").unwrap();
    let set = RadiositySettings {
        max_area: Some(0.03),
        tolerance: 1e-2,
        ..Default::default()
    };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap())
    };
    let a = run(1);
    let b = run(3);
    // enough elements for the shots' parallel update (several chunks) on 3 threads
    assert!(a.stats.elements > 2 * super::solve::UPDATE_CHUNK as u64);
    assert_eq!(a.stats.shots, b.stats.shots);
    assert_eq!(a.stats.rays, b.stats.rays);
    assert!(a.stats.shots > 10);
    assert!(a
        .vertex_b
        .iter()
        .zip(&b.vertex_b)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
}

#[test]
fn default_mesh_of_cornell_has_a_few_thousand_elements() {
    let scene = crate::scene::load("cornell").unwrap();
    // count only (the full solve is the CLI's job)
    let set = RadiositySettings {
        max_shots: Some(0),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap();
    println!(
        "cornell default: {} elements, max area {:.4}",
        sol.stats.elements, sol.stats.max_area
    );
    assert!((1000..10000).contains(&sol.stats.elements));
    assert!(!sol.stats.converged);
}

#[test]
fn refuses_a_mesh_too_fine_before_allocating() {
    let scene = crate::scene::load("cornell").unwrap();
    let set = RadiositySettings {
        max_area: Some(1e-9),
        ..Default::default()
    };
    let e = Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap_err();
    println!("{e}");
    assert!(e.contains("--radiosity-max-area") && e.contains("elements") && !e.contains('\n'));
    for bad in [0.0, -1.0, f32::NAN] {
        let set = RadiositySettings {
            max_area: Some(bad),
            ..Default::default()
        };
        assert!(Solution::compute(&scene, &set, 3, &crate::progress::Silent).is_err());
    }
    let set = RadiositySettings {
        tolerance: 0.0,
        ..Default::default()
    };
    assert!(Solution::compute(&scene, &set, 3, &crate::progress::Silent).is_err());
}

#[test]
fn refuses_a_scene_without_diffuse_surfaces() {
    let mut d = SceneDesc {
        name: "mirrors".into(),
        ..Default::default()
    };
    let mut mirror = MaterialDesc::named("mirror");
    mirror.illum = 5;
    let mut light = MaterialDesc::named("light");
    light.kd = [0.0; 3];
    light.ke = [1.0; 3];
    d.materials = vec![mirror, light];
    push_quad(
        &mut d,
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        0,
    );
    push_quad(
        &mut d,
        [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
        1,
    );
    let scene = Scene::build(d, 0.0).unwrap();
    let e = Solution::compute(
        &scene,
        &RadiositySettings::default(),
        3,
        &crate::progress::Silent,
    )
    .unwrap_err();
    println!("{e}");
    assert!(e.contains("no diffuse surface") && !e.contains('\n'));
}

#[test]
fn lookup_finds_the_element_of_a_point() {
    for level in 0..4 {
        let n = 1u32 << level;
        for (b1, b2) in [
            (0.1f32, 0.2f32),
            (0.7, 0.29),
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.33, 0.33),
        ] {
            let (_, w) = mesh::locate(level, b1, b2);
            let s: f32 = w.iter().map(|c| c.2).sum();
            assert!((s - 1.0).abs() < 1e-5);
            let (x, y) = w.iter().fold((0.0, 0.0), |(x, y), &(i, j, wt)| {
                (x + wt * i as f32 / n as f32, y + wt * j as f32 / n as f32)
            });
            assert!(
                (x - b1).abs() < 1e-5 && (y - b2).abs() < 1e-5,
                "{level} {b1} {b2}"
            );
            assert!(w.iter().all(|c| c.2 >= -1e-6 && c.0 + c.1 <= n));
        }
    }
}

/// A `--time` budget makes the default mesh as fine as a tenth of it allows: a budget too
/// small for more keeps the coarse solution, a large one reaches the default mesh and not
/// past it, and an explicit `--radiosity-max-area` is kept whatever the budget.
#[test]
fn the_default_mesh_follows_the_time_budget() {
    let scene = crate::scene::load("cornell").unwrap();
    let elements = |time_budget: Option<f64>, max_area: Option<f32>| {
        let set = RadiositySettings {
            time_budget,
            max_area,
            // the mesh is what is tested: one shot solves enough
            max_shots: Some(1),
            ..Default::default()
        };
        Solution::compute(&scene, &set, 3, &crate::progress::Silent)
            .unwrap()
            .stats
            .elements
    };
    let default = elements(None, None);
    let coarse = elements(Some(1e-4), None);
    assert!(coarse * 8 < default, "{coarse} against {default} elements");
    assert_eq!(elements(Some(1e6), None), default);
    assert_eq!(elements(Some(1e-4), Some(0.02)), elements(None, Some(0.02)));
}

/// The glossy furnace (diffuse + Phong walls emitting 1 - a(w), radiance exactly 1 in the
/// path tracer) solves to 1 within the mesh's error: the solution carries the Phong lobe's
/// hemispherical albedo (without it, B was 1 - a_glossy's share: about 0.6 on these walls).
#[test]
fn glossy_furnace_solution_is_one_everywhere() {
    let scene = crate::scene::load("furnace-glossy").unwrap();
    let set = RadiositySettings {
        max_area: Some(2.0 / 16.0),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap();
    assert!(sol.stats.converged);
    let mut worst = 0.0f32;
    for (t, tri) in scene.tris.iter().enumerate() {
        let p = (tri[0] + tri[1] + tri[2]) / 3.0;
        let full = sol.radiance::<3>(t as u32, p, true).unwrap();
        for c in 0..3 {
            worst = worst.max((full[c] - 1.0).abs());
        }
    }
    println!("glossy furnace: worst |L - 1| = {worst:.2e}");
    assert!(worst < 0.005, "worst deviation {worst}");
}

/// The roulette's lookup finds, from a hit's barycentrics, the element `locate` finds
/// for the same point, on every level, inside the cells and on their edges and corners.
#[test]
fn roulette_cell_is_the_located_element() {
    for level in 0..6 {
        let k = 48;
        for a in 0..=k {
            for b in 0..=(k - a) {
                let (b1, b2) = (a as f32 / k as f32, b as f32 / k as f32);
                assert_eq!(
                    mesh::cell_of(level, b1, b2),
                    mesh::locate(level, b1, b2).0,
                    "level {level}, barycentrics ({b1}, {b2})"
                );
            }
        }
        // rounding just outside the triangle stays in it
        for (b1, b2) in [
            (-1e-6, 0.5),
            (0.5, -1e-6),
            (0.5 + 1e-6, 0.5),
            (1.0 + 1e-6, 0.0),
        ] {
            assert_eq!(mesh::cell_of(level, b1, b2), mesh::locate(level, b1, b2).0);
        }
    }
}

/// The furnace (walls of albedo a emitting 1 - a: radiance 1 everywhere). A solution
/// that only the roulette reads may stop after a few shots (here 200 of 1,246); with the unshot power spread as
/// the ambient term its L~ (indirect radiance arriving) is close to the converged
/// solve's in the mean, without it far below.
#[test]
fn roulette_solution_stops_early_with_an_ambient_term() {
    let scene = crate::scene::load("furnace").unwrap();
    let solve = |roulette_only: bool, max_shots: Option<u64>| {
        let set = RadiositySettings {
            max_area: Some(2.0 / 16.0),
            roulette_only,
            max_shots,
            ..Default::default()
        };
        Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap()
    };
    let early = solve(true, Some(200));
    let full = solve(false, None);
    println!(
        "{} of {} shots, mean L~ {:?} (converged {:?})",
        early.stats.shots, full.stats.shots, early.mean_indirect, full.mean_indirect
    );
    assert!(early.stats.shots < full.stats.shots / 4 && !early.stats.converged);
    assert!(full.stats.converged);
    // the worst difference from the converged L~, front sides (the furnace's inside)
    let worst = |sol: &Solution| {
        (0..sol.mesh.elems.len() * 3)
            .map(|q| {
                let (i, k) = (q / 3, q % 3);
                (sol.element_indirect[2 * i * 3 + k] - full.element_indirect[2 * i * 3 + k]).abs()
            })
            .fold(0.0f32, f32::max)
    };
    let bare = solve(false, Some(early.stats.shots));
    let (we, wb) = (worst(&early), worst(&bare));
    println!("worst |L~ - converged|: early {we:.3e}, without the ambient term {wb:.3e}");
    assert!(we < 0.5 * wb, "{we} {wb}");
    // the mean within 8% of the converged one (the ambient term spreads the unshot power
    // by the area-weighted albedo; the furnace's saturated walls reflect it unevenly),
    // without the ambient term over 25% below
    for k in 0..3 {
        let (m, e, f) = (
            early.mean_indirect[k],
            bare.mean_indirect[k],
            full.mean_indirect[k],
        );
        assert!(
            (m - f).abs() < 0.08 * f && e < 0.75 * f,
            "band {k}: {m} {e} {f}"
        );
    }
}

/// A solution that only the roulette reads stops at `ROULETTE_RAYS` shadow rays on a
/// scene whose solve would cast far more (rw-room: 2,354 elements, 18.9M rays to the
/// tolerance), and converges where the budget allows (the Cornell box's 210 elements).
#[test]
fn roulette_solution_stops_at_its_ray_budget() {
    let solve = |name: &str| {
        let scene = crate::scene::load(name).unwrap();
        let set = RadiositySettings {
            default_elements: super::ROULETTE_ELEMENTS,
            roulette_only: true,
            ..Default::default()
        };
        Solution::compute(&scene, &set, 3, &crate::progress::Silent).unwrap()
    };
    let room = solve("rw-room");
    println!("rw-room: {:?}", room.stats);
    assert!(!room.stats.converged);
    assert!((super::ROULETTE_RAYS..2 * super::ROULETTE_RAYS).contains(&room.stats.rays));
    let cornell = solve("cornell");
    assert!(cornell.stats.converged && cornell.stats.rays < super::ROULETTE_RAYS);
}
