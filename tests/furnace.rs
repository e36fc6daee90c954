//! Known answer: in the furnace rooms (`furnace`: diffuse walls with albedo + emission = 1
//! on every band; `furnace-glossy`: diffuse + Phong walls emitting 1 - a(w)) the radiance is
//! exactly 1 in every pixel and channel, for every correct estimator: every roulette, every
//! lobe selection, every spectral mode, every sampler.

mod common;
use common::*;
use kalos::film::Film;
use kalos::integrator::{BsdfSelect, RrEstimate, RrMode, RrWeight};
use kalos::options::name as opt;
use kalos::pipeline::RenderSettings;
use kalos::sampling::SamplerKind;
use kalos::scene::Scene;
use kalos::spectrum::SpectralMode;

/// Share of pixels whose every channel is within 3 standard errors of 1.
fn share_within_3se(film: &Film) -> f64 {
    let inside = film
        .pixels
        .iter()
        .filter(|px| {
            let vm = px.variance_of_mean();
            (0..3).all(|c| (px.mean()[c] - 1.0).abs() <= 3.0 * vm[c].sqrt() + 1e-6)
        })
        .count();
    inside as f64 / film.pixels.len() as f64
}

/// Image mean within 3 standard errors of 1 in every channel, nearly all pixels too,
/// nothing rejected.
fn furnace_check(film: &Film) -> Result<(), String> {
    let (m, se) = mean_and_se(film);
    for c in 0..3 {
        if (m[c] - 1.0).abs() > 3.0 * se[c] + 1e-6 {
            return Err(format!(
                "channel {c} mean {} ({:.1} se off)",
                m[c],
                (m[c] - 1.0).abs() / se[c]
            ));
        }
    }
    // pixel by pixel: roulette weights are heavy-tailed, so this needs a few hundred
    // samples per pixel to be meaningful (walks without roulette are not: they get fewer)
    let share = share_within_3se(film);
    if share <= 0.9 {
        return Err(format!("only {share:.3} of pixels within 3 se"));
    }
    if film.rejected.total() != 0 {
        return Err(format!("{} samples rejected", film.rejected.total()));
    }
    Ok(())
}

/// The furnace answer, as a two-stage test. The whole family is some 700 checks at 3 standard
/// errors, so a few false alarms are expected by design; a failing combination is rendered
/// again with a new seed and 4x the samples and must pass then. A biased estimator fails
/// both stages (with 4x the samples the standard error halves, so a bias stands out more).
fn assert_furnace(scene: &Scene, set: &RenderSettings, spp: u32, what: &str) {
    let film = render_spp(scene, set, spp);
    if let Err(first) = furnace_check(&film) {
        let mut again = *set;
        again.sampler.seed += 1000;
        let film = render_spp(scene, &again, 4 * spp);
        if let Err(second) = furnace_check(&film) {
            panic!("{what}: {first}; again with a new seed and 4x spp: {second}");
        }
    }
}

/// Every --rr x --rr-weight x --bsdf-select x --spectral x sampler on one scene.
fn every_combination(scene: &Scene, name: &str, selects: &[BsdfSelect]) {
    for spectral in [
        SpectralMode::Rgb,
        SpectralMode::Bands8,
        SpectralMode::Bands16,
    ] {
        for kind in [SamplerKind::Random, SamplerKind::Sobol] {
            for &select in selects {
                for (rr, weight) in <RrMode as clap::ValueEnum>::value_variants()
                    .iter()
                    .copied()
                    .flat_map(|m| [(m, RrWeight::Luminance), (m, RrWeight::Flat)])
                    // h does not enter walks without roulette
                    .filter(|&(m, w)| m != RrMode::Off || w == RrWeight::Luminance)
                {
                    let mut set = settings(scene, 8, 8);
                    set.spectral = spectral;
                    set.sampler.kind = kind;
                    set.integrator.roulette.mode = rr;
                    set.integrator.roulette.weight = weight;
                    set.integrator.roulette.select = select;
                    // Walks without roulette run to f32 underflow (hundreds of reflections)
                    // but carry no roulette noise: fewer samples test them as well.
                    let spp = if rr == RrMode::Off { 64 } else { 256 };
                    let what = format!(
                        "{name} {spectral:?} {kind:?} --rr {} --rr-weight {} --bsdf-select {}",
                        opt(&rr),
                        opt(&weight),
                        opt(&select)
                    );
                    assert_furnace(scene, &set, spp, &what);
                }
            }
        }
    }
}

#[test]
fn furnace_is_one_for_every_roulette_and_selection() {
    let scene = kalos::scene::load("furnace").unwrap();
    every_combination(
        &scene,
        "furnace",
        <BsdfSelect as clap::ValueEnum>::value_variants(),
    );
}

#[test]
fn furnace_glossy_is_one_for_every_roulette_and_selection() {
    let scene = kalos::scene::load("furnace-glossy").unwrap();
    // Method 2 (static) is tested below on a room where its variance is finite.
    every_combination(
        &scene,
        "furnace-glossy",
        &[BsdfSelect::Mixture, BsdfSelect::Decompose, BsdfSelect::Mis],
    );
}

#[test]
fn furnace_glossy_is_one_with_static_selection() {
    // Method 2 weighs a direction the Phong lobe sampled by w / p_glossy, and w keeps the
    // diffuse part where p_glossy ~ cos^n vanishes at the rim of the lobe: the weights
    // have a tail of index 1 + 1/n, so with the room's exponents (3 to 60) any affordable
    // sample is short of the tail's share and the estimate falls a few percent short.
    // The method is unbiased all the same; with n = 1 the tail has index 2 and the
    // furnace test can see it.
    let mut desc = kalos::scene::load_desc("furnace-glossy").unwrap();
    for m in desc.materials.iter_mut() {
        m.ns = 1.0;
    }
    let scene = Scene::build(desc, 0.0).unwrap();
    every_combination(&scene, "furnace-glossy n=1", &[BsdfSelect::Static]);
}

#[test]
fn furnace_is_one_with_l_tilde_from_radiosity() {
    // --rr-estimate radiosity: L~ read from a (coarse) radiosity solution at each hit
    let scene = kalos::scene::load("furnace").unwrap();
    for spectral in [SpectralMode::Rgb, SpectralMode::Bands8] {
        for rr in [RrMode::Estimate, RrMode::SpectralEstimate] {
            let mut set = settings(&scene, 8, 8);
            set.spectral = spectral;
            set.integrator.roulette.mode = rr;
            set.integrator.roulette.estimate = RrEstimate::Radiosity;
            set.integrator.radiosity.max_area = Some(0.5);
            set.integrator.radiosity.source_level = 0;
            set.integrator.radiosity.tolerance = 1e-2;
            let what = format!(
                "furnace {spectral:?} --rr {} --rr-estimate radiosity",
                opt(&rr)
            );
            assert_furnace(&scene, &set, 256, &what);
        }
    }
}

#[test]
#[allow(clippy::needless_range_loop)]
fn furnace_with_dependent_tests_is_one() {
    // Dependent tests: pixels share random numbers, so test each pixel on its own.
    let scene = kalos::scene::load("furnace").unwrap();
    let mut set = settings(&scene, 8, 8);
    set.sampler.dependent = true;
    let film = render_spp(&scene, &set, 1024);
    let mut inside = 0;
    for px in &film.pixels {
        let vm = px.variance_of_mean();
        if (0..3).all(|c| (px.mean()[c] - 1.0).abs() <= 3.0 * vm[c].sqrt()) {
            inside += 1;
        }
        for c in 0..3 {
            assert!((px.mean()[c] - 1.0).abs() <= 4.0 * vm[c].sqrt(), "{px:?}");
        }
    }
    assert!(
        inside as f64 / film.pixels.len() as f64 > 0.9,
        "{inside} of 64 within 3 se"
    );
}

#[test]
fn a_biased_estimator_fails_the_furnace() {
    // The test must be able to fail: cutting paths at 3 segments loses energy.
    let scene = kalos::scene::load("furnace").unwrap();
    let mut set = settings(&scene, 12, 12);
    set.integrator.max_depth = 3;
    let film = render_spp(&scene, &set, 32);
    let (m, _) = mean_and_se(&film);
    assert!(m[0] < 0.9, "{m:?}");
}
