//! Rushmeier and Ward's method ("Energy preserving non-linear filters", SIGGRAPH 1994,
//! section 4): a pilot sample plans the trials, every pixel gets trials until it
//! converges, and the energy-preserving filter (`filter::energy`) removes what is left of
//! the noise without moving energy. Works with any estimator (the paper's is the path
//! tracer with `--gather radiosity`).
//!
//! 1. Pilot: a PILOT_RES x PILOT_RES image (same camera, same estimator, its own random
//!    stream) at 16 trials per pixel: S_16, L_ave, Lt_vis = L_ave / N_MID,
//!    Mt = 16 (S_16 / (D Lt_vis))^2 (Eq. 10), Mt_ceiling = 4 Mt. The convergence budget
//!    takes the larger of Eq. 10's Mt and the one whose ceiling covers 90% of the pilot's
//!    predicted needs (t S / (D Lt_vis))^2, S read as the stopping test reads it (pooled
//!    3x3 unless `--rw-pixel-test`): the average S_16 misses pixels with heavy tails.
//! 2. Trials: every pixel of the image gets Mt trials, then passes of ceil(Mt / 4) trials
//!    for the pixels not yet converged (t S_p / sqrt(M) <= D Lt_vis) until Mt_ceiling.
//!    Pixels still running are in lockstep, so each pass starts at one sample index and
//!    no index repeats in a pixel.
//! 3. The energy-preserving filter on the film (means, S_p, M).
//! 4. With the radiosity gather (the default of `--method rw`): the gather's bias
//!    correction (`rw_bias`), from its own samples taken after the first Mt trials.
//!
//! The light seen directly (through mirrors and glass too) is kept out of the filter, but
//! its deviation is in the stopping test: an emitter's edge pixels carry the image's
//! largest error and get trials to the ceiling.
//!
//! Budgets (`--spp`, `--time`): the paper plans by D alone; with a budget, Mt (and with it
//! Mt_ceiling = 4 Mt) is scaled so that the spend the pilot predicts,
//! mean_p clamp((t S_p / (D Lt_vis))^2, Mt, 4 Mt) over the pilot pixels, equals the
//! budget's average trials per pixel, and the passes stop when the budget is spent (a
//! hard cap on the total trials, or on the wall clock for `--time`, pilot included; with
//! `--time` the passes fit the time left, and once every pixel has converged or reached
//! the ceiling the rest goes to every pixel).

use super::render::{render_pass, render_pass_split, Counts, Pass, RenderSettings};
use super::{rw_bias, rw_depth};
use crate::film::Film;
use crate::filter::energy::{
    self, converged, deviation, EnergyOutput, EnergyParams, Pilot, CEILING_FACTOR, PILOT_TRIALS,
};
use crate::integrator::{Counters, Gather, Integrator};
use crate::progress::Progress;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Options of `--method rw`. Each option's name, help and default are written here once.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct RwParams {
    /// RW: D, the visible difference in display units of 255 (paper: 5).
    #[arg(long = "rw-d", default_value_t = energy::DEFAULT_D, allow_hyphen_values = true)]
    pub d: f64,
    /// RW: t of the convergence test t S_p / sqrt(M) <= D Lt_vis (default 1.2816, the
    /// paper's 80% two-sided confidence in the large-sample limit).
    #[arg(long = "rw-t", default_value_t = energy::DEFAULT_T, allow_hyphen_values = true)]
    pub t: f64,
    /// RW: side of the square pilot image (paper: 100).
    #[arg(long = "rw-pilot-res", default_value_t = energy::PILOT_RES)]
    pub pilot_res: u32,
    /// RW: skip the energy-preserving filter (the image is the trials' means).
    #[arg(long = "rw-no-filter")]
    pub no_filter: bool,
    /// RW: skip the gather's bias correction (a few samples per pixel of the radiosity
    /// solution as a control variate, added where their mean stands out of their noise):
    /// the image keeps the solution's bias.
    #[arg(long = "rw-no-correction")]
    pub no_correction: bool,
    /// RW: test and filter the light seen directly (through mirrors and glass) with the
    /// rest, as the paper's text does. By default it is kept apart: a pixel on an emitter's
    /// edge varies only with its footprint, and its excess is an edge, not noise.
    #[arg(long = "rw-filter-emitters")]
    pub filter_emitters: bool,
    /// RW: stop each pixel on its own deviation S_p, as the paper does. By default the
    /// stopping test reads the RMS deviation of the pixel's 3x3 neighbourhood: a pixel's
    /// own S_p is correlated with its own mean (a pixel that has not yet met its rare
    /// bright paths looks converged and stops low), which biased images by several
    /// percent; the filter still tests each pixel on its own S_p.
    #[arg(long = "rw-pixel-test")]
    pub pixel_test: bool,
    /// RW: what one display unit is in the stopping test: `linear` (the paper's planning
    /// operator, L_ave at N_MID: Lt_vis everywhere) or `display` (a gamma-2.2 display
    /// curve through the same point: Lt_vis(L) = 2.2 Lt_vis (L / L_ave)^(1 - 1/2.2) at the
    /// pixel's luminance L, so dark pixels are held to a smaller absolute error).
    #[arg(long = "rw-target", value_enum, default_value_t = RwTarget::Linear)]
    pub target: RwTarget,
}

/// What one display unit (the D of the stopping test) is in radiance at a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum RwTarget {
    /// The paper's linear operator T(L) = N_MID L / L_ave: one unit is Lt_vis everywhere.
    #[default]
    Linear,
    /// A display's curve T(L) = N_MID (L / L_ave)^(1/gamma), gamma = 2.2, through the
    /// paper's point (L_ave, N_MID): one unit at L is 1 / T'(L) = gamma Lt_vis
    /// (L / L_ave)^(1 - 1/gamma) (L at least Lt_vis, so a black pixel keeps a target).
    Display,
}

/// The display curve's gamma of `RwTarget::Display`.
pub const DISPLAY_GAMMA: f64 = 2.2;

impl RwTarget {
    /// One display unit in radiance at a pixel of luminance `l` (Lt_vis for `Linear`).
    pub fn unit(self, lt_vis: f64, l_ave: f64, l: f64) -> f64 {
        match self {
            RwTarget::Linear => lt_vis,
            RwTarget::Display => {
                let g = DISPLAY_GAMMA;
                g * lt_vis * (l.max(lt_vis) / l_ave).powf(1.0 - 1.0 / g)
            }
        }
    }
}

impl Default for RwParams {
    fn default() -> Self {
        crate::options::defaults::<RwParams>()
    }
}

impl RwParams {
    pub fn validate(&self) -> Result<(), String> {
        energy::check_d(self.d)?;
        if !(self.t.is_finite() && self.t > 0.0) {
            return Err(format!("--rw-t {}: must be a positive number", self.t));
        }
        if self.pilot_res < 2 {
            return Err(format!(
                "--rw-pilot-res {}: must be at least 2",
                self.pilot_res
            ));
        }
        Ok(())
    }
}

/// How the amount of work is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RwBudget {
    /// The paper's: Mt and Mt_ceiling from D.
    Convergence,
    /// An average of this many trials per pixel (pilot not counted).
    Spp(f64),
    /// Wall-clock seconds for the whole method (pilot, trials, filter).
    Time(f64),
}

/// The figures `--stats` records.
#[derive(Clone, Debug, Serialize)]
pub struct RwStats {
    pub s16: f64,
    pub l_ave: f64,
    pub lt_vis: f64,
    pub d: f64,
    pub t: f64,
    /// Mt and Mt_ceiling from Eq. 10.
    pub mt: u32,
    pub mt_ceiling: u32,
    /// The Mt whose ceiling 4 Mt covers 90% of the pilot's predicted needs (the
    /// convergence budget takes the larger of it and Eq. 10's).
    pub mt_quantile: u32,
    /// Mt and Mt_ceiling used (scaled by a budget; else the same).
    pub mt_used: u32,
    /// The ceiling used: 4 Mt, raised by the second stage (convergence budget only).
    pub mt_ceiling_used: u32,
    /// Trials per pixel the pilot predicted, and those taken.
    pub predicted_trials: f64,
    pub average_trials: f64,
    pub passes: u32,
    /// Share of pixels whose stopping test passed at the end of the trials.
    pub converged_share: f64,
    /// The same share when the pilot's ceiling 4 Mt was reached (or at the end).
    pub converged_share_at_pilot_ceiling: f64,
    /// Share of noise pixels (not converged) the filter saw, and of those it spread.
    pub noise_share: f64,
    pub spread_share: f64,
    pub filter_passes: u32,
    pub untreated: usize,
    /// The gather's bias correction: samples per pixel (0: none) and the image's mean
    /// weight alpha (0: the lookup kept, 1: the correction taken whole).
    pub correction_samples: u32,
    pub correction_alpha: f64,
    /// Standard error of the image mean's luminance the correction adds (its noise).
    pub correction_se: f64,
    pub pilot_seconds: f64,
    /// The gather's depth (0: no gather), and why (`rw_depth`; empty when it was named or
    /// not chosen), with the seconds its pilot took.
    pub gather_depth: u32,
    pub gather_depth_choice: String,
    pub gather_depth_seconds: f64,
    pub trials_seconds: f64,
    pub filter_seconds: f64,
}

/// Everything the method produced.
pub struct RwRun {
    pub pilot: Pilot,
    /// The trials' means (unfiltered), light seen directly included.
    pub unfiltered: Vec<[f64; 3]>,
    /// The trials of what was tested and filtered: the transport, without the light seen
    /// directly unless `--rw-filter-emitters` (its statistics are the variance layers).
    pub film: Film,
    /// Trials each pixel got.
    pub trials: Vec<u32>,
    /// The filter's output (with `no_filter`, the means and no spreading).
    pub out: EnergyOutput,
    pub stats: RwStats,
    pub counters: Counters,
    pub seconds: f64,
}

/// The RMS of S_p over pixel i's 3x3 neighbourhood (clipped at the image's borders).
fn pooled_deviation(s_p: &[f64], w: usize, h: usize, i: usize) -> f64 {
    let (x, y) = (i % w, i / w);
    let (mut sum, mut n) = (0.0, 0.0);
    for yy in y.saturating_sub(1)..(y + 2).min(h) {
        for xx in x.saturating_sub(1)..(x + 2).min(w) {
            sum += s_p[yy * w + xx].powi(2);
            n += 1.0;
        }
    }
    (sum / n).sqrt()
}

/// The RMS over each pixel's 3x3 neighbourhood of a per-pixel quantity (deviations),
/// or the quantity itself with `pixel`.
fn pooled(v: &[f64], w: usize, h: usize, pixel: bool) -> Vec<f64> {
    if pixel {
        return v.to_vec();
    }
    (0..v.len()).map(|i| pooled_deviation(v, w, h, i)).collect()
}

/// The luminance each pixel's stopping test is held to (the pixel's own mean, or the
/// 3x3 average of the means when the test is pooled).
fn test_luminance(mean: &[[f64; 3]], w: usize, h: usize, pixel: bool) -> Vec<f64> {
    let l: Vec<f64> = mean.iter().map(|&c| energy::luminance(c)).collect();
    if pixel {
        return l;
    }
    (0..l.len())
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (mut sum, mut n) = (0.0, 0.0);
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    sum += l[yy * w + xx];
                    n += 1.0;
                }
            }
            sum / n
        })
        .collect()
}

/// The q-quantile (0..1) of a list (nearest rank; 0 for an empty list).
fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let k = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[k]
}

/// Share of the pilot's pixels whose predicted need the ceiling must cover.
pub const CEILING_QUANTILE: f64 = 0.9;
/// The same for Stein's second stage, from the first Mt trials: higher, because a pixel
/// whose need the ceiling just covers passes its noisy test only about half the time
/// (measured on cornell at D 5, 100x100, without the gather: 0.833 of the pixels converged
/// with the 0.9 quantile, 0.886 with 0.95, 0.902 with 0.97; with the gather 0.949).
pub const STEIN_QUANTILE: f64 = 0.97;
/// Passes the first Mt trials are split into under a deadline (`--time`).
const FIRST_CHUNKS: u32 = 8;

/// Per-pixel means of a film, plus those of a second film of the same size.
fn sum_means(a: &Film, b: Option<&Film>) -> Vec<[f64; 3]> {
    let mut m: Vec<[f64; 3]> = a.pixels.iter().map(|p| p.mean()).collect();
    if let Some(b) = b {
        for (o, p) in m.iter_mut().zip(&b.pixels) {
            let v = p.mean();
            for c in 0..3 {
                o[c] += v[c];
            }
        }
    }
    m
}

/// Each pixel's S_p as the stopping test reads it: the transport's, with the deviation
/// of the light seen directly (kept apart from the filter) added in quadrature. An
/// emitter's edge is not noise to filter, but its pixels' error is the largest of the
/// image (their footprint on a bright light): they must get trials, not stop at Mt.
fn test_deviations(film: &Film, vis: Option<&Film>) -> Vec<f64> {
    let mut s: Vec<f64> = film.pixels.iter().map(deviation).collect();
    if let Some(v) = vis {
        for (s, p) in s.iter_mut().zip(&v.pixels) {
            *s = s.hypot(deviation(p));
        }
    }
    s
}

/// Predicted trials of a pixel of pilot deviation S_p: (t S_p / (D Lt_vis))^2.
fn need(t: f64, s_p: f64, allowed: f64) -> f64 {
    (t * s_p / allowed).powi(2)
}

/// Each pixel's predicted need (t S / (D unit))^2 from a film's statistics, read as the
/// stopping test reads them: S pooled over 3x3 unless `--rw-pixel-test`, the display unit
/// at the pixel's (pooled) luminance.
fn needs_of(film: &Film, vis: Option<&Film>, params: &RwParams, pilot: &Pilot) -> Vec<f64> {
    let (w, h) = (film.width as usize, film.height as usize);
    let s_p = test_deviations(film, vis);
    let s = pooled(&s_p, w, h, params.pixel_test);
    let mean: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.mean()).collect();
    let lum = test_luminance(&mean, w, h, params.pixel_test);
    s.iter()
        .zip(&lum)
        .map(|(&s, &l)| {
            let unit = params.target.unit(pilot.lt_vis, pilot.l_ave, l);
            need(params.t, s, params.d * unit)
        })
        .collect()
}

/// Predicted average spend with Mt = m: mean clamp(need_p, m, 4 m).
fn predicted(needs: &[f64], m: f64) -> f64 {
    let hi = m * CEILING_FACTOR as f64;
    needs.iter().map(|&n| n.clamp(m, hi)).sum::<f64>() / needs.len().max(1) as f64
}

/// The Mt whose predicted average spend is `spp` (bisection; at least 2).
fn mt_for_budget(needs: &[f64], spp: f64) -> u32 {
    let (mut lo, mut hi) = (0.0f64, spp.max(1.0));
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if predicted(needs, mid) < spp {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo.floor() as u32).max(2)
}

/// Run the whole method.
pub fn render_rw(
    scene: &Scene,
    integrator: &Integrator,
    set: &RenderSettings,
    params: &RwParams,
    budget: RwBudget,
    progress: &dyn Progress,
) -> Result<RwRun, String> {
    params.validate()?;
    let t0 = Instant::now();
    let pixels = set.width as usize * set.height as usize;

    // 0. The gather's depth, unless named: the one a pilot predicts the least error for.
    let depth_budget = match budget {
        RwBudget::Spp(spp) => Some(rw_depth::TrialBudget::PerPixel {
            trials: spp,
            pixels: pixels as f64,
        }),
        RwBudget::Time(secs) => Some(rw_depth::TrialBudget::Seconds {
            seconds: secs,
            pixels: pixels as f64,
        }),
        RwBudget::Convergence => None,
    };
    let mut chosen = integrator.clone();
    let depth_choice = match depth_budget {
        Some(b)
            if integrator.set.gather.reads_solution() && integrator.set.gather_depth.is_none() =>
        {
            rw_depth::choose(scene, integrator, set, b, progress)?
        }
        _ => None,
    };
    if let Some(c) = &depth_choice {
        match c.depth {
            rw_depth::NO_GATHER => chosen.set.gather = Gather::Off,
            d => chosen.set.gather_depth = Some(d),
        }
        progress.message(&c.line);
    }
    let integrator = &chosen;
    let gather_depth = match integrator.set.gather.reads_solution() {
        true => integrator
            .set
            .gather_depth
            .unwrap_or(crate::integrator::gather::DEFAULT_GATHER_DEPTH),
        false => rw_depth::NO_GATHER,
    };

    // 1. The pilot: same camera and estimator at PILOT_RES^2, stream 1.
    let t_pilot = Instant::now();
    let mut pset = *set;
    pset.width = params.pilot_res;
    pset.height = params.pilot_res;
    let pilot_pixels = (params.pilot_res as u64).pow(2);
    let mut planned = pilot_pixels * PILOT_TRIALS as u64;
    progress.begin("trials", planned);
    // The transport (tested and filtered) and the light seen directly (added back), from
    // the same samples: their sum is the plain estimate, sample by sample.
    let split = !params.filter_emitters;
    // One pass: split into `film` and `vfilm`, or whole into `film`.
    let run = |p: &Pass, film: &mut Film, vfilm: &mut Film| {
        if split {
            render_pass_split(p, film, vfilm)
        } else {
            render_pass(p, film, None)
        }
    };
    let mut pfilm = Film::new(pset.width, pset.height)?;
    let mut pvis = Film::new(pset.width, pset.height)?;
    let mut counters = Counters::default();
    counters.add(&run(
        &Pass {
            scene,
            integrator,
            set: &pset,
            counts: Counts::Uniform(PILOT_TRIALS),
            first_index: 0,
            stream: 1,
            progress,
        },
        &mut pfilm,
        &mut pvis,
    ));
    let pmean = sum_means(&pfilm, split.then_some(&pvis));
    let ps: Vec<f64> = pfilm.pixels.iter().map(deviation).collect();
    let pilot = energy::pilot_of(&pmean, &ps, params.d)?;
    let pilot_seconds = t_pilot.elapsed().as_secs_f64();
    // Each pilot pixel's predicted need, (t S / (D unit))^2, read with the statistic the
    // stopping test will read (the pooled 3x3 deviation unless --rw-pixel-test) and the
    // display unit at the pixel's level: the prediction is of the test that is applied.
    let needs = needs_of(&pfilm, split.then_some(&pvis), params, &pilot);
    // Eq. 10's Mt is a typical count from the average S_16; the paper multiplies it by a
    // heuristic 4 "to insure that the majority of pixels will converge". Where a few
    // pixels carry heavy tails (cornell's ceiling by the light) the average is far below
    // them, so the ceiling is also made to cover the 90% quantile of the needs.
    let mt_quantile = (quantile(&needs, CEILING_QUANTILE) / CEILING_FACTOR as f64)
        .ceil()
        .clamp(1.0, (u32::MAX / CEILING_FACTOR) as f64) as u32;

    // The gather's bias correction (`rw_bias`) takes its share of a budget.
    let correct = integrator.set.gather == Gather::Radiosity && !params.no_correction;
    let trial_share = if correct {
        1.0 / (1.0 + rw_bias::CORRECTION_COST * rw_bias::CORRECTION_SHARE)
    } else {
        1.0
    };
    // Mt used, and the cap on the total trials.
    let (mt, mut cap_total, deadline) = match budget {
        RwBudget::Convergence => (pilot.mt.max(mt_quantile).max(PILOT_TRIALS), u64::MAX, None),
        RwBudget::Spp(spp) => (
            mt_for_budget(&needs, spp * trial_share),
            (spp * pixels as f64).round() as u64,
            None,
        ),
        RwBudget::Time(secs) => {
            let rate = (pilot_pixels * PILOT_TRIALS as u64) as f64 / pilot_seconds.max(1e-9);
            // keep ~2% for the filter
            let left = (secs * 0.98 - t0.elapsed().as_secs_f64()).max(0.0);
            let spp = rate * left / pixels as f64;
            (
                mt_for_budget(&needs, spp * trial_share),
                u64::MAX,
                Some(secs * 0.98),
            )
        }
    };
    let correction_samples = if correct { rw_bias::samples_for(mt) } else { 0 };
    if cap_total != u64::MAX {
        let cost = rw_bias::CORRECTION_COST * (correction_samples as u64 * pixels as u64) as f64;
        cap_total = cap_total.saturating_sub(cost as u64);
    }
    let pilot_ceiling = mt.saturating_mul(CEILING_FACTOR);
    let mut ceiling = pilot_ceiling;
    let predicted_trials = predicted(&needs, mt as f64);

    // 2. Trials: Mt everywhere, then passes for the pixels not yet converged.
    let mut film = Film::new(set.width, set.height)?;
    let mut vfilm = Film::new(set.width, set.height)?;
    let first = mt.min((cap_total / pixels.max(1) as u64).min(u32::MAX as u64) as u32);
    let first = first.max(1);
    planned += first as u64 * pixels as u64;
    progress.set_total(planned);
    let step = mt.div_ceil(4).max(1);
    let pass = |counts: Counts, first_index: u64, film: &mut Film, vfilm: &mut Film| {
        let p = Pass {
            scene,
            integrator,
            set,
            counts,
            first_index,
            stream: 0,
            progress,
        };
        run(&p, film, vfilm)
    };
    // The correction's samples (their own streams 2 and 3) first, their share of the
    // budget taken out of Mt above: the deadline then trims only the trials. Two
    // independent halves: `rw_bias::correction` weighs each by the other.
    let mut cfilms = [
        Film::new(set.width, set.height)?,
        Film::new(set.width, set.height)?,
    ];
    if correction_samples > 0 {
        let mut corr = integrator.clone();
        corr.set.gather = Gather::Correction;
        planned += correction_samples as u64 * pixels as u64;
        progress.set_total(planned);
        for (k, cfilm) in cfilms.iter_mut().enumerate() {
            counters.add(&render_pass(
                &Pass {
                    scene,
                    integrator: &corr,
                    set,
                    counts: Counts::Uniform(correction_samples.div_ceil(2)),
                    first_index: 0,
                    stream: 2 + k as u32,
                    progress,
                },
                cfilm,
                None,
            ));
        }
    }
    // Mt for every pixel; under a deadline in `FIRST_CHUNKS` passes, the last ones fitted
    // to the time left at the rate measured (the pilot's rate can be off: one pass of Mt
    // ran 18 s past an 80-s budget).
    let t1 = Instant::now();
    let mut done = 0u32; // trials of every pixel still running
    let mut passes = 0u32;
    while done < first && !progress.cancelled() {
        let mut k = match deadline {
            None => first,
            Some(_) => first.div_ceil(FIRST_CHUNKS).min(first - done),
        };
        if let (Some(dl), true) = (deadline, done > 0) {
            let per_trial = t1.elapsed().as_secs_f64() / (done as f64 * pixels as f64);
            let left = dl - t0.elapsed().as_secs_f64();
            let fit = left / (per_trial * pixels as f64).max(1e-12);
            k = k.min(fit.clamp(0.0, u32::MAX as f64) as u32);
            if k == 0 {
                break;
            }
        }
        counters.add(&pass(
            Counts::Uniform(k),
            done as u64,
            &mut film,
            &mut vfilm,
        ));
        done += k;
        passes += 1;
    }
    let first = done;
    let mut trials = vec![first; pixels];
    let mut spent = first as u64 * pixels as u64;
    let (w, h) = (set.width as usize, set.height as usize);
    let conv_map = |film: &Film, vis: &Film| {
        let s_p = test_deviations(film, split.then_some(vis));
        let s = pooled(&s_p, w, h, params.pixel_test);
        let lum = match params.target {
            RwTarget::Linear => Vec::new(),
            RwTarget::Display => {
                let m: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.mean()).collect();
                test_luminance(&m, w, h, params.pixel_test)
            }
        };
        (0..pixels)
            .map(|i| {
                let unit = match params.target {
                    RwTarget::Linear => pilot.lt_vis,
                    t => t.unit(pilot.lt_vis, pilot.l_ave, lum[i]),
                };
                // no pixel stops before it has the pilot's 16 trials: S_p from fewer is
                // too unstable (and too correlated with the mean) to stop on
                film.pixels[i].n >= PILOT_TRIALS
                    && converged(params.t, s[i], film.pixels[i].n, params.d, unit)
            })
            .collect::<Vec<bool>>()
    };
    let is_conv = |film: &Film, i: usize| {
        converged(
            params.t,
            deviation(&film.pixels[i]),
            film.pixels[i].n,
            params.d,
            pilot.lt_vis,
        )
    };
    let first_conv = conv_map(&film, &vfilm);
    let share = |c: &[bool]| c.iter().filter(|&&x| x).count() as f64 / pixels.max(1) as f64;
    // The share converged once the pilot's ceiling 4 Mt is reached (or at the end).
    let mut share_at_pilot_ceiling = (done >= pilot_ceiling).then(|| share(&first_conv));
    // Stein's two-stage procedure (convergence budget only): the first Mt trials of every
    // pixel are a far larger sample than the pilot's 16, so the ceiling is raised to the
    // `STEIN_QUANTILE` of the needs they predict (never lowered below 4 Mt).
    if budget == RwBudget::Convergence && !progress.cancelled() {
        let q = quantile(
            &needs_of(&film, split.then_some(&vfilm), params, &pilot),
            STEIN_QUANTILE,
        );
        let q = q.ceil().clamp(0.0, u32::MAX as f64) as u32;
        ceiling = ceiling.max(q);
    }
    let mut active: Vec<bool> = first_conv.iter().map(|&c| !c).collect();
    // With --time, once every pixel has converged or reached the ceiling, what is left of
    // the time goes to every pixel (more trials never hurt; stopping early wasted 10%).
    let mut extend = false;
    while !progress.cancelled() {
        let mut n_active = active.iter().filter(|&&a| a).count() as u64;
        if done >= ceiling || n_active == 0 {
            if deadline.is_none() {
                break;
            }
            extend = true;
            ceiling = u32::MAX;
            active.iter_mut().for_each(|a| *a = true);
            n_active = pixels as u64;
        }
        // passes land on the pilot's ceiling, so the share there is measured
        let stop = if done < pilot_ceiling {
            pilot_ceiling
        } else {
            ceiling
        };
        let mut k = step.min(stop - done);
        if let Some(dl) = deadline {
            // as many trials as the time left holds, at the rate measured so far
            let left = dl - t0.elapsed().as_secs_f64();
            let per_trial = t1.elapsed().as_secs_f64() / (spent as f64).max(1.0);
            let fit = left / (per_trial * n_active as f64).max(1e-12);
            if fit < 1.0 {
                break;
            }
            k = k.min(fit.min(u32::MAX as f64) as u32);
        }
        if cap_total != u64::MAX {
            let left = cap_total.saturating_sub(spent);
            k = k.min((left / n_active).min(u32::MAX as u64) as u32);
        }
        if k == 0 {
            break;
        }
        let counts: Vec<u32> = active.iter().map(|&a| if a { k } else { 0 }).collect();
        planned += k as u64 * n_active;
        progress.set_total(planned);
        counters.add(&pass(
            Counts::PerPixel(&counts),
            done as u64,
            &mut film,
            &mut vfilm,
        ));
        let conv = conv_map(&film, &vfilm);
        for (i, t) in trials.iter_mut().enumerate() {
            if active[i] {
                *t += k;
                active[i] = extend || !conv[i];
            }
        }
        spent += k as u64 * n_active;
        done += k;
        passes += 1;
        if share_at_pilot_ceiling.is_none() && done >= pilot_ceiling {
            share_at_pilot_ceiling = Some(share(&conv));
        }
    }
    let trials_seconds = t1.elapsed().as_secs_f64();

    // 3. The energy-preserving filter.
    let t2 = Instant::now();
    let ep = EnergyParams {
        d: params.d,
        lt_vis: pilot.lt_vis,
        t: params.t,
    };
    let mut out = if params.no_filter {
        let mean: Vec<[f64; 3]> = film.pixels.iter().map(|p| p.mean()).collect();
        let noise: Vec<bool> = (0..pixels).map(|i| !is_conv(&film, i)).collect();
        let noise_pixels = noise.iter().filter(|&&x| x).count();
        EnergyOutput {
            image: mean,
            spread: vec![false; pixels],
            noise,
            passes: 0,
            noise_pixels,
            spread_pixels: 0,
            untreated: noise_pixels,
            max_gain: 0.0,
        }
    } else {
        energy::energy_filter_film(&film, &ep)?
    };
    // The light seen directly goes back in, unfiltered.
    let vis = split.then_some(&vfilm);
    if let Some(v) = vis {
        for (o, p) in out.image.iter_mut().zip(&v.pixels) {
            let m = p.mean();
            for c in 0..3 {
                o[c] += m[c];
            }
        }
    }
    let mut unfiltered = sum_means(&film, vis);
    let (mut correction_alpha, mut correction_se) = (0.0, 0.0);
    if correction_samples > 0 {
        let corr = rw_bias::correction(&cfilms[0], &cfilms[1]);
        (correction_alpha, correction_se) = (corr.alpha, corr.mean_se);
        for ((o, u), a) in out
            .image
            .iter_mut()
            .zip(unfiltered.iter_mut())
            .zip(&corr.add)
        {
            for c in 0..3 {
                o[c] += a[c];
                u[c] += a[c];
            }
        }
    }
    let filter_seconds = t2.elapsed().as_secs_f64();
    progress.finish();
    let final_conv = conv_map(&film, &vfilm);
    let conv = final_conv.iter().filter(|&&c| c).count();
    let share_at_pilot_ceiling = share_at_pilot_ceiling.unwrap_or_else(|| share(&final_conv));
    let np = pixels.max(1) as f64;
    let stats = RwStats {
        s16: pilot.s16,
        l_ave: pilot.l_ave,
        lt_vis: pilot.lt_vis,
        d: params.d,
        t: params.t,
        mt: pilot.mt,
        mt_ceiling: pilot.mt_ceiling,
        mt_quantile,
        mt_used: mt,
        mt_ceiling_used: ceiling,
        predicted_trials,
        average_trials: trials.iter().map(|&t| t as f64).sum::<f64>() / np,
        passes,
        converged_share: conv as f64 / np,
        converged_share_at_pilot_ceiling: share_at_pilot_ceiling,
        noise_share: out.noise_pixels as f64 / np,
        spread_share: out.spread_pixels as f64 / np,
        filter_passes: out.passes,
        untreated: out.untreated,
        correction_samples,
        correction_alpha,
        correction_se,
        pilot_seconds,
        gather_depth,
        gather_depth_choice: depth_choice
            .as_ref()
            .map(|c| c.line.clone())
            .unwrap_or_default(),
        gather_depth_seconds: depth_choice.as_ref().map_or(0.0, |c| c.seconds),
        trials_seconds,
        filter_seconds,
    };
    Ok(RwRun {
        pilot,
        unfiltered,
        film,
        trials,
        out,
        stats,
        counters,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests;
