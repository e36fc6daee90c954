// scratch A/B tuning harness (not committed)
#[path = "bvh_bench.rs"]
#[allow(dead_code)]
mod bench;
use bench::*;
use kalos::accel::Bvh;
use kalos::math::Ray;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let target: usize = args[1].parse().unwrap();
    let nrays: usize = args[2].parse().unwrap();
    let variants: Vec<String> = args[3..].to_vec(); // each "K=V,K=V"
    rayon::ThreadPoolBuilder::new().num_threads(1).build_global().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let tris = if target == 36 { cornell() } else { make_mesh(target) };
    let mut b = kalos::math::Bounds3::EMPTY;
    for t in &tris { for v in t { b.grow(*v); } }
    let rays = make_rays(&b, nrays);
    let mut bvhs = vec![];
    for v in &variants {
        for kv in ["BVH_CTRAV", "BVH_NOBLOCKS"] { std::env::remove_var(kv); }
        for kv in v.split(',').filter(|s| !s.is_empty()) {
            let (k, val) = kv.split_once('=').unwrap();
            std::env::set_var(k, val);
        }
        let t0 = std::time::Instant::now();
        let bvh = Bvh::build(&tris);
        eprintln!("{v}: build {:.1} ms nodes {} mem {}", t0.elapsed().as_secs_f64()*1e3, bvh.node_count(), bvh.memory_bytes());
        bvhs.push(bvh);
    }
    let mut best = vec![(0.0f64, 0.0f64); variants.len()];
    for _round in 0..5 {
        for (i, bvh) in bvhs.iter().enumerate() {
            let c = time_rays(&pool, &rays.closest, |r: &Ray| bvh.intersect(r, f32::INFINITY).map(|h| h.t));
            let a = time_rays(&pool, &rays.shadow, |r: &Ray| bvh.occluded(r, 1.0).then_some(0.0));
            best[i].0 = best[i].0.max(c.cpu);
            best[i].1 = best[i].1.max(a.cpu);
        }
    }
    for (i, v) in variants.iter().enumerate() {
        println!("{v:30} closest {:6.2}  any {:6.2}  Mrays/s/core", best[i].0 / 1e6, best[i].1 / 1e6);
    }
}
