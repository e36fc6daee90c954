//! The automatic choice of estimator (`--method auto`): a pilot renders the image at a
//! quarter of its resolution with each candidate estimator (the path tracer and BDPT) for
//! the same number of samples, and measures for each
//!
//! - v, the variance of one sample relative to the image, sum_p sigma_p^2 / (P mu^2),
//!   over the pilot's pixels p (sigma_p^2 the variance of one sample of pixel p, mu the
//!   image mean): the squared RMSE one sample per pixel gives, relative to the image.
//!   (Against each pixel's own mean mu_p instead, a firefly would hide itself: a pixel
//!   whose mean one outlier makes has a relative variance of at most n.)
//! - c, its cost: the rays it traced per sample, times the estimator's cost per ray
//!   against the path tracer's (`ray_cost`).
//!
//! The estimator of the largest efficiency 1 / (v c) wins, unless its image misses light
//! that the other finds (its mean lower by more than three standard errors and by more
//! than `MISSING`): an estimator whose rare paths carry the light (a caustic seen through
//! glass, reached by the path tracer only when a BSDF-sampled ray hits a small emitter)
//! shows a small variance in a short pilot because it has not yet met them.
//!
//! The cost is counted in rays, not seconds, so that the same scene, seed and options
//! choose the same estimator on any machine and thread count.
//!
//! A second pilot of the chosen estimator (another seed) predicts whether DTF's filter helps
//! at the budget: for each pilot pixel, r_p = 5% x max(||mu_p||, floor) / sigma_p (the
//! perceptual error's threshold over the standard deviation of one sample, measured as the
//! two pilots' difference, ||.|| the sum of the channels as in
//! `metrics::perceptual_error`), so that with n samples the pixel's error exceeds the
//! threshold with probability erfc(r_p sqrt(n / 2)) (a normal error). Their mean is the
//! share of pixels plain rendering is predicted to leave more than 5% off
//! (`predicted_off_share`); the same difference gives its relative RMSE at the budget.
//! Where both are low (below `DTF_MIN_OFF` and `DTF_MIN_REL_RMSE`), the noise left costs
//! less than the filter's bias: plain rendering wins (`dtf_helps`). The RMSE counts where
//! few pixels carry most of the noise (a small bright emitter's fireflies), which the share
//! of pixels off does not see and the filter removes.

use super::render::{render, Budget, RenderOutput, RenderSettings};
use crate::film::Film;
use crate::integrator::{Integrator, IntegratorKind};
use crate::progress::Silent;
use crate::scene::Scene;

/// Samples per pixel of each candidate's pilot.
pub const PILOT_SPP: u32 = 16;
/// The pilot's resolution divisor (per axis), down to `PILOT_MIN_SIDE` pixels.
pub const PILOT_SCALE: u32 = 4;
pub const PILOT_MIN_SIDE: u32 = 16;
/// An estimator misses light when its pilot's mean is below (1 - MISSING) x the other's
/// (and the difference is significant).
pub const MISSING: f64 = 0.05;
/// DTF is chosen only where plain rendering is predicted to leave at least this share of
/// the pixels more than 5% off at the budget (`dtf_helps`). Calibrated on the Cornell box
/// and the furnished room at 256x256, 10 s and 60 s (docs/results/auto.md): DTF won where
/// the prediction was 16-44% and lost where it was 1.7-3.6% (the prediction overstates
/// what plain rendering leaves off, most on the room: its 0.2% at 60 s).
pub const DTF_MIN_OFF: f64 = 0.12;
/// ... or, whatever that share, a predicted RMSE of plain rendering of at least this
/// share of the image's mean (`dtf_helps`). Calibrated on rw-room at 128x128 (DTF 0.56x
/// plain rendering's RMSE at 15 s, predicted 3.3% with 8% of the pixels off; 0.86x at 60 s,
/// predicted 1.5%) and the room at 60 s (plain rendering wins, predicted 1.8-2.5%).
pub const DTF_MIN_REL_RMSE: f64 = 0.03;

/// What a second pilot predicts of plain rendering's error (`thresholds_over_sd`).
#[derive(Clone, Debug)]
pub struct Noise {
    /// r_p of each pilot pixel: the perceptual error's threshold over one sample's
    /// standard deviation (infinite where the two pilots agree).
    pub threshold_over_sd: Vec<f64>,
    /// The RMSE one sample per pixel gives, relative to the image's mean.
    pub rel_sd: f64,
}

/// An estimator's seconds per ray against the path tracer's: BDPT evaluates every
/// connection's BSDFs and MIS weights and splats, beyond its rays. Measured with `kalos
/// render --method plain --integrator path|bdpt --spp 16` at 256x256 on two threads
/// (2026-12-06, Xeon with AVX-512): 1.58 on the Cornell box, 1.75 on the furnished room.
pub fn ray_cost(kind: IntegratorKind) -> f64 {
    match kind {
        IntegratorKind::Bdpt => 1.65,
        _ => 1.0,
    }
}

/// What the pilot measured of one estimator.
#[derive(Clone, Debug)]
pub struct Pilot {
    pub kind: IntegratorKind,
    /// v: the variance of one sample relative to the image.
    pub rel_var: f64,
    /// c: rays per sample, times `ray_cost`.
    pub cost: f64,
    /// mu and its standard error.
    pub mean: f64,
    pub mean_se: f64,
    /// Wall-clock seconds of the pilot, and of one sample per pixel at the full resolution
    /// extrapolated from it.
    pub seconds: f64,
    pub seconds_per_spp: f64,
    /// The pilot's image (its pixels' values), for `thresholds_over_sd`.
    pub image: Vec<[f64; 3]>,
}

impl Pilot {
    /// 1 / (v c): the inverse relative MSE per ray.
    pub fn efficiency(&self) -> f64 {
        let e = 1.0 / (self.rel_var * self.cost);
        if e.is_finite() {
            e
        } else {
            f64::MAX
        }
    }
}

/// The pilot's settings: the render's at a quarter of the resolution, with estimator
/// `kind` and a seed of its own.
fn pilot_settings(set: &RenderSettings, kind: IntegratorKind) -> RenderSettings {
    let mut p = *set;
    p.width = (set.width / PILOT_SCALE).max(PILOT_MIN_SIDE.min(set.width));
    p.height = (set.height / PILOT_SCALE).max(PILOT_MIN_SIDE.min(set.height));
    p.integrator.kind = kind;
    p.sampler.seed = set.sampler.seed ^ 0x9170_7d5e_ed00_a11c;
    p
}

/// `PILOT_SPP` samples per pixel with the pilot's settings `p`: the film, the rendering
/// seconds, and its pixels' values.
fn run(scene: &Scene, p: &RenderSettings) -> Result<(RenderOutput, Vec<[f64; 3]>), String> {
    let integrator = Integrator::prepare(scene, p.integrator, p.spectral.bands(), &Silent)?;
    let out = render(scene, &integrator, p, Budget::Spp(PILOT_SPP), 0, &Silent)?;
    let image = (0..out.film.pixels.len())
        .map(|i| out.film.value(i))
        .collect();
    Ok((out, image))
}

/// Render the pilot of estimator `kind`.
pub fn pilot(scene: &Scene, set: &RenderSettings, kind: IntegratorKind) -> Result<Pilot, String> {
    let t0 = std::time::Instant::now();
    let p = pilot_settings(set, kind);
    let (out, image) = run(scene, &p)?;
    let seconds = t0.elapsed().as_secs_f64();
    let (rel_var, mean, mean_se) = statistics(&out.film, PILOT_SPP);
    let pixels = p.width as f64 * p.height as f64;
    let full = set.width as f64 * set.height as f64;
    Ok(Pilot {
        kind,
        rel_var,
        cost: out.counters.rays as f64 / (pixels * PILOT_SPP as f64) * ray_cost(kind),
        mean,
        mean_se,
        seconds,
        seconds_per_spp: out.seconds / PILOT_SPP as f64 * full / pixels,
        image,
    })
}

/// r_p of each pilot pixel, from a second pilot of the chosen estimator with a seed of its
/// own (its seconds returned too): the perceptual error's threshold (5% of the sum of the
/// channels, at least the floor's share of the image's mean) over the standard deviation of
/// one sample. The deviation is measured as the two pilots' difference (the sum of its
/// channels' magnitudes, squared, averaged over the pixel's 3x3 neighbourhood), not as the
/// spread of a pixel's samples: that spread counts the detail inside a pilot pixel (which
/// covers `PILOT_SCALE`^2 pixels of the image) and ignores how much better than independent
/// samples the Sobol sampler integrates, and overstated the error of a furnished room 25x.
pub fn thresholds_over_sd(
    scene: &Scene,
    set: &RenderSettings,
    first: &Pilot,
) -> Result<(Noise, f64), String> {
    let t0 = std::time::Instant::now();
    let mut p = pilot_settings(set, first.kind);
    p.sampler.seed ^= 0x5ec0_4d00_0000_0001;
    let (_, second) = run(scene, &p)?;
    let r = threshold_over_error(&first.image, &second, p.width as usize, PILOT_SPP);
    Ok((r, t0.elapsed().as_secs_f64()))
}

/// r_p of two independent images `a` and `b` (`width` pixels a row) of `spp` samples per
/// pixel each: 5% x max(||mean||, floor) over sqrt(spp x E[||a - b||^2] / 2), the expectation
/// the mean over the 3x3 neighbourhood; infinite where the images agree. And the relative
/// RMSE of one sample: sqrt(spp x mean_p ||a - b||^2 / 2) / mean_p ||mean||.
pub fn threshold_over_error(a: &[[f64; 3]], b: &[[f64; 3]], width: usize, spp: u32) -> Noise {
    use crate::metrics::{PERCEPTUAL_FLOOR, PERCEPTUAL_THRESHOLD};
    let n = a.len().min(b.len());
    let width = width.max(1);
    let height = n / width;
    let norm = |i: usize| (0..3).map(|c| (a[i][c] + b[i][c]).abs() / 2.0).sum::<f64>();
    let diff2 = |i: usize| {
        (0..3)
            .map(|c| (a[i][c] - b[i][c]).abs())
            .sum::<f64>()
            .powi(2)
    };
    let mean = (0..n).map(norm).sum::<f64>() / n.max(1) as f64;
    let mean_diff2 = (0..n).map(diff2).sum::<f64>() / n.max(1) as f64;
    let rel_sd = (spp as f64 * mean_diff2 / 2.0).sqrt() / mean;
    let floor = PERCEPTUAL_FLOOR * mean;
    let threshold_over_sd = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let (mut sum, mut count) = (0.0, 0.0);
            for yy in y.saturating_sub(1)..(y + 2).min(height) {
                for xx in x.saturating_sub(1)..(x + 2).min(width) {
                    sum += diff2(yy * width + xx);
                    count += 1.0;
                }
            }
            let sd = (spp as f64 * sum / count / 2.0).sqrt();
            let t = PERCEPTUAL_THRESHOLD * norm(i).max(floor);
            if sd > 0.0 {
                t / sd
            } else {
                f64::INFINITY
            }
        })
        .collect();
    Noise {
        threshold_over_sd,
        rel_sd: if rel_sd.is_finite() { rel_sd } else { 0.0 },
    }
}

/// The share of pixels plain rendering is predicted to leave more than the perceptual
/// threshold off with `spp` samples per pixel: the mean of erfc(r_p sqrt(spp / 2)).
pub fn predicted_off_share(threshold_over_sd: &[f64], spp: f64) -> f64 {
    if threshold_over_sd.is_empty() {
        return 0.0;
    }
    let k = (spp.max(0.0) / 2.0).sqrt();
    threshold_over_sd
        .iter()
        .map(|r| libm::erfc(r * k))
        .sum::<f64>()
        / threshold_over_sd.len() as f64
}

/// What the pilot predicts of plain rendering at `spp` samples per pixel: whether DTF
/// beats it, the share of pixels it leaves more than 5% off, its RMSE relative to the
/// image's mean.
pub fn dtf_helps(noise: &Noise, spp: f64) -> (bool, f64, f64) {
    let off = predicted_off_share(&noise.threshold_over_sd, spp);
    let rel_rmse = noise.rel_sd / spp.max(1e-12).sqrt();
    (
        off >= DTF_MIN_OFF || rel_rmse >= DTF_MIN_REL_RMSE,
        off,
        rel_rmse,
    )
}

/// (v, mu, its standard error) of a film of `spp` samples per pixel, on the mean of the
/// three channels.
pub fn statistics(film: &Film, spp: u32) -> (f64, f64, f64) {
    let n = film.pixels.len();
    let value = |i: usize| film.value(i).iter().sum::<f64>() / 3.0;
    // the variance of the channels' mean, their covariance left out
    let var = |i: usize| film.variance_of_value(i).iter().sum::<f64>() / 9.0;
    let mean = (0..n).map(value).sum::<f64>() / n as f64;
    let sum_var = (0..n).map(var).sum::<f64>();
    let rel_var = sum_var * spp as f64 / (n as f64 * mean.max(f64::MIN_POSITIVE).powi(2));
    let mean_se = sum_var.sqrt() / n as f64;
    (rel_var, mean, mean_se)
}

/// The candidate that wins, and the one line that says why.
pub fn choose(pilots: &[Pilot]) -> (IntegratorKind, String) {
    let name = |k: IntegratorKind| crate::options::name(&k);
    // the first of the most efficient: ties go to the first candidate (the path tracer)
    let best = pilots
        .iter()
        .fold(None::<&Pilot>, |b, p| match b {
            Some(b) if b.efficiency() >= p.efficiency() => Some(b),
            _ => Some(p),
        })
        .expect("at least one candidate");
    // an estimator that misses light the other finds loses whatever its variance
    let misses = |a: &Pilot, b: &Pilot| {
        let d = b.mean - a.mean;
        d > MISSING * b.mean && d > 3.0 * (a.mean_se.powi(2) + b.mean_se.powi(2)).sqrt()
    };
    if let Some(other) = pilots.iter().find(|o| misses(best, o)) {
        return (
            other.kind,
            format!(
                "{}: {} misses light the pilot found with it (image mean {:.4} against {:.4})",
                name(other.kind),
                name(best.kind),
                best.mean,
                other.mean
            ),
        );
    }
    let others: Vec<String> = pilots
        .iter()
        .filter(|p| p.kind != best.kind)
        .map(|p| {
            format!(
                "{:.2}x {}'s",
                best.efficiency() / p.efficiency(),
                name(p.kind)
            )
        })
        .collect();
    (
        best.kind,
        format!(
            "{}: its efficiency (1 / (relative variance x cost) in a {PILOT_SPP}-spp pilot) {}",
            name(best.kind),
            if others.is_empty() {
                "is the only one measured".to_string()
            } else {
                format!("is {}", others.join(", "))
            }
        ),
    )
}

#[cfg(test)]
mod tests {
    use crate::render::{choose_method, Method, RenderJob};
    use crate::{integrator::IntegratorKind, pipeline::Silent};

    /// The job `--method auto` makes of `scene` at 64x64 with `extra` set.
    fn chosen(scene: &str, spp: Option<u32>, edit: impl Fn(&mut RenderJob)) -> (RenderJob, String) {
        let sc = crate::scene::load(scene).unwrap();
        let mut job = RenderJob::new(scene);
        job.res = Some((64, 64));
        job.spp = spp;
        edit(&mut job);
        let set = job.settings(&sc);
        let (j, line) = choose_method(&sc, &job, &set, &Silent).unwrap();
        (j, line.expect("auto says what it chose"))
    }

    /// A lamp whose light leaves only through a glass sphere: the path tracer reaches it
    /// only when a BSDF-sampled ray hits the lamp, BDPT's light paths carry it: BDPT wins.
    #[test]
    fn a_caustic_seen_through_glass_picks_bdpt() {
        let (j, line) = chosen("caustic", Some(64), |_| {});
        assert_eq!(j.integrator, Some(IntegratorKind::Bdpt), "{line}");
        assert_eq!(j.method, Method::Dtf, "{line}");
        assert!(line.starts_with("dtf over bdpt; bdpt: "), "{line}");
    }

    /// A diffuse box lit from the ceiling: the path tracer, filtered where the budget
    /// allows, plain where it does not.
    #[test]
    fn a_diffuse_box_picks_the_path_tracer() {
        let (j, line) = chosen("cornell", Some(64), |_| {});
        assert_eq!((j.method, j.integrator), (Method::Dtf, None), "{line}");
        let (j, line) = chosen("cornell", Some(8), |_| {});
        assert_eq!((j.method, j.integrator), (Method::Plain, None), "{line}");
        assert!(line.contains("about 8 spp fit the budget"), "{line}");
    }

    /// Naming the estimator, or a method, turns the choice off.
    #[test]
    fn a_named_estimator_or_method_is_kept() {
        let (j, line) = chosen("caustic", Some(64), |j| {
            j.integrator = Some(IntegratorKind::Path)
        });
        assert_eq!(
            (j.method, j.integrator),
            (Method::Plain, Some(IntegratorKind::Path))
        );
        assert!(line.contains("--integrator names the estimator"), "{line}");
        let sc = crate::scene::load("cornell").unwrap();
        let mut job = RenderJob::new("cornell");
        job.method = Method::Rw;
        let set = job.settings(&sc);
        let (j, line) = choose_method(&sc, &job, &set, &Silent).unwrap();
        assert_eq!((j.method, line), (Method::Rw, None));
    }

    /// The choice is made from ray counts, not seconds: the same on every seed tried.
    #[test]
    fn low_noise_picks_plain_high_noise_picks_dtf() {
        use crate::pipeline::auto::{dtf_helps, predicted_off_share, Noise, DTF_MIN_OFF};
        let noise = |r: f64, rel_sd: f64| Noise {
            threshold_over_sd: vec![r; 100],
            rel_sd,
        };
        // every pixel's sample deviation 1/10 of its threshold, the image's 1/10 of its
        // mean: at 64 spp no pixel is off (erfc(80 / sqrt 2) ~ 0), relative RMSE 1.25%
        let (helps, off, rel) = dtf_helps(&noise(10.0, 0.1), 64.0);
        assert!(
            !helps && off < 1e-12 && (rel - 0.0125).abs() < 1e-12,
            "{off} {rel}"
        );
        // deviation 10x the threshold: at 64 spp 1.25x, erfc(0.8 / sqrt 2) = 42% off
        let high = noise(0.1, 1.0);
        let (helps, off, _) = dtf_helps(&high, 64.0);
        assert!(helps && (off - 0.4237).abs() < 1e-3, "{off}");
        // the same pixels with enough samples: plain
        assert!(!dtf_helps(&high, 1e6).0);
        // a share: 20 noisy pixels in 100 (r = 0, always off) are above the bar, 5 are not
        let mut some = noise(10.0, 0.1);
        some.threshold_over_sd[..20].fill(0.0);
        assert!((predicted_off_share(&some.threshold_over_sd, 64.0) - 0.2).abs() < 1e-12);
        assert!(dtf_helps(&some, 64.0).0 && DTF_MIN_OFF <= 0.2);
        some.threshold_over_sd[5..].fill(10.0);
        assert!(!dtf_helps(&some, 64.0).0 && DTF_MIN_OFF > 0.05);
        // few pixels off but a large RMSE (fireflies): dtf
        assert!(dtf_helps(&noise(10.0, 0.5), 64.0).0);
        // a pixel with no noise is never off; an empty pilot predicts nothing off
        assert_eq!(predicted_off_share(&[f64::INFINITY], 1.0), 0.0);
        assert_eq!(predicted_off_share(&[], 1.0), 0.0);
    }

    /// r_p from two images: value 1 in every channel (threshold 0.15), differing by 0.06 in
    /// every channel (||a - b|| = 0.18) at 2 spp: one sample's deviation sqrt(2 x 0.0324 / 2).
    #[test]
    fn two_pilots_give_the_threshold_over_the_error() {
        use crate::pipeline::auto::threshold_over_error;
        let a = vec![[1.03; 3]; 12];
        let b = vec![[0.97; 3]; 12];
        let noise = threshold_over_error(&a, &b, 4, 2);
        // sqrt(2 x 0.0324 / 2) / 3
        assert!((noise.rel_sd - 0.06).abs() < 1e-12, "{}", noise.rel_sd);
        let r = noise.threshold_over_sd;
        assert_eq!(r.len(), 12);
        for v in &r {
            assert!((v - 0.15 / 0.18).abs() < 1e-9, "{v}");
        }
        // the same images: no error, never off
        let same = threshold_over_error(&a, &a, 4, 2);
        assert!(same.threshold_over_sd.iter().all(|v| v.is_infinite()) && same.rel_sd == 0.0);
        // one differing pixel is spread over its 3x3 neighbourhood (a corner: 4 pixels)
        let mut c = a.clone();
        c[0] = [0.97; 3];
        let r = threshold_over_error(&a, &c, 4, 2).threshold_over_sd;
        assert!(
            (r[0] - 0.15 / (0.18f64.powi(2) / 4.0).sqrt()).abs() < 1e-9,
            "{}",
            r[0]
        );
        assert!(r[5].is_finite() && r[2].is_infinite() && r[8].is_infinite());
    }

    #[test]
    fn the_choice_is_stable_over_seeds() {
        for seed in 1..4 {
            let (j, line) = chosen("cornell", Some(64), |j| j.seed = seed);
            assert_eq!(j.integrator, None, "seed {seed}: {line}");
            let (j, line) = chosen("caustic", Some(64), |j| j.seed = seed);
            assert_eq!(
                j.integrator,
                Some(IntegratorKind::Bdpt),
                "seed {seed}: {line}"
            );
        }
    }
}
