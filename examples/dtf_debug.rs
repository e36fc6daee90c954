use kalos::filter::dtf::DtfParams;
use kalos::integrator::*;
use kalos::pipeline::*;
use kalos::sampling::*;
use kalos::spectrum::SpectralMode;
fn rmse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| ((x[c] - y[c]) as f64).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (3.0 * a.len() as f64))
        .sqrt()
}
fn main() {
    let scene = kalos::scene::load("cornell").unwrap();
    let set = RenderSettings {
        width: 48,
        height: 48,
        camera: scene.camera,
        spectral: SpectralMode::Rgb,
        sampler: SamplerConfig {
            kind: SamplerKind::Random,
            seed: 1,
            dependent: false,
        },
        integrator: IntegratorSettings::default(),
    };
    let reference = render(&scene, &set, Budget::Spp(4096), None)
        .unwrap()
        .film
        .mean_rgb();
    for n in [16u32] {
        let params = DtfParams {
            n,
            ..Default::default()
        };
        for budget in [32.0, 128.0, 512.0] {
            let run = render_dtf(&scene, &set, &params, DtfBudget::Spp(budget), None).unwrap();
            let plain = render(&scene, &set, Budget::Spp(budget as u32), None)
                .unwrap()
                .film
                .mean_rgb();
            let avg_m: f64 = run.out.region.iter().map(|&m| m as f64).sum::<f64>() / 2304.0;
            println!("budget {budget}: plain {:.4} dep {:.4} indep {:.4} filtered {:.4} combined {:.4}  avgN {:.1} avgM {:.2} maxN {}",
                rmse(&plain, &reference), rmse(&run.dependent.mean_rgb(), &reference), rmse(&run.independent.mean_rgb(), &reference),
                rmse(&run.out.filtered.data, &reference), rmse(&run.out.combined.data, &reference), run.average_n(), avg_m, run.alloc.iter().max().unwrap());
        }
    }
}
