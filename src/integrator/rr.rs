//! Every Russian-roulette decision of kalos lives here, and every estimator calls it: the
//! path tracer now, light paths and the bidirectional tracer later. The notation is that of
//! Szecsi, Szirmay-Kalos and Kelemen, "Variance reduction for Russian-roulette" (WSCG 2003).
//!
//! At a reflection the walk arrives with the spectral weight F (the product of the W/s of
//! the reflections before: the path throughput; for light paths L_e / p_e times it). The
//! combined BRDF is a sum of elementary lobes, w = w_1 + ... + w_n; the walk selects lobe i
//! with probability s_i or ends with probability 1 - sum_i s_i, and a continued walk
//! carries W_i / s_i, where W_i is, for the paper's three methods (`BsdfSelect`):
//!
//! 1. `Decompose`: W_i = w_i / p_i;
//! 2. `Static`:    W_i = w s_i / (p_i sum_j s_j);
//! 3. `Mis`:       W_i = w s_i / sum_j s_j p_j (the balance heuristic).
//!
//! `Mixture` (the default) is kalos' ordinary sampler instead: `Bsdf::sample` picks a lobe
//! by the luminance of its reflectance and weighs by the mixture density, and a separate
//! roulette continues with one probability s.
//!
//! The probabilities (`RrMode`):
//! - `Classic`: s_i = the luminance (`--rr-weight luminance`) or the average (`flat`) of the
//!   lobe's albedo a_i, the usual practice; a terminated walk contributes zero.
//! - `Spectral`: s_i = sum_l F(l) W_i(l) h_l / sum_l F(l) h_l. The direction is not known
//!   when the lobe is chosen, so W_i is taken at its expectation under p_i, the lobe's
//!   albedo a_i (the paper: "a low-variance estimator selects an elementary BRDF with the
//!   probability of its albedo"). Green light arriving at a red lobe gives s_i = 0.
//! - `Estimate`: the classic s, but a terminated walk contributes a L~ instead of zero, and a
//!   continued one (w/p L_in - (1 - s) a L~) / s, with L~ the scene-average radiance
//!   (`RadianceEstimate`) and a the local albedo. Unbiased for any L~; the contributions
//!   can be negative and are kept (a clamp would be a bias).
//! - `SpectralEstimate`: both; `Off`: no roulette (the walk ends at `--max-depth`).
//! - `Throughput`: s = min(max_l F(l) a(l), 0.95), the roulette of Mitsuba and pbrt: the
//!   walk's weight, not the local albedo alone, decides, so a walk that has lost most of
//!   its weight ends and one that carries much goes on.
//!
//! The probabilities are scaled down to sum to 1 where sum_i s_i would exceed it (albedo
//! bounds above 1). Before `min_depth` reflections, and with `Off`, they are normalised to
//! sum to 1: the lobe is still selected, the walk never ends there.

use crate::material::{Bsdf, BsdfSample, Lobe};
use crate::radiosity::Solution;
use crate::scene::SurfaceHit;
use crate::spectrum::Spectrum;
use glam::{Vec2, Vec3};

/// Most elementary lobes of a combined BRDF (`Bsdf::lobe_array`).
pub const MAX_LOBES: usize = 2;

/// Which roulette (`--rr`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum RrMode {
    /// No roulette.
    Off,
    /// Continue with the albedo's weighted mean (the usual roulette).
    Classic,
    /// The paper's spectral roulette: s_i from the arriving spectrum F.
    Spectral,
    /// Classic roulette that adds the radiance estimate L~ when it terminates.
    Estimate,
    /// Spectral roulette with the radiance estimate.
    SpectralEstimate,
    /// Continue with the largest band of the throughput the walk would carry on, F a,
    /// at most `THROUGHPUT_MAX` (Mitsuba's and pbrt's roulette): paths whose weight has
    /// fallen end, paths that still carry much go on.
    Throughput,
}

/// Reflections before the roulette starts when neither the options nor the scene file
/// say. Measured for error at equal time against 0 (every reflection) on the Cornell box
/// and a furnished room, 10 s, three seeds (2026-12-06, Xeon with AVX-512, two threads):
/// with the spectral roulette and the Sobol sampler, 2 has 0.62-0.75x the RMSE of
/// Mitsuba 3's path tracer (rr_depth 5) and 0.99-1.2x its perceptual error on the Cornell
/// box, 0 has 0.92-0.98x and 1.7x; dark pixels lit through two bounces keep their light.
pub const DEFAULT_MIN_DEPTH: u32 = 2;

/// The throughput roulette's largest continuation probability (Mitsuba's 0.95).
pub const THROUGHPUT_MAX: f32 = 0.95;

/// Where the estimate roulette takes its L~.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum RrEstimate {
    /// One scene-average value (the paper's).
    #[default]
    Scene,
    /// The indirect radiance arriving at each hit, read from a radiosity solution computed
    /// before the render (the scene's value where it has none: mirrors, glass).
    Radiosity,
}

/// The estimate roulette's L~ at a reflection.
#[derive(Clone, Copy)]
pub enum LTilde<'a, const N: usize> {
    /// One value for the whole scene (zero when the roulette reads none).
    Scene(Spectrum<N>),
    /// (B - E - B_direct) / (pi rho) from the solution at the hit, else the scene's value.
    Radiosity(&'a Solution, Spectrum<N>),
}

impl<const N: usize> LTilde<'_, N> {
    /// L~ at `hit`, reached on its `front` side or not: for the radiosity solution, its
    /// element found from the hit's own barycentrics (no projection, no search).
    #[inline]
    pub fn at_hit(&self, hit: &SurfaceHit, front: bool) -> Spectrum<N> {
        match self {
            LTilde::Scene(l) => *l,
            LTilde::Radiosity(sol, l) => sol
                .indirect_at::<N>(hit.prim, hit.b1, hit.b2, front)
                .unwrap_or(*l),
        }
    }
}

impl RrMode {
    /// s_i from the arriving spectrum F.
    #[inline]
    pub fn is_spectral(self) -> bool {
        matches!(self, RrMode::Spectral | RrMode::SpectralEstimate)
    }
    /// A terminated walk contributes a L~.
    #[inline]
    pub fn uses_estimate(self) -> bool {
        matches!(self, RrMode::Estimate | RrMode::SpectralEstimate)
    }
}

/// The wavelength weights h_l of the spectral roulette (`--rr-weight`); for the classic
/// roulette, luminance or average of the albedo.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum RrWeight {
    /// h = 1 on every band.
    Flat,
    /// h = the luminance weights of the bands.
    Luminance,
}

impl RrWeight {
    /// h_l. Luminance weights are floored at 1e-3 of their peak: h_l must be positive on
    /// every band, or s_i could vanish for a lobe that still carries light to the output
    /// on that band (a bias); the 8-band table's violet band has a slightly negative
    /// luminance and the 16-band table's last band almost none.
    #[inline]
    pub fn h<const N: usize>(self) -> Spectrum<N> {
        match self {
            RrWeight::Flat => Spectrum::ONE,
            RrWeight::Luminance => {
                let y = Spectrum::<N>::luminance_weights();
                let floor = 1e-3 * y.max_value();
                y.map(|v| v.max(floor))
            }
        }
    }
}

/// How a combined BRDF's lobe is chosen (`--bsdf-select`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum BsdfSelect {
    /// One-sample mixture by reflectance luminance, then a separate roulette.
    Mixture,
    /// The paper's method 1.
    Decompose,
    /// The paper's method 2.
    Static,
    /// The paper's method 3.
    Mis,
}

/// The roulette settings an estimator gets; the options' names, help and defaults are
/// written here once (the CLI flattens this struct; `Default` parses an empty line).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct Roulette {
    /// Russian roulette: spectral | classic | estimate | spectral-estimate | throughput | off.
    #[arg(long = "rr", value_enum, default_value_t = RrMode::Spectral)]
    pub mode: RrMode,
    /// Wavelength weights h of the roulette: luminance | flat.
    #[arg(long = "rr-weight", value_enum, default_value_t = RrWeight::Luminance)]
    pub weight: RrWeight,
    /// Lobe selection of combined BRDFs: mixture | decompose | static | mis (the roulette
    /// paper's methods 1, 2, 3, with termination folded in).
    #[arg(long = "bsdf-select", value_enum, default_value_t = BsdfSelect::Mixture)]
    pub select: BsdfSelect,
    /// Reflections before roulette starts (0: at every reflection). Default 2
    /// (`DEFAULT_MIN_DEPTH`), or what a Mitsuba scene's integrator says (its rr_depth, 5
    /// unless given, less one).
    #[arg(long = "rr-min-depth")]
    pub min_depth: Option<u32>,
    /// Where --rr estimate / spectral-estimate take L~: scene (one scene-average value,
    /// the paper's) or radiosity (the indirect radiance arriving at each hit, from a
    /// radiosity solution computed before the render).
    #[arg(long = "rr-estimate", value_enum, default_value_t = RrEstimate::Scene)]
    pub estimate: RrEstimate,
}

impl Default for Roulette {
    fn default() -> Self {
        crate::options::defaults::<Roulette>()
    }
}

/// s_i = sum_l F(l) W_i(l) h_l / sum_l F(l) h_l: the share of the weighted power arriving
/// with F that lobe i carries on (0 if nothing arrives).
#[inline]
pub fn spectral_probability<const N: usize>(
    f: &Spectrum<N>,
    w_i: &Spectrum<N>,
    h: &Spectrum<N>,
) -> f32 {
    let fh = *f * *h;
    let den = fh.0.iter().sum::<f32>();
    if den <= 0.0 || !den.is_finite() {
        return 0.0;
    }
    (fh.dot(w_i) / den).max(0.0)
}

/// What the roulette decided at one reflection, before the direction is sampled: the
/// probabilities of the lobes and of going on. Estimators compute it once per reflection
/// and use it for both next-event estimation (its `pdf`) and the continuation (`sample`).
#[derive(Clone, Copy, Debug)]
pub struct Selection {
    /// `Mixture` also for BSDFs without elementary lobes (mirror, glass).
    select: BsdfSelect,
    /// s_i of the lobes (methods 1-3).
    s: [f32; MAX_LOBES],
    n: usize,
    /// s = sum_i s_i, the probability that the walk goes on (1: no roulette here).
    pub s_total: f32,
}

/// The outcome of a reflection.
#[derive(Clone, Copy, Debug)]
pub enum Step<const N: usize> {
    /// The roulette ended the walk (probability 1 - s).
    Terminated,
    /// The walk went on but found no direction (sampled below the surface): it ends with
    /// zero, as part of the continued estimator.
    Absorbed,
    /// Go on along `sample.wi`; the throughput is multiplied by `sample.weight`, then by
    /// `scale` (1/s of the mixture's separate roulette; 1 where W_i/s_i already holds it).
    Continue { sample: BsdfSample<N>, scale: f32 },
}

impl Roulette {
    /// Whether the walk may end at reflection `bounce` (0-based).
    #[inline]
    fn active(&self, bounce: u32) -> bool {
        // (None: every reflection; a render's settings always name the depth, from the
        // options, the scene file or `DEFAULT_MIN_DEPTH`)
        self.mode != RrMode::Off && bounce >= self.min_depth.unwrap_or(0)
    }

    /// Continuation probability s at reflection `bounce` of a walk arriving with spectral
    /// weight `f` at a surface of albedo `albedo` (1 = no roulette): classic, the luminance
    /// (or average) of the albedo; spectral, sum_l F(l) a(l) h_l / sum_l F(l) h_l.
    #[inline]
    pub fn continuation<const N: usize>(
        &self,
        bounce: u32,
        f: &Spectrum<N>,
        albedo: &Spectrum<N>,
    ) -> f32 {
        if !self.active(bounce) {
            return 1.0;
        }
        self.unclamped(f, albedo).clamp(0.0, 1.0)
    }

    #[inline]
    fn unclamped<const N: usize>(&self, f: &Spectrum<N>, a: &Spectrum<N>) -> f32 {
        if self.mode.is_spectral() {
            spectral_probability(f, a, &self.weight.h::<N>())
        } else if self.mode == RrMode::Throughput {
            // F a: the throughput after this reflection, in expectation over the lobe
            (*f * *a).max_value().min(THROUGHPUT_MAX)
        } else {
            // The classic roulette: the albedo's luminance exactly as before the roulette variants (raw
            // weights, so the default renders are bit-identical), or its average.
            match self.weight {
                RrWeight::Luminance => a.luminance(),
                RrWeight::Flat => a.average(),
            }
        }
    }

    /// s_i of `lobes` for a walk arriving with `f` at reflection `bounce`; the second
    /// value says whether the walk may end (sum_i s_i < 1). With roulette the s_i sum to
    /// at most 1; without, to exactly 1 (or all are 0 if no lobe reflects anything of F).
    pub fn lobe_probabilities<const N: usize>(
        &self,
        bounce: u32,
        f: &Spectrum<N>,
        lobes: &[Lobe],
    ) -> ([f32; MAX_LOBES], bool) {
        let mut s = [0.0f32; MAX_LOBES];
        for (si, lobe) in s.iter_mut().zip(lobes) {
            let a_i = Spectrum::<N>::from_rgb(lobe.albedo_rgb());
            *si = self.unclamped(f, &a_i).max(0.0);
        }
        let sum: f32 = s.iter().sum();
        let can_stop = self.active(bounce) && sum < 1.0;
        if !can_stop && sum > 0.0 {
            for si in s.iter_mut() {
                *si /= sum;
            }
        }
        (s, can_stop)
    }

    /// The selection at reflection `bounce` of a walk arriving with spectral weight `f`.
    /// (The default mixture stays inline in the estimators' loops; methods 1-3 are calls.)
    #[inline(always)]
    pub fn select<const N: usize>(&self, bounce: u32, f: &Spectrum<N>, bsdf: &Bsdf) -> Selection {
        if self.select != BsdfSelect::Mixture {
            if let Some(sel) = self.select_lobe(bounce, f, bsdf) {
                return sel;
            }
        }
        Selection::mixture(if self.active(bounce) {
            self.continuation(bounce, f, &bsdf.albedo::<N>())
        } else {
            1.0
        })
    }

    #[inline(never)]
    fn select_lobe<const N: usize>(
        &self,
        bounce: u32,
        f: &Spectrum<N>,
        bsdf: &Bsdf,
    ) -> Option<Selection> {
        let (lobes, n) = bsdf.lobe_array();
        if n == 0 {
            return None;
        }
        let (s, can_stop) = self.lobe_probabilities(bounce, f, &lobes[..n]);
        Some(Selection {
            select: self.select,
            s,
            n,
            s_total: if can_stop { s.iter().sum() } else { 1.0 },
        })
    }

    /// The estimate roulette's addition to the estimator at a reflection reached with
    /// spectral weight `f` (None for the other roulettes or where the walk cannot end):
    /// terminated, F a L~; continued, -F (1 - s) a L~ / s, with a the local albedo (the
    /// same bound the classic roulette uses).
    #[inline]
    pub fn estimate_term<const N: usize>(
        &self,
        sel: &Selection,
        bsdf: &Bsdf,
        terminated: bool,
        f: &Spectrum<N>,
        l_tilde: impl FnOnce() -> Spectrum<N>,
    ) -> Option<Spectrum<N>> {
        if !self.mode.uses_estimate() || sel.s_total >= 1.0 {
            return None;
        }
        let a_l = *f * bsdf.albedo::<N>() * l_tilde();
        Some(if terminated {
            a_l
        } else {
            a_l * (-(1.0 - sel.s_total) / sel.s_total)
        })
    }
}

impl Selection {
    /// The mixture selection (the BSDF's own sampling) whose walk goes on with
    /// probability `s_total` (1: no roulette here), as [`Roulette::select`] makes it.
    #[inline(always)]
    pub fn mixture(s_total: f32) -> Selection {
        Selection {
            select: BsdfSelect::Mixture,
            s: [0.0; MAX_LOBES],
            n: 0,
            s_total,
        }
    }

    /// Whether this is the mixture selection (see [`Selection::mixture`]).
    #[inline(always)]
    pub fn is_mixture(&self) -> bool {
        self.select == BsdfSelect::Mixture
    }

    /// s_i of lobe i (methods 1-3).
    pub fn probabilities(&self) -> &[f32] {
        &self.s[..self.n]
    }

    /// Solid-angle density with which the continuation produces `wi`, given that the walk
    /// goes on: what multiple importance sampling against light sampling weighs with.
    /// Mixture: the mixture density; methods 1-3: sum_j s_j p_j / sum_j s_j.
    #[inline(always)]
    pub fn pdf(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
        if self.select == BsdfSelect::Mixture {
            return bsdf.pdf(wo, wi);
        }
        self.pdf_lobes(bsdf, wo, wi)
    }

    #[inline(never)]
    fn pdf_lobes(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
        let (lobes, _) = bsdf.lobe_array();
        let (mut num, mut den) = (0.0f32, 0.0f32);
        for (&s_j, lobe) in self.s[..self.n].iter().zip(&lobes) {
            if s_j > 0.0 {
                num += s_j * lobe.pdf(wo, wi);
                den += s_j;
            }
        }
        if den > 0.0 {
            num / den
        } else {
            0.0
        }
    }

    /// Decide the reflection: end the walk, or choose a lobe and sample a direction.
    /// Mixture: `u_rr` plays the roulette, `u_lobe` picks the mixture's lobe; methods 1-3:
    /// `u_lobe` alone chooses among the lobes (s_i) and termination (1 - sum_i s_i).
    #[inline(always)]
    pub fn sample<const N: usize>(
        &self,
        bsdf: &Bsdf,
        wo: Vec3,
        u_lobe: f32,
        u_dir: Vec2,
        u_rr: f32,
    ) -> Step<N> {
        if self.select == BsdfSelect::Mixture {
            let (goes_on, scale) = self.roulette(u_rr);
            if !goes_on {
                return Step::Terminated;
            }
            return match bsdf.sample::<N>(wo, u_lobe, u_dir) {
                Some(sample) => Step::Continue { sample, scale },
                None => Step::Absorbed,
            };
        }
        self.sample_lobe(bsdf, wo, u_lobe, u_dir)
    }

    /// The mixture's roulette: whether the walk goes on (with probability s, by `u_rr`),
    /// and the throughput's scale if it does (1/s).
    #[inline(always)]
    pub fn roulette(&self, u_rr: f32) -> (bool, f32) {
        let q = self.s_total;
        (!(q < 1.0 && u_rr >= q), if q < 1.0 { 1.0 / q } else { 1.0 })
    }

    /// Methods 1-3: `u_lobe` chooses lobe i or termination, then lobe i samples wi.
    #[inline(never)]
    fn sample_lobe<const N: usize>(
        &self,
        bsdf: &Bsdf,
        wo: Vec3,
        u_lobe: f32,
        u_dir: Vec2,
    ) -> Step<N> {
        // Lobe i with probability s_i, termination with 1 - s.
        let mut acc = 0.0;
        let mut chosen = None;
        for i in 0..self.n {
            if self.s[i] > 0.0 {
                acc += self.s[i];
                // without roulette (s = 1) the last selectable lobe takes the rounding rest
                if u_lobe < acc || self.s_total >= 1.0 {
                    chosen = Some(i);
                    if u_lobe < acc {
                        break;
                    }
                }
            }
        }
        let Some(i) = chosen else {
            return Step::Terminated;
        };
        let (lobes, _) = bsdf.lobe_array();
        let Some(wi) = lobes[i].sample_dir(wo, u_dir) else {
            return Step::Absorbed;
        };
        match selection_weight::<N>(self.select, &lobes[..self.n], &self.s[..self.n], i, wo, wi) {
            Some((weight, pdf)) => Step::Continue {
                sample: BsdfSample {
                    wi,
                    weight,
                    pdf,
                    delta: false,
                },
                scale: 1.0,
            },
            None => Step::Absorbed,
        }
    }
}

/// W_i / s_i of the paper's method `select` (1, 2 or 3) for a direction `wi` that lobe `i`
/// sampled, with the cosine folded in (w = f cos), and the density of `Selection::pdf`.
/// None if the direction carries nothing (zero density, below the surface).
///
/// Method 2 as printed assumes every p_j covers the whole domain of w; a Phong lobe does
/// not cover the diffuse lobe's, which makes it biased there. Its weights are therefore
/// renormalised over the lobes that can produce `wi`: alpha_i = s_i / sum_{j: p_j(wi) > 0} s_j,
/// which is the printed method wherever the densities overlap and unbiased everywhere.
pub fn selection_weight<const N: usize>(
    select: BsdfSelect,
    lobes: &[Lobe],
    s: &[f32],
    i: usize,
    wo: Vec3,
    wi: Vec3,
) -> Option<(Spectrum<N>, f32)> {
    let cos = wi.z;
    if cos <= 0.0 {
        return None;
    }
    let mut p = [0.0f32; MAX_LOBES];
    let (mut sp, mut s_sum) = (0.0f32, 0.0f32);
    for j in 0..lobes.len() {
        p[j] = lobes[j].pdf(wo, wi);
        if s[j] > 0.0 {
            sp += s[j] * p[j];
            s_sum += s[j];
        }
    }
    if p[i] <= 0.0 || s[i] <= 0.0 || sp <= 0.0 {
        return None;
    }
    let w_total = || {
        let mut f = Spectrum::<N>::ZERO;
        for lobe in lobes {
            f += lobe.eval::<N>(wo, wi);
        }
        f * cos
    };
    let weight = match select {
        // W_i / s_i = w_i / (p_i s_i)
        BsdfSelect::Decompose => lobes[i].eval::<N>(wo, wi) * (cos / (p[i] * s[i])),
        // W_i / s_i = w / (p_i sum_{j: p_j > 0} s_j)
        BsdfSelect::Static => {
            let covering: f32 = (0..lobes.len())
                .filter(|&j| p[j] > 0.0 && s[j] > 0.0)
                .map(|j| s[j])
                .sum();
            w_total() * (1.0 / (p[i] * covering))
        }
        // W_i / s_i = w / sum_j s_j p_j
        BsdfSelect::Mis | BsdfSelect::Mixture => w_total() * (1.0 / sp),
    };
    Some((weight, sp / s_sum))
}

/// The paper's estimate of the radiance arriving anywhere in a scene, reflected light only
/// (direct light is left out: it varies too much to guess, and an overestimate costs more
/// than an underestimate). For a closed scene the paper's
///
///   L~ = (1 / (pi S)) a~ Phi_e / (1 - a~)   per wavelength,
///
/// from the emitted power Phi_e, the total area S and the area-weighted albedo a~: the
/// power reflected once, twice, ... is Phi_r = Phi_e (a~ + a~^2 + ...), and all of it
/// arrives somewhere again.
///
/// Open scenes (`scene::escape`): a share e_L of the emitted photons escapes before its
/// first hit and a share e_s of the reflected power escapes after each reflection, so
///
///   Phi_r = Phi_e (1 - e_L) (a~ + a~^2 (1 - e_s) + ...) = Phi_e (1 - e_L) a~ / (1 - a~ (1 - e_s)),
///
/// of which (1 - e_s) Phi_r arrives at the surfaces again (the rest leaves), and the
/// average radiance arriving is
///
///   L~ = (1 / (pi S)) (1 - e_s) Phi_r.
///
/// With e_s = e_L = 0 it is the paper's formula. Computed once per scene
/// (`Scene::radiance_estimate`) for every band count; a band with a~ (1 - e_s) >= 1 has no
/// finite estimate and gets 0 (the classic roulette's guess).
#[derive(Clone, Debug, PartialEq)]
pub struct RadianceEstimate {
    /// Phi_e per RGB channel.
    pub phi_e: [f64; 3],
    /// S.
    pub area: f64,
    /// a~ per RGB channel.
    pub albedo: [f64; 3],
    /// e_s: the share of the reflected power that escapes after a reflection.
    pub e_s: f64,
    /// e_L: the share of the emitted power that escapes before its first hit.
    pub e_l: f64,
    l3: Spectrum<3>,
    l8: Spectrum<8>,
    l16: Spectrum<16>,
}

impl RadianceEstimate {
    /// L~ on one band (e_s = e_L = 0: the paper's closed-scene formula).
    pub fn formula(phi_e: f64, area: f64, albedo: f64, e_s: f64, e_l: f64) -> f64 {
        // a~ (1 - e_s): the share of the power arriving at a surface that arrives at one
        // again after the reflection.
        let kept = albedo * (1.0 - e_s);
        if area <= 0.0 || !(0.0..1.0).contains(&kept) || albedo < 0.0 || phi_e <= 0.0 {
            return 0.0;
        }
        // Phi_r = Phi_e (1 - e_L) a~ / (1 - a~ (1 - e_s))
        let phi_r = phi_e * (1.0 - e_l) * albedo / (1.0 - kept);
        (1.0 - e_s) * phi_r / (std::f64::consts::PI * area)
    }

    /// The estimate of a closed scene (e_s = e_L = 0).
    pub fn closed(phi_e: [f64; 3], area: f64, albedo: [f64; 3]) -> Self {
        Self::new(phi_e, area, albedo, 0.0, 0.0)
    }

    pub fn new(phi_e: [f64; 3], area: f64, albedo: [f64; 3], e_s: f64, e_l: f64) -> Self {
        RadianceEstimate {
            phi_e,
            area,
            albedo,
            e_s,
            e_l,
            l3: Self::bands(phi_e, area, albedo, e_s, e_l),
            l8: Self::bands(phi_e, area, albedo, e_s, e_l),
            l16: Self::bands(phi_e, area, albedo, e_s, e_l),
        }
    }

    /// Phi_e and a~ are linear in the RGB inputs, so each band's comes from the uplift;
    /// the formula is then applied per band (e_s and e_L are grey: one walk of luminance).
    fn bands<const N: usize>(
        phi_e: [f64; 3],
        area: f64,
        albedo: [f64; 3],
        e_s: f64,
        e_l: f64,
    ) -> Spectrum<N> {
        let p = Spectrum::<N>::from_rgb(phi_e.map(|v| v as f32));
        let a = Spectrum::<N>::from_rgb(albedo.map(|v| v as f32));
        let mut l = Spectrum::<N>::ZERO;
        for k in 0..N {
            l[k] = Self::formula(p[k] as f64, area, a[k] as f64, e_s, e_l) as f32;
        }
        l
    }

    /// L~ on N bands.
    #[inline]
    pub fn l_tilde<const N: usize>(&self) -> Spectrum<N> {
        let src: &[f32] = match N {
            3 => &self.l3.0,
            8 => &self.l8.0,
            16 => &self.l16.0,
            _ => return Self::bands(self.phi_e, self.area, self.albedo, self.e_s, self.e_l),
        };
        let mut s = Spectrum::<N>::ZERO;
        s.0.copy_from_slice(src);
        s
    }
}

pub mod escape;

#[cfg(test)]
mod tests;

impl RadianceEstimate {
    /// The estimate roulette's L~ of a scene from its emitted power Phi_e, total area S,
    /// area-weighted albedo a~ (each material's albedo bound, textures by their mean texel)
    /// and how open the scene is: e_s and e_L from the photon walk of `escape`. Run by the
    /// integrator's `prepare`, only when a roulette that uses it is chosen.
    pub fn of_scene(scene: &crate::scene::Scene) -> RadianceEstimate {
        let (materials, textures) = (&scene.materials, &scene.textures);
        let albedo: Vec<[f64; 3]> = materials
            .iter()
            .map(|m| {
                let bsdf = match m.kd_texture {
                    Some(t) => m.bsdf.clone().with_kd(textures[t as usize].mean()),
                    None => m.bsdf.clone(),
                };
                bsdf.albedo::<3>().0.map(|v| v as f64)
            })
            .collect();
        let mut area = 0.0f64;
        let mut weighted = [0.0f64; 3];
        for (t, &m) in scene.tris.iter().zip(&scene.tri_material) {
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length() as f64;
            area += a;
            for c in 0..3 {
                weighted[c] += a * albedo[m as usize][c];
            }
        }
        let mean = weighted.map(|w| if area > 0.0 { w / area } else { 0.0 });
        let tri_albedo: Vec<f32> = scene
            .tri_material
            .iter()
            .map(|&m| {
                let a = albedo[m as usize].map(|v| v as f32);
                crate::spectrum::Spectrum::<3>(a)
                    .luminance()
                    .clamp(0.0, 1.0)
            })
            .collect();
        let e = escape::escape_probabilities(&scene.tris, &scene.bvh, &scene.lights, &tri_albedo);
        RadianceEstimate::new(scene.lights.total_power_rgb(), area, mean, e.e_s, e.e_l)
    }
}
