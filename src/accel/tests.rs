use super::*;

/// `SeqRng` with the helpers this file needs.
struct Rng(crate::sampling::SeqRng);
impl Rng {
    fn new(seed: u64) -> Self {
        Rng(crate::sampling::SeqRng::new(seed))
    }
    fn f(&mut self) -> f32 {
        self.0.next_f32()
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    fn v(&mut self, a: f32, b: f32) -> Vec3 {
        Vec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
}

fn brute(tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (i, t) in tris.iter().enumerate() {
        let tri = Tri::new(t);
        if tri.is_degenerate() {
            continue;
        }
        let lim = best.map_or(t_max, |h| h.t);
        if let Some((t, b1, b2)) = tri.intersect(ray.o, ray.d, lim) {
            best = Some(tri.hit(i as u32, t, b1, b2));
        }
    }
    best
}

/// A hit's fields, floats as bits, for bit-for-bit comparisons.
fn hit_bits(h: &Hit) -> (u32, [u32; 9]) {
    let (p, n) = (h.p, h.n);
    let f = [h.t, h.b1, h.b2, p.x, p.y, p.z, n.x, n.y, n.z];
    (h.prim, f.map(f32::to_bits))
}

fn is_degenerate(t: &[Vec3; 3]) -> bool {
    Tri::new(t).is_degenerate()
}

/// Triangle soup: small and large triangles, axis-aligned ones, exact
/// duplicates, and (if `degenerate`) every kind of degenerate triangle.
fn soup(rng: &mut Rng, n: usize, degenerate: bool) -> Vec<[Vec3; 3]> {
    let mut tris = Vec::with_capacity(n);
    while tris.len() < n {
        let c = rng.v(-1.0, 1.0);
        let s = if rng.f() < 0.1 { 0.8 } else { 0.08 };
        let mut t = [c + rng.v(-s, s), c + rng.v(-s, s), c + rng.v(-s, s)];
        match rng.0.next_u32() % 16 {
            0 => {
                // Axis-aligned (flat bounding box).
                let z = t[0].z;
                t[1].z = z;
                t[2].z = z;
            }
            1 if !tris.is_empty() => {
                // Exact duplicate of an earlier triangle.
                t = tris[rng.0.next_u32() as usize % tris.len()];
            }
            2 if degenerate => t[1] = t[0],
            3 if degenerate => t[2] = t[0] + (t[1] - t[0]) * 2.0,
            4 if degenerate => t = [c, c, c],
            5 if degenerate => t[rng.0.next_u32() as usize % 3].y = f32::NAN,
            6 if degenerate => t[rng.0.next_u32() as usize % 3].x = f32::INFINITY,
            _ => {}
        }
        tris.push(t);
    }
    tris
}

fn random_ray(rng: &mut Rng) -> (Ray, f32) {
    let o = rng.v(-1.3, 1.3);
    let mut d = rng.v(-1.0, 1.0) * rng.range(0.1, 10.0);
    match rng.0.next_u32() % 8 {
        0 => d.x = 0.0,
        1 => {
            d.y = 0.0;
            d.z = -0.0;
        }
        _ => {}
    }
    let t_max = if rng.f() < 0.5 {
        f32::INFINITY
    } else {
        rng.range(0.0, 2.0)
    };
    (Ray::new(o, d), t_max)
}

/// Checks every instruction set this CPU has against the brute force; returns
/// the hits and ties of the last.
fn check_against_brute(tris: &[[Vec3; 3]], rays: usize, seed: u64) -> (usize, usize) {
    let mut bvh = Bvh::build(tris);
    check_structure(&bvh, tris);
    let mut out = (0, 0);
    for isa in Isa::available() {
        assert!(bvh.set_isa(isa));
        out = check_isa_against_brute(&bvh, tris, rays, seed);
    }
    out
}

fn check_isa_against_brute(
    bvh: &Bvh,
    tris: &[[Vec3; 3]],
    rays: usize,
    seed: u64,
) -> (usize, usize) {
    let mut rng = Rng::new(seed);
    let mut hits = 0;
    let mut ties = 0;
    for _ in 0..rays {
        let (ray, t_max) = random_ray(&mut rng);
        let want = brute(tris, &ray, t_max);
        let got = bvh.intersect(&ray, t_max);
        assert_eq!(bvh.occluded(&ray, t_max), want.is_some(), "{ray:?} {t_max}");
        match (want, got) {
            (None, None) => {}
            (Some(w), Some(g)) => {
                hits += 1;
                assert!(!is_degenerate(&tris[g.prim as usize]));
                assert!(g.t > 0.0 && g.t < t_max);
                assert!(
                    (w.t - g.t).abs() <= 1e-5 * w.t,
                    "t mismatch {w:?} {g:?} {ray:?}"
                );
                if w.prim != g.prim {
                    assert_eq!(w.t, g.t, "different prim and t: {w:?} {g:?}");
                    ties += 1;
                } else {
                    // The hit's point and normal, from the BVH's copy of the
                    // triangle, are those of the input triangle, bit for bit.
                    assert_eq!(hit_bits(&w), hit_bits(&g));
                }
                // Barycentrics reproduce the hit point.
                let [v0, v1, v2] = tris[g.prim as usize];
                let p = v0 + (v1 - v0) * g.b1 + (v2 - v0) * g.b2;
                let q = ray.at(g.t);
                assert!((p - q).length() < 1e-4 * (1.0 + q.length()), "{p} {q}");
                assert!(
                    (g.p - q).length() < 1e-4 * (1.0 + q.length()),
                    "{} {q}",
                    g.p
                );
            }
            _ => panic!("mismatch: brute {want:?} bvh {got:?} for {ray:?} t_max {t_max}"),
        }
    }
    (hits, ties)
}

/// Node bounds contain their children/triangles, every non-degenerate
/// triangle is referenced exactly once, and the stack bound holds.
fn check_structure(bvh: &Bvh, input: &[[Vec3; 3]]) {
    let expected: Vec<u32> = (0..input.len() as u32)
        .filter(|&i| !is_degenerate(&input[i as usize]))
        .collect();
    if expected.is_empty() {
        assert!(bvh.nodes.is_empty() && bvh.tris.is_empty());
        return;
    }
    assert!(bvh.stack_needed <= LARGE_STACK);
    let mut seen = vec![0u32; input.len()];
    let b = bvh.bounds();
    let mut stack = vec![(bvh.root, b.min, b.max)];
    let mut leaves = 0;
    let inside = |p: Vec3, min: Vec3, max: Vec3| {
        // (v0 + e1 may round differently from v1.)
        let tol = (p.abs() + 1.0) * 1e-6;
        min.cmple(p + tol).all() && max.cmpge(p - tol).all()
    };
    while let Some((r, min, max)) = stack.pop() {
        if r & LEAF != 0 {
            leaves += 1;
            let (first, count) = leaf_packets(r);
            for k in 0..count.div_ceil(4) as usize {
                let p = first + k;
                let valid = lane_mask(count - 4 * k as u32);
                let t = &bvh.tris[p];
                for lane in 0..4 {
                    let id = bvh.tris[p].ids[lane];
                    if valid & (1 << lane) == 0 {
                        assert_eq!(id, u32::MAX);
                        continue;
                    }
                    seen[id as usize] += 1;
                    let get = |v: &[Vec4; 3]| Vec3::new(v[0][lane], v[1][lane], v[2][lane]);
                    let (v0, e1, e2) = (get(&t.v0), get(&t.e1), get(&t.e2));
                    let tri = Tri::new(&input[id as usize]);
                    assert_eq!((v0, e1, e2), (tri.v0, tri.e1, tri.e2));
                    for p in [v0, v0 + e1, v0 + e2] {
                        assert!(inside(p, min, max));
                    }
                }
            }
        } else {
            let n = &bvh.nodes[r as usize];
            let mut used = 0;
            for lane in 0..WIDTH {
                let cmin = Vec3::new(n.b[0][lane], n.b[1][lane], n.b[2][lane]);
                let cmax = Vec3::new(n.b[3][lane], n.b[4][lane], n.b[5][lane]);
                if cmin.x == f32::INFINITY {
                    assert_eq!((cmin, cmax), (Vec3::INFINITY, Vec3::INFINITY));
                    continue; // unused slot
                }
                used += 1;
                assert!(min.cmple(cmin).all() && max.cmpge(cmax).all());
                stack.push((n.child[lane], cmin, cmax));
            }
            assert!(used >= 2);
        }
    }
    assert_eq!(leaves + bvh.nodes.len(), bvh.node_count());
    for (i, &s) in seen.iter().enumerate() {
        assert_eq!(s, !is_degenerate(&input[i]) as u32, "triangle {i}");
    }
}

#[test]
fn matches_brute_force_small_soup() {
    let mut rng = Rng::new(1);
    let tris = soup(&mut rng, 60, false);
    check_against_brute(&tris, 4000, 11);
}

#[test]
fn matches_brute_force_random_soups() {
    let mut total_hits = 0;
    for (seed, n) in [(2u64, 3000usize), (3, 1500), (4, 700)] {
        let mut rng = Rng::new(seed);
        let tris = soup(&mut rng, n, false);
        let (hits, _) = check_against_brute(&tris, 3000, seed * 7);
        total_hits += hits;
    }
    assert!(
        total_hits > 3000,
        "too few hits to be meaningful: {total_hits}"
    );
}

#[test]
fn matches_brute_force_with_degenerates() {
    let mut rng = Rng::new(5);
    let tris = soup(&mut rng, 2500, true);
    assert!(tris.iter().filter(|t| is_degenerate(t)).count() > 500);
    let (hits, _) = check_against_brute(&tris, 4000, 55);
    assert!(hits > 1000);
}

#[test]
fn matches_brute_force_large_parallel_build() {
    // Large enough that the builder takes its parallel path.
    let mut rng = Rng::new(6);
    let tris = soup(&mut rng, 40_000, true);
    check_against_brute(&tris, 500, 66);
}

/// The SAH collapse fills the 8-wide nodes and makes some leaves of two
/// packets (which the structure check and the brute force above cover).
#[test]
fn collapse_fills_nodes_and_merges_leaves() {
    let mut rng = Rng::new(7);
    let tris = soup(&mut rng, 40_000, false);
    let bvh = Bvh::build(&tris);
    check_structure(&bvh, &tris);
    let (nodes, leaves, packets) = bvh.shape();
    assert!(packets > leaves, "no leaf of two packets");
    let fill = (nodes - 1 + leaves) as f64 / nodes as f64;
    assert!(fill > 6.0, "{fill} children per node");
}

/// Every instruction set returns the same hits, bit for bit, as the baseline
/// (on a soup with degenerates and on a large parallel-built one, with the
/// axis-aligned and signed-zero directions of `random_ray`).
#[test]
fn instruction_sets_agree_bit_for_bit() {
    let isas = Isa::available();
    assert!(isas.contains(&Isa::Base) && Isa::chosen().is_available());
    #[cfg(target_arch = "x86_64")]
    assert_eq!(
        isas.contains(&Isa::Avx2),
        is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
    );
    let mut rng = Rng::new(11);
    for n in [300, 40_000] {
        let tris = soup(&mut rng, n, true);
        let mut bvh = Bvh::build(&tris);
        let rays: Vec<(Ray, f32)> = (0..20_000).map(|_| random_ray(&mut rng)).collect();
        let run = |bvh: &Bvh| {
            rays.iter()
                .map(|(r, t)| {
                    let h = bvh.intersect(r, *t);
                    (h.map(|h| hit_bits(&h)), bvh.occluded(r, *t))
                })
                .collect::<Vec<_>>()
        };
        assert!(bvh.set_isa(Isa::Base));
        let base = run(&bvh);
        assert!(base.iter().filter(|h| h.0.is_some()).count() > 1000);
        for &isa in &isas[1..] {
            assert!(bvh.set_isa(isa));
            assert!(
                run(&bvh) == base,
                "{} differs from the baseline",
                isa.name()
            );
        }
    }
}

#[test]
fn coincident_centroids_and_deep_distributions() {
    // Many identical triangles: no SAH split exists, median splits are used.
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let same = vec![t; 1000];
    let bvh = Bvh::build(&same);
    check_structure(&bvh, &same);
    let hit = bvh
        .intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), f32::INFINITY)
        .unwrap();
    assert_eq!(hit.t, 1.0);
    // Geometrically spaced triangles: the SAH would peel one off at a time;
    // the depth limit must keep the tree shallow enough for the stack.
    let deep = geometric_strip(3000);
    check_against_brute(&deep, 1000, 7);
    // Nested triangles of geometrically growing size.
    let nested: Vec<[Vec3; 3]> = (0..3000)
        .map(|i| {
            let s = 1.003f32.powi(i);
            let z = Vec3::Z * (i as f32 * 1e-3);
            [z, Vec3::X * s + z, Vec3::Y * s + z]
        })
        .collect();
    check_against_brute(&nested, 1000, 8);
    let bvh = Bvh::build(&deep);
    for i in (0..3000).step_by(37) {
        let [v0, v1, v2] = deep[i];
        let c = (v0 + v1 + v2) / 3.0;
        let r = Ray::new(c + Vec3::Z, -Vec3::Z);
        let h = bvh.intersect(&r, f32::INFINITY);
        let h =
            h.unwrap_or_else(|| panic!("{i} {:?} {:?}", deep[i], brute(&deep, &r, f32::INFINITY)));
        assert_eq!(h.prim, i as u32);
    }
}

#[test]
fn empty_input() {
    let bvh = Bvh::build(&[]);
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(bvh.intersect(&ray, f32::INFINITY).is_none());
    assert!(!bvh.occluded(&ray, f32::INFINITY));
    assert!(bvh.bounds().is_empty());
    assert_eq!(bvh.node_count(), 0);
    // Only degenerate triangles: also empty.
    let bvh = Bvh::build(&[[Vec3::ZERO, Vec3::X, Vec3::X * 2.0], [Vec3::ONE; 3]]);
    assert!(bvh
        .intersect(&Ray::new(-Vec3::X, Vec3::X), f32::INFINITY)
        .is_none());
    assert!(!bvh.occluded(&Ray::new(-Vec3::X, Vec3::X), f32::INFINITY));
}

#[test]
fn single_triangle_edge_cases() {
    let tri = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
    let bvh = Bvh::build(&tri);
    assert_eq!(bvh.node_count(), 1);
    assert_eq!(bvh.nodes.len(), 0);
    assert_eq!(bvh.bounds().min, Vec3::ZERO);
    assert_eq!(bvh.bounds().max, Vec3::new(1.0, 1.0, 0.0));
    let down = Ray::new(Vec3::new(0.25, 0.5, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let h = bvh.intersect(&down, f32::INFINITY).unwrap();
    assert_eq!((h.t, h.prim, h.b1, h.b2), (1.0, 0, 0.25, 0.5));
    // Hit exactly at t_max is not reported; just beyond it is.
    assert!(bvh.intersect(&down, 1.0).is_none());
    assert!(!bvh.occluded(&down, 1.0));
    assert!(bvh.intersect(&down, 1.000001).is_some());
    assert!(bvh.occluded(&down, 1.000001));
    // Back side (double-sided), and non-normalised direction: t in units of d.
    let up = Ray::new(Vec3::new(0.25, 0.5, -2.0), Vec3::new(0.0, 0.0, 4.0));
    assert_eq!(bvh.intersect(&up, f32::INFINITY).unwrap().t, 0.5);
    // Triangle behind the origin.
    let away = Ray::new(Vec3::new(0.25, 0.5, 1.0), Vec3::Z);
    assert!(bvh.intersect(&away, f32::INFINITY).is_none());
    assert!(!bvh.occluded(&away, f32::INFINITY));
    // Origin on the triangle: t = 0 is excluded.
    let on = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z);
    assert!(bvh.intersect(&on, f32::INFINITY).is_none());
    // Ray in the triangle's plane (parallel), through its interior.
    for d in [Vec3::X, Vec3::new(1.0, 1.0, 0.0), -Vec3::Y] {
        let par = Ray::new(Vec3::new(0.2, 0.2, 0.0) - d, d);
        assert!(bvh.intersect(&par, f32::INFINITY).is_none());
        assert!(!bvh.occluded(&par, f32::INFINITY));
    }
    // Parallel and just above the plane.
    let above = Ray::new(Vec3::new(-1.0, 0.2, 1e-3), Vec3::X);
    assert!(bvh.intersect(&above, f32::INFINITY).is_none());
    // Vertices and edges are inside (closed triangle). (Rays with a zero
    // direction component whose origin lies exactly in a face plane of a node's
    // box may miss edges/vertices on that face; see the module docs.)
    let d = Vec3::new(0.125, 0.25, -1.0);
    for p in [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(0.5, 0.0, 0.0),
    ] {
        let r = Ray::new(p - d, d);
        let t = bvh.intersect(&r, f32::INFINITY).map(|h| h.t);
        assert!((t.unwrap() - 1.0).abs() < 1e-6, "{p}");
    }
    // Just outside an edge.
    let r = Ray::new(Vec3::new(0.5, -1e-6, 1.0), -Vec3::Z);
    assert!(bvh.intersect(&r, f32::INFINITY).is_none());
    // Zero direction: never a hit.
    let r = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::ZERO);
    assert!(bvh.intersect(&r, f32::INFINITY).is_none());
}

#[test]
fn is_send_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Bvh>();
    assert_send_sync::<Hit>();
}

/// `n` triangles along the x axis whose sizes and gaps grow geometrically: a deep tree.
fn geometric_strip(n: i32) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|i| {
            let x = 1.001f32.powi(i * 4) - 1.0;
            let s = 1e-3 * (1.0 + x);
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + s, 0.0, 0.0),
                Vec3::new(x, s, 0.0),
            ]
        })
        .collect()
}

#[test]
fn interleaved_queries_answer_as_single_ones_bit_for_bit() {
    // `Bvh::trace` against `intersect` / `occluded`, on every instruction set, with
    // closest-hit and any-hit queries mixed in one batch and batches of every length,
    // interleaved and one after another, with every traversal stack size (each is a
    // function of its own in `trace`).
    let mut rng = Rng::new(23);
    let mut stacks = [false; 3];
    for n in [1, 300, 40_000, 0] {
        // n = 0: the geometric strip, whose tree needs the large stack, with rays aimed
        // at its triangles (random rays would rarely meet them).
        let (tris, rays): (_, Vec<(Ray, f32)>) = if n > 0 {
            let tris = soup(&mut rng, n, true);
            (tris, (0..5_000).map(|_| random_ray(&mut rng)).collect())
        } else {
            let tris = geometric_strip(3000);
            let rays = (0..5_000)
                .map(|i| {
                    let [v0, v1, v2] = tris[i * 7 % tris.len()];
                    let c = (v0 + v1 + v2) / 3.0 + (v1 - v0) * rng.range(-0.5, 0.5);
                    let d = Vec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), -1.0);
                    (Ray::new(c + Vec3::Z, d), f32::INFINITY)
                })
                .collect();
            (tris, rays)
        };
        let mut bvh = Bvh::build(&tris);
        let size = bvh.stack_needed;
        stacks[(size > TINY_STACK) as usize + (size > SMALL_STACK) as usize] = true;
        let queries: Vec<RayQuery> = rays
            .iter()
            .enumerate()
            .map(|(i, &(r, t))| {
                if i % 3 == 0 {
                    RayQuery::Occluded(r, t)
                } else {
                    RayQuery::Closest(r, t)
                }
            })
            .collect();
        let key = |a: &RayAnswer| match *a {
            RayAnswer::Closest(h) => (h.map(|h| hit_bits(&h)), false),
            RayAnswer::Occluded(o) => (None, o),
        };
        for (isa, il) in Isa::available()
            .into_iter()
            .flat_map(|i| [(i, true), (i, false)])
        {
            assert!(bvh.set_isa(isa));
            // Interleaved even on small trees, and one after another even on large ones.
            bvh.set_interleaving(Some(il));
            let single: Vec<_> = queries
                .iter()
                .map(|q| match *q {
                    RayQuery::Closest(r, t) => key(&RayAnswer::Closest(bvh.intersect(&r, t))),
                    RayQuery::Occluded(r, t) => key(&RayAnswer::Occluded(bvh.occluded(&r, t))),
                })
                .collect();
            if n != 1 {
                assert!(single.iter().filter(|k| k.0.is_some()).count() > 500);
                assert!(single.iter().filter(|k| k.1).count() > 100);
            }
            // Batches of uneven lengths (1, 2, ..., BATCH + 3, ...), over the whole list.
            let mut answers = vec![RayAnswer::Occluded(false); queries.len()];
            let (mut at, mut len) = (0, 1);
            while at < queries.len() {
                let end = (at + len).min(queries.len());
                bvh.trace(&queries[at..end], &mut answers[at..end]);
                at = end;
                len = len % (BATCH + 3) + 1;
            }
            let batched: Vec<_> = answers.iter().map(key).collect();
            assert!(
                batched == single,
                "{} (interleaved: {il}): trace differs from single queries",
                isa.name()
            );
        }
    }
    assert_eq!(stacks, [true; 3], "every stack size tried");
}

/// The copy onto huge pages keeps every element, on arrays above and below its 4 MiB
/// threshold and across the 2 MiB pages it releases before writing.
#[test]
fn huge_page_copy_keeps_the_contents() {
    for n in [0usize, 1, 1000, (5 << 20) / 8 + 3] {
        let v: Vec<u64> = (0..n as u64)
            .map(|i| i.wrapping_mul(0x9e37_79b9_7f4a_7c15))
            .collect();
        let w = on_huge_pages(v.clone());
        assert_eq!(w.len(), n);
        assert!(w == v, "{n} elements: the copy differs");
    }
}
