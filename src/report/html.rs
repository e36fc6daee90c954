//! The report of an experiment's results folder: `report.html`, one self-contained page
//! (every image a data URI, no script or style from the network) with the error curves
//! against time and samples per pixel (each point the mean over seeds, its bar the range
//! over seeds), a table of the numbers, and per budget each configuration's image beside
//! the reference (hovering an image shows the reference in its place), a zoomed crop, and
//! false-colour maps of the relative colour error and of FLIP.
//!
//! It is built from what `kalos experiment` writes (results.json, report.json, the EXR
//! images), so `kalos report DIR` rebuilds it; for folders written before report.json
//! existed the configurations, budgets and images are found from results.json.

use super::{crop, plot_panels, Panel, Series};
use crate::image_io::{png_bytes, read_image, srgb8, RgbImage};
use crate::metrics::flip::{self, magma, Range};
use base64::Engine;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What the report needs besides results.json, written by the experiment as report.json.
#[derive(Serialize, Deserialize, Clone, Debug)]
pub struct Manifest {
    /// The experiment file's name, for the title.
    pub name: String,
    pub scene: String,
    /// "seconds" or "spp".
    pub budget_kind: String,
    pub budgets: Vec<f64>,
    /// The configurations in the experiment file's order.
    pub configs: Vec<String>,
    pub repeats: u32,
    /// x, y, w, h of the zoomed crop.
    pub crop: [u32; 4],
    pub exposure: f32,
    /// The reference image's file in the folder (EXR), if written.
    pub reference: Option<String>,
    /// Each configuration's image (seed 0) per budget: (config, budget, file).
    pub images: Vec<(String, f64, String)>,
    /// When the experiment ran (UTC date) and on which CPU.
    #[serde(default)]
    pub date: String,
    #[serde(default)]
    pub cpu: String,
}

pub const MANIFEST: &str = "report.json";
pub const REPORT: &str = "report.html";

/// One row of results.json (one run), the fields the report shows.
#[derive(Deserialize, Clone, Debug)]
struct Row {
    config: String,
    budget: f64,
    budget_kind: String,
    spp: u32,
    #[serde(default)]
    seconds: Option<f64>,
    rmse: f64,
    relmse: f64,
    perceptual_share: f64,
    #[serde(default)]
    flip: Option<f64>,
}

/// The budget as it appears in file names and headings: "4" spp, "0.5" seconds.
pub fn budget_text(b: f64, kind: &str) -> String {
    if kind == "spp" {
        (b as u32).to_string()
    } else {
        b.to_string()
    }
}

/// Today's date (UTC) as YYYY-MM-DD, from the system clock.
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    // days since 1970-01-01 to the civil date (Howard Hinnant's algorithm)
    let z = (secs / 86400) as i64 + 719468;
    let era = z.div_euclid(146097);
    let doe = z - era * 146097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// The CPU's model name (Linux's /proc/cpuinfo), or "" elsewhere.
pub fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_default()
}

fn read_rows(dir: &Path) -> Result<Vec<Row>, String> {
    let p = dir.join("results.json");
    if !p.exists() {
        return Err(format!(
            "{}: no results.json: not a folder `kalos experiment` wrote",
            dir.display()
        ));
    }
    let text = crate::input::read_text(&p)?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))
}

/// The manifest of a folder written before report.json existed: configurations and
/// budgets in the order results.json has them, images by the experiment's file names.
fn infer_manifest(dir: &Path, rows: &[Row]) -> Manifest {
    let mut configs: Vec<String> = Vec::new();
    let mut budgets: Vec<f64> = Vec::new();
    for r in rows {
        if !configs.contains(&r.config) {
            configs.push(r.config.clone());
        }
        if !budgets.contains(&r.budget) {
            budgets.push(r.budget);
        }
    }
    let kind = rows
        .first()
        .map(|r| r.budget_kind.clone())
        .unwrap_or_else(|| "spp".into());
    let mut images = Vec::new();
    for c in &configs {
        for &b in &budgets {
            let f = format!("{}-{}.exr", safe_name(c), budget_text(b, &kind));
            if dir.join(&f).exists() {
                images.push((c.clone(), b, f));
            }
        }
    }
    let reference = dir
        .join("reference.exr")
        .exists()
        .then(|| "reference.exr".to_string());
    let size = images
        .first()
        .and_then(|i| read_image(&dir.join(&i.2)).ok())
        .map(|i| (i.width, i.height))
        .unwrap_or((96, 96));
    let s = size.0.min(size.1).min(96);
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    Manifest {
        name,
        scene: String::new(),
        budget_kind: kind,
        budgets,
        configs,
        repeats: 0,
        crop: [(size.0 - s) / 2, (size.1 - s) / 2, s, s],
        exposure: 0.0,
        reference,
        images,
        date: String::new(),
        cpu: String::new(),
    }
}

/// A configuration's name as a file name: characters other than letters, digits, - and _
/// become _ (the experiment refuses names that collide so).
pub fn safe_name(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn std_dev(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// The runs of one configuration at one budget.
fn runs<'a>(rows: &'a [Row], config: &str, budget: f64) -> Vec<&'a Row> {
    rows.iter()
        .filter(|r| r.config == config && r.budget == budget)
        .collect()
}

type Metric = fn(&Row) -> Option<f64>;

const METRICS: [(&str, &str, Metric); 4] = [
    ("RMSE", "RMSE", |r| Some(r.rmse)),
    ("relMSE", "relMSE", |r| Some(r.relmse)),
    ("Perceptual error", "share of pixels with > 5% error", |r| {
        Some(r.perceptual_share)
    }),
    ("FLIP", "mean FLIP", |r| r.flip),
];

/// The panels against `x`: each metric's mean over seeds, bars from the least to the
/// largest over seeds. FLIP only when the results have it.
fn panels(rows: &[Row], m: &Manifest, x: fn(&Row) -> f64, x_label: &str) -> Vec<Panel> {
    METRICS
        .iter()
        .filter(|(_, _, f)| rows.iter().all(|r| f(r).is_some()))
        .map(|&(title, y_label, f)| Panel {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: m
                .configs
                .iter()
                .map(|c| {
                    let (mut points, mut spread) = (Vec::new(), Vec::new());
                    for &b in &m.budgets {
                        let rs = runs(rows, c, b);
                        if rs.is_empty() {
                            continue;
                        }
                        let ys: Vec<f64> = rs.iter().filter_map(|r| f(r)).collect();
                        let xs: Vec<f64> = rs.iter().map(|r| x(r)).collect();
                        points.push((mean(&xs), mean(&ys)));
                        let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
                        let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        spread.push((lo, hi));
                    }
                    Series {
                        name: c.clone(),
                        points,
                        spread,
                    }
                })
                .collect(),
        })
        .collect()
}

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!(
        "data:{mime};base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

fn png_uri(w: u32, h: u32, rgb: &[u8]) -> Result<String, String> {
    Ok(data_uri("image/png", &png_bytes(w, h, rgb)?))
}

fn image_uri(img: &RgbImage, exposure: f32) -> Result<String, String> {
    png_uri(img.width, img.height, &srgb8(img, exposure))
}

/// Text for HTML: &, <, >, " escaped.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;color:#222;max-width:1400px}\
h1{font-size:1.5em}h2{margin-top:1.6em;border-bottom:1px solid #ccc}\
img.plot{max-width:100%;border:1px solid #ddd}\
table{border-collapse:collapse;font-size:0.9em}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}\
th{background:#f4f4f4}td.name{text-align:left}\
.grid{display:grid;grid-template-columns:repeat(4,auto);gap:8px 14px;justify-content:start;align-items:start}\
figure{margin:0}figcaption{font-size:0.85em;color:#444}\
img.px{image-rendering:pixelated;display:block;max-width:100%}img.flip{cursor:crosshair}\
.bar{height:12px;width:256px;display:inline-block;vertical-align:middle;border:1px solid #999}";

const SCRIPT: &str = "document.querySelectorAll('img.flip').forEach(function(im){\
var own=im.src;var ref=document.getElementById(im.dataset.ref);\
im.addEventListener('mouseenter',function(){im.src=ref.src;});\
im.addEventListener('mouseleave',function(){im.src=own;});});";

/// The colour bar of the maps: magma from 0 to 1 as a CSS gradient.
fn colour_bar() -> String {
    let stops: Vec<String> = (0..=8)
        .map(|i| {
            let c = magma(i as f32 / 8.0);
            format!("rgb({},{},{})", c[0], c[1], c[2])
        })
        .collect();
    format!(
        "<span class=\"bar\" style=\"background:linear-gradient(to right,{})\"></span>",
        stops.join(",")
    )
}

/// Rebuild the plots and report.html of a results folder; returns the report's path.
pub fn rebuild(dir: &Path) -> Result<PathBuf, String> {
    let rows = read_rows(dir)?;
    let mp = dir.join(MANIFEST);
    let m: Manifest = if mp.exists() {
        let text = crate::input::read_text(&mp)?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", mp.display()))?
    } else {
        infer_manifest(dir, &rows)
    };
    if rows.is_empty() || m.configs.is_empty() {
        return Err(format!("{}: results.json has no runs", dir.display()));
    }
    let by_time = panels(&rows, &m, |r| r.seconds.unwrap_or(0.0), "render time (s)");
    let by_spp = panels(&rows, &m, |r| r.spp as f64, "samples per pixel");
    plot_panels(&dir.join("error-vs-time"), &by_time)?;
    plot_panels(&dir.join("error-vs-spp"), &by_spp)?;
    let html = page(dir, &m, &rows)?;
    let out = dir.join(REPORT);
    std::fs::write(&out, html).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(out)
}

fn page(dir: &Path, m: &Manifest, rows: &[Row]) -> Result<String, String> {
    let mut h = String::new();
    let title = format!("kalos experiment: {}", m.name);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <link rel=\"icon\" href=\"data:,\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        esc(&title),
        esc(&title)
    );
    let budgets: Vec<String> = m
        .budgets
        .iter()
        .map(|&b| budget_text(b, &m.budget_kind))
        .collect();
    let _ = writeln!(
        h,
        "<p>Scene <b>{}</b>; budgets ({}) {}; {} configurations; {} seed{} per point{}{}.</p>",
        esc(&m.scene),
        esc(&m.budget_kind),
        esc(&budgets.join(", ")),
        m.configs.len(),
        m.repeats,
        if m.repeats == 1 { "" } else { "s" },
        if m.date.is_empty() {
            String::new()
        } else {
            format!("; run {}", esc(&m.date))
        },
        if m.cpu.is_empty() {
            String::new()
        } else {
            format!(" on {}", esc(&m.cpu))
        },
    );
    h += "<h2>Error against time and samples</h2>\n<p>Each point is the mean over seeds; its bar spans the least to the largest value over seeds.</p>\n";
    for stem in ["error-vs-time", "error-vs-spp"] {
        let p = dir.join(format!("{stem}.svg"));
        let svg = std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))?;
        let _ = writeln!(
            h,
            "<figure><img class=\"plot\" alt=\"{stem}\" src=\"{}\"></figure>",
            data_uri("image/svg+xml", &svg)
        );
    }
    table(&mut h, m, rows);
    images(&mut h, dir, m)?;
    let _ = write!(h, "<script>{SCRIPT}</script>\n</body></html>\n");
    Ok(h)
}

fn table(h: &mut String, m: &Manifest, rows: &[Row]) {
    let has_flip = rows.iter().all(|r| r.flip.is_some());
    h.push_str("<h2>Numbers</h2>\n<p>Mean &plusmn; standard deviation over seeds.</p>\n<table><tr><th>configuration</th><th>budget</th><th>seconds</th><th>spp</th><th>RMSE</th><th>relMSE</th><th>perceptual error</th>");
    if has_flip {
        h.push_str("<th>FLIP</th>");
    }
    h.push_str("</tr>\n");
    for &b in &m.budgets {
        for c in &m.configs {
            let rs = runs(rows, c, b);
            if rs.is_empty() {
                continue;
            }
            let cell = |f: &dyn Fn(&Row) -> f64, prec: usize| {
                let v: Vec<f64> = rs.iter().map(|r| f(r)).collect();
                if v.len() > 1 {
                    format!("{:.prec$e} &plusmn; {:.1e}", mean(&v), std_dev(&v))
                } else {
                    format!("{:.prec$e}", mean(&v))
                }
            };
            let secs: Vec<f64> = rs.iter().map(|r| r.seconds.unwrap_or(0.0)).collect();
            let spp: Vec<f64> = rs.iter().map(|r| r.spp as f64).collect();
            let _ = write!(
                h,
                "<tr><td class=\"name\">{}</td><td>{}</td><td>{:.2}</td><td>{:.0}</td><td>{}</td><td>{}</td><td>{:.2}%</td>",
                esc(c),
                budget_text(b, &m.budget_kind),
                mean(&secs),
                mean(&spp),
                cell(&|r| r.rmse, 3),
                cell(&|r| r.relmse, 3),
                100.0 * mean(&rs.iter().map(|r| r.perceptual_share).collect::<Vec<_>>()),
            );
            if has_flip {
                let _ = write!(h, "<td>{}</td>", cell(&|r| r.flip.unwrap_or(0.0), 3));
            }
            h.push_str("</tr>\n");
        }
    }
    h.push_str("</table>\n");
}

/// Display zoom of a crop or a small image: about 256 pixels wide, at most `max`.
fn zoom_to_256(w: u32, max: u32) -> u32 {
    (256 / w.max(1)).clamp(1, max)
}

fn images(h: &mut String, dir: &Path, m: &Manifest) -> Result<(), String> {
    h.push_str("<h2>Images</h2>\n");
    let reference = match &m.reference {
        Some(f) => Some(read_image(&dir.join(f))?),
        None => None,
    };
    let Some(reference) = reference else {
        h.push_str("<p>No reference image in this folder (report.json names none): the images are shown without comparison.</p>\n");
        for (c, b, f) in &m.images {
            let img = read_image(&dir.join(f))?;
            let _ = writeln!(
                h,
                "<figure><img class=\"px\" alt=\"{} {}\" src=\"{}\"><figcaption>{} at {} {}</figcaption></figure>",
                esc(c),
                esc(f),
                image_uri(&img, m.exposure)?,
                esc(c),
                budget_text(*b, &m.budget_kind),
                esc(&m.budget_kind)
            );
        }
        return Ok(());
    };
    let c = m.crop;
    let z = zoom_to_256(c[2], 16);
    // small renders are shown larger, pixels kept sharp
    let fw = reference.width * zoom_to_256(reference.width, 4);
    let ref_crop = crop(&reference, c);
    let _ = writeln!(
        h,
        "<p>Hover over an image or crop to see the reference in its place. The crop is x {}, y {}, {}x{} pixels, shown {z}x. \
         Error maps: dark is no error; relative colour error from 0 to 100% and more, FLIP from 0 to 1: {}</p>",
        c[0], c[1], c[2], c[3], colour_bar()
    );
    let _ = writeln!(
        h,
        "<div class=\"grid\"><figure><img id=\"ref-full\" class=\"px\" alt=\"reference\" width=\"{fw}\" src=\"{}\"><figcaption>reference</figcaption></figure>\
         <figure><img id=\"ref-crop\" class=\"px\" alt=\"reference crop\" width=\"{}\" src=\"{}\"><figcaption>reference, crop</figcaption></figure></div>",
        image_uri(&reference, m.exposure)?,
        c[2] * z,
        image_uri(&ref_crop, m.exposure)?
    );
    for &b in &m.budgets {
        let bt = budget_text(b, &m.budget_kind);
        let _ = writeln!(
            h,
            "<h3 id=\"budget-{}\">{} {}</h3>\n<div class=\"grid\">",
            esc(&bt),
            esc(&bt),
            esc(&m.budget_kind)
        );
        for (cfg, _, f) in m.images.iter().filter(|i| i.1 == b) {
            let img = read_image(&dir.join(f))?;
            if (img.width, img.height) != (reference.width, reference.height) {
                return Err(format!(
                    "{}: {}x{}, but the reference is {}x{}",
                    dir.join(f).display(),
                    img.width,
                    img.height,
                    reference.width,
                    reference.height
                ));
            }
            let rel = crate::metrics::error_map(
                &img,
                &reference,
                crate::metrics::MapKind::Relative,
                Range::Hdr,
            )?;
            let fl = flip::flip(&img, &reference, Range::Hdr)?;
            let fl_rgb: Vec<u8> = fl.map.iter().flat_map(|&v| magma(v)).collect();
            let (w, hh) = (img.width, img.height);
            let n = esc(cfg);
            let _ = writeln!(
                h,
                "<figure><img class=\"px flip\" data-ref=\"ref-full\" alt=\"{n}\" width=\"{fw}\" src=\"{}\"><figcaption>{n}</figcaption></figure>\
                 <figure><img class=\"px flip\" data-ref=\"ref-crop\" alt=\"{n} crop\" width=\"{}\" src=\"{}\"><figcaption>{n}, crop</figcaption></figure>\
                 <figure><img class=\"px\" alt=\"{n} relative error\" width=\"{fw}\" src=\"{}\"><figcaption>relative error</figcaption></figure>\
                 <figure><img class=\"px\" alt=\"{n} FLIP\" width=\"{fw}\" src=\"{}\"><figcaption>FLIP {:.4}</figcaption></figure>",
                image_uri(&img, m.exposure)?,
                c[2] * z,
                image_uri(&crop(&img, c), m.exposure)?,
                png_uri(w, hh, &rel)?,
                png_uri(w, hh, &fl_rgb)?,
                fl.mean
            );
        }
        h.push_str("</div>\n");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_budgets_read_as_people_write_them() {
        let d = today();
        assert_eq!(d.len(), 10);
        assert!(
            d.starts_with("20") && &d[4..5] == "-" && &d[7..8] == "-",
            "{d}"
        );
        assert_eq!(budget_text(64.0, "spp"), "64");
        assert_eq!(budget_text(0.5, "seconds"), "0.5");
        assert_eq!(esc("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
    }
}
