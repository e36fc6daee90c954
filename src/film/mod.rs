//! The film keeps statistics, not just sums: for every pixel the number of samples and
//! the sums of the samples and of their squares per RGB channel, plus the light-tracing
//! splats that estimators such as BDPT send to other pixels.
//!
//! Two kinds of input (pbrt-v4's `AddSample` / `AddSplat`):
//! - a *sample* belongs to its own pixel: `PixelStats` keeps per-pixel statistics, which
//!   the filters (DTF, the energy-preserving filter) and adaptive sampling read;
//! - a *splat* lands in any pixel: the film keeps its sum and the number of light paths
//!   that could splat; the splat image is sum x pixels / light_paths (1 / spp for a
//!   uniform render). One sample no longer maps to one pixel, so per-sample variance is
//!   meaningless there: the film also keeps `BATCHES` independent batch images (sample
//!   index mod B) and estimates the variance of a pixel's value from them (batch means).
//!
//! Sums are exact: each f32 value is turned into a fixed-point integer (`stats::FIXED`)
//! and integers add associatively, so the image does not depend on the order in which
//! samples, splats or film parts arrive: any thread count, any split into shards
//! (`file.rs`), the same bits.

mod file;
mod sink;
mod splat;
mod stats;

pub use file::{
    film_from_bytes, film_to_bytes, merge_files, read_film, write_film, FilmFile, FILM_VERSION,
};
pub use sink::{raster_pixel, Layer, RowOut, RowSink, Sink, Splat, Splats, StrategySample};
pub use splat::{SplatFilm, BATCHES};
pub use stats::{PixelStats, Rejections, SAMPLE_MAX};

/// Bytes of film storage per pixel (statistics plus the output images made from them).
pub const BYTES_PER_PIXEL: u64 = std::mem::size_of::<PixelStats>() as u64 + 3 * 4 * 4;

/// A width x height grid of pixel statistics, row-major, y = 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelStats>,
    pub rejected: Rejections,
    /// Splats and batch statistics; None until an estimator splats.
    pub splats: Option<Box<SplatFilm>>,
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
            splats: None,
        })
    }

    /// A film that also takes splats (and keeps batch statistics for them).
    pub fn with_splats(width: u32, height: u32) -> Result<Film, String> {
        let mut f = Film::new(width, height)?;
        f.splats = Some(Box::new(SplatFilm::new(f.pixels.len())));
        Ok(f)
    }

    /// Gives the film a splat image (empty) if it has none, keeping what it holds.
    pub fn ensure_splats(&mut self) {
        if self.splats.is_none() {
            let mut f = Film::with_splats(self.width, self.height).expect("same size");
            f.merge(self);
            *self = f;
        }
    }

    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Add one camera sample of sample index `index` to pixel `pixel` (checked finite).
    #[inline]
    pub fn add_sample(&mut self, pixel: usize, index: u32, v: [f32; 3]) {
        if self.rejected.check(&v) {
            self.pixels[pixel].push(v);
            if let Some(s) = &mut self.splats {
                s.add_sample(pixel, index, v);
            }
        }
    }

    /// The value of pixel `i`: the mean of its samples plus its splats.
    #[inline]
    pub fn value(&self, i: usize) -> [f64; 3] {
        let m = self.pixels[i].mean();
        match &self.splats {
            None => m,
            Some(s) => {
                let sp = s.splat_value(i, self.pixels.len());
                [m[0] + sp[0], m[1] + sp[1], m[2] + sp[2]]
            }
        }
    }

    /// The image: every pixel's value, RGB.
    pub fn mean_rgb(&self) -> Vec<[f32; 3]> {
        (0..self.pixels.len())
            .map(|i| self.value(i).map(|v| v as f32))
            .collect()
    }

    /// Variance of pixel `i`'s value (per channel): sigma^2 / n from its own samples, or,
    /// with splats, from the spread of the batch images (batch means). Every method that
    /// reads variance reads it here.
    pub fn variance_of_value(&self, i: usize) -> [f64; 3] {
        match &self.splats {
            None => self.pixels[i].variance_of_mean(),
            Some(s) => s.batch_variance(i, self.pixels.len()),
        }
    }

    /// Per-pixel variance of one sample (n - 1 denominator), RGB; with splats, the
    /// batch-means variance of the value scaled by n so that variance / n is the value's.
    pub fn variance_rgb(&self) -> Vec<[f32; 3]> {
        (0..self.pixels.len())
            .map(|i| match &self.splats {
                None => self.pixels[i].variance().map(|v| v as f32),
                Some(_) => {
                    let n = self.pixels[i].n.max(1) as f64;
                    self.variance_of_value(i).map(|v| (v * n) as f32)
                }
            })
            .collect()
    }

    pub fn counts(&self) -> Vec<f32> {
        self.pixels.iter().map(|p| p.n as f32).collect()
    }

    pub fn total_samples(&self) -> u64 {
        self.pixels.iter().map(|p| p.n as u64).sum()
    }

    /// Merge another film of the same size into this one: exact, in any order.
    pub fn merge(&mut self, o: &Film) {
        assert_eq!((self.width, self.height), (o.width, o.height));
        for (a, b) in self.pixels.iter_mut().zip(o.pixels.iter()) {
            a.merge_from(b);
        }
        self.rejected.add(&o.rejected);
        match (&mut self.splats, &o.splats) {
            (Some(a), Some(b)) => a.merge_from(b),
            (None, Some(b)) => self.splats = Some(b.clone()),
            _ => {}
        }
    }
}

/// Largest film kalos agrees to allocate: what the machine has available (or 8 GiB where
/// that cannot be read).
pub fn max_film_bytes() -> u64 {
    available_memory().unwrap_or(8 << 30)
}

/// The memory the system says is available (Linux: MemAvailable), in bytes.
pub fn available_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Check that a film of this size can be made.
pub fn check_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!(
            "resolution {width}x{height}: width and height must be at least 1"
        ));
    }
    let bytes = width as u64 * height as u64 * BYTES_PER_PIXEL;
    let max = max_film_bytes();
    if bytes > max {
        return Err(format!(
            "resolution {width}x{height}: the film would need {:.1} GiB, more than the {:.1} GiB of memory available",
            bytes as f64 / (1u64 << 30) as f64,
            max as f64 / (1u64 << 30) as f64
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
