//! The roulette's pieces against the paper's formulas.

use super::*;
use crate::material::{AlbedoTable, Lambert, Phong};
use crate::sampling::chi2::TestRng;

fn roulette(mode: RrMode, weight: RrWeight, select: BsdfSelect) -> Roulette {
    Roulette {
        mode,
        weight,
        select,
        min_depth: Some(0),
        estimate: RrEstimate::Scene,
    }
}

fn lobes(kd: [f32; 3], ks: [f32; 3], n: f32) -> [Lobe; 2] {
    [Lobe::Diffuse(Lambert { kd }), Lobe::Glossy(Phong { ks, n })]
}

/// Diffuse + normalized Phong.
fn diffuse_glossy(kd: [f32; 3], ks: [f32; 3], n: f32) -> Bsdf {
    Bsdf::DiffuseGlossy(Lambert { kd }, Phong { ks, n })
}

fn wo_at(deg: f32) -> Vec3 {
    let t = deg.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

#[test]
fn classic_uses_albedo_luminance() {
    let r = Roulette {
        mode: RrMode::Classic,
        min_depth: Some(0),
        ..Roulette::default()
    };
    let one = Spectrum::<3>::ONE;
    let a = Spectrum::<3>([0.5, 0.5, 0.5]);
    assert!((r.continuation(0, &one, &a) - 0.5).abs() < 1e-6);
    // the throughput does not matter to the classic roulette
    assert_eq!(
        r.continuation(0, &Spectrum([0.0, 0.0, 9.0]), &a),
        r.continuation(0, &one, &a)
    );
    assert_eq!(r.continuation(0, &one, &Spectrum::<3>([2.0; 3])), 1.0);
    let flat = Roulette {
        weight: RrWeight::Flat,
        ..r
    };
    let c = Spectrum::<3>([0.9, 0.3, 0.0]);
    assert!((flat.continuation(0, &one, &c) - 0.4).abs() < 1e-6);
    assert!((r.continuation(0, &one, &c) - c.luminance()).abs() < 1e-7);
    let off = Roulette {
        mode: RrMode::Off,
        ..r
    };
    assert_eq!(off.continuation(5, &one, &a), 1.0);
    let late = Roulette {
        min_depth: Some(3),
        ..r
    };
    assert_eq!(late.continuation(2, &one, &a), 1.0);
    assert!(late.continuation(3, &one, &a) < 1.0);
}

#[test]
fn spectral_probability_is_the_papers_formula() {
    let f = Spectrum::<3>([0.2, 1.0, 3.0]);
    let w = Spectrum::<3>([0.5, 0.1, 0.9]);
    let h = Spectrum::<3>([1.0, 2.0, 0.5]);
    let num = 0.2 * 0.5 * 1.0 + 1.0 * 0.1 * 2.0 + 3.0 * 0.9 * 0.5;
    let den = 0.2 * 1.0 + 1.0 * 2.0 + 3.0 * 0.5;
    assert!((spectral_probability(&f, &w, &h) - num / den).abs() < 1e-6);
    // nothing arrives: nothing to continue
    assert_eq!(spectral_probability(&Spectrum::ZERO, &w, &h), 0.0);
    // white light: the h-weighted average of the weight
    let s = spectral_probability(&Spectrum::ONE, &w, &Spectrum::ONE);
    assert!((s - w.average()).abs() < 1e-6);
}

#[test]
fn blue_light_at_a_yellow_wall_ends_the_walk() {
    // The paper's example: classic continues with 2/3, spectral with 0.
    let blue = Spectrum::<3>([0.0, 0.0, 1.0]);
    let yellow = Spectrum::<3>([1.0, 1.0, 0.0]);
    let flat = roulette(RrMode::Classic, RrWeight::Flat, BsdfSelect::Mixture);
    assert!((flat.continuation(0, &blue, &yellow) - 2.0 / 3.0).abs() < 1e-6);
    for mode in [RrMode::Spectral, RrMode::SpectralEstimate] {
        for weight in [RrWeight::Flat, RrWeight::Luminance] {
            let r = roulette(mode, weight, BsdfSelect::Mixture);
            assert_eq!(r.continuation(0, &blue, &yellow), 0.0);
            // and white light continues as the weighted albedo
            let s = r.continuation(0, &Spectrum::ONE, &yellow);
            assert!(s > 0.6, "{s}");
        }
    }
}

fn s_i_properties<const N: usize>(rng: &mut TestRng) {
    for _ in 0..2000 {
        let rgb = |rng: &mut TestRng, k: f32| {
            [k * rng.next_f32(), k * rng.next_f32(), k * rng.next_f32()]
        };
        // albedo bounds from dark to above 1 in sum
        let k = 1.5 * rng.next_f32();
        let l = lobes(rgb(rng, k), rgb(rng, k), 20.0);
        let f = Spectrum::<N>::from_rgb(rgb(rng, 5.0));
        for &mode in <RrMode as clap::ValueEnum>::value_variants() {
            for weight in [RrWeight::Flat, RrWeight::Luminance] {
                let r = roulette(mode, weight, BsdfSelect::Mis);
                let (s, can_stop) = r.lobe_probabilities(0, &f, &l);
                let sum: f32 = s.iter().sum();
                assert!(s.iter().all(|&v| v >= 0.0), "{s:?}");
                assert!(sum <= 1.0 + 1e-5, "{mode:?} {weight:?}: sum s_i = {sum}");
                if mode == RrMode::Off {
                    assert!(!can_stop);
                    assert!(sum == 0.0 || (sum - 1.0).abs() < 1e-5, "{sum}");
                }
                if can_stop {
                    assert!(sum < 1.0);
                }
            }
        }
    }
}

#[test]
fn lobe_probabilities_sum_to_at_most_one() {
    let mut rng = TestRng::new(5);
    s_i_properties::<3>(&mut rng);
    s_i_properties::<8>(&mut rng);
    s_i_properties::<16>(&mut rng);
}

#[test]
fn a_lobe_that_cannot_carry_the_spectrum_is_never_chosen() {
    // Yellow diffuse, blue glossy; blue light arrives: only the glossy lobe may be chosen
    // (the paper's example of section 2).
    let l = lobes([0.6, 0.6, 0.0], [0.0, 0.0, 0.3], 10.0);
    let blue = Spectrum::<3>([0.0, 0.0, 2.0]);
    for mode in [RrMode::Spectral, RrMode::SpectralEstimate] {
        for weight in [RrWeight::Flat, RrWeight::Luminance] {
            let r = roulette(mode, weight, BsdfSelect::Decompose);
            let (s, _) = r.lobe_probabilities(0, &blue, &l);
            assert_eq!(s[0], 0.0, "{mode:?} {weight:?}");
            // W_glossy = 0.3 on the only band that arrives
            assert!((s[1] - 0.3).abs() < 1e-6, "{s:?}");
            // green light: only the diffuse lobe reflects it
            let (s, _) = r.lobe_probabilities(0, &Spectrum([0.0, 1.0, 0.0]), &l);
            assert!((s[0] - 0.6).abs() < 1e-6 && s[1] == 0.0, "{s:?}");
        }
    }
    // the classic selection ignores the spectrum and picks the useless lobe most often
    let c = roulette(RrMode::Classic, RrWeight::Flat, BsdfSelect::Decompose);
    let (s, _) = c.lobe_probabilities(0, &blue, &l);
    assert!(
        (s[0] - 0.4).abs() < 1e-6 && (s[1] - 0.1).abs() < 1e-6,
        "{s:?}"
    );
    // and the selection never chooses it
    let bsdf = diffuse_glossy([0.6, 0.6, 0.0], [0.0, 0.0, 0.3], 10.0);
    let r = roulette(RrMode::Spectral, RrWeight::Flat, BsdfSelect::Decompose);
    let sel = r.select::<3>(0, &blue, &bsdf);
    assert!((sel.s_total - 0.3).abs() < 1e-6);
    let mut rng = TestRng::new(9);
    for _ in 0..1000 {
        if let Step::Continue { sample, .. } =
            sel.sample::<3>(&bsdf, wo_at(30.0), rng.next_f32(), rng.next_2d(), 0.5)
        {
            // only the glossy lobe is chosen: its weight is blue only
            assert_eq!(sample.weight[0], 0.0);
            assert!(sample.weight[2] > 0.0);
        }
    }
}

#[test]
fn spectral_selection_in_bands_prefers_the_lobe_the_light_can_use() {
    // Uplifted spectra overlap a little, so "cannot carry" becomes "almost nothing".
    let l = lobes([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 10.0);
    let blue = Spectrum::<16>::from_rgb([0.0, 0.0, 1.0]);
    let r = roulette(RrMode::Spectral, RrWeight::Luminance, BsdfSelect::Mis);
    let (s, _) = r.lobe_probabilities(0, &blue, &l);
    assert!(s[0] < 0.01 && s[1] > 0.5, "{s:?}");
}

#[test]
fn luminance_weights_are_positive_on_every_band() {
    fn check<const N: usize>() {
        let h = RrWeight::Luminance.h::<N>();
        assert!(h.0.iter().all(|&v| v > 0.0), "{h:?}");
    }
    check::<3>();
    check::<8>();
    check::<16>();
}

#[test]
fn estimate_formula() {
    // L~ = a~ Phi_e / (pi S (1 - a~)): a~ = 1/2 and Phi_e = pi S give 1.
    let s = 24.0;
    assert!(
        (RadianceEstimate::formula(std::f64::consts::PI * s, s, 0.5, 0.0, 0.0) - 1.0).abs() < 1e-12
    );
    // no finite estimate for a~ >= 1, none without light
    assert_eq!(RadianceEstimate::formula(10.0, s, 1.0, 0.0, 0.0), 0.0);
    assert_eq!(RadianceEstimate::formula(0.0, s, 0.5, 0.0, 0.0), 0.0);
    // grey inputs: every band count gets the same L~
    let e = RadianceEstimate::closed([3.0; 3], 2.0, [0.25; 3]);
    let want = RadianceEstimate::formula(3.0, 2.0, 0.25, 0.0, 0.0) as f32;
    for v in e.l_tilde::<3>().0 {
        assert!((v - want).abs() < 1e-6);
    }
    for v in e.l_tilde::<8>().0 {
        assert!((v - want).abs() < 1e-5);
    }
    for v in e.l_tilde::<16>().0 {
        assert!((v - want).abs() < 1e-5);
    }
}

#[test]
fn furnace_estimate_is_the_reflected_radiance() {
    // In the furnace every wall has albedo a permutation of (1, 0.5, 0.2) and emission
    // 1 - a; the radiance is 1, of which a~ = 1.7/3 is reflected: L~ is exactly that.
    let scene = crate::scene::load("furnace").unwrap();
    let e = &RadianceEstimate::of_scene(&scene);
    assert!((e.area - 24.0).abs() < 1e-4);
    for c in 0..3 {
        assert!((e.albedo[c] - 1.7 / 3.0).abs() < 1e-6);
    }
    let l = e.l_tilde::<3>();
    for c in 0..3 {
        assert!((l[c] - 1.7 / 3.0).abs() < 1e-5, "{l:?}");
    }
}

#[test]
fn estimate_roulette_is_unbiased_for_any_guess() {
    // E = s (X / s - (1 - s) a L~ / s) + (1 - s) a L~ = X, for every s, a, L~.
    let bsdf = diffuse_glossy([0.5, 0.2, 0.1], [0.2, 0.3, 0.1], 8.0);
    let f = Spectrum::<3>([0.7, 1.3, 0.2]);
    let l_tilde = Spectrum::<3>([0.4, 2.0, 0.0]);
    let x = Spectrum::<3>([0.3, 0.1, 0.9]); // F times the continued walk's expectation
    for mode in [RrMode::Estimate, RrMode::SpectralEstimate] {
        for &select in <BsdfSelect as clap::ValueEnum>::value_variants() {
            let r = roulette(mode, RrWeight::Luminance, select);
            let sel = r.select::<3>(0, &f, &bsdf);
            let s = sel.s_total;
            assert!(s > 0.0 && s < 1.0, "{s}");
            let stop = r.estimate_term(&sel, &bsdf, true, &f, || l_tilde).unwrap();
            let go = r.estimate_term(&sel, &bsdf, false, &f, || l_tilde).unwrap();
            let albedo = bsdf.albedo::<3>();
            for c in 0..3 {
                let a_l = f[c] * albedo[c] * l_tilde[c];
                assert!((stop[c] - a_l).abs() < 1e-6);
                assert!((go[c] + (1.0 - s) / s * a_l).abs() < 1e-6);
                let e = s * (x[c] / s + go[c]) + (1.0 - s) * stop[c];
                assert!((e - x[c]).abs() < 1e-5, "{e} vs {}", x[c]);
            }
        }
    }
    // the other roulettes add nothing
    let r = roulette(RrMode::Classic, RrWeight::Luminance, BsdfSelect::Mixture);
    let sel = r.select::<3>(0, &f, &bsdf);
    assert!(r.estimate_term(&sel, &bsdf, true, &f, || l_tilde).is_none());
}

/// sum_i s_i E_{p_i}[W_i / s_i] by stratified sampling of each lobe: must be the
/// directional albedo, whatever the s_i (method 1, 2 and 3 are all unbiased).
fn expected_reflection(select: BsdfSelect, l: &[Lobe], s: &[f32], wo: Vec3, m: usize) -> [f64; 3] {
    let mut e = [0.0f64; 3];
    for i in 0..l.len() {
        if s[i] <= 0.0 {
            continue;
        }
        for a in 0..m {
            for b in 0..m {
                let u = Vec2::new((a as f32 + 0.5) / m as f32, (b as f32 + 0.5) / m as f32);
                let Some(wi) = l[i].sample_dir(wo, u) else {
                    continue;
                };
                if let Some((w, _)) = selection_weight::<3>(select, l, s, i, wo, wi) {
                    for c in 0..3 {
                        e[c] += (s[i] * w[c]) as f64 / (m * m) as f64;
                    }
                }
            }
        }
    }
    e
}

#[test]
fn selection_weights_of_the_three_methods() {
    let kd = [0.5, 0.3, 0.1];
    let ks = [0.1, 0.3, 0.6];
    let l = lobes(kd, ks, 4.0);
    let bsdf = diffuse_glossy(kd, ks, 4.0);
    let s = [0.3f32, 0.45];
    let wo = wo_at(35.0);
    let wi = Vec3::new(-0.4, 0.1, 0.9).normalize();
    let f = bsdf.eval::<3>(wo, wi) * wi.z;
    let fd = l[0].eval::<3>(wo, wi) * wi.z;
    let (pd, pg) = (l[0].pdf(wo, wi), l[1].pdf(wo, wi));
    assert!(pd > 0.0 && pg > 0.0);
    for i in 0..2 {
        let p_i = [pd, pg][i];
        // method 1: W_i = w_i / p_i
        let (w1, pdf) = selection_weight::<3>(BsdfSelect::Decompose, &l, &s, i, wo, wi).unwrap();
        let w_i = if i == 0 {
            fd
        } else {
            l[1].eval::<3>(wo, wi) * wi.z
        };
        // method 2: W_i = w s_i / (p_i sum_j s_j)
        let (w2, _) = selection_weight::<3>(BsdfSelect::Static, &l, &s, i, wo, wi).unwrap();
        // method 3: W_i = w s_i / sum_j s_j p_j
        let (w3, _) = selection_weight::<3>(BsdfSelect::Mis, &l, &s, i, wo, wi).unwrap();
        for c in 0..3 {
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * b.abs().max(1.0);
            assert!(close(w1[c] * s[i], w_i[c] / p_i), "method 1");
            assert!(
                close(w2[c] * s[i], f[c] * s[i] / (p_i * (s[0] + s[1]))),
                "method 2"
            );
            assert!(
                close(w3[c] * s[i], f[c] * s[i] / (s[0] * pd + s[1] * pg)),
                "method 3"
            );
        }
        // the density MIS weighs with: the selection's, given that the walk goes on
        assert!((pdf - (s[0] * pd + s[1] * pg) / (s[0] + s[1])).abs() < 1e-5 * pdf);
    }
    // the balance heuristic's weight does not depend on which lobe sampled wi
    let a = selection_weight::<3>(BsdfSelect::Mis, &l, &s, 0, wo, wi)
        .unwrap()
        .0;
    let b = selection_weight::<3>(BsdfSelect::Mis, &l, &s, 1, wo, wi)
        .unwrap()
        .0;
    assert_eq!(a, b);
    // a direction outside the glossy lobe: method 2 leans on the diffuse lobe alone there
    let away = Vec3::new(0.7, 0.0, 0.2).normalize();
    assert_eq!(l[1].pdf(wo, away), 0.0);
    let (w2, _) = selection_weight::<3>(BsdfSelect::Static, &l, &s, 0, wo, away).unwrap();
    let fa = bsdf.eval::<3>(wo, away) * away.z;
    assert!((w2[0] - fa[0] / (l[0].pdf(wo, away) * s[0])).abs() < 1e-5);
}

#[test]
fn every_method_reflects_the_directional_albedo() {
    let cases = [
        (lobes([0.5, 0.3, 0.1], [0.1, 0.3, 0.6], 2.0), [0.3f32, 0.45]),
        (lobes([0.2, 0.2, 0.2], [0.7, 0.5, 0.3], 1.0), [0.5, 0.5]),
        (lobes([0.6, 0.0, 0.3], [0.0, 0.4, 0.1], 1.0), [0.05, 0.9]),
    ];
    for (l, s) in cases {
        let bsdf = match l {
            [Lobe::Diffuse(d), Lobe::Glossy(g)] => Bsdf::DiffuseGlossy(d, g),
            _ => unreachable!(),
        };
        for deg in [0.0f32, 40.0, 75.0] {
            let wo = wo_at(deg);
            let want = AlbedoTable::integrate(&bsdf, wo.z, 300);
            // Method 2's weights w / p_glossy grow without bound at the rim of the Phong
            // lobe (its variance is infinite there); the low exponents above keep the
            // quadrature's error small enough to compare.
            for (select, tol) in [
                (BsdfSelect::Decompose, 2e-3),
                (BsdfSelect::Mis, 2e-3),
                (BsdfSelect::Static, 2e-2),
            ] {
                let e = expected_reflection(select, &l, &s, wo, 300);
                for c in 0..3 {
                    assert!(
                        (e[c] - want[c] as f64).abs() < tol,
                        "{select:?} at {deg}: {e:?} vs {want:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn selection_chooses_lobes_with_probability_s_i() {
    let bsdf = diffuse_glossy([0.5, 0.5, 0.5], [0.2, 0.2, 0.2], 1000.0);
    let r = roulette(RrMode::Classic, RrWeight::Flat, BsdfSelect::Decompose);
    let sel = r.select::<3>(0, &Spectrum::ONE, &bsdf);
    assert_eq!(sel.probabilities(), &[0.5, 0.2]);
    let wo = wo_at(0.0);
    let n = 100_000;
    let (mut stop, mut glossy, mut diffuse) = (0, 0, 0);
    for k in 0..n {
        let u = (k as f32 + 0.5) / n as f32;
        match sel.sample::<3>(&bsdf, wo, u, Vec2::new(0.3, 0.7), 0.0) {
            Step::Terminated => stop += 1,
            // the n = 1000 lobe stays within a few degrees of the mirror direction (+z)
            Step::Continue { sample, .. } if sample.wi.z > 0.99 => glossy += 1,
            Step::Continue { .. } => diffuse += 1,
            Step::Absorbed => {}
        }
    }
    let share = |k: i32| k as f64 / n as f64;
    assert!((share(stop) - 0.3).abs() < 1e-3, "{stop}");
    assert!((share(glossy) - 0.2).abs() < 1e-3, "{glossy}");
    assert!((share(diffuse) - 0.5).abs() < 1e-3, "{diffuse}");
    // without roulette the walk never ends, the lobes keep their ratio
    let off = roulette(RrMode::Off, RrWeight::Flat, BsdfSelect::Decompose);
    let sel = off.select::<3>(0, &Spectrum::ONE, &bsdf);
    assert_eq!(sel.s_total, 1.0);
    assert!(!matches!(
        sel.sample::<3>(&bsdf, wo, 0.999_999_9, Vec2::new(0.3, 0.7), 0.0),
        Step::Terminated
    ));
}

#[test]
fn methods_agree_on_a_single_lobe() {
    // With one lobe the three methods are the same estimator: w / (s p).
    let bsdf = Bsdf::Diffuse(Lambert {
        kd: [0.6, 0.4, 0.2],
    });
    let wo = wo_at(20.0);
    let mut out = vec![];
    for select in [BsdfSelect::Decompose, BsdfSelect::Static, BsdfSelect::Mis] {
        let r = roulette(RrMode::Classic, RrWeight::Luminance, select);
        let sel = r.select::<3>(0, &Spectrum::ONE, &bsdf);
        match sel.sample::<3>(&bsdf, wo, 0.1, Vec2::new(0.2, 0.9), 0.0) {
            Step::Continue { sample, scale } => out.push((sample.weight * scale, sample.pdf)),
            s => panic!("{s:?}"),
        }
    }
    let q = Spectrum::<3>([0.6, 0.4, 0.2]).luminance();
    for (w, pdf) in &out {
        for c in 0..3 {
            assert!((w[c] - [0.6, 0.4, 0.2][c] / q).abs() < 1e-5, "{out:?}");
        }
        assert!((pdf - out[0].1).abs() < 1e-6);
    }
}
