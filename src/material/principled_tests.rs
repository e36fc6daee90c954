//! Tests of the principled BSDF: known answers from Mitsuba 3.9.1 and chi-square tests of
//! its sampling.

use super::*;
use crate::material::Bsdf;
use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};

/// The parameter sets of bench/mitsuba-principled-values.py.
fn cases() -> [Principled; 3] {
    let d = Principled::default();
    [
        Principled {
            base_color: [0.2, 0.8, 0.1],
            roughness: 0.15,
            metallic: 0.7,
            clearcoat: 0.9,
            sheen: 0.2,
            eta: eta_of_specular(0.7),
            ..d
        },
        Principled {
            base_color: [0.3, 0.6, 0.8],
            roughness: 0.4,
            spec_trans: 0.7,
            clearcoat: 0.6,
            clearcoat_gloss: 0.3,
            sheen: 0.9,
            sheen_tint: 0.5,
            specular_tint: 0.4,
            eta: eta_of_specular(0.4),
            ..d
        },
        Principled {
            base_color: [0.9, 0.5, 0.3],
            roughness: 0.6,
            flatness: 0.5,
            eta: 1.33,
            spec_trans: 0.3,
            metallic: 0.2,
            ..d
        },
    ]
}

/// Mitsuba 3.9.1's eval (f |cos theta_o|) and pdf, printed by
/// bench/mitsuba-principled-values.py: (case, wi, wo, eval, pdf), Mitsuba's wi being
/// kalos' wo.
type Row = (usize, [f32; 3], [f32; 3], [f32; 3], f32);
#[rustfmt::skip]
#[allow(clippy::excessive_precision, clippy::approx_constant)]
const MITSUBA: &[Row] = &[
    (0, [5.0000000e-01, 0.0000000e+00, 8.6602540e-01], [-6.4278761e-01, 7.8718779e-17, 7.6604444e-01], [1.5326731e-01, 4.9494573e-01, 9.6320897e-02], 6.8824381e-01),
    (0, [1.7364818e-01, 0.0000000e+00, 9.8480775e-01], [5.3028762e-17, 8.6602540e-01, 5.0000000e-01], [1.0659464e-02, 3.9310805e-02, 5.8842404e-03], 4.1044198e-02),
    (0, [9.3969262e-01, 0.0000000e+00, 3.4202014e-01], [-3.2139380e-01, -1.1697778e-01, 9.3969262e-01], [2.0485613e-02, 7.3323488e-02, 1.1679303e-02], 7.6567754e-02),
    (0, [7.0710678e-01, 0.0000000e+00, 7.0710678e-01], [-5.0000000e-01, 6.1232340e-17, -8.6602540e-01], [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (0, [3.4202014e-01, 0.0000000e+00, -9.3969262e-01], [-5.0000000e-01, 6.1232340e-17, 8.6602540e-01], [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (0, [5.0000000e-01, 0.0000000e+00, -8.6602540e-01], [-6.3302222e-01, 1.1161890e-01, -7.6604444e-01], [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 3.4014010e-01),
    (1, [5.0000000e-01, 0.0000000e+00, 8.6602540e-01], [-6.4278761e-01, 7.8718779e-17, 7.6604444e-01], [1.0361734e-01, 1.4056033e-01, 1.6518898e-01], 6.8261999e-01),
    (1, [1.7364818e-01, 0.0000000e+00, 9.8480775e-01], [5.3028762e-17, 8.6602540e-01, 5.0000000e-01], [1.5729116e-02, 3.0282395e-02, 3.9984580e-02], 4.4591472e-02),
    (1, [9.3969262e-01, 0.0000000e+00, 3.4202014e-01], [-3.2139380e-01, -1.1697778e-01, 9.3969262e-01], [3.3435177e-02, 6.1348289e-02, 7.9957031e-02], 9.9619024e-02),
    (1, [7.0710678e-01, 0.0000000e+00, 7.0710678e-01], [-5.0000000e-01, 6.1232340e-17, -8.6602540e-01], [1.3665780e+01, 1.9326332e+01, 2.2316124e+01], 3.5543896e+01),
    (1, [3.4202014e-01, 0.0000000e+00, -9.3969262e-01], [-5.0000000e-01, 6.1232340e-17, 8.6602540e-01], [3.3613831e+01, 4.7537132e+01, 5.4891148e+01], 4.2623306e+01),
    (1, [5.0000000e-01, 0.0000000e+00, -8.6602540e-01], [-6.3302222e-01, 1.1161890e-01, -7.6604444e-01], [7.3704630e-02, 7.3704630e-02, 7.3704630e-02], 1.0576469e-01),
    (2, [5.0000000e-01, 0.0000000e+00, 8.6602540e-01], [-6.4278761e-01, 7.8718779e-17, 7.6604444e-01], [2.3137458e-01, 1.3345653e-01, 8.4497511e-02], 3.9909339e-01),
    (2, [1.7364818e-01, 0.0000000e+00, 9.8480775e-01], [5.3028762e-17, 8.6602540e-01, 5.0000000e-01], [8.9049093e-02, 5.0038505e-02, 3.0533213e-02], 9.7367734e-02),
    (2, [9.3969262e-01, 0.0000000e+00, 3.4202014e-01], [-3.2139380e-01, -1.1697778e-01, 9.3969262e-01], [2.0408934e-01, 1.1612158e-01, 7.2137691e-02], 2.4542342e-01),
    (2, [7.0710678e-01, 0.0000000e+00, 7.0710678e-01], [-5.0000000e-01, 6.1232340e-17, -8.6602540e-01], [1.6991705e+00, 1.2664870e+00, 9.8101664e-01], 2.0526297e+00),
    (2, [3.4202014e-01, 0.0000000e+00, -9.3969262e-01], [-5.0000000e-01, 6.1232340e-17, 8.6602540e-01], [4.0803671e+00, 3.0413263e+00, 2.3558013e+00], 1.0239520e+01),
    (2, [5.0000000e-01, 0.0000000e+00, -8.6602540e-01], [-6.3302222e-01, 1.1161890e-01, -7.6604444e-01], [4.6280040e-03, 4.6280040e-03, 4.6280040e-03], 1.9713650e-02),
];

#[test]
fn principled_agrees_with_mitsuba() {
    let cases = cases();
    for &(k, wi, wo, f, pdf) in MITSUBA {
        let b = cases[k];
        let (wi, wo) = (Vec3::from(wi), Vec3::from(wo));
        let v = b.eval_cos(wi, wo);
        for c in 0..3 {
            assert!(
                (v[c] - f[c]).abs() <= 2e-4 * f[c].abs().max(1e-2),
                "case {k} wi {wi} wo {wo}: eval {v:?}, Mitsuba {f:?}"
            );
        }
        let p = b.pdf(wi, wo);
        assert!(
            (p - pdf).abs() <= 2e-4 * pdf.max(1e-2),
            "case {k} wi {wi} wo {wo}: pdf {p}, Mitsuba {pdf}"
        );
        // kalos' eval is f without the cosine
        let e = Bsdf::Principled(Box::new(b)).eval::<3>(wi, wo);
        assert!((e[1] * wo.z.abs() - v[1]).abs() <= 1e-5 * v[1].max(1.0));
    }
}

/// Sampling follows `pdf` (chi-square) from both sides, and its weight is f cos / pdf.
#[test]
fn chi2_principled_sampling() {
    let mut rng = TestRng::new(11);
    for (k, b) in cases().into_iter().enumerate() {
        let bsdf = Bsdf::Principled(Box::new(b));
        for (j, (deg, inside)) in [(10.0f32, false), (60.0, false), (35.0, true)]
            .into_iter()
            .enumerate()
        {
            if inside && !b.transmits() {
                continue;
            }
            let t = deg.to_radians();
            let wo = Vec3::new(t.sin(), 0.0, if inside { -t.cos() } else { t.cos() });
            let r = chi2_sphere(
                |u1, u2| bsdf.sample::<3>(wo, u1, u2).map(|s| s.wi),
                |wi| bsdf.pdf(wo, wi),
                200_000,
                1200 + (k * 10 + j) as u64,
            );
            assert_chi2(&format!("principled {k} at {deg} (inside {inside})"), &r);
            assert_weights_are_f_cos_over_pdf(
                &bsdf,
                wo,
                &mut rng,
                &format!("principled {k}"),
                1e-3,
            );
        }
    }
}

/// Mitsuba's helper formulas at known values.
#[test]
fn principled_helpers_known_values() {
    assert_eq!(schlick_weight(1.0), 0.0);
    assert!((schlick_weight(0.5) - 0.03125).abs() < 1e-7);
    // specular 0.5: eta = 2 / (1 - 0.2) - 1 = 1.5
    assert!((eta_of_specular(0.5) - 1.5).abs() < 1e-6);
    assert!((schlick_r0(1.5) - 0.04).abs() < 1e-6);
    // outside, eta > 1: R0 + (1 - R0) (1 - cos)^5
    assert!((calc_schlick(0.04, 0.5, 1.5) - (0.04 + 0.96 * 0.03125)).abs() < 1e-6);
    // GTR1 integrates to 1 over the projected hemisphere
    let g = Gtr1 { alpha: 0.05 };
    let n = 20000;
    let mut s = 0.0f64;
    for i in 0..n {
        let x = (i as f64 + 0.5) / n as f64;
        let c = 1.0 - x * x;
        let m = Vec3::new((1.0 - c * c).sqrt() as f32, 0.0, c as f32);
        s += g.d(m) as f64 * c * 2.0 * std::f64::consts::PI * 2.0 * x / n as f64;
    }
    assert!((s - 1.0).abs() < 2e-3, "{s}");
}

/// 500 samples of `b` at `wo`: each non-Dirac weight is f |cos| / pdf (within `tol`,
/// relative above 1).
pub(crate) fn assert_weights_are_f_cos_over_pdf(
    b: &Bsdf,
    wo: Vec3,
    rng: &mut TestRng,
    name: &str,
    tol: f32,
) {
    for _ in 0..500 {
        let Some(s) = b.sample::<3>(wo, rng.next_f32(), rng.next_2d()) else {
            continue;
        };
        if s.delta {
            continue;
        }
        let expect = b.eval::<3>(wo, s.wi) * (s.wi.z.abs() / b.pdf(wo, s.wi));
        for c in 0..3 {
            assert!(
                (s.weight[c] - expect[c]).abs() <= tol * expect[c].max(1.0),
                "{name}: {:?} vs {expect:?}",
                s.weight
            );
        }
    }
}
