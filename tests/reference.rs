//! Agreement with an independent renderer: Mitsuba 3's path tracer on the same Cornell box
//! (assets/reference/cornell-256-reference.exr, 32768 spp). kalos' mean must be within
//! 0.5% of it and its per-pixel RMSE must keep falling as spp grows (no bias floor).

mod common;
use common::*;
use kalos::image_io::{read_image, RgbImage};

fn rmse(a: &RgbImage, b: &RgbImage) -> f64 {
    let mut s = 0.0;
    for (p, q) in a.data.iter().zip(b.data.iter()) {
        for c in 0..3 {
            s += ((p[c] - q[c]) as f64).powi(2);
        }
    }
    (s / (3 * a.data.len()) as f64).sqrt()
}

#[test]
fn cornell_agrees_with_mitsuba() {
    let reference = read_image(std::path::Path::new(
        "assets/reference/cornell-256-reference.exr",
    ))
    .unwrap();
    let scene = kalos::scene::load("cornell").unwrap();
    let set = settings(&scene, 256, 256);
    let ref_mean: f64 = reference.mean().iter().sum::<f64>() / 3.0;
    let mut last = f64::INFINITY;
    let mut errors = Vec::new();
    for spp in [4u32, 16, 64] {
        let film = render_spp(&scene, &set, spp);
        let img = RgbImage::new(256, 256, film.mean_rgb());
        let e = rmse(&img, &reference);
        let mean: f64 = img.mean().iter().sum::<f64>() / 3.0;
        errors.push((spp, e, mean));
        // quadrupling spp should roughly halve the error: demand at least a 1.6x drop
        assert!(e < last / 1.6, "RMSE stalls: {errors:?}");
        last = e;
        if spp == 64 {
            let rel = (mean - ref_mean).abs() / ref_mean;
            assert!(
                rel < 0.005,
                "mean {mean} vs reference {ref_mean} ({:.3}%)",
                rel * 100.0
            );
        }
    }
    eprintln!("(spp, rmse, mean) {errors:?}, reference mean {ref_mean}");
}
