//! MTL parsing with line numbers, so bad values are reported as `file:line: ...`.
//! (tobj's own MTL parser panics on short `Kd` lines, so kalos reads MTL itself.)
//! Texture statements are read as MTL files are written: options (`-s u v w`, `-o`,
//! `-bm`, `-clamp on`, ...) first, then a file name that may contain spaces. Values kalos
//! renders differently from what the file asks (`illum 99`, glass with `Ni 0`, a
//! duplicate `newmtl`) become notes on the material, one warning per material; Kd + Ks
//! above 1 is scaled when the scene is built ([`energy_scale`]).

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

/// Parse MTL text. `file` names it in messages; `dir` resolves texture paths.
pub fn parse_mtl(text: &str, file: &str, dir: &Path) -> Result<Vec<MaterialDesc>, String> {
    let text = crate::input::clean_text(text);
    let mut mats: Vec<MaterialDesc> = Vec::new();
    // (line of newmtl, line of Ni) of the current material
    let mut lines: Vec<(usize, Option<usize>)> = Vec::new();
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
            lines.push((line_no, None));
            continue;
        }
        let known = [
            "Kd", "Ks", "Ke", "Ns", "Ni", "illum", "map_Kd", "Ka", "d", "Tr", "Tf",
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
            "Ns" => m.ns = v3(1)?[0],
            "Ni" => {
                m.ni = v3(1)?[0];
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
            "map_Kd" => {
                let args = line[key.len()..].trim();
                let name = map_file_name(args, file, line_no, key)?;
                m.map_kd = Some(normalise_path(dir, name));
            }
            _ => {}
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
    Ok(mats)
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
        let m = parse_mtl(text, "x.mtl", Path::new("/d")).unwrap();
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
}
