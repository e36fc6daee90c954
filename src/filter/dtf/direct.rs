//! The emission seen directly, kept out of the filter (`DirectMode::Split`).
//!
//! Over BDPT a camera sample's value L holds, among its strategies, the emission of a
//! light the camera ray reaches at once or through mirrors and smooth glass only (its
//! s = 0 strategies through Dirac vertices, `bdpt::StrategySample::direct`): E. Each pass
//! writes the whole samples L to its film, splats and all, and L - E to a second film
//! (`pipeline::render_pass_rest`). Then:
//! - the allocation and the top-ups read the whole film, as before: a pixel on a light's
//!   edge varies with its footprint and needs its samples;
//! - the tests, the regions and the filter read the rest R = L - E with the film's splats
//!   ([`rest_film`]): exact sums and batch images, so sigma, Delta and the display weights
//!   are those of R;
//! - the display adds E back per pixel, the mean of all its samples of both phases
//!   ([`direct_mean`]): C = DTF(R) + mean(E).
//!
//! Both terms are unbiased estimates of their parts (E is one part of one estimator), so C
//! is as unbiased as DTF(R) is: asymptotically, as the paper's display.

use crate::film::Film;

/// The film of the rest R = L - E: the samples of `rest` (written by
/// `pipeline::render_pass_rest` beside `full`) with `full`'s splats, light paths and
/// rejections. Batch sums and counts come from `rest`, so the batch images are R's.
pub fn rest_film(full: &Film, rest: &Film) -> Result<Film, String> {
    if full.pixels.len() != rest.pixels.len()
        || full
            .pixels
            .iter()
            .zip(&rest.pixels)
            .any(|(a, b)| a.n != b.n)
    {
        return Err("dtf: the rest film does not hold the whole film's samples".into());
    }
    let splats = match (&full.splats, &rest.splats) {
        // (field by field: not a copy of the whole film's batch sums to overwrite)
        (Some(f), Some(r)) => Some(Box::new(crate::film::SplatFilm {
            sum: f.sum.clone(),
            light_paths: f.light_paths,
            batch_n: f.batch_n.clone(),
            batch_sum: r.batch_sum.clone(),
            batch_splat: f.batch_splat.clone(),
            batch_paths: f.batch_paths,
        })),
        (f, _) => f.clone(),
    };
    Ok(Film {
        width: full.width,
        height: full.height,
        pixels: rest.pixels.clone(),
        rejected: full.rejected,
        splats,
    })
}

/// mean(E) per pixel over the films' samples: sum over `parts` (whole film, rest film) of
/// n (mean L - mean R), divided by the samples of all parts. 0 where no sample was taken.
pub fn direct_mean(parts: &[(&Film, &Film)], pixels: usize) -> Vec<[f64; 3]> {
    (0..pixels)
        .map(|i| {
            let (mut sum, mut n) = ([0.0f64; 3], 0u64);
            for (full, rest) in parts {
                let (a, b) = (&full.pixels[i], &rest.pixels[i]);
                if a.n == 0 {
                    continue;
                }
                let (ma, mb) = (a.mean(), b.mean());
                for c in 0..3 {
                    sum[c] += a.n as f64 * (ma[c] - mb[c]);
                }
                n += a.n as u64;
            }
            if n == 0 {
                [0.0; 3]
            } else {
                sum.map(|s| s / n as f64)
            }
        })
        .collect()
}
