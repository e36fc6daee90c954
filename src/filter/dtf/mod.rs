//! Dependent-tests driven filtering (DTF), after Csonka, Szirmay-Kalos, Kelemen and Antal,
//! "Dependent tests driven filtering in Monte-Carlo global illumination".
//!
//! The renderer runs two phases and hands over two films:
//! - phase 1, *dependent tests*: every pixel takes n samples built from the same random
//!   numbers; per pixel this gives the mean colour C_d and the spread sigma;
//! - phase 2, *independent tests*: pixel p takes N[p] ordinary samples, mean C_i.
//!
//! This folder holds the renderer-independent parts: `params.rs` (the options), `alloc.rs`
//! (N[p]), `region.rs` (region forming, weights, filter), `tests.rs`:
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

mod alloc;
mod direct;
mod light;
mod params;
mod region;

pub use alloc::*;
pub use direct::*;
pub use light::*;
pub use params::*;
pub use region::*;

use crate::film::PixelStats;

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

/// C[p] as the film holds it: the mean of pixel `i`'s samples plus, for an estimator that
/// splats (BDPT's light tracing, t = 1), its splat image (`Film::value`). A film without
/// splats gives exactly `PixelStats::mean`.
#[inline]
pub fn film_value(film: &crate::film::Film, i: usize) -> [f64; 3] {
    match &film.splats {
        None => film.pixels[i].mean(),
        Some(_) => film.value(i),
    }
}

/// sigma[p] read from the film: [`sigma`] of the pixel's samples, or, with splats, the
/// same sum of per-channel deviations from the batch-means variance of the value
/// (`Film::variance_of_value` x n): one camera sample no longer holds all of a pixel's
/// estimate, and in the dependent phase the splats of every pixel come from the same
/// light subpaths, so only whole batches of samples are independent.
pub fn film_sigma(film: &crate::film::Film, i: usize) -> f64 {
    match &film.splats {
        None => sigma(&film.pixels[i]),
        Some(_) => {
            let n = film.pixels[i].n;
            if n < 2 {
                return 0.0;
            }
            film.variance_of_value(i)
                .iter()
                .map(|v| (v.max(0.0) * n as f64).sqrt())
                .sum()
        }
    }
}

/// Variance of C[p] (per channel): the mean's sigma^2 / N, or with splats the batch-means
/// variance (`Film::variance_of_value`); infinite with fewer than two samples.
pub fn film_variance_of_value(film: &crate::film::Film, i: usize) -> [f64; 3] {
    if film.pixels[i].n < 2 {
        return [f64::INFINITY; 3];
    }
    match &film.splats {
        None => film.pixels[i].variance_of_mean(),
        Some(_) => film.variance_of_value(i),
    }
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

/// Pixels whose own phase-2 mean C_i[p] has converged keep it: where its relative standard
/// error sqrt(sum_c Var C_i[p]_c) / ||C_i[p]|| is below `tau`, filtering could only add
/// bias (a region's neighbours differ from the pixel by more than its own noise). Returns
/// how many pixels kept their own mean. As the budget grows every pixel passes, so the
/// image tends to the unfiltered, unbiased mean.
pub fn keep_converged(
    image: &mut crate::image_io::RgbImage,
    independent: &crate::film::Film,
    tau: f64,
) -> usize {
    let mut kept = 0;
    for (i, px) in image.data.iter_mut().enumerate() {
        let c = film_value(independent, i);
        let norm = color_norm(c);
        let se = film_variance_of_value(independent, i)
            .iter()
            .sum::<f64>()
            .sqrt();
        if norm > 0.0 && se < tau * norm {
            *px = c.map(|v| v as f32);
            kept += 1;
        }
    }
    kept
}

#[cfg(test)]
mod tests;
