//! Rushmeier and Ward's energy-preserving filter ("Energy preserving non-linear filters",
//! SIGGRAPH 1994, section 4.1) and the pilot-sample quantities that plan the trials, as
//! pure functions of film statistics (the missing equations are written out in
//! `papers/README.md`; the names here are those).
//!
//! - Pilot (100x100 at 16 trials): S_16, the average deviation of a pixel's 16-trial mean,
//!   and L_ave, the image's average luminance; Lt_vis = L_ave / N_MID (one display unit
//!   of a linear tone operator mapping L_ave to N_MID = 127.5); Mt = 16 (S_16 / (D Lt_vis))^2
//!   (Eq. 10); Mt_ceiling = 4 Mt.
//! - Convergence of pixel p after M trials: t S_p / sqrt(M) <= D Lt_vis.
//! - Filter: for a noise pixel u (not converged) with luminance L_u and the average L_n of
//!   its converged 8-neighbours, L_excess = (L_u - L_n) - D Lt_vis, and (kalos' bound, not
//!   the paper's) at most u's own standard error S_u / sqrt(M_u): a firefly (one sample
//!   far above the rest) stands about one standard error above its neighbours and is
//!   spread whole, while a pixel on a true edge whose many samples agree stands many
//!   standard errors above them and keeps all but one (the paper's filter spread the lit
//!   side of every noisy edge: a window's reveal lost 80% of its light). A positive excess is
//!   removed from u with u's own colour (its RGB scaled by L_excess / L_u, so nothing turns
//!   grey) and spread evenly over ceil(L_excess / Lt_vis) pixels around u (the nearest
//!   rings of a box, u itself left out), so no pixel gains more than Lt_vis from one spread.
//!   Outside the image there are no pixels: the box grows until it holds that many image
//!   pixels, and no energy is lost at borders. Noise pixels without a converged neighbour
//!   wait for a further pass, in which the pixels treated before count as converged.
//!
//! Order independence: each pass reads only the state before it (which pixels are
//! converged, their values) and writes a separate buffer; removals are applied first,
//! then the spreads summed per receiver in the order of their source pixel, so the result
//! is bit-identical for any traversal order.
//!
//! Luminance deviation S_p: the film keeps per-channel variances but not the covariances,
//! so S_p is taken as sum_c w_c sigma_c (w the Rec. 709 luminance weights), the deviation
//! of the luminance if the channels are fully correlated, which path-traced samples nearly
//! are; it bounds the true deviation from above, so a pixel never passes for converged by
//! this approximation.

use crate::film::{Film, PixelStats};
use crate::spectrum::LUMINANCE_RGB;

/// The middle of the display range 0..255: the linear tone operator maps L_ave here.
pub const N_MID: f64 = 127.5;
/// Trials per pixel of the pilot sample, and its size.
pub const PILOT_TRIALS: u32 = 16;
pub const PILOT_RES: u32 = 100;
/// Mt_ceiling = CEILING_FACTOR x Mt (the paper's heuristic 4).
pub const CEILING_FACTOR: u32 = 4;
/// The t of the convergence test t S_p / sqrt(M) <= D Lt_vis. The paper asks for 80%
/// confidence (alpha = 0.2, two-sided) and then says t is "near 1.0" there and drops it
/// from Eq. 10; the t quantile t_{0.9} is 1.341 at 15 degrees of freedom and 1.282 in
/// the limit. We take the limit, 1.2816: the test is applied only from Mt >= 16 trials on,
/// where t_{0.9} is within 5% of it, and it honours the confidence the paper names. Eq. 10
/// keeps the paper's form (no t), so Mt is a typical count and Mt_ceiling = 4 Mt covers
/// the factor t^2 = 1.64.
pub const DEFAULT_T: f64 = 1.2816;
/// The paper's D: 5 display units of 255.
pub const DEFAULT_D: f64 = 5.0;
/// kalos' bound on what the filter removes from a noise pixel: at most this many of its
/// own standard errors, EXCESS_SE S_u / sqrt(M_u) (see the header). Measured with `kalos
/// render SCENE --method rw --spp 128` on seeds 1 and 2 (2026-12-06, Xeon with AVX-512),
/// RMSE against the committed references for bounds 0 (no filter), 0.5, 1, 2, 3, 5 and none
/// (the paper's), seed 1: cornell 128x128 0.00363, 0.00360, 0.00364, 0.00386, 0.00408,
/// 0.00467, 0.00583; rw-room 0.00377, 0.00364, 0.00362, 0.00365, 0.00370, 0.00384, 0.00394;
/// a Blender living room 160x120 (scenes/blender) 0.0220, 0.0216, 0.0220, 0.0243, 0.0284,
/// 0.0406 and (seed 0) 0.121.
pub const EXCESS_SE: f64 = 1.0;

#[inline]
pub fn luminance(c: [f64; 3]) -> f64 {
    LUMINANCE_RGB[0] as f64 * c[0] + LUMINANCE_RGB[1] as f64 * c[1] + LUMINANCE_RGB[2] as f64 * c[2]
}

/// S_p: the sample standard deviation of a pixel's luminance samples (see the header).
#[inline]
pub fn deviation(p: &PixelStats) -> f64 {
    let v = p.variance();
    (0..3)
        .map(|c| LUMINANCE_RGB[c] as f64 * v[c].max(0.0).sqrt())
        .sum()
}

/// D must be a positive number of display units.
pub fn check_d(d: f64) -> Result<(), String> {
    if d.is_finite() && d > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "--rw-d {d}: must be a positive number of display units"
        ))
    }
}

/// The pilot's figures.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Pilot {
    /// Average deviation of a pixel's 16-trial mean: mean_p S_p / sqrt(16).
    pub s16: f64,
    /// Average image luminance.
    pub l_ave: f64,
    /// L_ave / N_MID.
    pub lt_vis: f64,
    pub d: f64,
    pub mt: u32,
    pub mt_ceiling: u32,
}

/// S_16 from the pilot's per-pixel deviations S_p (at 16 trials): mean S_p / 4.
pub fn s16(s_p: &[f64]) -> f64 {
    if s_p.is_empty() {
        return 0.0;
    }
    s_p.iter().sum::<f64>() / s_p.len() as f64 / (PILOT_TRIALS as f64).sqrt()
}

/// L_ave: the mean luminance of an image.
pub fn l_ave(mean: &[[f64; 3]]) -> f64 {
    if mean.is_empty() {
        return 0.0;
    }
    mean.iter().map(|&c| luminance(c)).sum::<f64>() / mean.len() as f64
}

/// Lt_vis = L_ave / N_MID.
#[inline]
pub fn lt_vis(l_ave: f64) -> f64 {
    l_ave / N_MID
}

/// Eq. 10: Mt = 16 (S_16 / (D Lt_vis))^2, rounded up, at least 1.
pub fn mt(s16: f64, d: f64, lt_vis: f64) -> Result<u32, String> {
    check_d(d)?;
    if !(lt_vis.is_finite() && lt_vis > 0.0) {
        return Err(format!(
            "Lt_vis {lt_vis}: the pilot image is black or not finite, no trial count can be planned"
        ));
    }
    let m = PILOT_TRIALS as f64 * (s16 / (d * lt_vis)).powi(2);
    Ok(m.ceil().clamp(1.0, (u32::MAX / CEILING_FACTOR) as f64) as u32)
}

/// Mt_ceiling = 4 Mt.
#[inline]
pub fn mt_ceiling(mt: u32) -> u32 {
    mt.saturating_mul(CEILING_FACTOR)
}

/// All pilot figures from a pilot film (16 trials per pixel).
pub fn pilot(film: &Film, d: f64) -> Result<Pilot, String> {
    let s: Vec<f64> = film.pixels.iter().map(deviation).collect();
    let mean: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.mean()).collect();
    pilot_of(&mean, &s, d)
}

/// All pilot figures from the pilot's per-pixel means (L_ave) and deviations (S_16).
pub fn pilot_of(mean: &[[f64; 3]], s: &[f64], d: f64) -> Result<Pilot, String> {
    check_d(d)?;
    let s16 = s16(s);
    let l_ave = l_ave(mean);
    let lt = lt_vis(l_ave);
    let mt = mt(s16, d, lt)?;
    Ok(Pilot {
        s16,
        l_ave,
        lt_vis: lt,
        d,
        mt,
        mt_ceiling: mt_ceiling(mt),
    })
}

/// The convergence test t S_p / sqrt(M) <= D Lt_vis (fewer than two trials: not converged).
#[inline]
pub fn converged(t: f64, s_p: f64, m: u32, d: f64, lt_vis: f64) -> bool {
    m >= 2 && t * s_p / (m as f64).sqrt() <= d * lt_vis
}

/// Parameters of the filter.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnergyParams {
    /// D, in display units.
    pub d: f64,
    /// Lt_vis, in radiance (luminance) units.
    pub lt_vis: f64,
    /// t of the convergence test.
    pub t: f64,
}

impl EnergyParams {
    pub fn check(&self) -> Result<(), String> {
        check_d(self.d)?;
        if !(self.lt_vis.is_finite() && self.lt_vis > 0.0) {
            return Err(format!("Lt_vis {}: must be positive", self.lt_vis));
        }
        if !(self.t.is_finite() && self.t > 0.0) {
            return Err(format!("--rw-t {}: must be positive", self.t));
        }
        Ok(())
    }
}

/// The filtered image and what the filter did.
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyOutput {
    pub image: Vec<[f64; 3]>,
    /// Pixels that had not converged (the noise pixels).
    pub noise: Vec<bool>,
    /// Noise pixels whose excess was spread.
    pub spread: Vec<bool>,
    pub passes: u32,
    pub noise_pixels: usize,
    pub spread_pixels: usize,
    /// Noise pixels never treated (the image had no converged pixel near them at all).
    pub untreated: usize,
    /// The largest luminance one spread gave one pixel (<= Lt_vis unless the image is too
    /// small to hold a spread).
    pub max_gain: f64,
}

/// The filter on a film: means, S_p and M from its statistics.
pub fn energy_filter_film(film: &Film, p: &EnergyParams) -> Result<EnergyOutput, String> {
    let mean: Vec<[f64; 3]> = film.pixels.iter().map(|q| q.mean()).collect();
    let s: Vec<f64> = film.pixels.iter().map(deviation).collect();
    let m: Vec<u32> = film.pixels.iter().map(|q| q.n).collect();
    energy_filter(film.width, film.height, &mean, &s, &m, p)
}

/// The filter on plain arrays: per-pixel mean RGB, S_p and trial count M, row-major.
pub fn energy_filter(
    width: u32,
    height: u32,
    mean: &[[f64; 3]],
    s: &[f64],
    m: &[u32],
    p: &EnergyParams,
) -> Result<EnergyOutput, String> {
    let order: Vec<usize> = (0..mean.len()).collect();
    energy_filter_in_order(width, height, mean, s, m, p, &order)
}

/// The filter visiting noise pixels in `order` (a permutation of the pixels); the result
/// does not depend on it (the tests shuffle it).
pub fn energy_filter_in_order(
    width: u32,
    height: u32,
    mean: &[[f64; 3]],
    s: &[f64],
    m: &[u32],
    p: &EnergyParams,
    order: &[usize],
) -> Result<EnergyOutput, String> {
    p.check()?;
    let (w, h) = (width as usize, height as usize);
    let n = w * h;
    if mean.len() != n || s.len() != n || m.len() != n || order.len() != n {
        return Err(format!(
            "energy filter: {}x{} image but {} means, {} deviations, {} counts",
            width,
            height,
            mean.len(),
            s.len(),
            m.len()
        ));
    }
    let noise: Vec<bool> = (0..n)
        .map(|i| !converged(p.t, s[i], m[i], p.d, p.lt_vis))
        .collect();
    let mut conv: Vec<bool> = noise.iter().map(|&x| !x).collect();
    let mut cur: Vec<[f64; 3]> = mean.to_vec();
    let mut spread = vec![false; n];
    let mut pending: Vec<usize> = order.iter().copied().filter(|&i| noise[i]).collect();
    let allowed = p.d * p.lt_vis;
    let mut passes = 0;
    let mut max_gain = 0.0f64;
    while !pending.is_empty() {
        // --- one pass: reads `cur` and `conv`, writes `next`
        let mut removals: Vec<(usize, [f64; 3])> = Vec::new();
        let mut spreads: Vec<(usize, usize, [f64; 3])> = Vec::new();
        let mut treated = Vec::new();
        let mut deferred = Vec::new();
        for &u in &pending {
            let (x, y) = (u % w, u / w);
            // L_n: the mean luminance of the converged immediate neighbours
            let (mut sum, mut k) = (0.0, 0usize);
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue;
                    }
                    let q = ny as usize * w + nx as usize;
                    if conv[q] {
                        sum += luminance(cur[q]);
                        k += 1;
                    }
                }
            }
            if k == 0 {
                deferred.push(u);
                continue;
            }
            treated.push(u);
            let l_n = sum / k as f64;
            let l_u = luminance(cur[u]);
            let excess =
                ((l_u - l_n) - allowed).min(EXCESS_SE * s[u] / (m[u].max(1) as f64).sqrt());
            if excess <= 0.0 || l_u <= 0.0 {
                continue;
            }
            // L_excess with u's colour, over ceil(L_excess / Lt_vis) pixels around u
            let count = (excess / p.lt_vis).ceil() as usize;
            let targets = box_region(w, h, x, y, count);
            if targets.is_empty() {
                continue; // a one-pixel image: nowhere to spread
            }
            let frac = excess / l_u;
            let delta = cur[u].map(|c| c * frac);
            let per = delta.map(|c| c / targets.len() as f64);
            max_gain = max_gain.max(luminance(per));
            removals.push((u, delta));
            spread[u] = true;
            for t in targets {
                spreads.push((t, u, per));
            }
        }
        if treated.is_empty() {
            break; // no noise pixel left has any converged pixel near it
        }
        let mut next = cur.clone();
        for (u, d) in &removals {
            for c in 0..3 {
                next[*u][c] -= d[c];
            }
        }
        spreads.sort_unstable_by_key(|&(t, u, _)| (t, u));
        for (t, _, d) in &spreads {
            for c in 0..3 {
                next[*t][c] += d[c];
            }
        }
        cur = next;
        for &u in &treated {
            conv[u] = true;
        }
        pending = deferred;
        pending.sort_unstable();
        passes += 1;
    }
    let noise_pixels = noise.iter().filter(|&&x| x).count();
    Ok(EnergyOutput {
        image: cur,
        spread_pixels: spread.iter().filter(|&&x| x).count(),
        untreated: pending.len(),
        noise,
        spread,
        passes,
        noise_pixels,
        max_gain,
    })
}

/// `count` image pixels around (x, y), itself left out: whole square rings r = 1, 2, ...
/// and of the last ring the nearest (then by row, then column). Fewer only if the image
/// has fewer pixels.
pub fn box_region(w: usize, h: usize, x: usize, y: usize, count: usize) -> Vec<usize> {
    let total = (w * h).saturating_sub(1);
    let count = count.min(total);
    let mut out = Vec::with_capacity(count);
    let mut r = 1i64;
    let rmax = w.max(h) as i64;
    while out.len() < count && r <= rmax {
        let mut ring: Vec<(i64, i64, i64)> = Vec::with_capacity(8 * r as usize);
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs().max(dy.abs()) != r {
                    continue;
                }
                let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                    continue;
                }
                ring.push((dx * dx + dy * dy, dy, dx));
            }
        }
        ring.sort_unstable();
        for (_, dy, dx) in ring {
            if out.len() == count {
                break;
            }
            out.push((y as i64 + dy) as usize * w + (x as i64 + dx) as usize);
        }
        r += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::SeqRng;

    fn params(lt_vis: f64) -> EnergyParams {
        EnergyParams {
            d: 5.0,
            lt_vis,
            t: DEFAULT_T,
        }
    }

    /// A flat image of luminance ~1 where every pixel has converged (S_p = 0, M = 64).
    fn flat(w: u32, h: u32) -> (Vec<[f64; 3]>, Vec<f64>, Vec<u32>) {
        let n = (w * h) as usize;
        (vec![[1.0, 1.0, 1.0]; n], vec![0.0; n], vec![64; n])
    }

    fn total(img: &[[f64; 3]]) -> f64 {
        img.iter().map(|&c| luminance(c)).sum()
    }

    /// A noisy image: random values, a share of pixels unconverged, a few fireflies.
    fn noisy(w: u32, h: u32, seed: u64) -> (Vec<[f64; 3]>, Vec<f64>, Vec<u32>) {
        let mut r = SeqRng::new(seed);
        let n = (w * h) as usize;
        let mut mean = Vec::with_capacity(n);
        let mut s = Vec::with_capacity(n);
        for _ in 0..n {
            let base = 0.5 + r.next_f32() as f64;
            let hot = r.next_f32() < 0.05;
            let k = if hot {
                2.0 + 6.0 * r.next_f32() as f64
            } else {
                1.0
            };
            mean.push([base * k, 0.8 * base * k, 0.3 * base * k]);
            s.push(if hot || r.next_f32() < 0.1 {
                100.0
            } else {
                0.01
            });
        }
        (mean, s, vec![64; n])
    }

    #[test]
    fn pilot_quantities() {
        let l_ave = 0.51;
        let lt = lt_vis(l_ave);
        assert!((lt - 0.004).abs() < 1e-12);
        // S_16 = D Lt_vis gives exactly the pilot's 16 trials; twice that, 64
        assert_eq!(mt(5.0 * lt, 5.0, lt).unwrap(), 16);
        assert_eq!(mt(10.0 * lt, 5.0, lt).unwrap(), 64);
        assert_eq!(mt_ceiling(64), 256);
        assert!((s16(&[4.0, 8.0]) - 1.5).abs() < 1e-12);
        assert!((l_ave_of_flat() - 1.0).abs() < 1e-12);
        // the test itself: t S / sqrt(M) against D Lt_vis
        assert!(converged(1.0, 2.0, 16, 1.0, 0.5));
        assert!(!converged(1.0, 2.0, 15, 1.0, 0.5));
        assert!(!converged(1.0, 0.0, 1, 1.0, 0.5));
    }

    fn l_ave_of_flat() -> f64 {
        l_ave(&flat(4, 4).0)
    }

    #[test]
    fn bad_d_is_refused() {
        for d in [0.0, -1.0, f64::NAN] {
            let e = check_d(d).unwrap_err();
            assert!(e.contains("--rw-d") && !e.contains('\n'));
            assert!(mt(1.0, d, 0.1).is_err());
            let (m, s, c) = flat(4, 4);
            let p = EnergyParams { d, ..params(0.01) };
            assert!(energy_filter(4, 4, &m, &s, &c, &p).is_err());
        }
        assert!(mt(1.0, 5.0, 0.0).is_err());
        let (m, s, c) = flat(4, 4);
        assert!(energy_filter(4, 5, &m, &s, &c, &params(0.01)).is_err());
    }

    #[test]
    fn converged_image_passes_unchanged() {
        let (mut m, s, c) = flat(16, 12);
        m[37] = [9.0, 3.0, 1.0]; // bright but converged: not the filter's business
        let out = energy_filter(16, 12, &m, &s, &c, &params(1.0 / N_MID)).unwrap();
        assert_eq!(out.image, m);
        assert_eq!(out.noise_pixels, 0);
        assert_eq!(out.passes, 0);
    }

    #[test]
    fn energy_is_preserved_and_no_spread_gives_more_than_lt_vis() {
        for seed in 0..4 {
            let (m, s, c) = noisy(40, 30, seed);
            let lt = lt_vis(l_ave(&m));
            let out = energy_filter(40, 30, &m, &s, &c, &params(lt)).unwrap();
            let (a, b) = (total(&m), total(&out.image));
            assert!((a - b).abs() <= 1e-9 * a, "{a} vs {b}");
            assert!(out.spread_pixels > 10, "{out:?}");
            assert!(
                out.max_gain <= lt * (1.0 + 1e-12),
                "{} > {lt}",
                out.max_gain
            );
            assert_eq!(out.untreated, 0);
            // no negative values were made: the excess is at most L_u - L_n
            assert!(out.image.iter().all(|c| c.iter().all(|&v| v >= -1e-12)));
        }
    }

    #[test]
    fn result_does_not_depend_on_traversal_order() {
        let (m, s, c) = noisy(33, 21, 7);
        let lt = lt_vis(l_ave(&m));
        let a = energy_filter(33, 21, &m, &s, &c, &params(lt)).unwrap();
        let mut r = SeqRng::new(99);
        for _ in 0..3 {
            let mut order: Vec<usize> = (0..m.len()).collect();
            for i in (1..order.len()).rev() {
                let j = (r.next_u32() as usize) % (i + 1);
                order.swap(i, j);
            }
            let b = energy_filter_in_order(33, 21, &m, &s, &c, &params(lt), &order).unwrap();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn a_pixel_whose_samples_agree_loses_at_most_one_standard_error() {
        // u stands 9 above its converged neighbours with S_u = 8 over M = 64 trials: not
        // converged (t S / sqrt(M) = 1.28 > D Lt_vis = 1), but its standard error is 1, so
        // the excess is real (an edge, not a firefly): one standard error is spread, the
        // paper's L_excess = 9 - 1 = 8 would have been.
        let (w, h) = (20u32, 16u32);
        let (mut m, mut s, mut c) = flat(w, h);
        let u = 8 * w as usize + 10;
        m[u] = [10.0, 10.0, 10.0];
        s[u] = 8.0;
        c[u] = 64;
        let lt = 0.2;
        let p = params(lt);
        let out = energy_filter(w, h, &m, &s, &c, &p).unwrap();
        let se = 8.0 / 8.0;
        assert!((luminance(out.image[u]) - (luminance(m[u]) - se)).abs() < 1e-9);
        let changed = (0..m.len())
            .filter(|&i| i != u && out.image[i] != m[i])
            .count();
        assert_eq!(changed, (se / lt).ceil() as usize);
        assert!((total(&out.image) - total(&m)).abs() < 1e-9 * total(&m));
    }

    #[test]
    fn hot_pixel_is_spread_over_ceil_excess_over_lt_vis_pixels_with_its_colour() {
        for (x, y) in [(10usize, 8usize), (0, 0), (19, 3)] {
            let (w, h) = (20u32, 16u32);
            let (mut m, mut s, c) = flat(w, h);
            let u = y * w as usize + x;
            let hot = [30.0, 12.0, 2.0];
            m[u] = hot;
            s[u] = 1e3;
            let lt = 0.2;
            let p = params(lt);
            let out = energy_filter(w, h, &m, &s, &c, &p).unwrap();
            let l_u = luminance(hot);
            let excess = (l_u - 1.0) - p.d * lt;
            let count = (excess / lt).ceil() as usize;
            let changed: Vec<usize> = (0..m.len())
                .filter(|&i| i != u && out.image[i] != m[i])
                .collect();
            assert_eq!(changed.len(), count, "at ({x}, {y})");
            for &i in &changed {
                let d: Vec<f64> = (0..3).map(|k| out.image[i][k] - m[i][k]).collect();
                // the spread keeps the hot pixel's colour
                for k in 0..3 {
                    assert!((d[k] / d[0] - hot[k] / hot[0]).abs() < 1e-9);
                }
                assert!(luminance([d[0], d[1], d[2]]) <= lt * (1.0 + 1e-12));
            }
            // u keeps L_n + D Lt_vis, in its own colour
            assert!((luminance(out.image[u]) - (1.0 + p.d * lt)).abs() < 1e-9);
            assert!((out.image[u][1] / out.image[u][0] - hot[1] / hot[0]).abs() < 1e-9);
            assert!((total(&out.image) - total(&m)).abs() < 1e-9 * total(&m));
        }
    }

    #[test]
    fn noise_clusters_are_treated_in_further_passes() {
        let (w, h) = (9u32, 9u32);
        let (mut m, mut s, c) = flat(w, h);
        for y in 3..6 {
            for x in 3..6 {
                let i = y * 9 + x;
                m[i] = [4.0, 4.0, 4.0];
                s[i] = 1e3;
            }
        }
        let out = energy_filter(w, h, &m, &s, &c, &params(0.05)).unwrap();
        assert_eq!(out.passes, 2); // the centre has no converged neighbour at first
        assert_eq!(out.noise_pixels, 9);
        assert_eq!(out.untreated, 0);
        assert!((total(&out.image) - total(&m)).abs() < 1e-9 * total(&m));
        // an image without any converged pixel is left as it is
        let all_noise = vec![1e3; 81];
        let out = energy_filter(w, h, &m, &all_noise, &c, &params(0.05)).unwrap();
        assert_eq!(out.image, m);
        assert_eq!(out.untreated, 81);
    }

    #[test]
    fn box_region_stays_in_the_image() {
        let r = box_region(5, 4, 0, 0, 7);
        assert_eq!(r.len(), 7);
        assert!(!r.contains(&0));
        let mut s = r.clone();
        s.sort();
        s.dedup();
        assert_eq!(s.len(), 7);
        assert_eq!(box_region(5, 4, 2, 2, 1000).len(), 19);
        assert!(box_region(1, 1, 0, 0, 3).is_empty());
    }
}
