//! Image textures (map_Kd): PNG/JPEG/TGA/BMP decoded from sRGB to linear, EXR/PFM as stored (linear), bilinear lookup with
//! wrap-around, OBJ's v axis pointing up.

use std::path::Path;

#[derive(Clone, Debug)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
}

impl Texture {
    pub fn load(path: &Path) -> Result<Texture, String> {
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
            .map(|i| crate::image_io::srgb_decode(i as f32 / 255.0))
            .collect();
        let texels = img
            .pixels()
            .map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]])
            .collect();
        Ok(Texture {
            width,
            height,
            texels,
        })
    }

    #[inline]
    fn texel(&self, x: i64, y: i64) -> [f32; 3] {
        let xi = x.rem_euclid(self.width as i64) as usize;
        let yi = y.rem_euclid(self.height as i64) as usize;
        self.texels[yi * self.width as usize + xi]
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

    /// Bilinear lookup at (u, v), v = 0 at the bottom of the image.
    #[inline]
    pub fn lookup(&self, u: f32, v: f32) -> [f32; 3] {
        if !(u.is_finite() && v.is_finite()) {
            return self.texel(0, 0);
        }
        let x = u * self.width as f32 - 0.5;
        let y = (1.0 - v) * self.height as f32 - 0.5;
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
}
