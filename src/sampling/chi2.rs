//! Chi-square goodness-of-fit test of a direction sampler against its pdf (test-only),
//! after Mitsuba 3's `chi2.py`: directions are binned on a (cos theta, phi) grid of equal
//! solid-angle cells, expected counts come from integrating the pdf over each cell, cells
//! with expected count below 5 are pooled, and samples the routine refuses (None) are a
//! cell of their own whose expected count is the pdf mass missing from the sphere.

use glam::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;

pub struct Chi2Result {
    pub p_value: f64,
    pub statistic: f64,
    pub dof: usize,
    /// Integral of the pdf over the sphere (should be <= 1).
    pub pdf_integral: f64,
}

/// Deterministic uniform numbers for the tests.
pub use super::rng::SeqRng as TestRng;

/// Run the test with `n` samples; `sample(u_1d, u_2d)` returns a unit direction or None.
pub fn chi2_sphere(
    mut sample: impl FnMut(f32, Vec2) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
    n: usize,
    seed: u64,
) -> Chi2Result {
    const NT: usize = 48; // cos theta cells
    const NP: usize = 96; // phi cells
    const SUB: usize = 8;
    let mut obs = vec![0f64; NT * NP + 1];
    let mut rng = TestRng::new(seed);
    let cell = |w: Vec3| -> usize {
        let t = (((w.z as f64 + 1.0) * 0.5 * NT as f64) as usize).min(NT - 1);
        let mut phi = (w.y as f64).atan2(w.x as f64);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = ((phi / (2.0 * PI) * NP as f64) as usize).min(NP - 1);
        t * NP + p
    };
    for _ in 0..n {
        let u1 = rng.next_f32();
        let u2 = rng.next_2d();
        match sample(u1, u2) {
            Some(w) if w.is_finite() => obs[cell(w.normalize())] += 1.0,
            _ => obs[NT * NP] += 1.0,
        }
    }
    // expected counts: Simpson's rule in cos theta, midpoint rule in phi, on sub-cells
    let mut exp = vec![0f64; NT * NP + 1];
    let dz = 2.0 / (NT * SUB) as f64;
    let dphi = 2.0 * PI / (NP * SUB) as f64;
    let mut total = 0.0;
    for t in 0..NT * SUB {
        let z0 = -1.0 + t as f64 * dz;
        for p in 0..NP * SUB {
            let phi = (p as f64 + 0.5) * dphi;
            let f = |z: f64| {
                let r = (1.0 - z * z).max(0.0).sqrt();
                pdf(Vec3::new(
                    (r * phi.cos()) as f32,
                    (r * phi.sin()) as f32,
                    z as f32,
                )) as f64
            };
            let v = (f(z0) + 4.0 * f(z0 + 0.5 * dz) + f(z0 + dz)) / 6.0 * dz * dphi;
            exp[(t / SUB) * NP + p / SUB] += v * n as f64;
            total += v;
        }
    }
    exp[NT * NP] = ((1.0 - total).max(0.0)) * n as f64;
    // pool cells with small expected counts
    let (mut stat, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in obs.iter().zip(exp.iter()) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e >= 5.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else if pool_o > 20.0 {
        // samples where the pdf says (almost) none should be: a hard failure
        stat = f64::INFINITY;
    }
    let dof = dof.saturating_sub(1).max(1);
    let p_value = if stat.is_finite() {
        1.0 - ChiSquared::new(dof as f64).unwrap().cdf(stat)
    } else {
        0.0
    };
    Chi2Result {
        p_value,
        statistic: stat,
        dof,
        pdf_integral: total,
    }
}

/// Significance per test (Bonferroni-corrected for the few dozen tests kalos runs).
pub const ALPHA: f64 = 0.01 / 50.0;

pub fn assert_chi2(name: &str, r: &Chi2Result) {
    assert!(
        r.p_value > ALPHA,
        "{name}: chi-square rejects the sampler: p = {:.3e}, stat = {:.1}, dof = {}",
        r.p_value,
        r.statistic,
        r.dof
    );
    assert!(
        r.pdf_integral < 1.0 + 2e-3,
        "{name}: pdf integrates to {:.4} > 1",
        r.pdf_integral
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::*;

    const N: usize = 200_000;

    #[test]
    fn cosine_hemisphere() {
        let r = chi2_sphere(
            |_, u| Some(square_to_cosine_hemisphere(u)),
            pdf_cosine_hemisphere,
            N,
            1,
        );
        assert_chi2("cosine hemisphere", &r);
        assert!((r.pdf_integral - 1.0).abs() < 2e-3);
    }

    #[test]
    fn uniform_sphere() {
        let r = chi2_sphere(
            |_, u| Some(square_to_uniform_sphere(u)),
            |_| PDF_UNIFORM_SPHERE,
            N,
            2,
        );
        assert_chi2("uniform sphere", &r);
    }

    #[test]
    fn cos_power_lobes() {
        for (i, n) in [1.0f32, 10.0, 60.0].into_iter().enumerate() {
            let r = chi2_sphere(
                |_, u| Some(square_to_cos_power(u, n)),
                |w| pdf_cos_power(w.z, n),
                N,
                3 + i as u64,
            );
            assert_chi2(&format!("cos^{n}"), &r);
        }
    }

    #[test]
    fn a_wrong_pdf_is_rejected() {
        // the test must be able to fail: cosine samples against a uniform-hemisphere pdf
        let r = chi2_sphere(
            |_, u| Some(square_to_cosine_hemisphere(u)),
            |w| {
                if w.z > 0.0 {
                    0.5 / std::f32::consts::PI
                } else {
                    0.0
                }
            },
            N,
            9,
        );
        assert!(r.p_value < 1e-6);
    }

    #[test]
    fn discrete_distribution() {
        let w = [0.5f32, 2.0, 0.0, 1.0, 4.5, 0.25];
        let d = Distribution1D::new(&w);
        let total: f32 = w.iter().sum();
        let mut rng = TestRng::new(5);
        let mut counts = [0f64; 6];
        let n = 100_000;
        for _ in 0..n {
            counts[d.sample(rng.next_f32()).0] += 1.0;
        }
        let mut stat = 0.0;
        for i in 0..6 {
            let e = w[i] as f64 / total as f64 * n as f64;
            if e > 0.0 {
                stat += (counts[i] - e).powi(2) / e;
            } else {
                assert_eq!(counts[i], 0.0);
            }
        }
        let p = 1.0 - ChiSquared::new(4.0).unwrap().cdf(stat);
        assert!(p > ALPHA, "p = {p}");
    }
}
