//! MTL parsing with line numbers, so bad values are reported as `file:line: ...`.
//! (tobj's own MTL parser panics on short `Kd` lines, so kalos reads MTL itself.)
//! Texture statements are read as MTL files are written: options (`-s u v w`, `-o`,
//! `-bm`, `-clamp on`, ...) first, then a file name that may contain spaces. Values kalos
//! renders differently from what the file asks (`illum 99`, glass with `Ni 0`, a
//! duplicate `newmtl`) become notes on the material, one warning per material; Kd + Ks
//! above 1 is scaled when the scene is built ([`energy_scale`]). Dissolve (`d`, `Tr`) and
//! `map_d` are the surface's opacity, a cut-out as Blender renders them (glass excepted).
//!
//! Files written by Blender (a first line `# Blender ... MTL File`) and materials with
//! the PBR extension's `Pr`/`Pm` are not Phong materials: Blender writes its Principled
//! BSDF as base colour `Kd`, specular level `Ks` (0.5 is a 4% Fresnel reflectance),
//! roughness as `Ns` and metallic as `illum 3` with `Ka`. They are read as such
//! ([`principled`]); read as Phong, every Blender material (`Kd 0.8`, `Ks 0.5`) would
//! reflect 1.3 and, scaled to 1, make a closed room a lossless furnace.

use super::MaterialDesc;
use std::path::{Path, PathBuf};

fn parse_vals(
    file: &str,
    line_no: usize,
    key: &str,
    words: &[&str],
    n: usize,
) -> Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(n);
    for w in words.iter() {
        let v: f32 = w
            .parse()
            .map_err(|_| format!("{file}:{line_no}: {key}: {w:?} is not a number"))?;
        if !v.is_finite() {
            return Err(format!("{file}:{line_no}: {key}: value {w} is not finite"));
        }
        if v < 0.0 {
            return Err(format!("{file}:{line_no}: {key}: negative value {w}"));
        }
        out.push(v);
    }
    if out.is_empty() {
        return Err(format!("{file}:{line_no}: {key}: missing value"));
    }
    if n == 3 && out.len() == 1 {
        out = vec![out[0]; 3]; // "Kd r" means grey r
    }
    if out.len() < n {
        return Err(format!(
            "{file}:{line_no}: {key}: expected {n} values, found {}",
            out.len()
        ));
    }
    out.truncate(n);
    Ok(out)
}

/// Normalise a path written in a file: backslashes become separators.
pub fn normalise_path(base: &Path, written: &str) -> PathBuf {
    let p = written.trim().trim_matches('"').replace('\\', "/");
    base.join(p)
}

/// Options of texture statements (`map_Kd` and friends) and how many values each takes:
/// (name, least, most). `-o`, `-s` and `-t` take 1 to 3 numbers.
const MAP_OPTIONS: &[(&str, usize, usize)] = &[
    ("-blendu", 1, 1),
    ("-blendv", 1, 1),
    ("-boost", 1, 1),
    ("-bm", 1, 1),
    ("-cc", 1, 1),
    ("-clamp", 1, 1),
    ("-imfchan", 1, 1),
    ("-mm", 2, 2),
    ("-o", 1, 3),
    ("-s", 1, 3),
    ("-t", 1, 3),
    ("-texres", 1, 1),
    ("-type", 1, 1),
];

/// The file name of a texture statement: `args` is the line after the keyword. Options
/// are skipped with their values; the rest of the line, inner spaces kept, is the name.
fn map_file_name<'a>(
    args: &'a str,
    file: &str,
    line_no: usize,
    key: &str,
) -> Result<&'a str, String> {
    let mut rest = args.trim();
    while rest.starts_with('-') {
        let (opt, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
        let Some(&(_, least, most)) = MAP_OPTIONS.iter().find(|o| o.0 == opt) else {
            return Err(format!(
                "{file}:{line_no}: {key}: unknown option {opt} (known: {})",
                MAP_OPTIONS
                    .iter()
                    .map(|o| o.0)
                    .collect::<Vec<_>>()
                    .join(" ")
            ));
        };
        rest = after.trim_start();
        for k in 0..most {
            let (w, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
            // the optional values of -o/-s/-t are numbers; a word that is not one
            // starts the file name
            if w.is_empty() || (k >= least && w.parse::<f32>().is_err()) {
                if k < least {
                    return Err(format!(
                        "{file}:{line_no}: {key}: option {opt} needs {least} value{}",
                        if least > 1 { "s" } else { "" }
                    ));
                }
                break;
            }
            rest = after.trim_start();
        }
    }
    if rest.is_empty() {
        return Err(format!("{file}:{line_no}: {key} without a file name"));
    }
    Ok(rest)
}

/// Which of Blender's OBJ exporters wrote a file: the one in C++ (Blender 3.3 on, a
/// version in its first line) or the older Python add-on; they write roughness as `Ns`
/// differently.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Writer {
    /// `# Blender 3.6.0 MTL File: ...`: Ns = 1000 (1 - r)^2, version major.
    BlenderCpp(u32),
    /// `# Blender MTL File: ...`: Ns = (30 (1 - r))^2.
    BlenderPython,
    Other,
}

fn writer_of(text: &str) -> Writer {
    let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    let words: Vec<&str> = first.trim_start_matches('#').split_whitespace().collect();
    match words.as_slice() {
        ["Blender", "MTL", ..] => Writer::BlenderPython,
        ["Blender", v, "MTL", ..] => Writer::BlenderCpp(
            v.split('.')
                .next()
                .and_then(|m| m.parse().ok())
                .unwrap_or(3),
        ),
        _ => Writer::Other,
    }
}

/// The PBR statements of a material (Blender's and the PBR extension's).
#[derive(Clone, Copy, Debug, Default)]
struct Pbr {
    ka: Option<[f32; 3]>,
    pr: Option<f32>,
    pm: Option<f32>,
    /// The material has an `Ni` statement (Blender 4's importer keeps IOR 1.5 without).
    ni_given: bool,
}

/// Blender's Principled BSDF from what its exporter wrote, as a kalos surface model:
/// roughness r (`Pr`, else from `Ns`), GGX (Blender's) alpha = r^2; metallic m
/// (`Pm`, else `Ka` under `illum 3`); a dielectric (m < 0.5) is a diffuse base `Kd` under
/// a coat whose normal-incidence reflectance is F0 = 0.08 s (Blender 2.8-3.x, s = `Ks`)
/// or F0(`Ni`) 2 s (Blender 4's "IOR level"), of index eta = (1 + sqrt F0)/(1 - sqrt F0);
/// a metal (m >= 0.5) a conductor whose F0 is the base colour. `illum 1` (Blender's
/// specular 0) and glass or mirror models stay as MTL reads them. A dielectric whose
/// coat reflects nothing (`Ks 0`; Blender 4's `Ni 1` or `Ni 0`, an IOR Blender clamps
/// to 1) is the diffuse base alone, as Blender renders it: the model is None then.
/// Returns the model and a note when the material is only approximated.
fn principled(
    m: &MaterialDesc,
    pbr: &Pbr,
    writer: Writer,
) -> Option<(Option<super::SurfaceModel>, Option<String>)> {
    use super::SurfaceModel;
    use crate::material::Distribution;
    if !matches!(m.illum, 2 | 3) {
        return None;
    }
    let r = match (pbr.pr, writer) {
        (Some(r), _) => r,
        (None, Writer::BlenderPython) => 1.0 - m.ns.max(0.0).sqrt() / 30.0,
        (None, _) => 1.0 - (m.ns.max(0.0) / 1000.0).sqrt(),
    }
    .clamp(0.0, 1.0);
    let alpha = r * r;
    let metallic = match (pbr.pm, pbr.ka) {
        (Some(v), _) => v,
        (None, Some(ka)) if m.illum == 3 => (ka[0] + ka[1] + ka[2]) / 3.0,
        _ => 0.0,
    }
    .clamp(0.0, 1.0);
    let eta_of = |f0: f32| {
        let s = f0.clamp(0.0, 0.998).sqrt();
        (1.0 + s) / (1.0 - s)
    };
    let mut note = None;
    if metallic > 0.0 && metallic < 1.0 {
        note = Some(format!(
            "metallic {metallic} (a blend of metal and dielectric) rendered as {}",
            if metallic >= 0.5 {
                "a metal"
            } else {
                "a dielectric"
            }
        ));
    }
    if metallic >= 0.5 {
        if m.map_kd.is_some() {
            note = Some("a metal's colour from map_Kd: rendered with Kd, untextured".into());
        }
        return Some((
            Some(SurfaceModel::Conductor {
                eta: m.kd.map(eta_of),
                k: [0.0; 3],
                specular: [1.0; 3],
                alpha,
                distribution: Distribution::Ggx,
            }),
            note,
        ));
    }
    let level = (m.ks[0] + m.ks[1] + m.ks[2]) / 3.0;
    let fresnel0 = |ior: f32| ((ior - 1.0) / (ior + 1.0)).powi(2);
    let f0 = match writer {
        // Blender 4's IOR socket is at least 1; without Ni its importer keeps 1.5
        Writer::BlenderCpp(v) if v >= 4 => {
            let ior = if pbr.ni_given { m.ni.max(1.0) } else { 1.5 };
            fresnel0(ior) * 2.0 * level
        }
        Writer::Other if m.ni > 1.0 => fresnel0(m.ni),
        _ => 0.08 * level,
    };
    if f0 < 1e-6 {
        return Some((None, note));
    }
    Some((
        Some(SurfaceModel::Plastic {
            eta: eta_of(f0),
            specular: [1.0; 3],
            alpha,
            distribution: Distribution::Ggx,
            nonlinear: false,
        }),
        note,
    ))
}

/// Statements that change how a surface looks and that kalos does not render, said once
/// per file with the first line and how often each occurs: a bump or alpha map
/// left out changes the image, and the brief forbids doing that without a word. (Map
/// statements of the ambient term, which a global-illumination render has no use for,
/// and bookkeeping such as `Ka` without `illum 3` are not listed.)
const NOT_RENDERED: &[(&str, &str)] = &[
    ("map_Bump", "bump map"),
    ("map_bump", "bump map"),
    ("bump", "bump map"),
    ("norm", "normal map"),
    ("map_Kn", "normal map"),
    ("disp", "displacement map"),
    ("decal", "decal"),
    ("map_Ks", "specular map"),
    ("map_Ns", "roughness map"),
    ("map_Pr", "roughness map"),
    ("map_Pm", "metallic map"),
    ("map_Ke", "emission map"),
    ("refl", "reflection map"),
];

/// Parse MTL text. `file` names it in messages; `dir` resolves texture paths. Also
/// returns notes for the file (one warning each): its materials read as Blender's, and
/// the statements it uses that kalos does not render ([`NOT_RENDERED`]).
pub fn parse_mtl(
    text: &str,
    file: &str,
    dir: &Path,
) -> Result<(Vec<MaterialDesc>, Vec<String>), String> {
    let text = crate::input::clean_text(text);
    let writer = writer_of(&text);
    let mut mats: Vec<MaterialDesc> = Vec::new();
    let mut pbr: Vec<Pbr> = Vec::new();
    // (line of newmtl, line of Ni) of the current material
    let mut lines: Vec<(usize, Option<usize>)> = Vec::new();
    // (statement, what it is, first line, occurrences) of what is not rendered
    let mut ignored: Vec<(&str, &str, usize, usize)> = Vec::new();
    // (d or Tr, its line, the opacity) of the current material when it is below 1
    let mut dissolve: Vec<Option<(String, usize, f32)>> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, rest)) = words.split_first() else {
            continue;
        };
        if key == "newmtl" {
            let name = rest.join(" ");
            if name.is_empty() {
                return Err(format!("{file}:{line_no}: newmtl without a name"));
            }
            let mut m = MaterialDesc::named(&name);
            m.source = Some(format!("{file}:{line_no}"));
            if let Some(k) = mats.iter().position(|o| o.name == name) {
                m.notes.push(format!(
                    "duplicate newmtl (first at line {}): this later definition is used",
                    lines[k].0
                ));
            }
            mats.push(m);
            pbr.push(Pbr::default());
            lines.push((line_no, None));
            dissolve.push(None);
            continue;
        }
        if let Some(&(k, what)) = NOT_RENDERED.iter().find(|(k, _)| *k == key) {
            match ignored.iter_mut().find(|(i, ..)| *i == k) {
                Some(e) => e.3 += 1,
                None => ignored.push((k, what, line_no, 1)),
            }
            continue;
        }
        let known = [
            "Kd", "Ks", "Ke", "Ns", "Ni", "illum", "map_Kd", "map_d", "Ka", "d", "Tr", "Tf", "Pr",
            "Pm",
        ];
        if !known.contains(&key) {
            continue; // other statements (maps we do not use, PBR extensions) are ignored
        }
        let Some(m) = mats.last_mut() else {
            return Err(format!("{file}:{line_no}: {key} before any newmtl"));
        };
        let v3 = |n| parse_vals(file, line_no, key, rest, n);
        match key {
            "Kd" => m.kd = to3(&v3(3)?),
            "Ks" => m.ks = to3(&v3(3)?),
            "Ke" => m.ke = to3(&v3(3)?),
            "Ka" => {
                if let Some(p) = pbr.last_mut() {
                    p.ka = Some(to3(&v3(3)?));
                }
            }
            "Pr" | "Pm" => {
                let v = v3(1)?[0];
                if let Some(p) = pbr.last_mut() {
                    *(if key == "Pr" { &mut p.pr } else { &mut p.pm }) = Some(v);
                }
            }
            "Ns" => m.ns = v3(1)?[0],
            "Ni" => {
                m.ni = v3(1)?[0];
                if let Some(p) = pbr.last_mut() {
                    p.ni_given = true;
                }
                if let Some(l) = lines.last_mut() {
                    l.1 = Some(line_no);
                }
            }
            "illum" => {
                let w = rest.first().copied().unwrap_or("");
                m.illum = w.parse().map_err(|_| {
                    format!("{file}:{line_no}: illum: {w:?} is not a small integer")
                })?;
                if m.illum > 10 {
                    m.notes.push(format!(
                        "illum {} (line {line_no}) is not an MTL illumination model (0 to 10): rendered as diffuse + glossy from Kd and Ks",
                        m.illum
                    ));
                }
            }
            // Dissolve: d 1 (Tr 0) is opaque; below, the surface's opacity (a cut-out
            // that lets the rest of the light through, as Blender reads it), except on
            // glass (illum 7), which is see-through of its own.
            "d" | "Tr" => {
                // `d -halo f` (the MTL spec's orientation-dependent dissolve) is a dissolve too
                let words = match rest.split_first() {
                    Some((&"-halo", w)) if key == "d" => w,
                    _ => rest,
                };
                let v = parse_vals(file, line_no, key, words, 1)?[0];
                let opacity = if key == "d" { v } else { 1.0 - v }.clamp(0.0, 1.0);
                if let Some(d) = dissolve.last_mut() {
                    *d = (opacity < 1.0).then(|| (format!("{key} {v}"), line_no, opacity));
                }
            }
            "map_d" => {
                let args = line[key.len()..].trim();
                let name = map_file_name(args, file, line_no, key)?;
                m.map_opacity = Some((
                    normalise_path(dir, name),
                    crate::texture::Sampling::default(),
                    crate::texture::OpacityFrom::AlphaOrGrey,
                ));
            }
            "map_Kd" => {
                let args = line[key.len()..].trim();
                let name = map_file_name(args, file, line_no, key)?;
                m.map_kd = Some(normalise_path(dir, name));
            }
            _ => {}
        }
    }
    for (m, d) in mats.iter_mut().zip(&dissolve) {
        if m.illum == 7 {
            m.map_opacity = None; // glass is see-through by refraction
        } else if let Some((what, at, opacity)) = d {
            m.opacity = *opacity;
            if *opacity == 0.0 && m.map_opacity.is_none() {
                m.notes.push(format!(
                    "{what} (line {at}): fully transparent, the surface is invisible (as Blender renders it)"
                ));
            }
        } else if matches!(m.illum, 4 | 6 | 9) && m.map_opacity.is_none() {
            m.notes.push(format!(
                "illum {} (transparency, ray-traced refraction) is not rendered: opaque diffuse + glossy from Kd and Ks (illum 7 makes it glass)",
                m.illum
            ));
        }
    }
    for (m, (_, ni_line)) in mats.iter_mut().zip(&lines) {
        if m.illum == 7 && m.ni <= 0.0 {
            let at = ni_line.map(|l| format!(" (line {l})")).unwrap_or_default();
            m.notes.push(format!(
                "glass (illum 7) with Ni {}{at}: an index of refraction must be positive; rendered with 1.5",
                m.ni
            ));
        }
    }
    let blender = writer != Writer::Other;
    let mut read_as_pbr = 0;
    for (m, p) in mats.iter_mut().zip(&pbr) {
        if !(blender || p.pr.is_some() || p.pm.is_some()) {
            continue;
        }
        if let Some((model, note)) = principled(m, p, writer) {
            if model.is_none() {
                m.ks = [0.0; 3]; // no coat: the base alone, not MTL's Phong lobe
            }
            m.model = model;
            m.notes.extend(note);
            read_as_pbr += 1;
        }
    }
    let mut notes: Vec<String> = Vec::new();
    if !ignored.is_empty() {
        let list: Vec<String> = ignored
            .iter()
            .map(|(k, what, line, n)| {
                let times = if *n == 1 {
                    String::new()
                } else {
                    format!(", {n} times")
                };
                format!("{k} ({what}, line {line}{times})")
            })
            .collect();
        notes.push(format!(
            "{file}: not rendered, so these surfaces will look different: {}",
            list.join(", ")
        ));
    }
    let note = (read_as_pbr > 0).then(|| {
        format!(
            "{file}: {read_as_pbr} material{} {} read as a physically based surface ({}base colour Kd, roughness from {}, specular level Ks, metallic from {}), not as Phong Kd + Ks",
            if read_as_pbr == 1 { "" } else { "s" },
            if read_as_pbr == 1 { "is" } else { "are" },
            if blender { "Blender's Principled BSDF export: " } else { "the PBR extension: " },
            if blender { "Ns or Pr" } else { "Pr" },
            if blender { "illum 3 + Ka or Pm" } else { "Pm" },
        )
    });
    notes.extend(note);
    Ok((mats, notes))
}

/// The factor that brings the albedo of an MTL material to at most 1 on every band
/// (RGB, 8 and 16 bands), or None when it is at most 1 already. The diffuse reflectance
/// is `kd_mean` when a texture gives it (its mean texel), else Kd; a mirror (`illum 5`)
/// reflects Ks (1 when Ks is 0), glass (`illum 7`) is lossless by construction. Kd + Ks
/// bounds the albedo of diffuse + normalized Phong, so Kd + Ks <= 1 conserves energy.
/// Returns (scale, the largest band value before scaling).
pub fn energy_scale(m: &MaterialDesc, kd_mean: Option<[f32; 3]>) -> Option<(f32, f32)> {
    use crate::spectrum::Spectrum;
    let kd = kd_mean.unwrap_or(m.kd).map(f64::from);
    let ks = m.ks.map(f64::from);
    // in f64: Kd 3e38 + Ks 3e38 overflows f32
    let total: [f64; 3] = match m.illum {
        5 if m.ks == [0.0; 3] => return None,
        5 => ks,
        7 => return None,
        _ => [kd[0] + ks[0], kd[1] + ks[1], kd[2] + ks[2]],
    };
    let peak = total.iter().fold(0.0f64, |a, &b| a.max(b));
    if !(peak > 0.0 && peak.is_finite()) {
        return None;
    }
    // the uplift is linear: bands of total = peak x bands of total / peak
    let unit = total.map(|v| (v / peak) as f32);
    let bands = Spectrum::<3>::from_rgb(unit)
        .max_value()
        .max(Spectrum::<8>::from_rgb(unit).max_value())
        .max(Spectrum::<16>::from_rgb(unit).max_value());
    let max = peak * bands as f64;
    // a little above 1 is rounding in files (0.8 + 0.2 written as 0.800001 + 0.2)
    (max > 1.0 + 1e-5).then(|| ((1.0 / max) as f32, max as f32))
}

fn to3(v: &[f32]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_materials_and_reports_lines() {
        let text = "# c\nnewmtl a\nKd 0.5\nKs 0.1 0.2 0.3\nNs 15\nillum 5\nmap_Kd -s 1 1 1 tex\\wood.png\nnewmtl b\nKe 1 2 3\n";
        let (m, note) = parse_mtl(text, "x.mtl", Path::new("/d")).unwrap();
        assert!(note.is_empty() && m.iter().all(|m| m.model.is_none()));
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].kd, [0.5; 3]);
        assert_eq!(m[0].ks, [0.1, 0.2, 0.3]);
        assert_eq!(m[0].illum, 5);
        assert_eq!(m[0].map_kd.as_deref(), Some(Path::new("/d/tex/wood.png")));
        assert_eq!(m[1].ke, [1.0, 2.0, 3.0]);
        let e = parse_mtl("newmtl a\nKd 0.5 nan 1\n", "x.mtl", Path::new(".")).unwrap_err();
        assert!(e.starts_with("x.mtl:2: Kd"), "{e}");
        let e = parse_mtl("newmtl a\n\nKd 0.5 -1 1\n", "x.mtl", Path::new(".")).unwrap_err();
        assert!(e.starts_with("x.mtl:3: Kd: negative"), "{e}");
        let e = parse_mtl("Kd 1 1 1\n", "x.mtl", Path::new(".")).unwrap_err();
        assert!(e.contains("before any newmtl"), "{e}");
    }

    /// Blender's exporters' defaults (base 0.8, specular 0.5, roughness 0.5) as they write
    /// them, read back as the Principled BSDF they describe.
    #[test]
    fn blender_materials_are_read_as_principled() {
        use crate::scene::SurfaceModel;
        let cpp = "# Blender 3.6.5 MTL File: 'room.blend'\n# www.blender.org\n\nnewmtl Wall\nNs 250.000000\nKa 1.000000 1.000000 1.000000\nKd 0.800000 0.800000 0.800000\nKs 0.500000 0.500000 0.500000\nKe 0.0 0.0 0.0\nNi 1.450000\nd 1.000000\nillum 2\n\nnewmtl Gold\nNs 810.0\nKa 1.0 1.0 1.0\nKd 1.0 0.766 0.336\nKs 0.5 0.5 0.5\nNi 1.45\nillum 3\n\nnewmtl Matte\nNs 0\nKd 0.5 0.5 0.5\nKs 0 0 0\nillum 1\n";
        let (m, note) = parse_mtl(cpp, "room.mtl", Path::new(".")).unwrap();
        let note = note.first().expect("a note for the file");
        assert!(
            note.starts_with("room.mtl: 2 materials are read as") && note.contains("Blender"),
            "{note}"
        );
        match m[0].model {
            Some(SurfaceModel::Plastic { eta, alpha, .. }) => {
                // F0 = 0.08 x 0.5 = 0.04: eta 1.5; roughness 1 - sqrt(250/1000) = 0.5
                assert!((eta - 1.5).abs() < 1e-4, "{eta}");
                assert!((alpha - 0.25).abs() < 1e-5, "{alpha}");
            }
            ref o => panic!("{o:?}"),
        }
        match m[1].model {
            Some(SurfaceModel::Conductor { eta, k, alpha, .. }) => {
                // F0 of a k = 0 conductor of index eta is ((eta - 1)/(eta + 1))^2 = Kd
                for (e, kd) in eta.iter().zip(m[1].kd) {
                    let f0 = ((e - 1.0) / (e + 1.0)).powi(2);
                    assert!((f0 - kd).abs() < 2e-3, "{kd}: {f0}");
                }
                assert_eq!(k, [0.0; 3]);
                assert!((alpha - 0.01).abs() < 1e-4, "{alpha}");
            }
            ref o => panic!("{o:?}"),
        }
        assert!(
            m[2].model.is_none(),
            "illum 1 (specular 0) stays Lambertian"
        );
        // the Python add-on's Ns = (30 (1 - r))^2; Blender 4's F0 = F0(Ni) x 2 x level
        let py = "# Blender MTL File: 'None'\n# Material Count: 1\n\nnewmtl M\nNs 225\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNi 1.5\nillum 2\n";
        let (m, _) = parse_mtl(py, "a.mtl", Path::new(".")).unwrap();
        assert!(
            matches!(m[0].model, Some(SurfaceModel::Plastic { alpha, .. }) if (alpha - 0.25).abs() < 1e-5)
        );
        let v4 = py
            .replace("# Blender MTL File", "# Blender 4.2.1 MTL File")
            .replace("Ns 225", "Ns 250");
        let (m, _) = parse_mtl(&v4, "a.mtl", Path::new(".")).unwrap();
        assert!(
            matches!(m[0].model, Some(SurfaceModel::Plastic { eta, .. }) if (eta - 1.5).abs() < 1e-4)
        );
        // the PBR extension in a file of another writer
        let (m, note) = parse_mtl(
            "newmtl a\nKd 0.5 0.5 0.5\nPr 0.3\nPm 1\n",
            "b.mtl",
            Path::new("."),
        )
        .unwrap();
        assert!(
            matches!(m[0].model, Some(SurfaceModel::Conductor { alpha, .. }) if (alpha - 0.09).abs() < 1e-5)
        );
        assert!(note[0].contains("PBR extension"));
    }

    /// Maps kalos does not render are said, never dropped in silence (one note for the
    /// file); dissolve and map_d are the surface's opacity (a cut-out), `d 0` said.
    #[test]
    fn what_is_not_rendered_is_said() {
        use crate::texture::OpacityFrom;
        let text = "newmtl a\nKd 0.5 0.5 0.5\nmap_Bump -bm 0.3 a n.png\nmap_d leaf.png\nd 0.25\n\
                    newmtl b\nKd 0.5 0.5 0.5\nbump b.png\nmap_Bump c.png\nTr 0\nd 1\n\
                    newmtl c\nKs 1 1 1\nNi 1.5\nd 0.1\nillum 7\n\
                    newmtl w\nKd 0.2 0.2 0.2\nillum 4\nmap_Ka amb.png\n\
                    newmtl h\nKd 0.5 0.5 0.5\nd -halo 0.6\n\
                    newmtl z\nKd 0.5 0.5 0.5\nd 0.000000\nillum 9\n";
        let (m, notes) = parse_mtl(text, "x.mtl", Path::new("/d")).unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert_eq!(
            notes[0],
            "x.mtl: not rendered, so these surfaces will look different: map_Bump (bump map, \
             line 3, 2 times), bump (bump map, line 8)"
        );
        assert_eq!(m[0].opacity, 0.25);
        assert_eq!(
            m[0].map_opacity,
            Some((
                PathBuf::from("/d/leaf.png"),
                Default::default(),
                OpacityFrom::AlphaOrGrey
            ))
        );
        assert!(m[0].notes.is_empty(), "{:?}", m[0].notes);
        assert_eq!(m[1].opacity, 1.0, "Tr 0 then d 1");
        assert!(m[1].notes.is_empty(), "opaque d 1 / Tr 0: {:?}", m[1].notes);
        assert!(m[2].notes.is_empty(), "glass: {:?}", m[2].notes);
        assert_eq!(m[2].opacity, 1.0, "glass is see-through by refraction");
        assert!(
            m[3].notes[0].starts_with("illum 4 (transparency"),
            "{:?}",
            m[3].notes
        );
        assert_eq!(m[4].opacity, 0.6, "d -halo");
        assert_eq!(m[5].opacity, 0.0);
        assert!(
            m[5].notes[0].starts_with("d 0 (line 26): fully transparent"),
            "{:?}",
            m[5].notes
        );
    }
}
