//! Dependent-tests driven filtering (DTF), after Csonka, Szirmay-Kalos, Kelemen and Antal,
//! "Dependent tests driven filtering in Monte-Carlo global illumination".
//!
//! The renderer runs two phases and hands over two films:
//! - phase 1, *dependent tests*: every pixel takes n samples built from the same random
//!   numbers; per pixel this gives the mean colour C_d and the spread sigma;
//! - phase 2, *independent tests*: pixel p takes N[p] ordinary samples, mean C_i.
//!
//! This module holds the renderer-independent parts:
//! - [`allocate_relative`] / [`allocate_budget`]: N[p] from phase 1, classified into a
//!   few categories;
//! - [`Dtf`] / [`dtf_filter`]: region forming per pixel (windows m x m, m = 2..m_max),
//!   the error-minimising weights f*, the filtered C_i and the displayed colour
//!   C = (C_d n + C_i,filtered N) / (n + N).
//!
//! Documented choices (where the paper leaves room):
//! - sigma from per-channel statistics: sum of per-channel standard deviations ([`sigma`]);
//! - N is rounded *up* to the smallest category at or above it, clamped to the largest
//!   ([`classify`]);
//! - black pixels: ||C_d|| = 0 with sigma = 0 gets the smallest category, with sigma > 0
//!   the largest ([`samples_for_error`]);
//! - budget mode: one scale factor found by bisection, then single pixels promoted to get
//!   as close to the budget as one category step allows ([`allocate_budget`]);
//! - pyramid kernel radius m/sqrt(2) (the window's half diagonal), not M/sqrt(2) ([`Kernel`]);
//! - even windows: p sits at offset floor((m-1)/2) from the window's top-left corner, so
//!   windows are nested and grow right/down on even m, left/up on odd m;
//! - windows are clipped to the image; M counts the pixels actually in the window that
//!   have independent samples;
//! - [`Clamp`]: the paper's f^+ = max(f, 0), or the exact non-negative minimiser.

use crate::film::{Film, PixelStats};
use crate::image_io::RgbImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

// ---------------------------------------------------------------------------------------
// Colour norm and sigma
// ---------------------------------------------------------------------------------------

/// ||C||: the sum of the absolute values of the colour components (paper §4, last
/// paragraph: norms replace absolute values for vector-valued radiance).
#[inline]
pub fn color_norm(c: [f64; 3]) -> f64 {
    c[0].abs() + c[1].abs() + c[2].abs()
}

/// Delta_q = ||C_d[p] - C_d[q]||.
#[inline]
fn diff_norm(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs()
}

/// sigma[p] of the dependent phase: the spread of one sample C[s] around C_d.
///
/// The paper defines sigma^2 = sum_s ||C[s] - C_d||^2 / (n - 1) with the sum-of-abs norm.
/// The film keeps only per-channel Welford statistics, so the cross terms
/// |dr||dg| etc. are unknown; we use sigma = sum over channels of the per-channel standard
/// deviations (n - 1 denominator), the "extent of the variance ellipsoid" of §4. By
/// Minkowski's inequality it is an upper bound of the exact value (equal when the channel
/// deviations are proportional with the same sign, as for grey light). Fewer than two
/// samples give 0.
pub fn sigma(s: &PixelStats) -> f64 {
    s.variance().iter().map(|v| v.max(0.0).sqrt()).sum()
}

// ---------------------------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------------------------

/// Distance kernel d(q - p) that lowers the confidence in distant pixels (paper §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kernel {
    /// d = max(R - ||q - p||, 0) with R = m / sqrt(2), the half diagonal of the m x m
    /// window. The paper prints M/sqrt(2) with M = m^2, but then d would be almost flat
    /// (for m = 4: 11.3 at the centre, 8.5 at the farthest pixel), contradicting its
    /// purpose of "decreasing the weight of distant pixels"; with m/sqrt(2) it is a real
    /// pyramid that falls to (nearly) zero at the window's corner. On even windows the
    /// farthest pixel (offset (m/2, m/2)) sits exactly at R and gets weight 0.
    #[default]
    Pyramid,
    /// The "better solution" the paper mentions: d = exp(-||q - p||^2 / (2 s^2)) with
    /// s = m / (2 sqrt(2)) = R / 2, so d(R) = e^-2.
    Gaussian,
}

/// How negative filter coefficients are removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Clamp {
    /// As printed: f = 1/M + sqrt(N)/(3 sigma sqrt(M)) (sum_r Delta_r / M - Delta_q),
    /// f^+ = max(f, 0). Caveat: the mean of Delta is taken over all pixels, including the
    /// clipped ones, so as N -> infinity the weights tend to (mean Delta - Delta_q)^+,
    /// not to the primary pixel alone: on a colour gradient the filter does not vanish.
    Paper,
    /// The exact minimiser of the paper's linearised error under f >= 0 and sum f = 1
    /// (its KKT conditions): f_q = k (lambda - Delta_q)^+ with k = sqrt(N)/(3 sigma
    /// sqrt(M)) and lambda chosen so the positive part sums to 1 (water filling over the
    /// sorted Delta). Equal to `Paper` whenever no coefficient is clipped; as N grows all
    /// weight goes to pixels with Delta_q = 0, so the filter vanishes as the paper intends.
    #[default]
    ActiveSet,
}

/// How a sample budget is shared among pixels (budget mode, [`allocate_budget`]): N[p]
/// proportional to a weight w[p] from phase 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Allocation {
    /// w = sigma^2 / ||C_d||, as the paper prescribes for a given time or sample budget
    /// (§3). It sits between the two optima below and concentrates samples on high-sigma
    /// pixels (light edges) more than either.
    Paper,
    /// w = sigma: minimises the summed squared error sum_p sigma^2 / N[p] for a fixed total
    /// sum_p N[p] (Lagrange: N ∝ sigma). The default: on cornell and room it gave both a
    /// lower RMSE and a lower perceptual error than `Paper` at every budget measured.
    #[default]
    Mse,
    /// w = sigma / ||C_d||: minimises the summed squared *relative* error.
    RelMse,
}

impl Allocation {
    /// The weight w[p] for sigma > 0 and ||C_d|| > 0.
    #[inline]
    pub fn weight(self, sigma: f64, cd_norm: f64) -> f64 {
        match self {
            Allocation::Paper => sigma * sigma / cd_norm,
            Allocation::Mse => sigma,
            Allocation::RelMse => sigma / cd_norm,
        }
    }
}

/// Parameters of DTF (paper §6 names n, eps_r, m_max and Delta f[0]_min as the four
/// critical ones).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DtfParams {
    /// n: dependent samples per pixel the renderer takes in phase 1 (paper: 45..70). The
    /// functions here read the actual per-pixel counts from the films (they differ only
    /// where non-finite samples were rejected).
    pub n: u32,
    /// eps_r: prescribed relative error of [`allocate_relative`] (paper Fig. 2: 0.03).
    pub eps_r: f32,
    /// Categories N is classified into, strictly increasing (paper: "1, 10, 20, 50, 100").
    pub categories: Vec<u32>,
    /// m_max: largest window side (paper: 4 is enough).
    pub m_max: u32,
    /// Delta f[0]_min: minimal decrease of the primary pixel's weight f*[0] for a larger
    /// window to be accepted (paper: 0.01).
    pub df0_min: f32,
    /// Distance kernel d.
    pub kernel: Kernel,
    /// Removal of negative coefficients.
    pub clamp: Clamp,
    /// Floor of sigma for allocation, as a share of the image's mean sigma (0: the paper's
    /// raw formula). See [`robust_stats`].
    pub sigma_floor: f32,
    /// Floor of ||C_d|| for allocation, as a share of the image's mean ||C_d||.
    pub norm_floor: f32,
    /// Floor of sigma as a share of the pixel's own ||C_d||: all pixels share the n
    /// dependent jitters and paths, so a pixel can miss a thin feature (a sliver of a light)
    /// in every one of them and show sigma ~ 0; no Monte Carlo pixel is that certain.
    /// Relative-error mode only (a minimum of (3 F / eps_r)^2 samples); budget weights
    /// ignore it. At eps_r = 0.01 the Cornell light's own pixels otherwise kept a 0.8% error
    /// from a sliver of ceiling no sample had seen, and the RMSE stalled (0.0086 at 0.03,
    /// 0.0082 at 0.01).
    pub relative_sigma_floor: f32,
    /// Budget mode: allocation weights are clipped at this multiple of their median (0: no
    /// clipping, the raw proportionality).
    pub max_weight_ratio: f32,
    /// Budget mode: how the budget is shared ([`Allocation`]).
    pub allocation: Allocation,
    /// Budget mode: weigh the optimal rules by the pixels' sample costs measured in phase 1
    /// (rays per sample), N ∝ sigma / sqrt(c): least error for the *time* spent.
    pub cost_aware: bool,
    /// Relative-error mode: rounds of top-up samples after phase 2 ([`top_up`]; 0: the
    /// paper's single allocation).
    pub top_up_rounds: u32,
    /// Budget modes: share of phase 2's samples held back for one top-up round
    /// ([`top_up_budget`]; used when `top_up_rounds` > 0).
    pub top_up_share: f32,
    /// Region forming stops when a neighbour's N exceeds this multiple of the pixel's own
    /// N. The paper stops at any larger N (ratio 1). But sigma^2 from n samples has a
    /// relative standard error of about sqrt(2 / (n - 1)) (37% at n = 16, 20% at n = 50), so
    /// pixels of one homogeneous region often land one category apart (a factor 2 to 2.5);
    /// with ratio 1 about a quarter of the pixels of flat walls were never filtered. The
    /// default 2.5 tolerates one category step and still stops at real variance edges.
    pub stop_ratio: f32,
    /// Independent guard: Delta_q is at least the difference of the independent means
    /// beyond `guard` standard errors (0: off, the paper's Delta from C_d alone).
    pub guard: f32,
}

impl Default for DtfParams {
    fn default() -> Self {
        DtfParams {
            n: 50,
            eps_r: 0.03,
            categories: vec![0, 1, 10, 20, 50, 100, 200, 500],
            m_max: 4,
            df0_min: 0.01,
            kernel: Kernel::Pyramid,
            // ActiveSet: the exact minimiser of the paper's own error formula under f >= 0;
            // it equals the printed closed form whenever nothing is clipped, and unlike
            // the printed clamp it vanishes as N grows (asymptotic unbiasedness).
            clamp: Clamp::ActiveSet,
            sigma_floor: 0.05,
            norm_floor: 0.05,
            relative_sigma_floor: 0.1,
            max_weight_ratio: 16.0,
            allocation: Allocation::Mse,
            cost_aware: true,
            stop_ratio: 2.5,
            guard: 3.0,
            top_up_rounds: 2,
            top_up_share: 0.25,
        }
    }
}

impl DtfParams {
    /// A clear error for parameters the algorithm cannot use.
    pub fn validate(&self) -> Result<(), String> {
        if self.n < 2 {
            return Err(format!(
                "dtf: n = {}: the dependent phase needs at least 2 samples per pixel to estimate sigma",
                self.n
            ));
        }
        if !(self.eps_r.is_finite() && self.eps_r > 0.0) {
            return Err(format!(
                "dtf: eps_r = {}: the relative error must be positive",
                self.eps_r
            ));
        }
        if self.categories.is_empty() {
            return Err("dtf: the list of sample categories is empty".into());
        }
        if self.categories.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "dtf: categories {:?} must be strictly increasing",
                self.categories
            ));
        }
        if !(1..=32).contains(&self.m_max) {
            return Err(format!(
                "dtf: m_max = {}: the window side must be 1..=32",
                self.m_max
            ));
        }
        if !(self.stop_ratio.is_finite() && self.stop_ratio >= 1.0) {
            return Err(format!(
                "dtf: stop ratio = {}: must be a number >= 1 (1 is the paper's rule)",
                self.stop_ratio
            ));
        }
        if !(0.0..=1.0).contains(&self.top_up_share) {
            return Err(format!(
                "dtf: top-up share = {}: must be between 0 and 1",
                self.top_up_share
            ));
        }
        if !self.df0_min.is_finite() {
            return Err(format!("dtf: df0_min = {} is not finite", self.df0_min));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Sample allocation
// ---------------------------------------------------------------------------------------

/// Classify a wanted number of additional samples into a category: the smallest category
/// at or above `n` (rounding up keeps the prescribed error bound), clamped to the
/// largest. Negative values (phase 1 already reached the error) give the smallest
/// category; NaN is treated as "unbounded" and gives the largest. Values within a relative
/// 1e-9 above a category still count as that category (float rounding). `categories` must be
/// non-empty and increasing.
pub fn classify(n: f64, categories: &[u32]) -> u32 {
    let last = *categories.last().expect("non-empty categories");
    if n.is_nan() {
        return last;
    }
    if n == f64::INFINITY {
        return N_HARD_MAX;
    }
    // A relative tolerance of 1e-9 keeps rounding noise (e.g. (3 * 0.1 / 0.03)^2 - 50 =
    // 50.00000000000004) from pushing a value into the next category.
    let n = n - 1e-9 * n.abs().max(1.0);
    if let Some(c) = categories.iter().copied().find(|&c| c as f64 >= n) {
        return c;
    }
    // Past the largest category the classes go on doubling (last, 2 last, 4 last, ...):
    // a hard clamp would stop every pixel at the same N as eps_r -> 0 or the budget grows,
    // and the error would stall instead of falling (asymptotic unbiasedness).
    let mut c = last.max(1) as u64;
    while (c as f64) < n && c < N_HARD_MAX as u64 {
        c *= 2;
    }
    c.min(N_HARD_MAX as u64) as u32
}

/// The largest N ever allocated to one pixel.
pub const N_HARD_MAX: u32 = 1 << 24;

/// Robust per-pixel (sigma, ||C_d||) for allocation: both floored at a share of their image
/// means (`DtfParams::sigma_floor`, `norm_floor`). Where the n dependent samples happened to
/// agree (sigma = 0) or were all black, the raw formula would give N = 0 for ever and keep
/// the pixel at C_d however much is spent; with the floors every pixel's N grows without
/// bound as eps_r -> 0 or the budget grows, so DTF stays asymptotically unbiased.
/// `relative_floor` (F) also floors sigma at F ||C_d|| (eps_r mode's
/// `DtfParams::relative_sigma_floor`; budget weights pass 0).
pub fn robust_stats(dep: &Film, params: &DtfParams, relative_floor: f32) -> Vec<(f64, f64)> {
    let raw: Vec<(f64, f64)> = dep
        .pixels
        .par_iter()
        .map(|s| {
            let sg = sigma(s);
            let c = color_norm(s.mean);
            (
                if sg.is_finite() { sg.max(0.0) } else { 0.0 },
                if c.is_finite() { c } else { 0.0 },
            )
        })
        .collect();
    let k = raw.len().max(1) as f64;
    let mean_sigma = raw.iter().map(|r| r.0).sum::<f64>() / k;
    let mean_norm = raw.iter().map(|r| r.1).sum::<f64>() / k;
    let sf = params.sigma_floor as f64 * mean_sigma;
    let cf = params.norm_floor as f64 * mean_norm;
    let rel = relative_floor as f64;
    raw.into_iter()
        .map(|(sg, c)| {
            (
                sg.max(sf).max(rel * c),
                if cf > 0.0 { c.max(cf) } else { c },
            )
        })
        .collect()
}

/// Unclassified N = (3 sigma / (eps_r ||C_d||))^2 - n (paper §5): 3 sigma / sqrt(n + N)
/// is the 97% error bound of the pixel after both phases, required to be at most
/// eps_r ||C_d||.
///
/// Black pixels (||C_d|| = 0): with sigma = 0 too (every sample was black) the formula is
/// 0/0; we return -n, like any pixel with sigma = 0: no further samples are needed. With
/// sigma > 0 the samples were non-zero but cancelled (negative samples, e.g. from a
/// spectral-to-RGB conversion): no relative error can be reached, which is the limit
/// ||C_d|| -> 0+ of the formula, so we return +infinity (classified as the largest
/// category).
pub fn samples_for_error_raw(sigma: f64, cd_norm: f64, n: u32, eps_r: f64) -> f64 {
    // (NaN sigma or colour is treated like 0.)
    if sigma.is_nan() || sigma <= 0.0 {
        return -(n as f64);
    }
    if cd_norm.is_nan() || cd_norm <= 0.0 {
        return f64::INFINITY;
    }
    let r = 3.0 * sigma / (eps_r * cd_norm);
    r * r - n as f64
}

/// N for one pixel with a prescribed relative error: [`samples_for_error_raw`] classified
/// by [`classify`].
pub fn samples_for_error(sigma: f64, cd_norm: f64, n: u32, eps_r: f64, categories: &[u32]) -> u32 {
    classify(samples_for_error_raw(sigma, cd_norm, n, eps_r), categories)
}

/// Allocation mode (a), prescribed relative error `params.eps_r`: N[p] per pixel, row-major.
/// n is each pixel's own sample count in the dependent film.
pub fn allocate_relative(dep: &Film, params: &DtfParams) -> Result<Vec<u32>, String> {
    relative_counts(dep, params, false)
}

/// Top-up for the prescribed relative error (a departure from the paper, `top_up_rounds`):
/// the extra samples each pixel still needs after `total` = dependent + independent samples
/// so far, from the statistics of *all* of them: classify((3 sigma / (eps_r ||C||))^2 -
/// count), 0 where the pixel already reaches eps_r.
///
/// Why: phase 1 gives every pixel the same n jitters and paths, so a pixel can miss a thin
/// feature (a sliver of the light) in all of them, see sigma ~ 0 and get almost no samples;
/// its independent samples do see the feature, and with them the pixel asks for what it
/// needs. Without it the Cornell eps_r series stalled (RMSE 0.0118 at eps_r = 0.03, 0.0102
/// at 0.01). Floors as in [`robust_stats`] (image means of the merged statistics).
pub fn top_up(total: &Film, params: &DtfParams) -> Result<Vec<u32>, String> {
    relative_counts(total, params, true)
}

/// [`samples_for_error`] for every pixel of `film` with its own sample count; with
/// `zero_when_met`, 0 (not the smallest category) where eps_r is already reached.
fn relative_counts(
    film: &Film,
    params: &DtfParams,
    zero_when_met: bool,
) -> Result<Vec<u32>, String> {
    params.validate()?;
    let eps = params.eps_r as f64;
    let stats = robust_stats(film, params, params.relative_sigma_floor);
    Ok(film
        .pixels
        .par_iter()
        .zip(stats.par_iter())
        .map(|(s, &(sg, c))| {
            let want = samples_for_error_raw(sg, c, s.n, eps);
            if zero_when_met && want <= 0.0 {
                0
            } else {
                classify(want, &params.categories)
            }
        })
        .collect())
}

/// The scale bisection of the budget modes. T(s), the samples allocated at scale s, is a
/// non-decreasing step function; returns (s_lo, s_hi) with T(s_lo) <= B < T(s_hi), the
/// bracket narrowed in log scale until it is 1e-9 relative (no pixel changes category any
/// more), starting from the guess `s0`. None: T(s) <= B for every finite s (B out of reach).
fn bisect_scale(budget: u64, s0: f64, total: impl Fn(f64) -> u64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (0.0f64, s0.max(f64::MIN_POSITIVE));
    let mut doublings = 0;
    while total(hi) <= budget {
        lo = hi;
        hi *= 2.0;
        doublings += 1;
        if doublings > 2100 || !hi.is_finite() {
            return None;
        }
    }
    for _ in 0..2200 {
        let mid = if lo > 0.0 { (lo * hi).sqrt() } else { 0.5 * hi };
        if mid <= lo || mid >= hi || (lo > 0.0 && hi < lo * (1.0 + 1e-9)) {
            break;
        }
        if total(mid) <= budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some((lo, hi))
}

/// Budget-mode top-up (a departure from the paper, like [`top_up`]): share `extra_spp`
/// samples per pixel on average among the pixels again, from the statistics of all samples
/// so far (`total`: dependent + independent), so that each pixel's total approaches
/// s w[p] (w from `params.allocation`, clipped as in [`allocate_budget`]): extra[p] =
/// max(classify(s w[p]) - have[p], 0), with s the largest scale whose extras fit the budget
/// (bisection). A pixel whose n shared jitters all missed an edge shows its true sigma in
/// its independent samples and gets its share here.
pub fn top_up_budget(
    total: &Film,
    have: &[u32],
    params: &DtfParams,
    extra_spp: f64,
    cost: Option<&[f64]>,
) -> Result<Vec<u32>, String> {
    params.validate()?;
    check_cost(cost, total)?;
    if have.len() != total.pixels.len() {
        return Err(format!(
            "dtf: {} sample counts for {} pixels",
            have.len(),
            total.pixels.len()
        ));
    }
    let cats = &params.categories[..];
    let w = budget_weights(total, params, cost);
    let budget = (extra_spp.max(0.0) * w.len() as f64).round() as u64;
    // extra[p] at scale s
    let extra = |s: f64, wp: f64, h: u32| -> u32 {
        if wp > 0.0 && wp.is_finite() {
            classify(s * wp, cats).saturating_sub(h)
        } else {
            0
        }
    };
    let finite_sum: f64 = w.iter().filter(|x| x.is_finite()).sum();
    if budget == 0 || finite_sum <= 0.0 {
        return Ok(vec![0; have.len()]);
    }
    // The largest scale whose extras fit the budget.
    let spent_at = |s: f64| -> u64 {
        w.par_iter()
            .zip(have.par_iter())
            .map(|(&wp, &h)| extra(s, wp, h) as u64)
            .sum()
    };
    let s = match bisect_scale(budget, budget as f64 / finite_sum, spent_at) {
        Some((lo, _)) => lo,
        None => f64::INFINITY,
    };
    Ok(w.iter()
        .zip(have)
        .map(|(&wp, &h)| extra(s, wp, h))
        .collect())
}

fn check_cost(cost: Option<&[f64]>, film: &Film) -> Result<(), String> {
    match cost {
        Some(c) if c.len() != film.pixels.len() => Err(format!(
            "dtf: {} sample costs for {} pixels",
            c.len(),
            film.pixels.len()
        )),
        _ => Ok(()),
    }
}

/// Budget weights w[p] ([`Allocation`]) from a film's statistics, with the floors of
/// [`robust_stats`] and clipped at `max_weight_ratio` times their median: 0 where sigma = 0,
/// infinity for black pixels with sigma > 0. With per-pixel sample costs c[p] (e.g. rays
/// per sample) the optimal rules minimise the error for a given *time*: N ∝ sigma /
/// sqrt(c) (Lagrange on sum_p sigma^2 / N[p] with sum_p c[p] N[p] fixed); the paper's rule
/// ignores cost.
fn budget_weights(film: &Film, params: &DtfParams, cost: Option<&[f64]>) -> Vec<f64> {
    // The relative sigma floor is a minimum count for eps_r; in a budget it would hand the
    // light's own pixels (bright, sigma ~ 0) a large share.
    let mut w: Vec<f64> = robust_stats(film, params, 0.0)
        .into_iter()
        .enumerate()
        .map(|(p, (sg, c))| {
            if sg <= 0.0 {
                0.0
            } else if c > 0.0 {
                let w = params.allocation.weight(sg, c);
                match (params.allocation, cost) {
                    (Allocation::Paper, _) | (_, None) => w,
                    (_, Some(k)) => w / k[p].max(1e-3).sqrt(),
                }
            } else {
                f64::INFINITY
            }
        })
        .collect();
    // sigma^2/||C_d|| from n samples is heavy-tailed (one firefly in the dependent phase
    // makes one pixel swallow the budget): clip w at `max_weight_ratio` times its median,
    // which the tail cannot move, and keep the proportionality below that.
    if params.max_weight_ratio > 0.0 {
        let mut sorted: Vec<f64> = w.iter().copied().filter(|x| x.is_finite()).collect();
        if !sorted.is_empty() {
            let mid = sorted.len() / 2;
            let (_, med, _) = sorted.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
            let cap = *med * params.max_weight_ratio as f64;
            if cap > 0.0 {
                w.iter_mut().for_each(|x| *x = x.min(cap));
            }
        }
    }
    w
}

/// Allocation mode (b), a budget of B = round(spp_avg * pixels) independent samples in
/// total (phase 2 only; the n dependent samples are not counted).
///
/// N[p] proportional to w[p] (`params.allocation`; the paper's §3 w = sigma^2 / ||C_d||).
/// Then N[p] = classify(s w[p])
/// ([`classify`]: rounding up). The total T(s) is a non-decreasing step function of the
/// scale s; we bisect s ([`bisect_scale`]) to the last s_lo with T <= B and the
/// first s_hi with T > B, then promote the pixels whose category differs between s_lo and
/// s_hi one by one, largest w first, as long as each promotion brings the total closer to
/// B. The total then misses B by at most half of one category step of one pixel
/// (typically far below 1% for real images), unless B is out of reach:
/// - pixels with w = 0 (sigma = 0) always get the smallest category, and black pixels
///   with sigma > 0 (w = infinity) always the largest, as in mode (a);
/// - B below (above) what the smallest (largest) scale gives: all pixels at that scale;
/// - no pixel with a finite positive w (e.g. a noise-free image): w = 1 everywhere, i.e.
///   a uniform allocation close to spp_avg.
pub fn allocate_budget(dep: &Film, params: &DtfParams, spp_avg: f64) -> Result<Vec<u32>, String> {
    allocate_budget_costed(dep, params, spp_avg, None)
}

/// [`allocate_budget`] with per-pixel sample costs (see [`budget_weights`]).
pub fn allocate_budget_costed(
    dep: &Film,
    params: &DtfParams,
    spp_avg: f64,
    cost: Option<&[f64]>,
) -> Result<Vec<u32>, String> {
    params.validate()?;
    check_cost(cost, dep)?;
    if !(spp_avg.is_finite() && spp_avg >= 0.0) {
        return Err(format!(
            "dtf: budget of {spp_avg} samples per pixel: must be a non-negative number"
        ));
    }
    let cats = &params.categories[..];
    let mut w = budget_weights(dep, params, cost);
    if !w.iter().any(|&x| x > 0.0 && x.is_finite()) {
        w.iter_mut().for_each(|x| *x = 1.0);
    }
    let budget = (spp_avg * w.len() as f64).round() as u64;

    let cat = |s: f64, wp: f64| -> u32 {
        if wp == 0.0 {
            cats[0]
        } else if wp.is_infinite() {
            *cats.last().unwrap()
        } else {
            classify(s * wp, cats)
        }
    };
    let total = |s: f64| -> u64 { w.par_iter().map(|&wp| cat(s, wp) as u64).sum() };

    // Bracket T(s_lo) <= B < T(s_hi); then promotions between the two (below).
    if total(0.0) >= budget {
        return Ok(w.iter().map(|&wp| cat(0.0, wp)).collect());
    }
    let finite_sum: f64 = w.iter().filter(|x| x.is_finite()).sum();
    let Some((s_lo, s_hi)) = bisect_scale(budget, budget as f64 / finite_sum, total) else {
        // Out of reach: every pixel with w > 0 is at the largest category.
        return Ok(w.iter().map(|&wp| cat(f64::INFINITY, wp)).collect());
    };
    let mut alloc: Vec<u32> = w.iter().map(|&wp| cat(s_lo, wp)).collect();
    let mut spent: u64 = alloc.iter().map(|&a| a as u64).sum();
    let mut promote: Vec<(usize, u32)> = w
        .iter()
        .enumerate()
        .filter_map(|(i, &wp)| {
            let hi = cat(s_hi, wp);
            (hi > alloc[i]).then_some((i, hi))
        })
        .collect();
    promote.sort_by(|a, b| w[b.0].total_cmp(&w[a.0]).then(a.0.cmp(&b.0)));
    for (i, hi) in promote {
        let next = spent + (hi - alloc[i]) as u64;
        if next.abs_diff(budget) >= spent.abs_diff(budget) {
            break;
        }
        spent = next;
        alloc[i] = hi;
    }
    Ok(alloc)
}

// ---------------------------------------------------------------------------------------
// Display
// ---------------------------------------------------------------------------------------

/// Displayed colour C = (C_d n + C_i N) / (n + N) (paper §5, display step), with C_i the
/// filtered independent colour. Both counts zero gives black.
#[inline]
pub fn combine(cd: [f64; 3], n: u32, ci: [f64; 3], big_n: u32) -> [f64; 3] {
    let (a, b) = (n as f64, big_n as f64);
    if n == 0 && big_n == 0 {
        return [0.0; 3];
    }
    let k = 1.0 / (a + b);
    [
        (cd[0] * a + ci[0] * b) * k,
        (cd[1] * a + ci[1] * b) * k,
        (cd[2] * a + ci[2] * b) * k,
    ]
}

// ---------------------------------------------------------------------------------------
// Region forming and filter weights
// ---------------------------------------------------------------------------------------

/// The neighbourhood of one pixel and its normalised weights f*.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Accepted window side m (1: only the primary pixel, no filtering).
    pub m: u32,
    /// (x, y, f*[q - p]) for every pixel q of the accepted window that has independent
    /// samples, the primary pixel first. Non-negative, summing to 1.
    pub weights: Vec<(u32, u32, f64)>,
}

impl Region {
    /// M: number of pixels in the neighbourhood.
    pub fn count(&self) -> u32 {
        self.weights.len() as u32
    }
    /// f*[0], the weight of the primary pixel.
    pub fn primary_weight(&self) -> f64 {
        self.weights[0].2
    }
}

/// Result of [`Dtf::run`].
#[derive(Clone, Debug)]
pub struct DtfOutput {
    pub width: u32,
    pub height: u32,
    /// N[p]: the sample category used for region forming (the allocation).
    pub n: Vec<u32>,
    /// Accepted window side m per pixel (1 = unfiltered).
    pub m: Vec<u32>,
    /// M[p]: pixels in the accepted neighbourhood (m^2 inside the image, fewer at the
    /// border or next to pixels without independent samples).
    pub region: Vec<u32>,
    /// f*[0] per pixel, for diagnostics.
    pub primary_weight: Vec<f32>,
    /// C_i filtered: sum_q f*[q - p] C_i[q]; black where the pixel has no independent
    /// samples.
    pub filtered: RgbImage,
    /// Displayed colour C = (C_d n + C_i,filtered N) / (n + N).
    pub combined: RgbImage,
    /// Wall-clock seconds of the region forming, filtering and combination.
    pub seconds: f64,
}

/// A candidate neighbour: pixel index, offset from p and Delta_q.
#[derive(Clone, Copy, Debug)]
struct Cand {
    idx: usize,
    dx: i32,
    dy: i32,
    delta: f64,
}

#[derive(Default)]
struct Scratch {
    cand: Vec<Cand>,
    /// Accepted f*, aligned with the first entries of `cand`.
    w: Vec<f64>,
    tmp: Vec<f64>,
    sorted: Vec<f64>,
}

/// Per-pixel result of [`Dtf::run`]: m, M, f*[0], filtered C_i, displayed C.
type PixelOut = (u32, u32, f32, [f32; 3], [f32; 3]);

/// The tables DTF reads, taken from the two films and the allocation.
pub struct Dtf {
    params: DtfParams,
    width: usize,
    height: usize,
    /// C_d per pixel.
    cd: Vec<[f64; 3]>,
    /// sigma per pixel (phase 1).
    sigma: Vec<f64>,
    /// n per pixel (phase 1 count).
    n_dep: Vec<u32>,
    /// N per pixel, the category (for the "N[q] > N[p]" stopping rule).
    alloc: Vec<u32>,
    /// C_i per pixel.
    ci: Vec<[f64; 3]>,
    /// Actual phase-2 count per pixel.
    n_ind: Vec<u32>,
    /// Variance of C_i per channel (phase 2), for the independent guard.
    ci_var: Vec<[f64; 3]>,
}

impl Dtf {
    /// `dep`: phase-1 film (dependent tests); `indep`: phase-2 film (independent tests);
    /// `alloc`: N[p] as returned by [`allocate_relative`] or [`allocate_budget`].
    pub fn new(dep: &Film, indep: &Film, alloc: &[u32], params: &DtfParams) -> Result<Dtf, String> {
        params.validate()?;
        if (dep.width, dep.height) != (indep.width, indep.height) {
            return Err(format!(
                "dtf: the dependent film is {}x{} but the independent film is {}x{}",
                dep.width, dep.height, indep.width, indep.height
            ));
        }
        if alloc.len() != dep.pixels.len() || indep.pixels.len() != dep.pixels.len() {
            return Err(format!(
                "dtf: {} sample counts for a {}x{} film ({} pixels)",
                alloc.len(),
                dep.width,
                dep.height,
                dep.pixels.len()
            ));
        }
        Ok(Dtf {
            params: params.clone(),
            width: dep.width as usize,
            height: dep.height as usize,
            cd: dep.pixels.iter().map(|s| s.mean).collect(),
            sigma: dep.pixels.par_iter().map(sigma).collect(),
            n_dep: dep.pixels.iter().map(|s| s.n).collect(),
            alloc: alloc.to_vec(),
            // A pixel without samples has no C_i (whatever its stored mean says).
            ci: indep
                .pixels
                .iter()
                .map(|s| if s.n > 0 { s.mean } else { [0.0; 3] })
                .collect(),
            n_ind: indep.pixels.iter().map(|s| s.n).collect(),
            ci_var: indep
                .pixels
                .iter()
                .map(|s| {
                    if s.n > 1 {
                        s.variance_of_mean()
                    } else {
                        [f64::INFINITY; 3]
                    }
                })
                .collect(),
        })
    }

    /// Region and weights f* of pixel (x, y) (for inspection and tests; [`Dtf::run`] uses
    /// the same code).
    pub fn weights(&self, x: u32, y: u32) -> Region {
        assert!((x as usize) < self.width && (y as usize) < self.height);
        let mut s = Scratch::default();
        let m = self.region_into(x as usize, y as usize, &mut s);
        Region {
            m,
            weights: s
                .w
                .iter()
                .zip(&s.cand)
                .map(|(&w, c)| ((c.idx % self.width) as u32, (c.idx / self.width) as u32, w))
                .collect(),
        }
    }

    /// The independent guard (`DtfParams::guard`, k): the true colour difference of p and q
    /// is at least sum_c (|C_i[p] - C_i[q]|_c - k SE_c)^+, SE_c from the phase-2 variances.
    /// Phase 1 shares its jitters among all pixels, so a light's thin edge can be missed in
    /// every pixel of a row alike: C_d then calls two rows homogeneous that phase 2 shows
    /// are not (Cornell, the light's lower edge: 0.94 against 0.26, averaged to 0.63). As N
    /// grows the SE vanishes and any real difference is seen, so the filter vanishes too.
    #[inline]
    fn guard_delta(&self, p: usize, q: usize) -> f64 {
        let k = self.params.guard as f64;
        if k <= 0.0 || self.n_ind[p] < 2 || self.n_ind[q] < 2 {
            return 0.0;
        }
        let (a, b, va, vb) = (self.ci[p], self.ci[q], self.ci_var[p], self.ci_var[q]);
        (0..3)
            .map(|c| ((a[c] - b[c]).abs() - k * (va[c] + vb[c]).sqrt()).max(0.0))
            .sum::<f64>()
    }

    /// d(q - p) for window side m.
    #[inline]
    fn kernel(&self, dx: i32, dy: i32, m: u32) -> f64 {
        let r2 = (dx * dx + dy * dy) as f64;
        let m = m as f64;
        match self.params.kernel {
            Kernel::Pyramid => (m * std::f64::consts::FRAC_1_SQRT_2 - r2.sqrt()).max(0.0),
            Kernel::Gaussian => (-4.0 * r2 / (m * m)).exp(),
        }
    }

    /// Region forming for pixel p = (x, y) (paper §5, third step). On return the first
    /// `s.w.len()` candidates carry the accepted weights f*; returns the accepted m.
    fn region_into(&self, x: usize, y: usize, s: &mut Scratch) -> u32 {
        let (w, h) = (self.width as isize, self.height as isize);
        let p = y * self.width + x;
        s.cand.clear();
        s.w.clear();
        // f*[0] = 1: the primary pixel alone.
        s.cand.push(Cand {
            idx: p,
            dx: 0,
            dy: 0,
            delta: 0.0,
        });
        s.w.push(1.0);

        // N = 0 (no independent samples): C_i[p] does not exist and the display gives C_d.
        // sigma = 0: no Monte-Carlo error to trade for bias, so filtering can only hurt
        // (and sqrt(N) / (3 sigma) would divide by zero).
        let big_n = self.n_ind[p];
        let sg = self.sigma[p];
        if big_n == 0 || !(sg > 0.0 && sg.is_finite()) {
            return 1;
        }
        let np_stop = self.alloc[p] as f64 * self.params.stop_ratio as f64;
        let cdp = self.cd[p];
        let sqrt_n = (big_n as f64).sqrt();

        // Current (clipped, inclusive) window and sum_r Delta_r, both grown incrementally:
        // with p at offset floor((m-1)/2) the m-window contains the (m-1)-window, so only
        // the new L-shaped strip of pixels is visited.
        let (px, py) = (x as isize, y as isize);
        let (mut x0, mut x1, mut y0, mut y1) = (px, px, py, py);
        let mut sum_delta = 0.0;
        let mut f0_old = 1.0;
        let mut m_acc = 1;

        for m in 2..=self.params.m_max {
            let off = ((m - 1) / 2) as isize;
            let nx0 = (px - off).max(0);
            let nx1 = (px - off + m as isize - 1).min(w - 1);
            let ny0 = (py - off).max(0);
            let ny1 = (py - off + m as isize - 1).min(h - 1);
            for qy in ny0..=ny1 {
                for qx in nx0..=nx1 {
                    if (x0..=x1).contains(&qx) && (y0..=y1).contains(&qy) {
                        continue;
                    }
                    let q = qy as usize * self.width + qx as usize;
                    // "if N[p] < N[q] then stop for pixel p": keep the (m-1)-window. With
                    // a tolerance of `stop_ratio` (1: the paper's rule).
                    if self.alloc[q] as f64 > np_stop {
                        return m_acc;
                    }
                    // A pixel without independent samples has no C_i to average: it is
                    // left out of the neighbourhood (as if outside the image).
                    if self.n_ind[q] == 0 {
                        continue;
                    }
                    // Delta_q = ||C_d[p] - C_d[q]||.
                    let delta = diff_norm(cdp, self.cd[q]).max(self.guard_delta(p, q));
                    sum_delta += delta;
                    s.cand.push(Cand {
                        idx: q,
                        dx: (qx - px) as i32,
                        dy: (qy - py) as i32,
                        delta,
                    });
                }
            }
            (x0, x1, y0, y1) = (nx0, nx1, ny0, ny1);

            // Unnormalised coefficients f, clipped to f^+. M is the number of pixels
            // actually in the window, so that sum f = 1 holds at the image border too.
            let big_m = s.cand.len() as f64;
            let k = sqrt_n / (3.0 * sg * big_m.sqrt());
            if !k.is_finite() {
                return m_acc;
            }
            s.tmp.clear();
            match self.params.clamp {
                Clamp::Paper => {
                    // f = 1/M + sqrt(N)/(3 sigma sqrt(M)) (sum_r Delta_r / M - Delta_q).
                    let mean = sum_delta / big_m;
                    s.tmp.extend(
                        s.cand
                            .iter()
                            .map(|c| (1.0 / big_m + k * (mean - c.delta)).max(0.0)),
                    );
                }
                Clamp::ActiveSet => {
                    // f = k (lambda - Delta_q)^+, lambda from the sorted Delta: the largest
                    // active set {j smallest} with lambda_j = (1/k + sum_j Delta)/j > Delta_j.
                    s.sorted.clear();
                    s.sorted.extend(s.cand.iter().map(|c| c.delta));
                    s.sorted.sort_by(f64::total_cmp);
                    let inv_k = 1.0 / k;
                    let (mut prefix, mut lambda) = (0.0, 0.0);
                    for (j, &d) in s.sorted.iter().enumerate() {
                        prefix += d;
                        let l = (inv_k + prefix) / (j + 1) as f64;
                        if l > d {
                            lambda = l;
                        } else {
                            break;
                        }
                    }
                    s.tmp
                        .extend(s.cand.iter().map(|c| k * (lambda - c.delta).max(0.0)));
                }
            }
            // f^+ d and its sum. (Not incremental: f and d both change with M.)
            let mut sum = 0.0;
            for (f, c) in s.tmp.iter_mut().zip(&s.cand) {
                *f *= self.kernel(c.dx, c.dy, m);
                sum += *f;
            }
            if !(sum > 0.0 && sum.is_finite()) {
                return m_acc;
            }
            // f*_new[0] = f^+[0] d(0) / sum_r f^+[r-p] d(r-p): accept the m-window only if
            // the primary weight drops by at least Delta f[0]_min.
            let f0_new = s.tmp[0] / sum;
            if f0_old - f0_new < self.params.df0_min as f64 {
                return m_acc;
            }
            let inv = 1.0 / sum;
            s.w.clear();
            s.w.extend(s.tmp.iter().map(|f| f * inv));
            f0_old = f0_new;
            m_acc = m;
        }
        m_acc
    }

    /// Region forming, filtering and display for every pixel (in parallel).
    pub fn run(&self) -> DtfOutput {
        let t0 = Instant::now();
        let per_pixel: Vec<PixelOut> = (0..self.width * self.height)
            .into_par_iter()
            .map_init(Scratch::default, |s, p| {
                let (x, y) = (p % self.width, p / self.width);
                let m = self.region_into(x, y, s);
                // C_i,filtered = sum_q f*[q-p] C_i[q]  (C_i[p] = 0 when N[p] = 0).
                let mut c = [0.0f64; 3];
                for (&wq, cq) in s.w.iter().zip(&s.cand) {
                    for (ch, v) in c.iter_mut().enumerate() {
                        *v += wq * self.ci[cq.idx][ch];
                    }
                }
                // C = (C_d n + C_i N) / (n + N).
                let disp = combine(self.cd[p], self.n_dep[p], c, self.n_ind[p]);
                let f32s = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
                (m, s.w.len() as u32, s.w[0] as f32, f32s(c), f32s(disp))
            })
            .collect();
        let (w, h) = (self.width as u32, self.height as u32);
        let out = DtfOutput {
            width: w,
            height: h,
            n: self.alloc.clone(),
            m: per_pixel.iter().map(|r| r.0).collect(),
            region: per_pixel.iter().map(|r| r.1).collect(),
            primary_weight: per_pixel.iter().map(|r| r.2).collect(),
            filtered: RgbImage::new(w, h, per_pixel.iter().map(|r| r.3).collect()),
            combined: RgbImage::new(w, h, per_pixel.iter().map(|r| r.4).collect()),
            seconds: 0.0,
        };
        DtfOutput {
            seconds: t0.elapsed().as_secs_f64(),
            ..out
        }
    }
}

/// DTF in one call: [`Dtf::new`] then [`Dtf::run`]; `seconds` includes building the tables.
pub fn dtf_filter(
    dep: &Film,
    indep: &Film,
    alloc: &[u32],
    params: &DtfParams,
) -> Result<DtfOutput, String> {
    let t0 = Instant::now();
    let out = Dtf::new(dep, indep, alloc, params)?.run();
    Ok(DtfOutput {
        seconds: t0.elapsed().as_secs_f64(),
        ..out
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pixel with mean `mean`, per-channel standard deviation `sd` and `n` samples.
    fn px(mean: [f64; 3], sd: [f64; 3], n: u32) -> PixelStats {
        let k = n.saturating_sub(1) as f64;
        PixelStats {
            n,
            mean,
            m2: [sd[0] * sd[0] * k, sd[1] * sd[1] * k, sd[2] * sd[2] * k],
        }
    }

    fn film(w: u32, h: u32, f: impl Fn(u32, u32) -> PixelStats) -> Film {
        let mut film = Film::new(w, h).unwrap();
        for y in 0..h {
            for x in 0..w {
                let i = film.index(x, y);
                film.pixels[i] = f(x, y);
            }
        }
        film
    }

    /// Deterministic hash noise in [0, 1).
    fn hash(x: u32, y: u32, salt: u32) -> f64 {
        let mut v = x
            .wrapping_mul(0x9E37_79B9)
            .wrapping_add(y.wrapping_mul(0x85EB_CA6B))
            .wrapping_add(salt.wrapping_mul(0xC2B2_AE35));
        v ^= v >> 16;
        v = v.wrapping_mul(0x7FEB_352D);
        v ^= v >> 15;
        v = v.wrapping_mul(0x846C_A68B);
        v ^= v >> 16;
        v as f64 / 4_294_967_296.0
    }

    fn grey(v: f64) -> [f64; 3] {
        [v, v, v]
    }

    #[test]
    fn norm_and_sigma() {
        assert_eq!(color_norm([1.0, -2.0, 0.5]), 3.5);
        let s = px([0.5, 0.3, 0.2], [0.1, 0.02, 0.03], 50);
        assert!((sigma(&s) - 0.15).abs() < 1e-12);
        assert_eq!(sigma(&px([1.0; 3], [0.1; 3], 1)), 0.0);
    }

    #[test]
    fn classify_rounds_up_and_clamps() {
        let c = DtfParams::default().categories;
        let cases = [
            (-25.0, 0),
            (0.0, 0),
            (0.5, 1),
            (1.0, 1),
            (1.01, 10),
            (10.0, 10),
            (20.5, 50),
            (499.0, 500),
            // past the largest category the classes double: 1000, 2000, ... up to N_HARD_MAX
            (501.0, 1000),
            (1999.0, 2000),
            (1e30, N_HARD_MAX),
            (f64::INFINITY, N_HARD_MAX),
            (f64::NAN, 500),
        ];
        for (v, want) in cases {
            assert_eq!(classify(v, &c), want, "classify({v})");
        }
        assert_eq!(classify(-1.0, &[5, 7]), 5);
    }

    #[test]
    fn samples_follow_formula_and_categories() {
        let c = DtfParams::default().categories;
        // (3 * 0.1 / (0.03 * 1))^2 - 50 = 100 - 50 = 50 -> 50
        assert!((samples_for_error_raw(0.1, 1.0, 50, 0.03) - 50.0).abs() < 1e-9);
        assert_eq!(samples_for_error(0.1, 1.0, 50, 0.03, &c), 50);
        // (3 * 0.12 / 0.03)^2 - 50 = 144 - 50 = 94 -> 100
        assert!((samples_for_error_raw(0.12, 1.0, 50, 0.03) - 94.0).abs() < 1e-9);
        assert_eq!(samples_for_error(0.12, 1.0, 50, 0.03, &c), 100);
        // (3 * 0.05 / 0.03)^2 - 50 = 25 - 50 < 0 -> 0
        assert_eq!(samples_for_error(0.05, 1.0, 50, 0.03, &c), 0);
        // (3 * 0.3 / 0.03)^2 - 50 = 850 -> the doubled class 1000
        assert_eq!(samples_for_error(0.3, 1.0, 50, 0.03, &c), 1000);
        // relative: doubling the colour quarters the samples: (3*0.2/(0.03*2))^2 - 10 = 90
        assert!((samples_for_error_raw(0.2, 2.0, 10, 0.03) - 90.0).abs() < 1e-9);
        // black pixels
        assert_eq!(samples_for_error(0.0, 0.0, 50, 0.03, &c), 0);
        assert_eq!(samples_for_error(0.1, 0.0, 50, 0.03, &c), N_HARD_MAX);

        // Through the film: sigma = 0.1 + 0.02 + 0.03 = 0.15, ||C_d|| = 1,
        // (3 * 0.15 / 0.03)^2 - 50 = 175 -> 200.
        let f = film(2, 1, |x, _| {
            if x == 0 {
                px([0.5, 0.3, 0.2], [0.1, 0.02, 0.03], 50)
            } else {
                px([0.0; 3], [0.0; 3], 50)
            }
        });
        // the paper's raw formula (no floors): the black pixel needs nothing more
        let raw = DtfParams {
            sigma_floor: 0.0,
            norm_floor: 0.0,
            relative_sigma_floor: 0.0,
            ..Default::default()
        };
        assert_eq!(allocate_relative(&f, &raw).unwrap(), vec![200, 0]);
        // with the default floors the black pixel still gets samples (it may not be black)
        assert!(allocate_relative(&f, &DtfParams::default()).unwrap()[1] > 0);
    }

    #[test]
    fn budget_is_spent_within_tolerance() {
        let (w, h) = (64u32, 48u32);
        let f = film(w, h, |x, y| {
            let c = 0.05 + hash(x, y, 1) * 2.0;
            let sd = 0.01 + hash(x, y, 2).powi(2) * 3.0;
            px(grey(c), grey(sd), 40)
        });
        // the raw proportionality: no floors, no clipping; every allocation rule
        for allocation in [Allocation::Paper, Allocation::Mse, Allocation::RelMse] {
            let params = DtfParams {
                sigma_floor: 0.0,
                norm_floor: 0.0,
                relative_sigma_floor: 0.0,
                max_weight_ratio: 0.0,
                allocation,
                ..Default::default()
            };
            for spp in [3.0, 17.0, 43.0, 120.0] {
                let a = allocate_budget(&f, &params, spp).unwrap();
                let spent: u64 = a.iter().map(|&v| v as u64).sum();
                let budget = spp * (w * h) as f64;
                let rel = (spent as f64 - budget).abs() / budget;
                assert!(rel < 0.02, "spp {spp}: spent {spent} of {budget}");
                assert!(a
                    .iter()
                    .all(|v| params.categories.contains(v) || v % 500 == 0));
                // Monotone in w (e.g. the paper's sigma^2 / ||C_d||).
                let wv: Vec<f64> = f
                    .pixels
                    .iter()
                    .map(|s| allocation.weight(sigma(s), color_norm(s.mean)))
                    .collect();
                for i in 0..a.len() {
                    for j in 0..a.len() {
                        if wv[i] < wv[j] {
                            assert!(a[i] <= a[j], "{allocation:?} spp {spp}: w order broken");
                        }
                    }
                }
            }
        }
        let params = DtfParams {
            sigma_floor: 0.0,
            norm_floor: 0.0,
            relative_sigma_floor: 0.0,
            max_weight_ratio: 0.0,
            ..Default::default()
        };
        // Beyond the largest category the classes go on doubling: large budgets are spent too.
        let a = allocate_budget(&f, &params, 5000.0).unwrap();
        let spent: u64 = a.iter().map(|&v| v as u64).sum();
        assert!(
            (spent as f64 / (5000.0 * (w * h) as f64) - 1.0).abs() < 0.05,
            "{spent}"
        );
        // Zero budget: the smallest category.
        let a = allocate_budget(&f, &params, 0.0).unwrap();
        assert!(a.iter().all(|&v| v == 0));
        // Noise-free image: uniform fallback.
        let flat = film(10, 10, |_, _| px(grey(1.0), grey(0.0), 40));
        let a = allocate_budget(&flat, &params, 20.0).unwrap();
        assert!(a.iter().all(|&v| v == 20), "{a:?}");
    }

    fn setup(
        w: u32,
        h: u32,
        dep: impl Fn(u32, u32) -> PixelStats,
        ind: impl Fn(u32, u32) -> PixelStats,
        alloc: impl Fn(u32, u32) -> u32,
        params: &DtfParams,
    ) -> Dtf {
        let d = film(w, h, dep);
        let i = film(w, h, ind);
        let a: Vec<u32> = (0..w * h).map(|p| alloc(p % w, p / w)).collect();
        Dtf::new(&d, &i, &a, params).unwrap()
    }

    #[test]
    fn flat_region_pixel_weights_hand_computed() {
        // Flat C_d: Delta = 0, f = 1/M, f* proportional to the pyramid d = m/sqrt2 - r.
        let params = DtfParams {
            m_max: 2,
            ..Default::default()
        };
        let dtf = setup(
            5,
            5,
            |_, _| px(grey(1.0), grey(0.2), 50),
            |_, _| px(grey(1.0), grey(0.2), 10),
            |_, _| 10,
            &params,
        );
        let r = dtf.weights(2, 2);
        assert_eq!(r.m, 2);
        // Even window: p at offset floor((2-1)/2) = 0 from the top-left corner.
        let pos: Vec<(u32, u32)> = r.weights.iter().map(|w| (w.0, w.1)).collect();
        assert_eq!(pos, vec![(2, 2), (3, 2), (2, 3), (3, 3)]);
        let s2 = std::f64::consts::SQRT_2;
        let (d0, d1) = (s2, s2 - 1.0);
        let sum = d0 + 2.0 * d1; // the diagonal pixel sits at the pyramid's edge: d = 0
        let want = [d0 / sum, d1 / sum, d1 / sum, 0.0];
        for (got, want) in r.weights.iter().zip(want) {
            assert!((got.2 - want).abs() < 1e-12, "{:?} vs {want}", r.weights);
        }
    }

    #[test]
    fn constant_image_passes_unchanged() {
        for kernel in [Kernel::Pyramid, Kernel::Gaussian] {
            for clamp in [Clamp::Paper, Clamp::ActiveSet] {
                let params = DtfParams {
                    kernel,
                    clamp,
                    ..Default::default()
                };
                let dtf = setup(
                    9,
                    7,
                    |_, _| px([0.3, 0.5, 0.7], [0.2, 0.1, 0.3], 50),
                    |_, _| px([0.35, 0.45, 0.75], [0.2, 0.1, 0.3], 20),
                    |_, _| 20,
                    &params,
                );
                let out = dtf.run();
                for (i, c) in out.filtered.data.iter().enumerate() {
                    for (ch, want) in [0.35f32, 0.45, 0.75].iter().enumerate() {
                        assert!((c[ch] - want).abs() < 1e-6, "pixel {i}: {c:?}");
                    }
                }
                // And it did form regions: interior pixels reach m_max.
                assert_eq!(out.m[3 * 9 + 4], 4, "{kernel:?} {clamp:?}");
                // Combined: (C_d * 50 + C_i * 20) / 70.
                let want = (0.3 * 50.0 + 0.35 * 20.0) / 70.0;
                assert!((out.combined.data[10][0] as f64 - want).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn edge_between_flat_regions_is_not_smeared() {
        // Left half C_d = 1, right half C_d = 0.2 (Delta = 2.4 across the edge),
        // sigma = 0.3, N = 10. Left C_i noisy in [0.9, 1.1], right C_i exactly 0.2.
        for clamp in [Clamp::Paper, Clamp::ActiveSet] {
            let params = DtfParams {
                clamp,
                ..Default::default()
            };
            let left = |x: u32| x < 6;
            let dtf = setup(
                12,
                8,
                |x, _| px(grey(if left(x) { 1.0 } else { 0.2 }), grey(0.1), 50),
                |x, y| {
                    let v = if left(x) {
                        0.9 + 0.2 * hash(x, y, 7)
                    } else {
                        0.2
                    };
                    px(grey(v), grey(0.1), 10)
                },
                |_, _| 10,
                &params,
            );
            for y in 0..8 {
                for x in 0..12 {
                    let r = dtf.weights(x, y);
                    for &(qx, _, wq) in &r.weights {
                        if left(qx) != left(x) {
                            assert_eq!(wq, 0.0, "({x},{y}) takes from ({qx}) across the edge");
                        }
                    }
                }
            }
            let out = dtf.run();
            let mut filtered_somewhere = false;
            for y in 0..8 {
                for x in 0..12 {
                    let c = out.filtered.get(x, y)[0];
                    if left(x) {
                        assert!((0.9..=1.1).contains(&c), "({x},{y}) = {c}");
                        filtered_somewhere |= out.m[(y * 12 + x) as usize] > 1;
                    } else {
                        assert!((c - 0.2).abs() < 1e-6, "({x},{y}) = {c}");
                    }
                }
            }
            assert!(filtered_somewhere);
        }
    }

    #[test]
    fn weights_non_negative_and_normalised_everywhere() {
        let (w, h) = (13u32, 11u32);
        let cats = DtfParams::default().categories;
        for kernel in [Kernel::Pyramid, Kernel::Gaussian] {
            for clamp in [Clamp::Paper, Clamp::ActiveSet] {
                let params = DtfParams {
                    kernel,
                    clamp,
                    m_max: 5,
                    ..Default::default()
                };
                let alloc = |x: u32, y: u32| cats[1 + (hash(x, y, 3) * 4.0) as usize];
                let dtf = setup(
                    w,
                    h,
                    |x, y| {
                        // blocks of colour, some noise, a few zero-sigma pixels
                        let base = if (x / 4 + y / 3) % 2 == 0 { 0.8 } else { 0.3 };
                        let sd = if hash(x, y, 4) < 0.1 { 0.0 } else { 0.5 };
                        px(
                            [base + 0.05 * hash(x, y, 5), base, base * 0.5],
                            grey(sd),
                            50,
                        )
                    },
                    |x, y| {
                        // a few pixels lost all independent samples
                        let n = if hash(x, y, 6) < 0.05 { 0 } else { alloc(x, y) };
                        px(grey(hash(x, y, 8)), grey(0.1), n)
                    },
                    alloc,
                    &params,
                );
                let mut sizes = [0usize; 6];
                for y in 0..h {
                    for x in 0..w {
                        let r = dtf.weights(x, y);
                        let sum: f64 = r.weights.iter().map(|q| q.2).sum();
                        assert!((sum - 1.0).abs() < 1e-12, "({x},{y}) sum {sum}");
                        assert_eq!((r.weights[0].0, r.weights[0].1), (x, y));
                        let f0 = r.primary_weight();
                        for &(qx, qy, wq) in &r.weights {
                            assert!(wq >= 0.0 && wq <= f0 + 1e-15, "({x},{y}): {wq} > {f0}");
                            assert!(qx < w && qy < h);
                            let off = ((r.m - 1) / 2) as i64;
                            let (dx, dy) = (qx as i64 - x as i64, qy as i64 - y as i64);
                            assert!((-off..=r.m as i64 - 1 - off).contains(&dx));
                            assert!((-off..=r.m as i64 - 1 - off).contains(&dy));
                            assert!(
                                alloc(qx, qy) as f64
                                    <= alloc(x, y) as f64 * params.stop_ratio as f64
                            );
                        }
                        sizes[r.m as usize] += 1;
                    }
                }
                // The test image exercises several window sizes.
                assert!(
                    sizes.iter().filter(|&&c| c > 0).count() >= 3,
                    "{kernel:?} {clamp:?}: {sizes:?}"
                );
            }
        }
    }

    #[test]
    fn larger_neighbour_category_stops_region() {
        // Neighbour (3, 2) has N = 50, five times the others' 10: beyond the default
        // tolerance (2.5x), so it stops regions as in the paper.
        let build = |big: u32, params: &DtfParams| {
            setup(
                6,
                6,
                |_, _| px(grey(1.0), grey(0.3), 50),
                |_, _| px(grey(1.0), grey(0.3), 10),
                move |x, y| if (x, y) == (3, 2) { big } else { 10 },
                params,
            )
        };
        for (big, params) in [
            (50, DtfParams::default()),
            (
                20,
                DtfParams {
                    stop_ratio: 1.0,
                    ..Default::default()
                },
            ),
        ] {
            let dtf = build(big, &params);
            // (2, 2): its 2x2 window already holds (3, 2).
            assert_eq!(dtf.weights(2, 2).m, 1);
            // (1, 2): the 2x2 (x 1..=2) and 3x3 (x 0..=2) windows are fine; the 4x4 one
            // (x 0..=3) holds (3, 2) and stops the growth.
            assert_eq!(dtf.weights(1, 2).m, 3);
            // (3, 2) itself may take from its smaller-N neighbours.
            assert_eq!(dtf.weights(3, 2).m, 4);
        }
        // One category step (20 against 10) is within the noise of sigma^2 from n samples:
        // the default tolerates it, the paper's rule (ratio 1) does not.
        let dtf = build(20, &DtfParams::default());
        assert_eq!(dtf.weights(2, 2).m, 4);
    }

    #[test]
    fn top_up_asks_for_what_the_samples_so_far_need() {
        // eps_r = 0.1, no floors: a pixel with ||C|| = 3 (grey 1), sigma = 3 * 0.3 = 0.9 and
        // 100 samples needs (3 * 0.9 / (0.1 * 3))^2 = 81 in all: nothing more. With
        // sigma = 3 * 1.0 it needs 900, i.e. 800 more, classified up to 1000.
        let params = DtfParams {
            eps_r: 0.1,
            sigma_floor: 0.0,
            norm_floor: 0.0,
            ..Default::default()
        };
        let f = film(2, 1, |x, _| {
            px(grey(1.0), grey(if x == 0 { 0.3 } else { 1.0 }), 100)
        });
        assert_eq!(top_up(&f, &params).unwrap(), vec![0, 1000]);
        // A pixel whose samples all agreed needs nothing.
        let f = film(1, 1, |_, _| px(grey(1.0), grey(0.0), 100));
        assert_eq!(top_up(&f, &params).unwrap(), vec![0]);
    }

    #[test]
    fn cost_aware_allocation_follows_sigma_over_sqrt_cost() {
        // Two equal pixels, the second's samples four times as costly: N ∝ sigma / sqrt(c)
        // gives it half the samples (the paper's rule ignores the cost).
        let f = film(2, 1, |_, _| px(grey(1.0), grey(0.5), 16));
        let params = DtfParams {
            categories: (0..=1000).collect(),
            sigma_floor: 0.0,
            norm_floor: 0.0,
            ..Default::default()
        };
        let cost = [1.0, 4.0];
        let a = allocate_budget_costed(&f, &params, 300.0, Some(&cost)).unwrap();
        assert!((a[0] as f64 / a[1] as f64 - 2.0).abs() < 0.02, "{a:?}");
        assert!((a[0] + a[1]) as i64 - 600 <= 1, "{a:?}");
        let paper = DtfParams {
            allocation: Allocation::Paper,
            ..params.clone()
        };
        let a = allocate_budget_costed(&f, &paper, 300.0, Some(&cost)).unwrap();
        assert_eq!(a[0], a[1]);
        // A cost table of the wrong size is an error, not a panic.
        assert!(allocate_budget_costed(&f, &params, 300.0, Some(&[1.0])).is_err());
    }

    #[test]
    fn guard_keeps_apart_what_phase_1_missed() {
        // Phase 1 saw one flat field; phase 2 shows rows y < 3 at 1.0 and y >= 3 at 0.3,
        // far beyond their standard errors (0.3 / sqrt(1000)).
        let build = |guard: f32| {
            setup(
                8,
                8,
                |_, _| px(grey(0.5), grey(0.3), 16),
                |_, y| px(grey(if y < 3 { 1.0 } else { 0.3 }), grey(0.3), 1000),
                |_, _| 1000,
                &DtfParams {
                    guard,
                    ..Default::default()
                },
            )
        };
        let across = |r: &Region| {
            r.weights
                .iter()
                .filter(|q| q.1 >= 3)
                .map(|q| q.2)
                .sum::<f64>()
        };
        // Without the guard, pixel (4, 2) averages in rows 3 and 4; with it, none of them.
        assert!(across(&build(0.0).weights(4, 2)) > 0.1);
        assert_eq!(across(&build(3.0).weights(4, 2)), 0.0);
        // Within its own rows the guard still lets the filter work.
        let r = build(3.0).weights(4, 2);
        assert!(r.primary_weight() < 0.5, "f*[0] = {}", r.primary_weight());
    }

    #[test]
    fn top_up_budget_fits_the_budget_and_follows_the_weights() {
        // Three pixels with sigma 0.1, 0.2, 0.4 (grey 1), each already holding 10 samples;
        // 60 more per pixel on average. Fine categories: the totals follow N ∝ sigma.
        let f = film(3, 1, |x, _| px(grey(1.0), grey(0.1 * (1 << x) as f64), 50));
        let params = DtfParams {
            categories: (0..=1000).collect(),
            sigma_floor: 0.0,
            norm_floor: 0.0,
            ..Default::default()
        };
        let have = [10, 10, 10];
        let e = top_up_budget(&f, &have, &params, 60.0, None).unwrap();
        let spent: u32 = e.iter().sum();
        assert!((177..=180).contains(&spent), "{e:?}");
        // totals (10 + e) in ratio 1 : 2 : 4 (to one sample)
        let t: Vec<f64> = e.iter().map(|&v| (v + 10) as f64).collect();
        assert!(
            (t[1] / t[0] - 2.0).abs() < 0.1 && (t[2] / t[0] - 4.0).abs() < 0.1,
            "{t:?}"
        );
        // a pixel that already holds more than its share gets nothing
        let e = top_up_budget(&f, &[10, 10, 1000], &params, 30.0, None).unwrap();
        assert_eq!(e[2], 0, "{e:?}");
        assert!(e.iter().sum::<u32>() <= 90);
        // wrong sizes are errors
        assert!(top_up_budget(&f, &[1, 2], &params, 10.0, None).is_err());
    }

    #[test]
    fn degenerate_pixels_are_not_filtered() {
        let dtf = setup(
            4,
            4,
            |x, _| px(grey(1.0), grey(if x == 0 { 0.0 } else { 0.3 }), 50),
            |x, y| px(grey(2.0), grey(0.3), if (x, y) == (2, 1) { 0 } else { 10 }),
            |_, _| 10,
            &DtfParams::default(),
        );
        // sigma = 0: primary only.
        assert_eq!(dtf.weights(0, 1).m, 1);
        assert_eq!(dtf.weights(0, 1).weights, vec![(0, 1, 1.0)]);
        // No independent samples: primary only, filtered black, displayed C_d.
        assert_eq!(dtf.weights(2, 1).weights, vec![(2, 1, 1.0)]);
        // ... and left out of its neighbours' regions.
        let r = dtf.weights(1, 1);
        assert!(r.m > 1 && r.weights.iter().all(|q| (q.0, q.1) != (2, 1)));
        let out = dtf.run();
        assert_eq!(out.filtered.get(2, 1), [0.0; 3]);
        assert_eq!(out.combined.get(2, 1), [1.0; 3]);
        assert!(out
            .combined
            .data
            .iter()
            .all(|c| c.iter().all(|v| v.is_finite())));
    }

    #[test]
    fn combination_formula_hand_computed() {
        let c = combine([1.0, 2.0, 3.0], 50, [2.0, 2.0, 0.0], 150);
        assert_eq!(c, [1.75, 2.0, 0.75]);
        assert_eq!(combine([1.0; 3], 0, [0.5; 3], 0), [0.0; 3]);
        assert_eq!(combine([1.0; 3], 40, [0.5; 3], 0), [1.0; 3]);
        // Through the filter on a 1x1 image (no neighbours: filtered = C_i).
        let d = film(1, 1, |_, _| px([1.0, 2.0, 3.0], grey(0.5), 50));
        let i = film(1, 1, |_, _| px([2.0, 2.0, 0.0], grey(0.5), 150));
        let out = dtf_filter(&d, &i, &[100], &DtfParams::default()).unwrap();
        assert_eq!(out.filtered.data[0], [2.0, 2.0, 0.0]);
        assert_eq!(out.combined.data[0], [1.75, 2.0, 0.75]);
        assert_eq!((out.m[0], out.region[0], out.n[0]), (1, 1, 100));
        assert!(out.seconds >= 0.0);
    }

    /// C_d varies so that every neighbour has Delta_q > 0 (a 2D gradient); N grows.
    fn gradient(clamp: Clamp, big_n: u32) -> Dtf {
        gradient_guarded(clamp, big_n, DtfParams::default().guard)
    }

    fn gradient_guarded(clamp: Clamp, big_n: u32, guard: f32) -> Dtf {
        let params = DtfParams {
            clamp,
            categories: vec![0, big_n],
            guard,
            ..Default::default()
        };
        setup(
            9,
            9,
            |x, y| {
                px(
                    grey(1.0 + 0.01 * (x as f64 + 2.3 * y as f64)),
                    grey(0.3),
                    50,
                )
            },
            |x, y| px(grey(1.0 + hash(x, y, 9)), grey(0.3), big_n),
            |_, _| big_n,
            &params,
        )
    }

    #[test]
    fn filter_vanishes_as_n_grows() {
        let mut last = 0.0;
        for big_n in [1u32, 100, 10_000, 1_000_000, 100_000_000] {
            let dtf = gradient(Clamp::ActiveSet, big_n);
            let f0 = dtf.weights(4, 4).primary_weight();
            if big_n == 1 {
                assert!(f0 < 0.5, "N = 1 should filter: f*[0] = {f0}");
            }
            assert!(f0 >= last - 1e-12, "N = {big_n}: f*[0] {f0} < {last}");
            last = f0;
        }
        assert!(last > 0.999, "f*[0] = {last}");
        // The filtered image converges to C_i.
        let dtf = gradient(Clamp::ActiveSet, 100_000_000);
        let out = dtf.run();
        for y in 0..9 {
            for x in 0..9 {
                let want = 1.0 + hash(x, y, 9);
                assert!((out.filtered.get(x, y)[0] as f64 - want).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn paper_clamp_limit_behaviour() {
        // An isolated bright pixel in a dark flat field: every neighbour has the same
        // Delta > mean Delta, so with the paper's f^+ the filter vanishes as N grows...
        let spot = |big_n: u32| {
            setup(
                7,
                7,
                |x, y| {
                    px(
                        grey(if (x, y) == (3, 3) { 2.0 } else { 0.5 }),
                        grey(0.3),
                        50,
                    )
                },
                |_, _| px(grey(1.0), grey(0.3), big_n),
                |_, _| big_n,
                &DtfParams {
                    categories: vec![0, big_n],
                    ..Default::default()
                },
            )
            .weights(3, 3)
        };
        assert!(spot(1).primary_weight() < 0.9);
        assert_eq!(spot(100_000_000).m, 1);
        // ... but on a gradient it keeps averaging over the pixels with Delta_q < mean
        // Delta, however large N is (the documented caveat of Clamp::Paper), unless the
        // independent guard sees that the neighbours' phase-2 means differ.
        let f0 = gradient_guarded(Clamp::Paper, 100_000_000, 0.0)
            .weights(4, 4)
            .primary_weight();
        assert!(f0 < 0.95, "f*[0] = {f0}");
        let f0 = gradient_guarded(Clamp::Paper, 100_000_000, 3.0)
            .weights(4, 4)
            .primary_weight();
        assert_eq!(f0, 1.0);
    }

    #[test]
    fn bad_inputs_are_reported() {
        let d = film(3, 2, |_, _| px(grey(1.0), grey(0.1), 50));
        let i = film(2, 3, |_, _| px(grey(1.0), grey(0.1), 10));
        let e = Dtf::new(&d, &i, &[10; 6], &DtfParams::default())
            .err()
            .unwrap();
        assert!(e.contains("3x2") && e.contains("2x3"), "{e}");
        let e = Dtf::new(&d, &d, &[10; 5], &DtfParams::default())
            .err()
            .unwrap();
        assert!(e.contains("5 sample counts"), "{e}");
        let bad = DtfParams {
            categories: vec![10, 1],
            ..Default::default()
        };
        assert!(allocate_relative(&d, &bad).is_err());
        assert!(allocate_budget(&d, &DtfParams::default(), -1.0).is_err());
    }
}

#[cfg(test)]
mod robust_tests {
    use super::*;
    use crate::film::{Film, PixelStats};

    /// A film where most pixels are noisy and a few had dependent samples that all agreed
    /// (sigma = 0), one black, one a firefly.
    fn film() -> Film {
        let mut f = Film::new(16, 16).unwrap();
        for (i, p) in f.pixels.iter_mut().enumerate() {
            let v = 0.5 + (i % 7) as f64 * 0.1;
            *p = PixelStats {
                n: 16,
                mean: [v; 3],
                m2: [0.04 * 15.0; 3],
            };
        }
        f.pixels[3] = PixelStats {
            n: 16,
            mean: [0.4; 3],
            m2: [0.0; 3],
        }; // agreeing samples
        f.pixels[4] = PixelStats {
            n: 16,
            mean: [0.0; 3],
            m2: [0.0; 3],
        }; // black
        f.pixels[5] = PixelStats {
            n: 16,
            mean: [0.6; 3],
            m2: [4000.0; 3],
        }; // firefly
        f
    }

    #[test]
    fn no_pixel_is_starved_and_all_grow_with_the_budget() {
        let f = film();
        let p = DtfParams::default();
        let small = allocate_budget(&f, &p, 20.0).unwrap();
        let large = allocate_budget(&f, &p, 2000.0).unwrap();
        for i in [3usize, 4] {
            assert!(small[i] >= 1, "pixel {i} starved: {}", small[i]);
            assert!(
                large[i] > 10 * small[i].max(1) / 2,
                "pixel {i} does not grow: {} -> {}",
                small[i],
                large[i]
            );
        }
        // the firefly cannot swallow the budget: at most ~16x the median share
        let mut sorted = large.clone();
        sorted.sort();
        let median = sorted[sorted.len() / 2] as f64;
        assert!(
            (large[5] as f64) <= 40.0 * median,
            "firefly got {} vs median {median}",
            large[5]
        );
        // prescribed error: as eps_r falls every pixel's N grows without bound
        let a = allocate_relative(
            &f,
            &DtfParams {
                eps_r: 0.1,
                ..p.clone()
            },
        )
        .unwrap();
        let b = allocate_relative(
            &f,
            &DtfParams {
                eps_r: 0.01,
                ..p.clone()
            },
        )
        .unwrap();
        for i in 0..a.len() {
            assert!(
                b[i] > a[i] || b[i] == N_HARD_MAX,
                "pixel {i}: {} -> {}",
                a[i],
                b[i]
            );
        }
    }
}
