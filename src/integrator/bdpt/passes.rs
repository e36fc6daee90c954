//! Images rendered by independent passes, for tests and diagnostics that compare
//! estimators per pixel: pass j gives every pixel one camera sample (sample index j) and its
//! splats, so a pixel's pass values are i.i.d. and give the variance of its mean.

use super::{sample_pixel_with, BdptOptions};
use crate::integrator::{path, Counters, IntegratorKind, IntegratorSettings, Roulette, RrMode};
use crate::math::Vec2;
use crate::sampling::SampleStream;
use crate::sampling::{SamplerConfig, SamplerKind};
use crate::scene::{Camera, Scene};

/// An image rendered by independent passes: pass j gives every pixel one camera sample
/// (sample index j) and its splats, so a pixel's pass values are i.i.d. and its film value
/// (mean of the samples + splats / spp) is their mean.
pub struct Img {
    pub w: u32,
    pub h: u32,
    pub mean: Vec<[f64; 3]>,
    /// Variance of the mean, per pixel.
    pub var: Vec<[f64; 3]>,
    /// Image mean and its standard error (from the passes' image means).
    pub img_mean: [f64; 3],
    pub img_se: [f64; 3],
}

/// The test-only render loop with the film's convention: pixel value = mean of its
/// returned samples + (sum of the splats that landed in it) / spp.
pub fn render(
    scene: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
    mut f: impl FnMut(&Camera, u32, u32, &mut SampleStream, &mut dyn FnMut(Vec2, [f32; 3])) -> [f32; 3],
) -> Img {
    let cam = Camera::new(scene.camera, w, h);
    let cfg = SamplerConfig {
        kind: SamplerKind::Random,
        seed,
        dependent: false,
    };
    let n = (w * h) as usize;
    let mut sum = vec![[0.0f64; 3]; n];
    let mut sum2 = vec![[0.0f64; 3]; n];
    let (mut isum, mut isum2) = ([0.0f64; 3], [0.0f64; 3]);
    let mut pass = vec![[0.0f64; 3]; n];
    for j in 0..spp {
        pass.iter_mut().for_each(|p| *p = [0.0; 3]);
        for y in 0..h {
            for x in 0..w {
                let pix = (y * w + x) as usize;
                let mut s = SampleStream::new(&cfg, 0, pix as u32, j);
                let mut splats: Vec<(Vec2, [f32; 3])> = Vec::new();
                let v = f(&cam, x, y, &mut s, &mut |r, c| splats.push((r, c)));
                for c in 0..3 {
                    pass[pix][c] += v[c] as f64;
                }
                for (r, v) in splats {
                    let (px, py) = (r.x.floor() as i64, r.y.floor() as i64);
                    assert!(px >= 0 && py >= 0 && px < w as i64 && py < h as i64, "{r}");
                    let q = (py as u32 * w + px as u32) as usize;
                    for c in 0..3 {
                        pass[q][c] += v[c] as f64;
                    }
                }
            }
        }
        let mut im = [0.0f64; 3];
        for (i, p) in pass.iter().enumerate() {
            for c in 0..3 {
                assert!(p[c].is_finite(), "pixel {i} pass {j}: {p:?}");
                sum[i][c] += p[c];
                sum2[i][c] += p[c] * p[c];
                im[c] += p[c] / n as f64;
            }
        }
        for c in 0..3 {
            isum[c] += im[c];
            isum2[c] += im[c] * im[c];
        }
    }
    let k = spp as f64;
    let mv = |s: f64, s2: f64| {
        let m = s / k;
        (m, ((s2 / k - m * m) * k / (k - 1.0)).max(0.0) / k)
    };
    let mut mean = vec![[0.0; 3]; n];
    let mut var = vec![[0.0; 3]; n];
    for i in 0..n {
        for c in 0..3 {
            (mean[i][c], var[i][c]) = mv(sum[i][c], sum2[i][c]);
        }
    }
    let mut img_mean = [0.0; 3];
    let mut img_se = [0.0; 3];
    for c in 0..3 {
        let (m, v) = mv(isum[c], isum2[c]);
        img_mean[c] = m;
        img_se[c] = v.sqrt();
    }
    Img {
        w,
        h,
        mean,
        var,
        img_mean,
        img_se,
    }
}

/// Settings of the path tracer with roulette `mode` and `max_depth`.
pub fn settings(mode: RrMode, max_depth: i32) -> IntegratorSettings {
    IntegratorSettings {
        kind: IntegratorKind::Path,
        max_depth,
        roulette: Roulette {
            mode,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// BDPT by passes.
pub fn render_bdpt<const N: usize>(
    scene: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
    set: &IntegratorSettings,
    opts: BdptOptions,
) -> Img {
    let mut c = Counters::default();
    render(scene, w, h, spp, seed, |cam, x, y, s, splat| {
        sample_pixel_with::<N>(scene, cam, x, y, s, set, &opts, &mut c, splat, None)
    })
}

/// The path tracer by passes.
pub fn render_path<const N: usize>(
    scene: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
    set: &IntegratorSettings,
) -> Img {
    let mut c = Counters::default();
    render(scene, w, h, spp, seed, |cam, x, y, s, _| {
        path::sample_pixel::<N>(scene, cam, x, y, s, set, &mut c)
    })
}
