//! The anisotropic rough conductor: its sampling against its density (chi-square), its
//! energy (white furnace), the frame its roughness applies in, and per-hit roughness.

use super::*;
use crate::material::conductor::Conductor;
use crate::material::Distribution;
use crate::math::Vec3;
use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};
use crate::texture::Texture;

const DISTS: [Distribution; 2] = [Distribution::Ggx, Distribution::Beckmann];

/// A conductor reflecting everything (F = 1) of roughness (alpha_u, alpha_v), its tangent
/// at `angle` radians from the local x axis.
fn white(dist: Distribution, au: f32, av: f32, angle: f32) -> Bsdf {
    Bsdf::Conductor(Conductor {
        aniso: Some(Anisotropy {
            alpha_v: av,
            tangent: [angle.cos(), angle.sin()],
        }),
        ..Conductor::new([0.0; 3], [1e4; 3], [1.0; 3], au, dist)
    })
}

fn dir(theta_deg: f32, phi: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
}

#[test]
fn chi2_anisotropic_conductor() {
    for (k, dist) in DISTS.into_iter().enumerate() {
        for (j, (au, av)) in [(0.6f32, 0.2f32), (0.15, 0.7)].into_iter().enumerate() {
            let b = white(dist, au, av, 0.7);
            for (i, deg) in [0.0f32, 45.0, 75.0].into_iter().enumerate() {
                let wo = dir(deg, 2.0);
                let r = chi2_sphere(
                    |u1, u2| b.sample::<3>(wo, u1, u2).map(|s| s.wi),
                    |wi| b.pdf(wo, wi),
                    200_000,
                    900 + (k * 100 + j * 10 + i) as u64,
                );
                assert_chi2(&format!("{dist:?} ({au}, {av}) at {deg}"), &r);
            }
        }
    }
}

#[test]
fn anisotropic_sample_weight_is_f_cos_over_pdf() {
    let mut rng = TestRng::new(7);
    for dist in DISTS {
        let b = white(dist, 0.3, 0.05, -1.1);
        for deg in [10.0f32, 50.0, 80.0] {
            let wo = dir(deg, 0.4);
            for _ in 0..500 {
                let Some(s) = b.sample::<3>(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                let f = b.eval::<3>(wo, s.wi)[0] * s.wi.z;
                assert!((s.pdf - b.pdf(wo, s.wi)).abs() <= 1e-3 * s.pdf, "{dist:?}");
                assert!(
                    (s.weight[0] - f / s.pdf).abs() <= 1e-3 * s.weight[0],
                    "{dist:?}"
                );
            }
        }
    }
}

#[test]
fn anisotropic_white_furnace() {
    // F = 1: what is lost is shadowing alone; nearly nothing for small roughness along
    // both axes, never more than everything
    for dist in DISTS {
        for (au, av, exact) in [
            (0.02f32, 0.01f32, true),
            (0.5, 0.05, false),
            (0.1, 0.9, false),
        ] {
            let b = white(dist, au, av, 0.3);
            for deg in [0.0f32, 30.0, 60.0, 85.0] {
                let (a, se) = crate::material::tests::energy(&b, dir(deg, 1.0), 100_000, 17);
                assert!(
                    a <= 1.0 + 4.0 * se + 1e-4,
                    "{dist:?} ({au}, {av}) at {deg}: {a}"
                );
                if exact && deg < 80.0 {
                    assert!((a - 1.0).abs() < 2e-3 + 4.0 * se, "{dist:?} at {deg}: {a}");
                }
            }
        }
    }
}

#[test]
fn roughness_follows_the_tangent() {
    // turning the tangent and both directions by the same angle about the normal changes
    // nothing
    let turn = |v: Vec3, a: f32| {
        Vec3::new(
            a.cos() * v.x - a.sin() * v.y,
            a.sin() * v.x + a.cos() * v.y,
            v.z,
        )
    };
    for dist in DISTS {
        let (wo, wi) = (dir(40.0, 0.3), dir(30.0, 2.9));
        let f0 = white(dist, 0.4, 0.1, 0.0).eval::<3>(wo, wi)[0];
        let f1 = white(dist, 0.4, 0.1, 1.2).eval::<3>(turn(wo, 1.2), turn(wi, 1.2))[0];
        assert!((f0 - f1).abs() <= 1e-4 * f0, "{f0} vs {f1}");
        // the highlight spreads along the rougher axis: off the mirror direction by 20
        // degrees along the tangent (alpha_u 0.4) it is brighter than along the bitangent
        // (alpha_v 0.1)
        let b = white(dist, 0.4, 0.1, 0.5);
        let n = Vec3::Z;
        let (t, bt) = (turn(Vec3::X, 0.5), turn(Vec3::Y, 0.5));
        let tilt = |axis: Vec3| n * 20f32.to_radians().cos() + axis * 20f32.to_radians().sin();
        let along_u = b.eval::<3>(n, tilt(t))[0];
        let along_v = b.eval::<3>(n, tilt(bt))[0];
        assert!(along_u > 10.0 * along_v, "{dist:?}: {along_u} vs {along_v}");
    }
}

#[test]
fn roughness_applies_per_hit() {
    let iso = Bsdf::Conductor(Conductor::new(
        [0.2; 3],
        [3.0; 3],
        [1.0; 3],
        0.1,
        Distribution::Ggx,
    ));
    // a checkerboard of alpha_u over the uv square, alpha_v constant
    let map = Texture::checkerboard([0.3; 3], [0.05; 3], [2.0, 0.0, 0.0, 0.0, 2.0, 0.0]);
    let r = Roughness {
        alpha_u: Alpha::Map(std::sync::Arc::new(map)),
        alpha_v: Alpha::Value(0.05),
    };
    // kalos' v runs up, Mitsuba's down: (0.1, 0.9) is Mitsuba's (0.1, 0.1), color0
    let at = |u: f32, v: f32| r.apply(iso.clone(), crate::math::Vec2::new(u, v), || [0.0, 1.0]);
    match at(0.1, 0.9) {
        Bsdf::Conductor(c) => {
            assert_eq!(c.alpha, 0.3);
            assert_eq!(
                c.aniso.map(|a| (a.alpha_v, a.tangent)),
                Some((0.05, [0.0, 1.0]))
            );
        }
        b => panic!("{b:?}"),
    }
    // where both are 0.05 the conductor is isotropic, and the tangent is never asked
    let b = r.apply(iso, crate::math::Vec2::new(0.3, 0.9), || {
        panic!("not asked")
    });
    match b {
        Bsdf::Conductor(c) => assert_eq!((c.alpha, c.aniso), (0.05, None)),
        b => panic!("{b:?}"),
    }
    // other BSDFs pass unchanged
    assert_eq!(
        r.apply(Bsdf::Black, crate::math::Vec2::ZERO, || [1.0, 0.0]),
        Bsdf::Black
    );
}
