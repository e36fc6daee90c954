//! Spectral radiance carried on N bands at once: `Spectrum<3>` is plain linear RGB,
//! `Spectrum<8>` and `Spectrum<16>` are equal-width bands over 380..780 nm.
//!
//! RGB inputs are uplifted with three smooth basis spectra b_r + b_g + b_b = 1 (a
//! partition of unity), so a white (1, 1, 1) reflectance is exactly 1 on every band and
//! reflectances in [0, 1] stay in [0, 1]. Bands go to output through the CIE 1931 matching
//! functions (Wyman, Sloan and Shirley's multi-lobe fit) and XYZ -> linear sRGB; the output
//! matrix is normalised so that uplift followed by output is the identity on RGB, so the
//! furnace answer (1 everywhere) holds in every mode.

mod tables;

use std::ops::{Add, AddAssign, Div, Index, IndexMut, Mul, MulAssign, Sub};

pub use tables::{band_range, cie_xyz, SpectralTables};

/// Rec. 709 / sRGB luminance weights.
pub const LUMINANCE_RGB: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// N spectral samples (bands) carried together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectrum<const N: usize>(pub [f32; N]);

impl<const N: usize> Default for Spectrum<N> {
    fn default() -> Self {
        Self::ZERO
    }
}

impl<const N: usize> Spectrum<N> {
    pub const ZERO: Self = Spectrum([0.0; N]);
    pub const ONE: Self = Spectrum([1.0; N]);

    #[inline]
    pub fn splat(v: f32) -> Self {
        Spectrum([v; N])
    }

    /// Uplift a linear RGB triple to the bands (identity when N = 3).
    #[inline]
    pub fn from_rgb(rgb: [f32; 3]) -> Self {
        if N == 3 {
            let mut s = [0.0; N];
            s.copy_from_slice(&rgb[..N]);
            return Spectrum(s);
        }
        let t = SpectralTables::get(N);
        let mut s = [0.0; N];
        for (k, v) in s.iter_mut().enumerate() {
            let u = &t.uplift[k];
            *v = u[0] * rgb[0] + u[1] * rgb[1] + u[2] * rgb[2];
        }
        Spectrum(s)
    }

    /// Linear sRGB of this spectrum (identity when N = 3).
    #[inline]
    pub fn to_rgb(&self) -> [f32; 3] {
        if N == 3 {
            return [self.0[0], self.0[1], self.0[2]];
        }
        let t = SpectralTables::get(N);
        let mut out = [0.0f32; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let row = &t.output[c];
            *o = self.0.iter().zip(row.iter()).map(|(a, b)| a * b).sum();
        }
        out
    }

    /// Luminance (Y of the output RGB).
    #[inline]
    pub fn luminance(&self) -> f32 {
        if N == 3 {
            return LUMINANCE_RGB[0] * self.0[0]
                + LUMINANCE_RGB[1] * self.0[1]
                + LUMINANCE_RGB[2] * self.0[2];
        }
        let w = &SpectralTables::get(N).luminance;
        self.0.iter().zip(w.iter()).map(|(a, b)| a * b).sum()
    }

    /// Per-band weights h_l that make `luminance` a weighted sum.
    pub fn luminance_weights() -> Spectrum<N> {
        if N == 3 {
            let mut s = [0.0; N];
            s.copy_from_slice(&LUMINANCE_RGB[..N]);
            return Spectrum(s);
        }
        let w = &SpectralTables::get(N).luminance;
        let mut s = [0.0; N];
        s.copy_from_slice(&w[..N]);
        Spectrum(s)
    }

    #[inline]
    pub fn average(&self) -> f32 {
        self.0.iter().sum::<f32>() / N as f32
    }
    #[inline]
    pub fn max_value(&self) -> f32 {
        self.0.iter().copied().fold(f32::NEG_INFINITY, f32::max)
    }
    #[inline]
    pub fn is_black(&self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
    #[inline]
    pub fn map(&self, f: impl Fn(f32) -> f32) -> Self {
        let mut s = self.0;
        for v in s.iter_mut() {
            *v = f(*v);
        }
        Spectrum(s)
    }
    /// Sum of elementwise products, weighted: sum_l a(l) b(l) h(l).
    #[inline]
    pub fn dot(&self, o: &Self) -> f32 {
        self.0.iter().zip(o.0.iter()).map(|(a, b)| a * b).sum()
    }
}

impl<const N: usize> Index<usize> for Spectrum<N> {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}
impl<const N: usize> IndexMut<usize> for Spectrum<N> {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

macro_rules! elementwise {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const N: usize> $tr for Spectrum<N> {
            type Output = Self;
            #[inline]
            fn $f(self, o: Self) -> Self {
                let mut s = self.0;
                for i in 0..N {
                    s[i] $op o.0[i];
                }
                Spectrum(s)
            }
        }
    };
}
elementwise!(Add, add, +=);
elementwise!(Sub, sub, -=);
elementwise!(Mul, mul, *=);

impl<const N: usize> Mul<f32> for Spectrum<N> {
    type Output = Self;
    #[inline]
    fn mul(self, k: f32) -> Self {
        let mut s = self.0;
        for v in s.iter_mut() {
            *v *= k;
        }
        Spectrum(s)
    }
}
impl<const N: usize> Mul<Spectrum<N>> for f32 {
    type Output = Spectrum<N>;
    #[inline]
    fn mul(self, s: Spectrum<N>) -> Spectrum<N> {
        s * self
    }
}
impl<const N: usize> Div<f32> for Spectrum<N> {
    type Output = Self;
    #[inline]
    fn div(self, k: f32) -> Self {
        self * (1.0 / k)
    }
}
impl<const N: usize> AddAssign for Spectrum<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        for i in 0..N {
            self.0[i] += o.0[i];
        }
    }
}
impl<const N: usize> MulAssign for Spectrum<N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        for i in 0..N {
            self.0[i] *= o.0[i];
        }
    }
}
impl<const N: usize> MulAssign<f32> for Spectrum<N> {
    #[inline]
    fn mul_assign(&mut self, k: f32) {
        for v in self.0.iter_mut() {
            *v *= k;
        }
    }
}

/// Which spectral mode a render runs in (`--spectral rgb|8|16`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
pub enum SpectralMode {
    /// Three RGB bands.
    #[default]
    #[serde(rename = "rgb")]
    #[value(name = "rgb", alias = "3")]
    Rgb,
    /// Eight spectral bands.
    #[serde(rename = "8")]
    #[value(name = "8")]
    Bands8,
    /// Sixteen spectral bands.
    #[serde(rename = "16")]
    #[value(name = "16")]
    Bands16,
}

/// `f::<N>(args)` with N the band count of a [`SpectralMode`]: the one place where the
/// run-time mode becomes the compile-time number of bands (`Spectrum<N>`). `f` is a
/// function in scope generic over `const N: usize` first.
macro_rules! per_band {
    ($mode:expr, $f:ident($($arg:expr),* $(,)?)) => {
        match $mode {
            $crate::spectrum::SpectralMode::Rgb => $f::<3>($($arg),*),
            $crate::spectrum::SpectralMode::Bands8 => $f::<8>($($arg),*),
            $crate::spectrum::SpectralMode::Bands16 => $f::<16>($($arg),*),
        }
    };
}
pub(crate) use per_band;

impl SpectralMode {
    pub fn bands(self) -> usize {
        match self {
            SpectralMode::Rgb => 3,
            SpectralMode::Bands8 => 8,
            SpectralMode::Bands16 => 16,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roundtrip<const N: usize>() {
        for rgb in [
            [1.0, 1.0, 1.0],
            [0.2, 0.5, 1.0],
            [0.885809, 0.698859, 0.666422],
            [18.387, 13.9873, 6.75357],
        ] {
            let s = Spectrum::<N>::from_rgb(rgb);
            let back = s.to_rgb();
            for c in 0..3 {
                assert!(
                    (back[c] - rgb[c]).abs() < 1e-4 * rgb[c].max(1.0),
                    "{N}: {rgb:?} -> {back:?}"
                );
            }
        }
    }

    #[test]
    fn uplift_then_output_is_identity() {
        roundtrip::<3>();
        roundtrip::<8>();
        roundtrip::<16>();
    }

    fn white_is_one<const N: usize>() {
        let s = Spectrum::<N>::from_rgb([1.0, 1.0, 1.0]);
        for v in s.0 {
            assert!((v - 1.0).abs() < 1e-6);
        }
        assert!((s.luminance() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn white_reflectance_is_one_on_every_band() {
        white_is_one::<3>();
        white_is_one::<8>();
        white_is_one::<16>();
    }

    fn bounded<const N: usize>() {
        for rgb in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.3, 0.9, 0.1],
        ] {
            let s = Spectrum::<N>::from_rgb(rgb);
            for v in s.0 {
                assert!((-1e-6..=1.0 + 1e-6).contains(&v), "{N}: {rgb:?} -> {s:?}");
            }
        }
    }

    #[test]
    fn reflectances_stay_in_unit_range() {
        bounded::<8>();
        bounded::<16>();
    }

    #[test]
    fn red_reflectance_is_small_on_blue_bands() {
        let s = Spectrum::<16>::from_rgb([1.0, 0.0, 0.0]);
        assert!(s.0[0] < 0.01 && s.0[15] > 0.99);
    }
}
