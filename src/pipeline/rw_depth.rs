//! The gather's depth, chosen from a pilot (`--method rw` without `--gather-depth`).
//!
//! The lookup at depth d (at the d-th diffuse vertex, `integrator::gather`) trades noise
//! for bias: a deeper gather traces one more diffuse bounce (more noise, more cost per
//! trial) and sees the radiosity solution's error through it (blurred, scaled by an
//! albedo). Measured at equal time (docs/results/rushmeier-ward.md), depth 2-3 wins on the
//! Cornell box and depth 1 on rw-room at every budget: the choice is the scene's, and the
//! budget's, so it is measured.
//!
//! For each candidate depth d, a small pilot (`PILOT_SIDE`^2 pixels, two independent halves
//! of `PILOT_SAMPLES` trials each, in rounds until `PILOT_SHARE` of the budget is spent; the
//! rounds' figures averaged) renders the lookup twice with the same random numbers:
//! with the solution (n_f elements) and with the coarse solution the preprocess solved first
//! (n_c elements, `Solution::coarser`). From it:
//!
//! - s^2_d: a trial's variance, per pixel and channel (averaged), read as the two halves'
//!   difference, (a - b)^2 / 2 times the trials of a half (not from each pixel's sample
//!   spread: the difference keeps the sampler's stratification, which the spread ignores),
//!   of the light the gather carries (the light seen directly is the same at every depth
//!   and is left out, as `rw` tests it apart); and t_d, the seconds per trial;
//! - Delta_d,p = (fine - coarse) at pixel p, in each half. If the solution's error falls as
//!   h^k in the element size h ~ n^(-1/2) (Richardson's assumption; k = `ERROR_ORDER` = 1,
//!   the order at shadow edges and corners, the conservative one), the fine solution's
//!   error at p is e_p = -Delta_p / (r^k - 1), r = sqrt(n_f / n_c). Its square is estimated
//!   without the pilot's noise as the product of the two halves' Delta_p (independent, so
//!   the product's mean is the square of the mean).
//!
//! The predicted mean squared error at the budget, N_d trials per pixel (the seconds left
//! over t_d and the image's pixels, or the `--spp` given):
//!
//!   E_d = mean_p s^2_d,p / N_d + mean_p e^2_d,p
//!
//! and the depth with the least E_d renders. Left out of the model: the energy-preserving
//! filter (it lowers every depth's noise alike) and the bias correction (`rw_bias`, which
//! removes the part of e common to a 9x9 box); both make E_d's bias term an upper bound.
//!
//! One more candidate is no gather at all (`NO_GATHER`: every bounce traced, the trials and
//! the filter as before): no bias, so E = s^2 / N. As the budget grows every depth's E_d
//! falls to its e^2 and this one to 0, so past some budget it is chosen: the method's
//! error keeps falling as path tracing's does, with no floor set by the solution.

use super::render::{render_pass_split, Counts, Pass};
use super::RenderSettings;
use crate::film::Film;
use crate::integrator::gather::DEFAULT_GATHER_DEPTH;
use crate::integrator::{Gather, Integrator};
use crate::progress::Progress;
use crate::scene::Scene;
use std::time::Instant;

/// The candidate that gathers nothing: every bounce traced (`--gather off`).
pub const NO_GATHER: u32 = 0;
/// The depths the pilot compares, and no gather.
pub const CANDIDATES: [u32; 4] = [1, 2, 3, NO_GATHER];
/// Side of the square pilot image.
pub const PILOT_SIDE: u32 = 32;
/// Trials per pixel in each of the pilot's two halves.
pub const PILOT_SAMPLES: u32 = 16;
/// The pilot's share of the budget: rounds of `PILOT_SAMPLES` trials are added until it
/// is spent (at least one round, at most `MAX_ROUNDS`).
pub const PILOT_SHARE: f64 = 0.02;
/// The most rounds the pilot takes.
pub const MAX_ROUNDS: u32 = 16;
/// The order k of the solution's error in the element size (Richardson's estimate).
pub const ERROR_ORDER: f64 = 1.0;
/// The pilot's first random stream (`rw` uses 0-3; each round takes two).
const FIRST_STREAM: u32 = 4;

/// What the pilot measured of one depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthEstimate {
    pub depth: u32,
    /// Mean over pixels and channels of the trials' variance s^2.
    pub variance: f64,
    /// Seconds per trial: the pilot's seconds per ray (all depths together) times the
    /// depth's rays per trial, so that the depths' relative costs are counts, not timings
    /// of passes of a few milliseconds.
    pub seconds_per_trial: f64,
    pub rays_per_trial: f64,
    /// Mean over pixels and channels of the solution's squared error seen at the pixel,
    /// e^2 (an unbiased estimate: it can come out below 0).
    pub error2: f64,
}

/// The budget the depth is chosen for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrialBudget {
    /// Trials per pixel over this many pixels, whatever their cost.
    PerPixel { trials: f64, pixels: f64 },
    /// Seconds for trials over this many pixels.
    Seconds { seconds: f64, pixels: f64 },
}

impl DepthEstimate {
    /// The sum of two rounds' figures (their mean is the sum scaled by 1/2).
    fn plus(&self, o: &DepthEstimate) -> DepthEstimate {
        DepthEstimate {
            depth: self.depth,
            variance: self.variance + o.variance,
            seconds_per_trial: self.seconds_per_trial + o.seconds_per_trial,
            rays_per_trial: self.rays_per_trial + o.rays_per_trial,
            error2: self.error2 + o.error2,
        }
    }

    fn scaled(&self, k: f64) -> DepthEstimate {
        DepthEstimate {
            depth: self.depth,
            variance: self.variance * k,
            seconds_per_trial: self.seconds_per_trial * k,
            rays_per_trial: self.rays_per_trial * k,
            error2: self.error2 * k,
        }
    }

    /// Trials per pixel the budget allows at this depth.
    pub fn trials(&self, budget: TrialBudget) -> f64 {
        match budget {
            TrialBudget::PerPixel { trials, .. } => trials,
            TrialBudget::Seconds { seconds, pixels } => {
                seconds / (self.seconds_per_trial.max(1e-12) * pixels.max(1.0))
            }
        }
        .max(1.0)
    }

    /// E_d: the noise left at the budget and the solution's squared error.
    pub fn predicted_mse(&self, budget: TrialBudget) -> f64 {
        self.variance / self.trials(budget) + self.error2.max(0.0)
    }
}

/// The depth taken, and the line `--stats` gives for it.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthChoice {
    pub depth: u32,
    pub line: String,
    pub estimates: Vec<DepthEstimate>,
    pub seconds: f64,
}

/// The candidate with the least predicted error (the shallower on a tie).
pub fn least(estimates: &[DepthEstimate], budget: TrialBudget) -> Option<DepthEstimate> {
    estimates.iter().copied().reduce(|best, e| {
        if e.predicted_mse(budget) < best.predicted_mse(budget) {
            e
        } else {
            best
        }
    })
}

/// Measure the candidates and choose (None without a solution; the default depth, saying
/// why, when the solution has no coarser one to compare with: a `--radiosity-max-area`
/// mesh, one of about an element per triangle, or a budget too small to refine).
pub fn choose(
    scene: &Scene,
    integrator: &Integrator,
    set: &RenderSettings,
    budget: TrialBudget,
    progress: &dyn Progress,
) -> Result<Option<DepthChoice>, String> {
    let t0 = Instant::now();
    let Some(fine) = integrator.radiosity.as_ref() else {
        return Ok(None);
    };
    let unchosen = |why: String| DepthChoice {
        depth: DEFAULT_GATHER_DEPTH,
        line: format!("gather depth {DEFAULT_GATHER_DEPTH}, the paper's: {why}"),
        estimates: Vec::new(),
        seconds: 0.0,
    };
    let Some(coarse) = fine.coarser.as_ref() else {
        return Ok(Some(unchosen(format!(
            "the solution's {} elements have no coarser solution to measure its error against \
             (the mesh is about one element per triangle, or a budget too small to refine it)",
            fine.stats.elements
        ))));
    };
    let r = (fine.stats.elements as f64 / coarse.stats.elements.max(1) as f64).sqrt();
    let scale = r.powf(ERROR_ORDER) - 1.0;
    if scale <= 0.0 {
        return Ok(Some(unchosen("the coarser solution is not coarser".into())));
    }
    let mut pset = *set;
    pset.width = PILOT_SIDE;
    pset.height = PILOT_SIDE;
    // per candidate: with the solution and with the coarse one (no gather: traced alone)
    let integrators: Vec<Vec<Integrator>> = CANDIDATES
        .iter()
        .map(|&depth| {
            let mut with_fine = integrator.clone();
            if depth == NO_GATHER {
                with_fine.set.gather = Gather::Off;
                return vec![with_fine];
            }
            with_fine.set.gather_depth = Some(depth);
            let mut with_coarse = with_fine.clone();
            with_coarse.radiosity = Some(coarse.clone());
            vec![with_fine, with_coarse]
        })
        .collect();
    // Rounds of the pilot until its share of the budget is spent (at least one).
    let mut sums: Vec<DepthEstimate> = Vec::new();
    let mut rounds = 0;
    while rounds < MAX_ROUNDS {
        let round: Vec<DepthEstimate> = CANDIDATES
            .iter()
            .zip(&integrators)
            .map(|(&depth, integ)| pilot_round(scene, integ, &pset, depth, rounds, scale, progress))
            .collect::<Result<_, _>>()?;
        sums = if sums.is_empty() {
            round
        } else {
            sums.iter().zip(&round).map(|(a, b)| a.plus(b)).collect()
        };
        rounds += 1;
        let spent = t0.elapsed().as_secs_f64();
        let share = PILOT_SHARE * budget_seconds(&sums[0], budget);
        if spent * (rounds + 1) as f64 / rounds as f64 > share {
            break;
        }
    }
    let mut estimates: Vec<DepthEstimate> =
        sums.iter().map(|e| e.scaled(1.0 / rounds as f64)).collect();
    let seconds_per_ray = estimates.iter().map(|e| e.seconds_per_trial).sum::<f64>()
        / estimates
            .iter()
            .map(|e| e.rays_per_trial)
            .sum::<f64>()
            .max(1e-12);
    for e in &mut estimates {
        e.seconds_per_trial = seconds_per_ray * e.rays_per_trial;
    }
    let Some(best) = least(&estimates, budget) else {
        return Ok(None);
    };
    let each: Vec<String> = estimates
        .iter()
        .map(|e| {
            format!(
                "{} {:.2e} = noise {:.2e} at {:.0} trials + error {:.2e}",
                name(e.depth),
                e.predicted_mse(budget).sqrt(),
                (e.variance / e.trials(budget)).sqrt(),
                e.trials(budget),
                e.error2.max(0.0).sqrt(),
            )
        })
        .collect();
    let line = format!(
        "{}: the least predicted RMSE ({}; the solution's error from its {} elements against \
         the coarse {})",
        match best.depth {
            NO_GATHER => "no gather".to_string(),
            d => format!("gather depth {d}"),
        },
        each.join(", "),
        fine.stats.elements,
        coarse.stats.elements,
    );
    Ok(Some(DepthChoice {
        depth: best.depth,
        line,
        estimates,
        seconds: t0.elapsed().as_secs_f64(),
    }))
}

/// A candidate's name in the choice's line.
fn name(depth: u32) -> String {
    match depth {
        NO_GATHER => "no gather".into(),
        d => format!("depth {d}"),
    }
}

/// One round of the pilot for one depth: two halves (their own streams), each rendered with
/// the solution and with the coarse one from the same random numbers (no gather: once).
#[allow(clippy::too_many_arguments)]
fn pilot_round(
    scene: &Scene,
    integ: &[Integrator],
    pset: &RenderSettings,
    depth: u32,
    round: u32,
    scale: f64,
    progress: &dyn Progress,
) -> Result<DepthEstimate, String> {
    let mut films = Vec::with_capacity(4);
    let (mut seconds, mut rays) = (0.0, 0u64);
    for half in 0..2 {
        for (k, integrator) in integ.iter().enumerate() {
            let mut film = Film::new(PILOT_SIDE, PILOT_SIDE)?;
            let mut seen = Film::new(PILOT_SIDE, PILOT_SIDE)?;
            let t = Instant::now();
            let c = render_pass_split(
                &Pass {
                    scene,
                    integrator,
                    set: pset,
                    counts: Counts::Uniform(PILOT_SAMPLES),
                    first_index: 0,
                    stream: FIRST_STREAM + 2 * round + half,
                    progress,
                },
                &mut film,
                &mut seen,
            );
            if k == 0 {
                seconds += t.elapsed().as_secs_f64();
                rays += c.rays;
            }
            films.push(film);
        }
    }
    Ok(estimate_of(depth, &films, scale, seconds, rays))
}

/// The seconds a budget stands for (the trials over the image at the measured rate).
fn budget_seconds(e: &DepthEstimate, budget: TrialBudget) -> f64 {
    match budget {
        TrialBudget::Seconds { seconds, .. } => seconds,
        TrialBudget::PerPixel { trials, pixels } => trials * e.seconds_per_trial * pixels,
    }
}

/// One depth's figures from its four films: (fine, coarse) of half a, then of half b; or
/// from two, half a and half b, for a candidate without a solution's error (`NO_GATHER`).
fn estimate_of(depth: u32, films: &[Film], scale: f64, seconds: f64, rays: u64) -> DepthEstimate {
    let (fa, ca, fb, cb) = match films {
        [a, b] => (a, a, b, b),
        [fa, ca, fb, cb] => (fa, ca, fb, cb),
        _ => unreachable!("two or four films"),
    };
    let n = fa.pixels.len().max(1) as f64 * 3.0;
    let (mut variance, mut error2) = (0.0, 0.0);
    for i in 0..fa.pixels.len() {
        let (ma, mca) = (fa.pixels[i].mean(), ca.pixels[i].mean());
        let (mb, mcb) = (fb.pixels[i].mean(), cb.pixels[i].mean());
        for c in 0..3 {
            // (a - b)^2 / 2 is the variance of one half's mean: a trial's, times its trials
            variance += 0.5 * (ma[c] - mb[c]).powi(2) * PILOT_SAMPLES as f64;
            error2 += (ma[c] - mca[c]) * (mb[c] - mcb[c]) / (scale * scale);
        }
    }
    let trials = 2.0 * PILOT_SAMPLES as f64 * fa.pixels.len() as f64;
    DepthEstimate {
        depth,
        variance: variance / n,
        seconds_per_trial: seconds / trials.max(1.0),
        rays_per_trial: rays as f64 / trials.max(1.0),
        error2: error2 / n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn est(depth: u32, variance: f64, seconds_per_trial: f64, error2: f64) -> DepthEstimate {
        DepthEstimate {
            depth,
            variance,
            seconds_per_trial,
            rays_per_trial: seconds_per_trial * 1e7,
            error2,
        }
    }

    /// The candidate chosen at n trials per pixel.
    fn chosen_at(d: &[DepthEstimate], n: f64) -> u32 {
        let b = TrialBudget::PerPixel {
            trials: n,
            pixels: 1.0,
        };
        least(d, b).unwrap().depth
    }

    /// Noise wins at small budgets, the solution's error at large ones: a shallow gather
    /// (little noise, more error) first, a deeper one (more noise and cost, less error) later.
    #[test]
    fn the_depth_moves_with_the_budget() {
        let d = [est(1, 1.0, 1e-6, 1e-4), est(2, 3.0, 1.5e-6, 1e-5)];
        let at = |n: f64| chosen_at(&d, n);
        // E_1 = 1/n + 1e-4, E_2 = 3/n + 1e-5: equal at n = 2 / 9e-5 ~ 22,222
        assert_eq!(at(1_000.0), 1);
        assert_eq!(at(100_000.0), 2);
        // in seconds: depth 2's trials cost 1.5x, so it needs 1.5x the trials' time
        let secs = |s: f64| {
            least(
                &d,
                TrialBudget::Seconds {
                    seconds: s,
                    pixels: 1.0,
                },
            )
            .unwrap()
            .depth
        };
        assert_eq!(secs(0.02), 1); // 20,000 trials of depth 1
        assert_eq!(secs(1.0), 2);
        // a negative error estimate counts as none, not as a gain
        let e = [est(1, 1.0, 1e-6, 0.0), est(2, 1.0, 1e-6, -1.0)];
        assert_eq!(
            least(
                &e,
                TrialBudget::PerPixel {
                    trials: 10.0,
                    pixels: 1.0
                }
            )
            .unwrap()
            .depth,
            1
        );
    }

    /// On the Cornell box the coarse solution (a few hundred elements) is far from the fine
    /// one at the first bounce and the pilot measures it; the deeper gather sees less of it.
    #[test]
    fn the_pilot_sees_the_solutions_error_on_cornell() {
        use crate::render::RenderJob;
        let scene = crate::scene::load("cornell").unwrap();
        let mut job = RenderJob::new("cornell");
        job.res = Some((32, 32));
        job.method = crate::render::Method::Rw;
        let set = job.settings(&scene);
        let mut iset = set.integrator;
        iset.gather = crate::integrator::Gather::Radiosity;
        let integ = Integrator::prepare(&scene, iset, 3, &crate::progress::Silent).unwrap();
        let sol = integ.radiosity.as_ref().unwrap();
        assert!(
            sol.coarser.is_some(),
            "the default mesh keeps its coarse solution"
        );
        let choice = choose(
            &scene,
            &integ,
            &set,
            TrialBudget::PerPixel {
                trials: 1e6,
                pixels: 32.0 * 32.0,
            },
            &crate::progress::Silent,
        )
        .unwrap()
        .unwrap();
        let e = &choice.estimates;
        assert_eq!(e.len(), 4);
        assert!(e[0].error2 > 0.0, "{e:?}");
        assert!(e[1].error2 < e[0].error2, "{e:?}");
        assert!(e[1].variance > e[0].variance, "{e:?}");
        // tracing every bounce: no error, the most noise
        assert_eq!((e[3].depth, e[3].error2), (NO_GATHER, 0.0), "{e:?}");
        assert!(e[3].variance > e[0].variance, "{e:?}");
        // at a million trials the error decides, and only tracing every bounce has none
        assert_eq!(choice.depth, NO_GATHER, "{}", choice.line);
        assert!(choice.line.starts_with("no gather: "), "{}", choice.line);
        // at 64 trials the noise decides: a gather
        let small = TrialBudget::PerPixel {
            trials: 64.0,
            pixels: 32.0 * 32.0,
        };
        assert_ne!(least(e, small).unwrap().depth, NO_GATHER, "{e:?}");
    }

    /// No floor: whatever the depths' errors, past some budget the candidate without a
    /// gather (no error) is chosen, however noisy.
    #[test]
    fn past_some_budget_no_gather_is_chosen() {
        let d = [
            est(1, 1.0, 1e-6, 1e-6),
            est(2, 2.0, 1.5e-6, 1e-8),
            est(NO_GATHER, 50.0, 3e-6, 0.0),
        ];
        let at = |n: f64| chosen_at(&d, n);
        assert_eq!(at(1e3), 1);
        // E_2 = 2/n + 1e-8 against E_none = 50/n: equal at n = 4.8e9
        assert_eq!(at(1e9), 2);
        assert_eq!(at(1e11), NO_GATHER);
    }
}
