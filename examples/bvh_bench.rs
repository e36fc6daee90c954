//! BVH benchmark: build time, size and ray throughput on a procedural mesh.
//!
//! `cargo run --release --example bvh_bench -- [triangles] [rays]`
//!
//! The mesh is a 4x4 grid of finely tessellated, displaced UV spheres on a
//! tessellated ground plane (pole triangles of the UV spheres are degenerate).
//! Closest-hit rays start uniformly inside the bounds with uniform directions;
//! any-hit (shadow) rays are segments between two uniform points in the bounds.
//! Queries run on 2 rayon threads. Throughput is reported per core from each
//! thread's own CPU time (/proc/thread-self/schedstat), which is robust to
//! other processes on a shared machine, and as wall-clock rays/s. The same
//! scenes and rays are then run through the `obvhs` crate (CWBVH, fast and
//! medium build presets) for comparison.
//!
//! Env: `NO_OBVHS=1` skips obvhs; `SCENES=mesh` / `SCENES=cornell` runs one
//! scene (both by default).

use kalos::accel::{Bvh, RayAnswer, RayQuery, BATCH};
use kalos::math::{Bounds3, Ray, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::time::Instant;

const THREADS: usize = 2;

/// `SeqRng` with the helpers this file needs.
struct Rng(kalos::sampling::SeqRng);
impl Rng {
    fn new(seed: u64) -> Self {
        Rng(kalos::sampling::SeqRng::new(seed))
    }
    fn f(&mut self) -> f32 {
        self.0.next_f32()
    }
    fn in_bounds(&mut self, b: &Bounds3) -> Vec3 {
        let u = Vec3::new(self.f(), self.f(), self.f());
        b.min + (b.max - b.min) * u
    }
    fn dir(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * self.f();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// Displaced UV sphere, `2 * nu * nv` triangles.
fn sphere(tris: &mut Vec<[Vec3; 3]>, c: Vec3, radius: f32, nu: usize, nv: usize, seed: f32) {
    let p = |i: usize, j: usize| {
        let phi = 2.0 * PI * (i % nu) as f32 / nu as f32;
        let theta = PI * j as f32 / nv as f32;
        let disp = 1.0
            + 0.15 * (5.0 * theta + seed).sin() * (7.0 * phi).sin()
            + 0.04 * (41.0 * theta).sin() * (37.0 * phi + seed).cos()
            + 0.01 * (171.0 * theta + 3.0 * phi).sin();
        let dir = Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        );
        c + dir * radius * disp
    };
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            tris.push([a, b, cc]);
            tris.push([a, cc, d]);
        }
    }
}

fn make_mesh(target: usize) -> Vec<[Vec3; 3]> {
    let mut tris = Vec::with_capacity(target + 1024);
    let mut rng = Rng::new(7);
    // Ground: ~5% of the triangles, slightly wavy.
    let g = ((target as f32 * 0.05 / 2.0).sqrt() as usize).max(1);
    let h = |x: f32, z: f32| 0.05 * (x * 3.0).sin() * (z * 2.0).cos();
    let gp = |i: usize, j: usize| {
        let x = -1.5 + 12.0 * i as f32 / g as f32;
        let z = -1.5 + 12.0 * j as f32 / g as f32;
        Vec3::new(x, h(x, z) - 1.2, z)
    };
    for j in 0..g {
        for i in 0..g {
            tris.push([gp(i, j), gp(i + 1, j), gp(i + 1, j + 1)]);
            tris.push([gp(i, j), gp(i + 1, j + 1), gp(i, j + 1)]);
        }
    }
    let per = (target.saturating_sub(tris.len()) / 16).max(8);
    let nv = ((per as f32 / 4.0).sqrt() as usize).max(2);
    let nu = (per / (2 * nv)).max(3);
    for k in 0..16 {
        let c = Vec3::new((k % 4) as f32 * 3.0, 0.0, (k / 4) as f32 * 3.0)
            + Vec3::new(rng.f() - 0.5, rng.f() * 0.5, rng.f() - 0.5);
        sphere(&mut tris, c, 0.8 + 0.4 * rng.f(), nu, nv, k as f32);
    }
    tris
}

/// Cornell box in the unit cube: floor, ceiling, three walls, a light quad just
/// below the ceiling (12 triangles) and two rotated blocks (12 each): 36
/// triangles.
fn cornell() -> Vec<[Vec3; 3]> {
    let mut t = Vec::new();
    let quad = |t: &mut Vec<[Vec3; 3]>, a: Vec3, b: Vec3, c: Vec3, d: Vec3| {
        t.push([a, b, c]);
        t.push([a, c, d]);
    };
    let v = |x, y, z| Vec3::new(x, y, z);
    quad(
        &mut t,
        v(0., 0., 0.),
        v(1., 0., 0.),
        v(1., 0., 1.),
        v(0., 0., 1.),
    ); // floor
    quad(
        &mut t,
        v(0., 1., 0.),
        v(0., 1., 1.),
        v(1., 1., 1.),
        v(1., 1., 0.),
    ); // ceiling
    quad(
        &mut t,
        v(0., 0., 1.),
        v(1., 0., 1.),
        v(1., 1., 1.),
        v(0., 1., 1.),
    ); // back
    quad(
        &mut t,
        v(0., 0., 0.),
        v(0., 0., 1.),
        v(0., 1., 1.),
        v(0., 1., 0.),
    ); // left
    quad(
        &mut t,
        v(1., 0., 0.),
        v(1., 1., 0.),
        v(1., 1., 1.),
        v(1., 0., 1.),
    ); // right
    quad(
        &mut t,
        v(0.4, 0.999, 0.4),
        v(0.6, 0.999, 0.4),
        v(0.6, 0.999, 0.6),
        v(0.4, 0.999, 0.6),
    ); // light
    let block = |t: &mut Vec<[Vec3; 3]>, c: Vec3, s: Vec3, ang: f32| {
        let (sa, ca) = ang.sin_cos();
        let p = |x: f32, y: f32, z: f32| {
            let (x, z) = ((x - 0.5) * s.x, (z - 0.5) * s.z);
            c + Vec3::new(x * ca - z * sa, y * s.y, x * sa + z * ca)
        };
        let q = [
            [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
            [p(0., 0., 1.), p(0., 1., 1.), p(1., 1., 1.), p(1., 0., 1.)],
            [p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
            [p(1., 0., 0.), p(1., 0., 1.), p(1., 1., 1.), p(1., 1., 0.)],
            [p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)],
            [p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)],
        ];
        for f in q {
            t.push([f[0], f[1], f[2]]);
            t.push([f[0], f[2], f[3]]);
        }
    };
    block(&mut t, v(0.35, 0.0, 0.65), v(0.3, 0.6, 0.3), 0.3);
    block(&mut t, v(0.68, 0.0, 0.33), v(0.3, 0.3, 0.3), -0.3);
    t
}

fn peak_rss_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

struct Rays {
    closest: Vec<Ray>,
    shadow: Vec<Ray>,
}

fn make_rays(b: &Bounds3, n: usize) -> Rays {
    let mut rng = Rng::new(12345);
    let closest = (0..n)
        .map(|_| Ray::new(rng.in_bounds(b), rng.dir()))
        .collect();
    let shadow = (0..n)
        .map(|_| {
            let o = rng.in_bounds(b);
            Ray::new(o, rng.in_bounds(b) - o)
        })
        .collect();
    Rays { closest, shadow }
}

/// CPU time consumed so far by the calling thread, in ns (from
/// /proc/thread-self/schedstat, so it excludes time spent waiting for a core
/// on a shared machine).
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// User + system CPU time of the whole process so far, in seconds (10 ms
/// resolution).
fn process_cpu_s() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which is in parentheses).
    let rest = s.rsplit_once(')').map_or("", |r| r.1);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // utime and stime are fields 14 and 15 (1-based), i.e. 11 and 12 here.
    (ticks(11) + ticks(12)) / 100.0
}

struct Rate {
    /// Rays per second of wall time, all threads.
    wall: f64,
    /// Rays per second of thread CPU time (per core).
    cpu: f64,
    hits: usize,
    sum_t: f64,
}

impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "{:6.2} Mrays/s per core (CPU time) -> {:6.2} Mrays/s on {THREADS} cores; wall {:6.2} Mrays/s",
            self.cpu / 1e6,
            self.cpu * THREADS as f64 / 1e6,
            self.wall / 1e6
        )
    }
}

/// Runs `f` over the rays on the pool, best of 3 passes.
fn time_rays(
    pool: &rayon::ThreadPool,
    rays: &[Ray],
    f: impl Fn(&Ray) -> Option<f32> + Sync,
) -> Rate {
    time_chunks(pool, rays, |c| {
        let mut hits = 0usize;
        let mut sum = 0.0f64;
        for r in c {
            if let Some(t) = f(r) {
                hits += 1;
                sum += t as f64;
            }
        }
        (hits, sum)
    })
}

/// Runs `f` over chunks of the rays on the pool (it returns the chunk's hits and
/// sum of t), best of 3 passes.
fn time_chunks(
    pool: &rayon::ThreadPool,
    rays: &[Ray],
    f: impl Fn(&[Ray]) -> (usize, f64) + Sync,
) -> Rate {
    let mut best = Rate {
        wall: 0.0,
        cpu: 0.0,
        hits: 0,
        sum_t: 0.0,
    };
    for _ in 0..3 {
        let t0 = Instant::now();
        let (hits, sum_t, cpu_ns) = pool.install(|| {
            rays.par_chunks(4096)
                .map(|c| {
                    let c0 = thread_cpu_ns();
                    let (hits, sum) = f(c);
                    (hits, sum, thread_cpu_ns() - c0)
                })
                .reduce(|| (0, 0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2))
        });
        let wall = rays.len() as f64 / t0.elapsed().as_secs_f64();
        let cpu = rays.len() as f64 / (cpu_ns as f64 * 1e-9);
        best.wall = best.wall.max(wall);
        best.cpu = best.cpu.max(cpu);
        best.hits = hits;
        best.sum_t = sum_t;
    }
    best
}

fn bench_kalos(name: &str, pool: &rayon::ThreadPool, tris: &[[Vec3; 3]], rays: &Rays) {
    let mut build_s = f64::MAX;
    let mut build_cpu = f64::MAX;
    let mut bvh = None;
    for _ in 0..3 {
        drop(bvh.take());
        let (t0, c0) = (Instant::now(), process_cpu_s());
        let b = Bvh::build(tris);
        build_s = build_s.min(t0.elapsed().as_secs_f64());
        build_cpu = build_cpu.min(process_cpu_s() - c0);
        bvh = Some(b);
    }
    let bvh = bvh.unwrap();
    println!(
        "[kalos {name}] build {:.1} ms wall, {:.2} s CPU (best of 3), {} nodes, {:.1} MiB",
        build_s * 1e3,
        build_cpu,
        bvh.node_count(),
        bvh.memory_bytes() as f64 / (1 << 20) as f64
    );
    let (nodes, leaves, packets) = bvh.shape();
    println!(
        "[kalos {name}] {nodes} 8-wide nodes ({:.1} MiB), {:.2} children per node, \
         {leaves} leaves in {packets} packets ({:.1} MiB, {:.2} triangles per packet)",
        (nodes * 256) as f64 / (1 << 20) as f64,
        (nodes.max(1) - 1 + leaves) as f64 / nodes.max(1) as f64,
        (packets * 160) as f64 / (1 << 20) as f64,
        tris.len() as f64 / packets as f64,
    );
    let r = time_rays(pool, &rays.closest, |r| {
        bvh.intersect(r, f32::INFINITY).map(|h| h.t)
    });
    println!(
        "[kalos {name}] closest: {r}  (hits {}, sum t {:.6e})",
        r.hits, r.sum_t
    );
    let r = time_rays(pool, &rays.shadow, |r| bvh.occluded(r, 1.0).then_some(0.0));
    println!("[kalos {name}] any-hit: {r}  (occluded {})", r.hits);
    // The same rays through `Bvh::trace`, BATCH queries interleaved at a time.
    let batched = |rays: &[Ray], q: fn(Ray) -> RayQuery| {
        let mut hits = 0usize;
        let mut sum = 0.0f64;
        let mut qs = Vec::with_capacity(BATCH);
        let mut out = vec![RayAnswer::Occluded(false); BATCH];
        for b in rays.chunks(BATCH) {
            qs.clear();
            qs.extend(b.iter().map(|&r| q(r)));
            bvh.trace(&qs, &mut out[..b.len()]);
            for a in &out[..b.len()] {
                match *a {
                    RayAnswer::Closest(Some(h)) => {
                        hits += 1;
                        sum += h.t as f64;
                    }
                    RayAnswer::Occluded(true) => hits += 1,
                    _ => {}
                }
            }
        }
        (hits, sum)
    };
    let r = time_chunks(pool, &rays.closest, |c| {
        batched(c, |r| RayQuery::Closest(r, f32::INFINITY))
    });
    println!(
        "[kalos {name}] closest, {BATCH} interleaved: {r}  (hits {}, sum t {:.6e})",
        r.hits, r.sum_t
    );
    let r = time_chunks(pool, &rays.shadow, |c| {
        batched(c, |r| RayQuery::Occluded(r, 1.0))
    });
    println!(
        "[kalos {name}] any-hit, {BATCH} interleaved: {r}  (occluded {})",
        r.hits
    );
}

fn bench_obvhs(name: &str, pool: &rayon::ThreadPool, tris: &[[Vec3; 3]], rays: &Rays) {
    use glam_obvhs::Vec3A;
    use obvhs::{
        cwbvh::builder::build_cwbvh_from_tris, ray::Ray as ORay, ray::RayHit,
        rt_triangle::RtTriangle, triangle::Triangle, BvhBuildParams,
    };
    let a = |v: Vec3| Vec3A::new(v.x, v.y, v.z);
    let otris: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: a(t[0]),
            v1: a(t[1]),
            v2: a(t[2]),
        })
        .collect();
    for (preset, params) in [
        ("fast_build", BvhBuildParams::fast_build()),
        ("medium_build", BvhBuildParams::medium_build()),
    ] {
        let mut build_s = f64::MAX;
        let mut build_cpu = f64::MAX;
        let mut built = None;
        for _ in 0..3 {
            drop(built.take());
            let (t0, c0) = (Instant::now(), process_cpu_s());
            let bvh = build_cwbvh_from_tris(&otris, params, &mut Default::default());
            // Triangles reordered into leaf order, precomputed edges (as in
            // obvhs' own cornell_box example); counted as part of the build.
            let rt: Vec<RtTriangle> = bvh
                .primitive_indices
                .iter()
                .map(|&i| {
                    let t = &otris[i as usize];
                    RtTriangle::new(t.v0, t.v1, t.v2)
                })
                .collect();
            build_s = build_s.min(t0.elapsed().as_secs_f64());
            build_cpu = build_cpu.min(process_cpu_s() - c0);
            built = Some((bvh, rt));
        }
        let (bvh, rt) = built.unwrap();
        let mem = bvh.nodes.len() * std::mem::size_of_val(&bvh.nodes[0])
            + bvh.primitive_indices.len() * 4
            + rt.len() * std::mem::size_of::<RtTriangle>();
        println!(
            "[obvhs {name} {preset}] build {:.1} ms wall, {:.2} s CPU (best of 3), {} nodes (8-wide), {:.1} MiB",
            build_s * 1e3,
            build_cpu,
            bvh.nodes.len(),
            mem as f64 / (1 << 20) as f64
        );
        let r = time_rays(pool, &rays.closest, |r| {
            let ray = ORay::new(a(r.o), a(r.d), 0.0, f32::INFINITY);
            let mut hit = RayHit::none();
            bvh.ray_traverse(ray, &mut hit, |ray, id| rt[id].intersect(ray))
                .then_some(hit.t)
        });
        println!(
            "[obvhs {name} {preset}] closest: {r}  (hits {}, sum t {:.6e})",
            r.hits, r.sum_t
        );
        let r = time_rays(pool, &rays.shadow, |r| {
            let ray = ORay::new(a(r.o), a(r.d), 0.0, 1.0);
            (!bvh.ray_traverse_miss(ray, |ray, id| rt[id].intersect(ray))).then_some(0.0)
        });
        println!(
            "[obvhs {name} {preset}] any-hit: {r}  (occluded {})",
            r.hits
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let target: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let nrays: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_000_000);
    // NO_OBVHS=1 skips the comparison; SCENES=mesh or SCENES=cornell runs one.
    let skip_obvhs = std::env::var_os("NO_OBVHS").is_some();
    let scenes = std::env::var("SCENES").unwrap_or_else(|_| "mesh,cornell".into());
    rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build_global()
        .unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .unwrap();

    let bounds = |tris: &[[Vec3; 3]]| {
        let mut b = Bounds3::EMPTY;
        for t in tris {
            for v in t {
                b.grow(*v);
            }
        }
        b
    };
    if scenes.contains("mesh") {
        let tris = make_mesh(target);
        let b = bounds(&tris);
        println!(
            "mesh: {} triangles, bounds {:?}..{:?}; {nrays} rays per query type, {THREADS} threads",
            tris.len(),
            b.min,
            b.max
        );
        let rays = make_rays(&b, nrays);
        println!("peak RSS after mesh + rays: {:.1} MiB", peak_rss_mib());
        bench_kalos("mesh", &pool, &tris, &rays);
        println!("peak RSS after kalos: {:.1} MiB", peak_rss_mib());
        if !skip_obvhs {
            bench_obvhs("mesh", &pool, &tris, &rays);
            println!("peak RSS after obvhs: {:.1} MiB", peak_rss_mib());
        }
    }
    if scenes.contains("cornell") {
        let tris = cornell();
        let rays = make_rays(&bounds(&tris), nrays);
        bench_kalos("cornell36", &pool, &tris, &rays);
        if !skip_obvhs {
            bench_obvhs("cornell36", &pool, &tris, &rays);
        }
    }
}
