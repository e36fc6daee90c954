//! Sample allocation N[p] from the dependent phase: for a prescribed relative error eps_r
//! (paper §3) or a budget of samples or time, plus top-up rounds from all samples so far.

use super::*;
use crate::film::Film;
use rayon::prelude::*;

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
/// means (`DtfParams::floor`). Where the n dependent samples happened to
/// agree (sigma = 0) or were all black, the raw formula would give N = 0 for ever and keep
/// the pixel at C_d however much is spent; with the floors every pixel's N grows without
/// bound as eps_r -> 0 or the budget grows, so DTF stays asymptotically unbiased.
/// `relative_floor` (F) also floors sigma at F ||C_d|| (eps_r mode's
/// `DtfParams::relative_sigma_floor`; budget weights pass 0).
pub fn robust_stats(dep: &Film, params: &DtfParams, relative_floor: f32) -> Vec<(f64, f64)> {
    let raw: Vec<(f64, f64)> = (0..dep.pixels.len())
        .into_par_iter()
        .map(|i| {
            let sg = film_sigma(dep, i);
            let c = color_norm(film_value(dep, i));
            (
                if sg.is_finite() { sg.max(0.0) } else { 0.0 },
                if c.is_finite() { c } else { 0.0 },
            )
        })
        .collect();
    let k = raw.len().max(1) as f64;
    let mean_sigma = raw.iter().map(|r| r.0).sum::<f64>() / k;
    let mean_norm = raw.iter().map(|r| r.1).sum::<f64>() / k;
    let sf = params.floor as f64 * mean_sigma;
    let cf = params.floor as f64 * mean_norm;
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
    let eps = params.eps()?;
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
