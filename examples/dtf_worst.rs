//! Diagnostic: the pixels where DTF's image differs most from a reference, with N, C_d,
//! the filtered C_i and the region size. `cargo run --release --example dtf_worst -- REF.exr EPS`
use kalos::filter::dtf::DtfParams;
use kalos::integrator::IntegratorSettings;
use kalos::pipeline::*;
use kalos::sampling::*;
use kalos::spectrum::SpectralMode;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let reference = kalos::image_io::read_image(std::path::Path::new(&a[1])).unwrap();
    let eps: f32 = a[2].parse().unwrap();
    let scene = kalos::scene::load("cornell").unwrap();
    let set = RenderSettings {
        width: reference.width,
        height: reference.height,
        camera: scene.camera,
        spectral: SpectralMode::Rgb,
        sampler: SamplerConfig {
            kind: SamplerKind::Random,
            seed: 0,
            dependent: false,
        },
        integrator: IntegratorSettings::default(),
    };
    let integ = kalos::integrator::Integrator::prepare(
        &scene,
        set.integrator,
        set.spectral.bands(),
        &Silent,
    )
    .unwrap();
    let p = DtfParams {
        n: Some(32),
        eps_r: Some(eps),
        ..Default::default()
    };
    let run = render_dtf(&scene, &integ, &set, &p, DtfBudget::RelativeError, &Silent).unwrap();
    let mut e: Vec<(f64, usize)> = (0..reference.data.len())
        .map(|i| {
            let (x, r) = (run.out.combined.data[i], reference.data[i]);
            (
                (0..3).map(|c| ((x[c] - r[c]) as f64).powi(2)).sum::<f64>(),
                i,
            )
        })
        .collect();
    e.sort_by(|a, b| b.0.total_cmp(&a.0));
    let total: f64 = e.iter().map(|v| v.0).sum();
    for &(err, i) in e.iter().take(8) {
        let d = &run.dependent.pixels[i];
        println!(
            "px ({},{}) share {:.2} N {} nind {} M {} Cd {:?} Ci {:?} comb {:?} ref {:?}",
            i % 32,
            i / 32,
            err / total,
            run.alloc[i],
            run.independent.pixels[i].n,
            run.out.region[i],
            d.mean_f32(),
            run.independent.pixels[i].mean_f32(),
            run.out.combined.data[i],
            reference.data[i]
        );
    }
}
