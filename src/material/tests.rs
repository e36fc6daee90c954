//! Every BSDF's sample/pdf pair is chi-square tested; every BSDF passes a white-furnace
//! energy test (albedo <= 1); BSDF sampling agrees with uniform sampling of f cos.

use super::*;
use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};
use crate::sampling::{square_to_uniform_sphere, PDF_UNIFORM_SPHERE};

fn wo_at(deg: f32) -> Vec3 {
    let t = deg.to_radians();
    Vec3::new(t.sin() * 0.8, t.sin() * 0.6, t.cos()).normalize()
}

fn non_delta_bsdfs() -> Vec<(&'static str, Bsdf)> {
    vec![
        (
            "lambert",
            Bsdf::Diffuse(Lambert {
                kd: [0.8, 0.5, 0.2],
            }),
        ),
        (
            "phong n=5",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.0; 3] },
                Phong {
                    ks: [0.9; 3],
                    n: 5.0,
                },
            ),
        ),
        (
            "phong n=80",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.0; 3] },
                Phong {
                    ks: [0.7; 3],
                    n: 80.0,
                },
            ),
        ),
        (
            "diffuse+phong",
            Bsdf::DiffuseGlossy(
                Lambert {
                    kd: [0.5, 0.3, 0.3],
                },
                Phong {
                    ks: [0.4; 3],
                    n: 15.0,
                },
            ),
        ),
        (
            "floor of the paper (ks 0.6, n 15)",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.3; 3] },
                Phong {
                    ks: [0.6; 3],
                    n: 15.0,
                },
            ),
        ),
    ]
}

#[test]
fn chi2_bsdf_sampling() {
    for (k, (name, b)) in non_delta_bsdfs().into_iter().enumerate() {
        for (j, deg) in [0.0f32, 40.0, 80.0].into_iter().enumerate() {
            let wo = wo_at(deg);
            let r = chi2_sphere(
                |u1, u2| b.sample::<3>(wo, u1, u2).map(|s| s.wi),
                |wi| b.pdf(wo, wi),
                200_000,
                (k * 10 + j) as u64 + 100,
            );
            assert_chi2(&format!("{name} at {deg} deg"), &r);
        }
    }
}

#[test]
fn chi2_elementary_lobes() {
    let lobes = [
        Lobe::Diffuse(Lambert { kd: [1.0; 3] }),
        Lobe::Glossy(Phong {
            ks: [1.0; 3],
            n: 3.0,
        }),
        Lobe::Glossy(Phong {
            ks: [1.0; 3],
            n: 40.0,
        }),
    ];
    for (k, lobe) in lobes.iter().enumerate() {
        for deg in [10.0f32, 70.0] {
            let wo = wo_at(deg);
            let r = chi2_sphere(
                |_, u| lobe.sample_dir(wo, u),
                |wi| lobe.pdf(wo, wi),
                200_000,
                300 + k as u64,
            );
            assert_chi2(&format!("lobe {lobe:?} at {deg}"), &r);
        }
    }
}

#[test]
fn sample_weight_is_f_cos_over_pdf() {
    let mut rng = TestRng::new(7);
    for (name, b) in non_delta_bsdfs() {
        let wo = wo_at(30.0);
        for _ in 0..1000 {
            if let Some(s) = b.sample::<3>(wo, rng.next_f32(), rng.next_2d()) {
                let expect = b.eval::<3>(wo, s.wi) * (s.wi.z / b.pdf(wo, s.wi));
                for c in 0..3 {
                    assert!(
                        (s.weight[c] - expect[c]).abs() <= 1e-4 * expect[c].max(1.0),
                        "{name}"
                    );
                }
                assert!((s.pdf - b.pdf(wo, s.wi)).abs() <= 1e-4 * s.pdf, "{name}");
            }
        }
    }
}

/// Mean and standard error of the sampled weights: the directional albedo.
fn albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = TestRng::new(seed);
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let w = b
            .sample::<3>(wo, rng.next_f32(), rng.next_2d())
            .map(|s| s.weight.average() as f64)
            .unwrap_or(0.0);
        s += w;
        s2 += w * w;
    }
    let m = s / n as f64;
    (m, ((s2 / n as f64 - m * m) / n as f64).max(0.0).sqrt())
}

#[test]
fn white_furnace_energy() {
    let white = [
        ("lambert", Bsdf::Diffuse(Lambert { kd: [1.0; 3] })),
        (
            "phong n=1",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.0; 3] },
                Phong {
                    ks: [1.0; 3],
                    n: 1.0,
                },
            ),
        ),
        (
            "phong n=20",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.0; 3] },
                Phong {
                    ks: [1.0; 3],
                    n: 20.0,
                },
            ),
        ),
        (
            "half+half",
            Bsdf::DiffuseGlossy(
                Lambert { kd: [0.5; 3] },
                Phong {
                    ks: [0.5; 3],
                    n: 10.0,
                },
            ),
        ),
        ("mirror", Bsdf::Mirror(Mirror { ks: [1.0; 3] })),
    ];
    for (name, b) in white {
        for deg in [0.0f32, 30.0, 60.0, 85.0] {
            let (a, se) = albedo(&b, wo_at(deg), 100_000, 11);
            assert!(
                a <= 1.0 + 4.0 * se + 1e-6,
                "{name} at {deg}: albedo {a} > 1"
            );
            if name == "lambert" || name == "mirror" {
                assert!((a - 1.0).abs() < 1e-5, "{name}: albedo {a} != 1");
            }
            if deg == 0.0 && name.starts_with("phong") {
                // the normalised lobe reflects all at normal incidence (minus the part cut
                // off by the horizon, which is small for these lobes)
                assert!(a > 0.9, "{name}: normal-incidence albedo {a}");
            }
        }
    }
}

#[test]
fn bsdf_sampling_agrees_with_uniform_sampling() {
    // Two estimators of the same integral of f cos: importance sampled vs uniform sphere.
    for (name, b) in non_delta_bsdfs() {
        let wo = wo_at(35.0);
        let (a, se_a) = albedo(&b, wo, 200_000, 21);
        let mut rng = TestRng::new(22);
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        let n = 400_000;
        for _ in 0..n {
            let wi = square_to_uniform_sphere(rng.next_2d());
            let v = (b.eval::<3>(wo, wi).average() * wi.z.max(0.0) / PDF_UNIFORM_SPHERE) as f64;
            s += v;
            s2 += v * v;
        }
        let m = s / n as f64;
        let se_b = ((s2 / n as f64 - m * m) / n as f64).sqrt();
        let tol = 4.0 * (se_a * se_a + se_b * se_b).sqrt();
        assert!(
            (a - m).abs() < tol,
            "{name}: sampled {a} vs uniform {m} (tol {tol})"
        );
    }
}

#[test]
fn dielectric_fresnel_and_snell() {
    let d = Dielectric { eta: 1.5 };
    let f0 = d.reflectance(Vec3::Z);
    assert!((f0 - 0.04).abs() < 1e-4, "F(0) = {f0}");
    // total internal reflection from inside beyond the critical angle
    let inside = Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt());
    assert_eq!(d.reflectance(inside), 1.0);
    // refraction obeys Snell's law and the radiance scaling (eta_o/eta_i)^2
    let wo = wo_at(50.0);
    let s = d.sample::<3>(wo, 0.999).unwrap();
    assert!(s.wi.z < 0.0 && s.delta);
    let sin_o = (1.0 - wo.z * wo.z).sqrt();
    let sin_i = (1.0 - s.wi.z * s.wi.z).sqrt();
    assert!((sin_o - 1.5 * sin_i).abs() < 1e-5);
    assert!((s.weight[0] - 1.0 / 2.25).abs() < 1e-5);
    // reflection probability equals F
    let mut rng = TestRng::new(3);
    let n = 100_000;
    let refl = (0..n)
        .filter(|_| d.sample::<3>(wo, rng.next_f32()).unwrap().wi.z > 0.0)
        .count();
    let f = d.reflectance(wo) as f64;
    assert!((refl as f64 / n as f64 - f).abs() < 4.0 * (f * (1.0 - f) / n as f64).sqrt() + 1e-4);
}

#[test]
fn from_mtl_picks_the_model() {
    assert!(matches!(
        Bsdf::from_mtl([0.5; 3], [0.0; 3], 1.0, 1.5, 2),
        Bsdf::Diffuse(_)
    ));
    assert!(matches!(
        Bsdf::from_mtl([0.5; 3], [0.5; 3], 10.0, 1.5, 2),
        Bsdf::DiffuseGlossy(..)
    ));
    assert!(matches!(
        Bsdf::from_mtl([0.5; 3], [0.0; 3], 1.0, 1.5, 5),
        Bsdf::Mirror(_)
    ));
    assert!(matches!(
        Bsdf::from_mtl([0.5; 3], [0.0; 3], 1.0, 1.5, 7),
        Bsdf::Dielectric(_)
    ));
    assert!(matches!(
        Bsdf::from_mtl([0.0; 3], [0.0; 3], 1.0, 1.5, 2),
        Bsdf::Black
    ));
}
