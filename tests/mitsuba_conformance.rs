//! Mitsuba 3's own render tests, run on kalos: each scene of Mitsuba's `tests/scenes`
//! (outside `participating_media/`) is loaded with `spp` and `integrator` defined as
//! Mitsuba's test_renders.py defines them, rendered with seed 0 at 2e6 / pixels samples per
//! pixel, and compared with Mitsuba 3.9.1's mean and per-sample variance
//! (tests/conformance/, made by bench/mitsuba-conformance.py): per pixel and XYZ channel,
//! z = |image - reference| sqrt(spp / max(variance, 1e-4)), accepted when its two-sided
//! p-value exceeds Sidak's alpha 1 - 0.99^(1 / pixels); a scene passes with 99.75% accepted.
//!
//! The scenes are read from `shared/conformance/mitsuba` beside the repository (or any
//! folder above it), or from `$KALOS_CONFORMANCE_DIR`. Without them the test is skipped,
//! except in CI (`CI=true`), where that is a failure.
//!
//! `KNOWN_FAILURES` lists the scenes that do not pass yet, each with its reason; the test
//! fails when one of them passes (so the list stays true) or when another scene fails.
//! `KALOS_CONFORMANCE_REPORT=docs/results/mitsuba-conformance.md cargo test --release
//! --test mitsuba_conformance` rewrites the results page; `KALOS_CONFORMANCE_IMAGES=folder`
//! keeps kalos' images there.

use kalos::image_io::read_image;
use kalos::pipeline::Silent;
use kalos::RenderJob;
use std::path::{Path, PathBuf};

/// Mitsuba's budget per image.
const SAMPLES_PER_IMAGE: u64 = 2_000_000;
/// Share of pixel-channels that must be accepted.
const ACCEPT: f64 = 0.9975;
/// Significance of the whole image (before Sidak's correction).
const SIGNIFICANCE: f64 = 0.01;
/// Mitsuba's floor on the reference variance.
const VARIANCE_FLOOR: f64 = 1e-4;

/// Scenes that do not pass yet, with the reason.
const KNOWN_FAILURES: &[(&str, &str)] = &[];

/// sRGB (linear) to CIE XYZ, as Mitsuba's `Bitmap.convert`.
fn xyz(c: [f32; 3]) -> [f64; 3] {
    let [r, g, b] = c.map(f64::from);
    [
        0.412453 * r + 0.357580 * g + 0.180423 * b,
        0.212671 * r + 0.715160 * g + 0.072169 * b,
        0.019334 * r + 0.119193 * g + 0.950227 * b,
    ]
}

/// 1 - Phi(z) for z >= 0 (complementary error function, Numerical Recipes' erfc
/// approximation: relative error below 1.2e-7).
fn upper_tail(z: f64) -> f64 {
    let x = z / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * x);
    let erfc = t
        * (-x * x - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    0.5 * erfc
}

fn conformance_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("KALOS_CONFORMANCE_DIR") {
        return Some(PathBuf::from(d));
    }
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .map(|a| a.join("shared/conformance"))
        .find(|d| d.join("mitsuba/tests/scenes").is_dir())
}

fn scenes(root: &Path) -> Vec<PathBuf> {
    fn walk(d: &Path, out: &mut Vec<PathBuf>) {
        let mut es: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        es.sort();
        for p in es {
            let name = p.file_name().unwrap().to_str().unwrap().to_string();
            if p.is_dir() {
                if name != "participating_media" && name != "fragments" {
                    walk(&p, out);
                }
            } else if name.ends_with(".xml") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(root, &mut out);
    out
}

struct Outcome {
    name: String,
    folder: String,
    /// Accepted share of pixel-channels, or the error that stopped the render.
    result: Result<f64, String>,
    spp: u32,
    seconds: f64,
}

fn run(scene: &Path) -> Outcome {
    let name = scene.file_stem().unwrap().to_str().unwrap().to_string();
    let folder = scene
        .parent()
        .and_then(|p| p.file_name())
        .and_then(|f| f.to_str())
        .unwrap_or("")
        .to_string();
    let t0 = std::time::Instant::now();
    let mut spp = 0;
    let result = (|| -> Result<f64, String> {
        let refs = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
        let reference = read_image(&refs.join(format!("{name}.exr")))
            .map_err(|e| format!("no reference ({e}): run bench/mitsuba-conformance.py"))?;
        let variance = read_image(&refs.join(format!("{name}-var.exr")))?;
        let pixels = reference.width as u64 * reference.height as u64;
        spp = (SAMPLES_PER_IMAGE / pixels) as u32;
        let integrator = name.rsplit('_').next().unwrap().to_string();
        let defines = [
            ("spp".to_string(), spp.to_string()),
            ("integrator".to_string(), integrator),
        ];
        let spec = scene.to_str().unwrap();
        let loaded = kalos::scene::load_with(spec, &defines)?;
        let mut job = RenderJob::new(spec);
        job.defines = defines.to_vec();
        job.spp = Some(spp);
        job.seed = 0;
        let r = kalos::render_scene(&loaded, &job, &Silent)?;
        let img = &r.image;
        if let Some(dir) = std::env::var_os("KALOS_CONFORMANCE_IMAGES") {
            let out = Path::new(&dir).join(format!("{name}.exr"));
            kalos::image_io::write_image(&out, img, 1.0, &[])?;
        }
        if (img.width, img.height) != (reference.width, reference.height) {
            return Err(format!(
                "kalos renders {}x{}, the reference is {}x{}",
                img.width, img.height, reference.width, reference.height
            ));
        }
        let alpha = 1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / pixels as f64);
        let mut accepted = 0u64;
        for i in 0..img.data.len() {
            let (m, r, v) = (
                xyz(img.data[i]),
                xyz(reference.data[i]),
                xyz(variance.data[i]),
            );
            for c in 0..3 {
                let z = (m[c] - r[c]).abs() * (spp as f64 / v[c].max(VARIANCE_FLOOR)).sqrt();
                if 2.0 * upper_tail(z) > alpha {
                    accepted += 1;
                }
            }
        }
        Ok(accepted as f64 / (3 * pixels) as f64)
    })();
    Outcome {
        name,
        folder,
        result,
        spp,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

fn report(outcomes: &[Outcome]) -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let passed = outcomes
        .iter()
        .filter(|o| matches!(o.result, Ok(f) if f >= ACCEPT))
        .count();
    let mut s = format!(
        "# Mitsuba 3 render tests on kalos\n\n\
         Mitsuba 3's own render-test scenes (`shared/conformance/mitsuba/tests/scenes`, outside\n\
         `participating_media/`) under Mitsuba's protocol: 2e6 samples per image, seed 0, a\n\
         per-pixel XYZ Z-test against Mitsuba 3.9.1's mean and per-sample variance\n\
         (`tests/conformance/`, made by `bench/mitsuba-conformance.py`; spp per scene in\n\
         `tests/conformance/references.tsv`), Sidak-corrected significance 0.01, a scene passes\n\
         with at least 99.75% of pixel-channels accepted.\n\n\
         **{passed} of {} pass.** Regenerate this page with\n\n\
         ```\n\
         KALOS_CONFORMANCE_REPORT=docs/results/mitsuba-conformance.md \\\n    \
         cargo test --release --test mitsuba_conformance\n\
         ```\n\n\
         Rendered on {cpu} (times include loading; the machine is shared, so they are noisy).\n\n\
         | folder | scene | spp | accepted | status | seconds |\n\
         |---|---|---:|---:|---|---:|\n",
        outcomes.len()
    );
    for o in outcomes {
        let (acc, status) = match &o.result {
            Ok(f) if *f >= ACCEPT => (format!("{:.2}%", 100.0 * f), "passes".to_string()),
            Ok(f) => (format!("{:.2}%", 100.0 * f), known_reason(&o.name)),
            Err(e) => ("-".into(), format!("error: {}", e.replace('|', "\\|"))),
        };
        s += &format!(
            "| {} | {} | {} | {acc} | {status} | {:.1} |\n",
            o.folder, o.name, o.spp, o.seconds
        );
    }
    s
}

fn known_reason(name: &str) -> String {
    KNOWN_FAILURES
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("fails (not listed)".into(), |(_, r)| format!("fails: {r}"))
}

#[test]
fn sidak_alpha_and_tail_known_answers() {
    // Phi(1.96) = 0.975, Phi(3) = 0.99865
    assert!((upper_tail(1.959964) - 0.025).abs() < 1e-6);
    assert!((upper_tail(3.0) - 0.0013499).abs() < 1e-6);
    assert!((upper_tail(0.0) - 0.5).abs() < 1e-7);
    // white (1,1,1) is D65's white point, Y = 1
    let w = xyz([1.0; 3]);
    assert!((w[1] - 1.0).abs() < 1e-5 && (w[0] - 0.950456).abs() < 1e-5);
}

#[test]
fn mitsubas_render_tests() {
    let Some(root) = conformance_dir() else {
        if std::env::var("CI").as_deref() == Ok("true") {
            panic!(
                "shared/conformance/mitsuba not found beside the repository (set KALOS_CONFORMANCE_DIR)"
            );
        }
        eprintln!("mitsuba conformance scenes not found: skipped (set KALOS_CONFORMANCE_DIR)");
        return;
    };
    let all = scenes(&root.join("mitsuba/tests/scenes"));
    assert_eq!(
        all.len(),
        29,
        "Mitsuba's render tests outside participating media"
    );
    for (n, _) in KNOWN_FAILURES {
        assert!(
            all.iter().any(|p| p.file_stem().unwrap() == *n),
            "known failure {n} is no scene"
        );
    }
    let outcomes: Vec<Outcome> = all.iter().map(|p| run(p)).collect();
    let text = report(&outcomes);
    eprintln!("{text}");
    if let Some(path) = std::env::var_os("KALOS_CONFORMANCE_REPORT") {
        std::fs::write(&path, &text).unwrap();
    }
    let mut wrong = Vec::new();
    for o in &outcomes {
        let pass = matches!(o.result, Ok(f) if f >= ACCEPT);
        let known = KNOWN_FAILURES.iter().any(|(n, _)| *n == o.name);
        match (pass, known) {
            (true, true) => wrong.push(format!("{} passes: take it off KNOWN_FAILURES", o.name)),
            (false, false) => wrong.push(format!(
                "{} fails: {}",
                o.name,
                match &o.result {
                    Ok(f) => format!("{:.2}% accepted", 100.0 * f),
                    Err(e) => e.clone(),
                }
            )),
            _ => {}
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
