//! Tests of the thin principled BSDF: known answers from Mitsuba 3.9.1 (both sides, both
//! hemispheres) and chi-square tests of its sampling.

use super::*;
use crate::material::principled::tests::{
    assert_agrees_with_mitsuba, assert_sampling_follows_pdf, Row,
};
use crate::material::Bsdf;
use crate::sampling::chi2::TestRng;

/// The parameter sets of bench/mitsuba-principled-values.py's `THIN_CASES`.
fn cases() -> [PrincipledThin; 3] {
    let d = PrincipledThin::default();
    [
        PrincipledThin {
            base_color: [0.7, 0.1, 0.1],
            anisotropic: 0.8,
            spec_trans: 0.6,
            diff_trans: 1.4,
            sheen: 0.8,
            eta: 1.33,
            ..d
        },
        PrincipledThin {
            base_color: [0.3, 0.6, 0.8],
            roughness: 0.3,
            spec_trans: 0.3,
            diff_trans: 0.4,
            specular_tint: 0.5,
            sheen: 0.3,
            sheen_tint: 0.6,
            flatness: 0.4,
            ..d
        },
        PrincipledThin {
            base_color: [0.9, 0.8, 0.2],
            roughness: 0.6,
            anisotropic: 0.3,
            spec_trans: 0.9,
            eta: 1.2,
            ..d
        },
    ]
}

/// Mitsuba 3.9.1's eval (f |cos theta_o|) and pdf, printed by
/// bench/mitsuba-principled-values.py: (case, wi, wo, eval, pdf), Mitsuba's wi being
/// kalos' wo.
#[rustfmt::skip]
#[allow(clippy::excessive_precision, clippy::approx_constant)]
const MITSUBA: &[Row] = &[
    (0, [3.8302222e-01, 3.2139380e-01, 8.6602540e-01], [-1.9617469e-01, -5.3898554e-01, 8.1915204e-01], [2.6770711e-02, 7.9961075e-03, 7.9961075e-03], 1.4582871e-01),
    (0, [-3.8302222e-01, 6.6341395e-01, 6.4278761e-01], [2.9619813e-01, -8.1379768e-01, 5.0000000e-01], [2.6168745e-02, 1.4780029e-02, 1.4780029e-02], 1.6865690e-01),
    (0, [3.4202014e-01, 0.0000000e+00, 9.3969262e-01], [-7.6975113e-01, 2.8016650e-01, 5.7357644e-01], [1.7288938e-02, 4.1179834e-03, 4.1179834e-03], 6.7448489e-02),
    (0, [5.5667040e-01, 3.2139380e-01, 7.6604444e-01], [-3.2139380e-01, -3.8302222e-01, -8.6602540e-01], [8.8688797e-01, 1.2669829e-01, 1.2669829e-01], 6.8585473e-01),
    (0, [3.2139380e-01, 5.5667040e-01, -7.6604444e-01], [-1.7101007e-01, -4.6984631e-01, 8.6602540e-01], [7.2521299e-01, 1.0360185e-01, 1.0360185e-01], 5.6758690e-01),
    (0, [4.6984631e-01, 1.7101007e-01, -8.6602540e-01], [-6.3302222e-01, -1.1161890e-01, -7.6604444e-01], [3.5612863e-02, 1.8054154e-02, 1.8054154e-02], 3.8281494e-01),
    (1, [5.0000000e-01, 0.0000000e+00, 8.6602540e-01], [-6.4278761e-01, 7.8718779e-17, 7.6604444e-01], [6.6787824e-02, 1.1385272e-01, 1.4522934e-01], 5.9297532e-01),
    (1, [1.7364818e-01, 0.0000000e+00, 9.8480775e-01], [5.3028762e-17, 8.6602540e-01, 5.0000000e-01], [2.5053661e-02, 5.0048918e-02, 6.6712424e-02], 9.0500183e-02),
    (1, [9.3969262e-01, 0.0000000e+00, 3.4202014e-01], [-3.2139380e-01, -1.1697778e-01, 9.3969262e-01], [4.9022324e-02, 9.7567625e-02, 1.2993115e-01], 1.7441402e-01),
    (1, [7.0710678e-01, 0.0000000e+00, 7.0710678e-01], [-5.0000000e-01, 6.1232340e-17, -8.6602540e-01], [4.7479421e-02, 9.4958842e-02, 1.2661178e-01], 1.0120350e-01),
    (1, [3.4202014e-01, 0.0000000e+00, -9.3969262e-01], [-5.0000000e-01, 6.1232340e-17, 8.6602540e-01], [1.2765524e-01, 2.5531048e-01, 3.4041399e-01], 2.4028116e-01),
    (1, [5.0000000e-01, 0.0000000e+00, -8.6602540e-01], [-6.3302222e-01, 1.1161890e-01, -7.6604444e-01], [5.6773197e-02, 1.0048992e-01, 1.2963443e-01], 4.3910393e-01),
    (2, [3.8302222e-01, 3.2139380e-01, 8.6602540e-01], [-1.9617469e-01, -5.3898554e-01, 8.1915204e-01], [2.7275246e-02, 2.4667572e-02, 9.0215243e-03], 2.4130644e-01),
    (2, [-3.8302222e-01, 6.6341395e-01, 6.4278761e-01], [2.9619813e-01, -8.1379768e-01, 5.0000000e-01], [2.6188809e-02, 2.4603106e-02, 1.5088892e-02], 3.0888787e-01),
    (2, [3.4202014e-01, 0.0000000e+00, 9.3969262e-01], [-7.6975113e-01, 2.8016650e-01, 5.7357644e-01], [1.8501723e-02, 1.6669139e-02, 5.6736362e-03], 1.2874529e-01),
    (2, [5.5667040e-01, 3.2139380e-01, 7.6604444e-01], [-3.2139380e-01, -3.8302222e-01, -8.6602540e-01], [8.2956290e-01, 7.3738933e-01, 1.8434733e-01], 4.6538803e-01),
    (2, [3.2139380e-01, 5.5667040e-01, -7.6604444e-01], [-1.7101007e-01, -4.6984631e-01, 8.6602540e-01], [1.7933649e+00, 1.5941019e+00, 3.9852548e-01], 1.0060847e+00),
    (2, [4.6984631e-01, 1.7101007e-01, -8.6602540e-01], [-6.3302222e-01, -1.1161890e-01, -7.6604444e-01], [2.7089145e-02, 2.4650192e-02, 1.0016464e-02], 3.0536735e-01),
];

#[test]
fn principledthin_agrees_with_mitsuba() {
    let cases = cases();
    assert_agrees_with_mitsuba(
        MITSUBA,
        |k, wi, wo| cases[k].eval_cos(wi, wo),
        |k| Bsdf::PrincipledThin(Box::new(cases[k])),
    );
}

/// Sampling follows `pdf` (chi-square) from both sides, and its weight is f cos / pdf
/// (anisotropic lobes with their tangent turned off the local axes).
#[test]
fn chi2_principledthin_sampling() {
    let mut rng = TestRng::new(17);
    for (k, b) in cases().into_iter().enumerate() {
        let b = PrincipledThin {
            tangent: [0.6f32.cos(), 0.6f32.sin()],
            ..b
        };
        let bsdf = Bsdf::PrincipledThin(Box::new(b));
        let name = format!("principledthin {k}");
        assert_sampling_follows_pdf(&name, &bsdf, 0.3, 1700 + 10 * k as u64, &mut rng);
    }
}

/// A thin surface is symmetric: the same from both sides (directions negated).
#[test]
fn principledthin_is_symmetric() {
    for b in cases() {
        for &(_, wi, wo, _, _) in MITSUBA {
            let (wi, wo) = (Vec3::from(wi), Vec3::from(wo));
            assert_eq!(b.eval_cos(wi, wo), b.eval_cos(-wi, -wo));
            assert_eq!(b.pdf(wi, wo), b.pdf(-wi, -wo));
        }
    }
}
