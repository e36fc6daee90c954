//! Diagnostic: render plain path tracing and DTF's two phases once, then re-run the filter
//! with variants of its parameters on the same films and compare them with a reference.
//! `cargo run --release --example dtf_sweep -- SCENE REF.exr SPP N [WxH]`
use kalos::filter::dtf::{dtf_filter, CdDisplay, Clamp, DtfParams, Kernel};
use kalos::image_io::RgbImage;
use kalos::integrator::IntegratorSettings;
use kalos::metrics::{perceptual_error, rmse};
use kalos::pipeline::*;
use kalos::sampling::*;
use kalos::spectrum::SpectralMode;

fn report(
    name: &str,
    img: &RgbImage,
    reference: &RgbImage,
    base: Option<(f64, f64)>,
) -> (f64, f64) {
    let r = rmse(img, reference).unwrap();
    let p = perceptual_error(img, reference).unwrap().1;
    match base {
        Some((br, bp)) => println!(
            "{name:<40} rmse {r:.5} ({:.2}x)  perc {p:.4} ({:.2}x)",
            r / br,
            p / bp
        ),
        None => println!("{name:<40} rmse {r:.5}  perc {p:.4}"),
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
    let set = RenderSettings {
        width: reference.width,
        height: reference.height,
        camera: scene.camera,
        spectral: SpectralMode::Rgb,
        sampler: SamplerConfig {
            kind: SamplerKind::Random,
            seed,
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

    let p0 = DtfParams {
        n: Some(n),
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
        ("stop 5", |p| p.stop_ratio = 5.0),
        ("stop none", |p| p.stop_ratio = 1e9),
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
            p.stop_ratio = 1e9
        }),
        ("paper display", |p| p.paper_display = true),
        ("mmax 8 stop none cd none", |p| {
            p.m_max = 8;
            p.stop_ratio = 1e9;
            p.cd_display = CdDisplay::None
        }),
        ("mmax 8 stop none df0 0.003", |p| {
            p.m_max = 8;
            p.stop_ratio = 1e9;
            p.df0_min = 0.003
        }),
        ("mmax 8 stop 5", |p| {
            p.m_max = 8;
            p.stop_ratio = 5.0
        }),
        ("mmax 8 stop none gaussian", |p| {
            p.m_max = 8;
            p.stop_ratio = 1e9;
            p.kernel = Kernel::Gaussian
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
