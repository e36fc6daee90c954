//! Sample passes over the film, pixels in parallel by rows (rayon). Each sample's random
//! numbers are a pure function of (seed, stream, pixel, sample index), and each pixel's
//! samples are accumulated in index order by one thread, so the image is bit-identical
//! for any thread count.

use crate::film::{Film, Rejections};
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
    let a = (
        scene,
        set,
        film,
        counts,
        first_index,
        stream,
        progress,
        rays,
    );
    match set.spectral {
        SpectralMode::Rgb => pass::<3>(a),
        SpectralMode::Bands8 => pass::<8>(a),
        SpectralMode::Bands16 => pass::<16>(a),
    }
}

type PassArgs<'a, 'b> = (
    &'a Scene,
    &'a RenderSettings,
    &'a mut Film,
    Counts<'b>,
    u32,
    u32,
    Option<&'a ProgressBar>,
    Option<&'a mut [u64]>,
);

fn pass<const N: usize>(
    (scene, set, film, counts, first_index, stream, progress, rays): PassArgs,
) -> Counters {
    let cam = Camera::new(set.camera, set.width, set.height);
    let w = film.width as usize;
    let mut no_rays = Vec::new();
    let rays: &mut [u64] = match rays {
        Some(r) => {
            assert_eq!(r.len(), film.pixels.len());
            r
        }
        None => {
            no_rays.resize(film.pixels.len(), 0);
            &mut no_rays
        }
    };
    let (counters, rejected) = film
        .pixels
        .par_chunks_mut(w)
        .zip(rays.par_chunks_mut(w))
        .enumerate()
        .map(|(y, (row, row_rays))| {
            let mut c = Counters::default();
            let mut rej = Rejections::default();
            for (x, (px, px_rays)) in row.iter_mut().zip(row_rays.iter_mut()).enumerate() {
                let pixel = y * w + x;
                let rays_before = c.rays;
                for k in 0..counts.get(pixel) {
                    let mut s =
                        SampleStream::new(&set.sampler, stream, pixel as u32, first_index + k);
                    let v = match set.integrator.kind {
                        IntegratorKind::Path => path::sample_pixel::<N>(
                            scene,
                            &cam,
                            x as u32,
                            y as u32,
                            &mut s,
                            &set.integrator,
                            &mut c,
                        ),
                    };
                    if rej.check(&v) {
                        px.push(v);
                    }
                }
                *px_rays += c.rays - rays_before;
            }
            if let Some(pb) = progress {
                pb.inc(1);
            }
            (c, rej)
        })
        .reduce(
            || (Counters::default(), Rejections::default()),
            |(mut a, mut ra), (b, rb)| {
                a.add(&b);
                ra.add(&rb);
                (a, ra)
            },
        );
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
