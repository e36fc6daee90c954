use super::*;
use crate::sampling::SeqRng;

fn v(r: &mut SeqRng, a: f32, b: f32) -> Vec3 {
    let mut f = || a + (b - a) * r.next_f32();
    Vec3::new(f(), f(), f())
}

/// A cloud of small random triangles in [-1, 1]^3.
fn cloud(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut r = SeqRng::new(seed);
    (0..n)
        .map(|_| {
            let c = v(&mut r, -1.0, 1.0);
            [
                c + v(&mut r, -0.2, 0.2),
                c + v(&mut r, -0.2, 0.2),
                c + v(&mut r, -0.2, 0.2),
            ]
        })
        .collect()
}

fn placements() -> Vec<Mat4> {
    vec![
        Mat4::IDENTITY,
        Mat4::from_translation(Vec3::new(3.0, 0.5, -1.0)),
        Mat4::from_scale_rotation_translation(
            Vec3::new(1.5, 0.7, 2.0),
            glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.8),
            Vec3::new(-3.0, 1.0, 2.0),
        ),
        // a mirroring one
        Mat4::from_translation(Vec3::new(0.0, -3.5, 0.0))
            * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
    ]
}

/// Hits on the instances agree with hits on the same triangles copied into world space:
/// the same triangle, `t` and point to a few ulps, normals parallel, and the same
/// occlusion answers; the identity instance bit for bit.
#[test]
fn instances_hit_what_copies_of_their_group_hit() {
    let group = cloud(300, 1);
    let xfs = placements();
    let inst: Vec<(u32, Mat4)> = xfs.iter().map(|m| (0, *m)).collect();
    let base = 7;
    let ins = Instances::build(&[&group], &inst, base).unwrap();
    let mut copies = Vec::new();
    for m in &xfs {
        copies.extend(group.iter().map(|t| t.map(|p| m.transform_point3(p))));
    }
    let flat = Bvh::build(&copies);
    let mut r = SeqRng::new(2);
    let (mut agree, mut total) = (0, 0);
    for _ in 0..4000 {
        let o = v(&mut r, -8.0, 8.0);
        let target = v(&mut r, -4.0, 4.0);
        let ray = Ray::new(o, target - o);
        let a = flat.intersect(&ray, f32::INFINITY);
        let b = ins.intersect(&ray, f32::INFINITY);
        assert_eq!(
            flat.occluded(&ray, 0.9),
            ins.occluded(&ray, 0.9),
            "occlusion of {ray:?}"
        );
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                total += 1;
                let prim = b.prim - base;
                if prim == a.prim {
                    agree += 1;
                    assert!((a.t - b.t).abs() <= 1e-5 * a.t.abs(), "{a:?} {b:?}");
                    assert!(
                        (a.p - b.p).length() <= 1e-4 * (1.0 + a.p.length()),
                        "{a:?} {b:?}"
                    );
                    let c = a.n.normalize().dot(b.n.normalize()).abs();
                    assert!(c > 0.9999, "{a:?} {b:?}");
                    if prim < group.len() as u32 {
                        assert_eq!(a.t.to_bits(), b.t.to_bits(), "identity instance");
                    }
                    assert_eq!(
                        ins.locate(b.prim),
                        Some((prim / group.len() as u32, 0, prim % group.len() as u32))
                    );
                } else {
                    // a near tie between two triangles: the distances agree
                    assert!((a.t - b.t).abs() <= 1e-4 * a.t.abs(), "{a:?} {b:?}");
                }
            }
            (a, b) => panic!("{ray:?}: copies {a:?}, instances {b:?}"),
        }
    }
    assert!(
        total > 500 && agree * 100 >= total * 99,
        "{agree} of {total}"
    );
    assert_eq!(ins.locate(base - 1), None);
    assert_eq!(ins.locate(base + 4 * 300), None);
}

/// A thousand instances of a 10k-triangle group take a small fraction of the memory of
/// the same triangles copied (the copies' BVH alone is counted for them).
#[test]
fn a_thousand_instances_cost_little_memory() {
    let group = cloud(10_000, 3);
    let one = Bvh::build(&group).memory_bytes();
    let inst: Vec<(u32, Mat4)> = (0..1000)
        .map(|i| {
            let p = Vec3::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32) * 3.0;
            (0, Mat4::from_translation(p))
        })
        .collect();
    let ins = Instances::build(&[&group], &inst, 0).unwrap();
    // copies: at least one group BVH per copy
    let copies = 1000 * one;
    assert!(
        ins.memory_bytes() * 50 < copies,
        "instances {} bytes, copies at least {copies}",
        ins.memory_bytes()
    );
    // and the instances are all there: a ray down each column of the grid hits
    let mut hits = 0;
    for i in 0..100 {
        let p = Vec3::new((i % 10) as f32, (i / 10) as f32, 0.0) * 3.0;
        let ray = Ray::new(p + Vec3::new(0.05, 0.03, -5.0), Vec3::Z);
        if let Some(h) = ins.intersect(&ray, f32::INFINITY) {
            hits += 1;
            assert!(
                h.p.z < 1.5,
                "the nearest instance is the first of the column: {h:?}"
            );
        }
    }
    assert!(hits > 90, "{hits}");
}

#[test]
fn a_singular_transform_or_a_missing_group_is_an_error() {
    let group = cloud(10, 4);
    let e = Instances::build(
        &[&group],
        &[(0, Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)))],
        0,
    )
    .unwrap_err();
    assert!(e.contains("not invertible"), "{e}");
    let e = Instances::build(&[&group], &[(1, Mat4::IDENTITY)], 0).unwrap_err();
    assert!(e.contains("no group 1"), "{e}");
}
