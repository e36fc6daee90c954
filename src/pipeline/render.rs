//! The one pixel loop (`each_row`): rows in parallel (rayon), each row's camera samples
//! evaluated by `Integrator::sample` into the row's sink: the film's `film::RowSink` for
//! sample passes, the strategy images' own (`strategies`). Each sample's random numbers are
//! a pure function of (seed, stream, pixel, sample index) and the film's sums are exact,
//! so the image is bit-identical for any thread count. Splats are collected per row and
//! added to the film after the pass, in row order.

use crate::film::{Film, PixelStats, RowOut, RowSink, Sink, Splats};
use crate::integrator::{CameraSample, Counters, Integrator, IntegratorSettings, SampleCtx};
use crate::progress::Progress;
use crate::sampling::{SampleStream, SamplerConfig};
use crate::scene::{Camera, CameraDesc, Scene};
use crate::spectrum::{per_band, SpectralMode};
use rayon::prelude::*;
use std::time::Instant;

/// Everything that decides the value of a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub camera: CameraDesc,
    pub spectral: SpectralMode,
    pub sampler: SamplerConfig,
    /// The estimator's settings (`Integrator::prepare` turns them into an estimator).
    pub integrator: IntegratorSettings,
}

/// How many samples each pixel gets in a pass.
#[derive(Clone, Copy, Debug)]
pub enum Counts<'a> {
    Uniform(u32),
    PerPixel(&'a [u32]),
}

impl Counts<'_> {
    #[inline]
    fn get(&self, i: usize) -> u32 {
        match self {
            Counts::Uniform(n) => *n,
            Counts::PerPixel(v) => v[i],
        }
    }
    pub fn total(&self, pixels: usize) -> u64 {
        match self {
            Counts::Uniform(n) => *n as u64 * pixels as u64,
            Counts::PerPixel(v) => v.iter().map(|&n| n as u64).sum(),
        }
    }
}

/// One pass: what it reads (everything but the film it writes).
#[derive(Clone, Copy)]
pub struct Pass<'a> {
    pub scene: &'a Scene,
    pub integrator: &'a Integrator,
    pub set: &'a RenderSettings,
    pub counts: Counts<'a>,
    /// Sample index of each pixel's first sample in this pass.
    pub first_index: u64,
    /// Random stream (phases of a method use different streams).
    pub stream: u32,
    pub progress: &'a dyn Progress,
}

/// Add the pass's samples to `film`. Returns the work done; with `rays`, also adds each
/// pixel's traced rays to `rays[pixel]` (the cost of its samples, for cost-aware sample
/// allocation).
pub fn render_pass(p: &Pass, film: &mut Film, rays: Option<&mut [u64]>) -> Counters {
    if let Some(r) = &rays {
        assert_eq!(r.len(), film.pixels.len(), "one ray count per pixel");
    }
    if p.integrator.splats() {
        film.ensure_splats();
    }
    per_band!(p.set.spectral, pass(p, film, None, None, rays))
}

/// [`render_pass`] of an estimator that [`Integrator::splits_direct`] (BDPT), which also
/// writes each camera sample less its emission seen directly (the sink's `Layer::Direct`)
/// to `rest`: the same samples' indices and batches, no splats (its `light_paths` stays
/// 0, so read its `pixels` and batch sums, not its `value`). `film` gets the whole
/// samples and the splats as [`render_pass`] gives them, so the two films hold per pixel
/// the whole value and the value without the light seen directly, each with its exact
/// spread (`filter::dtf::rest_film` joins the second with the first's splats).
pub fn render_pass_rest(
    p: &Pass,
    film: &mut Film,
    rest: &mut Film,
    rays: Option<&mut [u64]>,
) -> Counters {
    assert!(
        p.integrator.splits_direct(),
        "a rest film is for estimators that split off the light seen directly"
    );
    assert_eq!(film.pixels.len(), rest.pixels.len(), "films of one size");
    film.ensure_splats();
    rest.ensure_splats();
    per_band!(p.set.spectral, pass(p, film, None, Some(rest), rays))
}

/// A pass whose samples are split (the sink's `Layer::Visible`, for `--method rw`): the
/// transport L - f(ray) to `film`, the light seen directly f(ray) to `visible`, from one
/// evaluation of each sample. A sample rejected in either part is left out of both.
pub fn render_pass_split(p: &Pass, film: &mut Film, visible: &mut Film) -> Counters {
    assert!(
        !p.integrator.splats() && film.splats.is_none(),
        "split passes are for estimators that do not splat"
    );
    assert_eq!(film.pixels.len(), visible.pixels.len(), "films of one size");
    per_band!(p.set.spectral, pass(p, film, Some(visible), None, None))
}

/// The one pixel loop: the rows of a pass in parallel (rayon), each row's camera samples
/// (in pixel order, then sample index) evaluated by `Integrator::sample` into that row's
/// sink (`sinks`: one per row, top to bottom). Returns each row's counters and sink in row
/// order; a row not yet started when the render is cancelled is left as it was.
pub fn each_row<const N: usize, S: Sink + Send>(
    p: &Pass,
    sinks: impl IndexedParallelIterator<Item = S>,
) -> Vec<(Counters, S)> {
    let set = p.set;
    let cam = Camera::new(set.camera, set.width, set.height);
    let ctx = SampleCtx {
        scene: p.scene,
        cam: &cam,
        sampler: &set.sampler,
        stream: p.stream,
    };
    let w = set.width;
    sinks
        .enumerate()
        .map(|(y, mut sink)| {
            let mut counters = Counters::default();
            if p.progress.cancelled() {
                return (counters, sink);
            }
            let y = y as u32;
            let samples = (0..w).flat_map(|x| {
                let pixel = y * w + x;
                let n = p.counts.get(pixel as usize);
                (0..n).map(move |k| CameraSample {
                    x,
                    y,
                    pixel,
                    index: p.first_index + k as u64,
                })
            });
            p.integrator
                .sample::<N>(&ctx, samples, &mut sink, &mut counters);
            let done: u64 = (0..w)
                .map(|x| p.counts.get((y * w + x) as usize) as u64)
                .sum();
            p.progress.advance(done);
            (counters, sink)
        })
        .collect()
}

/// A pass over the film: each row's sink is the film's (`film::RowSink`: the row's
/// pixels, or buffers when splatting; with `visible`, the light seen directly into its
/// row; with `rest`, the samples less their emission seen directly; with `rays`, each
/// pixel's rays), added to the film in row order after the pass.
fn pass<const N: usize>(
    p: &Pass,
    film: &mut Film,
    visible: Option<&mut Film>,
    mut rest: Option<&mut Film>,
    rays: Option<&mut [u64]>,
) -> Counters {
    let (width, height) = (p.set.width, p.set.height);
    let direct = rest.is_some();
    let w = film.width as usize;
    let h = film.pixels.len() / w.max(1);
    let splatting = film.splats.is_some();
    // each row's share of the optional outputs, as one list per output
    let vis_rows: Vec<Option<&mut [PixelStats]>> = match visible {
        Some(v) => v.pixels.chunks_mut(w).map(Some).collect(),
        None => (0..h).map(|_| None).collect(),
    };
    let ray_rows: Vec<Option<&mut [u64]>> = match rays {
        Some(r) => r.chunks_mut(w).map(Some).collect(),
        None => (0..h).map(|_| None).collect(),
    };
    let sinks = film
        .pixels
        .par_chunks_mut(w)
        .zip(vis_rows)
        .zip(ray_rows)
        .enumerate()
        .map(|(y, ((px, vr), rr))| {
            RowSink::new(width, height, y as u32, px, vr, rr, direct, splatting)
        });
    let outs: Vec<(Counters, RowOut)> = each_row::<N, _>(p, sinks)
        .into_iter()
        .map(|(c, sink)| (c, sink.out))
        .collect();
    let mut counters = Counters::default();
    for (c, o) in outs {
        counters.add(&c);
        film.add_row(&o, rest.as_deref_mut());
    }
    counters
}

/// Light paths traced for light tracing alone (`Integrator::light_sample`, BDPT): paths
/// `first..first + count` of random stream `stream`. Path m draws its numbers as sample
/// index m / P of pixel m % P (P the film's pixels) and belongs to batch m mod B of the
/// film's batch statistics; the film counts each as a light path (its splat image is
/// sum x P / light paths) without a camera sample. Paths run in parallel in chunks whose
/// splats are added in path order: the same bits for any thread count.
#[allow(clippy::too_many_arguments)]
pub fn render_light_pass(
    scene: &Scene,
    integrator: &Integrator,
    set: &RenderSettings,
    stream: u32,
    first: u64,
    count: u64,
    film: &mut Film,
    progress: &dyn Progress,
) -> Counters {
    film.ensure_splats();
    // at most LIGHT_PASS_MAX paths' splats buffered at a time (as camera passes, ~4M)
    let mut counters = Counters::default();
    let mut a = first;
    while a < first + count {
        let k = LIGHT_PASS_MAX.min(first + count - a);
        let c = per_band!(
            set.spectral,
            light_pass(scene, integrator, set, stream, a, k, film, progress)
        );
        counters.add(&c);
        if progress.cancelled() {
            break;
        }
        a += k;
    }
    counters
}

/// Light paths whose splats `render_light_pass` buffers at a time.
const LIGHT_PASS_MAX: u64 = 4_000_000;

/// Light paths per parallel chunk of `render_light_pass`.
const LIGHT_CHUNK: u64 = 1024;

#[allow(clippy::too_many_arguments)]
fn light_pass<const N: usize>(
    scene: &Scene,
    integrator: &Integrator,
    set: &RenderSettings,
    stream: u32,
    first: u64,
    count: u64,
    film: &mut Film,
    progress: &dyn Progress,
) -> Counters {
    let cam = Camera::new(set.camera, set.width, set.height);
    let ctx = SampleCtx {
        scene,
        cam: &cam,
        sampler: &set.sampler,
        stream,
    };
    let pixels = film.pixels.len() as u64;
    // the batch key of path m: m itself as far as it matters (m mod B)
    let key = |m: u64| (m % (1u64 << 30)) as u32;
    let chunks = count.div_ceil(LIGHT_CHUNK);
    // per chunk: its counters, its splats and the paths it traced (none if the render
    // was cancelled before it started)
    let outs: Vec<(Counters, Splats, u64)> = (0..chunks)
        .into_par_iter()
        .map(|ch| {
            let mut c = Counters::default();
            let mut sink = Splats::new(set.width, set.height);
            if progress.cancelled() {
                return (c, sink, 0);
            }
            let a = first + ch * LIGHT_CHUNK;
            let b = (a + LIGHT_CHUNK).min(first + count);
            for m in a..b {
                let mut s =
                    SampleStream::new(&set.sampler, stream, (m % pixels) as u32, m / pixels);
                integrator.light_sample::<N>(&ctx, &mut s, key(m) as u64, &mut sink, &mut c);
            }
            (c, sink, b - a)
        })
        .collect();
    let mut counters = Counters::default();
    for (ch, (c, sink, done)) in outs.iter().enumerate() {
        counters.add(c);
        let a = first + ch as u64 * LIGHT_CHUNK;
        if let Some(sf) = film.splats.as_mut() {
            for m in a..a + done {
                sf.add_light_path(key(m));
            }
        }
        film.add_splats(&sink.splats);
    }
    counters
}

/// How much work a plain render does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Samples per pixel.
    Spp(u32),
    /// Wall-clock seconds: whole passes of one sample per pixel while time remains, then
    /// one sample in a share of the pixels for the time a whole pass would overrun.
    Time(f64),
}

/// The result of a plain render.
pub struct RenderOutput {
    pub film: Film,
    pub counters: Counters,
    pub seconds: f64,
    /// Samples per pixel taken (fewer than asked if the render was interrupted); with a
    /// time budget the whole passes, the last partial pass not counted.
    pub spp: u32,
    pub interrupted: bool,
}

/// Plain rendering: the same number of independent samples in every pixel, sample
/// indices `first_index..first_index + spp` of stream 0.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    set: &RenderSettings,
    budget: Budget,
    first_index: u64,
    progress: &dyn Progress,
) -> Result<RenderOutput, String> {
    let mut film = if integrator.splats() {
        Film::with_splats(set.width, set.height)?
    } else {
        Film::new(set.width, set.height)?
    };
    let pixels = set.width as u64 * set.height as u64;
    let t0 = Instant::now();
    let mut counters = Counters::default();
    let mut spp = 0u32;
    let mut interrupted = false;
    let mut one_pass = |film: &mut Film, counts: Counts<'_>, spp: u32| {
        let p = Pass {
            scene,
            integrator,
            set,
            counts,
            first_index: first_index + spp as u64,
            stream: 0,
            progress,
        };
        counters.add(&render_pass(&p, film, None));
        progress.pass_image(set.width, set.height, &|| film.mean_rgb());
    };
    match budget {
        Budget::Spp(n) => {
            progress.begin("samples", pixels * n as u64);
            // Passes of several samples keep the progress alive on long renders; a
            // splatting estimator's passes are kept small (their splats are buffered).
            let size = pass_size(n, integrator.splats(), pixels);
            while spp < n {
                let k = size.min(n - spp);
                one_pass(&mut film, Counts::Uniform(k), spp);
                if progress.cancelled() {
                    interrupted = true;
                    break;
                }
                spp += k;
            }
        }
        Budget::Time(secs) => {
            progress.begin("samples", pixels);
            loop {
                one_pass(&mut film, Counts::Uniform(1), spp);
                if progress.cancelled() {
                    interrupted = true;
                    break;
                }
                spp += 1;
                let el = t0.elapsed().as_secs_f64();
                // When another whole pass would not fit, spend the time left on one sample
                // in a share of the pixels (a splatting estimator's passes are slow: BDPT on
                // a 256x256 Cornell box at 1 s otherwise stopped at 0.62 s).
                let per_pass = el / spp as f64;
                if el + per_pass > secs {
                    let share = (secs - el) / per_pass;
                    if share > 0.0 {
                        let extra = partial_pass(pixels as usize, share);
                        one_pass(&mut film, Counts::PerPixel(&extra), spp);
                        interrupted = progress.cancelled();
                    }
                    break;
                }
                let est = (secs / (el / spp as f64)).floor() as u64;
                progress.set_total(pixels * est.max(spp as u64 + 1));
            }
        }
    }
    progress.finish();
    Ok(RenderOutput {
        film,
        counters,
        seconds: t0.elapsed().as_secs_f64(),
        spp,
        interrupted,
    })
}

/// One sample for a share (0..1) of the pixels, zero for the others: pixel i takes one if
/// frac(i phi) < share (phi the golden ratio's conjugate), so the chosen pixels are spread
/// evenly over the image, and each pixel's mean stays its own samples' mean.
fn partial_pass(pixels: usize, share: f64) -> Vec<u32> {
    const PHI: f64 = 0.618_033_988_749_894_9;
    (0..pixels)
        .map(|i| ((i as f64 * PHI).fract() < share) as u32)
        .collect()
}

/// Samples per pass for an spp budget.
fn pass_size(n: u32, splats: bool, pixels: u64) -> u32 {
    let k = (n / 16).clamp(1, 64);
    if splats {
        // at most ~4M buffered camera samples per pass
        k.min((4_000_000 / pixels.max(1)).max(1) as u32)
    } else {
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::IntegratorKind;
    use crate::pipeline::Silent;

    /// The partial last pass of a time budget gives one sample to the share of the pixels
    /// asked, spread over the image: every 16-pixel run of pixel indices within one of it.
    #[test]
    fn partial_pass_takes_the_share_asked_evenly() {
        for share in [0.01, 0.3, 0.5, 0.97] {
            let v = partial_pass(65536, share);
            let total = v.iter().sum::<u32>() as f64;
            assert!(
                (total - share * 65536.0).abs() <= 8.0,
                "share {share}: {total}"
            );
            for run in v.chunks(16) {
                let k = run.iter().sum::<u32>() as f64;
                assert!((k - 16.0 * share).abs() <= 2.0, "share {share}: run {k}");
            }
        }
    }

    /// Splats reach the pixel they aim at with the value sent, whatever the thread count.
    #[test]
    fn splats_land_where_sent_on_any_thread_count() {
        let scene = crate::scene::load("cornell").unwrap();
        let mut set = RenderSettings {
            width: 7,
            height: 5,
            camera: scene.camera,
            spectral: SpectralMode::Rgb,
            sampler: SamplerConfig::default(),
            integrator: Default::default(),
        };
        set.integrator.kind = IntegratorKind::SplatTest;
        let integ =
            Integrator::prepare(&scene, set.integrator, set.spectral.bands(), &Silent).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| render(&scene, &integ, &set, Budget::Spp(11), 0, &Silent))
                .unwrap()
                .film
        };
        let one = run(1);
        let three = run(3);
        assert_eq!(one, three);
        for y in 0..5u32 {
            for x in 0..7u32 {
                let from = (x + 6) % 7;
                let v = one.value(one.index(x, y));
                assert_eq!(v, [from as f64, y as f64, 1.0], "pixel ({x}, {y})");
                assert_eq!(one.variance_of_value(one.index(x, y)), [0.0; 3]);
            }
        }
        assert_eq!(one.splats.as_ref().unwrap().light_paths, 7 * 5 * 11);
    }
}
