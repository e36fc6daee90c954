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
    film.pixels.iter().map(|p| p.mean()).collect()
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

/// Shards: two film files of consecutive sample ranges merge into exactly the image of one
/// render of all the samples; parts that do not belong together are refused.
#[test]
fn shards_merge_into_the_one_process_image() {
    use std::process::Command;
    let exe = env!("CARGO_BIN_EXE_kalos");
    let dir = std::env::temp_dir().join(format!("kalos-shards-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |n: &str| dir.join(n).display().to_string();
    let run = |args: &[&str]| {
        let o = Command::new(exe).args(args).output().unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    let base = [
        "render", "cornell", "--method", "plain", "--res", "40x30", "-q",
    ];
    let part = |first: &str, spp: &str, out: &str, extra: &[&str]| {
        let mut a: Vec<&str> = base.to_vec();
        a.extend(["--first-sample", first, "--spp", spp, "-o", out]);
        a.extend(extra);
        run(&a)
    };
    assert!(part("0", "5", &p("a.kfilm"), &["--threads", "1"]).0);
    assert!(part("5", "11", &p("b.kfilm"), &["--threads", "3"]).0);
    let (ok, err) = run(&["merge", &p("b.kfilm"), &p("a.kfilm"), "-o", &p("m.exr")]);
    assert!(ok, "{err}");
    let mut all = base.to_vec();
    all.extend(["--spp", "16", "-o"]);
    let full = p("full.exr");
    all.push(&full);
    assert!(run(&all).0);
    let read = |f: &str| kalos::image_io::read_image(std::path::Path::new(f)).unwrap();
    assert!(
        read(&p("m.exr")).data == read(&full).data,
        "merged != one render"
    );

    // refusals, one line each, naming the file
    assert!(part("3", "4", &p("over.kfilm"), &[]).0);
    let (ok, err) = run(&["merge", &p("a.kfilm"), &p("over.kfilm"), "-o", &p("x.exr")]);
    assert!(
        !ok && err.contains("overlap") && err.lines().count() == 1,
        "{err}"
    );
    assert!(part("5", "4", &p("seed.kfilm"), &["--seed", "9"]).0);
    let (ok, err) = run(&["merge", &p("a.kfilm"), &p("seed.kfilm"), "-o", &p("x.exr")]);
    assert!(
        !ok && err.contains("seed.kfilm") && err.contains("another render"),
        "{err}"
    );
    let bytes = std::fs::read(p("a.kfilm")).unwrap();
    std::fs::write(p("cut.kfilm"), &bytes[..bytes.len() / 3]).unwrap();
    let (ok, err) = run(&["merge", &p("cut.kfilm"), &p("b.kfilm"), "-o", &p("x.exr")]);
    assert!(
        !ok && err.contains("cut.kfilm") && err.contains("truncated"),
        "{err}"
    );
    let mut v = bytes.clone();
    v[10] = 7;
    std::fs::write(p("ver.kfilm"), &v).unwrap();
    let (ok, err) = run(&["merge", &p("ver.kfilm"), "-o", &p("x.exr")]);
    assert!(!ok && err.contains("version 7"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The BVH's run-time dispatched instruction sets (baseline SSE2, AVX2 where the CPU has it)
/// give the same image bit for bit: each available one forced on the Cornell box (path
/// tracer, next-event estimation: closest-hit and shadow rays) and on the BDPT.
#[test]
fn bit_identical_for_every_simd_path() {
    use kalos::accel::Isa;
    let mut scene = kalos::scene::load("cornell").unwrap();
    for integrator in [
        kalos::integrator::IntegratorKind::Path,
        kalos::integrator::IntegratorKind::Bdpt,
    ] {
        let mut set = settings(&scene, 24, 20);
        set.integrator.kind = integrator;
        let mut images = Vec::new();
        for isa in Isa::available() {
            assert!(scene.bvh.set_isa(isa));
            let film = render_spp(&scene, &set, 8);
            images.push((
                isa,
                film.pixels.iter().map(|p| p.mean()).collect::<Vec<_>>(),
            ));
        }
        for (isa, img) in &images[1..] {
            assert!(
                *img == images[0].1,
                "{integrator:?}: {} gives another image than {}",
                isa.name(),
                images[0].0.name()
            );
        }
        assert!(images[0].1.iter().any(|p| p[0] > 0.0));
    }
}

/// The path tracer's batches of samples give the image of one sample at a time, bit for
/// bit, whether their ray queries are answered one after another (as small scenes do) or
/// with their traversal steps interleaved (as large scenes do), on every instruction set
/// and any number of threads, with and without roulette. The batches end their diffuse
/// vertices in SIMD lanes (`integrator::lanes`), one path at a time does not: this also
/// checks the lanes against the one-path code (a factor of 1.0001 on the lanes' NEE
/// estimate makes it fail).
#[test]
fn bit_identical_batched_or_not() {
    use kalos::accel::Isa;
    use kalos::integrator::rr::RrMode;
    // Diffuse and glossy walls; the furnished room (4,226 triangles, its own lights); with
    // roulette, and without.
    for (name, max_depth, rr) in [
        ("cornell-glossy", -1, RrMode::Classic),
        ("cornell-glossy", 6, RrMode::Classic),
        ("cornell-glossy", 6, RrMode::Off),
        ("room", 5, RrMode::Off),
    ] {
        let mut scene = kalos::scene::load(name).unwrap();
        let mut set = settings(&scene, 24, 20);
        set.integrator.max_depth = max_depth;
        set.integrator.roulette.mode = rr;
        let case = format!("{name}, max_depth {max_depth}, rr {rr:?}");
        let mut images = Vec::new();
        for isa in Isa::available() {
            assert!(scene.bvh.set_isa(isa));
            for (interleaved, threads) in [(false, 1), (true, 1), (true, 3)] {
                scene.bvh.set_interleaving(Some(interleaved));
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let film = pool.install(|| render_spp(&scene, &set, 8));
                let img: Vec<_> = film.pixels.iter().map(|p| p.mean()).collect();
                images.push((
                    format!("{} interleaved={interleaved} threads={threads}", isa.name()),
                    img,
                ));
            }
        }
        scene.bvh.set_interleaving(None);
        // One sample at a time: a pass that counts each pixel's rays takes no batches.
        {
            use kalos::film::Film;
            use kalos::integrator::Integrator;
            use kalos::pipeline::{render_pass, Counts, Pass, Silent};
            let integrator =
                Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap();
            let mut film = Film::new(set.width, set.height).unwrap();
            let mut rays = vec![0u64; film.pixels.len()];
            let pass = Pass {
                scene: &scene,
                integrator: &integrator,
                set: &set,
                counts: Counts::Uniform(8),
                first_index: 0,
                stream: 0,
                progress: &Silent,
            };
            render_pass(&pass, &mut film, Some(&mut rays));
            let img: Vec<_> = film.pixels.iter().map(|p| p.mean()).collect();
            images.push(("one sample at a time".to_string(), img));
        }
        for (what, img) in &images[1..] {
            assert!(
                *img == images[0].1,
                "{case}: {what} gives another image than {}",
                images[0].0
            );
        }
        assert!(images[0].1.iter().any(|p| p[0] > 0.0), "{case}: black");
    }
}

/// DTF over BDPT with light paths of their own (`--dtf-light auto`, half of phase 2 forced
/// to them): the light pass and the K-weighted phase 2 give the same image on 1 and 3
/// threads.
#[test]
fn dtf_over_bdpt_with_light_paths_is_bit_identical_for_any_thread_count() {
    let scene = kalos::scene::load("caustic").unwrap();
    let go = |threads: usize| {
        let mut job = kalos::render::RenderJob::new("caustic");
        job.integrator = Some(kalos::integrator::IntegratorKind::Bdpt);
        job.method = kalos::render::Method::Dtf;
        job.res = Some((24, 20));
        job.spp = Some(24);
        job.threads = Some(threads);
        job.dtf.light_share = Some(0.5);
        let r = kalos::render::render_scene(&scene, &job, &kalos::pipeline::Silent).unwrap();
        assert!(r.dtf.as_ref().unwrap().light_paths > 0);
        r.image.data
    };
    assert!(
        go(1) == go(3),
        "DTF over BDPT: images differ with thread count"
    );
}

/// A render with no method named: the pilot chooses by ray counts, so the same seed gives
/// the same choice, the same line in the statistics and the same image on any thread count.
#[test]
fn the_automatic_choice_is_the_same_on_any_thread_count() {
    let scene = kalos::scene::load("cornell").unwrap();
    let go = |threads: usize| {
        let mut job = kalos::render::RenderJob::new("cornell");
        job.res = Some((24, 20));
        job.spp = Some(24);
        job.threads = Some(threads);
        let r = kalos::render::render_scene(&scene, &job, &kalos::pipeline::Silent).unwrap();
        let stats = serde_json::to_value(&r.stats).unwrap();
        (
            r.image.data,
            stats["method"].clone(),
            stats["method_choice"].clone(),
        )
    };
    let (one, three) = (go(1), go(3));
    assert_eq!(one.1, "dtf");
    assert!(
        one.2
            .as_str()
            .is_some_and(|s| s.starts_with("dtf over path; path: ")),
        "{:?}",
        one.2
    );
    assert!(
        one == three,
        "the automatic choice differs with thread count"
    );
}
