//! FLIP, NVIDIA's perceptual difference of a test image against a reference, as the
//! reference implementation computes it (Andersson et al., "FLIP: A Difference Evaluator
//! for Alternating Images", HPG 2020; "Visualizing Errors in Rendered High Dynamic Range
//! Images", Eurographics 2021; NVlabs/flip 1.x, `flip-evaluator` on PyPI):
//!
//! - LDR-FLIP (8-bit images, values in [0, 1]): both images to YCxCz, filtered by the
//!   contrast sensitivity functions (separable: Y, Cx and a sum of two Gaussians for Cz),
//!   clamped in linear RGB, to CIELab with the Hunt adjustment, the HyAB distance raised to
//!   0.7 and remapped to [0, 1]; edges and points of the luminance (first and second
//!   derivatives of a Gaussian) raise the colour error to the power 1 - feature difference.
//! - HDR-FLIP (linear radiance): the maximum of LDR-FLIP over exposures of both images
//!   tone-mapped by ACES, the exposure range found from the reference's luminances.
//!
//! Everything is in f32 as in the reference; its edges are clamped to the border pixel.
//! The mean of the per-pixel map is the FLIP value (0: identical, 1: as different as
//! green and blue). The viewing condition is the reference's default, 67 pixels per degree
//! (0.7 m from a 0.7 m wide 3840-pixel screen).

// The constants are written as the reference implementation writes them (rounded to f32).
#![allow(clippy::excessive_precision)]

use crate::image_io::RgbImage;
use rayon::prelude::*;

/// Pixels per degree of visual angle: 0.7 m * (3840 px / 0.7 m) * pi / 180.
pub const DEFAULT_PPD: f32 = 0.7 * (3840.0 / 0.7) * (std::f32::consts::PI / 180.0);

/// Which FLIP: LDR for 8-bit images (PNG), HDR for radiance (EXR, PFM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    Ldr,
    Hdr,
}

impl Range {
    pub fn name(self) -> &'static str {
        match self {
            Range::Ldr => "LDR",
            Range::Hdr => "HDR",
        }
    }
}

/// The FLIP of files: LDR when every one is an 8-bit PNG, else HDR.
pub fn range_of(paths: &[&std::path::Path]) -> Range {
    let png =
        |p: &&std::path::Path| crate::image_io::format_of(p) == Ok(crate::image_io::Format::Png);
    if paths.iter().all(png) {
        Range::Ldr
    } else {
        Range::Hdr
    }
}

/// A FLIP evaluation: the per-pixel map in [0, 1] (row-major) and its mean.
#[derive(Clone, Debug)]
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub map: Vec<f32>,
    pub mean: f64,
}

// The paper's constants: colour exponent, the share of the range below the cutoff, the
// cutoff's place, the feature filter's width in degrees, the feature exponent.
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
const W: f32 = 0.082;
const QF: f32 = 0.5;
// The contrast sensitivity functions as Gaussians a * sqrt(pi / b) * exp(-pi^2 x^2 / b)
// (Y, Cx, then the two of Cz).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2_CZ: f32 = 13.5;
const B2_CZ: f32 = 0.025;
const ILLUMINANT: [f32; 3] = [0.950428545, 1.0, 1.088900371];
const INV_ILLUMINANT: [f32; 3] = [1.052156925, 1.0, 0.918357670];
/// ACES (with the 0.6 pre-exposure cancelled): (a x^2 + b x + c) / (d x^2 + e x + f).
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

type C3 = [f32; 3];

fn rgb_to_xyz(c: C3) -> C3 {
    let m = [
        [
            10135552.0 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    let f = |r: [f32; 3]| r[0] * c[0] + r[1] * c[1] + r[2] * c[2];
    [f(m[0]), f(m[1]), f(m[2])]
}

fn xyz_to_rgb(c: C3) -> C3 {
    let m = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    let f = |r: [f32; 3]| r[0] * c[0] + r[1] * c[1] + r[2] * c[2];
    [f(m[0]), f(m[1]), f(m[2])]
}

fn xyz_to_ycxcz(c: C3) -> C3 {
    let (x, y, z) = (
        c[0] * INV_ILLUMINANT[0],
        c[1] * INV_ILLUMINANT[1],
        c[2] * INV_ILLUMINANT[2],
    );
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: C3) -> C3 {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    [x * ILLUMINANT[0], y * ILLUMINANT[1], z * ILLUMINANT[2]]
}

fn xyz_to_lab(c: C3) -> C3 {
    let delta = 6.0f32 / 29.0;
    let cube = delta * delta * delta;
    let f = |v: f32| {
        if v > cube {
            v.powf(1.0 / 3.0)
        } else {
            v / (3.0 * delta * delta) + 4.0 / 29.0
        }
    };
    let (x, y, z) = (
        f(c[0] * INV_ILLUMINANT[0]),
        f(c[1] * INV_ILLUMINANT[1]),
        f(c[2] * INV_ILLUMINANT[2]),
    );
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// CIELab with the Hunt effect: chroma scaled by 0.01 * L.
fn hunt(lab: C3) -> C3 {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

fn hyab(a: C3, b: C3) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The largest colour distance: green against blue, raised to QC.
fn max_distance() -> f32 {
    let g = hunt(xyz_to_lab(rgb_to_xyz([0.0, 1.0, 0.0])));
    let b = hunt(xyz_to_lab(rgb_to_xyz([0.0, 0.0, 1.0])));
    hyab(g, b).powf(QC)
}

fn gaussian_ab(x2: f32, a: f32, b: f32) -> f32 {
    let pi = std::f32::consts::PI;
    a * (pi / b).sqrt() * (-pi * pi * x2 / b).exp()
}

/// The square root of a Gaussian's weight: the Cz filter is a sum of two Gaussians,
/// separated as two passes whose products add up (the reference's separatedConvolutions).
fn gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    let pi = std::f32::consts::PI;
    (a * (pi / b).sqrt()).sqrt() * (-pi * pi * x2 / b).exp()
}

/// The separable spatial filters: per tap (Y, Cx) and the two Cz parts.
fn spatial_filters(ppd: f32) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let pi_sq = std::f32::consts::PI * std::f32::consts::PI;
    let max_b = B1[0].max(B1[1]).max(B1[2]).max(B2_CZ);
    let r = (3.0 * (max_b / (2.0 * pi_sq)).sqrt() * ppd).ceil() as i32;
    let (mut ycx, mut cz) = (Vec::new(), Vec::new());
    let (mut s_ycx, mut s_cz) = ([0f32; 2], [0f32; 2]);
    for i in -r..=r {
        let x = i as f32 / ppd;
        let x2 = x * x;
        let a = [gaussian_ab(x2, A1[0], B1[0]), gaussian_ab(x2, A1[1], B1[1])];
        let b = [
            gaussian_sqrt(x2, A1[2], B1[2]),
            gaussian_sqrt(x2, A2_CZ, B2_CZ),
        ];
        for k in 0..2 {
            s_ycx[k] += a[k];
            s_cz[k] += b[k];
        }
        ycx.push(a);
        cz.push(b);
    }
    let n_cz = 1.0 / (s_cz[0] * s_cz[0] + s_cz[1] * s_cz[1]).sqrt();
    for w in &mut ycx {
        w[0] /= s_ycx[0];
        w[1] /= s_ycx[1];
    }
    for w in &mut cz {
        w[0] *= n_cz;
        w[1] *= n_cz;
    }
    (ycx, cz)
}

/// The feature filter: per tap the Gaussian, its first and its second derivative, each
/// normalised (the Gaussian to sum 1, the derivatives' positive and negative parts to 1
/// and -1).
fn feature_filter(ppd: f32) -> Vec<C3> {
    let sd = 0.5 * W * ppd;
    let r = (3.0 * sd).ceil() as i32;
    let mut taps = Vec::new();
    let (mut g_sum, mut d_pos, mut d_neg, mut dd_pos, mut dd_neg) = (0f32, 0f32, 0f32, 0f32, 0f32);
    for i in -r..=r {
        let x = i as f32;
        let g = (-(x * x) / (2.0 * sd * sd)).exp();
        let dg = -x * g;
        let ddg = (x * x / (sd * sd) - 1.0) * g;
        g_sum += g;
        if dg > 0.0 {
            d_pos += dg
        } else {
            d_neg -= dg
        }
        if ddg > 0.0 {
            dd_pos += ddg
        } else {
            dd_neg -= ddg
        }
        taps.push([g, dg, ddg]);
    }
    for t in &mut taps {
        t[0] /= g_sum;
        t[1] /= if t[1] > 0.0 { d_pos } else { d_neg };
        t[2] /= if t[2] > 0.0 { dd_pos } else { dd_neg };
    }
    taps
}

/// Separable convolution of `n` channels per pixel, clamped at the border: `row` gives the
/// weights of one pass per tap. `horizontal` then `vertical` pass are written by the caller.
fn convolve<const N: usize, T: Copy + Sync, F>(
    src: &[T],
    (w, h): (usize, usize),
    taps: usize,
    horizontal: bool,
    f: F,
) -> Vec<[f32; N]>
where
    F: Fn(usize, T) -> [f32; N] + Sync,
{
    let r = (taps / 2) as isize;
    let mut out = vec![[0f32; N]; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = [0f32; N];
            for t in 0..taps {
                let d = t as isize - r;
                let i = if horizontal {
                    let xx = (x as isize + d).clamp(0, w as isize - 1) as usize;
                    y * w + xx
                } else {
                    let yy = (y as isize + d).clamp(0, h as isize - 1) as usize;
                    yy * w + x
                };
                let v = f(t, src[i]);
                for k in 0..N {
                    acc[k] += v[k];
                }
            }
            *o = acc;
        }
    });
    out
}

/// LDR-FLIP of linear RGB images with values in [0, 1] (clamped): the per-pixel map.
pub fn ldr_flip(reference: &[C3], test: &[C3], w: usize, h: usize, ppd: f32) -> Vec<f32> {
    let to_ycxcz = |img: &[C3]| -> Vec<C3> {
        img.iter()
            .map(|c| xyz_to_ycxcz(rgb_to_xyz(c.map(|v| v.clamp(0.0, 1.0)))))
            .collect()
    };
    let (r, t) = (to_ycxcz(reference), to_ycxcz(test));
    let (ycx, cz) = spatial_filters(ppd);
    let n = ycx.len();
    // colour: per image, horizontal pass to (Y, Cx, Cz1, Cz2), then vertical
    let filtered = |img: &[C3]| -> Vec<C3> {
        let hx = convolve::<4, C3, _>(img, (w, h), n, true, |k, c| {
            [
                ycx[k][0] * c[0],
                ycx[k][1] * c[1],
                cz[k][0] * c[2],
                cz[k][1] * c[2],
            ]
        });
        let v = convolve::<4, [f32; 4], _>(&hx, (w, h), n, false, |k, c| {
            [
                ycx[k][0] * c[0],
                ycx[k][1] * c[1],
                cz[k][0] * c[2],
                cz[k][1] * c[3],
            ]
        });
        v.iter()
            .map(|c| {
                let rgb = xyz_to_rgb(ycxcz_to_xyz([c[0], c[1], c[2] + c[3]]));
                hunt(xyz_to_lab(rgb_to_xyz(rgb.map(|v| v.clamp(0.0, 1.0)))))
            })
            .collect()
    };
    let (fr, ft) = (filtered(&r), filtered(&t));
    let cmax = max_distance();
    let pccmax = PC * cmax;
    // features of the luminance, normalised to [0, 1]
    let ff = feature_filter(ppd);
    let m = ff.len();
    let features = |img: &[C3]| -> Vec<[f32; 4]> {
        let hx = convolve::<3, C3, _>(img, (w, h), m, true, |k, c| {
            let y = (c[0] + 16.0) / 116.0;
            [ff[k][1] * y, ff[k][2] * y, ff[k][0] * y]
        });
        // (dx, ddx, dy, ddy)
        convolve::<4, [f32; 3], _>(&hx, (w, h), m, false, |k, c| {
            [
                ff[k][0] * c[0],
                ff[k][0] * c[1],
                ff[k][1] * c[2],
                ff[k][2] * c[2],
            ]
        })
    };
    let (er, et) = (features(&r), features(&t));
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let mut c = hyab(fr[i], ft[i]).powf(QC);
            c = if c < pccmax {
                c * PT / pccmax
            } else {
                PT + (c - pccmax) / (cmax - pccmax) * (1.0 - PT)
            };
            let (a, b) = (er[i], et[i]);
            let edge = |f: [f32; 4]| (f[0] * f[0] + f[2] * f[2]).sqrt();
            let point = |f: [f32; 4]| (f[1] * f[1] + f[3] * f[3]).sqrt();
            let d = (edge(a) - edge(b)).abs().max((point(a) - point(b)).abs());
            let feature = (std::f32::consts::FRAC_1_SQRT_2 * d).powf(QF);
            c.powf(1.0 - feature)
        })
        .collect()
}

fn luminance(c: C3) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// HDR-FLIP's exposures (start, stop, count) from the reference: from the exposure that
/// maps its brightest pixel to where ACES reaches 0.85, to the one that does so for its
/// median. A reference whose median is black uses its darkest non-black pixel instead
/// (the reference implementation's range would be infinite), an all-black one exposure 0.
pub fn exposures(reference: &[C3]) -> (f32, f32, usize) {
    let t = 0.85f32;
    let (a, b, c) = (
        ACES[0] - t * ACES[3],
        ACES[1] - t * ACES[4],
        ACES[2] - t * ACES[5],
    );
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        d1 + (d1 * d1 - c / a).sqrt()
    };
    let mut lum: Vec<f32> = reference.iter().map(|&p| luminance(p)).collect();
    let y_max = lum.iter().copied().fold(f32::MIN, f32::max);
    let y_min = lum
        .iter()
        .copied()
        .filter(|&v| v != 0.0)
        .fold(f32::INFINITY, f32::min);
    let mid = lum.len() / 2;
    let y_median = *lum.select_nth_unstable_by(mid, |p, q| p.total_cmp(q)).1;
    let y_median = if y_median > 0.0 { y_median } else { y_min };
    let (start, stop) = if y_max > 0.0 && y_median.is_finite() {
        ((x_max / y_max).log2(), (x_max / y_median).log2())
    } else {
        (0.0, 0.0)
    };
    let n = ((stop - start).ceil().max(2.0)) as usize;
    (start, stop, n)
}

fn aces(v: f32) -> f32 {
    let t = &ACES;
    ((v * v * t[0] + v * t[1] + t[2]) / (v * v * t[3] + v * t[4] + t[5])).clamp(0.0, 1.0)
}

/// HDR-FLIP of linear radiance images: the per-pixel maximum of LDR-FLIP over the
/// exposures of [`exposures`], both images tone-mapped by ACES.
pub fn hdr_flip(reference: &[C3], test: &[C3], w: usize, h: usize, ppd: f32) -> Vec<f32> {
    let (start, stop, n) = exposures(reference);
    let step = (stop - start) / (n - 1) as f32;
    let mut out = vec![0f32; w * h];
    for i in 0..n {
        let k = 2f32.powf(start + i as f32 * step);
        let tone = |img: &[C3]| -> Vec<C3> {
            img.iter()
                .map(|c| c.map(|v| aces(v.max(0.0) * k)))
                .collect()
        };
        let m = ldr_flip(&tone(reference), &tone(test), w, h, ppd);
        for (o, v) in out.iter_mut().zip(m) {
            *o = o.max(v);
        }
    }
    out
}

/// FLIP of `test` against `reference` (linear RGB, the same size) at the default
/// viewing condition.
pub fn flip(test: &RgbImage, reference: &RgbImage, range: Range) -> Result<FlipMap, String> {
    if (test.width, test.height) != (reference.width, reference.height)
        || test.data.len() != reference.data.len()
    {
        return Err(format!(
            "image sizes differ: the test image is {}x{}, the reference is {}x{}",
            test.width, test.height, reference.width, reference.height
        ));
    }
    if test.data.is_empty() {
        return Err("the images have no pixels to compare".into());
    }
    let (w, h) = (test.width as usize, test.height as usize);
    let map = match range {
        Range::Ldr => ldr_flip(&reference.data, &test.data, w, h, DEFAULT_PPD),
        Range::Hdr => hdr_flip(&reference.data, &test.data, w, h, DEFAULT_PPD),
    };
    let mean = map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64;
    Ok(FlipMap {
        width: test.width,
        height: test.height,
        map,
        mean,
    })
}

/// The magma colour map (as the reference's error maps use) at t in [0, 1], 8-bit sRGB:
/// matplotlib's magma table (public domain) at every 16th of its 256 entries and the
/// last, linearly interpolated (within one 8-bit step of the full table).
pub fn magma(t: f32) -> [u8; 3] {
    const KNOTS: [[f32; 3]; 17] = [
        [0.001462, 0.000466, 0.013866],
        [0.039608, 0.031090, 0.133515],
        [0.113094, 0.065492, 0.276784],
        [0.211718, 0.061992, 0.418647],
        [0.316654, 0.071690, 0.485380],
        [0.414709, 0.110431, 0.504662],
        [0.512831, 0.148179, 0.507648],
        [0.613617, 0.181811, 0.498536],
        [0.716387, 0.214982, 0.475290],
        [0.816914, 0.255895, 0.436461],
        [0.904281, 0.319610, 0.388137],
        [0.960949, 0.418323, 0.359630],
        [0.986700, 0.535582, 0.382210],
        [0.996096, 0.653659, 0.446213],
        [0.996898, 0.769591, 0.534892],
        [0.992440, 0.884330, 0.640099],
        [0.987053, 0.991438, 0.749504],
    ];
    let t = if t.is_nan() { 1.0 } else { t.clamp(0.0, 1.0) };
    // table index 0..255; knot k is entry 16 k, the last knot entry 255
    let idx = t * 255.0;
    let k = ((idx / 16.0) as usize).min(15);
    let (a, b) = (
        16.0 * k as f32,
        if k == 15 {
            255.0
        } else {
            16.0 * (k + 1) as f32
        },
    );
    let f = ((idx - a) / (b - a)).clamp(0.0, 1.0);
    let mut out = [0u8; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let v = KNOTS[k][c] + f * (KNOTS[k + 1][c] - KNOTS[k][c]);
        *o = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_no_error_and_green_blue_the_most() {
        let a: Vec<C3> = (0..64).map(|i| [i as f32 / 64.0, 0.5, 0.25]).collect();
        assert!(ldr_flip(&a, &a, 8, 8, DEFAULT_PPD)
            .iter()
            .all(|&v| v == 0.0));
        let g = vec![[0.0, 1.0, 0.0]; 64 * 64];
        let b = vec![[0.0, 0.0, 1.0]; 64 * 64];
        let m = ldr_flip(&g, &b, 64, 64, DEFAULT_PPD);
        // flat fields: no features, the colour error is the maximum, 1
        assert!(m.iter().all(|&v| (v - 1.0).abs() < 1e-4), "{}", m[0]);
    }

    #[test]
    fn magma_ends_match_the_table() {
        // matplotlib's magma: (0.001462, 0.000466, 0.013866) .. (0.987053, 0.991438, 0.749504)
        assert_eq!(magma(0.0), [0, 0, 4]);
        assert_eq!(magma(1.0), [252, 253, 191]);
        // the middle of the table, entry 128 (0.716387, 0.214982, 0.475290) at 128/255
        assert_eq!(magma(128.0 / 255.0), [183, 55, 121]);
    }

    #[test]
    fn exposure_range_follows_the_reference() {
        // ACES reaches 0.85 at x_max; brightest 4 and median 1: exposures log2(x/4) ..
        // log2(x), two apart: max(2, ceil(2)) = 2 steps
        let img = vec![[4.0; 3], [1.0; 3], [1.0; 3]];
        let (s, e, n) = exposures(&img);
        assert!((e - s - 2.0).abs() < 1e-5 && n == 2, "{s} {e} {n}");
        let black = vec![[0.0; 3]; 4];
        assert_eq!(exposures(&black), (0.0, 0.0, 2));
    }
}
