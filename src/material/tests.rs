//! Every BSDF's sample/pdf pair is chi-square tested; every BSDF passes a white-furnace
//! energy test (albedo <= 1); BSDF sampling agrees with uniform sampling of f cos.

use super::*;
use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};
use crate::sampling::{square_to_cosine_hemisphere, square_to_uniform_sphere, PDF_UNIFORM_SPHERE};

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
    let d = Dielectric {
        eta: 1.5,
        tint: super::dielectric::Tint::NONE,
    };
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

// ---- Microfacet models ----

const GGX: Distribution = Distribution::Ggx;
const BECKMANN: Distribution = Distribution::Beckmann;

fn gold_of(dist: Distribution, alpha: f32) -> Bsdf {
    // Mitsuba's Au at its RGB wavelengths (roughly)
    Bsdf::Conductor(Conductor::new(
        [0.143, 0.374, 1.442],
        [3.983, 2.385, 1.603],
        [1.0; 3],
        alpha,
        dist,
    ))
}

fn gold(alpha: f32) -> Bsdf {
    gold_of(GGX, alpha)
}

fn rough_plastic_of(dist: Distribution, kd: f32, alpha: f32, nonlinear: bool) -> Bsdf {
    Bsdf::Plastic(Plastic::new(
        [kd, kd * 0.6, kd * 0.3],
        [1.0; 3],
        1.49,
        alpha,
        dist,
        nonlinear,
    ))
}

fn rough_plastic(kd: f32, alpha: f32, nonlinear: bool) -> Bsdf {
    rough_plastic_of(GGX, kd, alpha, nonlinear)
}

fn rough_glass(dist: Distribution, eta: f32, alpha: f32) -> Bsdf {
    Bsdf::RoughDielectric(RoughDielectric {
        eta,
        alpha,
        dist,
        tint: super::dielectric::Tint::NONE,
    })
}

/// The non-delta microfacet BSDFs (reflection only unless named "glass").
fn microfacet_bsdfs() -> Vec<(&'static str, Bsdf)> {
    vec![
        ("gold a=0.15", gold(0.15)),
        ("gold a=0.3", gold(0.3)),
        ("gold a=1", gold(1.0)),
        ("rough plastic a=0.15", rough_plastic(0.5, 0.15, false)),
        (
            "rough plastic a=0.4 nonlinear",
            rough_plastic(0.8, 0.4, true),
        ),
        ("smooth plastic", rough_plastic(0.5, 0.0, false)),
        ("glass a=0.2", rough_glass(GGX, 1.5, 0.2)),
        ("glass a=0.6", rough_glass(GGX, 1.33, 0.6)),
        // Beckmann (Mitsuba's default distribution)
        ("beckmann gold a=0.15", gold_of(BECKMANN, 0.15)),
        ("beckmann gold a=0.7", gold_of(BECKMANN, 0.7)),
        (
            "beckmann rough plastic a=0.3",
            rough_plastic_of(BECKMANN, 0.6, 0.3, false),
        ),
        ("beckmann glass a=0.3", rough_glass(BECKMANN, 1.5, 0.3)),
    ]
}

/// wo at `deg` from the normal, on the inside (z < 0) if `inside`.
fn wo_side(deg: f32, inside: bool) -> Vec3 {
    let w = wo_at(deg);
    if inside {
        Vec3::new(w.x, w.y, -w.z)
    } else {
        w
    }
}

fn sides(b: &Bsdf) -> &'static [bool] {
    if b.transmits() {
        &[false, true]
    } else {
        &[false]
    }
}

#[test]
fn chi2_microfacet_sampling() {
    for (k, (name, b)) in microfacet_bsdfs().into_iter().enumerate() {
        // (the refracted lobe is narrow; near the pole the test's quadrature of the pdf is
        // not accurate enough for it, so glass is tested away from normal incidence)
        let angles = if b.transmits() {
            [25.0f32, 50.0, 80.0]
        } else {
            [0.0f32, 40.0, 80.0]
        };
        for &inside in sides(&b) {
            for (j, deg) in angles.into_iter().enumerate() {
                let wo = wo_side(deg, inside);
                // Dirac samples (the smooth coat) are not in the pdf: a cell of their own
                let r = chi2_sphere(
                    |u1, u2| b.sample::<3>(wo, u1, u2).filter(|s| !s.delta).map(|s| s.wi),
                    |wi| b.pdf(wo, wi),
                    200_000,
                    (k * 10 + j) as u64 + 700 + inside as u64 * 5,
                );
                assert_chi2(&format!("{name} at {deg} deg (inside {inside})"), &r);
            }
        }
    }
}

#[test]
fn chi2_microfacet_lobes() {
    for (k, (name, b)) in microfacet_bsdfs().into_iter().enumerate() {
        let (lobes, n) = b.lobe_array();
        for (i, lobe) in lobes[..n].iter().enumerate() {
            let wo = wo_at(55.0);
            let r = chi2_sphere(
                |_, u| lobe.sample_dir(wo, u),
                |wi| lobe.pdf(wo, wi),
                200_000,
                900 + (k * 4 + i) as u64,
            );
            assert_chi2(&format!("{name} lobe {i}"), &r);
        }
    }
}

#[test]
fn microfacet_sample_weight_is_f_cos_over_pdf() {
    let mut rng = TestRng::new(17);
    for (name, b) in microfacet_bsdfs() {
        for &inside in sides(&b) {
            let wo = wo_side(35.0, inside);
            let mut seen = 0;
            for _ in 0..2000 {
                let Some(s) = b.sample::<3>(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                if s.delta {
                    continue;
                }
                seen += 1;
                let pdf = b.pdf(wo, s.wi);
                let expect = b.eval::<3>(wo, s.wi) * (s.wi.z.abs() / pdf);
                for c in 0..3 {
                    assert!(
                        (s.weight[c] - expect[c]).abs() <= 2e-3 * expect[c].max(1.0),
                        "{name}: weight {:?} vs f cos / pdf {:?}",
                        s.weight,
                        expect
                    );
                }
                assert!(
                    (s.pdf - pdf).abs() <= 2e-3 * pdf,
                    "{name}: pdf {} vs {pdf}",
                    s.pdf
                );
            }
            assert!(seen > 500, "{name}: only {seen} non-Dirac samples");
        }
    }
}

#[test]
fn microfacet_sampling_agrees_with_uniform_sampling() {
    // E[weight] under the BSDF's sampling = integral of f |cos| by uniform sampling.
    for (name, b) in microfacet_bsdfs() {
        for &inside in sides(&b) {
            let wo = wo_side(50.0, inside);
            let mut rng = TestRng::new(31);
            let n = 400_000;
            let (mut a, mut a2, mut m, mut m2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for _ in 0..n {
                let w = b
                    .sample::<3>(wo, rng.next_f32(), rng.next_2d())
                    .filter(|s| !s.delta)
                    .map(|s| s.weight.average() as f64)
                    .unwrap_or(0.0);
                a += w;
                a2 += w * w;
                let wi = square_to_uniform_sphere(rng.next_2d());
                let v = (b.eval::<3>(wo, wi).average() * wi.z.abs() / PDF_UNIFORM_SPHERE) as f64;
                m += v;
                m2 += v * v;
            }
            let nf = n as f64;
            let (a, m) = (a / nf, m / nf);
            let se = ((a2 / nf - a * a) / nf + (m2 / nf - m * m) / nf).sqrt();
            assert!(
                (a - m).abs() < 4.0 * se + 1e-4,
                "{name} (inside {inside}): sampled {a} vs uniform {m} (se {se})"
            );
        }
    }
}

/// Mean and standard error of the energy a sample carries: its weight, with the
/// radiance scaling of refraction undone (importance), over `n` samples.
pub(super) fn energy(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = TestRng::new(seed);
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let w = b
            .sample::<3>(wo, rng.next_f32(), rng.next_2d())
            .map(|s| (s.weight.average() * b.adjoint_scale(wo, s.wi)) as f64)
            .unwrap_or(0.0);
        s += w;
        s2 += w * w;
    }
    let m = s / n as f64;
    (m, ((s2 / n as f64 - m * m) / n as f64).max(0.0).sqrt())
}

#[test]
fn microfacet_white_furnace() {
    let white_metal_of =
        |dist, alpha| Bsdf::Conductor(Conductor::new([0.0; 3], [1e4; 3], [1.0; 3], alpha, dist));
    let white_metal = |alpha| white_metal_of(GGX, alpha);
    let cases: Vec<(&str, Bsdf, Option<f64>)> = vec![
        // F = 1: the smooth perfect conductor reflects everything
        ("perfect conductor", white_metal(0.0), Some(1.0)),
        (
            "perfect rough conductor a=0.01",
            white_metal(0.01),
            Some(1.0),
        ),
        ("perfect rough conductor a=0.5", white_metal(0.5), None),
        ("perfect rough conductor a=1", white_metal(1.0), None),
        (
            "beckmann perfect rough conductor a=0.01",
            white_metal_of(BECKMANN, 0.01),
            Some(1.0),
        ),
        (
            "beckmann perfect rough conductor a=0.6",
            white_metal_of(BECKMANN, 0.6),
            None,
        ),
        // eta = 1, k = 0: no interface, F = 0, nothing reflected
        (
            "index-matched conductor",
            Bsdf::Conductor(Conductor::new([1.0; 3], [0.0; 3], [1.0; 3], 0.3, GGX)),
            Some(0.0),
        ),
        ("gold a=0.3", gold(0.3), None),
        (
            "smooth dielectric",
            Bsdf::Dielectric(Dielectric {
                eta: 1.5,
                tint: super::dielectric::Tint::NONE,
            }),
            Some(1.0),
        ),
        (
            "thin dielectric",
            Bsdf::ThinDielectric(ThinDielectric {
                eta: 1.5,
                tint: super::dielectric::Tint::NONE,
            }),
            Some(1.0),
        ),
        (
            "rough dielectric a=0.01",
            rough_glass(GGX, 1.5, 0.01),
            Some(1.0),
        ),
        ("rough dielectric a=0.5", rough_glass(GGX, 1.5, 0.5), None),
        (
            "beckmann rough dielectric a=0.01",
            rough_glass(BECKMANN, 1.5, 0.01),
            Some(1.0),
        ),
        (
            "beckmann rough dielectric a=0.5",
            rough_glass(BECKMANN, 1.5, 0.5),
            None,
        ),
        (
            "white rough plastic a=0.3",
            Bsdf::Plastic(Plastic::new([1.0; 3], [1.0; 3], 1.5, 0.3, GGX, false)),
            None,
        ),
        (
            "beckmann white rough plastic a=0.3",
            Bsdf::Plastic(Plastic::new([1.0; 3], [1.0; 3], 1.5, 0.3, BECKMANN, false)),
            None,
        ),
    ];
    for (name, b, exact) in &cases {
        for &inside in sides(b) {
            for deg in [0.0f32, 30.0, 60.0, 85.0] {
                let (a, se) = energy(b, wo_side(deg, inside), 100_000, 41);
                assert!(
                    a <= 1.0 + 4.0 * se + 1e-4,
                    "{name} at {deg}: albedo {a} > 1"
                );
                if let Some(e) = exact {
                    // grazing angles lose a little to shadowing even at small roughness
                    let tol = if deg > 80.0 { 0.02 } else { 2e-3 };
                    assert!(
                        (a - e).abs() < tol + 4.0 * se,
                        "{name} at {deg} (inside {inside}): albedo {a} != {e}"
                    );
                }
            }
        }
    }
    // The white smooth plastic reflects all: F + t_i (1 - Fdr_ext) / (eta^2 (1 - Fdr_int))
    // = 1 by the reciprocity of the coat, up to Mitsuba's fits of Fdr (within 0.5%).
    let b = Bsdf::Plastic(Plastic::new([1.0; 3], [1.0; 3], 1.5, 0.0, GGX, false));
    for deg in [0.0f32, 45.0, 80.0] {
        let (a, se) = energy(&b, wo_at(deg), 200_000, 43);
        assert!(
            (a - 1.0).abs() < 5e-3 + 4.0 * se,
            "white smooth plastic at {deg}: {a}"
        );
    }
}

#[test]
fn microfacet_reciprocity() {
    let mut rng = TestRng::new(53);
    for (name, b) in microfacet_bsdfs() {
        for _ in 0..2000 {
            let wo = square_to_uniform_sphere(rng.next_2d());
            let wi = square_to_uniform_sphere(rng.next_2d());
            let (a, r) = (b.eval::<3>(wo, wi), b.eval::<3>(wi, wo));
            // generalised reciprocity of refraction: f(wi, wo) = (eta_i / eta_o)^2 f(wo, wi)
            let k = b.adjoint_scale(wo, wi);
            for c in 0..3 {
                let (x, y) = (a[c] * k, r[c]);
                assert!(
                    (x - y).abs() <= 1e-3 * x.abs().max(y.abs()).max(1e-3),
                    "{name}: f(wo, wi) k = {x} vs f(wi, wo) = {y} for wo {wo} wi {wi}"
                );
            }
        }
    }
}

#[test]
fn conductor_fresnel_known_values() {
    use conductor::fresnel_conductor;
    // k = 0 is a dielectric: normal incidence ((eta - 1) / (eta + 1))^2
    let f = fresnel_conductor(1.0, 1.5, 0.0);
    assert!((f - 0.04).abs() < 1e-5, "{f}");
    // and agrees with the dielectric formula at an angle
    let fd = dielectric::fresnel_dielectric(0.6, 1.5).0;
    assert!((fresnel_conductor(0.6, 1.5, 0.0) - fd).abs() < 1e-5);
    // normal incidence: ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2)
    let (eta, k) = (0.2f32, 3.0f32);
    let want = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
    assert!((fresnel_conductor(1.0, eta, k) - want).abs() < 1e-5);
    // grazing: 1
    assert!((fresnel_conductor(0.0, eta, k) - 1.0).abs() < 1e-5);
}

#[test]
fn plastic_coat_tables() {
    use plastic::{fresnel_diffuse_reflectance, CoatTable};
    // A nearly smooth rough coat transmits 1 - F(mu) and reflects the diffuse Fresnel
    // reflectance from inside.
    let t = CoatTable::get(1.5, 0.002, GGX);
    for mu in [0.2f32, 0.5, 0.9, 1.0] {
        let want = 1.0 - dielectric::fresnel_dielectric(mu, 1.5).0;
        assert!(
            (t.transmittance(mu) - want).abs() < 3e-3,
            "t({mu}) {} vs {want}",
            t.transmittance(mu)
        );
    }
    let fdr = fresnel_diffuse_reflectance(1.0 / 1.5);
    assert!(
        (t.r_int - fdr).abs() < 0.01,
        "r_int {} vs Fdr {fdr}",
        t.r_int
    );
    // the fits against the integral 2 int F mu dmu
    for eta in [1.33f32, 1.5, 1.0 / 1.5] {
        let n = 20000;
        let exact: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * mu * dielectric::fresnel_dielectric(mu as f32, eta).0 as f64 / n as f64
            })
            .sum();
        let fit = fresnel_diffuse_reflectance(eta) as f64;
        assert!(
            (fit - exact).abs() < 0.01 * exact.max(0.05),
            "eta {eta}: fit {fit} vs {exact}"
        );
    }
    // ... and so does a nearly smooth Beckmann coat
    let b = CoatTable::get(1.5, 0.002, BECKMANN);
    for mu in [0.2f32, 0.5, 0.9, 1.0] {
        let want = 1.0 - dielectric::fresnel_dielectric(mu, 1.5).0;
        assert!(
            (b.transmittance(mu) - want).abs() < 3e-3,
            "Beckmann t({mu})"
        );
    }
    assert!((b.r_int - fdr).abs() < 0.01, "Beckmann r_int {}", b.r_int);
    // the cache hands out one table per (eta, alpha, distribution)
    assert!(std::ptr::eq(
        CoatTable::get(1.5, 0.3, GGX),
        CoatTable::get(1.5, 0.3, GGX)
    ));
    assert!(!std::ptr::eq(
        CoatTable::get(1.5, 0.3, GGX),
        CoatTable::get(1.5, 0.3, BECKMANN)
    ));
}

#[test]
fn rough_plastic_lobes_sum_to_the_bsdf() {
    let b = rough_plastic(0.6, 0.25, false);
    let (lobes, n) = b.lobe_array();
    assert_eq!(n, 2);
    let mut rng = TestRng::new(61);
    for _ in 0..500 {
        let wo = square_to_cosine_hemisphere(rng.next_2d());
        let wi = square_to_cosine_hemisphere(rng.next_2d());
        let sum = lobes[0].eval::<3>(wo, wi) + lobes[1].eval::<3>(wo, wi);
        let f = b.eval::<3>(wo, wi);
        for c in 0..3 {
            assert!((sum[c] - f[c]).abs() <= 1e-6 * f[c].max(1.0));
        }
    }
}

/// Every hit moves a `Bsdf` around (built per hit, held per path vertex): the principled
/// BSDF's 17 parameters behind a box and a conductor's optical constants shared keep it
/// below the size it had before either existed (48 bytes on 2026-12-05, e91aa28; 72 with
/// them inline), so that scenes of the common BSDFs do not pay for the rare large ones.
#[test]
fn bsdf_stays_small() {
    let n = std::mem::size_of::<Bsdf>();
    eprintln!(
        "size_of Bsdf {n}, Conductor {}, Plastic {}, Principled {}",
        std::mem::size_of::<Conductor>(),
        std::mem::size_of::<Plastic>(),
        std::mem::size_of::<Principled>()
    );
    assert!(n <= 40, "Bsdf is {n} bytes");
}
