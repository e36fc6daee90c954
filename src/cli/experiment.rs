//! `kalos experiment FILE.toml`: named configurations (any render options) run at a list of
//! equal budgets (seconds or spp) against a reference; writes results.csv, results.json,
//! error-versus-time and -spp plots (log-log, PNG and SVG), a side-by-side crop and
//! report.html (`report::html`), into a new folder: results written before are never
//! overwritten.
//!
//! ```toml
//! scene = "cornell"                 # built-in, or an .obj/.toml path relative to this file
//! options = "--res 128x128"         # options shared by every run (and the reference)
//! repeats = 1                       # seeds per (config, budget); metrics are averaged
//! crop = [40, 60, 48, 48]           # x, y, w, h of the side-by-side crop
//! zoom = 4
//!
//! [reference]
//! image = "ref.exr"                 # an image, relative to this file, or
//! spp = 4096                        # rendered once with these options and cached (seed
//!                                   # 2718281828 unless given, apart from the runs'), or
//! constant = 1.0                    # a known answer (the furnace rooms)
//! options = "--rr classic"
//!
//! [budgets]
//! seconds = [1, 2, 4, 8]            # or: spp = [16, 64, 256]
//!
//! [[config]]
//! name = "path"
//! options = ""
//!
//! [[config]]
//! name = "dtf"
//! options = "--method dtf --dtf-n 16"
//! ```

use super::render::RenderArgs;
use crate::image_io::{read_image, write_image, RgbImage};
use crate::metrics::Metrics;
use crate::pipeline::Silent;
use crate::render::render_scene;
use crate::report::html::{budget_text, safe_name, Manifest};
use crate::report::{crop, side_by_side};
use clap::Parser;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Seed of a reference rendered by the experiment: far from the runs' seeds 0..repeats.
const REFERENCE_SEED: &str = "2718281828";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExperimentFile {
    scene: String,
    #[serde(default)]
    options: String,
    #[serde(default)]
    repeats: Option<u32>,
    crop: Option<[u32; 4]>,
    zoom: Option<u32>,
    exposure: Option<f32>,
    reference: ReferenceSpec,
    budgets: BudgetSpec,
    #[serde(rename = "config")]
    configs: Vec<ConfigSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReferenceSpec {
    image: Option<String>,
    spp: Option<u32>,
    /// A known answer: every pixel and channel has this value (the furnace rooms: 1).
    constant: Option<f32>,
    #[serde(default)]
    options: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BudgetSpec {
    seconds: Option<Vec<f64>>,
    spp: Option<Vec<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigSpec {
    name: String,
    #[serde(default)]
    options: String,
}

/// One run of one configuration at one budget: the metrics (with the render's seconds and
/// efficiency) plus what identifies the run.
#[derive(Serialize, Clone, Debug)]
pub struct ResultRow {
    pub config: String,
    pub budget: f64,
    pub budget_kind: &'static str,
    pub seed: u64,
    pub spp: u32,
    pub paths: u64,
    #[serde(flatten)]
    pub metrics: Metrics,
}

impl ResultRow {
    fn seconds(&self) -> f64 {
        self.metrics.seconds.unwrap_or(0.0)
    }
}

#[derive(Parser)]
#[command(no_binary_name = true)]
struct OneRender {
    #[command(flatten)]
    args: RenderArgs,
}

/// Parse "scene + options" as `kalos render` would.
fn parse_render(scene: &str, options: &[&str], what: &str) -> Result<RenderArgs, String> {
    let mut argv: Vec<String> = vec![scene.to_string()];
    argv.extend(options.iter().map(|s| s.to_string()));
    OneRender::try_parse_from(argv)
        .map(|o| o.args)
        .map_err(|e| {
            let first = e
                .to_string()
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
                .to_string();
            format!("{what}: {first}")
        })
}

fn words(s: &str) -> Vec<&str> {
    s.split_whitespace().collect()
}

/// Options the experiment sets on every run itself: (option, who sets it). Given again in
/// `options`, clap would only say "cannot be used multiple times".
const OWN_OPTIONS: &[(&str, &str)] = &[
    ("--spp", "[budgets] (samples per pixel of every run)"),
    ("--time", "[budgets] (seconds of every run)"),
    (
        "--seed",
        "the experiment (seeds 0 .. repeats - 1, one per repeat)",
    ),
    ("--quiet", "the experiment"),
    ("-q", "the experiment"),
    (
        "--output",
        "the experiment (every run's images go to its output folder, --out)",
    ),
    (
        "-o",
        "the experiment (every run's images go to its output folder, --out)",
    ),
    (
        "--stats",
        "the experiment (its CSV and JSON hold every run's statistics)",
    ),
    (
        "--dask",
        "the experiment (it renders every run in this process)",
    ),
];

/// Refuse an option of `OWN_OPTIONS` in `options` (`what` names where they come from);
/// `allowed` are exceptions (the reference may choose its seed).
fn refuse_own_options(options: &str, what: &str, allowed: &[&str]) -> Result<(), String> {
    for w in words(options) {
        for &(opt, owner) in OWN_OPTIONS {
            let given = w == opt
                || (opt.starts_with("--") && w.starts_with(&format!("{opt}=")))
                || (opt.len() == 2 && !w.starts_with("--") && w.starts_with(opt));
            if given && !allowed.contains(&opt) {
                return Err(format!(
                    "{what}: options: {opt} is set by {owner}: remove it from the options"
                ));
            }
        }
    }
    Ok(())
}

/// What the validation of an experiment file settles before any work starts.
struct Plan {
    budgets: Vec<f64>,
    kind: &'static str,
    repeats: u32,
    /// (width, height) of every run and of the reference.
    res: (u32, u32),
    crop: [u32; 4],
    zoom: u32,
}

/// Check an experiment file for contradictions before anything is rendered or written:
/// every error names the file and the key. `scene_res` is the scene's default resolution.
fn validate(
    ex: &ExperimentFile,
    fname: &str,
    scene_spec: &str,
    scene_res: Option<(u32, u32)>,
) -> Result<Plan, String> {
    if ex.configs.is_empty() {
        return Err(format!("{fname}: no [[config]]"));
    }
    if let Some(e) = ex.exposure.filter(|e| !e.is_finite()) {
        return Err(format!(
            "{fname}: exposure = {e}: must be a finite number of stops"
        ));
    }
    // names: each config's images are written under its name
    for (i, c) in ex.configs.iter().enumerate() {
        if c.name.trim().is_empty() {
            return Err(format!("{fname}: [[config]] {}: name is empty", i + 1));
        }
        for d in &ex.configs[..i] {
            if d.name == c.name {
                return Err(format!(
                    "{fname}: [[config]] name {:?} is used twice: each configuration needs its own name (its images are written under it)",
                    c.name
                ));
            }
            if safe_name(&d.name) == safe_name(&c.name) {
                return Err(format!(
                    "{fname}: [[config]] names {:?} and {:?} both give the file name {:?}: their images would overwrite each other",
                    d.name,
                    c.name,
                    safe_name(&c.name)
                ));
            }
        }
    }
    let (budgets, kind): (Vec<f64>, &'static str) = match (&ex.budgets.seconds, &ex.budgets.spp) {
        (Some(s), None) if !s.is_empty() => (s.clone(), "seconds"),
        (None, Some(s)) if !s.is_empty() => (s.iter().map(|&v| v as f64).collect(), "spp"),
        _ => {
            return Err(format!(
                "{fname}: [budgets] needs exactly one non-empty list: seconds or spp"
            ))
        }
    };
    if budgets.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
        return Err(format!("{fname}: [budgets]: every budget must be positive"));
    }
    let repeats = match ex.repeats {
        Some(0) => {
            return Err(format!(
                "{fname}: repeats = 0: must be at least 1 (the number of seeds per configuration and budget)"
            ))
        }
        r => r.unwrap_or(1),
    };
    // the reference: exactly one source
    let r = &ex.reference;
    let given: Vec<&str> = [
        ("image", r.image.is_some()),
        ("spp", r.spp.is_some()),
        ("constant", r.constant.is_some()),
    ]
    .iter()
    .filter(|k| k.1)
    .map(|k| k.0)
    .collect();
    if given.len() != 1 {
        return Err(format!(
            "{fname}: [reference] needs exactly one of image, spp or constant; it has {}",
            if given.is_empty() {
                "none".to_string()
            } else {
                given.join(" and ")
            }
        ));
    }
    if let Some(v) = r.constant {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "{fname}: [reference] constant = {v}: must be a finite non-negative radiance"
            ));
        }
    }
    if r.spp == Some(0) {
        return Err(format!("{fname}: [reference] spp = 0: must be at least 1"));
    }
    if !r.options.trim().is_empty() && r.spp.is_none() {
        return Err(format!(
            "{fname}: [reference] options apply only to a rendered reference (spp), not to {}",
            given[0]
        ));
    }
    // options: those the experiment sets itself are refused with the reason; then each
    // run's full command line is parsed now, not after hours of rendering
    refuse_own_options(&ex.options, fname, &[])?;
    refuse_own_options(&r.options, &format!("{fname}: [reference]"), &["--seed"])?;
    let common = words(&ex.options);
    let base = parse_render(scene_spec, &common, &format!("{fname}: options"))?;
    let res = base
        .job
        .res
        .or(scene_res)
        .unwrap_or(crate::render::DEFAULT_RES);
    let budget_opt = if kind == "seconds" { "--time" } else { "--spp" };
    for c in &ex.configs {
        let what = format!("{fname}: config {}", c.name);
        refuse_own_options(&c.options, &what, &[])?;
        for b in &budgets {
            let bs = if kind == "seconds" {
                b.to_string()
            } else {
                (*b as u32).to_string()
            };
            let mut o = common.clone();
            o.extend(words(&c.options));
            o.extend([budget_opt, bs.as_str(), "--seed", "0", "-q"]);
            let a = parse_render(scene_spec, &o, &what)?;
            let run_res = a
                .job
                .res
                .or(scene_res)
                .unwrap_or(crate::render::DEFAULT_RES);
            if run_res != res {
                return Err(format!(
                    "{what}: renders {}x{}, but the reference is {}x{}: give --res in the common options only",
                    run_res.0, run_res.1, res.0, res.1
                ));
            }
        }
    }
    if let Some(spp) = r.spp {
        let mut o = common.clone();
        o.extend(words(&r.options));
        let spp_s = spp.to_string();
        o.extend(["--spp", spp_s.as_str(), "-q"]);
        let a = parse_render(scene_spec, &o, &format!("{fname}: [reference]"))?;
        if a.job
            .res
            .or(scene_res)
            .unwrap_or(crate::render::DEFAULT_RES)
            != res
        {
            return Err(format!(
                "{fname}: [reference] options: the reference must be rendered at the runs' {}x{}",
                res.0, res.1
            ));
        }
    }
    // the side-by-side crop: inside the image, not empty, and a bounded picture
    let (w, h) = res;
    let crop = match ex.crop {
        Some(c) => {
            if c[2] == 0 || c[3] == 0 {
                return Err(format!(
                    "{fname}: crop = {c:?}: width and height must be at least 1"
                ));
            }
            if c[0] as u64 + c[2] as u64 > w as u64 || c[1] as u64 + c[3] as u64 > h as u64 {
                return Err(format!(
                    "{fname}: crop = {c:?} (x, y, w, h) reaches outside the {w}x{h} image"
                ));
            }
            c
        }
        None => {
            let s = w.min(h).min(96);
            [(w - s) / 2, (h - s) / 2, s, s]
        }
    };
    let tiles = ex.configs.len() + 1;
    let fits = |z: u32| {
        let (a, b) = crate::report::side_by_side_size(tiles, crop[2], crop[3], z);
        a.max(b) <= crate::report::MAX_SIDE_BY_SIDE
    };
    let zoom = match ex.zoom {
        Some(0) => return Err(format!("{fname}: zoom = 0: must be at least 1")),
        Some(z) if !fits(z) => {
            let (a, b) = crate::report::side_by_side_size(tiles, crop[2], crop[3], z);
            return Err(format!(
                "{fname}: zoom = {z}: the side-by-side image of {tiles} crops of {}x{} would be {a}x{b} pixels, more than {} on a side: lower zoom or the crop",
                crop[2],
                crop[3],
                crate::report::MAX_SIDE_BY_SIDE
            ));
        }
        Some(z) => z,
        // the default zoom shrinks to fit many configurations
        None => match (1..=3).rev().find(|&z| fits(z)) {
            Some(z) => z,
            None => {
                return Err(format!(
                    "{fname}: the side-by-side image of {tiles} crops of {}x{} would be more than {} pixels wide: give a smaller crop",
                    crop[2],
                    crop[3],
                    crate::report::MAX_SIDE_BY_SIDE
                ))
            }
        },
    };
    Ok(Plan {
        budgets,
        kind,
        repeats,
        res,
        crop,
        zoom,
    })
}

pub fn run(file: &Path, out: Option<PathBuf>, quiet: bool) -> Result<(), String> {
    let fname = file.display().to_string();
    let text = crate::input::read_text(file)?;
    let ex: ExperimentFile = toml::from_str(&text)
        .map_err(|e| crate::scene::toml_scene::toml_error(&fname, &text, e))?;
    let dir = file.parent().unwrap_or(Path::new("."));
    let scene_spec = if crate::scene::builtin::NAMES.contains(&ex.scene.as_str()) {
        ex.scene.clone()
    } else {
        dir.join(&ex.scene).display().to_string()
    };
    let scene = crate::scene::load(&scene_spec)?;
    // Validate everything before spending time on any run or creating the output folder.
    let plan = validate(&ex, &fname, &scene_spec, scene.defaults.res)?;
    let (budgets, kind) = (plan.budgets.clone(), plan.kind);
    let common = words(&ex.options);
    let given_reference = match (&ex.reference.image, ex.reference.constant) {
        (Some(p), _) => {
            let path = dir.join(p);
            let img = read_image(&path)?;
            let name = path.display().to_string();
            crate::metrics::check_comparable(&img, &name)
                .map_err(|e| format!("{fname}: [reference] image {e}"))?;
            if (img.width, img.height) != plan.res {
                return Err(format!(
                    "{fname}: [reference] image {name} is {}x{}, but the runs render {}x{}",
                    img.width, img.height, plan.res.0, plan.res.1
                ));
            }
            Some(img)
        }
        (None, Some(v)) => {
            let (w, h) = plan.res;
            Some(RgbImage::new(w, h, vec![[v; 3]; (w * h) as usize]))
        }
        (None, None) => None,
    };
    let stem = file
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("experiment");
    // the default folder; a reference rendered into it before is reused from there
    let usual = dir.join(format!("{stem}-results"));
    let out = out.unwrap_or_else(|| new_folder(&usual, &crate::report::html::today()));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;

    // The reference: an image or a constant (read above), or a cached render.
    let reference = match (given_reference, ex.reference.spp) {
        (Some(img), _) => img,
        (None, Some(spp)) => {
            let mut o = common.clone();
            o.extend(words(&ex.reference.options));
            // The runs use seeds 0, 1, ...: a reference from the same seed would share its
            // first samples with them (plain path tracing's first spp samples would be the
            // reference's own) and flatter their error.
            if !o.iter().any(|w| *w == "--seed" || w.starts_with("--seed=")) {
                o.extend(["--seed", REFERENCE_SEED]);
            }
            let spp_s = spp.to_string();
            o.extend(["--spp", spp_s.as_str(), "-q"]);
            let key = format!("{scene_spec} {}", o.join(" "));
            let cached = out.join("reference.exr");
            let key_file = out.join("reference.key");
            let is_cached = |d: &Path| {
                d.join("reference.exr").exists()
                    && crate::input::read_text(&d.join("reference.key"))
                        .ok()
                        .as_deref()
                        == Some(key.as_str())
            };
            let img = if is_cached(&out) {
                read_image(&cached)?
            } else if is_cached(&usual) {
                // rendered by an earlier run into the usual folder: copied, not redone
                let img = read_image(&usual.join("reference.exr"))?;
                write_image(&cached, &img, 0.0, &[])?;
                std::fs::write(&key_file, &key)
                    .map_err(|e| format!("{}: {e}", key_file.display()))?;
                img
            } else {
                if !quiet {
                    eprintln!("kalos: rendering the reference ({key})");
                }
                let args = parse_render(&scene_spec, &o, &format!("{fname}: [reference]"))?;
                let r = render_scene(&scene, &args.job(), &Silent)?;
                write_image(&cached, &r.image, 0.0, &[])?;
                std::fs::write(&key_file, &key)
                    .map_err(|e| format!("{}: {e}", key_file.display()))?;
                r.image
            };
            crate::metrics::check_comparable(&img, &cached.display().to_string())
                .map_err(|e| format!("{fname}: [reference]: {e}"))?;
            img
        }
        (None, None) => {
            return Err(format!(
                "{fname}: [reference] needs exactly one of image, spp or constant"
            ))
        }
    };

    if ex.reference.spp.is_none() {
        // the report shows the reference beside the runs
        write_image(&out.join("reference.exr"), &reference, 0.0, &[])?;
    }
    let repeats = plan.repeats;
    let mut images = Vec::new();
    let mut rows: Vec<ResultRow> = Vec::new();
    // Budgets outer, configurations inner: runs of one budget see the same machine load.
    let mut last: Vec<Option<RgbImage>> = vec![None; ex.configs.len()];
    for &b in &budgets {
        for (ci, c) in ex.configs.iter().enumerate() {
            for rep in 0..repeats {
                let mut o = common.clone();
                o.extend(words(&c.options));
                let bs = budget_text(b, kind);
                let seed = rep.to_string();
                o.extend([
                    if kind == "seconds" { "--time" } else { "--spp" },
                    bs.as_str(),
                    "--seed",
                    seed.as_str(),
                    "-q",
                ]);
                let args = parse_render(&scene_spec, &o, &format!("{fname}: config {}", c.name))?;
                let r = render_scene(&scene, &args.job(), &Silent)?;
                let metrics = Metrics::compute(&r.image, &reference)
                    .map_err(|e| format!("{fname}: config {}: against the reference: {e}", c.name))?
                    // the estimator's preprocess (a radiosity solution, L~'s photon walk)
                    // is part of the run's cost, as --time counts it
                    .with_seconds(r.stats.seconds + r.stats.prepare_seconds);
                let row = ResultRow {
                    config: c.name.clone(),
                    budget: b,
                    budget_kind: kind,
                    seed: rep as u64,
                    spp: r.stats.spp,
                    paths: r.stats.paths,
                    metrics,
                };
                let m = &row.metrics;
                if !quiet {
                    eprintln!(
                        "kalos: {:<16} {kind} {b:<6} seed {rep}: {:.2} s, {} spp, rmse {:.5}, relmse {:.5}, perceptual {:.1}%, flip {:.4}",
                        c.name, row.seconds(), row.spp, m.rmse, m.relmse, m.perceptual_share * 100.0, m.flip
                    );
                }
                rows.push(row);
                if rep == 0 {
                    let img_name = format!("{}-{}.exr", safe_name(&c.name), bs);
                    write_image(&out.join(&img_name), &r.image, 0.0, &[])?;
                    images.push((c.name.clone(), b, img_name));
                    last[ci] = Some(r.image);
                }
            }
        }
    }
    let last_images: Vec<(String, RgbImage)> = ex
        .configs
        .iter()
        .zip(last)
        .filter_map(|(c, img)| img.map(|i| (c.name.clone(), i)))
        .collect();

    // Tables.
    let mut csv = String::from(
        "config,budget,budget_kind,seed,seconds,spp,paths,mse,rmse,relmse,perceptual_count,perceptual_share,luminance_ratio,efficiency,flip\n",
    );
    for r in &rows {
        csv += &format!(
            "{},{},{},{},{:.4},{},{},{:.6e},{:.6e},{:.6e},{},{:.6},{:.6},{:.6e},{:.6}\n",
            csv_field(&r.config),
            r.budget,
            r.budget_kind,
            r.seed,
            r.seconds(),
            r.spp,
            r.paths,
            r.metrics.mse,
            r.metrics.rmse,
            r.metrics.relmse,
            r.metrics.perceptual_count,
            r.metrics.perceptual_share,
            r.metrics.luminance_ratio,
            r.metrics.efficiency.unwrap_or(0.0),
            r.metrics.flip
        );
    }
    let write = |name: &str, data: String| -> Result<(), String> {
        let p = out.join(name);
        std::fs::write(&p, data).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("results.csv", csv)?;
    write(
        "results.json",
        serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())? + "\n",
    )?;

    let manifest = Manifest {
        name: file
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default(),
        scene: ex.scene.clone(),
        budget_kind: kind.to_string(),
        budgets: budgets.clone(),
        configs: ex.configs.iter().map(|c| c.name.clone()).collect(),
        repeats,
        crop: plan.crop,
        exposure: ex.exposure.unwrap_or(0.0),
        reference: Some("reference.exr".into()),
        images,
        date: crate::report::html::today(),
        cpu: crate::report::html::cpu_name(),
    };
    write(
        crate::report::html::MANIFEST,
        serde_json::to_string_pretty(&manifest).map_err(|e| e.to_string())? + "\n",
    )?;
    // the plots and report.html, from the files just written (as `kalos report` does)
    let report = crate::report::html::rebuild(&out)?;

    // Side by side: the same crop of every configuration (largest budget) and the reference.
    let c = plan.crop;
    let mut tiles: Vec<(String, RgbImage)> = last_images
        .iter()
        .map(|(n, i)| (n.clone(), crop(i, c)))
        .collect();
    tiles.push(("reference".into(), crop(&reference, c)));
    side_by_side(
        &out.join("side-by-side.png"),
        &tiles,
        plan.zoom,
        ex.exposure.unwrap_or(0.0),
    )?;
    if !quiet {
        eprintln!(
            "kalos: wrote {}/results.csv, results.json, error-vs-time and error-vs-spp .png/.svg, side-by-side.png and {}",
            out.display(),
            report.display()
        );
    }
    Ok(())
}

/// The default results folder: `usual` (FILE-results) when it does not exist yet, else
/// FILE-results-DATE, FILE-results-DATE-2, ...: results written before, committed ones
/// too, are never overwritten.
fn new_folder(usual: &Path, date: &str) -> PathBuf {
    if !usual.exists() {
        return usual.to_path_buf();
    }
    let base = format!("{}-{date}", usual.display());
    (1..)
        .map(|i| {
            PathBuf::from(if i == 1 {
                base.clone()
            } else {
                format!("{base}-{i}")
            })
        })
        .find(|p| !p.exists())
        .unwrap_or_else(|| usual.to_path_buf())
}

/// A CSV field: quoted as RFC 4180 has it when it holds a comma, a quote or a line break
/// (a config named `path, 1 thread`), so the table keeps its columns.
fn csv_field(v: &str) -> String {
    if v.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stricter validation must still accept every experiment the project ships.
    #[test]
    fn csv_fields_with_commas_and_quotes_are_quoted() {
        assert_eq!(csv_field("path"), "path");
        assert_eq!(csv_field("path, 1 thread"), "\"path, 1 thread\"");
        assert_eq!(csv_field("rw \"paper\""), "\"rw \"\"paper\"\"\"");
    }

    #[test]
    fn the_projects_experiment_files_pass_validation() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/results");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().and_then(|e| e.to_str()) != Some("toml") {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap();
            let ex: ExperimentFile = toml::from_str(&text).unwrap();
            let spec = if crate::scene::builtin::NAMES.contains(&ex.scene.as_str()) {
                ex.scene.clone()
            } else {
                dir.join(&ex.scene).display().to_string()
            };
            // a public scene a fetch script writes (scenes/*/public/, not committed)
            // is checked where it has been fetched
            if ex.scene.contains("/public/") && !Path::new(&spec).exists() {
                eprintln!("{}: {} not fetched, not checked", p.display(), ex.scene);
                continue;
            }
            let res = crate::scene::load_desc(&spec).unwrap().defaults.res;
            let name = p.display().to_string();
            let plan = validate(&ex, &name, &spec, res).unwrap_or_else(|e| panic!("{e}"));
            assert!(plan.zoom >= 1 && plan.repeats >= 1, "{name}");
            n += 1;
        }
        assert!(n >= 5, "{n} experiment files");
    }

    #[test]
    fn results_written_before_are_never_overwritten() {
        let d = std::env::temp_dir().join(format!("kalos-newfolder-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let usual = d.join("x-results");
        assert_eq!(new_folder(&usual, "2026-01-02"), usual);
        std::fs::create_dir(&usual).unwrap();
        let second = new_folder(&usual, "2026-01-02");
        assert_eq!(second, d.join("x-results-2026-01-02"));
        std::fs::create_dir(&second).unwrap();
        assert_eq!(
            new_folder(&usual, "2026-01-02"),
            d.join("x-results-2026-01-02-2")
        );
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn own_options_are_refused_with_who_sets_them() {
        let e = refuse_own_options("--rr off --spp=4", "x.toml: config a", &[]).unwrap_err();
        assert!(e.contains("--spp is set by [budgets]"), "{e}");
        let e = refuse_own_options("-q", "x.toml", &[]).unwrap_err();
        assert!(e.contains("-q is set by the experiment"), "{e}");
        assert!(refuse_own_options("--seed 7", "x.toml: [reference]", &["--seed"]).is_ok());
        assert!(refuse_own_options("--sppx 3 --rr classic", "x.toml", &[]).is_ok());
    }
}
