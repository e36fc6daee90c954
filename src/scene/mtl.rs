//! MTL parsing with line numbers, so bad values are reported as `file:line: ...`.
//! (tobj's own MTL parser panics on short `Kd` lines, so kalos reads MTL itself.)

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

/// Parse MTL text. `file` names it in messages; `dir` resolves texture paths.
pub fn parse_mtl(text: &str, file: &str, dir: &Path) -> Result<Vec<MaterialDesc>, String> {
    let mut mats: Vec<MaterialDesc> = Vec::new();
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
            mats.push(MaterialDesc::named(&name));
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
            "Ni" => m.ni = v3(1)?[0],
            "illum" => {
                let w = rest.first().copied().unwrap_or("");
                m.illum = w.parse().map_err(|_| {
                    format!("{file}:{line_no}: illum: {w:?} is not a small integer")
                })?;
            }
            "map_Kd" => {
                // options such as -s/-o are skipped: the path is the last word(s) not starting with '-'
                let path = rest
                    .iter()
                    .rposition(|w| w.starts_with('-'))
                    .map(|k| rest[k + 1..].to_vec())
                    .unwrap_or_else(|| rest.to_vec());
                let joined = path.last().copied().unwrap_or("");
                if joined.is_empty() {
                    return Err(format!("{file}:{line_no}: map_Kd without a file name"));
                }
                m.map_kd = Some(normalise_path(dir, joined));
            }
            _ => {}
        }
    }
    Ok(mats)
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
