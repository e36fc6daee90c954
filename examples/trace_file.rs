//! Closest-hit rays per second of kalos' BVH on a scene file, the rays uniform in the
//! scene's bounds with uniformly distributed directions, on one thread (best of five passes
//! over 2^20 rays). `bench/mitsuba_trace.py` measures Mitsuba 3 on the same kind of rays,
//! so that the two renderers' ray tracing alone can be compared on any scene:
//!
//! `cargo run --release --example trace_file -- SCENE [RAYS]`
use kalos::math::{Ray, Vec3};
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(spec) = args.next() else {
        eprintln!("usage: trace_file SCENE [RAYS]");
        std::process::exit(2);
    };
    let n: usize = args
        .next()
        .map_or(1 << 20, |s| s.parse().expect("RAYS: a count"));
    let scene = kalos::scene::load(&spec).unwrap_or_else(|e| {
        eprintln!("trace_file: {e}");
        std::process::exit(1)
    });
    let b = scene.bvh.bounds();
    let mut rng = kalos::sampling::SeqRng::new(1);
    let rays: Vec<Ray> = (0..n)
        .map(|_| {
            let mut u = || rng.next_f32();
            let o = b.min + (b.max - b.min) * Vec3::new(u(), u(), u());
            let z = 1.0 - 2.0 * u();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect();
    let mut best = 0.0f64;
    let mut hits = 0;
    for _ in 0..5 {
        let t0 = Instant::now();
        hits = rays
            .iter()
            .filter(|r| scene.bvh.intersect(r, f32::INFINITY).is_some())
            .count();
        best = best.max(n as f64 / t0.elapsed().as_secs_f64());
    }
    println!(
        "{spec}: {:.2} M closest-hit rays/s on one thread ({}), {hits} hits of {n}",
        best / 1e6,
        scene.bvh.isa().name()
    );
}
