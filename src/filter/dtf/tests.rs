//! DTF's weights, allocation, combination and limits.
use super::*;
use crate::film::Film;

/// A pixel with mean `mean`, per-channel standard deviation `sd` and `n` samples.
fn px(mean: [f64; 3], sd: [f64; 3], n: u32) -> PixelStats {
    let k = n.saturating_sub(1) as f64;
    PixelStats::from_moments(
        n,
        mean,
        [sd[0] * sd[0] * k, sd[1] * sd[1] * k, sd[2] * sd[2] * k],
    )
}

fn film(w: u32, h: u32, f: impl Fn(u32, u32) -> PixelStats) -> Film {
    let mut film = Film::new(w, h).unwrap();
    for y in 0..h {
        for x in 0..w {
            let i = film.index(x, y);
            film.pixels[i] = f(x, y);
        }
    }
    film
}

/// Deterministic hash noise in [0, 1).
fn hash(x: u32, y: u32, salt: u32) -> f64 {
    let mut v = x
        .wrapping_mul(0x9E37_79B9)
        .wrapping_add(y.wrapping_mul(0x85EB_CA6B))
        .wrapping_add(salt.wrapping_mul(0xC2B2_AE35));
    v ^= v >> 16;
    v = v.wrapping_mul(0x7FEB_352D);
    v ^= v >> 15;
    v = v.wrapping_mul(0x846C_A68B);
    v ^= v >> 16;
    v as f64 / 4_294_967_296.0
}

fn grey(v: f64) -> [f64; 3] {
    [v, v, v]
}

#[test]
fn norm_and_sigma() {
    assert_eq!(color_norm([1.0, -2.0, 0.5]), 3.5);
    let s = px([0.5, 0.3, 0.2], [0.1, 0.02, 0.03], 50);
    assert!((sigma(&s) - 0.15).abs() < 1e-12);
    assert_eq!(sigma(&px([1.0; 3], [0.1; 3], 1)), 0.0);
}

#[test]
fn classify_rounds_up_and_clamps() {
    // the paper's categories (the default fills their steps in)
    let c = [0, 1, 10, 20, 50, 100, 200, 500];
    let cases = [
        (-25.0, 0),
        (0.0, 0),
        (0.5, 1),
        (1.0, 1),
        (1.01, 10),
        (10.0, 10),
        (20.5, 50),
        (499.0, 500),
        // past the largest category the classes double: 1000, 2000, ... up to N_HARD_MAX
        (501.0, 1000),
        (1999.0, 2000),
        (1e30, N_HARD_MAX),
        (f64::INFINITY, N_HARD_MAX),
        (f64::NAN, 500),
    ];
    for (v, want) in cases {
        assert_eq!(classify(v, &c), want, "classify({v})");
    }
    assert_eq!(classify(-1.0, &[5, 7]), 5);
}

#[test]
fn samples_follow_formula_and_categories() {
    let c = DtfParams::default().categories;
    // (3 * 0.1 / (0.03 * 1))^2 - 50 = 100 - 50 = 50 -> 50
    assert!((samples_for_error_raw(0.1, 1.0, 50, 0.03) - 50.0).abs() < 1e-9);
    assert_eq!(samples_for_error(0.1, 1.0, 50, 0.03, &c), 50);
    // (3 * 0.12 / 0.03)^2 - 50 = 144 - 50 = 94 -> 100
    assert!((samples_for_error_raw(0.12, 1.0, 50, 0.03) - 94.0).abs() < 1e-9);
    assert_eq!(samples_for_error(0.12, 1.0, 50, 0.03, &c), 100);
    // (3 * 0.05 / 0.03)^2 - 50 = 25 - 50 < 0 -> 0
    assert_eq!(samples_for_error(0.05, 1.0, 50, 0.03, &c), 0);
    // (3 * 0.3 / 0.03)^2 - 50 = 850 -> the doubled class 1000
    assert_eq!(samples_for_error(0.3, 1.0, 50, 0.03, &c), 1000);
    // relative: doubling the colour quarters the samples: (3*0.2/(0.03*2))^2 - 10 = 90
    assert!((samples_for_error_raw(0.2, 2.0, 10, 0.03) - 90.0).abs() < 1e-9);
    // black pixels
    assert_eq!(samples_for_error(0.0, 0.0, 50, 0.03, &c), 0);
    assert_eq!(samples_for_error(0.1, 0.0, 50, 0.03, &c), N_HARD_MAX);

    // Through the film: sigma = 0.1 + 0.02 + 0.03 = 0.15, ||C_d|| = 1,
    // (3 * 0.15 / 0.03)^2 - 50 = 175 -> 200.
    let f = film(2, 1, |x, _| {
        if x == 0 {
            px([0.5, 0.3, 0.2], [0.1, 0.02, 0.03], 50)
        } else {
            px([0.0; 3], [0.0; 3], 50)
        }
    });
    // the paper's raw formula (no floors): the black pixel needs nothing more
    let eps = DtfParams {
        eps_r: Some(0.03),
        ..Default::default()
    };
    let raw = DtfParams {
        floor: 0.0,
        relative_sigma_floor: 0.0,
        ..eps.clone()
    };
    assert_eq!(allocate_relative(&f, &raw).unwrap(), vec![200, 0]);
    // with the default floors the black pixel still gets samples (it may not be black)
    assert!(allocate_relative(&f, &eps).unwrap()[1] > 0);
}

#[test]
fn budget_is_spent_within_tolerance() {
    let (w, h) = (64u32, 48u32);
    let f = film(w, h, |x, y| {
        let c = 0.05 + hash(x, y, 1) * 2.0;
        let sd = 0.01 + hash(x, y, 2).powi(2) * 3.0;
        px(grey(c), grey(sd), 40)
    });
    // the raw proportionality: no floors, no clipping; every allocation rule
    for allocation in [Allocation::Paper, Allocation::Mse, Allocation::RelMse] {
        let params = DtfParams {
            floor: 0.0,
            relative_sigma_floor: 0.0,
            max_weight_ratio: 0.0,
            allocation,
            ..Default::default()
        };
        for spp in [3.0, 17.0, 43.0, 120.0] {
            let a = allocate_budget(&f, &params, spp).unwrap();
            let spent: u64 = a.iter().map(|&v| v as u64).sum();
            let budget = spp * (w * h) as f64;
            let rel = (spent as f64 - budget).abs() / budget;
            assert!(rel < 0.02, "spp {spp}: spent {spent} of {budget}");
            assert!(a
                .iter()
                .all(|v| params.categories.contains(v) || v % 500 == 0));
            // Monotone in w (e.g. the paper's sigma^2 / ||C_d||).
            let wv: Vec<f64> = f
                .pixels
                .iter()
                .map(|s| allocation.weight(sigma(s), color_norm(s.mean())))
                .collect();
            for i in 0..a.len() {
                for j in 0..a.len() {
                    if wv[i] < wv[j] {
                        assert!(a[i] <= a[j], "{allocation:?} spp {spp}: w order broken");
                    }
                }
            }
        }
    }
    let params = DtfParams {
        floor: 0.0,
        relative_sigma_floor: 0.0,
        max_weight_ratio: 0.0,
        ..Default::default()
    };
    // Beyond the largest category the classes go on doubling: large budgets are spent too.
    let a = allocate_budget(&f, &params, 5000.0).unwrap();
    let spent: u64 = a.iter().map(|&v| v as u64).sum();
    assert!(
        (spent as f64 / (5000.0 * (w * h) as f64) - 1.0).abs() < 0.05,
        "{spent}"
    );
    // Zero budget: the smallest category.
    let a = allocate_budget(&f, &params, 0.0).unwrap();
    assert!(a.iter().all(|&v| v == 0));
    // Noise-free image: uniform fallback.
    let flat = film(10, 10, |_, _| px(grey(1.0), grey(0.0), 40));
    let a = allocate_budget(&flat, &params, 20.0).unwrap();
    assert!(a.iter().all(|&v| v == 20), "{a:?}");
}

fn setup(
    w: u32,
    h: u32,
    dep: impl Fn(u32, u32) -> PixelStats,
    ind: impl Fn(u32, u32) -> PixelStats,
    alloc: impl Fn(u32, u32) -> u32,
    params: &DtfParams,
) -> Dtf {
    let d = film(w, h, dep);
    let i = film(w, h, ind);
    let a: Vec<u32> = (0..w * h).map(|p| alloc(p % w, p / w)).collect();
    Dtf::new(&d, &i, &a, params).unwrap()
}

/// `CdDisplay::Mse`: C_d''s share of the display is V_i / (V_d + V_i) with V_d shared by
/// the region, which in a flat region is n / (n + M_eff N), M_eff = 1 / sum f*^2: the
/// paper's n / (n + N) for a lone pixel, less as the region grows.
#[test]
fn cd_share_is_the_paper_share_at_the_region_effective_count() {
    let (n, big_n) = (16u32, 24u32);
    let flat = |m_max| {
        setup(
            9,
            9,
            |_, _| px(grey(0.5), grey(0.3), n),
            |_, _| px(grey(0.5), grey(0.3), big_n),
            |_, _| big_n,
            &DtfParams {
                m_max,
                ..Default::default()
            },
        )
    };
    let paper = n as f64 / (n + big_n) as f64;
    for m_max in [1, 2, 4, 8] {
        let dtf = flat(m_max);
        let r = dtf.weights(4, 4);
        let sum_f2: f64 = r.weights.iter().map(|w| w.2 * w.2).sum();
        let a = dtf.cd_share(
            4 * 9 + 4,
            r.weights
                .iter()
                .map(|&(x, y, f)| (y as usize * 9 + x as usize, f)),
        );
        let want = n as f64 / (n as f64 + big_n as f64 / sum_f2);
        assert!((a - want).abs() < 1e-12, "m_max {m_max}: {a} vs {want}");
        assert!(a <= paper + 1e-15);
        if m_max == 1 {
            assert!((a - paper).abs() < 1e-15);
        } else {
            assert!(r.m > 1 && a < 0.8 * paper, "m_max {m_max}: m {} a {a}", r.m);
        }
    }
    // Without a usable variance (sigma = 0: no error to weigh) the share is the paper's.
    let zero = setup(
        5,
        5,
        |_, _| px(grey(0.5), grey(0.0), n),
        |_, _| px(grey(0.5), grey(0.3), big_n),
        |_, _| big_n,
        &DtfParams::default(),
    );
    assert!((zero.cd_share(12, [(12usize, 1.0)].into_iter()) - paper).abs() < 1e-15);
}

#[test]
fn flat_region_pixel_weights_hand_computed() {
    // Flat C_d: Delta = 0, f = 1/M, f* proportional to the pyramid d = m/sqrt2 - r.
    let params = DtfParams {
        m_max: 2,
        ..Default::default()
    };
    let dtf = setup(
        5,
        5,
        |_, _| px(grey(1.0), grey(0.2), 50),
        |_, _| px(grey(1.0), grey(0.2), 10),
        |_, _| 10,
        &params,
    );
    let r = dtf.weights(2, 2);
    assert_eq!(r.m, 2);
    // Even window: p at offset floor((2-1)/2) = 0 from the top-left corner.
    let pos: Vec<(u32, u32)> = r.weights.iter().map(|w| (w.0, w.1)).collect();
    assert_eq!(pos, vec![(2, 2), (3, 2), (2, 3), (3, 3)]);
    let s2 = std::f64::consts::SQRT_2;
    let (d0, d1) = (s2, s2 - 1.0);
    let sum = d0 + 2.0 * d1; // the diagonal pixel sits at the pyramid's edge: d = 0
    let want = [d0 / sum, d1 / sum, d1 / sum, 0.0];
    for (got, want) in r.weights.iter().zip(want) {
        assert!((got.2 - want).abs() < 1e-12, "{:?} vs {want}", r.weights);
    }
}

#[test]
fn constant_image_passes_unchanged() {
    for kernel in [Kernel::Pyramid, Kernel::Gaussian] {
        for clamp in [Clamp::Paper, Clamp::ActiveSet] {
            let params = DtfParams {
                kernel,
                clamp,
                m_max: 4,
                ..Default::default()
            };
            let dtf = setup(
                9,
                7,
                |_, _| px([0.3, 0.5, 0.7], [0.2, 0.1, 0.3], 50),
                |_, _| px([0.35, 0.45, 0.75], [0.2, 0.1, 0.3], 20),
                |_, _| 20,
                &params,
            );
            let out = dtf.run();
            for (i, c) in out.filtered.data.iter().enumerate() {
                for (ch, want) in [0.35f32, 0.45, 0.75].iter().enumerate() {
                    assert!((c[ch] - want).abs() < 1e-6, "pixel {i}: {c:?}");
                }
            }
            // And it did form regions: interior pixels reach m_max.
            assert_eq!(out.m[3 * 9 + 4], 4, "{kernel:?} {clamp:?}");
            // Combined: C_d rescaled to phase 2's brightness (g = 0.35 / 0.3 in every
            // window), so (g C_d * 50 + C_i * 20) / 70 = C_i, whether g C_d is filtered
            // (the default), the pixel's own, or left out.
            assert!((out.combined.data[10][0] as f64 - 0.35).abs() < 1e-6);
            for cd_display in [CdDisplay::Scaled, CdDisplay::Filtered, CdDisplay::None] {
                let p = DtfParams {
                    cd_display,
                    ..params.clone()
                };
                let o = setup(
                    9,
                    7,
                    |_, _| px([0.3, 0.5, 0.7], [0.2, 0.1, 0.3], 50),
                    |_, _| px([0.35, 0.45, 0.75], [0.2, 0.1, 0.3], 20),
                    |_, _| 20,
                    &p,
                )
                .run();
                assert!(
                    (o.combined.data[10][0] as f64 - 0.35).abs() < 1e-6,
                    "{cd_display:?}"
                );
            }
            // The paper's display: (C_d * 50 + C_i * 20) / 70.
            let paper = DtfParams {
                paper_display: true,
                ..params.clone()
            };
            let dtf = setup(
                9,
                7,
                |_, _| px([0.3, 0.5, 0.7], [0.2, 0.1, 0.3], 50),
                |_, _| px([0.35, 0.45, 0.75], [0.2, 0.1, 0.3], 20),
                |_, _| 20,
                &paper,
            );
            let want = (0.3 * 50.0 + 0.35 * 20.0) / 70.0;
            assert!((dtf.run().combined.data[10][0] as f64 - want).abs() < 1e-6);
        }
    }
}

#[test]
fn edge_between_flat_regions_is_not_smeared() {
    // Left half C_d = 1, right half C_d = 0.2 (Delta = 2.4 across the edge),
    // sigma = 0.3, N = 10. Left C_i noisy in [0.9, 1.1], right C_i exactly 0.2.
    for clamp in [Clamp::Paper, Clamp::ActiveSet] {
        let params = DtfParams {
            clamp,
            ..Default::default()
        };
        let left = |x: u32| x < 6;
        let dtf = setup(
            12,
            8,
            |x, _| px(grey(if left(x) { 1.0 } else { 0.2 }), grey(0.1), 50),
            |x, y| {
                let v = if left(x) {
                    0.9 + 0.2 * hash(x, y, 7)
                } else {
                    0.2
                };
                px(grey(v), grey(0.1), 10)
            },
            |_, _| 10,
            &params,
        );
        for y in 0..8 {
            for x in 0..12 {
                let r = dtf.weights(x, y);
                for &(qx, _, wq) in &r.weights {
                    if left(qx) != left(x) {
                        assert_eq!(wq, 0.0, "({x},{y}) takes from ({qx}) across the edge");
                    }
                }
            }
        }
        let out = dtf.run();
        let mut filtered_somewhere = false;
        for y in 0..8 {
            for x in 0..12 {
                let c = out.filtered.get(x, y)[0];
                if left(x) {
                    assert!((0.9..=1.1).contains(&c), "({x},{y}) = {c}");
                    filtered_somewhere |= out.m[(y * 12 + x) as usize] > 1;
                } else {
                    assert!((c - 0.2).abs() < 1e-6, "({x},{y}) = {c}");
                }
            }
        }
        assert!(filtered_somewhere);
    }
}

#[test]
fn weights_non_negative_and_normalised_everywhere() {
    let (w, h) = (13u32, 11u32);
    // the paper's categories: neighbours up to 50x apart, so the stop rule acts
    let cats = [0u32, 1, 10, 20, 50, 100, 200, 500];
    for kernel in [Kernel::Pyramid, Kernel::Gaussian] {
        for clamp in [Clamp::Paper, Clamp::ActiveSet] {
            let params = DtfParams {
                kernel,
                clamp,
                m_max: 5,
                stop_ratio: Some(5.0),
                ..Default::default()
            };
            let alloc = |x: u32, y: u32| cats[1 + (hash(x, y, 3) * 4.0) as usize];
            let dtf = setup(
                w,
                h,
                |x, y| {
                    // blocks of colour, some noise, a few zero-sigma pixels
                    let base = if (x / 4 + y / 3) % 2 == 0 { 0.8 } else { 0.3 };
                    let sd = if hash(x, y, 4) < 0.1 { 0.0 } else { 0.5 };
                    px(
                        [base + 0.05 * hash(x, y, 5), base, base * 0.5],
                        grey(sd),
                        50,
                    )
                },
                |x, y| {
                    // a few pixels lost all independent samples
                    let n = if hash(x, y, 6) < 0.05 { 0 } else { alloc(x, y) };
                    px(grey(hash(x, y, 8)), grey(0.1), n)
                },
                alloc,
                &params,
            );
            let mut sizes = [0usize; 6];
            for y in 0..h {
                for x in 0..w {
                    let r = dtf.weights(x, y);
                    let sum: f64 = r.weights.iter().map(|q| q.2).sum();
                    assert!((sum - 1.0).abs() < 1e-12, "({x},{y}) sum {sum}");
                    assert_eq!((r.weights[0].0, r.weights[0].1), (x, y));
                    let f0 = r.primary_weight();
                    for &(qx, qy, wq) in &r.weights {
                        assert!(wq >= 0.0 && wq <= f0 + 1e-15, "({x},{y}): {wq} > {f0}");
                        assert!(qx < w && qy < h);
                        let off = ((r.m - 1) / 2) as i64;
                        let (dx, dy) = (qx as i64 - x as i64, qy as i64 - y as i64);
                        assert!((-off..=r.m as i64 - 1 - off).contains(&dx));
                        assert!((-off..=r.m as i64 - 1 - off).contains(&dy));
                        assert!(
                            alloc(qx, qy) as f64
                                <= alloc(x, y) as f64
                                    * params.stop_ratio.map_or(f64::INFINITY, f64::from)
                        );
                    }
                    sizes[r.m as usize] += 1;
                }
            }
            // The test image exercises several window sizes.
            assert!(
                sizes.iter().filter(|&&c| c > 0).count() >= 3,
                "{kernel:?} {clamp:?}: {sizes:?}"
            );
        }
    }
}

#[test]
fn larger_neighbour_category_stops_region() {
    // Neighbour (3, 2) has N = 100, ten times the others' 10: beyond a tolerance of 5x,
    // so it stops regions as in the paper.
    let build = |big: u32, params: &DtfParams| {
        setup(
            6,
            6,
            |_, _| px(grey(1.0), grey(0.3), 50),
            |_, _| px(grey(1.0), grey(0.3), 10),
            move |x, y| if (x, y) == (3, 2) { big } else { 10 },
            params,
        )
    };
    let four = DtfParams {
        m_max: 4,
        stop_ratio: Some(5.0),
        ..Default::default()
    };
    for (big, params) in [
        (100, four.clone()),
        (
            20,
            DtfParams {
                stop_ratio: Some(1.0),
                ..four.clone()
            },
        ),
    ] {
        let dtf = build(big, &params);
        // (2, 2): its 2x2 window already holds (3, 2).
        assert_eq!(dtf.weights(2, 2).m, 1);
        // (1, 2): the 2x2 (x 1..=2) and 3x3 (x 0..=2) windows are fine; the 4x4 one
        // (x 0..=3) holds (3, 2) and stops the growth.
        assert_eq!(dtf.weights(1, 2).m, 3);
        // (3, 2) itself may take from its smaller-N neighbours.
        assert_eq!(dtf.weights(3, 2).m, 4);
    }
    // One category step (20 against 10) is within the noise of sigma^2 from n samples:
    // 5x tolerates it, the paper's rule (ratio 1) does not.
    let dtf = build(20, &four);
    assert_eq!(dtf.weights(2, 2).m, 4);
    // Without a stop ratio (the default) N does not stop regions at all.
    let none = DtfParams {
        stop_ratio: None,
        ..four.clone()
    };
    let dtf = build(100, &none);
    assert_eq!((dtf.weights(2, 2).m, dtf.weights(1, 2).m), (4, 4));
}

#[test]
fn top_up_asks_for_what_the_samples_so_far_need() {
    // eps_r = 0.1, no floors: a pixel with ||C|| = 3 (grey 1), sigma = 3 * 0.3 = 0.9 and
    // 100 samples needs (3 * 0.9 / (0.1 * 3))^2 = 81 in all: nothing more. With
    // sigma = 3 * 1.0 it needs 900, i.e. 800 more, classified up to 1000.
    let params = DtfParams {
        eps_r: Some(0.1),
        floor: 0.0,
        ..Default::default()
    };
    let f = film(2, 1, |x, _| {
        px(grey(1.0), grey(if x == 0 { 0.3 } else { 1.0 }), 100)
    });
    assert_eq!(top_up(&f, &params).unwrap(), vec![0, 1000]);
    // A pixel whose samples all agreed needs nothing.
    let f = film(1, 1, |_, _| px(grey(1.0), grey(0.0), 100));
    assert_eq!(top_up(&f, &params).unwrap(), vec![0]);
}

#[test]
fn cost_aware_allocation_follows_sigma_over_sqrt_cost() {
    // Two equal pixels, the second's samples four times as costly: N ∝ sigma / sqrt(c)
    // gives it half the samples (the paper's rule ignores the cost).
    let f = film(2, 1, |_, _| px(grey(1.0), grey(0.5), 16));
    let params = DtfParams {
        categories: (0..=1000).collect(),
        floor: 0.0,
        ..Default::default()
    };
    let cost = [1.0, 4.0];
    let a = allocate_budget_costed(&f, &params, 300.0, Some(&cost)).unwrap();
    assert!((a[0] as f64 / a[1] as f64 - 2.0).abs() < 0.02, "{a:?}");
    assert!((a[0] + a[1]) as i64 - 600 <= 1, "{a:?}");
    let paper = DtfParams {
        allocation: Allocation::Paper,
        ..params.clone()
    };
    let a = allocate_budget_costed(&f, &paper, 300.0, Some(&cost)).unwrap();
    assert_eq!(a[0], a[1]);
    // A cost table of the wrong size is an error, not a panic.
    assert!(allocate_budget_costed(&f, &params, 300.0, Some(&[1.0])).is_err());
}

#[test]
fn guard_keeps_apart_what_phase_1_missed() {
    // Phase 1 saw one flat field; phase 2 shows rows y < 3 at 1.0 and y >= 3 at 0.3,
    // far beyond their standard errors (0.3 / sqrt(1000)).
    let build = |guard: f32| {
        setup(
            8,
            8,
            |_, _| px(grey(0.5), grey(0.3), 16),
            |_, y| px(grey(if y < 3 { 1.0 } else { 0.3 }), grey(0.3), 1000),
            |_, _| 1000,
            &DtfParams {
                guard,
                ..Default::default()
            },
        )
    };
    let across = |r: &Region| {
        r.weights
            .iter()
            .filter(|q| q.1 >= 3)
            .map(|q| q.2)
            .sum::<f64>()
    };
    // Without the guard, pixel (4, 2) averages in rows 3 and 4; with it, none of them.
    assert!(across(&build(0.0).weights(4, 2)) > 0.1);
    assert_eq!(across(&build(3.0).weights(4, 2)), 0.0);
    // Within its own rows the guard still lets the filter work.
    let r = build(3.0).weights(4, 2);
    assert!(r.primary_weight() < 0.5, "f*[0] = {}", r.primary_weight());
}

#[test]
fn top_up_budget_fits_the_budget_and_follows_the_weights() {
    // Three pixels with sigma 0.1, 0.2, 0.4 (grey 1), each already holding 10 samples;
    // 60 more per pixel on average. Fine categories: the totals follow N ∝ sigma.
    let f = film(3, 1, |x, _| px(grey(1.0), grey(0.1 * (1 << x) as f64), 50));
    let params = DtfParams {
        categories: (0..=1000).collect(),
        floor: 0.0,
        ..Default::default()
    };
    let have = [10, 10, 10];
    let e = top_up_budget(&f, &have, &params, 60.0, None).unwrap();
    let spent: u32 = e.iter().sum();
    assert!((177..=180).contains(&spent), "{e:?}");
    // totals (10 + e) in ratio 1 : 2 : 4 (to one sample)
    let t: Vec<f64> = e.iter().map(|&v| (v + 10) as f64).collect();
    assert!(
        (t[1] / t[0] - 2.0).abs() < 0.1 && (t[2] / t[0] - 4.0).abs() < 0.1,
        "{t:?}"
    );
    // a pixel that already holds more than its share gets nothing
    let e = top_up_budget(&f, &[10, 10, 1000], &params, 30.0, None).unwrap();
    assert_eq!(e[2], 0, "{e:?}");
    assert!(e.iter().sum::<u32>() <= 90);
    // wrong sizes are errors
    assert!(top_up_budget(&f, &[1, 2], &params, 10.0, None).is_err());
}

#[test]
fn degenerate_pixels_are_not_filtered() {
    let dtf = setup(
        4,
        4,
        |x, _| px(grey(1.0), grey(if x == 0 { 0.0 } else { 0.3 }), 50),
        |x, y| px(grey(2.0), grey(0.3), if (x, y) == (2, 1) { 0 } else { 10 }),
        |_, _| 10,
        &DtfParams::default(),
    );
    // sigma = 0: primary only.
    assert_eq!(dtf.weights(0, 1).m, 1);
    assert_eq!(dtf.weights(0, 1).weights, vec![(0, 1, 1.0)]);
    // No independent samples: primary only, filtered black, displayed C_d.
    assert_eq!(dtf.weights(2, 1).weights, vec![(2, 1, 1.0)]);
    // ... and left out of its neighbours' regions.
    let r = dtf.weights(1, 1);
    assert!(r.m > 1 && r.weights.iter().all(|q| (q.0, q.1) != (2, 1)));
    let out = dtf.run();
    assert_eq!(out.filtered.get(2, 1), [0.0; 3]);
    // displayed: C_d at phase 2's brightness (its neighbours' C_i = 2 C_d)
    assert_eq!(out.combined.get(2, 1), [2.0; 3]);
    assert!(out
        .combined
        .data
        .iter()
        .all(|c| c.iter().all(|v| v.is_finite())));
}

#[test]
fn combination_formula_hand_computed() {
    let c = combine([1.0, 2.0, 3.0], 50, [2.0, 2.0, 0.0], 150);
    assert_eq!(c, [1.75, 2.0, 0.75]);
    assert_eq!(combine([1.0; 3], 0, [0.5; 3], 0), [0.0; 3]);
    assert_eq!(combine([1.0; 3], 40, [0.5; 3], 0), [1.0; 3]);
    // Through the filter on a 1x1 image (no neighbours: filtered = C_i).
    let d = film(1, 1, |_, _| px([1.0, 2.0, 3.0], grey(0.5), 50));
    let i = film(1, 1, |_, _| px([2.0, 2.0, 0.0], grey(0.5), 150));
    let paper = DtfParams {
        paper_display: true,
        ..DtfParams::default()
    };
    let out = dtf_filter(&d, &i, &[100], &paper).unwrap();
    assert_eq!(out.filtered.data[0], [2.0, 2.0, 0.0]);
    assert_eq!(out.combined.data[0], [1.75, 2.0, 0.75]);
    assert_eq!((out.m[0], out.region[0], out.n[0]), (1, 1, 100));
    assert!(out.seconds >= 0.0);
}

/// C_d varies so that every neighbour has Delta_q > 0 (a 2D gradient); N grows.
fn gradient(clamp: Clamp, big_n: u32) -> Dtf {
    gradient_guarded(clamp, big_n, DtfParams::default().guard)
}

fn gradient_guarded(clamp: Clamp, big_n: u32, guard: f32) -> Dtf {
    let params = DtfParams {
        clamp,
        categories: vec![0, big_n],
        guard,
        ..Default::default()
    };
    setup(
        9,
        9,
        |x, y| {
            px(
                grey(1.0 + 0.01 * (x as f64 + 2.3 * y as f64)),
                grey(0.3),
                50,
            )
        },
        |x, y| px(grey(1.0 + hash(x, y, 9)), grey(0.3), big_n),
        |_, _| big_n,
        &params,
    )
}

#[test]
fn filter_vanishes_as_n_grows() {
    let mut last = 0.0;
    for big_n in [1u32, 100, 10_000, 1_000_000, 100_000_000] {
        let dtf = gradient(Clamp::ActiveSet, big_n);
        let f0 = dtf.weights(4, 4).primary_weight();
        if big_n == 1 {
            assert!(f0 < 0.5, "N = 1 should filter: f*[0] = {f0}");
        }
        assert!(f0 >= last - 1e-12, "N = {big_n}: f*[0] {f0} < {last}");
        last = f0;
    }
    assert!(last > 0.999, "f*[0] = {last}");
    // The filtered image converges to C_i.
    let dtf = gradient(Clamp::ActiveSet, 100_000_000);
    let out = dtf.run();
    for y in 0..9 {
        for x in 0..9 {
            let want = 1.0 + hash(x, y, 9);
            assert!((out.filtered.get(x, y)[0] as f64 - want).abs() < 1e-3);
        }
    }
}

#[test]
fn paper_clamp_limit_behaviour() {
    // An isolated bright pixel in a dark flat field: every neighbour has the same
    // Delta > mean Delta, so with the paper's f^+ the filter vanishes as N grows...
    let spot = |big_n: u32| {
        setup(
            7,
            7,
            |x, y| {
                px(
                    grey(if (x, y) == (3, 3) { 2.0 } else { 0.5 }),
                    grey(0.3),
                    50,
                )
            },
            |_, _| px(grey(1.0), grey(0.3), big_n),
            |_, _| big_n,
            &DtfParams {
                categories: vec![0, big_n],
                ..Default::default()
            },
        )
        .weights(3, 3)
    };
    assert!(spot(1).primary_weight() < 0.9);
    assert_eq!(spot(100_000_000).m, 1);
    // ... but on a gradient it keeps averaging over the pixels with Delta_q < mean
    // Delta, however large N is (the documented caveat of Clamp::Paper), unless the
    // independent guard sees that the neighbours' phase-2 means differ.
    let f0 = gradient_guarded(Clamp::Paper, 100_000_000, 0.0)
        .weights(4, 4)
        .primary_weight();
    assert!(f0 < 0.95, "f*[0] = {f0}");
    let f0 = gradient_guarded(Clamp::Paper, 100_000_000, 3.0)
        .weights(4, 4)
        .primary_weight();
    assert_eq!(f0, 1.0);
}

#[test]
fn bad_inputs_are_reported() {
    let d = film(3, 2, |_, _| px(grey(1.0), grey(0.1), 50));
    let i = film(2, 3, |_, _| px(grey(1.0), grey(0.1), 10));
    let e = Dtf::new(&d, &i, &[10; 6], &DtfParams::default())
        .err()
        .unwrap();
    assert!(e.contains("3x2") && e.contains("2x3"), "{e}");
    let e = Dtf::new(&d, &d, &[10; 5], &DtfParams::default())
        .err()
        .unwrap();
    assert!(e.contains("5 sample counts"), "{e}");
    let bad = DtfParams {
        categories: vec![10, 1],
        ..Default::default()
    };
    assert!(allocate_relative(&d, &bad).is_err());
    assert!(allocate_budget(&d, &DtfParams::default(), -1.0).is_err());
}

mod robust_tests {
    use super::*;
    use crate::film::{Film, PixelStats};

    /// A film where most pixels are noisy and a few had dependent samples that all agreed
    /// (sigma = 0), one black, one a firefly.
    fn film() -> Film {
        let mut f = Film::new(16, 16).unwrap();
        for (i, p) in f.pixels.iter_mut().enumerate() {
            let v = 0.5 + (i % 7) as f64 * 0.1;
            *p = PixelStats::from_moments(16, [v; 3], [0.04 * 15.0; 3]);
        }
        f.pixels[3] = PixelStats::from_moments(16, [0.4; 3], [0.0; 3]); // agreeing samples
        f.pixels[4] = PixelStats::from_moments(16, [0.0; 3], [0.0; 3]); // black
        f.pixels[5] = PixelStats::from_moments(16, [0.6; 3], [4000.0; 3]); // firefly
        f
    }

    #[test]
    fn no_pixel_is_starved_and_all_grow_with_the_budget() {
        let f = film();
        let p = DtfParams::default();
        let small = allocate_budget(&f, &p, 20.0).unwrap();
        let large = allocate_budget(&f, &p, 2000.0).unwrap();
        for i in [3usize, 4] {
            assert!(small[i] >= 1, "pixel {i} starved: {}", small[i]);
            assert!(
                large[i] > 10 * small[i].max(1) / 2,
                "pixel {i} does not grow: {} -> {}",
                small[i],
                large[i]
            );
        }
        // the firefly cannot swallow the budget: at most ~16x the median share
        let mut sorted = large.clone();
        sorted.sort();
        let median = sorted[sorted.len() / 2] as f64;
        assert!(
            (large[5] as f64) <= 40.0 * median,
            "firefly got {} vs median {median}",
            large[5]
        );
        // prescribed error: as eps_r falls every pixel's N grows without bound
        let a = allocate_relative(
            &f,
            &DtfParams {
                eps_r: Some(0.1),
                ..p.clone()
            },
        )
        .unwrap();
        let b = allocate_relative(
            &f,
            &DtfParams {
                eps_r: Some(0.01),
                ..p.clone()
            },
        )
        .unwrap();
        for i in 0..a.len() {
            assert!(
                b[i] > a[i] || b[i] == N_HARD_MAX,
                "pixel {i}: {} -> {}",
                a[i],
                b[i]
            );
        }
    }
}

/// A phase-1 film with splat batches (as BDPT's): every pixel's n samples carry their own
/// noise (uniform, half-width 0.2) around `base(x, y)`, as each pixel's own light subpath
/// gives them.
fn splat_dependent(w: u32, h: u32, n: u32, base: impl Fn(u32, u32) -> f64) -> Film {
    let mut f = Film::with_splats(w, h).unwrap();
    for k in 0..n {
        for y in 0..h {
            for x in 0..w {
                let v = (base(x, y) + 0.4 * (hash(x, y, k) - 0.5)) as f32;
                let i = f.index(x, y);
                f.add_sample(i, k, [v; 3]);
                f.splats.as_mut().unwrap().add_light_path(k);
            }
        }
    }
    f
}

#[test]
fn dep_noise_takes_unshared_noise_out_of_delta_but_keeps_edges() {
    let (w, h) = (8, 8);
    let run = |base: &dyn Fn(u32, u32) -> f64, dep_noise: f32, big_n: u32| {
        let d = splat_dependent(w, h, 32, base);
        let i = film(w, h, |x, y| px(grey(base(x, y)), grey(0.115), big_n));
        let params = DtfParams {
            dep_noise,
            guard: 0.0,
            ..Default::default()
        };
        Dtf::new(&d, &i, &vec![big_n; (w * h) as usize], &params).unwrap()
    };
    // A flat field: the paper's Delta sees the pixels' own noise as colour differences.
    let flat = |_: u32, _: u32| 0.5;
    let f0 = run(&flat, 0.0, 1000).weights(4, 4).primary_weight();
    let f2 = run(&flat, 2.0, 1000).weights(4, 4).primary_weight();
    assert!(
        f2 < 0.8 * f0,
        "f*[0] with dep-noise 2: {f2}, paper's Delta: {f0}"
    );
    // A step far beyond the noise (1.0 above row 4, 0.3 from it on) stays apart.
    let step = |_: u32, y: u32| if y < 4 { 1.0 } else { 0.3 };
    for k in [0.0, 2.0] {
        let r = run(&step, k, 16).weights(4, 2);
        let across: f64 = r.weights.iter().filter(|q| q.1 >= 4).map(|q| q.2).sum();
        assert_eq!(
            across, 0.0,
            "dep-noise {k}: weight across the step {across}"
        );
    }
    // Without splats (a path tracer's film) the option changes nothing.
    let plain = |k: f32| {
        setup(
            w,
            h,
            |x, y| px(grey(0.5 + 0.05 * hash(x, y, 7)), grey(0.1), 32),
            |_, _| px(grey(0.5), grey(0.1), 100),
            |_, _| 100,
            &DtfParams {
                dep_noise: k,
                ..Default::default()
            },
        )
        .weights(4, 4)
    };
    assert_eq!(plain(0.0), plain(2.0));
}
