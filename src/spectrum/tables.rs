//! Per-band tables for the uplift and output of `Spectrum<N>`, computed once per N.

use std::sync::OnceLock;

pub const LAMBDA_MIN: f64 = 380.0;
pub const LAMBDA_MAX: f64 = 780.0;

/// Tables for one band count.
pub struct SpectralTables {
    /// uplift[k] = (b_r, b_g, b_b) averaged over band k.
    pub uplift: Vec<[f32; 3]>,
    /// output[c][k]: linear sRGB channel c per unit of band k.
    pub output: [Vec<f32>; 3],
    /// Luminance per unit of band k.
    pub luminance: Vec<f32>,
}

/// Wavelength range [lo, hi) of band k of n, in nm.
pub fn band_range(k: usize, n: usize) -> (f64, f64) {
    let w = (LAMBDA_MAX - LAMBDA_MIN) / n as f64;
    (LAMBDA_MIN + w * k as f64, LAMBDA_MIN + w * (k + 1) as f64)
}

/// Piecewise Gaussian of the multi-lobe CIE fit.
fn g(l: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let s = if l < mu { s1 } else { s2 };
    let t = (l - mu) / s;
    (-0.5 * t * t).exp()
}

/// CIE 1931 2-degree matching functions (Wyman, Sloan, Shirley 2013, multi-lobe fit).
pub fn cie_xyz(l: f64) -> [f64; 3] {
    let x = 1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
        - 0.065 * g(l, 501.1, 20.4, 26.2);
    let y = 0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1);
    let z = 1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8);
    [x, y, z]
}

const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

/// The RGB basis spectra: logistic steps at 490 nm and 590 nm; they sum to 1.
fn basis(l: f64) -> [f64; 3] {
    let b = 1.0 / (1.0 + ((l - 490.0) / 10.0).exp());
    let r = 1.0 / (1.0 + (-(l - 590.0) / 10.0).exp());
    [r, 1.0 - r - b, b]
}

fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let d = 1.0 / det;
    [
        [
            (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * d,
            (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * d,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * d,
        ],
        [
            (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * d,
            (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * d,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * d,
        ],
        [
            (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * d,
            (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * d,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * d,
        ],
    ]
}

impl SpectralTables {
    fn compute(n: usize) -> Self {
        const STEPS: usize = 200;
        let mut uplift = vec![[0.0f32; 3]; n];
        // P[c][k]: sRGB channel c of a unit spectrum on band k (unnormalised).
        let mut p = vec![[0.0f64; 3]; n];
        for k in 0..n {
            let (lo, hi) = band_range(k, n);
            let dl = (hi - lo) / STEPS as f64;
            let mut ub = [0.0f64; 3];
            let mut xyz = [0.0f64; 3];
            for i in 0..STEPS {
                let l = lo + (i as f64 + 0.5) * dl;
                let b = basis(l);
                let c = cie_xyz(l);
                for j in 0..3 {
                    ub[j] += b[j] / STEPS as f64;
                    xyz[j] += c[j] * dl;
                }
            }
            uplift[k] = [ub[0] as f32, ub[1] as f32, ub[2] as f32];
            for c in 0..3 {
                p[k][c] = (0..3).map(|j| XYZ_TO_SRGB[c][j] * xyz[j]).sum();
            }
        }
        // A = P U (3x3); output = A^-1 P, so that output(uplift(rgb)) = rgb.
        let mut a = [[0.0f64; 3]; 3];
        for (r, row) in a.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = (0..n).map(|k| p[k][r] * uplift[k][c] as f64).sum();
            }
        }
        let ai = invert3(a);
        let mut output = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
        for (c, out) in output.iter_mut().enumerate() {
            for (k, o) in out.iter_mut().enumerate() {
                *o = (0..3).map(|j| ai[c][j] * p[k][j]).sum::<f64>() as f32;
            }
        }
        let luminance = (0..n)
            .map(|k| (0..3).map(|c| super::LUMINANCE_RGB[c] * output[c][k]).sum())
            .collect();
        SpectralTables {
            uplift,
            output,
            luminance,
        }
    }

    /// Tables for N bands (8 or 16; other counts are computed the same way).
    pub fn get(n: usize) -> &'static SpectralTables {
        static T8: OnceLock<SpectralTables> = OnceLock::new();
        static T16: OnceLock<SpectralTables> = OnceLock::new();
        static OTHER: OnceLock<std::sync::Mutex<Vec<(usize, &'static SpectralTables)>>> =
            OnceLock::new();
        match n {
            8 => T8.get_or_init(|| Self::compute(8)),
            16 => T16.get_or_init(|| Self::compute(16)),
            _ => {
                let m = OTHER.get_or_init(Default::default);
                let mut v = m.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((_, t)) = v.iter().find(|(k, _)| *k == n) {
                    return t;
                }
                let t: &'static SpectralTables = Box::leak(Box::new(Self::compute(n)));
                v.push((n, t));
                t
            }
        }
    }
}
