//! `kalos experiment`'s report.html: built for a tiny experiment, its structure checked
//! (every image embedded, no address outside the file, the table and the sections), rebuilt
//! the same by `kalos report`, results written before never overwritten; and the page
//! opened in headless Chromium (tests/browser/check_report.js: no console error, every
//! image loaded, hovering shows the reference) where Chromium, Node and playwright-core
//! are installed (`.ci/run` installs them; KALOS_REQUIRE_BROWSER=1 makes their absence a
//! failure instead of a skip).

use std::path::{Path, PathBuf};
use std::process::Command;

const EXPERIMENT: &str = r#"
scene = "cornell"
options = "--res 32x24"
repeats = 2
crop = [8, 4, 12, 12]

[reference]
spp = 32

[budgets]
spp = [2, 8]

[[config]]
name = "path"

[[config]]
name = "no <rr>"
options = "--rr off"
"#;

fn kalos(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn tiny_experiment(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-report-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("tiny.toml"), EXPERIMENT).unwrap();
    let out = kalos(&["experiment", "tiny.toml", "-q"], &d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    d
}

#[test]
fn the_report_holds_every_section_and_image_and_is_rebuilt_the_same() {
    let d = tiny_experiment("structure");
    let res = d.join("tiny-results");
    let html = std::fs::read_to_string(res.join("report.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    // self-contained: every image a data URI, nothing fetched from elsewhere
    let imgs = html.matches("<img ").count();
    let embedded = html.matches(" src=\"data:image/").count();
    // two figures of curves, the reference and its crop, per budget and configuration
    // the image, its crop and two error maps
    assert_eq!(imgs, 2 + 2 + 2 * 2 * 4, "{imgs} images");
    assert_eq!(embedded, imgs);
    assert!(!html.contains("http://") && !html.contains("https://"));
    // the sections, the table (a row per configuration and budget), escaped names
    for s in [
        "Error against time and samples",
        "<h2>Numbers</h2>",
        "<h3 id=\"budget-2\">2 spp</h3>",
        "<h3 id=\"budget-8\">8 spp</h3>",
        "<th>FLIP</th>",
        "no &lt;rr&gt;",
        "data-ref=\"ref-full\"",
        "data-ref=\"ref-crop\"",
    ] {
        assert!(html.contains(s), "no {s:?} in the report");
    }
    assert!(!html.contains("no <rr>"));
    assert_eq!(html.matches("<tr><td class=\"name\">").count(), 4);
    // the spread over the two seeds is shown
    assert!(html.contains("&plusmn;"));
    // the plots have every panel's y label, FLIP among them
    let svg = std::fs::read_to_string(res.join("error-vs-spp.svg")).unwrap();
    for label in [
        "RMSE",
        "relMSE",
        "share of pixels with &gt; 5% error",
        "mean FLIP",
    ] {
        assert!(svg.contains(label), "no y label {label:?}");
    }
    assert!(
        !svg.contains(".000\n"),
        "axis labels with needless decimals"
    );
    assert!(svg.contains("\n5\n"), "the spp axis's 5");
    // `kalos report` rebuilds the same page from the folder
    let out = kalos(&["report", "tiny-results"], &d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(res.join("report.html")).unwrap(),
        html
    );
    // a folder that holds no results: one line, non-zero exit
    let out = kalos(&["report", "."], &d);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.lines().count() == 1 && err.contains("no results.json"),
        "{err}"
    );
    browser_check(&res.join("report.html"));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_second_run_writes_a_new_folder() {
    let d = tiny_experiment("again");
    let first = std::fs::read(d.join("tiny-results/results.json")).unwrap();
    let out = kalos(&["experiment", "tiny.toml", "-q"], &d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(d.join("tiny-results/results.json")).unwrap(),
        first
    );
    let dated: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with("tiny-results-20"))
        .collect();
    assert_eq!(dated.len(), 1, "{dated:?}");
    assert!(d.join(&dated[0]).join("report.html").exists());
    // the reference rendered the first time is reused, not rendered again
    assert!(d.join(&dated[0]).join("reference.key").exists());
    // -o names the folder
    let out = kalos(&["experiment", "tiny.toml", "-q", "-o", "mine"], &d);
    assert!(out.status.success());
    assert!(d.join("mine/report.html").exists());
    std::fs::remove_dir_all(&d).ok();
}

fn on_path(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| {
        std::env::split_paths(&p)
            .map(|d| d.join(name))
            .find(|f| f.is_file())
    })
}

/// Open the report in headless Chromium; skipped, with the reason printed, where the
/// browser, Node or playwright-core are missing.
fn browser_check(report: &Path) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser/check_report.js");
    let module =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser/node_modules/playwright-core");
    let chromium = std::env::var_os("KALOS_CHROMIUM")
        .map(PathBuf::from)
        .or_else(|| on_path("chromium"))
        .or_else(|| on_path("chromium-browser"));
    let node = on_path("node");
    let missing = match (&chromium, &node, module.exists()) {
        (None, _, _) => Some("no chromium on PATH (apt-get install chromium)"),
        (_, None, _) => Some("no node on PATH"),
        (_, _, false) => Some("no playwright-core (npm install --prefix tests/browser)"),
        _ => None,
    };
    if let Some(why) = missing {
        assert!(
            std::env::var_os("KALOS_REQUIRE_BROWSER").is_none(),
            "the browser check is required here: {why}"
        );
        println!("skipped: the report in a browser: {why}");
        return;
    }
    let out = Command::new(node.unwrap())
        .arg(script)
        .arg(report)
        .arg(chromium.unwrap())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.starts_with("ok: "),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!("the report in headless Chromium: {}", text.trim());
}
