//! Diagnostic for DTF over BDPT's light paths of their own (`--dtf-light`): plain BDPT and
//! DTF variants at one spp budget against a reference, with each run's seconds and its
//! error split between the pixels that hold most of plain BDPT's squared error (the top 1%,
//! on `caustic` the caustic and its reflection) and the rest.
//! `cargo run --release --example dtf_light -- SCENE REF.exr SPP SEED [SHARE ...]`
//! (SHARE: `off`, `auto` or a number for --dtf-light-share; default: off auto 0 0.2 0.4).
use kalos::filter::dtf::{DtfParams, LightMode};
use kalos::image_io::RgbImage;
use kalos::integrator::IntegratorKind;
use kalos::metrics::{perceptual_error, rmse};
use kalos::pipeline::*;
use kalos::render::RenderJob;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = kalos::scene::load(&a[1]).unwrap();
    let reference = kalos::image_io::read_image(std::path::Path::new(&a[2])).unwrap();
    let spp: u32 = a[3].parse().unwrap();
    let seed: u64 = a[4].parse().unwrap();
    let variants: Vec<String> = if a.len() > 5 {
        a[5..].to_vec()
    } else {
        ["off", "auto", "0", "0.2", "0.4"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    };
    let mut job = RenderJob::new(&a[1]);
    job.res = Some((reference.width, reference.height));
    job.seed = seed;
    job.integrator = Some(IntegratorKind::Bdpt);
    let set = job.settings(&scene);
    let integ = kalos::integrator::Integrator::prepare(
        &scene,
        set.integrator,
        set.spectral.bands(),
        &Silent,
    )
    .unwrap();
    let t = std::time::Instant::now();
    let plain = render(&scene, &integ, &set, Budget::Spp(spp), 0, &Silent).unwrap();
    let plain_s = t.elapsed().as_secs_f64();
    let plain_img = RgbImage::new(plain.film.width, plain.film.height, plain.film.mean_rgb());
    let se = |im: &RgbImage| -> Vec<f64> {
        im.data
            .iter()
            .zip(&reference.data)
            .map(|(x, r)| (0..3).map(|c| ((x[c] - r[c]) as f64).powi(2)).sum::<f64>() / 3.0)
            .collect()
    };
    let e0 = se(&plain_img);
    let mut order: Vec<usize> = (0..e0.len()).collect();
    order.sort_by(|&i, &j| e0[j].total_cmp(&e0[i]));
    // the bright pixels (reference colour sum > 3: the caustic, its reflection, the light),
    // or with DTF_LIGHT_TOP=1 the 1% of pixels with most of plain's squared error
    let mut top: Vec<bool> = reference
        .data
        .iter()
        .map(|r| r[0] + r[1] + r[2] > 3.0)
        .collect();
    if std::env::var("DTF_LIGHT_TOP").is_ok() {
        top.iter_mut().for_each(|t| *t = false);
        for &i in &order[..e0.len() / 100] {
            top[i] = true;
        }
    }
    println!(
        "{} bright pixels of {}",
        top.iter().filter(|&&t| t).count(),
        top.len()
    );
    let report = |name: &str, im: &RgbImage, secs: f64, extra: String| {
        let e = se(im);
        let (mut st, mut sr) = (0.0, 0.0);
        for (i, &v) in e.iter().enumerate() {
            if top[i] {
                st += v
            } else {
                sr += v
            }
        }
        let n = e.len() as f64;
        let mean = |im: &RgbImage| {
            im.data
                .iter()
                .map(|c| (c[0] + c[1] + c[2]) as f64)
                .sum::<f64>()
        };
        println!(
            "{name:<10} {secs:6.2} s  mean {:.4}  rmse {:.5}  perc {:.4}  mse bright {:.3e} rest {:.3e}  {extra}",
            mean(im) / mean(&reference),
            rmse(im, &reference).unwrap(),
            perceptual_error(im, &reference).unwrap().1,
            st / n,
            sr / n,
        );
    };
    // DTF_LIGHT_DUMP=DIR: 3 x |error| of each image as PNG there (error maps to look at)
    let dump = std::env::var("DTF_LIGHT_DUMP")
        .ok()
        .map(std::path::PathBuf::from);
    let save = |name: &str, im: &RgbImage| {
        if let Some(d) = &dump {
            std::fs::create_dir_all(d).unwrap();
            let e = RgbImage::new(
                im.width,
                im.height,
                im.data
                    .iter()
                    .zip(&reference.data)
                    .map(|(x, r)| std::array::from_fn(|c| 3.0 * (x[c] - r[c]).abs()))
                    .collect(),
            );
            kalos::image_io::write_image(&d.join(format!("err-{name}.png")), &e, 0.0, &[]).unwrap();
            kalos::image_io::write_image(&d.join(format!("{name}.png")), im, 0.0, &[]).unwrap();
            // pixels more than 5% off, 4x: white; the reference dimmed behind them
            let (w, h) = (im.width as usize, im.height as usize);
            let norm = |c: [f32; 3]| (c[0].abs() + c[1].abs() + c[2].abs()) as f64;
            let mean_n = reference.data.iter().map(|&c| norm(c)).sum::<f64>() / (w * h) as f64;
            let mut big = vec![[0.0f32; 3]; 16 * w * h];
            for y in 0..4 * h {
                for x in 0..4 * w {
                    let i = (y / 4) * w + x / 4;
                    let (a, r) = (im.data[i], reference.data[i]);
                    let off = norm([a[0] - r[0], a[1] - r[1], a[2] - r[2]])
                        > 0.05 * norm(r).max(0.01 * mean_n);
                    big[y * 4 * w + x] = if off { [1.0; 3] } else { r.map(|v| 0.3 * v) };
                }
            }
            let b = RgbImage::new(4 * im.width, 4 * im.height, big);
            kalos::image_io::write_image(&d.join(format!("off-{name}.png")), &b, 0.0, &[]).unwrap();
        }
    };
    save("ref", &reference);
    save("plain", &plain_img);
    report("plain", &plain_img, plain_s, String::new());
    for v in &variants {
        let mut p = DtfParams::default();
        // VARIANT[/CD]: --dtf-cd's mode after a slash
        let (v, cd) = v.split_once('/').unwrap_or((v.as_str(), ""));
        if !cd.is_empty() {
            use clap::ValueEnum;
            p.cd_display = kalos::filter::dtf::CdDisplay::from_str(cd, true).unwrap();
        }
        match v {
            "off" => p.light = LightMode::Off,
            "auto" => {}
            x => p.light_share = Some(x.parse().unwrap()),
        }
        let t = std::time::Instant::now();
        let run = render_dtf(
            &scene,
            &integ,
            &set,
            &p,
            DtfBudget::Spp(spp as f64),
            &Silent,
        )
        .unwrap();
        let secs = t.elapsed().as_secs_f64();
        let ind = RgbImage::new(set.width, set.height, run.independent.mean_rgb());
        let e_ind = se(&ind);
        let mean = |im: &RgbImage| {
            im.data
                .iter()
                .map(|c| (c[0] + c[1] + c[2]) as f64)
                .sum::<f64>()
        };
        let dep = RgbImage::new(set.width, set.height, run.dependent.mean_rgb());
        let extra = format!(
            "means: dependent {:.4} independent {:.4} filtered {:.4}; N {:.1} light paths/px {:.1} share {:?} costs {:?} (phase-2 film mse top {:.3e} rest {:.3e})",
            mean(&dep) / mean(&reference),
            mean(&ind) / mean(&reference),
            mean(&run.out.filtered) / mean(&reference),
            run.average_n(),
            run.light_paths as f64 / e_ind.len() as f64,
            run.light_plan.map(|p| p.share),
            run.light_plan.map(|p| (p.cost_camera, p.cost_light, p.splat_variance_share)),
            e_ind.iter().zip(&top).filter(|x| *x.1).map(|x| x.0).sum::<f64>() / e_ind.len() as f64,
            e_ind.iter().zip(&top).filter(|x| !*x.1).map(|x| x.0).sum::<f64>() / e_ind.len() as f64,
        );
        let name = format!("{v}/{cd}");
        report(&name, &run.out.combined, secs, extra);
        {
            // diagnostic: the perceptual error with the image's mean brought to the reference's
            let m = mean(&reference) / mean(&run.out.combined);
            let sc = RgbImage::new(
                set.width,
                set.height,
                run.out
                    .combined
                    .data
                    .iter()
                    .map(|c| c.map(|v| v * m as f32))
                    .collect(),
            );
            println!(
                "  rescaled by {m:.4}: perc {:.4}",
                perceptual_error(&sc, &reference).unwrap().1
            );
        }
        save(&format!("dtf-{v}-{cd}"), &run.out.combined);
    }
}
