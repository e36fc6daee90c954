//! Diagnostic: render plain path tracing and DTF's two phases once, then re-run the filter
//! with variants of its parameters on the same films and compare them with a reference.
//! `cargo run --release --example dtf_sweep -- SCENE REF.exr SPP N [SEED] [path|bdpt]`
//! (the reference's size is the render's; N = 0: the default n for SPP; the render's other
//! settings are `kalos render`'s defaults). With `DTF_SWEEP_DUMP=DIR` the reference, plain,
//! DTF and its layers are written there as .pfm (for numpy) and the N map as n.pfm.
use kalos::filter::dtf::{dtf_filter, CdDisplay, Clamp, DtfParams, Kernel};
use kalos::image_io::RgbImage;
use kalos::integrator::IntegratorKind;
use kalos::metrics::{perceptual_error, rmse};
use kalos::pipeline::*;
use kalos::render::RenderJob;

fn report(
    name: &str,
    img: &RgbImage,
    reference: &RgbImage,
    base: Option<(f64, f64)>,
) -> (f64, f64) {
    let r = rmse(img, reference).unwrap();
    let p = perceptual_error(img, reference).unwrap().1;
    // squared error off the emitters seen directly (reference luminance-ish norm > 3)
    let (mut se, mut k) = (0.0f64, 0usize);
    for (x, y) in img.data.iter().zip(&reference.data) {
        if y[0] + y[1] + y[2] <= 3.0 {
            se += (0..3).map(|c| ((x[c] - y[c]) as f64).powi(2)).sum::<f64>() / 3.0;
            k += 1;
        }
    }
    let r_dim = (se / k.max(1) as f64).sqrt();
    let mean = |im: &RgbImage| {
        im.data
            .iter()
            .map(|c| (c[0] + c[1] + c[2]) as f64)
            .sum::<f64>()
    };
    let m = mean(img) / mean(reference);
    match base {
        Some((br, bp)) => println!(
            "{name:<40} rmse {r:.5} ({:.2}x)  perc {p:.4} ({:.2}x)  rmse off lights {r_dim:.5}  mean {m:.4}",
            r / br,
            p / bp
        ),
        None => println!("{name:<40} rmse {r:.5}  perc {p:.4}  rmse off lights {r_dim:.5}  mean {m:.4}"),
    }
    (r, p)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = kalos::scene::load(&a[1]).unwrap();
    let reference = kalos::image_io::read_image(std::path::Path::new(&a[2])).unwrap();
    let spp: u32 = a[3].parse().unwrap();
    let n: u32 = a[4].parse().unwrap();
    let seed: u64 = a.get(5).map(|s| s.parse().unwrap()).unwrap_or(0);
    let mut job = RenderJob::new(&a[1]);
    job.res = Some((reference.width, reference.height));
    job.seed = seed;
    job.integrator = Some(match a.get(6).map(|s| s.as_str()) {
        None | Some("path") => IntegratorKind::Path,
        Some("bdpt") => IntegratorKind::Bdpt,
        Some(o) => panic!("integrator {o}: path or bdpt"),
    });
    let set = job.settings(&scene);
    let dump = std::env::var("DTF_SWEEP_DUMP")
        .ok()
        .map(std::path::PathBuf::from);
    let save = |name: &str, im: &RgbImage| {
        if let Some(d) = &dump {
            std::fs::create_dir_all(d).unwrap();
            kalos::image_io::write_image(&d.join(format!("{name}.pfm")), im, 0.0, &[]).unwrap();
        }
    };
    save("ref", &reference);
    let integ = kalos::integrator::Integrator::prepare(
        &scene,
        set.integrator,
        set.spectral.bands(),
        &Silent,
    )
    .unwrap();
    let plain = render(&scene, &integ, &set, Budget::Spp(spp), 0, &Silent).unwrap();
    let img = |f: &kalos::film::Film| RgbImage::new(f.width, f.height, f.mean_rgb());
    let base = report("plain", &img(&plain.film), &reference, None);
    {
        let im = img(&plain.film);
        let mut e: Vec<f64> = im
            .data
            .iter()
            .zip(&reference.data)
            .map(|(x, r)| (0..3).map(|c| ((x[c] - r[c]) as f64).powi(2)).sum::<f64>())
            .collect();
        let tot: f64 = e.iter().sum();
        e.sort_by(|a, b| b.total_cmp(a));
        let k = e.len() / 100;
        let top: f64 = e[..k].iter().sum();
        let top10: f64 = e[..k / 10].iter().sum();
        println!(
            "plain: top 1% of pixels hold {:.2} of the squared error, top 0.1% {:.2}",
            top / tot,
            top10 / tot
        );
    }

    save("plain", &img(&plain.film));
    let p0 = DtfParams {
        n: (n > 0).then_some(n),
        ..Default::default()
    };
    let run = render_dtf(
        &scene,
        &integ,
        &set,
        &p0,
        DtfBudget::Spp(spp as f64),
        &Silent,
    )
    .unwrap();
    report(
        "dependent only",
        &img(&run.dependent),
        &reference,
        Some(base),
    );
    report("dtf default", &run.out.combined, &reference, Some(base));
    println!("n {} average N {:.1}", run.n, run.average_n());
    save("dtf", &run.out.combined);
    save("dependent", &img(&run.dependent));
    save("independent", &img(&run.independent));
    save("filtered", &run.out.filtered);
    let grey = |v: Vec<f32>| {
        RgbImage::new(
            reference.width,
            reference.height,
            v.into_iter().map(|x| [x; 3]).collect(),
        )
    };
    save("n", &grey(run.alloc.iter().map(|&x| x as f32).collect()));
    save("m", &grey(run.out.m.iter().map(|&x| x as f32).collect()));
    // unfiltered combination
    let mut p = p0.clone();
    p.m_max = 1;
    let o = dtf_filter(&run.dependent, &run.independent, &run.classes, &p).unwrap();
    report("no filter (mmax 1)", &o.combined, &reference, Some(base));
    let mut hist = [0usize; 33];
    for &m in &run.out.m {
        hist[m as usize] += 1;
    }
    println!("m histogram (default): {:?}", &hist[..=p0.m_max as usize]);
    {
        let d = kalos::filter::dtf::Dtf::new(&run.dependent, &run.independent, &run.classes, &p0)
            .unwrap();
        let (w, h) = (reference.width, reference.height);
        let mut meff = vec![0.0f64; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let r = d.weights(x, y);
                meff[(y * w + x) as usize] = 1.0 / r.weights.iter().map(|q| q.2 * q.2).sum::<f64>();
            }
        }
        let mut hm = [0usize; 8];
        for &v in &meff {
            hm[(v.log2().floor().max(0.0) as usize).min(7)] += 1;
        }
        println!(
            "Meff = 1/sum f^2 histogram by powers of 2 [1,2) [2,4) ...: {:?}",
            hm
        );
        let comb = &run.out.combined;
        let norm = |c: [f32; 3]| (c[0].abs() + c[1].abs() + c[2].abs()) as f64;
        let mean_n: f64 =
            reference.data.iter().map(|&c| norm(c)).sum::<f64>() / reference.data.len() as f64;
        // pixels per bucket of Meff, and how many of them are off by more than 5%
        let buckets = |im: &RgbImage| {
            let mut out = [(0usize, 0usize); 8];
            for (i, m) in meff.iter().enumerate() {
                let (x, r) = (im.data[i], reference.data[i]);
                let bad = norm([x[0] - r[0], x[1] - r[1], x[2] - r[2]])
                    > 0.05 * norm(r).max(0.01 * mean_n);
                let b = (m.log2().floor().max(0.0) as usize).min(7);
                out[b].0 += 1;
                out[b].1 += bad as usize;
            }
            out
        };
        println!("per Meff bucket (pixels, bad): {:?}", buckets(comb));
        println!(
            "plain per Meff bucket (pixels, bad): {:?}",
            buckets(&img(&plain.film))
        );
    }
    for (name, f) in [
        (
            "mmax 6",
            (|p: &mut DtfParams| p.m_max = 6) as fn(&mut DtfParams),
        ),
        ("mmax 8", |p| p.m_max = 8),
        ("df0 0.001", |p| p.df0_min = 0.001),
        ("df0 0", |p| p.df0_min = 0.0),
        ("gaussian", |p| p.kernel = Kernel::Gaussian),
        ("paper clamp", |p| p.clamp = Clamp::Paper),
        ("guard off", |p| p.guard = 0.0),
        ("stop 5", |p| p.stop_ratio = Some(5.0)),
        ("stop none", |p| p.stop_ratio = None),
        ("guard 2", |p| p.guard = 2.0),
        ("guard 5", |p| p.guard = 5.0),
        ("cd scaled", |p| p.cd_display = CdDisplay::Scaled),
        ("cd none", |p| p.cd_display = CdDisplay::None),
        ("cd scaled mmax 8", |p| {
            p.cd_display = CdDisplay::Scaled;
            p.m_max = 8
        }),
        ("cd none mmax 8", |p| {
            p.cd_display = CdDisplay::None;
            p.m_max = 8
        }),
        ("mmax 12", |p| p.m_max = 12),
        ("mmax 8 stop none", |p| {
            p.m_max = 8;
            p.stop_ratio = None
        }),
        ("paper display", |p| p.paper_display = true),
        ("mmax 8 stop none cd none", |p| {
            p.m_max = 8;
            p.stop_ratio = None;
            p.cd_display = CdDisplay::None
        }),
        ("mmax 8 stop none df0 0.003", |p| {
            p.m_max = 8;
            p.stop_ratio = None;
            p.df0_min = 0.003
        }),
        ("mmax 8 stop 5", |p| {
            p.m_max = 8;
            p.stop_ratio = Some(5.0)
        }),
        ("mmax 8 stop none gaussian", |p| {
            p.m_max = 8;
            p.stop_ratio = None;
            p.kernel = Kernel::Gaussian
        }),
        ("dep-noise 0 (paper Delta)", |p| p.dep_noise = 0.0),
        ("dep-noise 1", |p| p.dep_noise = 1.0),
        ("dep-noise 3", |p| p.dep_noise = 3.0),
        ("z 1", |p| p.z = 1.0),
        ("z 1.5", |p| p.z = 1.5),
        ("z 2", |p| p.z = 2.0),
        ("z 4", |p| p.z = 4.0),
        ("z 2 guard 2", |p| {
            p.z = 2.0;
            p.guard = 2.0
        }),
        ("z 2 cd none", |p| {
            p.z = 2.0;
            p.cd_display = CdDisplay::None
        }),
        ("mmax 6 df0 0.001", |p| {
            p.m_max = 6;
            p.df0_min = 0.001
        }),
    ] {
        let mut p = p0.clone();
        f(&mut p);
        let o = dtf_filter(&run.dependent, &run.independent, &run.classes, &p).unwrap();
        report(name, &o.combined, &reference, Some(base));
    }
}
