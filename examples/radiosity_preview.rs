//! The radiosity preview (emitters + (B - E)/pi at the first non-specular hit, mirrors and
//! glass followed) of a scene at one max element area, and its bias against a reference:
//!
//!   cargo run --release --example radiosity_preview -- cornell 0.05 out.exr [ref.exr [SPP]]
//!
//! The table of the preview's bias against plain path tracing at three mesh sizes.
//! With SPP, the gather path tracer (`integrator::gather`, gather depth 1) at SPP samples
//! per pixel instead of the preview.

use kalos::image_io::{read_image, write_image, RgbImage};
use kalos::integrator::{camera_ray, gather, Counters};
use kalos::radiosity::{RadiositySettings, Solution};
use kalos::sampling::{SampleStream, SamplerConfig};
use kalos::scene::Camera;
use rayon::prelude::*;
use std::path::Path;

fn main() -> Result<(), String> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 4 {
        return Err("usage: radiosity_preview SCENE MAX_AREA OUT.exr [REF.exr]".into());
    }
    let scene = kalos::scene::load(&a[1])?;
    let max_area: f32 = a[2].parse().map_err(|e| format!("{}: {e}", a[2]))?;
    let set = RadiositySettings {
        max_area: Some(max_area),
        ..Default::default()
    };
    let sol = Solution::compute(&scene, &set, 3, &kalos::progress::Silent)?;
    let (w, h) = scene.defaults.res.unwrap_or((256, 256));
    let cam = Camera::new(scene.camera, w, h);
    let cfg = SamplerConfig::default();
    let gather_spp: Option<u32> = a.get(5).and_then(|v| v.parse().ok());
    let spp = gather_spp.unwrap_or(16);
    let iset = kalos::integrator::IntegratorSettings::default();
    let data: Vec<[f32; 3]> = (0..w * h)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let mut c = Counters::default();
            let mut acc = [0.0f32; 3];
            for i in 0..spp {
                let mut s = SampleStream::new(&cfg, 0, p, i as u64);
                let ray = camera_ray(&cam, x, y, &mut s);
                let l = match gather_spp {
                    None => gather::preview::<3>(&scene, &sol, ray, &mut s, 64, &mut c),
                    Some(_) => gather::radiance::<3>(
                        &scene,
                        &sol,
                        ray,
                        &mut s,
                        &iset,
                        1,
                        &kalos::integrator::LTilde::Scene(kalos::spectrum::Spectrum::ZERO),
                        &mut c,
                    ),
                }
                .to_rgb();
                for k in 0..3 {
                    acc[k] += l[k] / spp as f32;
                }
            }
            acc
        })
        .collect();
    let img = RgbImage::new(w, h, data);
    write_image(Path::new(&a[3]), &img, 0.0, &[])?;
    let st = &sol.stats;
    print!(
        "{} max_area {:.4}: {} elements, {} shots, {:.1} s",
        a[1], st.max_area, st.elements, st.shots, st.seconds
    );
    if let Some(r) = a.get(4) {
        let reference = read_image(Path::new(r))?;
        let m = kalos::metrics::Metrics::compute(&img, &reference)?;
        print!(
            "; rmse {:.5}, relmse {:.5}, perceptual {:.2}%, luminance ratio {:.4}",
            m.rmse,
            m.relmse,
            m.perceptual_share * 100.0,
            m.luminance_ratio
        );
    }
    println!();
    Ok(())
}
