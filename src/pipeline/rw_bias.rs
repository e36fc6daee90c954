//! The radiosity gather's bias, measured and taken out where it shows (`--method rw`).
//!
//! The gather's lookup reads the radiosity solution, whose error (mesh interpolation,
//! form factors, the diffuse-only transfer) is a bias no number of trials removes. The
//! solution as a control variate instead (`Gather::Correction`: the path goes on whole
//! from the gather vertex, its own lookup is taken out and the gather rays' lookups put
//! in) is unbiased, but its variance is path tracing's: on `rw-room` the indirect light's
//! variance is almost all in estimating the light a first-bounce point y reflects (next
//! event at y and beyond), which a control variate that depends on y alone cannot remove.
//! So the trials keep the lookup and a few samples per pixel measure the difference
//! D = control variate - lookup (same random numbers: mean D = minus the lookup's bias):
//!
//! - D-bar: the mean of D over the pixel's (2 `POOL_RADIUS` + 1)^2 box, v its variance
//!   (the pixels' variances of the mean over the box's pixel count squared);
//! - alpha = 1 where D-bar's luminance stands `SIGNIFICANCE` standard errors out of its
//!   noise, else 0: the solution is used only where its measured bias is below the
//!   noise. (A positive-part James-Stein weight max(0, 1 - v / D-bar^2) added noise on
//!   `cornell`, v being itself noisy; made stricter, 1 - 4 v / D-bar^2, it kept 12-16% of
//!   a 4% bias on `rw-room` with a badly converged solution.)
//! - the samples come in two independent halves a and b, and the image gets
//!   (alpha_a D-bar_b + alpha_b D-bar_a) / 2: a weight read from the same samples as the
//!   value it weighs would favour their large values, and D is skewed (the path's rare
//!   bright continuations), so the weighted mean would lean to the skew's side (measured
//!   on `rw-room`: the image 0.3% darker, not lighter, with one half).
//!
//! As the budget grows v falls as 1/M and alpha tends to 1 wherever the bias is not 0:
//! the image tends to the control variate's, box-averaged over the 9x9 pixels (a
//! smoothing of the correction alone, which keeps the image's mean).

use crate::film::Film;
use crate::filter::energy::luminance;

/// Correction samples per pixel per trial of Mt (at least `MIN_CORRECTION_SAMPLES`).
pub const CORRECTION_SHARE: f64 = 0.0625;
/// Standard errors D-bar must stand out before any of it is added.
pub const SIGNIFICANCE: f64 = 2.0;
/// The fewest correction samples a pixel gets.
pub const MIN_CORRECTION_SAMPLES: u32 = 2;
/// Half side of the box the correction is averaged over (9x9: the bias is a smooth field,
/// and over 3x3 it stayed under its noise almost everywhere on `rw-room` at 80 s, leaving
/// the image 0.3% dark).
pub const POOL_RADIUS: usize = 4;
/// A correction sample's cost in trials (the lookup's estimate and the control
/// variate's: two paths from one camera ray), for budgets.
pub const CORRECTION_COST: f64 = 2.0;

/// Correction samples per pixel for Mt trials.
pub fn samples_for(mt: u32) -> u32 {
    ((mt as f64 * CORRECTION_SHARE).ceil() as u32)
        .max(MIN_CORRECTION_SAMPLES)
        .next_multiple_of(2)
}

/// What the correction adds to each pixel from the two halves' films.
pub struct Correction {
    pub add: Vec<[f64; 3]>,
    /// alpha's image average.
    pub alpha: f64,
    /// Standard error of the luminance the correction adds to the image's mean, taken
    /// whole (alpha 1) and before the box: sqrt(sum_p (D_a,p - D_b,p)^2 / 4) / P, the two
    /// halves' pixel means being independent estimates of one mean.
    pub mean_se: f64,
}

/// The correction from the two halves' films. (With one sample per half, the smallest
/// budgets, a half's variance reads 0 and alpha is 1 wherever D-bar is not 0: the
/// correction is then taken whole, which is unbiased; its noise is the box's.)
pub fn correction(a: &Film, b: &Film) -> Correction {
    let (da, wa) = pooled(a);
    let (db, wb) = pooled(b);
    let n = da.len().max(1) as f64;
    let add = (0..da.len())
        .map(|i| std::array::from_fn(|c| 0.5 * (wa[i] * db[i][c] + wb[i] * da[i][c])))
        .collect();
    let alpha = wa.iter().chain(&wb).sum::<f64>() / (2.0 * n);
    let var: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (luminance(p.mean()) - luminance(q.mean())).powi(2) / 4.0)
        .sum();
    Correction {
        add,
        alpha,
        mean_se: var.sqrt() / n,
    }
}

/// Each pixel's D-bar (over its box) and its weight alpha.
fn pooled(film: &Film) -> (Vec<[f64; 3]>, Vec<f64>) {
    let (w, h) = (
        film.width as usize,
        film.pixels.len() / film.width.max(1) as usize,
    );
    let mean: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.mean()).collect();
    let var: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.variance_of_mean()).collect();
    let mut out = vec![[0.0; 3]; mean.len()];
    let mut weight = vec![0.0; mean.len()];
    for y in 0..h {
        for x in 0..w {
            let (mut d, mut v, mut n) = ([0.0f64; 3], [0.0f64; 3], 0.0f64);
            for yy in y.saturating_sub(POOL_RADIUS)..(y + POOL_RADIUS + 1).min(h) {
                for xx in x.saturating_sub(POOL_RADIUS)..(x + POOL_RADIUS + 1).min(w) {
                    let i = yy * w + xx;
                    for c in 0..3 {
                        d[c] += mean[i][c];
                        v[c] += var[i][c];
                    }
                    n += 1.0;
                }
            }
            let d = d.map(|s| s / n);
            let v = v.map(|s| s / (n * n));
            // the luminance of D-bar and its variance (the channels taken as independent)
            let dl = luminance(d);
            let lw = crate::spectrum::LUMINANCE_RGB;
            let vl: f64 = (0..3).map(|c| (lw[c] as f64).powi(2) * v[c]).sum();
            let alpha = if dl * dl > SIGNIFICANCE * SIGNIFICANCE * vl {
                1.0
            } else {
                0.0
            };
            weight[y * w + x] = alpha;
            out[y * w + x] = d;
        }
    }
    (out, weight)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A film of `n` samples per pixel: `bias` plus noise of the given amplitude.
    fn film(w: u32, h: u32, n: u32, bias: f32, noise: f32) -> Film {
        let mut f = Film::new(w, h).unwrap();
        let mut state = 12345u64 + n as u64 * 7 + (noise * 1e3) as u64;
        for p in f.pixels.iter_mut() {
            for _ in 0..n {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5;
                let v = bias + noise * u;
                p.push([v, v, v]);
            }
        }
        f
    }

    /// A bias far above its measurement's noise is taken out whole; one far below it is
    /// left (alpha near 0); with more samples the same small bias is taken out.
    /// (The consistency of `--method rw` as a whole: `tests::rw_mean_is_unbiased_*`.)
    #[test]
    fn alpha_follows_the_bias_against_its_noise() {
        let two = |n: u32, bias: f32, noise: f32| {
            let c = correction(&film(8, 8, n, bias, noise), &film(8, 8, n + 1, bias, noise));
            (c.add, c.alpha)
        };
        let (c, a) = two(64, -0.1, 0.01);
        assert!(a > 0.99, "{a}");
        assert!((c[27][0] + 0.1).abs() < 1e-3, "{:?}", c[27]);
        let (_, a_small) = two(4, -0.001, 1.0);
        assert!(a_small < 0.2, "{a_small}");
        let (_, a_many) = two(400_000, -0.001, 0.2);
        assert!(a_many > 0.9, "{a_many}");
        assert_eq!(samples_for(1), MIN_CORRECTION_SAMPLES);
        assert_eq!(samples_for(80), 6);
    }

    use crate::render::{render_scene, Method, RenderJob, Rendered};

    /// Image mean luminance of a render and its standard error from the film.
    fn mean_of(r: &Rendered) -> (f64, f64) {
        let m = luminance(r.image.mean());
        let n = r.film.pixels.len() as f64;
        let lw = crate::spectrum::LUMINANCE_RGB;
        let v: f64 = r
            .film
            .pixels
            .iter()
            .map(|p| {
                let vm = p.variance_of_mean();
                (0..3).map(|c| (lw[c] as f64).powi(2) * vm[c]).sum::<f64>()
            })
            .sum();
        (m, v.sqrt() / n)
    }

    /// z of `--method rw`'s image mean (4 seeds, their spread) against plain path tracing
    /// at many samples, on `rw-room` with a badly converged solution (tolerance 0.3: the
    /// lookup alone is about 4% dark).
    fn rw_mean_z(correct: bool) -> f64 {
        let scene = crate::scene::load("rw-room").unwrap();
        let silent = crate::progress::Silent;
        let mut p = RenderJob::new("rw-room");
        p.res = Some((24, 24));
        p.spp = Some(8192);
        p.seed = 1000;
        let (m_ref, s_ref) = mean_of(&render_scene(&scene, &p, &silent).unwrap());
        let runs: Vec<f64> = (0..4)
            .map(|seed| {
                let mut j = RenderJob::new("rw-room");
                j.method = Method::Rw;
                j.res = Some((24, 24));
                j.spp = Some(1024);
                j.seed = seed;
                j.radiosity.tolerance = 0.3;
                j.rw.no_correction = !correct;
                luminance(render_scene(&scene, &j, &silent).unwrap().image.mean())
            })
            .collect();
        let n = runs.len() as f64;
        let m = runs.iter().sum::<f64>() / n;
        let var = runs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
        let z = (m - m_ref) / (var / n + s_ref * s_ref).sqrt();
        eprintln!(
            "rw-room rw (correction {correct}): {m:.5} +- {:.1e}, plain {m_ref:.5} +- {s_ref:.1e}, relative {:+.4}, z {z:.2}",
            (var / n).sqrt(),
            m / m_ref - 1.0
        );
        z
    }

    /// The correction makes the method's mean the path tracer's whatever the solution's
    /// error: within noise with it, and the same test fails without it.
    #[test]
    fn rw_mean_is_unbiased_with_the_correction_only() {
        let z = rw_mean_z(true);
        assert!(z.abs() < 4.0, "rw with the correction: z = {z:.2}");
        let z = rw_mean_z(false);
        assert!(
            z.abs() > 4.0,
            "rw without the correction is not biased: z = {z:.2}"
        );
    }
}
