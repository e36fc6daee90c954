//! Colours as Mitsuba 3's RGB mode reads them: rgb, srgb, spectra (integrated against
//! CIE 1931, reflectances under D65), textures, and the named indices of refraction and
//! conductors.

use super::*;

#[derive(Clone, Copy, PartialEq)]
pub(super) enum Use {
    /// Reflectances and other bounded values: the spectrum under D65.
    Reflectance,
    /// Radiance, intensity: an unbounded spectrum (equal-energy white).
    Unbounded,
    /// A conductor's eta and k: unbounded, but a constant is that number in every channel
    /// (Mitsuba's uniform spectrum), not an equal-energy white.
    Ior,
}

/// A colour-valued parameter.
pub(super) enum Color {
    Rgb([f32; 3]),
    /// A bitmap texture: its file and how it is looked up.
    Bitmap(PathBuf, crate::texture::Sampling),
    /// A texture made here (Mitsuba's `checkerboard`).
    Procedural(crate::scene::Texture),
    /// Mitsuba's `mesh_attribute`: a mesh's attribute, looked up per hit.
    Attribute(crate::texture::mesh_attribute::MeshAttribute),
}

impl Color {
    /// The colour as a float parameter reads it (Mitsuba's `eval_1`: roughnesses,
    /// principled's scalars): a checkerboard's `eval_1` takes color0 where its colour
    /// lookup (`eval`) takes color1, and color1 where it takes color0.
    pub(super) fn scalar_lookup(self) -> Color {
        match self {
            Color::Procedural(t) if t.texels.len() == 4 => Color::Procedural(
                crate::scene::Texture::checkerboard(t.texels[1], t.texels[0], t.sampling.to_uv),
            ),
            c => c,
        }
    }
}

/// What is said of a negative colour value.
const NEGATIVE: &str = "a negative value (reflectances, radiances and indices are non-negative)";

/// CIE 15:2004 illuminant D65, 300..830 nm in 5 nm steps (normalised to 100 at 560 nm).
pub(super) const D65: [f32; 107] = [
    0.0341, 1.6643, 3.2945, 11.7652, 20.236, 28.6447, 37.0535, 38.5011, 39.9488, 42.4302, 44.9117,
    45.775, 46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549,
    87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023, 100.0,
    98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991,
    88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146,
    81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054, 46.4182, 56.6118,
    66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4518, 55.7054, 51.959, 54.6998,
    57.4406, 58.8765, 60.3125,
];

pub(super) fn d65(l: f64) -> f64 {
    let x = (l - 300.0) / 5.0;
    if !(0.0..=106.0).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(105);
    let f = x - i as f64;
    D65[i] as f64 * (1.0 - f) + D65[i + 1] as f64 * f
}

/// Piecewise-linear spectrum (sorted wavelengths in nm) to linear sRGB, as Mitsuba 3's
/// RGB variants do: integrated against CIE 1931 over 360..830 nm (kalos' multi-lobe fit of
/// the curves), under D65 and normalised to white = 1 for reflectances; as an
/// equal-energy spectrum (Y normalised) for emission.
pub fn spectrum_to_rgb(wl: &[f32], val: &[f32], reflectance: bool) -> [f32; 3] {
    let at = |l: f64| -> f64 {
        if wl.is_empty() || l < wl[0] as f64 || l > wl[wl.len() - 1] as f64 {
            return 0.0;
        }
        let i = wl
            .partition_point(|&w| (w as f64) <= l)
            .clamp(1, wl.len() - 1);
        let (l0, l1) = (wl[i - 1] as f64, wl[i] as f64);
        let f = if l1 > l0 { (l - l0) / (l1 - l0) } else { 0.0 };
        val[i - 1] as f64 * (1.0 - f) + val[i] as f64 * f
    };
    let (mut xyz, mut norm) = ([0.0f64; 3], 0.0f64);
    let steps = 940;
    let dl = (830.0 - 360.0) / steps as f64;
    for k in 0..steps {
        let l = 360.0 + (k as f64 + 0.5) * dl;
        let c = crate::spectrum::cie_xyz(l);
        let w = if reflectance { d65(l) } else { 1.0 };
        let s = at(l) * w;
        for j in 0..3 {
            xyz[j] += c[j] * s;
        }
        norm += c[1] * w;
    }
    let m = [
        [3.2404542, -1.5371385, -0.4985314],
        [-0.9692660, 1.8760108, 0.0415560],
        [0.0556434, -0.2040259, 1.0572252],
    ];
    let xyz = xyz.map(|v| v / norm);
    let mut rgb = [0.0f32; 3];
    for c in 0..3 {
        let v: f64 = (0..3).map(|j| m[c][j] * xyz[j]).sum();
        rgb[c] = if reflectance {
            v.max(0.0) as f32
        } else {
            v as f32
        };
    }
    rgb
}

/// Named indices of refraction (Mitsuba 3's list).
pub(super) const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Mitsuba 3's named conductors as its RGB variants see them (eta, k per channel, as
/// `mi.traverse` reports them for `conductor` with `material` set, Mitsuba 3.9.1).
pub(super) const METALS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("none", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.828354, 3.122222, 2.146901],
    ),
    (
        "Al",
        [1.657501, 0.880405, 0.521244],
        [9.223811, 6.269502, 4.837004],
    ),
    (
        "AlAs",
        [3.605296, 3.232938, 2.216319],
        [0.000679, 0.0, 0.007513],
    ),
    ("AlSb", [0.0, 4.139375, 4.669254], [0.0, 0.094009, 1.30057]),
    (
        "Au",
        [0.143036, 0.375307, 1.442045],
        [3.982997, 2.385556, 1.603359],
    ),
    (
        "Be",
        [4.185012, 3.185029, 2.784061],
        [3.835466, 3.010122, 2.868994],
    ),
    (
        "Cr",
        [4.369668, 2.916505, 1.654905],
        [5.206547, 4.231306, 3.754699],
    ),
    ("CsI", [2.1449, 1.702319, 1.662427], [0.0, 0.0, 0.0]),
    (
        "Cu",
        [0.201005, 0.92375, 1.102215],
        [3.913262, 2.453045, 2.14209],
    ),
    (
        "Cu2O",
        [3.551773, 2.94987, 2.751875],
        [0.114207, 0.193897, 0.606134],
    ),
    (
        "CuO",
        [3.247541, 2.447805, 2.21022],
        [0.52109, 0.570031, 0.722179],
    ),
    (
        "Hg",
        [2.398939, 1.440028, 0.90957],
        [6.327587, 4.371925, 3.421764],
    ),
    (
        "HgTe",
        [4.77904, 3.231196, 2.659901],
        [1.631613, 1.58081, 1.729287],
    ),
    (
        "Ir",
        [3.0863, 2.082191, 1.617915],
        [5.592153, 4.067088, 3.267312],
    ),
    (
        "K",
        [0.064043, 0.04641, 0.038185],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "Li",
        [0.265791, 0.195618, 0.220949],
        [3.540155, 2.311123, 1.668607],
    ),
    ("MgO", [2.089584, 1.650723, 1.594879], [0.0, 0.0, 0.0]),
    (
        "Mo",
        [4.483974, 3.525131, 2.77631],
        [4.111437, 3.420827, 3.150607],
    ),
    (
        "Na",
        [0.060269, 0.056141, 0.061988],
        [3.179273, 2.11249, 1.579041],
    ),
    (
        "Nb",
        [3.420074, 2.790093, 2.395629],
        [3.441395, 2.737666, 2.579746],
    ),
    (
        "Ni",
        [2.367305, 1.663373, 1.467078],
        [4.498812, 3.050153, 2.345439],
    ),
    (
        "Rh",
        [2.585793, 1.860216, 1.554263],
        [6.78226, 4.702987, 3.976073],
    ),
    (
        "Se",
        [4.058311, 2.842935, 2.820853],
        [0.75405, 0.638444, 0.521808],
    ),
    (
        "Se-e",
        [5.722849, 4.165736, 4.081338],
        [0.871136, 1.105157, 1.56532],
    ),
    (
        "SiC",
        [3.172342, 2.525972, 2.479371],
        [0.000001, 0.0, 0.00001],
    ),
    ("SnTe", [4.52425, 1.981645, 1.281591], [0.0, 0.0, 0.0]),
    (
        "Ta",
        [2.062721, 2.392939, 2.627929],
        [2.40836, 1.741486, 1.947028],
    ),
    (
        "Te",
        [7.390234, 4.482105, 2.637106],
        [3.256022, 3.527059, 3.292054],
    ),
    (
        "Te-e",
        [7.508907, 4.296429, 2.369988],
        [5.583929, 4.947205, 3.997592],
    ),
    ("ThF4", [1.830714, 1.442229, 1.387648], [0.0, 0.0, 0.0]),
    (
        "TiC",
        [3.700528, 2.837422, 2.582287],
        [3.265635, 2.351589, 2.172791],
    ),
    (
        "TiN",
        [1.64845, 1.150516, 1.379823],
        [3.368328, 1.943498, 1.102068],
    ),
    (
        "TiO2",
        [3.45661, 2.801736, 2.905175],
        [0.000105, 0.0, 0.000653],
    ),
    (
        "TiO2-e",
        [3.106565, 2.513168, 2.582444],
        [0.00003, 0.0, 0.000183],
    ),
    (
        "V",
        [4.277582, 3.512949, 2.761071],
        [3.491301, 2.889455, 3.111522],
    ),
    (
        "VC",
        [3.657566, 2.752736, 2.532672],
        [3.068301, 2.198687, 1.963193],
    ),
    (
        "VN",
        [2.865602, 2.119189, 1.940091],
        [3.032243, 2.056116, 1.616306],
    ),
    (
        "W",
        [4.370817, 3.300246, 2.998407],
        [3.500641, 2.604874, 2.273233],
    ),
    (
        "a-C",
        [2.944046, 2.227136, 1.968162],
        [0.887465, 0.799299, 0.81529],
    ),
    ("d-C", [2.70872, 2.318826, 2.228898], [0.0, 0.0, 0.0]),
];

impl<'a> Loader<'a> {
    /// A colour property (rgb, srgb, spectrum, float, texture or ref to a texture).
    pub(super) fn color(&self, el: &'a El, name: &str, use_: Use) -> R<Option<Color>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.color_of(p, use_)?)),
            None => Ok(None),
        }
    }

    pub(super) fn color_of(&self, p: &'a El, use_: Use) -> R<Color> {
        let target = self.resolve(p)?;
        self.building(p, target, || self.color_of_resolved(target, use_))
    }

    fn color_of_resolved(&self, p: &'a El, use_: Use) -> R<Color> {
        let name = p.name().unwrap_or("");
        let bad = |v: &str, what: &str| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: {what}",
                p.at, p.tag
            )
        };
        match p.tag.as_str() {
            "rgb" | "srgb" | "color" => {
                let v = self.value(p)?;
                let mut rgb = if let Some(hex) = v.trim().strip_prefix('#') {
                    let h = u32::from_str_radix(hex, 16)
                        .ok()
                        .filter(|_| hex.len() == 6)
                        .ok_or_else(|| bad(v, "not a #rrggbb colour"))?;
                    [(h >> 16) & 255, (h >> 8) & 255, h & 255].map(|c| c as f32 / 255.0)
                } else {
                    match numbers(v).as_deref() {
                        Some([r, g, b]) => [*r, *g, *b],
                        Some([s]) => [*s; 3],
                        _ => return Err(bad(v, "expected 3 (or 1) finite numbers")),
                    }
                };
                if rgb.iter().any(|c| *c < 0.0) {
                    return Err(bad(v, NEGATIVE));
                }
                if p.tag == "srgb" || v.trim().starts_with('#') {
                    rgb = rgb.map(crate::image_io::srgb_decode);
                }
                Ok(Color::Rgb(rgb))
            }
            "float" => {
                let v = self.value(p)?;
                match numbers(v).as_deref() {
                    Some([s]) if *s < 0.0 => Err(bad(v, NEGATIVE)),
                    Some([s]) => Ok(Color::Rgb([*s; 3])),
                    _ => Err(bad(v, "not a finite number")),
                }
            }
            "spectrum" => {
                if let Some(t) = p.attr("type") {
                    self.warn(
                        &format!("spectrum {t}"),
                        format!(
                            "{}: spectrum plugin '{t}' is not supported: rendered as 1 (white)",
                            p.at
                        ),
                    );
                    self.mark_all(p);
                    return Ok(Color::Rgb([1.0; 3]));
                }
                let (wl, val) = if let Some(f) = p.attr("filename") {
                    let path = self.path(f);
                    let text = crate::input::read_text(&path)
                        .map_err(|e| format!("{}: <spectrum filename>: {e}", p.at))?;
                    let mut wl = Vec::new();
                    let mut val = Vec::new();
                    for (i, line) in text.lines().enumerate() {
                        let line = line.split('#').next().unwrap_or("").trim();
                        if line.is_empty() {
                            continue;
                        }
                        match numbers(line).as_deref() {
                            Some([_, v]) if *v < 0.0 => {
                                return Err(format!("{}:{}: {NEGATIVE}", path.display(), i + 1))
                            }
                            Some([l, v]) => {
                                wl.push(*l);
                                val.push(*v);
                            }
                            _ => {
                                return Err(format!(
                                    "{}:{}: expected a wavelength and a value",
                                    path.display(),
                                    i + 1
                                ))
                            }
                        }
                    }
                    (wl, val)
                } else {
                    let v = self.value(p)?;
                    if !v.contains(':') {
                        let s = match numbers(v).as_deref() {
                            Some([s]) if *s < 0.0 => return Err(bad(v, NEGATIVE)),
                            Some([s]) => *s,
                            _ => return Err(bad(v, "expected a number or wavelength:value pairs")),
                        };
                        // a constant: a reflectance stays s; emission is equal-energy white
                        return Ok(Color::Rgb(match use_ {
                            Use::Reflectance | Use::Ior => [s; 3],
                            Use::Unbounded => spectrum_to_rgb(&[360.0, 830.0], &[s, s], false),
                        }));
                    }
                    let mut wl = Vec::new();
                    let mut val = Vec::new();
                    // Mitsuba tokenizes on commas and whitespace: "400:0.1, 500:0.5" or
                    // "400:0.1 500:0.5"
                    for pair in v
                        .split(|c: char| c == ',' || c.is_whitespace())
                        .filter(|s| !s.is_empty())
                    {
                        let (l, x) = pair
                            .split_once(':')
                            .ok_or_else(|| bad(v, "expected wavelength:value pairs"))?;
                        let (Ok(l), Ok(x)) = (l.trim().parse::<f32>(), x.trim().parse::<f32>())
                        else {
                            return Err(bad(v, "expected wavelength:value pairs of numbers"));
                        };
                        if !(l.is_finite() && x.is_finite()) {
                            return Err(bad(v, "values must be finite"));
                        }
                        if x < 0.0 {
                            return Err(bad(v, NEGATIVE));
                        }
                        wl.push(l);
                        val.push(x);
                    }
                    (wl, val)
                };
                if wl.is_empty() || wl.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(format!(
                        "{}: <spectrum name=\"{name}\">: wavelengths must be given in increasing order",
                        p.at
                    ));
                }
                Ok(Color::Rgb(spectrum_to_rgb(
                    &wl,
                    &val,
                    use_ == Use::Reflectance,
                )))
            }
            "texture" => {
                let kind = p.kind();
                if !known_plugin("texture", kind) {
                    return Err(format!("{}: unknown texture plugin '{kind}'", p.at));
                }
                match kind {
                    "bitmap" => {
                        let (path, sampling, _) = self.bitmap(p, false)?;
                        Ok(Color::Bitmap(path, sampling))
                    }
                    "checkerboard" => {
                        // each colour a constant (a texture inside gives its mean, warned)
                        let colour = |name: &str, default: f32| -> R<[f32; 3]> {
                            match self.color(p, name, use_)? {
                                None => Ok([default; 3]),
                                Some(Color::Rgb(v)) => Ok(v),
                                Some(c) => {
                                    self.warn(
                                        "checkerboard of textures",
                                        format!(
                                            "{}: a texture as checkerboard '{name}' is not supported: rendered with its mean",
                                            p.at
                                        ),
                                    );
                                    self.mean_rgb(c, &p.at)
                                }
                            }
                        };
                        let (a, b) = (colour("color0", 0.4)?, colour("color1", 0.2)?);
                        let to_uv = self.to_uv(p)?;
                        self.unused(p, "texture 'checkerboard'");
                        Ok(Color::Procedural(crate::scene::Texture::checkerboard(
                            a, b, to_uv,
                        )))
                    }
                    "mesh_attribute" => self.mesh_attribute(p).map(Color::Attribute),
                    k => {
                        self.mark_all(p);
                        self.warn(
                            &format!("texture {k}"),
                            format!(
                                "{}: unsupported texture '{k}': rendered as 0.5 (grey)",
                                p.at
                            ),
                        );
                        Ok(Color::Rgb([0.5; 3]))
                    }
                }
            }
            t => Err(format!(
                "{}: <{t} name=\"{name}\">: expected a colour (rgb, spectrum, float or texture)",
                p.at
            )),
        }
    }

    /// A `bitmap` texture element: its file (checked to be one), its lookup, and its
    /// `raw` flag (8-bit values not sRGB-decoded), which is warned unless `raw_read` (the
    /// caller reads it).
    pub(super) fn bitmap(
        &self,
        p: &'a El,
        raw_read: bool,
    ) -> R<(PathBuf, crate::texture::Sampling, bool)> {
        let f = self
            .string(p, "filename")?
            .ok_or_else(|| format!("{}: bitmap texture without a filename", p.at))?;
        let path = self.path(&f);
        crate::input::check_regular_file(&path, crate::input::max_input_bytes()?)
            .map_err(|e| format!("{}: bitmap texture: {e}", p.at))?;
        let sampling = self.bitmap_sampling(p)?;
        let raw = self.boolean(p, "raw")?.unwrap_or(false);
        if raw && !raw_read {
            self.warn(
                "bitmap raw",
                format!(
                    "{}: bitmap raw 'true' is not supported here: sRGB-decoded 8-bit or linear EXR",
                    p.at
                ),
            );
        }
        // Mitsuba's `format` sets the precision it keeps the texels in
        if let Some(c) = self.prop(p, "format") {
            let v = c.attr("value").unwrap_or("");
            if v != "variant" {
                self.warn(
                    "bitmap format",
                    format!(
                        "{}: bitmap format '{v}' is not supported: sRGB-decoded 8-bit or linear EXR",
                        c.at
                    ),
                );
            }
        }
        self.unused(p, "texture 'bitmap'");
        Ok((path, sampling, raw))
    }

    /// A bitmap's `filter_type`, `wrap_mode` and `to_uv`.
    fn bitmap_sampling(&self, p: &'a El) -> R<crate::texture::Sampling> {
        use crate::texture::{Sampling, Wrap};
        let mut s = Sampling::default();
        match self.string(p, "filter_type")?.as_deref() {
            None | Some("bilinear") => {}
            Some("nearest") => s.nearest = true,
            Some(v) => {
                return Err(format!(
                    "{}: bitmap filter_type \"{v}\": must be \"bilinear\" or \"nearest\"",
                    p.at
                ))
            }
        }
        s.wrap = match self.string(p, "wrap_mode")?.as_deref() {
            None | Some("repeat") => Wrap::Repeat,
            Some("mirror") => Wrap::Mirror,
            Some("clamp") => Wrap::Clamp,
            Some(v) => {
                return Err(format!(
                    "{}: bitmap wrap_mode \"{v}\": must be \"repeat\", \"mirror\" or \"clamp\"",
                    p.at
                ))
            }
        };
        s.to_uv = self.to_uv(p)?;
        Ok(s)
    }

    /// A texture's `to_uv` as [`crate::texture::Sampling::to_uv`] holds it.
    fn to_uv(&self, p: &'a El) -> R<[f32; 6]> {
        let m = self.transform(p, "to_uv")?;
        let to_uv = [
            m.x_axis.x, m.y_axis.x, m.w_axis.x, m.x_axis.y, m.y_axis.y, m.w_axis.y,
        ];
        if !to_uv.iter().all(|v| v.is_finite()) {
            return Err(format!("{}: texture to_uv is not finite", p.at));
        }
        Ok(to_uv)
    }

    /// The mean of a colour (a bitmap's mean texel).
    pub(super) fn mean_rgb(&self, c: Color, at: &str) -> R<[f32; 3]> {
        match c {
            Color::Rgb(v) => Ok(v),
            Color::Bitmap(p, _) => crate::scene::Texture::load(&p)
                .map(|t| t.mean())
                .map_err(|e| format!("{at}: {e}")),
            Color::Procedural(t) => Ok(t.mean()),
            // unknown before the meshes are read: the scale
            Color::Attribute(a) => Ok([a.scale; 3]),
        }
    }

    /// A colour used where kalos takes a constant: a texture gives its mean, warned.
    pub(super) fn constant(
        &self,
        el: &'a El,
        name: &str,
        use_: Use,
        plugin: &str,
    ) -> R<Option<[f32; 3]>> {
        match self.color(el, name, use_)? {
            None => Ok(None),
            Some(Color::Rgb(v)) => Ok(Some(v)),
            Some(c) => {
                self.warn(
                    &format!("texture in {plugin} {name}"),
                    format!(
                        "{}: a texture as {plugin} '{name}' is not supported: rendered with its mean",
                        el.at
                    ),
                );
                Ok(Some(self.mean_rgb(c, &el.at)?))
            }
        }
    }
}
