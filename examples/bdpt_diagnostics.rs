//! Diagnostics of the bidirectional path tracer that print figures and assert nothing
//! (the tests in src/integrator/bdpt/tests.rs assert): speed against the path tracer, per-pixel
//! z-scores against a path-traced reference, the caustic scene's image means, and
//! efficiency 1 / (variance x time) with PNGs of both images in /tmp.
//!
//! Run: cargo run --release --example bdpt_diagnostics [bdpt_speed|bdpt_vs_reference|caustic_means|bdpt_efficiency]
//! (`KALOS_SPP` sets the samples of bdpt_vs_reference and caustic_means.)

use kalos::integrator::bdpt::passes::{render, render_bdpt, render_path, settings, Img};
use kalos::integrator::bdpt::{sample_pixel_with, BdptOptions};
use kalos::integrator::{path, Counters, RrMode};
use kalos::scene;

fn main() {
    let which = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "bdpt_efficiency".into());
    match which.as_str() {
        "bdpt_speed" => bdpt_speed(),
        "bdpt_vs_reference" => bdpt_vs_reference(),
        "caustic_means" => caustic_means(),
        "bdpt_efficiency" => bdpt_efficiency(),
        w => {
            eprintln!("bdpt_diagnostics: unknown diagnostic '{w}' (bdpt_speed, bdpt_vs_reference, caustic_means, bdpt_efficiency)");
            std::process::exit(2);
        }
    }
}

/// Paths per second of BDPT and the path tracer on cornell in the same loop
/// (`cargo run --release --example bdpt_diagnostics bdpt_speed`).
fn bdpt_speed() {
    let scene = scene::load("cornell").unwrap();
    let set = settings(RrMode::Classic, -1);
    let (w, h, spp) = (64, 64, 32);
    for round in 0..2 {
        let t0 = std::time::Instant::now();
        let mut c = Counters::default();
        render(&scene, w, h, spp, 1, |cam, x, y, s, _| {
            path::sample_pixel::<3>(&scene, cam, x, y, s, &set, &mut c)
        });
        let tp = t0.elapsed().as_secs_f64();
        let cp = c;
        let t0 = std::time::Instant::now();
        let mut c = Counters::default();
        let o = BdptOptions::default();
        render(&scene, w, h, spp, 1, |cam, x, y, s, splat| {
            sample_pixel_with::<3>(&scene, cam, x, y, s, &set, &o, &mut c, splat, None)
        });
        let tb = t0.elapsed().as_secs_f64();
        println!(
            "round {round}: path {:.0} paths/s ({:.2} rays/path), bdpt {:.0} paths/s ({:.2} rays/path): bdpt {:.2}x slower per sample",
            cp.paths as f64 / tp,
            cp.rays as f64 / cp.paths as f64,
            c.paths as f64 / tb,
            c.rays as f64 / c.paths as f64,
            tb / tp
        );
    }
}

/// Diagnostic: BDPT and the path tracer at `KALOS_SPP` against a path-traced reference at
/// 16x that (`cargo run --release --example bdpt_diagnostics bdpt_vs_reference`).
fn bdpt_vs_reference() {
    let scene = scene::load("cornell").unwrap();
    let set = settings(RrMode::Classic, -1);
    let spp: u32 = std::env::var("KALOS_SPP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    let (w, h) = (16, 16);
    let r = render_path::<3>(&scene, w, h, spp * 16, 99, &set);
    let a = render_bdpt::<3>(&scene, w, h, spp, 3, &set, BdptOptions::default());
    let b = render_path::<3>(&scene, w, h, spp, 4, &set);
    for (name, x) in [("bdpt", &a), ("path", &b)] {
        let (mut hi, mut lo, mut zs) = (0, 0, 0.0f64);
        for i in 0..(w * h) as usize {
            for c in 0..3 {
                let v = x.var[i][c] + r.var[i][c];
                let z = if v > 0.0 {
                    (x.mean[i][c] - r.mean[i][c]) / v.sqrt()
                } else {
                    0.0
                };
                zs += z;
                if z > 3.0 {
                    hi += 1;
                }
                if z < -3.0 {
                    lo += 1;
                }
            }
        }
        println!(
            "{name}: {hi} above 3 se, {lo} below, mean z {:.3}",
            zs / 768.0
        );
    }
}

/// Diagnostic: image means on `caustic` (`cargo run --release --example bdpt_diagnostics caustic_means`).
fn caustic_means() {
    let scene = scene::load("caustic").unwrap();
    let set = settings(RrMode::Classic, -1);
    let spp: u32 = std::env::var("KALOS_SPP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    let (w, h) = (8, 8);
    let t0 = std::time::Instant::now();
    let a = render_bdpt::<3>(&scene, w, h, spp, 3, &set, BdptOptions::default());
    let ta = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let b = render_path::<3>(&scene, w, h, 16 * spp, 4, &set);
    let tb = t0.elapsed().as_secs_f64();
    println!("bdpt {:?} +- {:?} in {ta:.2}s", a.img_mean, a.img_se);
    println!("path {:?} +- {:?} in {tb:.2}s", b.img_mean, b.img_se);
}

/// Diagnostic: efficiency 1 / (mean per-pixel variance x time) of BDPT against the path
/// tracer (variance from the passes; single-threaded, same loop), and PNGs of both in /tmp
/// (`cargo run --release --example bdpt_diagnostics bdpt_efficiency`).
fn bdpt_efficiency() {
    let set = settings(RrMode::Classic, -1);
    for (name, w, spp_b, spp_p) in [("cornell", 32, 64, 256), ("caustic", 32, 64, 256)] {
        let scene = scene::load(name).unwrap();
        let t0 = std::time::Instant::now();
        let a = render_bdpt::<3>(&scene, w, w, spp_b, 1, &set, BdptOptions::default());
        let ta = t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        let b = render_path::<3>(&scene, w, w, spp_p, 2, &set);
        let tb = t0.elapsed().as_secs_f64();
        let mv = |x: &Img| {
            x.var
                .iter()
                .map(|v| (v[0] + v[1] + v[2]) / 3.0)
                .sum::<f64>()
                / x.var.len() as f64
        };
        let (va, vb) = (mv(&a), mv(&b));
        println!(
            "{name} {w}x{w}: bdpt {spp_b} spp {ta:.2}s var {va:.3e}; path {spp_p} spp {tb:.2}s var {vb:.3e}; efficiency bdpt/path {:.2}",
            (vb * tb) / (va * ta)
        );
        write_png(&a, &format!("/tmp/{name}-bdpt.png"));
        write_png(&b, &format!("/tmp/{name}-path.png"));
    }
    let scene = scene::load("caustic").unwrap();
    let a = render_bdpt::<3>(&scene, 128, 128, 16, 1, &set, BdptOptions::default());
    write_png(&a, "/tmp/caustic-bdpt-128.png");
    let b = render_path::<3>(&scene, 128, 128, 64, 2, &set);
    write_png(&b, "/tmp/caustic-path-128.png");
}

/// A pass image's means as a PNG.
fn write_png(x: &Img, path: &str) {
    let data = x.mean.iter().map(|m| m.map(|c| c as f32)).collect();
    let img = kalos::image_io::RgbImage::new(x.w, x.h, data);
    kalos::image_io::write_image(std::path::Path::new(path), &img, 0.0, &[]).unwrap();
}
