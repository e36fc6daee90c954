//! Image textures (map_Kd, opacity): PNG/JPEG/TGA/BMP decoded from sRGB to linear,
//! EXR/PFM as stored (linear), OBJ's v axis pointing up; looked up as Mitsuba's `bitmap`
//! does ([`Sampling`]: bilinear or nearest, repeat, mirror or clamp, a `to_uv` transform).
//! Mitsuba's `checkerboard` is the 2 x 2 texture of its two colours, looked up nearest and
//! repeated ([`Texture::checkerboard`]).

pub mod mesh_attribute;
pub mod normal;

use std::path::Path;

/// What a lookup does outside [0, 1) (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Wrap {
    #[default]
    Repeat,
    Mirror,
    Clamp,
}

/// How a texture is looked up (Mitsuba's `filter_type`, `wrap_mode` and `to_uv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// The nearest texel instead of the bilinear blend of four.
    pub nearest: bool,
    pub wrap: Wrap,
    /// Affine map of Mitsuba's uv (v pointing down the image): u' = a u + b v + c,
    /// v' = d u + e v + f, as [a, b, c, d, e, f].
    pub to_uv: [f32; 6],
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            nearest: false,
            wrap: Wrap::Repeat,
            to_uv: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        }
    }
}

/// Where a scalar opacity map takes its value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OpacityFrom {
    /// The luminance of the linear (sRGB-decoded) colour, as Mitsuba's `bitmap` as a float
    /// texture (a grey image's grey).
    Luminance,
    /// MTL's `map_d`: the image's alpha where it has one that is not all opaque, else the
    /// stored grey (Blender's importer reads it as non-colour data).
    AlphaOrGrey,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
    pub sampling: Sampling,
}

impl Texture {
    pub fn load(path: &Path) -> Result<Texture, String> {
        Texture::load_as(path, false)
    }

    /// [`Texture::load`]; `raw`: 8-bit values as they are, v / 255, not sRGB-decoded
    /// (Mitsuba's bitmap `raw`, for normal and bump maps).
    pub fn load_as(path: &Path, raw: bool) -> Result<Texture, String> {
        // linear HDR images (Mitsuba scenes' bitmaps): EXR and PFM through image_io
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        if matches!(ext.as_deref(), Some("exr") | Some("pfm")) {
            let img = crate::image_io::read_image(path)
                .map_err(|e| format!("cannot read texture: {e}"))?;
            return Ok(Texture {
                width: img.width,
                height: img.height,
                texels: img.data,
                sampling: Sampling::default(),
            });
        }
        // through `input`: only regular files, within the input limit
        let bytes = crate::input::read_bytes(path)?;
        let img = crate::image_io::decode_8bit(&bytes, ext.as_deref())
            .map_err(|e| format!("{}: cannot read texture: {e}", path.display()))?
            .to_rgb8();
        let (width, height) = img.dimensions();
        if width == 0 || height == 0 {
            return Err(format!("{}: texture is empty", path.display()));
        }
        let lut: Vec<f32> = (0..256)
            .map(|i| {
                if raw {
                    i as f32 / 255.0
                } else {
                    crate::image_io::srgb_decode(i as f32 / 255.0)
                }
            })
            .collect();
        let texels = img
            .pixels()
            .map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]])
            .collect();
        Ok(Texture {
            width,
            height,
            texels,
            sampling: Sampling::default(),
        })
    }

    /// Mitsuba's `checkerboard`: `color0` where the fractional parts of (u, v) (after
    /// `to_uv`, in Mitsuba's uv) are both above 1/2 or both below, `color1` elsewhere.
    pub fn checkerboard(color0: [f32; 3], color1: [f32; 3], to_uv: [f32; 6]) -> Texture {
        Texture {
            width: 2,
            height: 2,
            texels: vec![color0, color1, color1, color0],
            sampling: Sampling {
                nearest: true,
                wrap: Wrap::Repeat,
                to_uv,
            },
        }
    }

    /// A scalar map (every texel's three values equal) for opacity.
    pub fn load_opacity(path: &Path, from: OpacityFrom) -> Result<Texture, String> {
        let mut t = Texture::load(path)?;
        if from == OpacityFrom::AlphaOrGrey {
            let ext = path
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_deref(), Some("exr") | Some("pfm")) {
                let bytes = crate::input::read_bytes(path)?;
                let img = crate::image_io::decode_8bit(&bytes, ext.as_deref())
                    .map_err(|e| format!("{}: cannot read texture: {e}", path.display()))?
                    .to_rgba8();
                let alpha = img.pixels().any(|p| p[3] < 255);
                for (t, p) in t.texels.iter_mut().zip(img.pixels()) {
                    let v = if alpha {
                        p[3] as f32
                    } else {
                        (p[0] as f32 + p[1] as f32 + p[2] as f32) / 3.0
                    };
                    *t = [v / 255.0; 3];
                }
                return Ok(t);
            }
        }
        for t in &mut t.texels {
            *t = [0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2]; 3];
        }
        Ok(t)
    }

    #[inline]
    fn texel(&self, x: i64, y: i64) -> [f32; 3] {
        let wrap = |i: i64, n: u32| -> usize {
            let n = n as i64;
            (match self.sampling.wrap {
                Wrap::Repeat => i.rem_euclid(n),
                Wrap::Clamp => i.clamp(0, n - 1),
                Wrap::Mirror => {
                    let m = i.rem_euclid(2 * n);
                    if m >= n {
                        2 * n - 1 - m
                    } else {
                        m
                    }
                }
            }) as usize
        };
        self.texels[wrap(y, self.height) * self.width as usize + wrap(x, self.width)]
    }

    /// (df/du, df/dv) of the first channel f at (u, v) (v = 0 at the bottom of the
    /// image), the derivatives taken in Mitsuba's uv (v down the image), as Mitsuba's
    /// bitmap `eval_1_grad`: the derivative of the bilinear blend, through `to_uv`'s
    /// linear part; 0 for a nearest lookup (constant between texels).
    pub fn gradient(&self, u: f32, v: f32) -> [f32; 2] {
        if self.sampling.nearest || !(u.is_finite() && v.is_finite()) {
            return [0.0; 2];
        }
        let [a, b, c, d, e, f] = self.sampling.to_uv;
        let w = 1.0 - v;
        let (wf, hf) = (self.width as f32, self.height as f32);
        let x = (a * u + b * w + c) * wf - 0.5;
        let y = (d * u + e * w + f) * hf - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let f00 = self.texel(x0, y0)[0];
        let f10 = self.texel(x0 + 1, y0)[0];
        let f01 = self.texel(x0, y0 + 1)[0];
        let f11 = self.texel(x0 + 1, y0 + 1)[0];
        // per texel along x and y, then per unit of the transformed uv
        let df_dx = ((f10 - f00) * (1.0 - fy) + (f11 - f01) * fy) * wf;
        let df_dy = ((f01 - f00) * (1.0 - fx) + (f11 - f10) * fx) * hf;
        [a * df_dx + d * df_dy, b * df_dx + e * df_dy]
    }

    /// Mean texel (linear RGB).
    pub fn mean(&self) -> [f32; 3] {
        let mut s = [0.0f64; 3];
        for t in &self.texels {
            for c in 0..3 {
                s[c] += t[c] as f64;
            }
        }
        let k = 1.0 / self.texels.len().max(1) as f64;
        [(s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32]
    }

    /// Lookup at (u, v), v = 0 at the bottom of the image, as [`Sampling`] says.
    #[inline]
    pub fn lookup(&self, u: f32, v: f32) -> [f32; 3] {
        if !(u.is_finite() && v.is_finite()) {
            return self.texel(0, 0);
        }
        // Mitsuba's uv runs down the image: its to_uv applies to (u, 1 - v)
        let [a, b, c, d, e, f] = self.sampling.to_uv;
        let (u, w) = (u, 1.0 - v);
        let (u, w) = (a * u + b * w + c, d * u + e * w + f);
        if self.sampling.nearest {
            let x = (u * self.width as f32).floor();
            let y = (w * self.height as f32).floor();
            return self.texel(x as i64, y as i64);
        }
        let x = u * self.width as f32 - 0.5;
        let y = w * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(x0, y0);
        let b = self.texel(x0 + 1, y0);
        let c = self.texel(x0, y0 + 1);
        let d = self.texel(x0 + 1, y0 + 1);
        let mut out = [0.0; 3];
        for i in 0..3 {
            out[i] =
                (a[i] * (1.0 - fx) + b[i] * fx) * (1.0 - fy) + (c[i] * (1.0 - fx) + d[i] * fx) * fy;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// TGA (no signature: read by its extension) and BMP textures decode like PNG:
    /// sRGB to linear, top row first.
    #[test]
    fn tga_and_bmp_textures_load() {
        let dir = std::env::temp_dir().join(format!("kalos-tex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img =
            image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([255 * x as u8, 128, 255 * y as u8]));
        for (ext, fmt) in [
            ("tga", image::ImageFormat::Tga),
            ("bmp", image::ImageFormat::Bmp),
            ("png", image::ImageFormat::Png),
        ] {
            let path = dir.join(format!("t.{ext}"));
            img.save_with_format(&path, fmt).unwrap();
            let t = Texture::load(&path).unwrap_or_else(|e| panic!("{ext}: {e}"));
            assert_eq!((t.width, t.height), (2, 2), "{ext}");
            let mid = crate::image_io::srgb_decode(128.0 / 255.0);
            assert_eq!(t.texels[0], [0.0, mid, 0.0], "{ext}");
            assert_eq!(t.texels[3], [1.0, mid, 1.0], "{ext}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Nearest and bilinear lookups, the wrap modes and to_uv on a 2 x 1 texture of
    /// texels 0 and 1 (known answers).
    #[test]
    fn sampling_follows_mitsubas_bitmap() {
        let mut t = Texture {
            width: 2,
            height: 1,
            texels: vec![[0.0; 3], [1.0; 3]],
            sampling: Sampling::default(),
        };
        // u = 0.5 is between the texel centres 0.25 and 0.75: bilinear 0.5
        assert_eq!(t.lookup(0.5, 0.5)[0], 0.5);
        assert_eq!(t.lookup(0.375, 0.5)[0], 0.25);
        // repeat: u = 0 is halfway between texel 1 (wrapped) and texel 0
        assert_eq!(t.lookup(0.0, 0.5)[0], 0.5);
        t.sampling.wrap = Wrap::Clamp;
        assert_eq!(t.lookup(0.0, 0.5)[0], 0.0);
        assert_eq!(t.lookup(1.2, 0.5)[0], 1.0);
        t.sampling.wrap = Wrap::Mirror;
        // texel -1 mirrors texel 0, texel 2 mirrors texel 1
        assert_eq!(t.lookup(0.0, 0.5)[0], 0.0);
        assert_eq!(t.lookup(1.1, 0.5)[0], 1.0);
        t.sampling = Sampling {
            nearest: true,
            ..Sampling::default()
        };
        assert_eq!(t.lookup(0.49, 0.5)[0], 0.0);
        assert_eq!(t.lookup(0.51, 0.5)[0], 1.0);
        assert_eq!(t.lookup(1.51, 0.5)[0], 1.0, "repeats");
        // to_uv: u' = 2 u - 0.5 puts u = 0.2 at u' = -0.1 (texel -1, repeated: texel 1)
        assert_eq!(t.lookup(0.2, 0.5)[0], 0.0);
        t.sampling.to_uv = [2.0, 0.0, -0.5, 0.0, 1.0, 0.0];
        assert_eq!(t.lookup(0.2, 0.5)[0], 1.0);
        assert_eq!(t.lookup(0.3, 0.5)[0], 0.0);
    }

    /// The gradient of a bilinear lookup is the derivative of the blend: on a ramp
    /// f = x (texel index) it is the width along u; v runs down the image in Mitsuba's
    /// uv, so a ramp down the rows has df/dv = +height; to_uv's scale multiplies it.
    #[test]
    fn gradient_is_the_bilinear_derivative() {
        let ramp = |w: u32, h: u32, f: &dyn Fn(u32, u32) -> f32| Texture {
            width: w,
            height: h,
            texels: (0..w * h).map(|i| [f(i % w, i / w); 3]).collect(),
            sampling: Sampling::default(),
        };
        let t = ramp(8, 4, &|x, _| x as f32);
        let g = t.gradient(0.4, 0.3);
        assert!((g[0] - 8.0).abs() < 1e-4 && g[1].abs() < 1e-6, "{g:?}");
        let t = ramp(8, 4, &|_, y| 0.5 * y as f32);
        let g = t.gradient(0.4, 0.3);
        assert!(g[0].abs() < 1e-6 && (g[1] - 2.0).abs() < 1e-4, "{g:?}");
        let mut t = ramp(8, 4, &|x, _| x as f32);
        t.sampling.to_uv = [0.5, 0.0, 0.0, 0.0, 1.0, 0.0];
        let g = t.gradient(0.4, 0.3);
        assert!((g[0] - 4.0).abs() < 1e-4, "{g:?}");
        // a finite difference of the lookup agrees (inside a texel cell)
        let t = ramp(8, 4, &|x, y| (x * x + 3 * y) as f32 * 0.1);
        let (u, v, h) = (0.41, 0.37, 1e-3);
        let du = (t.lookup(u + h, v)[0] - t.lookup(u - h, v)[0]) / (2.0 * h);
        // kalos' v is up: d/dv_mitsuba = -d/dv_kalos
        let dv = -(t.lookup(u, v + h)[0] - t.lookup(u, v - h)[0]) / (2.0 * h);
        let g = t.gradient(u, v);
        assert!(
            (g[0] - du).abs() < 1e-2 && (g[1] - dv).abs() < 1e-2,
            "{g:?} vs {du} {dv}"
        );
    }

    /// The checkerboard as Mitsuba 3.9.1 evaluates it (color0 red, color1 green, read
    /// from `mi.load_dict({'type': 'checkerboard', ...}).eval(si)`): red at Mitsuba's uv
    /// (0.25, 0.25) and (0.75, 0.75), green at (0.75, 0.25) and (0.25, 0.75); `to_uv`
    /// scales the squares. kalos' v points up: Mitsuba's (u, v) is kalos' (u, 1 - v).
    #[test]
    fn checkerboard_follows_mitsuba() {
        let (r, g) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let t = Texture::checkerboard(r, g, Sampling::default().to_uv);
        let at = |t: &Texture, u: f32, v_mitsuba: f32| t.lookup(u, 1.0 - v_mitsuba);
        assert_eq!(at(&t, 0.25, 0.25), r);
        assert_eq!(at(&t, 0.75, 0.75), r);
        assert_eq!(at(&t, 0.75, 0.25), g);
        assert_eq!(at(&t, 0.25, 0.75), g);
        assert_eq!(at(&t, 1.25, -0.75), r, "repeats");
        assert_eq!(t.mean(), [0.5, 0.5, 0.0]);
        // to_uv scaled by 5: squares of 1/10
        let t = Texture::checkerboard(r, g, [5.0, 0.0, 0.0, 0.0, 5.0, 0.0]);
        assert_eq!(at(&t, 0.05, 0.05), r);
        assert_eq!(at(&t, 0.15, 0.05), g);
        assert_eq!(at(&t, 0.15, 0.15), r);
    }
}
