//! BDPT's strategy images (pbrt-v4's `visualizestrategies`; Veach's thesis, figure 10.3):
//! one image per connection strategy (s, t) of the path lengths up to a bound, each the
//! contribution C*_{s,t} of that strategy alone, MIS-weighted (w_{s,t} C*_{s,t}: what it
//! adds to the render) and unweighted (C*_{s,t}: an estimate of the whole light of that
//! path length, by that strategy alone).
//!
//! A pass of the one pixel loop (`render::each_row`) with a sink that reads the strategies
//! (`film::Sink::strategy`). Camera-side strategies (t >= 2) add to their own pixel, light
//! tracing (t = 1) to the pixel its splat lands in; every image is the sum divided by the samples per pixel (one light
//! subpath per camera sample, as in the render). Rows run in parallel, each keeping its own
//! sums and its list of splats; rows are reduced in row order, so the images are the same
//! bits for any thread count. The random streams are the render's (stream 0, sample indices
//! `first..first + spp`), so the weighted images of every path length sum to the render.

use crate::film::{raster_pixel, Sink, StrategySample};
use crate::integrator::{Integrator, IntegratorKind};
use crate::math::Vec2;
use crate::pipeline::render::{each_row, Counts, Pass, RenderSettings};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::spectrum::per_band;
use rayon::prelude::*;

/// The default bound on the path length (segments, Mitsuba's depth) of the images.
pub const DEFAULT_MAX_LENGTH: u32 = 4;

/// The two images of one strategy (s, t): path length s + t - 1 segments.
#[derive(Clone, Debug, PartialEq)]
pub struct StrategyImage {
    pub s: u32,
    pub t: u32,
    /// Linear RGB, row-major: w_{s,t} C*_{s,t}.
    pub weighted: Vec<[f32; 3]>,
    /// Linear RGB, row-major: C*_{s,t}.
    pub unweighted: Vec<[f32; 3]>,
}

impl StrategyImage {
    /// File name part, pbrt's: `s1-t2`.
    pub fn name(&self) -> String {
        format!("s{}-t{}", self.s, self.t)
    }
}

/// Every strategy of path lengths 1..=max_length (s + t - 1 segments, s + t >= 2; (1, 1)
/// does not exist), in order of length, then s.
pub fn strategy_list(max_length: u32) -> Vec<(u32, u32)> {
    let mut v = Vec::new();
    for len in 1..=max_length {
        for s in 0..=len + 1 {
            let t = len + 1 - s;
            if t >= 1 && !(s == 1 && t == 1) {
                v.push((s, t));
            }
        }
    }
    v
}

/// Index of (s, t) in `strategy_list(max_length)`, if its length is within the bound.
fn slot(s: u32, t: u32, max_length: u32) -> Option<usize> {
    let len = (s + t).checked_sub(1)?;
    if len == 0 || len > max_length || t == 0 || (s == 1 && t == 1) {
        return None;
    }
    // length l has the l + 1 strategies s = 0..=l, but length 1 only (0, 2)
    let before: u32 = (1..len).map(|l| if l == 1 { 1 } else { l + 1 }).sum();
    let within = if len == 1 { 0 } else { s };
    Some((before + within) as usize)
}

/// Refuses an estimator other than BDPT.
pub fn check_estimator(kind: IntegratorKind) -> Result<(), String> {
    if kind != IntegratorKind::Bdpt {
        return Err(format!(
            "--bdpt-strategies: the strategy images are BDPT's; add --integrator bdpt (not {})",
            crate::options::name(&kind)
        ));
    }
    Ok(())
}

/// The strategy images of a BDPT render with settings `set` (checked as the render checks
/// them), sample indices `first..first + spp`, for the path lengths up to `max_length`
/// (and the settings' --max-depth, if smaller); rows in parallel on the current thread pool.
/// `render::render_strategies` is the job's front door.
pub fn render_strategies(
    scene: &Scene,
    set: &RenderSettings,
    first: u64,
    spp: u32,
    max_length: u32,
    progress: &dyn Progress,
) -> Result<Vec<StrategyImage>, String> {
    check_estimator(set.integrator.kind)?;
    // The render's estimator (its settings checked as the render does, e.g. --rr off
    // with no depth): BDPT with every strategy, one light subpath per camera sample.
    let integrator = Integrator::prepare(
        scene,
        set.integrator,
        set.spectral.bands(),
        &crate::progress::Silent,
    )?;
    let max_len = match set.integrator.max_depth {
        d if d >= 0 => max_length.min(d as u32),
        _ => max_length,
    };
    let list = strategy_list(max_len);
    let pass = Pass {
        scene,
        integrator: &integrator,
        set,
        counts: Counts::Uniform(spp),
        first_index: first,
        stream: 0,
        progress,
    };
    progress.begin("samples", set.width as u64 * set.height as u64 * spp as u64);
    let sums = per_band!(set.spectral, pass_sums(&pass, max_len, list.len()));
    progress.finish();
    if progress.cancelled() {
        return Err("--bdpt-strategies: interrupted, no strategy images written".into());
    }
    let k = 1.0 / spp as f64;
    Ok(list
        .iter()
        .enumerate()
        .map(|(j, &(s, t))| StrategyImage {
            s,
            t,
            weighted: sums
                .iter()
                .map(|p| p[j][0].map(|v| (v * k) as f32))
                .collect(),
            unweighted: sums
                .iter()
                .map(|p| p[j][1].map(|v| (v * k) as f32))
                .collect(),
        })
        .collect())
}

/// Per pixel, per strategy: [weighted, unweighted] RGB sums.
type Sums = Vec<[[f64; 3]; 2]>;

/// A row's sink: each pixel's own sums (camera-side strategies), and the light-tracing
/// strategies' contributions (pixel, strategy slot, sample), added after all rows.
struct RowStrategies {
    width: u32,
    height: u32,
    start: u32,
    max_len: u32,
    own: Vec<Sums>,
    splats: Vec<(usize, usize, StrategySample)>,
}

impl Sink for RowStrategies {
    fn wants_strategies(&self) -> bool {
        true
    }
    fn sample(&mut self, _: u32, _: u64, _: [f32; 3], _: [f32; 3]) {}
    fn splat(&mut self, _: u64, _: Vec2, _: [f32; 3]) {}
    fn strategy(&mut self, pixel: u32, ss: &StrategySample) {
        let Some(j) = slot(ss.s, ss.t, self.max_len) else {
            return;
        };
        if ss.t == 1 {
            if let Some(p) = raster_pixel(ss.raster, self.width, self.height) {
                self.splats.push((p as usize, j, *ss));
            }
        } else {
            add(&mut self.own[(pixel - self.start) as usize][j], ss);
        }
    }
}

/// Each pixel's sums over the pass `p` (strategy slots of the lengths up to `max_len`).
fn pass_sums<const N: usize>(p: &Pass, max_len: u32, slots: usize) -> Vec<Sums> {
    let (width, height) = (p.set.width, p.set.height);
    let (w, h) = (width as usize, height as usize);
    let sinks = (0..height).into_par_iter().map(|y| RowStrategies {
        width,
        height,
        start: y * width,
        max_len,
        own: vec![vec![[[0.0; 3]; 2]; slots]; w],
        splats: Vec::new(),
    });
    let rows = each_row::<N, _>(p, sinks);
    // Reduce in row order: the same additions in the same order on any thread count.
    let mut sums: Vec<Sums> = Vec::with_capacity(w * h);
    let mut all_splats = Vec::new();
    for (_, r) in rows {
        sums.extend(r.own);
        all_splats.push(r.splats);
    }
    for splats in all_splats {
        for (p, j, ss) in splats {
            add(&mut sums[p][j], &ss);
        }
    }
    sums
}

#[inline]
fn add(acc: &mut [[f64; 3]; 2], ss: &StrategySample) {
    for (c, (&wv, &uv)) in ss.weighted.iter().zip(&ss.unweighted).enumerate() {
        acc[0][c] += wv as f64;
        acc[1][c] += uv as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_follow_the_list() {
        let list = strategy_list(5);
        for (j, &(s, t)) in list.iter().enumerate() {
            assert_eq!(slot(s, t, 5), Some(j), "({s}, {t})");
        }
        assert_eq!(slot(1, 1, 5), None);
        assert_eq!(slot(3, 4, 5), None); // length 6
        assert_eq!(list.len(), 1 + 3 + 4 + 5 + 6);
    }
}
