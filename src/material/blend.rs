//! Mitsuba's `blendbsdf`: the linear blend (1 - w) f_0 + w f_1 of two BSDFs, w in [0, 1]
//! (a value, or a texture or mesh attribute looked up per hit).
//!
//! eval and pdf are the blends of the two BSDFs' (Mitsuba's). Sampling picks BSDF 1 with
//! probability w and BSDF 0 otherwise (Mitsuba's split of the lobe number u: u <= w picks
//! BSDF 1 and is rescaled to u / w, else (u - w) / (1 - w) for BSDF 0) and samples it; a
//! Dirac direction keeps the chosen BSDF's weight (its selection cancels its blend
//! factor), any other direction is weighted by the blended f cos / pdf, which the blended
//! pdf makes consistent with `pdf`. (Mitsuba returns the chosen BSDF's own weight there:
//! the same expectation, a larger variance.)
//!
//! The two BSDFs are fixed per material (shared, `'static`, one copy per distinct pair):
//! only the weight varies over a surface.

use super::{Bsdf, BsdfSample};
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};

/// The two blended BSDFs and the weight of the second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    pub pair: &'static [Bsdf; 2],
    pub weight: f32,
}

impl Blend {
    /// A blend of `pair` with the weight clamped to [0, 1] (as Mitsuba clamps it).
    pub fn new(pair: &'static [Bsdf; 2], weight: f32) -> Blend {
        let weight = if weight.is_nan() {
            0.5
        } else {
            weight.clamp(0.0, 1.0)
        };
        Blend { pair, weight }
    }

    /// The shared copy of a pair of BSDFs (made once per distinct pair per process).
    pub fn intern(pair: [Bsdf; 2]) -> &'static [Bsdf; 2] {
        super::intern::intern(pair)
    }

    // The blend's answers to `Bsdf`'s questions about its pair, out of line: `Bsdf`'s
    // own answer then does not call itself and is inlined into the per-hit code of every
    // scene (recursive, it was a call per hit: the furnished room, 2026-12-06).

    /// Both two-sided ([`Bsdf::is_two_sided`]).
    #[inline(never)]
    pub fn is_two_sided(&self) -> bool {
        self.pair.iter().all(Bsdf::is_two_sided)
    }

    /// Both only Dirac lobes ([`Bsdf::is_delta`]).
    #[inline(never)]
    pub fn is_delta(&self) -> bool {
        self.pair.iter().all(Bsdf::is_delta)
    }

    /// Either lets light through ([`Bsdf::transmits`]).
    #[inline(never)]
    pub fn transmits(&self) -> bool {
        self.pair.iter().any(Bsdf::transmits)
    }

    #[inline]
    pub fn eval<const N: usize>(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let w = self.weight;
        let mut f = Spectrum::ZERO;
        if w < 1.0 {
            f += self.pair[0].eval::<N>(wo, wi) * (1.0 - w);
        }
        if w > 0.0 {
            f += self.pair[1].eval::<N>(wo, wi) * w;
        }
        f
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let w = self.weight;
        let mut p = 0.0;
        if w < 1.0 {
            p += self.pair[0].pdf(wo, wi) * (1.0 - w);
        }
        if w > 0.0 {
            p += self.pair[1].pdf(wo, wi) * w;
        }
        p
    }

    pub fn sample<const N: usize>(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let w = self.weight;
        let (chosen, p_sel, u_lobe) = if u_lobe <= w && w > 0.0 {
            (&self.pair[1], w, (u_lobe / w).min(1.0 - f32::EPSILON))
        } else {
            (
                &self.pair[0],
                1.0 - w,
                ((u_lobe - w) / (1.0 - w)).clamp(0.0, 1.0 - f32::EPSILON),
            )
        };
        let s = chosen.sample::<N>(wo, u_lobe, u)?;
        if s.delta {
            return Some(BsdfSample {
                pdf: s.pdf * p_sel,
                ..s
            });
        }
        let pdf = self.pdf(wo, s.wi);
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: s.wi,
            weight: self.eval::<N>(wo, s.wi) * (s.wi.z.abs() / pdf),
            pdf,
            delta: false,
        })
    }

    pub fn albedo<const N: usize>(&self) -> Spectrum<N> {
        self.pair[0].albedo::<N>() * (1.0 - self.weight) + self.pair[1].albedo::<N>() * self.weight
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::principled::tests::assert_weights_are_f_cos_over_pdf;
    use crate::material::{Conductor, Distribution, Lambert};
    use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};

    fn gold(alpha: f32) -> Bsdf {
        Bsdf::Conductor(Conductor::new(
            [0.143, 0.374, 1.442],
            [3.983, 2.385, 1.603],
            [1.0; 3],
            alpha,
            Distribution::Ggx,
        ))
    }

    fn diffuse(kd: [f32; 3]) -> Bsdf {
        Bsdf::Diffuse(Lambert { kd })
    }

    fn wo(deg: f32) -> Vec3 {
        let t = deg.to_radians();
        Vec3::new(t.sin(), 0.0, t.cos())
    }

    /// eval and pdf are the weight's blends of the two BSDFs' (known answers from the
    /// parts); the weight is clamped to [0, 1]; equal pairs are shared.
    #[test]
    fn eval_and_pdf_blend_the_two() {
        let pair = Blend::intern([diffuse([0.0, 0.5, 0.5]), gold(0.2)]);
        assert!(std::ptr::eq(
            pair,
            Blend::intern([diffuse([0.0, 0.5, 0.5]), gold(0.2)])
        ));
        let (o, i) = (wo(30.0), Vec3::new(-0.3, 0.2, 0.9).normalize());
        for w in [0.0f32, 0.25, 1.0] {
            let b = Blend::new(pair, w);
            let f = b.eval::<3>(o, i);
            let (f0, f1) = (pair[0].eval::<3>(o, i), pair[1].eval::<3>(o, i));
            for c in 0..3 {
                let expect = (1.0 - w) * f0[c] + w * f1[c];
                assert!((f[c] - expect).abs() <= 1e-6 * expect.max(1.0), "w {w}");
            }
            let p = (1.0 - w) * pair[0].pdf(o, i) + w * pair[1].pdf(o, i);
            assert!((b.pdf(o, i) - p).abs() <= 1e-6 * p.max(1.0));
        }
        assert_eq!(Blend::new(pair, 1.7).weight, 1.0);
        assert_eq!(Blend::new(pair, -0.2).weight, 0.0);
        // Mitsuba's test scene: diffuse (0, .5, .5) and (1, 1, 0) at weight 0.3
        let two = Blend::new(
            Blend::intern([diffuse([0.0, 0.5, 0.5]), diffuse([1.0, 1.0, 0.0])]),
            0.3,
        );
        let f = two.eval::<3>(o, i);
        let pi = std::f32::consts::PI;
        for (c, kd) in [0.3f32, 0.65, 0.35].into_iter().enumerate() {
            assert!((f[c] - kd / pi).abs() < 1e-6, "{c}: {}", f[c]);
        }
    }

    /// A blend is two-sided if both are, Dirac if both are, and transmits if either does.
    #[test]
    fn a_blend_answers_for_its_pair() {
        use crate::material::{Dielectric, RoughDielectric};
        let glass = Bsdf::Dielectric(Dielectric {
            eta: 1.5,
            tint: crate::material::dielectric::Tint::NONE,
        });
        let rough_glass = Bsdf::RoughDielectric(RoughDielectric {
            eta: 1.5,
            alpha: 0.3,
            dist: Distribution::Ggx,
            tint: crate::material::dielectric::Tint::NONE,
        });
        let blend = |a: Bsdf, b: Bsdf| Bsdf::Blend(Blend::new(Blend::intern([a, b]), 0.5));
        let d = diffuse([0.5; 3]);
        let b = blend(d.clone(), gold(0.0));
        assert!(b.is_two_sided() && !b.is_delta() && !b.transmits());
        let b = blend(gold(0.0), glass.clone());
        assert!(!b.is_two_sided() && b.is_delta() && !b.transmits());
        let b = blend(d, rough_glass);
        assert!(!b.is_two_sided() && !b.is_delta() && b.transmits());
    }

    /// Sampling follows `pdf` (chi-square), rough and Dirac parts alike, and its weight
    /// is f cos / pdf for the non-Dirac directions.
    #[test]
    fn chi2_blend_sampling() {
        let cases = [
            (
                "diffuse + rough gold",
                [diffuse([0.8, 0.5, 0.2]), gold(0.3)],
                0.4f32,
            ),
            ("smooth gold + diffuse", [gold(0.0), diffuse([0.5; 3])], 0.7),
            ("rough gold + rough gold", [gold(0.1), gold(0.6)], 0.5),
        ];
        let mut rng = TestRng::new(3);
        for (k, (name, pair, w)) in cases.into_iter().enumerate() {
            let b = Bsdf::Blend(Blend::new(Blend::intern(pair), w));
            for (j, deg) in [10.0f32, 60.0].into_iter().enumerate() {
                let o = wo(deg);
                let r = chi2_sphere(
                    |u1, u2| b.sample::<3>(o, u1, u2).filter(|s| !s.delta).map(|s| s.wi),
                    |wi| b.pdf(o, wi),
                    200_000,
                    900 + (k * 10 + j) as u64,
                );
                assert_chi2(&format!("blend {name} at {deg}"), &r);
                assert_weights_are_f_cos_over_pdf(&b, o, &mut rng, name, 1e-4);
            }
        }
    }
}
