//! Sample passes over the film, pixels in parallel by rows (rayon). Each sample's random
//! numbers are a pure function of (seed, stream, pixel, sample index), and each pixel's
//! samples are accumulated in index order by one thread, so the image is bit-identical
//! for any thread count.

use crate::film::{Film, PixelStats, Rejections};
use crate::integrator::{path, Counters, IntegratorKind, IntegratorSettings};
use crate::sampling::{SampleStream, SamplerConfig};
use crate::scene::{Camera, CameraDesc, Scene};
use crate::spectrum::SpectralMode;
use indicatif::ProgressBar;
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

/// Add `counts` samples to every pixel of `film`, with sample indices starting at
/// `first_index`, drawn from random stream `stream`. Returns the work done.
pub fn render_into(
    scene: &Scene,
    set: &RenderSettings,
    film: &mut Film,
    counts: Counts,
    first_index: u32,
    stream: u32,
    progress: Option<&ProgressBar>,
) -> Counters {
    render_into_costed(
        scene,
        set,
        film,
        counts,
        first_index,
        stream,
        progress,
        None,
    )
}

/// [`render_into`] that also adds each pixel's traced rays to `rays[pixel]` (the cost of
/// its samples, for cost-aware sample allocation).
#[allow(clippy::too_many_arguments)]
pub fn render_into_costed(
    scene: &Scene,
    set: &RenderSettings,
    film: &mut Film,
    counts: Counts,
    first_index: u32,
    stream: u32,
    progress: Option<&ProgressBar>,
    rays: Option<&mut [u64]>,
) -> Counters {
    let p = Pass {
        scene,
        set,
        counts,
        first_index,
        stream,
        progress,
    };
    if let Some(r) = &rays {
        assert_eq!(r.len(), film.pixels.len(), "one ray count per pixel");
    }
    match set.spectral {
        SpectralMode::Rgb => pass::<3>(&p, film, rays),
        SpectralMode::Bands8 => pass::<8>(&p, film, rays),
        SpectralMode::Bands16 => pass::<16>(&p, film, rays),
    }
}

/// What one pass reads: everything but the film it writes.
struct Pass<'a> {
    scene: &'a Scene,
    set: &'a RenderSettings,
    counts: Counts<'a>,
    first_index: u32,
    stream: u32,
    progress: Option<&'a ProgressBar>,
}

fn pass<const N: usize>(p: &Pass, film: &mut Film, rays: Option<&mut [u64]>) -> Counters {
    let cam = Camera::new(p.set.camera, p.set.width, p.set.height);
    let w = film.width as usize;
    // One row: its samples into the film, and (if asked) each pixel's rays.
    let row = |y: usize, row: &mut [PixelStats], mut row_rays: Option<&mut [u64]>| {
        let mut c = Counters::default();
        let mut rej = Rejections::default();
        for (x, px) in row.iter_mut().enumerate() {
            let pixel = y * w + x;
            let rays_before = c.rays;
            for k in 0..p.counts.get(pixel) {
                let mut s =
                    SampleStream::new(&p.set.sampler, p.stream, pixel as u32, p.first_index + k);
                let v = match p.set.integrator.kind {
                    IntegratorKind::Path => path::sample_pixel::<N>(
                        p.scene,
                        &cam,
                        x as u32,
                        y as u32,
                        &mut s,
                        &p.set.integrator,
                        &mut c,
                    ),
                };
                if rej.check(&v) {
                    px.push(v);
                }
            }
            if let Some(r) = row_rays.as_deref_mut() {
                r[x] += c.rays - rays_before;
            }
        }
        if let Some(pb) = p.progress {
            pb.inc(1);
        }
        (c, rej)
    };
    let sum = |(mut a, mut ra): (Counters, Rejections), (b, rb): (Counters, Rejections)| {
        a.add(&b);
        ra.add(&rb);
        (a, ra)
    };
    let zero = || (Counters::default(), Rejections::default());
    let rows = film.pixels.par_chunks_mut(w).enumerate();
    let (counters, rejected) = match rays {
        Some(r) => rows
            .zip(r.par_chunks_mut(w))
            .map(|((y, px), rr)| row(y, px, Some(rr)))
            .reduce(zero, sum),
        None => rows.map(|(y, px)| row(y, px, None)).reduce(zero, sum),
    };
    film.rejected.add(&rejected);
    counters
}

/// How much work a plain render does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Samples per pixel.
    Spp(u32),
    /// Wall-clock seconds: whole passes of one sample per pixel while time remains.
    Time(f64),
}

/// The result of a plain render.
pub struct RenderOutput {
    pub film: Film,
    pub counters: Counters,
    pub seconds: f64,
    pub spp: u32,
}

/// Plain rendering: the same number of independent samples in every pixel.
pub fn render(
    scene: &Scene,
    set: &RenderSettings,
    budget: Budget,
    progress: Option<&ProgressBar>,
) -> Result<RenderOutput, String> {
    let mut film = Film::new(set.width, set.height)?;
    let t0 = Instant::now();
    let mut counters = Counters::default();
    let mut spp = 0u32;
    match budget {
        Budget::Spp(n) => {
            if let Some(pb) = progress {
                pb.set_length(set.height as u64 * n.div_ceil(pass_size(n)) as u64);
            }
            // Passes of several samples keep the progress bar alive on long renders.
            while spp < n {
                let k = pass_size(n).min(n - spp);
                let c = render_into(scene, set, &mut film, Counts::Uniform(k), spp, 0, progress);
                counters.add(&c);
                spp += k;
            }
        }
        Budget::Time(secs) => {
            if let Some(pb) = progress {
                pb.set_length(set.height as u64);
            }
            loop {
                let c = render_into(scene, set, &mut film, Counts::Uniform(1), spp, 0, progress);
                counters.add(&c);
                spp += 1;
                let el = t0.elapsed().as_secs_f64();
                // stop when another whole pass would not fit in the budget
                if el + el / spp as f64 > secs {
                    break;
                }
                if let Some(pb) = progress {
                    let est = (secs / (el / spp as f64)).floor() as u64;
                    pb.set_length(set.height as u64 * est.max(spp as u64 + 1));
                }
            }
        }
    }
    if let Some(pb) = progress {
        pb.finish_and_clear();
    }
    Ok(RenderOutput {
        film,
        counters,
        seconds: t0.elapsed().as_secs_f64(),
        spp,
    })
}

/// Samples per pass for an spp budget (a pass is one progress step).
fn pass_size(n: u32) -> u32 {
    (n / 16).clamp(1, 64)
}
