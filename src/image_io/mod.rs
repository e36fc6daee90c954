//! Image files by extension: `.exr` (linear float, optional extra layers), `.pfm`
//! (linear float), `.png` (exposure + sRGB transfer, 8 bit). Reading supports the same
//! three, so `compare` and references work with any of them. Every writer encodes into
//! memory and writes the file in one call, so a full disk or a failed write is an error
//! (a buffered writer flushed on drop loses it); every reader reads through
//! `crate::input` (regular files within the input limit) and refuses images without
//! pixels or whose decoded size exceeds that limit.

use std::path::Path;

/// A linear RGB image, row-major, y = 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 3]>,
}

impl RgbImage {
    pub fn new(width: u32, height: u32, data: Vec<[f32; 3]>) -> Self {
        assert_eq!(data.len(), width as usize * height as usize);
        RgbImage {
            width,
            height,
            data,
        }
    }
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[y as usize * self.width as usize + x as usize]
    }
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.data {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
        let n = self.data.len().max(1) as f64;
        [s[0] / n, s[1] / n, s[2] / n]
    }
}

/// An extra single- or three-channel layer written beside the main image in EXR.
pub struct ExtraLayer<'a> {
    pub name: &'a str,
    pub channels: LayerData<'a>,
}

pub enum LayerData<'a> {
    Rgb(&'a [[f32; 3]]),
    Mono(&'a [f32]),
}

/// Output format chosen from a file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Pfm,
    Png,
}

pub fn format_of(path: &Path) -> Result<Format, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => Ok(Format::Exr),
        Some("pfm") => Ok(Format::Pfm),
        Some("png") => Ok(Format::Png),
        _ => Err(format!(
            "{}: unknown image extension (use .exr, .pfm or .png)",
            path.display()
        )),
    }
}

/// Write an image with the layers of `--aovs` when `aovs` gives the per-pixel variance
/// (RGB) and sample count: `variance`, `count`, and `negative` (1 where a channel of the
/// estimate is negative: the estimate roulette can make it so, the roulette paper's
/// figure 4, right). The CLI, `kalos merge` and the Python module all write through it.
pub fn write_image_aovs(
    path: &Path,
    img: &RgbImage,
    exposure: f32,
    aovs: Option<(&[[f32; 3]], &[f32])>,
) -> Result<(), String> {
    let Some((var, cnt)) = aovs else {
        return write_image(path, img, exposure, &[]);
    };
    let neg: Vec<f32> = img
        .data
        .iter()
        .map(|p| if p.iter().any(|&v| v < 0.0) { 1.0 } else { 0.0 })
        .collect();
    let extra = [
        ExtraLayer {
            name: "variance",
            channels: LayerData::Rgb(var),
        },
        ExtraLayer {
            name: "count",
            channels: LayerData::Mono(cnt),
        },
        ExtraLayer {
            name: "negative",
            channels: LayerData::Mono(&neg),
        },
    ];
    write_image(path, img, exposure, &extra)
}

/// Write an image; `exposure` (in stops) applies to PNG only; extra layers go to EXR only.
pub fn write_image(
    path: &Path,
    img: &RgbImage,
    exposure: f32,
    extra: &[ExtraLayer],
) -> Result<(), String> {
    let fail = |e: &dyn std::fmt::Display| format!("{}: cannot write image: {e}", path.display());
    match format_of(path)? {
        Format::Exr => write_exr(path, img, extra).map_err(|e| fail(&e)),
        Format::Pfm => write_pfm(path, img).map_err(|e| fail(&e)),
        Format::Png => write_png(path, img, exposure).map_err(|e| fail(&e)),
    }
}

fn write_exr(path: &Path, img: &RgbImage, extra: &[ExtraLayer]) -> Result<(), String> {
    use exr::prelude::*;
    let size = (img.width as usize, img.height as usize);
    let plane = |c: usize| -> Vec<f32> { img.data.iter().map(|p| p[c]).collect() };
    let mut channels: Vec<AnyChannel<FlatSamples>> = vec![
        AnyChannel::new("R", FlatSamples::F32(plane(0))),
        AnyChannel::new("G", FlatSamples::F32(plane(1))),
        AnyChannel::new("B", FlatSamples::F32(plane(2))),
    ];
    // Extra layers use the EXR naming convention "layer.channel" in the same part.
    for l in extra {
        match &l.channels {
            LayerData::Rgb(d) => {
                for (c, ch) in ["R", "G", "B"].iter().enumerate() {
                    let v: Vec<f32> = d.iter().map(|p| p[c]).collect();
                    channels.push(AnyChannel::new(
                        format!("{}.{}", l.name, ch).as_str(),
                        FlatSamples::F32(v),
                    ));
                }
            }
            LayerData::Mono(d) => {
                channels.push(AnyChannel::new(
                    format!("{}.Y", l.name).as_str(),
                    FlatSamples::F32(d.to_vec()),
                ));
            }
        }
    }
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut out = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| e.to_string())?;
    std::fs::write(path, out.into_inner()).map_err(|e| e.to_string())
}

fn write_pfm(path: &Path, img: &RgbImage) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = Vec::with_capacity(img.data.len() * 12 + 32);
    // Negative scale: little endian. Rows go bottom to top.
    write!(out, "PF\n{} {}\n-1.0\n", img.width, img.height)?;
    for y in (0..img.height).rev() {
        for x in 0..img.width {
            for v in img.get(x, y) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out)
}

/// sRGB transfer function of a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.0031308 {
        12.92 * v.max(0.0)
    } else {
        1.055 * v.min(1.0).powf(1.0 / 2.4) - 0.055
    }
}

pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// 8-bit sRGB rows of a linear image scaled by 2^exposure (as PNGs are written).
pub fn srgb8(img: &RgbImage, exposure: f32) -> Vec<u8> {
    let k = 2f32.powf(exposure);
    let mut buf = Vec::with_capacity(img.data.len() * 3);
    for p in &img.data {
        for v in p {
            buf.push((srgb_encode(v * k).clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
    }
    buf
}

fn write_png(path: &Path, img: &RgbImage, exposure: f32) -> Result<(), String> {
    encode_png(path, img.width, img.height, &srgb8(img, exposure))
}

/// A PNG file's bytes of 8-bit RGB rows, in memory.
pub fn png_bytes(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(png)
}

/// Encode 8-bit RGB in memory, then one write whose error is seen (image::save_buffer's
/// BufWriter is flushed on drop, where a full disk goes unnoticed).
fn encode_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    std::fs::write(path, png_bytes(width, height, rgb)?).map_err(|e| e.to_string())
}

/// Write 8-bit sRGB pixels (row-major RGB) as a PNG, reporting any write error (plots
/// and side-by-side images drawn into memory).
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    encode_png(path, width, height, rgb)
        .map_err(|e| format!("{}: cannot write image: {e}", path.display()))
}

/// Bytes a decoded pixel can take on its way to linear RGB: the decoder's buffer (up to
/// 16-bit RGBA, 8), its f32 RGB conversion (12) and the image kalos keeps (12).
const DECODED_PIXEL_BYTES: u64 = 32;

/// Largest number of pixels an image read may have: the input limit over the bytes a
/// decoded pixel takes, so no header (a small PNG can declare 13000 x 13000) can make
/// kalos allocate more than that limit. Checked before decoding.
fn max_pixels() -> Result<u64, String> {
    Ok(crate::input::max_input_bytes()? / DECODED_PIXEL_BYTES)
}

/// Refuse an image of `w` x `h` beyond [`max_pixels`], before it is decoded.
fn check_pixels(w: u64, h: u64) -> Result<(), String> {
    let limit = max_pixels()?;
    if w.saturating_mul(h) > limit {
        return Err(format!(
            "the image is {w}x{h}: decoding it would take {}, more than the input limit allows ({limit} pixels; set {} to raise it)",
            crate::input::human_size(w.saturating_mul(h).saturating_mul(DECODED_PIXEL_BYTES)),
            crate::input::MAX_INPUT_ENV
        ));
    }
    Ok(())
}

/// The largest layer of an EXR, from its header alone, checked by [`check_pixels`].
fn check_exr_size(bytes: &[u8]) -> Result<(), String> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| e.to_string())?;
    for h in &meta.headers {
        check_pixels(h.layer_size.width() as u64, h.layer_size.height() as u64)?;
    }
    Ok(())
}

/// Decode an 8-bit image held in memory (PNG, JPEG, TGA, BMP), within the image crate's
/// default allocation limit (512 MiB). The format comes from the content, else from `ext`,
/// the file's extension (TGA has no signature; older game-asset scenes such as Crytek's
/// original Sponza ship `.tga` textures).
pub fn decode_8bit(bytes: &[u8], ext: Option<&str>) -> Result<image::DynamicImage, String> {
    let reader = || -> Result<_, String> {
        let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        if r.format().is_none() {
            if let Some(f) = ext.and_then(image::ImageFormat::from_extension) {
                r.set_format(f);
            }
        }
        Ok(r)
    };
    // the size from the header, before anything is allocated for the pixels
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    check_pixels(w as u64, h as u64)?;
    reader()?.decode().map_err(|e| e.to_string())
}

/// Whether `path` names an image `read_image` reads: EXR, PFM, PNG, or Radiance HDR
/// (read only: environment maps).
pub fn check_readable(path: &Path) -> Result<(), String> {
    if is_hdr(path) {
        return Ok(());
    }
    format_of(path).map(|_| ()).map_err(|_| {
        format!(
            "{}: unknown image extension (use .exr, .hdr, .pfm or .png)",
            path.display()
        )
    })
}

fn is_hdr(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("hdr"))
}

/// Read an EXR (first RGB(A) layer), PFM, PNG (sRGB-decoded) or Radiance HDR (linear) as
/// linear RGB. Images without pixels (0 x h, w x 0) are refused.
pub fn read_image(path: &Path) -> Result<RgbImage, String> {
    let fail = |e: &dyn std::fmt::Display| format!("{}: cannot read image: {e}", path.display());
    if is_hdr(path) {
        let bytes = crate::input::read_bytes(path)?;
        let hdr = || {
            image::ImageReader::with_format(std::io::Cursor::new(&bytes), image::ImageFormat::Hdr)
        };
        let (w, h) = hdr().into_dimensions().map_err(|e| fail(&e))?;
        check_pixels(w as u64, h as u64).map_err(|e| fail(&e))?;
        let im = hdr().decode().map_err(|e| fail(&e))?.to_rgb32f();
        let (w, h) = im.dimensions();
        if w == 0 || h == 0 {
            return Err(format!(
                "{}: the image is {w}x{h}: it has no pixels",
                path.display()
            ));
        }
        let data = im.pixels().map(|p| [p[0], p[1], p[2]]).collect();
        return Ok(RgbImage::new(w, h, data));
    }
    let format = format_of(path)?;
    let bytes = crate::input::read_bytes(path)?;
    let img = match format {
        Format::Exr => read_exr(&bytes).map_err(|e| fail(&e))?,
        Format::Pfm => read_pfm(&bytes).map_err(|e| fail(&e))?,
        Format::Png => {
            let im = decode_8bit(&bytes, None).map_err(|e| fail(&e))?.to_rgb32f();
            let (w, h) = im.dimensions();
            let data = im
                .pixels()
                .map(|p| [srgb_decode(p[0]), srgb_decode(p[1]), srgb_decode(p[2])])
                .collect();
            RgbImage::new(w, h, data)
        }
    };
    if img.width == 0 || img.height == 0 {
        return Err(format!(
            "{}: the image is {}x{}: it has no pixels",
            path.display(),
            img.width,
            img.height
        ));
    }
    Ok(img)
}

fn read_exr(bytes: &[u8]) -> Result<RgbImage, String> {
    use exr::prelude::traits::*;
    check_exr_size(bytes)?;
    let limit = max_pixels()?;
    // the header's size is checked before the pixels are allocated
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            move |res, _| {
                let n = res.width() as u64 * res.height() as u64;
                let data = if n <= limit {
                    vec![[0.0f32; 3]; n as usize]
                } else {
                    Vec::new()
                };
                (res.width(), data)
            },
            |(w, data), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                if let Some(p) = data.get_mut(pos.y() * *w + pos.x()) {
                    *p = [r, g, b];
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let size = image.layer_data.size;
    let (_, data) = image.layer_data.channel_data.pixels;
    let n = size.width() as u64 * size.height() as u64;
    if data.len() as u64 != n {
        return Err(format!(
            "the image is {}x{}: more pixels than the input limit allows ({limit})",
            size.width(),
            size.height()
        ));
    }
    Ok(RgbImage::new(
        size.width() as u32,
        size.height() as u32,
        data,
    ))
}

fn read_pfm(bytes: &[u8]) -> Result<RgbImage, String> {
    // header: 3 whitespace-separated tokens after the magic, then one whitespace byte
    let mut pos = 0;
    let mut tokens = Vec::new();
    while tokens.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("truncated PFM header".into());
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..pos]).to_string());
    }
    pos += 1;
    let channels = match tokens[0].as_str() {
        "PF" => 3,
        "Pf" => 1,
        t => return Err(format!("not a PFM file (magic {t:?})")),
    };
    let w: u32 = tokens[1].parse().map_err(|_| "bad PFM width")?;
    let h: u32 = tokens[2].parse().map_err(|_| "bad PFM height")?;
    let scale: f32 = tokens[3].parse().map_err(|_| "bad PFM scale")?;
    // the sign of the scale gives the byte order: 0 or NaN gives none
    if !(scale.is_finite() && scale != 0.0) {
        return Err(format!(
            "PFM scale {:?} must be a finite non-zero number (negative: little endian, positive: big endian)",
            tokens[3]
        ));
    }
    if w == 0 || h == 0 {
        return Err(format!("the image is {w}x{h}: it has no pixels"));
    }
    // in u128: 4 x w x h x 3 overflows 64 bits for the largest headers
    let need = 4 * w as u128 * h as u128 * channels as u128;
    if (bytes.len().saturating_sub(pos) as u128) < need {
        return Err(format!(
            "PFM file is shorter than its header says ({w}x{h}, {channels} channel{})",
            if channels > 1 { "s" } else { "" }
        ));
    }
    let rd = |i: usize| {
        let b = [
            bytes[pos + 4 * i],
            bytes[pos + 4 * i + 1],
            bytes[pos + 4 * i + 2],
            bytes[pos + 4 * i + 3],
        ];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut data = vec![[0.0f32; 3]; w as usize * h as usize];
    for y in 0..h as usize {
        for x in 0..w as usize {
            let src = ((h as usize - 1 - y) * w as usize + x) * channels;
            data[y * w as usize + x] = if channels == 3 {
                [rd(src), rd(src + 1), rd(src + 2)]
            } else {
                [rd(src); 3]
            };
        }
    }
    Ok(RgbImage::new(w, h, data))
}

/// Read the named channels of an EXR's first layer (e.g. "variance.R", "count.Y"), each
/// as a row-major plane, with the image's size. A channel that is missing is an error
/// naming it.
pub fn read_exr_channels(path: &Path, names: &[&str]) -> Result<(u32, u32, Vec<Vec<f32>>), String> {
    use exr::prelude::*;
    if format_of(path)? != Format::Exr {
        return Err(format!("{}: not an EXR file", path.display()));
    }
    let bytes = crate::input::read_bytes(path)?;
    check_exr_size(&bytes).map_err(|e| format!("{}: cannot read image: {e}", path.display()))?;
    let limit = max_pixels()?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("{}: cannot read image: {e}", path.display()))?;
    let size = image.layer_data.size;
    let n = size.width() as u64 * size.height() as u64;
    if n > limit {
        return Err(format!(
            "{}: the image is {}x{}: more pixels than the input limit allows ({limit})",
            path.display(),
            size.width(),
            size.height()
        ));
    }
    let chans = &image.layer_data.channel_data.list;
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let c = chans
            .iter()
            .find(|c| c.name.to_string() == *name)
            .ok_or_else(|| format!("{}: no channel {name}", path.display()))?;
        out.push(c.sample_data.values_as_f32().collect::<Vec<f32>>());
    }
    Ok((size.width() as u32, size.height() as u32, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_image() -> RgbImage {
        let data = (0..6)
            .map(|i| [i as f32 * 0.25, 1.5, -0.0 + i as f32])
            .collect();
        RgbImage::new(3, 2, data)
    }

    #[test]
    fn exr_and_pfm_round_trip() {
        let dir = std::env::temp_dir().join(format!("kalos-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = sample_image();
        for name in ["a.exr", "a.pfm"] {
            let p = dir.join(name);
            let var = vec![[1.0f32; 3]; 6];
            let cnt = vec![4.0f32; 6];
            let extra = [
                ExtraLayer {
                    name: "variance",
                    channels: LayerData::Rgb(&var),
                },
                ExtraLayer {
                    name: "count",
                    channels: LayerData::Mono(&cnt),
                },
            ];
            write_image(&p, &img, 0.0, &extra).unwrap();
            assert_eq!(read_image(&p).unwrap(), img, "{name}");
        }
        let p = dir.join("a.png");
        write_image(&p, &img, 0.0, &[]).unwrap();
        let back = read_image(&p).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        assert!((back.get(1, 0)[0] - 0.25).abs() < 0.01);
        assert!(read_image(&dir.join("missing.exr")).is_err());
        assert!(format_of(Path::new("x.tga")).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("kalos-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// /dev/full fails every write with ENOSPC, as a full disk does: every writer must
    /// say so (PNG's buffered writer used to drop the error).
    #[cfg(target_os = "linux")]
    #[test]
    fn every_writer_reports_a_full_disk() {
        let dir = temp("full");
        let img = sample_image();
        for name in ["full.png", "full.pfm", "full.exr"] {
            let p = dir.join(name);
            std::os::unix::fs::symlink("/dev/full", &p).unwrap();
            let e = write_image(&p, &img, 0.0, &[]).unwrap_err();
            assert!(e.contains(name) && e.contains("cannot write"), "{e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn pfm_with_a_zero_nan_or_infinite_scale_is_refused() {
        let dir = temp("scale");
        for scale in ["0", "-0.0", "nan", "inf", "-inf", "NaN"] {
            let p = dir.join("s.pfm");
            let mut b = format!("PF\n1 1\n{scale}\n").into_bytes();
            b.extend_from_slice(&[0x3f, 0x80, 0, 0, 0x3f, 0x80, 0, 0, 0x3f, 0x80, 0, 0]);
            std::fs::write(&p, b).unwrap();
            let e = read_image(&p).unwrap_err();
            assert!(e.contains("s.pfm") && e.contains("scale"), "{scale}: {e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn empty_and_oversized_pfm_are_refused() {
        let dir = temp("empty");
        let cases = [
            ("PF\n0 0\n-1.0\n".to_string(), "0x0"),
            ("PF\n0 5\n-1.0\n".to_string(), "0x5"),
            ("PF\n4294967295 4294967295\n-1.0\n".to_string(), "shorter"),
            ("Pf\n4294967295 4294967295\n-1.0\n".to_string(), "shorter"),
        ];
        for (head, want) in cases {
            let p = dir.join("e.pfm");
            std::fs::write(&p, head.as_bytes()).unwrap();
            let e = read_image(&p).unwrap_err();
            assert!(e.contains("e.pfm") && e.contains(want), "{head:?}: {e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
