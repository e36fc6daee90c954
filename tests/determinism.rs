//! The same seed and options give the same image, bit for bit, on any number of threads.

mod common;
use common::*;
use kalos::sampling::SamplerKind;

fn render_with_threads(threads: usize, kind: SamplerKind, dependent: bool) -> Vec<[f64; 3]> {
    let scene = kalos::scene::load("cornell").unwrap();
    let mut set = settings(&scene, 24, 20);
    set.sampler.kind = kind;
    set.sampler.dependent = dependent;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let film = pool.install(|| render_spp(&scene, &set, 8));
    film.pixels.iter().map(|p| p.mean).collect()
}

#[test]
fn bit_identical_for_any_thread_count() {
    for kind in [SamplerKind::Random, SamplerKind::Sobol] {
        for dependent in [false, true] {
            let one = render_with_threads(1, kind, dependent);
            let three = render_with_threads(3, kind, dependent);
            assert!(
                one == three,
                "{kind:?} dependent={dependent}: images differ with thread count"
            );
        }
    }
}

#[test]
fn the_seed_changes_the_image() {
    let scene = kalos::scene::load("cornell").unwrap();
    let mut set = settings(&scene, 16, 16);
    let a = render_spp(&scene, &set, 4);
    set.sampler.seed = 2;
    let b = render_spp(&scene, &set, 4);
    assert!(a.pixels != b.pixels);
}
