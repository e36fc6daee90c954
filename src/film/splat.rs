//! Splats (light-tracing contributions to any pixel) and the batch statistics that keep a
//! per-pixel variance meaningful when one sample no longer maps to one pixel.
//!
//! Batch means: sample index k belongs to batch k mod B. Each batch keeps its own camera
//! sample sums, splat sums and light-path count, so each batch is an independent image
//! I_b; the variance of the full image's pixel is estimated as
//! sum_b (I_b - mean_b I_b)^2 / (B (B - 1)). Cost: B x (count + 2 x 3 sums) per pixel,
//! about 1 KiB per pixel for B = 8, paid only by estimators that splat.

use super::stats::FIXED;

/// Number of batches (B).
pub const BATCHES: usize = 8;

#[inline]
fn fixed(x: f32) -> i128 {
    ((x as f64) * FIXED).clamp(-1.9e28, 1.9e28) as i128
}

/// Per-pixel splat sums, the light paths that could splat, and B batch images.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatFilm {
    /// Sum of splats per pixel, fixed point.
    pub sum: Vec<[i128; 3]>,
    /// Light paths traced (one per camera sample of a splatting estimator).
    pub light_paths: u64,
    /// Per batch: camera-sample count and sum per pixel, splat sum per pixel, light paths.
    pub batch_n: Vec<[u32; BATCHES]>,
    pub batch_sum: Vec<[[i128; 3]; BATCHES]>,
    pub batch_splat: Vec<[[i128; 3]; BATCHES]>,
    pub batch_paths: [u64; BATCHES],
}

impl SplatFilm {
    pub fn new(pixels: usize) -> SplatFilm {
        SplatFilm {
            sum: vec![[0; 3]; pixels],
            light_paths: 0,
            batch_n: vec![[0; BATCHES]; pixels],
            batch_sum: vec![[[0; 3]; BATCHES]; pixels],
            batch_splat: vec![[[0; 3]; BATCHES]; pixels],
            batch_paths: [0; BATCHES],
        }
    }

    /// The camera sample `v` of sample index `index` in pixel `pixel` (its batch's share).
    #[inline]
    pub fn add_sample(&mut self, pixel: usize, index: u32, v: [f32; 3]) {
        let b = index as usize % BATCHES;
        self.batch_n[pixel][b] += 1;
        for (acc, &x) in self.batch_sum[pixel][b].iter_mut().zip(&v) {
            *acc += fixed(x);
        }
    }

    /// A splat `v` into `pixel` by a light path of sample index `index`.
    #[inline]
    pub fn add_splat(&mut self, pixel: usize, index: u32, v: [f32; 3]) {
        let b = index as usize % BATCHES;
        for (c, &x) in v.iter().enumerate() {
            let f = fixed(x);
            self.sum[pixel][c] += f;
            self.batch_splat[pixel][b][c] += f;
        }
    }

    /// Count one light path of sample index `index`.
    #[inline]
    pub fn add_light_path(&mut self, index: u32) {
        self.light_paths += 1;
        self.batch_paths[index as usize % BATCHES] += 1;
    }

    /// The splat image at pixel `i`: sum x pixels / light paths.
    #[inline]
    pub fn splat_value(&self, i: usize, pixels: usize) -> [f64; 3] {
        if self.light_paths == 0 {
            return [0.0; 3];
        }
        let k = pixels as f64 / (self.light_paths as f64 * FIXED);
        self.sum[i].map(|s| s as f64 * k)
    }

    /// Batch image b at pixel i (None when the batch has no camera sample there).
    pub fn batch_value(&self, i: usize, b: usize, pixels: usize) -> Option<[f64; 3]> {
        let n = self.batch_n[i][b];
        if n == 0 {
            return None;
        }
        let km = 1.0 / (n as f64 * FIXED);
        let ks = if self.batch_paths[b] > 0 {
            pixels as f64 / (self.batch_paths[b] as f64 * FIXED)
        } else {
            0.0
        };
        Some(
            [0, 1, 2].map(|c| {
                self.batch_sum[i][b][c] as f64 * km + self.batch_splat[i][b][c] as f64 * ks
            }),
        )
    }

    /// Variance of pixel i's value from the spread of its batch images.
    pub fn batch_variance(&self, i: usize, pixels: usize) -> [f64; 3] {
        let mut vals = [[0.0; 3]; BATCHES];
        let mut k = 0;
        for v in (0..BATCHES).filter_map(|b| self.batch_value(i, b, pixels)) {
            vals[k] = v;
            k += 1;
        }
        batch_means_variance(&vals[..k])
    }

    /// The variance of pixel i's value split in its two parts, each from the spread of
    /// its batch images: (the camera samples' mean, the splat image). The first falls with
    /// the pixel's own samples, the second with the light paths of the whole film.
    pub fn batch_variance_parts(&self, i: usize, pixels: usize) -> ([f64; 3], [f64; 3]) {
        let (mut cam, mut spl) = ([[0.0; 3]; BATCHES], [[0.0; 3]; BATCHES]);
        let mut k = 0;
        for b in 0..BATCHES {
            let n = self.batch_n[i][b];
            if n == 0 || self.batch_paths[b] == 0 {
                continue;
            }
            let km = 1.0 / (n as f64 * FIXED);
            let ks = pixels as f64 / (self.batch_paths[b] as f64 * FIXED);
            cam[k] = [0, 1, 2].map(|c| self.batch_sum[i][b][c] as f64 * km);
            spl[k] = [0, 1, 2].map(|c| self.batch_splat[i][b][c] as f64 * ks);
            k += 1;
        }
        (
            batch_means_variance(&cam[..k]),
            batch_means_variance(&spl[..k]),
        )
    }

    /// Add another splat film (exact).
    pub fn merge_from(&mut self, o: &SplatFilm) {
        for (a, b) in self.sum.iter_mut().zip(&o.sum) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.light_paths += o.light_paths;
        for i in 0..self.sum.len() {
            for b in 0..BATCHES {
                self.batch_n[i][b] += o.batch_n[i][b];
                for c in 0..3 {
                    self.batch_sum[i][b][c] += o.batch_sum[i][b][c];
                    self.batch_splat[i][b][c] += o.batch_splat[i][b][c];
                }
            }
        }
        for b in 0..BATCHES {
            self.batch_paths[b] += o.batch_paths[b];
        }
    }
}

/// The variance of the mean of k batch images (per channel): their spread / (k (k - 1));
/// zero with fewer than two.
fn batch_means_variance(vals: &[[f64; 3]]) -> [f64; 3] {
    let k = vals.len();
    if k < 2 {
        return [0.0; 3];
    }
    [0, 1, 2].map(|c| {
        let m = vals.iter().map(|v| v[c]).sum::<f64>() / k as f64;
        let ss = vals.iter().map(|v| (v[c] - m).powi(2)).sum::<f64>();
        ss / ((k * (k - 1)) as f64)
    })
}
