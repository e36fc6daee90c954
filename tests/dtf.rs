//! Dependent-tests driven filtering through the whole pipeline: asymptotically unbiased
//! (the furnace stays 1; the error keeps falling with the budget), and the budget is spent.

mod common;
use common::*;
use kalos::filter::dtf::DtfParams;
use kalos::integrator::Integrator;
use kalos::pipeline::{render_dtf, DtfBudget, Silent};

#[test]
fn dtf_on_the_furnace_is_one() {
    let scene = kalos::scene::load("furnace").unwrap();
    let set = settings(&scene, 16, 16);
    let params = DtfParams {
        n: Some(16),
        ..Default::default()
    };
    let run = render_dtf(
        &scene,
        &Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap(),
        &set,
        &params,
        DtfBudget::Spp(400.0),
        &Silent,
    )
    .unwrap();
    // the displayed image: every channel of every pixel near 1, the mean very near 1
    let img = &run.out.combined;
    let mean = img.mean();
    for c in 0..3 {
        assert!((mean[c] - 1.0).abs() < 0.03, "mean {mean:?}");
    }
    // and pixel by pixel only noise: the RMS deviation from 1 is small
    let rms = (img
        .data
        .iter()
        .flat_map(|p| p.iter())
        .map(|v| ((v - 1.0) as f64).powi(2))
        .sum::<f64>()
        / (3 * img.data.len()) as f64)
        .sqrt();
    // measured 0.037 (n = 16, 400 spp, 16x16)
    assert!(rms < 0.05, "RMS deviation from 1 is {rms}");
}

#[test]
fn budget_mode_spends_the_budget() {
    let scene = kalos::scene::load("cornell").unwrap();
    let set = settings(&scene, 32, 32);
    let params = DtfParams {
        n: Some(8),
        ..Default::default()
    };
    let run = render_dtf(
        &scene,
        &Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap(),
        &set,
        &params,
        DtfBudget::Spp(40.0),
        &Silent,
    )
    .unwrap();
    let pixels = 32.0 * 32.0;
    let phase2 = run.independent.total_samples() as f64 / pixels;
    assert_eq!(run.dependent.total_samples() as f64 / pixels, 8.0);
    assert!(
        (phase2 - 32.0).abs() / 32.0 < 0.05,
        "phase 2 averaged {phase2} spp instead of 32"
    );
    // N[p] counts every independent sample, top-ups included
    let n_sum: u64 = run.alloc.iter().map(|&n| n as u64).sum();
    assert_eq!(n_sum, run.independent.total_samples());
    // and N varies across the image (the allocation is adaptive)
    let (lo, hi) = (
        run.alloc.iter().min().unwrap(),
        run.alloc.iter().max().unwrap(),
    );
    assert!(hi > lo);
}

#[test]
fn dtf_error_keeps_falling_with_the_budget() {
    // No bias floor: against a high-spp plain render, DTF's error falls as the budget grows.
    let scene = kalos::scene::load("cornell").unwrap();
    let set = settings(&scene, 48, 48);
    let reference = render_spp(&scene, &set, 4096).mean_rgb();
    let params = DtfParams {
        n: Some(16),
        ..Default::default()
    };
    let mut last = f64::INFINITY;
    let mut errs = Vec::new();
    for budget in [32.0, 128.0, 512.0] {
        let run = render_dtf(
            &scene,
            &Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap(),
            &set,
            &params,
            DtfBudget::Spp(budget),
            &Silent,
        )
        .unwrap();
        let mse: f64 = run
            .out
            .combined
            .data
            .iter()
            .zip(reference.iter())
            .map(|(a, b)| (0..3).map(|c| ((a[c] - b[c]) as f64).powi(2)).sum::<f64>())
            .sum::<f64>()
            / (3.0 * reference.len() as f64);
        errs.push(mse.sqrt());
        assert!(mse.sqrt() < last, "RMSE does not keep falling: {errs:?}");
        last = mse.sqrt();
    }
    // and by a real factor over the 16x larger budget
    assert!(errs[2] < 0.75 * errs[0], "{errs:?}");
}

#[test]
fn per_pixel_ray_counts_add_up_to_the_render_counters() {
    use kalos::film::Film;
    use kalos::pipeline::{render_pass, Counts, Pass};
    let scene = kalos::scene::load("cornell").unwrap();
    let set = settings(&scene, 16, 16);
    let mut film = Film::new(16, 16).unwrap();
    let mut rays = vec![0u64; 256];
    let integrator =
        Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap();
    let pass = Pass {
        scene: &scene,
        integrator: &integrator,
        set: &set,
        counts: Counts::Uniform(4),
        first_index: 0,
        stream: 0,
        progress: &Silent,
    };
    let c = render_pass(&pass, &mut film, Some(&mut rays));
    assert_eq!(rays.iter().sum::<u64>(), c.rays);
    // every pixel traced at least its 4 camera rays
    assert!(rays.iter().all(|&r| r >= 4));
}

/// With eps_r the work is unknown until phase 1 has run: then a line says what phase 2
/// will cost, and the progress total is phase 1's samples plus that.
#[test]
fn relative_error_mode_says_its_predicted_work_after_phase_1() {
    use kalos::progress::Progress;
    use std::sync::Mutex;
    #[derive(Default)]
    struct Record {
        messages: Mutex<Vec<String>>,
        totals: Mutex<Vec<u64>>,
    }
    impl Progress for Record {
        fn set_total(&self, total: u64) {
            self.totals.lock().unwrap().push(total);
        }
        fn message(&self, text: &str) {
            self.messages.lock().unwrap().push(text.to_string());
        }
    }
    let scene = kalos::scene::load("cornell").unwrap();
    let set = settings(&scene, 8, 8);
    let params = DtfParams {
        n: Some(8),
        eps_r: Some(0.5),
        top_up_rounds: 0,
        ..Default::default()
    };
    let rec = Record::default();
    let run = render_dtf(
        &scene,
        &Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap(),
        &set,
        &params,
        DtfBudget::RelativeError,
        &rec,
    )
    .unwrap();
    let messages = rec.messages.lock().unwrap();
    let line = messages
        .iter()
        .find(|m| m.contains("asks for"))
        .unwrap_or_else(|| panic!("no predicted-work line in {messages:?}"));
    // phase 2's samples as the line states them are the samples that were taken
    let phase2: u64 = run.independent.pixels.iter().map(|p| p.n as u64).sum();
    assert!(
        line.contains(&format!("asks for {phase2} more samples")),
        "{line} (phase 2 took {phase2})"
    );
    assert_eq!(rec.totals.lock().unwrap().last(), Some(&(64 * 8 + phase2)));
}
