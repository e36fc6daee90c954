//! Directional albedo a(wo) = integral of f(wo, wi) cos(theta_i) dwi of an isotropic BSDF,
//! tabulated over mu = cos(theta_o). The analytically computable scenes of Szirmay-Kalos,
//! Kovacs and Abbas (2001) need it: a surface that emits L_e(wo) = 1 - a(wo) in a closed
//! room has radiance exactly 1 everywhere (`furnace-glossy`).
//!
//! Each elementary lobe i contributes E[f_i cos / p_i] under its own sampling density; the
//! expectation is taken with a deterministic midpoint grid over the unit square, with
//! u_1 = v^2 (Jacobian 2v) so that the Phong warp's cos = u_1^(1/(n+1)), steep at u_1 = 0,
//! becomes smooth: accurate to a few 1e-5.

use super::Bsdf;
use glam::{Vec2, Vec3};

/// a(mu) per RGB channel on `SIZE` equally spaced mu in [0, 1], linearly interpolated.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoTable {
    values: Vec<[f32; 3]>,
}

impl AlbedoTable {
    pub const SIZE: usize = 65;
    /// Strata per axis of the quadrature of one lobe at one mu.
    const STRATA: usize = 64;

    /// Tabulate the directional albedo of the non-delta lobes of `bsdf`.
    pub fn new(bsdf: &Bsdf) -> AlbedoTable {
        let values = (0..Self::SIZE)
            .map(|k| {
                // mu = 0 exactly is a wo in the surface plane, where the lobes are zero;
                // the grazing node takes its value from just above it.
                let mu = (k as f32 / (Self::SIZE - 1) as f32).max(1e-4);
                Self::integrate(bsdf, mu, Self::STRATA)
            })
            .collect();
        AlbedoTable { values }
    }

    /// a(mu) by stratified sampling of each elementary lobe with `m` x `m` strata.
    pub fn integrate(bsdf: &Bsdf, mu: f32, m: usize) -> [f32; 3] {
        let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        let (lobes, n) = bsdf.lobe_array();
        let mut a = [0.0f64; 3];
        for lobe in &lobes[..n] {
            for i in 0..m {
                let v = (i as f64 + 0.5) / m as f64;
                let jacobian = 2.0 * v;
                for j in 0..m {
                    let u = Vec2::new((v * v) as f32, (j as f32 + 0.5) / m as f32);
                    let Some(wi) = lobe.sample_dir(wo, u) else {
                        continue;
                    };
                    let pdf = lobe.pdf(wo, wi);
                    if pdf <= 0.0 {
                        continue;
                    }
                    let w = lobe.eval::<3>(wo, wi) * (wi.z / pdf);
                    for c in 0..3 {
                        a[c] += w[c] as f64 * jacobian;
                    }
                }
            }
        }
        let k = 1.0 / (m * m) as f64;
        [(a[0] * k) as f32, (a[1] * k) as f32, (a[2] * k) as f32]
    }

    /// a(mu), mu = cos(theta_o) clamped to [0, 1].
    #[inline]
    pub fn eval(&self, mu: f32) -> [f32; 3] {
        let x = mu.clamp(0.0, 1.0) * (Self::SIZE - 1) as f32;
        let i = (x as usize).min(Self::SIZE - 2);
        let t = x - i as f32;
        let (a, b) = (self.values[i], self.values[i + 1]);
        [
            a[0] + (b[0] - a[0]) * t,
            a[1] + (b[1] - a[1]) * t,
            a[2] + (b[2] - a[2]) * t,
        ]
    }

    /// 1 - a(mu): the emission that makes a closed room's radiance exactly 1. (Kept out
    /// of line: inlined into the path tracer's loop it costs the ordinary emitters ~2%.)
    #[inline(never)]
    pub fn complement(&self, mu: f32) -> [f32; 3] {
        let a = self.eval(mu);
        [1.0 - a[0], 1.0 - a[1], 1.0 - a[2]]
    }

    /// Cosine-weighted hemispherical average 2 * integral of g(mu) mu dmu of the table
    /// (`complement = true`: of 1 - a), by the trapezoidal rule on the nodes. Times pi
    /// and the area, this is the power a surface emitting `complement` radiates.
    pub fn hemispherical(&self, complement: bool) -> [f32; 3] {
        let mut s = [0.0f64; 3];
        let h = 1.0 / (Self::SIZE - 1) as f64;
        for k in 0..Self::SIZE {
            let mu = k as f64 * h;
            let wk = if k == 0 || k == Self::SIZE - 1 {
                0.5
            } else {
                1.0
            };
            let v = if complement {
                self.complement(mu as f32)
            } else {
                self.eval(mu as f32)
            };
            for c in 0..3 {
                s[c] += 2.0 * wk * h * mu * v[c] as f64;
            }
        }
        [s[0] as f32, s[1] as f32, s[2] as f32]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Lambert, Phong};

    fn glossy(kd: f32, ks: f32, n: f32) -> Bsdf {
        Bsdf::DiffuseGlossy(Lambert { kd: [kd; 3] }, Phong { ks: [ks; 3], n })
    }

    #[test]
    fn lambert_albedo_is_kd() {
        let t = AlbedoTable::new(&Bsdf::Diffuse(Lambert {
            kd: [0.2, 0.5, 1.0],
        }));
        for mu in [0.0, 0.3, 0.77, 1.0] {
            let a = t.eval(mu);
            for (c, want) in [0.2, 0.5, 1.0].iter().enumerate() {
                assert!((a[c] - want).abs() < 1e-6, "{a:?}");
            }
        }
        let h = t.hemispherical(false);
        assert!((h[2] - 1.0).abs() < 1e-4, "{h:?}");
    }

    #[test]
    fn phong_table_matches_a_fine_quadrature() {
        for n in [3.0, 30.0, 100.0] {
            let b = glossy(0.3, 0.7, n);
            let t = AlbedoTable::new(&b);
            // normal incidence: the normalized lobe reflects everything (no horizon cut)
            let a1 = t.eval(1.0)[0];
            assert!((a1 - 1.0).abs() < 5e-5, "n {n}: a(1) = {a1}");
            for mu in [0.05f32, 0.21, 0.5, 0.93] {
                let fine = AlbedoTable::integrate(&b, mu, 400)[0];
                let tab = t.eval(mu)[0];
                assert!((tab - fine).abs() < 2e-4, "n {n} mu {mu}: {tab} vs {fine}");
                assert!(tab <= 1.0 + 1e-4 && tab > 0.3);
            }
        }
    }
}
