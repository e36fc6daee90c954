//! How good is the estimate roulette's L~? Prints the scene's L~ next to the measured
//! average radiance arriving by reflection (direct light left out, as in L~) at the points
//! the camera sees first, where the first roulette decision is taken: a cosine-distributed
//! direction about the side the camera sees, its radiance by the path tracer (classic
//! roulette) minus the emission it hits directly.
//!
//! Run: cargo run --release --example rr_ltilde [SCENE] [RES] [SPP]

use kalos::integrator::{path, Counters, IntegratorSettings, LTilde};
use kalos::math::{offset_origin, Frame, Ray};
use kalos::sampling::{square_to_cosine_hemisphere, SampleStream, SamplerConfig};
use kalos::scene::Camera;
use kalos::spectrum::Spectrum;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("cornell");
    let res: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(64);
    let spp: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(64);
    let scene = kalos::scene::load(name).unwrap();
    let cam = Camera::new(scene.camera, res, res);
    let set = IntegratorSettings::default();
    let cfg = SamplerConfig::default();
    let mut c = Counters::default();
    let (mut sum, mut n) = ([0.0f64; 3], 0u64);
    let (mut sum_al, mut sum_a) = ([0.0f64; 3], [0.0f64; 3]);
    for y in 0..res {
        for x in 0..res {
            for k in 0..spp {
                let mut s = SampleStream::new(&cfg, 7, y * res + x, k as u64);
                let ray = kalos::integrator::camera_ray(&cam, x, y, &mut s);
                let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                let mat = scene.material_of(hit.prim);
                let ng = if (-ray.d).dot(hit.ng) < 0.0 {
                    -hit.ng
                } else {
                    hit.ng
                };
                s.set_dimension(200);
                let wi = Frame::from_normal(ng).to_world(square_to_cosine_hemisphere(s.next_2d()));
                let r = Ray::new(offset_origin(hit.p, ng, wi), wi);
                let mut s2 = SampleStream::new(&cfg, 8, y * res + x, k as u64);
                let l = path::radiance::<3>(
                    &scene,
                    r,
                    &mut s2,
                    &set,
                    &LTilde::Scene(Spectrum::ZERO),
                    &mut c,
                );
                // leave out the emission seen directly (L~ is reflected light only)
                let mut direct = [0.0f32; 3];
                if let Some(h2) = scene.intersect(&r, f32::INFINITY) {
                    let m2 = scene.material_of(h2.prim);
                    if m2.is_emissive() && (-wi).dot(h2.ng) > 0.0 {
                        direct = m2.emitted((-wi).dot(h2.ng));
                    }
                }
                let a = mat.bsdf.albedo::<3>();
                for ch in 0..3 {
                    let li = (l[ch] - direct[ch]) as f64;
                    sum[ch] += li;
                    sum_al[ch] += a[ch] as f64 * li;
                    sum_a[ch] += a[ch] as f64;
                }
                n += 1;
            }
        }
    }
    let e = &kalos::integrator::RadianceEstimate::of_scene(&scene);
    let lt: Spectrum<3> = e.l_tilde::<3>();
    let m = sum.map(|v| v / n as f64);
    println!("scene {name}: e_s {:.4} e_L {:.4}", e.e_s, e.e_l);
    println!(
        "L~                         {:.4} {:.4} {:.4}",
        lt[0], lt[1], lt[2]
    );
    println!(
        "measured mean L_in (refl.) {:.4} {:.4} {:.4}",
        m[0], m[1], m[2]
    );
    println!(
        "L~ / measured              {:.3} {:.3} {:.3}",
        lt[0] as f64 / m[0],
        lt[1] as f64 / m[1],
        lt[2] as f64 / m[2]
    );
    println!(
        "albedo-weighted: mean a L_in {:.4} {:.4} {:.4}, mean a L~ {:.4} {:.4} {:.4}",
        sum_al[0] / n as f64,
        sum_al[1] / n as f64,
        sum_al[2] / n as f64,
        sum_a[0] / n as f64 * lt[0] as f64,
        sum_a[1] / n as f64 * lt[1] as f64,
        sum_a[2] / n as f64 * lt[2] as f64
    );
}
