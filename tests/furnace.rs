//! Known answer: in the furnace room (albedo + emission = 1 on every band) the radiance is
//! exactly 1 in every pixel and channel, for every correct estimator, in every spectral
//! mode, with every sampler, with roulette on and off.

mod common;
use common::*;
use kalos::integrator::RrMode;
use kalos::sampling::SamplerKind;
use kalos::spectrum::SpectralMode;

#[test]
fn furnace_is_one_everywhere() {
    let scene = kalos::scene::load("furnace").unwrap();
    for spectral in [
        SpectralMode::Rgb,
        SpectralMode::Bands8,
        SpectralMode::Bands16,
    ] {
        for kind in [SamplerKind::Random, SamplerKind::Sobol] {
            for rr in [RrMode::Classic, RrMode::Off] {
                let mut set = settings(&scene, 8, 8);
                set.spectral = spectral;
                set.sampler.kind = kind;
                set.integrator.roulette.mode = rr;
                let film = render_spp(&scene, &set, 256);
                let what = format!("furnace {spectral:?} {kind:?} rr {rr:?}");
                assert_mean(&film, [1.0; 3], 3.0, &what);
                // and pixel by pixel: nearly all within 3 standard errors (roulette weights
                // are heavy-tailed, so this needs a few hundred samples to be meaningful)
                let mut inside = 0;
                for px in &film.pixels {
                    let vm = px.variance_of_mean();
                    if (0..3).all(|c| (px.mean[c] - 1.0).abs() <= 3.0 * vm[c].sqrt() + 1e-6) {
                        inside += 1;
                    }
                }
                let share = inside as f64 / film.pixels.len() as f64;
                assert!(share > 0.9, "{what}: only {share:.3} of pixels within 3 se");
                assert_eq!(film.rejected.total(), 0);
            }
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
        if (0..3).all(|c| (px.mean[c] - 1.0).abs() <= 3.0 * vm[c].sqrt()) {
            inside += 1;
        }
        for c in 0..3 {
            assert!((px.mean[c] - 1.0).abs() <= 5.0 * vm[c].sqrt(), "{px:?}");
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
