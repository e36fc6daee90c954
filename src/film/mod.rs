//! The film keeps statistics, not just sums: for every pixel the number of samples,
//! their mean and the sum of squared deviations (Welford, f64), per RGB channel.
//! One sample contributes to exactly one pixel (box filter), so each pixel's statistics
//! are its own: the filters, adaptive sampling and error estimates all read them.

use serde::Serialize;

/// Statistics of the samples of one pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    pub n: u32,
    pub mean: [f64; 3],
    /// Sum of squared deviations from the mean (Welford's M2).
    pub m2: [f64; 3],
}

impl PixelStats {
    /// Add one sample (Welford's update). The caller has checked it is finite.
    #[inline]
    #[allow(clippy::needless_range_loop)]
    pub fn push(&mut self, v: [f32; 3]) {
        self.n += 1;
        let inv = 1.0 / self.n as f64;
        for c in 0..3 {
            let x = v[c] as f64;
            let d = x - self.mean[c];
            self.mean[c] += d * inv;
            self.m2[c] += d * (x - self.mean[c]);
        }
    }

    /// Merge two sets of statistics (Chan et al.'s parallel update).
    pub fn merge(&self, o: &PixelStats) -> PixelStats {
        if self.n == 0 {
            return *o;
        }
        if o.n == 0 {
            return *self;
        }
        let n = self.n + o.n;
        let (na, nb, nn) = (self.n as f64, o.n as f64, n as f64);
        let mut r = PixelStats {
            n,
            ..Default::default()
        };
        for c in 0..3 {
            let d = o.mean[c] - self.mean[c];
            r.mean[c] = self.mean[c] + d * nb / nn;
            r.m2[c] = self.m2[c] + o.m2[c] + d * d * na * nb / nn;
        }
        r
    }

    /// Sample variance per channel (n - 1 denominator); 0 with fewer than two samples.
    #[inline]
    pub fn variance(&self) -> [f64; 3] {
        if self.n < 2 {
            return [0.0; 3];
        }
        let k = 1.0 / (self.n - 1) as f64;
        [self.m2[0] * k, self.m2[1] * k, self.m2[2] * k]
    }

    /// Variance of the mean per channel (sigma^2 / n).
    #[inline]
    pub fn variance_of_mean(&self) -> [f64; 3] {
        let v = self.variance();
        let n = self.n.max(1) as f64;
        [v[0] / n, v[1] / n, v[2] / n]
    }

    #[inline]
    pub fn mean_f32(&self) -> [f32; 3] {
        [
            self.mean[0] as f32,
            self.mean[1] as f32,
            self.mean[2] as f32,
        ]
    }
}

/// Counts of samples that were caught before reaching a pixel.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq, Eq)]
pub struct Rejections {
    pub nan: u64,
    pub infinite: u64,
}

impl Rejections {
    pub fn total(&self) -> u64 {
        self.nan + self.infinite
    }
    pub fn add(&mut self, o: &Rejections) {
        self.nan += o.nan;
        self.infinite += o.infinite;
    }
    /// Returns true if the sample may go into a pixel; counts it otherwise.
    #[inline]
    pub fn check(&mut self, v: &[f32; 3]) -> bool {
        if v.iter().all(|x| x.is_finite()) {
            return true;
        }
        if v.iter().any(|x| x.is_nan()) {
            self.nan += 1;
        } else {
            self.infinite += 1;
        }
        false
    }
}

/// Bytes of film storage per pixel (statistics plus the output images made from them).
pub const BYTES_PER_PIXEL: u64 = std::mem::size_of::<PixelStats>() as u64 + 3 * 4 * 4;

/// Largest film kalos agrees to allocate.
pub const MAX_FILM_BYTES: u64 = 8 << 30;

/// A width x height grid of pixel statistics, row-major, y = 0 at the top.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelStats>,
    pub rejected: Rejections,
}

impl Film {
    /// A film, or a clear error if the resolution is zero or would not fit in memory.
    pub fn new(width: u32, height: u32) -> Result<Film, String> {
        check_resolution(width, height)?;
        Ok(Film {
            width,
            height,
            pixels: vec![PixelStats::default(); width as usize * height as usize],
            rejected: Rejections::default(),
        })
    }

    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// The mean image, RGB interleaved.
    pub fn mean_rgb(&self) -> Vec<[f32; 3]> {
        self.pixels.iter().map(|p| p.mean_f32()).collect()
    }

    /// Per-pixel sample variance (n - 1 denominator), RGB.
    pub fn variance_rgb(&self) -> Vec<[f32; 3]> {
        self.pixels
            .iter()
            .map(|p| {
                let v = p.variance();
                [v[0] as f32, v[1] as f32, v[2] as f32]
            })
            .collect()
    }

    pub fn counts(&self) -> Vec<f32> {
        self.pixels.iter().map(|p| p.n as f32).collect()
    }

    pub fn total_samples(&self) -> u64 {
        self.pixels.iter().map(|p| p.n as u64).sum()
    }

    /// Merge another film of the same size into this one (pixel by pixel).
    pub fn merge(&mut self, o: &Film) {
        assert_eq!((self.width, self.height), (o.width, o.height));
        for (a, b) in self.pixels.iter_mut().zip(o.pixels.iter()) {
            *a = a.merge(b);
        }
        self.rejected.add(&o.rejected);
    }
}

/// Check that a film of this size can be made.
pub fn check_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!(
            "resolution {width}x{height}: width and height must be at least 1"
        ));
    }
    let bytes = width as u64 * height as u64 * BYTES_PER_PIXEL;
    if bytes > MAX_FILM_BYTES {
        return Err(format!(
            "resolution {width}x{height}: the film would need {:.1} GiB, more than the {} GiB kalos allows",
            bytes as f64 / (1u64 << 30) as f64,
            MAX_FILM_BYTES >> 30
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let xs = [1.0f32, 2.0, 4.0, 8.0, -3.0, 0.5];
        let mut p = PixelStats::default();
        for &x in &xs {
            p.push([x, 2.0 * x, 0.0]);
        }
        let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / xs.len() as f64;
        let var =
            xs.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
        assert!((p.mean[0] - mean).abs() < 1e-12);
        assert!((p.variance()[0] - var).abs() < 1e-12);
        assert!((p.variance()[1] - 4.0 * var).abs() < 1e-9);
        assert_eq!(p.variance()[2], 0.0);
    }

    #[test]
    fn merge_equals_sequential() {
        let mut a = PixelStats::default();
        let mut b = PixelStats::default();
        let mut all = PixelStats::default();
        for i in 0..10 {
            let v = [(i * i) as f32 * 0.1, i as f32, 1.0];
            all.push(v);
            if i < 4 {
                a.push(v)
            } else {
                b.push(v)
            }
        }
        let m = a.merge(&b);
        assert_eq!(m.n, all.n);
        for c in 0..3 {
            assert!((m.mean[c] - all.mean[c]).abs() < 1e-12);
            assert!((m.m2[c] - all.m2[c]).abs() < 1e-9);
        }
    }

    #[test]
    fn rejects_non_finite_samples() {
        let mut r = Rejections::default();
        assert!(r.check(&[1.0, 2.0, 3.0]));
        assert!(!r.check(&[f32::NAN, 2.0, 3.0]));
        assert!(!r.check(&[f32::INFINITY, 2.0, 3.0]));
        assert_eq!(
            r,
            Rejections {
                nan: 1,
                infinite: 1
            }
        );
    }

    #[test]
    fn resolution_limits() {
        assert!(Film::new(0, 0).is_err());
        assert!(Film::new(4, 0).is_err());
        assert!(check_resolution(100_000, 100_000).is_err());
        assert!(Film::new(3, 2).is_ok());
    }
}
