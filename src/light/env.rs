//! Light from infinitely far away: a constant radiance, or an equirectangular map in
//! Mitsuba 3's convention (`envmap`), times a scale, rotated by `to_world`.
//!
//! Mitsuba's convention: a direction d = (x, y, z) in the map's frame (y up) has
//!   u = atan2(x, -z) / (2 pi)  (wrapped to [0, 1)),   v = acos(y) / pi,
//! i.e. d = (sin theta sin phi, cos theta, -sin theta cos phi) with phi = 2 pi u,
//! theta = pi v. Texel column i sits at u = (i + 1/2) / W (periodic), row j at
//! v = j / (H - 1) (the first and last rows are the poles); radiance is interpolated
//! bilinearly between them.
//!
//! Importance sampling: a piecewise-constant 2D distribution over the cells between the
//! texel nodes, each weighted by the largest luminance at its corners times sin theta at
//! its centre (positive wherever the interpolated map can be), uniform within the cell in
//! (u, v); the solid-angle density is p(u, v) / (2 pi^2 sin theta). The constant
//! environment is sampled uniformly over the sphere.

use crate::image_io::RgbImage;
use crate::math::Vec3;
use crate::sampling::{square_to_uniform_sphere, Distribution1D, PDF_UNIFORM_SPHERE};
use crate::spectrum::Spectrum;
use glam::{Mat3, Vec2};
use std::f32::consts::PI;

pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    /// Rows of cells (H - 1), then the cells of the chosen row (W).
    rows: Distribution1D,
    cols: Vec<Distribution1D>,
}

pub struct EnvLight {
    scale: [f32; 3],
    map: Option<EnvMap>,
    to_world: Mat3,
    to_local: Mat3,
    /// Mean luminance of the radiance over the sphere (for the choice among lights).
    pub mean_luminance: f32,
}

#[inline]
fn lum(c: [f32; 3]) -> f32 {
    Spectrum::<3>(c).luminance().max(0.0)
}

/// (u, v) of a direction in the map's frame.
#[inline]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let mut u = d.x.atan2(-d.z) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The direction of (u, v) in the map's frame, and sin theta.
#[inline]
pub fn uv_to_direction(uv: Vec2) -> (Vec3, f32) {
    let (st, ct) = (uv.y * PI).sin_cos();
    let (sp, cp) = (uv.x * 2.0 * PI).sin_cos();
    (Vec3::new(sp * st, ct, -cp * st), st)
}

impl EnvMap {
    fn new(img: &RgbImage) -> Result<EnvMap, String> {
        let (w, h) = (img.width as usize, img.height as usize);
        if w < 2 || h < 3 {
            return Err(format!(
                "the environment map is {w}x{h}: it needs at least 2x3 pixels"
            ));
        }
        if img
            .data
            .iter()
            .any(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0))
        {
            return Err("the environment map has negative or non-finite pixels".into());
        }
        let texels = img.data.clone();
        let l = |i: usize, j: usize| lum(texels[j * w + i % w]);
        let mut row_w = Vec::with_capacity(h - 1);
        let mut cols = Vec::with_capacity(h - 1);
        for j in 0..h - 1 {
            let sin_t = ((j as f32 + 0.5) / (h - 1) as f32 * PI).sin();
            let cells: Vec<f32> = (0..w)
                .map(|i| {
                    l(i, j)
                        .max(l(i + 1, j))
                        .max(l(i, j + 1))
                        .max(l(i + 1, j + 1))
                        * sin_t
                })
                .collect();
            row_w.push(cells.iter().sum::<f32>());
            cols.push(Distribution1D::new(&cells));
        }
        Ok(EnvMap {
            width: w,
            height: h,
            texels,
            rows: Distribution1D::new(&row_w),
            cols,
        })
    }

    /// Bilinear lookup at (u, v).
    #[inline]
    fn lookup(&self, uv: Vec2) -> [f32; 3] {
        let (w, h) = (self.width, self.height);
        let mut x = uv.x * w as f32 - 0.5;
        if x < 0.0 {
            x += w as f32;
        }
        let y = (uv.y * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let i = (x as usize).min(w - 1);
        let j = (y as usize).min(h - 2);
        let (fx, fy) = (x - i as f32, y - j as f32);
        let t = |i: usize, j: usize| self.texels[j * w + i % w];
        let (a, b, c, d) = (t(i, j), t(i + 1, j), t(i, j + 1), t(i + 1, j + 1));
        let mut r = [0.0; 3];
        for k in 0..3 {
            let top = a[k] * (1.0 - fx) + b[k] * fx;
            let bot = c[k] * (1.0 - fx) + d[k] * fx;
            r[k] = top * (1.0 - fy) + bot * fy;
        }
        r
    }

    /// Density of (u, v) per unit area of the parameter square.
    #[inline]
    fn pdf_uv(&self, uv: Vec2) -> f32 {
        let (w, h) = (self.width, self.height);
        let mut x = uv.x * w as f32 - 0.5;
        if x < 0.0 {
            x += w as f32;
        }
        let i = (x as usize).min(w - 1);
        let j = ((uv.y * (h - 1) as f32) as usize).min(h - 2);
        self.rows.pmf(j) * self.cols[j].pmf(i) * (w * (h - 1)) as f32
    }

    fn sample_uv(&self, u: Vec2) -> Option<(Vec2, f32)> {
        if self.rows.is_empty() {
            return None;
        }
        let (j, pr, v_in) = self.rows.sample(u.y);
        let (i, pc, u_in) = self.cols[j].sample(u.x);
        let (w, h) = (self.width as f32, (self.height - 1) as f32);
        let mut uu = (i as f32 + 0.5 + u_in) / w;
        if uu >= 1.0 {
            uu -= 1.0;
        }
        let vv = (j as f32 + v_in) / h;
        Some((Vec2::new(uu, vv), pr * pc * w * h))
    }

    /// Mean luminance over the sphere (sin theta weighted).
    fn mean_luminance(&self) -> f32 {
        let n = 256;
        let mut s = 0.0f64;
        for j in 0..n {
            let v = (j as f32 + 0.5) / n as f32;
            let st = (v * PI).sin();
            for i in 0..2 * n {
                let u = (i as f32 + 0.5) / (2 * n) as f32;
                s += (lum(self.lookup(Vec2::new(u, v))) * st) as f64;
            }
        }
        // int sin theta dtheta dphi = 4 pi; the grid sums sin theta over 2 n^2 cells
        // of area (pi / n)(2 pi / 2n)
        (s * (PI as f64 / n as f64) * (PI as f64 / n as f64) / (4.0 * PI as f64)) as f32
    }
}

impl EnvLight {
    /// A constant environment (`map` None) or a map, times `scale`, rotated by `to_world`.
    pub fn new(scale: [f32; 3], map: Option<&RgbImage>, to_world: Mat3) -> Result<Self, String> {
        if scale.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err("environment radiance must be finite and non-negative".into());
        }
        if !to_world.is_finite() || (to_world.determinant().abs() - 1.0).abs() > 1e-3 {
            return Err("environment to_world must be a rotation".into());
        }
        let map = map.map(EnvMap::new).transpose()?;
        let ml = match &map {
            Some(m) => m.mean_luminance(),
            None => 1.0,
        };
        Ok(EnvLight {
            mean_luminance: ml * lum(scale),
            scale,
            map,
            to_world,
            to_local: to_world.transpose(),
        })
    }

    /// Radiance arriving from direction `d` (world space, pointing away from the scene).
    #[inline]
    pub fn eval(&self, d: Vec3) -> [f32; 3] {
        match &self.map {
            None => self.scale,
            Some(m) => {
                let uv = direction_to_uv(self.to_local * d);
                let r = m.lookup(uv);
                [
                    r[0] * self.scale[0],
                    r[1] * self.scale[1],
                    r[2] * self.scale[2],
                ]
            }
        }
    }

    /// Solid-angle density of `sample` producing direction `d` (world space).
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        match &self.map {
            None => PDF_UNIFORM_SPHERE,
            Some(m) => {
                let l = self.to_local * d;
                let sin_t = (l.x * l.x + l.z * l.z).sqrt();
                if sin_t <= 1e-6 {
                    return 0.0;
                }
                m.pdf_uv(direction_to_uv(l)) / (2.0 * PI * PI * sin_t)
            }
        }
    }

    /// A direction towards the environment (world space), its density and radiance.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32, [f32; 3])> {
        match &self.map {
            None => Some((square_to_uniform_sphere(u), PDF_UNIFORM_SPHERE, self.scale)),
            Some(m) => {
                let (uv, p_uv) = m.sample_uv(u)?;
                let (l, sin_t) = uv_to_direction(uv);
                if sin_t <= 1e-6 || p_uv <= 0.0 {
                    return None;
                }
                let d = (self.to_world * l).normalize();
                Some((d, p_uv / (2.0 * PI * PI * sin_t), self.eval(d)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::{assert_chi2, chi2_sphere};

    fn test_map() -> RgbImage {
        // a bright spot, a gradient and a dark band
        let (w, h) = (32u32, 17u32);
        let mut data = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let u = (i as f32 + 0.5) / w as f32;
                let v = j as f32 / (h - 1) as f32;
                let spot = if (u - 0.3).abs() < 0.07 && (v - 0.35).abs() < 0.1 {
                    20.0
                } else {
                    0.0
                };
                let band = if (v - 0.7).abs() < 0.05 { 0.0 } else { 1.0 };
                data.push([spot + 0.5 * u * band, spot + 0.2 * band, 0.1 + v]);
            }
        }
        RgbImage::new(w, h, data)
    }

    #[test]
    fn mitsuba_uv_convention_round_trips() {
        for uv in [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.75, 0.9),
            Vec2::new(0.5, 0.5),
        ] {
            let (d, _) = uv_to_direction(uv);
            let back = direction_to_uv(d);
            assert!((back - uv).length() < 1e-5, "{uv} -> {d} -> {back}");
        }
        // u = 0 looks along -z, u = 1/4 along +x, v = 0 up (+y)
        assert!((uv_to_direction(Vec2::new(0.0, 0.5)).0 - Vec3::NEG_Z).length() < 1e-6);
        assert!((uv_to_direction(Vec2::new(0.25, 0.5)).0 - Vec3::X).length() < 1e-6);
        assert!((uv_to_direction(Vec2::new(0.3, 0.0)).0 - Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn chi2_envmap_sampling() {
        let img = test_map();
        let rot = Mat3::from_rotation_x(0.4) * Mat3::from_rotation_y(1.1);
        let env = EnvLight::new([1.0, 2.0, 0.5], Some(&img), rot).unwrap();
        let r = chi2_sphere(
            |_, u| env.sample(u).map(|s| s.0),
            |d| env.pdf(d),
            300_000,
            77,
        );
        assert_chi2("envmap sampling", &r);
        assert!((r.pdf_integral - 1.0).abs() < 5e-3, "{}", r.pdf_integral);
        // the sampled radiance is the map's value in that direction
        let (d, pdf, le) = env.sample(Vec2::new(0.3, 0.6)).unwrap();
        assert!((pdf - env.pdf(d)).abs() < 1e-3 * pdf);
        assert_eq!(le, env.eval(d));
    }

    #[test]
    fn envmap_estimates_of_the_mean_agree() {
        // E[L(d) / p(d)] over importance samples = integral of L over the sphere, which
        // a uniform estimate gives too: the map, sampling and pdf agree.
        let img = test_map();
        let env = EnvLight::new([1.0; 3], Some(&img), Mat3::IDENTITY).unwrap();
        let mut rng = crate::sampling::chi2::TestRng::new(5);
        let n = 400_000;
        let (mut a, mut b) = (0.0f64, 0.0f64);
        for _ in 0..n {
            if let Some((_, p, le)) = env.sample(rng.next_2d()) {
                a += (lum(le) / p) as f64;
            }
            let d = square_to_uniform_sphere(rng.next_2d());
            b += (lum(env.eval(d)) / PDF_UNIFORM_SPHERE) as f64;
        }
        let (a, b) = (a / n as f64, b / n as f64);
        assert!((a - b).abs() < 0.01 * b, "importance {a} vs uniform {b}");
        let mean = env.mean_luminance as f64 * 4.0 * std::f64::consts::PI;
        assert!((mean - b).abs() < 0.01 * b, "mean {mean} vs {b}");
    }

    #[test]
    fn radiance_hdr_maps_are_read_linear() {
        use image::codecs::hdr::HdrEncoder;
        let (w, h) = (4usize, 3usize);
        let px: Vec<image::Rgb<f32>> = (0..w * h)
            .map(|i| image::Rgb([i as f32 * 0.5, 2.0, 0.125]))
            .collect();
        let mut bytes = Vec::new();
        HdrEncoder::new(&mut bytes).encode(&px, w, h).unwrap();
        let path = std::env::temp_dir().join(format!("kalos-env-{}.hdr", std::process::id()));
        std::fs::write(&path, &bytes).unwrap();
        let img = crate::image_io::read_image(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!((img.width, img.height), (4, 3));
        // RGBE keeps 8 bits of mantissa: within 1%
        assert!((img.get(3, 2)[0] - 5.5).abs() < 0.06 && (img.get(0, 0)[1] - 2.0).abs() < 0.02);
        assert!(EnvLight::new([1.0; 3], Some(&img), Mat3::IDENTITY).is_ok());
    }

    #[test]
    fn bad_maps_are_refused() {
        let tiny = RgbImage::new(1, 1, vec![[1.0; 3]]);
        assert!(EnvLight::new([1.0; 3], Some(&tiny), Mat3::IDENTITY).is_err());
        let neg = RgbImage::new(2, 3, vec![[-1.0; 3]; 6]);
        assert!(EnvLight::new([1.0; 3], Some(&neg), Mat3::IDENTITY).is_err());
        assert!(EnvLight::new([f32::NAN; 3], None, Mat3::IDENTITY).is_err());
    }
}
