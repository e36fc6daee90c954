//! Closest-hit rays per second of kalos' BVH on a scene file, the rays uniform in the
//! scene's bounds with uniformly distributed directions, on one thread (best of five passes
//! over 2^20 rays). `bench/mitsuba_trace.py` measures Mitsuba 3 on the same kind of rays,
//! so that the two renderers' ray tracing alone can be compared on any scene:
//!
//! `cargo run --release --example trace_file -- SCENE [RAYS] [chained]`
//!
//! With `chained`, each ray's origin waits on the previous ray's answer (it adds 0 derived
//! from the hit distance, so the rays are the same): the queries then run one after the
//! other as a path's do, instead of overlapping in the CPU's out-of-order window.
use kalos::math::{Ray, Vec2, Vec3};
use kalos::sampling::warp::square_to_uniform_sphere;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(spec) = args.next() else {
        eprintln!("usage: trace_file SCENE [RAYS] [chained]");
        std::process::exit(2);
    };
    let n: usize = match args.next().map(|s| s.parse::<usize>()) {
        None => 1 << 20,
        Some(Ok(n)) if n > 0 => n,
        _ => {
            eprintln!("trace_file: RAYS must be a positive whole number");
            std::process::exit(2);
        }
    };
    let chained = match args.next().as_deref() {
        None => false,
        Some("chained") => true,
        Some(other) => {
            eprintln!("trace_file: the third argument is `chained` or nothing, not {other:?}");
            std::process::exit(2);
        }
    };
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
            Ray::new(o, square_to_uniform_sphere(Vec2::new(u(), u())))
        })
        .collect();
    let mut best = 0.0f64;
    let mut hits = 0;
    for _ in 0..5 {
        let t0 = Instant::now();
        hits = if chained {
            // 0 from the last answer (min(t, 0) is 0 for any t >= 0, inf included).
            let mut zero = 0.0f32;
            let mut hits = 0;
            for r in &rays {
                let r = Ray::new(r.o + Vec3::new(zero, 0.0, 0.0), r.d);
                let h = scene.bvh.intersect(&r, f32::INFINITY);
                zero = h.map_or(0.0, |h| h.t.min(0.0) * 0.0);
                hits += h.is_some() as usize;
            }
            hits
        } else {
            rays.iter()
                .filter(|r| scene.bvh.intersect(r, f32::INFINITY).is_some())
                .count()
        };
        best = best.max(n as f64 / t0.elapsed().as_secs_f64());
    }
    // The CPU beside the figure: a rate holds for the CPU it was measured on.
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |k: &str| {
        info.lines()
            .find(|l| l.starts_with(k))
            .and_then(|l| l.split_once(':'))
            .map_or("?", |(_, v)| v.trim())
    };
    let flags: Vec<&str> = field("flags")
        .split_whitespace()
        .filter(|f| ["sse4_2", "avx", "avx2", "fma", "avx512f"].contains(f))
        .collect();
    println!(
        "{spec}: {:.2} M closest-hit rays/s{} on one thread ({}), {hits} hits of {n}; CPU {} ({})",
        best / 1e6,
        if chained { ", chained" } else { "" },
        scene.bvh.isa().name(),
        field("model name"),
        flags.join(" ")
    );
}
