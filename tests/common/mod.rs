//! Shared helpers of the integration tests.
#![allow(dead_code)]

use kalos::film::Film;
use kalos::integrator::Integrator;
use kalos::integrator::{IntegratorSettings, Roulette, RrMode};
use kalos::math::Vec3;
use kalos::pipeline::{render, Budget, RenderSettings, Silent};
use kalos::sampling::{SamplerConfig, SamplerKind};
use kalos::scene::{Scene, SceneDesc};
use kalos::spectrum::SpectralMode;

pub fn settings(scene: &Scene, w: u32, h: u32) -> RenderSettings {
    RenderSettings {
        width: w,
        height: h,
        camera: scene.camera,
        spectral: SpectralMode::Rgb,
        sampler: SamplerConfig {
            kind: SamplerKind::Random,
            seed: 1,
            dependent: false,
        },
        integrator: IntegratorSettings {
            roulette: Roulette {
                mode: RrMode::Classic,
                min_depth: Some(0),
                ..Default::default()
            },
            ..Default::default()
        },
    }
}

pub fn render_spp(scene: &Scene, set: &RenderSettings, spp: u32) -> Film {
    let integ = Integrator::prepare(scene, set.integrator, set.spectral.bands(), &Silent).unwrap();
    render(scene, &integ, set, Budget::Spp(spp), 0, &Silent)
        .unwrap()
        .film
}

/// Image mean per channel and its standard error (pixels independent).
pub fn mean_and_se(film: &Film) -> ([f64; 3], [f64; 3]) {
    let p = film.pixels.len() as f64;
    let mut m = [0.0; 3];
    let mut v = [0.0; 3];
    for px in &film.pixels {
        let vm = px.variance_of_mean();
        for c in 0..3 {
            m[c] += px.mean()[c] / p;
            v[c] += vm[c] / (p * p);
        }
    }
    (m, [v[0].sqrt(), v[1].sqrt(), v[2].sqrt()])
}

/// Assert the image mean is `expect` within `k` standard errors in every channel.
pub fn assert_mean(film: &Film, expect: [f64; 3], k: f64, what: &str) {
    let (m, se) = mean_and_se(film);
    for c in 0..3 {
        assert!(
            se[c] > 0.0 || (m[c] - expect[c]).abs() < 1e-6,
            "{what}: zero variance"
        );
        assert!(
            (m[c] - expect[c]).abs() <= k * se[c] + 1e-6,
            "{what}: channel {c} mean {} vs {} (se {}, {:.1} se off)",
            m[c],
            expect[c],
            se[c],
            (m[c] - expect[c]).abs() / se[c]
        );
    }
}

/// The floor [-5, 5]^2 at z = 0, facing +z, of material `mat`.
pub fn push_floor(d: &mut SceneDesc, mat: u32) {
    let c = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let v = [c(-5.0, -5.0), c(5.0, -5.0), c(5.0, 5.0), c(-5.0, 5.0)];
    kalos::scene::builtin::push_quad(d, v, mat);
}
