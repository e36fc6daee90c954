//! Tests of Rushmeier and Ward's pipeline (`pipeline::rw`).

use super::*;
use crate::render::{render_scene, Method, RenderJob};

fn job(scene: &str, res: u32, d: f64) -> RenderJob {
    let mut j = RenderJob::new(scene);
    j.method = Method::Rw;
    j.res = Some((res, res));
    j.rw.d = d;
    j
}

fn lum_mean(img: &[[f64; 3]]) -> f64 {
    img.iter().map(|&c| energy::luminance(c)).sum::<f64>() / img.len() as f64
}

/// Standard deviation of the image's mean luminance from the film (sum_p S_p^2 / M_p).
fn sigma_of_mean(film: &Film) -> f64 {
    let n = film.pixels.len() as f64;
    film.pixels
        .iter()
        .map(|p| deviation(p).powi(2) / p.n.max(1) as f64)
        .sum::<f64>()
        .sqrt()
        / n
}

/// On the furnace every pixel is 1: the method's image (filtered) stays 1 within
/// noise, and the filter does not move energy (filtered and unfiltered means agree).
#[test]
fn furnace_stays_one() {
    let scene = crate::scene::load("furnace").unwrap();
    let mut j = job("furnace", 32, 5.0);
    j.rw.pilot_res = 32;
    let r = render_scene(&scene, &j, &crate::progress::Silent).unwrap();
    let run = r.rw.as_ref().unwrap();
    let unf = run.unfiltered.clone();
    let (lf, lu) = (lum_mean(&run.out.image), lum_mean(&unf));
    // the trials' noise and the correction's (a few samples per pixel, taken whole)
    let sigma = sigma_of_mean(&run.film).hypot(run.stats.correction_se);
    eprintln!(
        "furnace rw: filtered {lf:.6}, unfiltered {lu:.6}, sigma {sigma:.2e}, stats {:?}",
        run.stats
    );
    assert!(
        (lf - 1.0).abs() <= 4.0 * sigma + 1e-6,
        "furnace: {lf} not 1 (sigma {sigma})"
    );
    assert!(
        (lf - lu).abs() <= 1e-9 * lu,
        "the filter moved energy: {lf} vs {lu}"
    );
    assert!(r.stats.rw.is_some());
}

/// The pilot predicts: at Mt_ceiling at least 90% of pixels have converged (the
/// paper's claim), on cornell and rw-room at the pilot's own resolution. Measured
/// (pooled 3x3 stopping test, light seen directly kept apart): rw-room 0.994 at D 20;
/// cornell at D 5 without the gather 0.55 with Eq. 10 alone, 0.795 at the pilot's
/// ceiling once Mt also covers the 90% quantile of the pilot's needs (Mt 386 where
/// Eq. 10 gives 185), 0.833 after Stein's second stage raised the ceiling to the 90%
/// quantile of the needs its first Mt trials predict (1838), 0.886 at their 95%
/// quantile and 0.902 at the 97% (`STEIN_QUANTILE`, ceiling 2707); with `--gather
/// radiosity` (tested here, the method as the tables of docs/results/rushmeier-ward.md run it) 0.883 at 4 Mt and
/// 0.949 at the second stage's ceiling (311, where the 90% quantile gave 212, for 7%
/// more trials on average). The pixels that need the most are the back wall's top and
/// the walls above the tall box (`--rw-layers`): median luminance 2.3-2.5x the others',
/// variance 9-11x, nearly all of it indirect light (direct light alone, `--max-depth
/// 2`, under 4%; next-event estimation uniform in the light's solid angle, tried
/// and not kept, changed nothing). The absolute test needs (t S_p / (D
/// Lt_vis))^2 trials, more than 4 Mt wherever S_p is over twice the pilot's mean S:
/// the paper's 4 Mt alone does not cover cornell's brightness range.
fn converged_share(job: RenderJob) -> f64 {
    let s = crate::scene::load(&job.scene).unwrap();
    let r = render_scene(&s, &job, &crate::progress::Silent).unwrap();
    let st = r.stats.rw.unwrap();
    eprintln!(
        "{}: converged share {:.4} at Mt_ceiling {} ({:.4} at the pilot's 4 Mt; Mt {}, Eq. 10 {}, quantile {}, trials {:.1}, predicted {:.1})",
        job.scene,
        st.converged_share,
        st.mt_ceiling_used,
        st.converged_share_at_pilot_ceiling,
        st.mt_used,
        st.mt,
        st.mt_quantile,
        st.average_trials,
        st.predicted_trials
    );
    st.converged_share
}

#[test]
fn pilot_predicts_convergence_on_rw_room() {
    assert!(converged_share(job("rw-room", 100, 20.0)) >= 0.9);
}

#[test]
fn pilot_predicts_convergence_on_cornell() {
    let mut j = job("cornell", 100, 5.0);
    j.gather = Some(crate::integrator::Gather::Radiosity);
    j.radiosity.source_level = 0;
    assert!(converged_share(j) >= 0.9);
}

/// Early stopping on a variance estimate: a pixel that has not yet met its rare bright
/// paths looks converged and stops low. Measured as the image mean of rw without the
/// filter over 8 seeds against plain path tracing with many samples; the standard
/// error is the seeds' spread (one run's S_p underestimates it where tails are heavy).
/// Measured at 24x24, D 10, 10 seeds (docs/results/rushmeier-ward.md): the paper's per-pixel test
/// (`--rw-pixel-test`) is 1.6% low on cornell (z -5.0), the default pooled test
/// 0.26% (z -0.8).
fn early_stopping_z(scene: &str, pixel_test: bool, target: RwTarget) -> f64 {
    let s = crate::scene::load(scene).unwrap();
    let lum = |r: &crate::render::Rendered| {
        let m = r.image.mean();
        energy::luminance(m)
    };
    let mut p = RenderJob::new(scene);
    p.res = Some((24, 24));
    p.spp = Some(4096);
    p.seed = 1000;
    let rp = render_scene(&s, &p, &crate::progress::Silent).unwrap();
    let (m_ref, s_ref) = (lum(&rp), sigma_of_mean(&rp.film));
    let runs: Vec<f64> = (0..8)
        .map(|seed| {
            let mut j = job(scene, 24, 10.0);
            j.rw.no_filter = true;
            j.rw.pilot_res = 50;
            j.rw.pixel_test = pixel_test;
            j.rw.target = target;
            j.seed = seed;
            lum(&render_scene(&s, &j, &crate::progress::Silent).unwrap())
        })
        .collect();
    let n = runs.len() as f64;
    let m_rw = runs.iter().sum::<f64>() / n;
    let var = runs.iter().map(|x| (x - m_rw).powi(2)).sum::<f64>() / (n - 1.0);
    let s_rw = (var / n).sqrt();
    let z = (m_rw - m_ref) / (s_rw * s_rw + s_ref * s_ref).sqrt();
    eprintln!(
        "{scene} (pixel test {pixel_test}, target {target:?}): rw unfiltered {m_rw:.6} +- {s_rw:.2e} over 8 seeds, plain 4096 spp {m_ref:.6} +- {s_ref:.2e}: z = {z:.2}, relative {:+.4}",
        m_rw / m_ref - 1.0
    );
    z
}

#[test]
fn early_stopping_bias_is_within_noise() {
    // the display target reads the pooled mean, which correlates with the pixel's
    // own: it is checked as well
    for (scene, target) in [
        ("cornell", RwTarget::Linear),
        ("rw-room", RwTarget::Linear),
        ("cornell", RwTarget::Display),
    ] {
        let z = early_stopping_z(scene, false, target);
        assert!(
            z.abs() < 4.0,
            "{scene} ({target:?}): early stopping biases the mean: z = {z}"
        );
    }
}

/// The paper's per-pixel stopping test, kept as the measurement of its bias.
#[test]
#[ignore = "measured: the per-pixel test biases cornell's mean by -1.6% (z -5.0 over 10 seeds)"]
fn per_pixel_stopping_is_biased_on_cornell() {
    let z = early_stopping_z("cornell", true, RwTarget::Linear);
    assert!(
        z.abs() < 4.0,
        "cornell: per-pixel stopping biases the mean: z = {z}"
    );
}

/// The display unit is 1 / T'(L) of T(L) = N_MID (L / L_ave)^(1/2.2) (a central
/// difference of T), gamma Lt_vis at L_ave, and Lt_vis for the paper's linear T.
#[test]
fn display_unit_is_the_inverse_slope_of_the_tone_curve() {
    let l_ave = 0.4;
    let lt = energy::lt_vis(l_ave);
    let t = |l: f64| energy::N_MID * (l / l_ave).powf(1.0 / DISPLAY_GAMMA);
    for l in [0.01, 0.1, 0.4, 2.0, 30.0] {
        let h = l * 1e-5;
        let slope = (t(l + h) - t(l - h)) / (2.0 * h);
        let u = RwTarget::Display.unit(lt, l_ave, l);
        assert!(
            (u * slope - 1.0).abs() < 1e-6,
            "L {l}: unit {u}, 1/T' {}",
            1.0 / slope
        );
        assert_eq!(RwTarget::Linear.unit(lt, l_ave, l), lt);
    }
    let at_ave = RwTarget::Display.unit(lt, l_ave, l_ave);
    assert!((at_ave / lt - DISPLAY_GAMMA).abs() < 1e-12);
    // a black pixel is held to the unit at one display unit's luminance, not to 0
    assert!(RwTarget::Display.unit(lt, l_ave, 0.0) > 0.0);
    assert_eq!(quantile(&[3.0, 1.0, 2.0, 4.0], 0.5), 2.0);
    assert_eq!(quantile(&[3.0, 1.0, 2.0, 4.0], 0.9), 4.0);
    assert_eq!(quantile(&[], 0.9), 0.0);
}

#[test]
fn bad_d_and_t_are_refused() {
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let p = RwParams {
            d,
            ..Default::default()
        };
        let e = p.validate().unwrap_err();
        assert!(e.starts_with("--rw-d") && !e.contains('\n'), "{e}");
    }
    let p = RwParams {
        t: 0.0,
        ..Default::default()
    };
    assert!(p.validate().unwrap_err().starts_with("--rw-t"));
    assert_eq!(RwParams::default().d, energy::DEFAULT_D);
    assert_eq!(RwParams::default().t, energy::DEFAULT_T);
}

/// With --spp the average spend matches the budget and never exceeds it.
#[test]
fn spp_budget_is_kept() {
    let s = crate::scene::load("cornell").unwrap();
    let mut j = job("cornell", 24, 5.0);
    j.rw.pilot_res = 50;
    j.spp = Some(40);
    let r = render_scene(&s, &j, &crate::progress::Silent).unwrap();
    let st = r.stats.rw.unwrap();
    eprintln!(
        "cornell --spp 40: {:.2} trials, Mt {} (Eq. 10: {})",
        st.average_trials, st.mt_used, st.mt
    );
    assert!(st.average_trials <= 40.0 + 1e-9);
    assert!(st.average_trials >= 30.0, "{}", st.average_trials);
}
