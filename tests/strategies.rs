//! BDPT's strategy images (`kalos render --bdpt-strategies`) through the library's front
//! door: they sum to the render and do not depend on the thread count.

use kalos::integrator::IntegratorKind;
use kalos::pipeline::strategies::strategy_list;
use kalos::pipeline::Silent;
use kalos::render::{render_scene, render_strategies, RenderJob};

fn job() -> RenderJob {
    let mut j = RenderJob::new("cornell");
    j.integrator = Some(IntegratorKind::Bdpt);
    j.res = Some((12, 10));
    j.spp = Some(4);
    j.max_depth = Some(3);
    j
}

/// The weighted images of every length sum to the render's image (same streams, all
/// lengths within --max-depth), and the result does not depend on the thread count.
#[test]
fn weighted_strategies_sum_to_the_render_on_any_thread_count() {
    let scene = kalos::scene::load("cornell").unwrap();
    let mut j = job();
    j.threads = Some(1);
    let one = render_strategies(&scene, &j, 8, &Silent).unwrap();
    j.threads = Some(3);
    let three = render_strategies(&scene, &j, 8, &Silent).unwrap();
    assert_eq!(one, three);
    assert_eq!(one.len(), strategy_list(3).len());
    let r = render_scene(&scene, &j, &Silent).unwrap();
    let mut worst = 0.0f64;
    for i in 0..120 {
        let v = r.film.value(i);
        for (c, &vc) in v.iter().enumerate() {
            let sum: f64 = one.iter().map(|im| im.weighted[i][c] as f64).sum();
            worst = worst.max((sum - vc).abs() / vc.abs().max(1e-3));
        }
    }
    assert!(
        worst < 1e-4,
        "weighted strategies vs render: relative {worst}"
    );
    // (0, 2) is the emitters seen directly: the light's pixels only, same both ways.
    let direct = one.iter().find(|im| (im.s, im.t) == (0, 2)).unwrap();
    assert_eq!(direct.weighted, direct.unweighted);
}

#[test]
fn refused_without_bdpt() {
    let scene = kalos::scene::load("cornell").unwrap();
    let mut j = job();
    j.integrator = Some(IntegratorKind::Path);
    let e = render_strategies(&scene, &j, 4, &Silent).unwrap_err();
    assert!(e.contains("--integrator bdpt"), "{e}");
}
