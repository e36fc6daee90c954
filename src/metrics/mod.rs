//! Error metrics of a test image `x` against a reference `y` (both linear RGB, same size).
//!
//! - [`mse`] / [`rmse`]: over all pixels and channels;
//! - [`relmse`]: mean of (x - y)^2 / (y^2 + 0.01) over pixels and channels;
//! - [`perceptual_error`]: the paper's perceptual measure, the number (and share) of pixels
//!   whose relative colour error ||x - y|| / ||y|| exceeds 5% (sum-of-abs norm);
//! - [`luminance_ratio`]: mean Rec.709 luminance of x over that of y (energy bias);
//! - [`efficiency`]: 1 / (error * seconds);
//! - [`flip`]: NVIDIA's perceptual FLIP (LDR for 8-bit images, HDR for radiance), and the
//!   false-colour maps of it and of [`relative_error_map`].
//!
//! All accumulate in f64. Non-finite pixels propagate into the results (NaN), on purpose:
//! a broken image should not get a good score; [`check_comparable`] refuses such images
//! (and images without pixels) up front, naming the file, where a user gives them.

pub mod flip;

use crate::image_io::RgbImage;
use serde::Serialize;

/// Epsilon of [`relmse`]'s denominator: (x - y)^2 / (y^2 + RELMSE_EPS). 0.01 is the usual
/// choice in the denoising literature (e.g. Rousselle et al.); it keeps near-black
/// reference pixels from dominating: below y ~ 0.1 the error counts as absolute.
pub const RELMSE_EPS: f64 = 1e-2;

/// Relative colour error threshold of [`perceptual_error`] (paper §6: five percent).
pub const PERCEPTUAL_THRESHOLD: f64 = 0.05;

/// Floor of ||y|| in [`perceptual_error`], relative to the image's mean ||y||: pixels
/// darker than 1% of the average are judged against that 1%, so black pixels with a
/// little noise do not all count as 100% wrong, and the measure stays scale-invariant.
pub const PERCEPTUAL_FLOOR: f64 = 1e-2;

/// Rec.709 / sRGB luminance weights.
pub const REC709: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Refuse an image that cannot be judged or judged against: no pixels, or NaN or
/// infinite values (the metrics would be NaN, or an empty image would "match"). `name`
/// (the file) starts the message.
pub fn check_comparable(img: &RgbImage, name: &str) -> Result<(), String> {
    if img.data.is_empty() {
        return Err(format!(
            "{name}: the image is {}x{}: it has no pixels to compare",
            img.width, img.height
        ));
    }
    let (mut nan, mut inf, mut first) = (0u64, 0u64, None);
    for (i, p) in img.data.iter().enumerate() {
        let (n, f) = (
            p.iter().filter(|v| v.is_nan()).count(),
            p.iter().filter(|v| v.is_infinite()).count(),
        );
        if n + f > 0 {
            first.get_or_insert(i);
            nan += n as u64;
            inf += f as u64;
        }
    }
    match first {
        None => Ok(()),
        Some(i) => {
            let w = img.width.max(1) as usize;
            Err(format!(
                "{name}: {nan} NaN and {inf} infinite values (first at pixel x {}, y {}): an image with them cannot be compared",
                i % w,
                i / w
            ))
        }
    }
}

fn check(x: &RgbImage, y: &RgbImage) -> Result<(), String> {
    if (x.width, x.height) != (y.width, y.height) {
        return Err(format!(
            "image sizes differ: the test image is {}x{}, the reference is {}x{}",
            x.width, x.height, y.width, y.height
        ));
    }
    if x.data.len() != y.data.len() {
        return Err(format!(
            "image data sizes differ: {} and {} pixels",
            x.data.len(),
            y.data.len()
        ));
    }
    if x.data.is_empty() {
        return Err(format!(
            "the images are {}x{}: no pixels to compare",
            x.width, x.height
        ));
    }
    Ok(())
}

fn mean_over_channels(x: &RgbImage, y: &RgbImage, f: impl Fn(f64, f64) -> f64) -> f64 {
    let mut s = 0.0f64;
    for (a, b) in x.data.iter().zip(&y.data) {
        for c in 0..3 {
            s += f(a[c] as f64, b[c] as f64);
        }
    }
    s / (3 * x.data.len().max(1)) as f64
}

/// Mean squared error over all pixels and channels.
pub fn mse(x: &RgbImage, y: &RgbImage) -> Result<f64, String> {
    check(x, y)?;
    Ok(mean_over_channels(x, y, |a, b| (a - b) * (a - b)))
}

/// Root mean squared error over all pixels and channels.
pub fn rmse(x: &RgbImage, y: &RgbImage) -> Result<f64, String> {
    mse(x, y).map(f64::sqrt)
}

/// Relative MSE: mean over pixels and channels of (x - y)^2 / (y^2 + [`RELMSE_EPS`]).
pub fn relmse(x: &RgbImage, y: &RgbImage) -> Result<f64, String> {
    check(x, y)?;
    Ok(mean_over_channels(x, y, |a, b| {
        (a - b) * (a - b) / (b * b + RELMSE_EPS)
    }))
}

fn norm(c: [f32; 3]) -> f64 {
    c.iter().map(|v| (*v as f64).abs()).sum()
}

/// The paper's perceptual error (§6, after Prikryl and Purgathofer): the number and the
/// share of pixels with ||x - y|| > 5% * max(||y||, floor), ||.|| the sum of absolute
/// components, floor = [`PERCEPTUAL_FLOOR`] * mean ||y||. With an all-black reference
/// every pixel that differs at all counts.
pub fn perceptual_error(x: &RgbImage, y: &RgbImage) -> Result<(u64, f64), String> {
    check(x, y)?;
    let n = x.data.len();
    let mean_norm = y.data.iter().map(|&c| norm(c)).sum::<f64>() / n.max(1) as f64;
    let floor = PERCEPTUAL_FLOOR * mean_norm;
    let count = x
        .data
        .iter()
        .zip(&y.data)
        .filter(|(a, b)| {
            let d = norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
            // Written as a product: no 0/0 when both the error and the reference are 0.
            // A NaN error counts as exceeding.
            d.is_nan() || d > PERCEPTUAL_THRESHOLD * norm(**b).max(floor)
        })
        .count() as u64;
    Ok((count, count as f64 / n.max(1) as f64))
}

/// Mean Rec.709 luminance of an image.
pub fn mean_luminance(img: &RgbImage) -> f64 {
    let m = img.mean();
    REC709[0] * m[0] + REC709[1] * m[1] + REC709[2] * m[2]
}

/// Mean luminance of x over mean luminance of y (1 = no energy bias). Both black: 1;
/// only the reference black: infinity (written as `null` in JSON).
pub fn luminance_ratio(x: &RgbImage, y: &RgbImage) -> Result<f64, String> {
    check(x, y)?;
    let (lx, ly) = (mean_luminance(x), mean_luminance(y));
    Ok(if lx == 0.0 && ly == 0.0 { 1.0 } else { lx / ly })
}

/// Per-pixel relative colour error of x against y, as [`perceptual_error`] measures it:
/// ||x - y|| / max(||y||, floor) (row-major; 0.05 is the perceptual threshold).
pub fn relative_error_map(x: &RgbImage, y: &RgbImage) -> Result<Vec<f32>, String> {
    check(x, y)?;
    let n = x.data.len();
    let mean_norm = y.data.iter().map(|&c| norm(c)).sum::<f64>() / n.max(1) as f64;
    let floor = PERCEPTUAL_FLOOR * mean_norm;
    Ok(x.data
        .iter()
        .zip(&y.data)
        .map(|(a, b)| {
            let d = norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
            let r = norm(*b).max(floor);
            if r > 0.0 {
                (d / r) as f32
            } else if d > 0.0 {
                f32::INFINITY
            } else {
                0.0
            }
        })
        .collect())
}

/// Which error a false-colour map shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MapKind {
    /// FLIP per pixel, 0 to 1.
    Flip,
    /// Relative colour error per pixel, 0 to 100%.
    Relative,
}

/// The false-colour map (magma, 8-bit sRGB rows) of x against y: FLIP of `range`, or the
/// relative colour error with 100% and more at the top of the scale.
pub fn error_map(
    x: &RgbImage,
    y: &RgbImage,
    kind: MapKind,
    range: flip::Range,
) -> Result<Vec<u8>, String> {
    let values = match kind {
        MapKind::Flip => flip::flip(x, y, range)?.map,
        MapKind::Relative => relative_error_map(x, y)?,
    };
    Ok(values.iter().flat_map(|&v| flip::magma(v)).collect())
}

/// Efficiency of a method: 1 / (error * seconds), higher is better (error: MSE or
/// relMSE; seconds: render time).
pub fn efficiency(mse: f64, seconds: f64) -> f64 {
    1.0 / (mse * seconds)
}

/// All metrics of one comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    pub width: u32,
    pub height: u32,
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
    /// Pixels with relative colour error above 5%.
    pub perceptual_count: u64,
    /// perceptual_count / pixels.
    pub perceptual_share: f64,
    pub luminance_ratio: f64,
    /// Mean FLIP (0: identical, 1: green against blue), of the dynamic range in `flip_range`.
    pub flip: f64,
    /// "LDR" (8-bit images) or "HDR" (radiance): which FLIP `flip` is.
    pub flip_range: &'static str,
    /// Render time, if known.
    pub seconds: Option<f64>,
    /// 1 / (mse * seconds).
    pub efficiency: Option<f64>,
    /// 1 / (relmse * seconds).
    pub efficiency_relmse: Option<f64>,
}

impl Metrics {
    /// Compare test image `x` with reference `y` (radiance: HDR-FLIP).
    pub fn compute(x: &RgbImage, y: &RgbImage) -> Result<Metrics, String> {
        Metrics::compute_range(x, y, flip::Range::Hdr)
    }

    /// Compare test image `x` with reference `y`, FLIP of the given dynamic range.
    pub fn compute_range(
        x: &RgbImage,
        y: &RgbImage,
        range: flip::Range,
    ) -> Result<Metrics, String> {
        let m = mse(x, y)?;
        let (count, share) = perceptual_error(x, y)?;
        Ok(Metrics {
            width: x.width,
            height: x.height,
            mse: m,
            rmse: m.sqrt(),
            relmse: relmse(x, y)?,
            perceptual_count: count,
            perceptual_share: share,
            luminance_ratio: luminance_ratio(x, y)?,
            flip: flip::flip(x, y, range)?.mean,
            flip_range: range.name(),
            seconds: None,
            efficiency: None,
            efficiency_relmse: None,
        })
    }

    /// The same metrics with the render time and the efficiencies filled in.
    pub fn with_seconds(self, seconds: f64) -> Metrics {
        Metrics {
            seconds: Some(seconds),
            efficiency: Some(efficiency(self.mse, seconds)),
            efficiency_relmse: Some(efficiency(self.relmse, seconds)),
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, d: &[[f32; 3]]) -> RgbImage {
        RgbImage::new(w, h, d.to_vec())
    }

    #[test]
    fn hand_computed_values() {
        // x - y per channel: (0, 1, 2), (0, 0, -1), (0.02, 0, 0), (0, 0, 0)
        let x = img(
            2,
            2,
            &[[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [1.02, 1.0, 1.0], [0.5; 3]],
        );
        let y = img(
            2,
            2,
            &[[1.0, 1.0, 1.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.5; 3]],
        );
        // squares: 0 1 4 | 0 0 1 | 0.0004 0 0 | 0 0 0 -> 6.0004 / 12
        let m = mse(&x, &y).unwrap();
        assert!((m - 6.0004 / 12.0).abs() < 1e-7, "{m}");
        assert!((rmse(&x, &y).unwrap() - (6.0004f64 / 12.0).sqrt()).abs() < 1e-7);
        // relmse: (1 + 4 + 1 + 0.0004) / 1.01 (all nonzero terms have y = 1) / 12
        let r = relmse(&x, &y).unwrap();
        assert!((r - 6.0004 / 1.01 / 12.0).abs() < 1e-7, "{r}");
        // relative colour errors: 3/3, 1/1, 0.02/3, 0 -> two pixels above 5%
        assert_eq!(perceptual_error(&x, &y).unwrap(), (2, 0.5));
        // luminance: x mean = (2.52/4, 3.5/4, 4.5/4), y mean = (2.5/4, 2.5/4, 3.5/4)
        let lx = 0.2126 * 2.52 + 0.7152 * 3.5 + 0.0722 * 4.5;
        let ly = 0.2126 * 2.5 + 0.7152 * 2.5 + 0.0722 * 3.5;
        assert!((luminance_ratio(&x, &y).unwrap() - lx / ly).abs() < 1e-6);
        assert_eq!(efficiency(0.5, 4.0), 0.5);

        let all = Metrics::compute(&x, &y).unwrap().with_seconds(2.0);
        assert_eq!(all.perceptual_count, 2);
        assert!((all.efficiency.unwrap() - 1.0 / (m * 2.0)).abs() < 1e-6);
        assert!((all.efficiency_relmse.unwrap() - 1.0 / (r * 2.0)).abs() < 1e-6);
        let json = serde_json::to_string(&all).unwrap();
        for key in [
            "rmse",
            "relmse",
            "perceptual_share",
            "luminance_ratio",
            "efficiency",
        ] {
            assert!(json.contains(key), "{json}");
        }
    }

    #[test]
    fn identical_images_score_perfectly() {
        let x = img(3, 1, &[[0.0; 3], [1.0, 0.5, 0.25], [4.0; 3]]);
        let m = Metrics::compute(&x, &x).unwrap();
        assert_eq!((m.mse, m.relmse, m.perceptual_count), (0.0, 0.0, 0));
        assert_eq!(m.luminance_ratio, 1.0);
        let black = img(2, 1, &[[0.0; 3], [0.0; 3]]);
        assert_eq!(luminance_ratio(&black, &black).unwrap(), 1.0);
        assert_eq!(perceptual_error(&black, &black).unwrap(), (0, 0.0));
    }

    #[test]
    fn dark_pixels_use_the_floor() {
        // mean ||y|| = (0 + 30) / 2 = 15, floor = 0.15, 5% of it = 0.0075.
        let y = img(2, 1, &[[0.0; 3], [10.0; 3]]);
        let small = img(2, 1, &[[0.002; 3], [10.0; 3]]); // ||d|| = 0.006: below
        let big = img(2, 1, &[[0.003; 3], [10.0; 3]]); // ||d|| = 0.009: above
        assert_eq!(perceptual_error(&small, &y).unwrap().0, 0);
        assert_eq!(perceptual_error(&big, &y).unwrap().0, 1);
        // relmse near black counts as absolute error / 0.01.
        let r = relmse(&big, &y).unwrap();
        assert!((r - 3.0 * 0.003f64.powi(2) / 0.01 / 6.0).abs() < 1e-9);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = img(2, 1, &[[0.0; 3]; 2]);
        let b = img(1, 2, &[[0.0; 3]; 2]);
        let e = rmse(&a, &b).unwrap_err();
        assert!(e.contains("2x1") && e.contains("1x2"), "{e}");
        assert!(Metrics::compute(&a, &b).is_err());
    }

    #[test]
    fn nan_infinite_and_empty_images_are_not_comparable() {
        let good = img(2, 1, &[[0.5; 3], [1.0; 3]]);
        assert!(check_comparable(&good, "g.pfm").is_ok());
        let nan = img(2, 1, &[[0.5; 3], [0.0, f32::NAN, 0.0]]);
        let e = check_comparable(&nan, "n.pfm").unwrap_err();
        assert!(
            e.starts_with("n.pfm: 1 NaN and 0 infinite") && e.contains("x 1, y 0"),
            "{e}"
        );
        let inf = img(1, 1, &[[f32::INFINITY, f32::NEG_INFINITY, 1.0]]);
        let e = check_comparable(&inf, "i.pfm").unwrap_err();
        assert!(e.contains("0 NaN and 2 infinite"), "{e}");
        let empty = img(0, 0, &[]);
        let e = check_comparable(&empty, "e.pfm").unwrap_err();
        assert!(e.contains("0x0"), "{e}");
        // an empty pair no longer "matches perfectly"
        assert!(Metrics::compute(&empty, &empty).is_err());
    }
}
