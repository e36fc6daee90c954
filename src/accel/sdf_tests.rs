use super::*;

const C: Vec3 = Vec3::new(0.5, 0.5, 0.5);
const R: f32 = 0.3;

/// The distance to a sphere of radius `R` about `C`, sampled on `n`^3 points.
fn sphere_grid(n: u32) -> SdfGrid {
    let s = 1.0 / (n - 1) as f32;
    let mut v = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, y as f32, z as f32) * s;
                v.push((p - C).length() - R);
            }
        }
    }
    SdfGrid::new([n, n, n], v).unwrap()
}

/// The analytic sphere's first hit in (0, inf).
fn sphere_t(o: Vec3, d: Vec3) -> Option<f32> {
    let oc = o - C;
    let (a, b, c) = (d.dot(d), 2.0 * oc.dot(d), oc.dot(oc) - R * R);
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / (2.0 * a);
    (t > 0.0).then_some(t)
}

/// A deterministic sequence of numbers in [0, 1).
fn uniforms(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn unit(u: &mut impl FnMut() -> f32) -> Vec3 {
    let z = 2.0 * u() - 1.0;
    let phi = std::f32::consts::TAU * u();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[test]
fn solve_cubic_finds_the_first_root() {
    // (t - 0.25)(t - 0.5)(t - 2) on [0, 1]: the first root, 0.25
    let c = [-0.25, 1.625, -2.75, 1.0];
    let f = |t: f32| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    let t = solve_cubic(1.0, f(0.0), f(1.0), c).unwrap();
    assert!((t - 0.25).abs() < 1e-5, "{t}");
    // no sign change and no root inside: none
    let c = [1.0, 0.0, 1.0, 0.0];
    assert_eq!(solve_cubic(1.0, 1.0, 2.0, c), None);
}

#[test]
fn sphere_grid_hits_agree_with_the_analytic_sphere() {
    let g = sphere_grid(33);
    let mut u = uniforms(7);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = C + unit(&mut u) * 0.9;
        let target = C + unit(&mut u) * (0.25 * u());
        let d = (target - o) * (0.5 + u());
        let want = sphere_t(o, d).expect("aimed inside the sphere");
        let (t, v) = g.intersect(o, d, f32::INFINITY, false).expect("a hit");
        // the trilinear interpolant of |p - c| - r differs from it by at most h^2 / 8
        // times the sum of its second derivatives' bounds along the axes (each 1 / |p - c|,
        // |p - c| >= r - sqrt(3) h in a voxel the surface crosses), h = 1/32: the hit lies
        // that close to the sphere, and its t near the analytic one
        let h = 1.0 / 32.0f32;
        let bound = h * h / 8.0 * 3.0 / (R - 3.0f32.sqrt() * h);
        let off = ((o + d * t - C).length() - R).abs();
        assert!(off < bound, "{off} off the sphere (bound {bound})");
        let err = (t - want).abs() * d.length();
        assert!(err < 2e-3, "t {t} against {want}: {err}");
        // the interpolant's gradient (one-sided differences across the voxel) is the
        // sphere's normal within the angle a voxel spans seen from the centre, h / r
        let p = o + d * t;
        let n_true = (p - C).normalize();
        let n = g.eval(v, p).1.normalize();
        assert!(
            n.dot(n_true) > (1.0f32 / 32.0 / R).cos(),
            "{n} against {n_true}"
        );
        let ns = g.smooth_normal(p).normalize();
        assert!(ns.dot(n_true) > 0.998, "smooth {ns} against {n_true}");
        // the same answer for a shadow query, and none before the hit
        assert!(g.intersect(o, d, t * 1.001, true).is_some());
        assert!(g.intersect(o, d, t * 0.999, false).is_none());
        hits += 1;
    }
    assert_eq!(hits, 2000);
}

#[test]
fn rays_that_miss_the_sphere_miss_the_grid() {
    let g = sphere_grid(33);
    let mut u = uniforms(11);
    for _ in 0..2000 {
        let o = C + unit(&mut u) * 0.9;
        let to_c = (C - o).normalize();
        // a direction whose line passes C at more than R + 0.02
        let side = to_c.any_orthonormal_vector();
        let off = side * (R + 0.02 + 0.1 * u());
        let d = ((C + off) - o).normalize();
        assert!(sphere_t(o, d).is_none());
        assert_eq!(g.intersect(o, d, f32::INFINITY, false), None, "{o} {d}");
        // and away from the sphere
        assert_eq!(g.intersect(o, -to_c, f32::INFINITY, true), None);
    }
    // axis-aligned rays along the grid planes, outside the sphere
    for x in [0.0, 0.125, 1.0] {
        let o = Vec3::new(x, 0.0, -1.0);
        assert_eq!(g.intersect(o, Vec3::Z, f32::INFINITY, false), None);
    }
}

#[test]
fn axis_aligned_rays_through_grid_planes_hit() {
    let g = sphere_grid(33);
    // along z through the centre, which lies on sample planes in x and y
    let (t, _) = g
        .intersect(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, f32::INFINITY, false)
        .unwrap();
    assert!((t - 1.2).abs() < 1e-3, "{t}");
    // from inside: the far side
    let (t, v) = g.intersect(C, Vec3::X, f32::INFINITY, false).unwrap();
    assert!((t - R).abs() < 1e-3, "{t}");
    assert!(g.eval(v, C + Vec3::X * t).1.x > 0.0);
}

#[test]
fn bad_grids_are_refused_with_the_reason() {
    let e = SdfGrid::new([1, 2, 2], vec![0.0; 4]).unwrap_err();
    assert!(e.contains("at least 2"), "{e}");
    let e = SdfGrid::new([2, 2, 2], vec![0.0; 7]).unwrap_err();
    assert!(e.contains("7 distances"), "{e}");
    let mut v = vec![-1.0; 8];
    v[3] = f32::NAN;
    let e = SdfGrid::new([2, 2, 2], v).unwrap_err();
    assert!(e.contains("distance 3 is NaN"), "{e}");
    let e = SdfGrid::new([2, 2, 2], vec![1.0; 8]).unwrap_err();
    assert!(e.contains("never change sign"), "{e}");
}

#[test]
fn placed_grids_hit_in_world_space() {
    let g = Arc::new(sphere_grid(33));
    // the unit cube scaled by 4 and moved: a sphere of radius 1.2 about (3, 2, 2)
    let m = Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0)) * Mat4::from_scale(Vec3::splat(4.0));
    let s = SdfShapes::build(&[(g.clone(), Mat4::IDENTITY, false), (g.clone(), m, true)]).unwrap();
    let ray = Ray::new(Vec3::new(3.0, 2.0, -5.0), Vec3::Z);
    let h = s.intersect(&ray, f32::INFINITY).unwrap();
    assert!((h.t - 5.8).abs() < 4e-3, "{}", h.t);
    assert!((h.p - Vec3::new(3.0, 2.0, 0.8)).length() < 4e-3, "{}", h.p);
    assert!(
        h.n.normalize().dot(-Vec3::Z) > (1.0f32 / 32.0 / R).cos(),
        "{}",
        h.n
    );
    assert!(s.shading_normal(&h).dot(-Vec3::Z) > 0.999);
    // the second grid's voxels are numbered after the first's
    assert_eq!(s.locate(h.prim), Some(1));
    assert!(h.prim >= SDF_FIRST_PRIM + g.occupied() as u32);
    assert_eq!(s.locate(SDF_FIRST_PRIM), Some(0));
    assert_eq!(s.locate(SDF_FIRST_PRIM + 2 * g.occupied() as u32), None);
    assert_eq!(s.locate(5), None);
    assert!(s.occluded(&ray, 5.9));
    assert!(!s.occluded(&ray, 5.7));
    // a ray between the two spheres misses both
    assert!(s
        .intersect(&Ray::new(Vec3::new(-2.0, 4.0, 0.5), Vec3::X), 1e9)
        .is_none());
    let e = SdfShapes::build(&[(g, Mat4::ZERO, true)]).unwrap_err();
    assert!(e.contains("not invertible"), "{e}");
}
