//! Experiment files: contradictions and limits refused naming the key, and a tiny valid
//! experiment that still runs.

use super::{assert_one_line_error, kalos, pfm, temp_dir, write};
use std::path::Path;

/// An experiment on an 8x8 Cornell box with one 1-spp budget; `top` goes before the
/// tables, `reference` into [reference], `configs` after them.
pub(crate) fn experiment_text(top: &str, reference: &str, configs: &str) -> String {
    format!(
        "scene = \"cornell\"\noptions = \"--res 8x8 --threads 1\"\n{top}\n\
         [reference]\n{reference}\n\n[budgets]\nspp = [1]\n\n{configs}\n"
    )
}

pub(crate) const ONE_CONFIG: &str = "[[config]]\nname = \"a\"\n";

/// Run `kalos experiment` on `text`; it must fail with one line naming every needle,
/// and create no output folder.
#[track_caller]
pub(crate) fn assert_experiment_refused(d: &Path, name: &str, text: &str, needles: &[&str]) {
    let file = write(d, &format!("{name}.toml"), text);
    let out = d.join(format!("{name}-out"));
    let (code, _, err) = kalos(&["experiment", &file, "--out", out.to_str().unwrap(), "-q"]);
    let mut all = vec![format!("{name}.toml")];
    all.extend(needles.iter().map(|s| s.to_string()));
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    assert_one_line_error(name, code, &err, 1, &all);
    assert!(!out.exists(), "{name}: the output folder was created");
}

#[test]
fn experiment_files_with_contradictions_are_refused_naming_the_key() {
    let d = temp_dir("experiments");
    write(&d, "nan.pfm", pfm(8, 8, 0.5, f32::NAN));
    write(&d, "small.pfm", pfm(4, 4, 0.5, 0.5));
    let constant = "constant = 1.0";
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "same-name",
            experiment_text(
                "",
                constant,
                "[[config]]\nname = \"a\"\n[[config]]\nname = \"a\"\noptions = \"--rr off\"\n",
            ),
            vec!["config", "\"a\""],
        ),
        (
            "same-file-name",
            experiment_text(
                "",
                constant,
                "[[config]]\nname = \"a b\"\n[[config]]\nname = \"a_b\"\n",
            ),
            vec!["config", "a_b"],
        ),
        (
            "image-and-constant",
            experiment_text("", "image = \"nan.pfm\"\nconstant = 1.0", ONE_CONFIG),
            vec!["[reference]", "image", "constant"],
        ),
        (
            "spp-and-constant",
            experiment_text("", "spp = 4\nconstant = 1.0", ONE_CONFIG),
            vec!["[reference]", "spp", "constant"],
        ),
        (
            "crop-outside",
            experiment_text("crop = [4, 4, 8, 8]", constant, ONE_CONFIG),
            vec!["crop", "8x8"],
        ),
        (
            "crop-empty",
            experiment_text("crop = [0, 0, 0, 4]", constant, ONE_CONFIG),
            vec!["crop"],
        ),
        (
            "zoom-zero",
            experiment_text("zoom = 0", constant, ONE_CONFIG),
            vec!["zoom"],
        ),
        (
            "repeats-zero",
            experiment_text("repeats = 0", constant, ONE_CONFIG),
            vec!["repeats"],
        ),
        (
            "spp-in-options",
            experiment_text(
                "",
                constant,
                "[[config]]\nname = \"a\"\noptions = \"--spp 0\"\n",
            ),
            vec!["config a", "--spp", "[budgets]"],
        ),
        (
            "seed-in-options",
            experiment_text(
                "",
                constant,
                "[[config]]\nname = \"a\"\noptions = \"--seed 3\"\n",
            ),
            vec!["config a", "--seed", "repeats"],
        ),
        (
            "nan-reference",
            experiment_text("", "image = \"nan.pfm\"", ONE_CONFIG),
            vec!["nan.pfm", "NaN"],
        ),
        (
            "nan-constant",
            experiment_text("", "constant = nan", ONE_CONFIG),
            vec!["[reference]", "constant"],
        ),
        (
            "reference-size",
            experiment_text("", "image = \"small.pfm\"", ONE_CONFIG),
            vec!["small.pfm", "4x4", "8x8"],
        ),
    ];
    for (name, text, needles) in cases {
        assert_experiment_refused(&d, name, &text, &needles);
    }
}

#[test]
fn experiment_side_by_side_size_is_limited() {
    let d = temp_dir("zoom");
    let text = experiment_text(
        "crop = [0, 0, 8, 8]\nzoom = 100000",
        "constant = 1.0",
        ONE_CONFIG,
    );
    assert_experiment_refused(&d, "huge-zoom", &text, &["zoom", "side-by-side"]);
}

#[test]
fn a_valid_tiny_experiment_still_runs() {
    let d = temp_dir("experiment-ok");
    write(&d, "ref.pfm", pfm(8, 8, 0.5, 0.5));
    let text = experiment_text(
        "repeats = 1\ncrop = [2, 2, 4, 4]\nzoom = 2",
        "image = \"ref.pfm\"",
        "[[config]]\nname = \"plain path\"\n[[config]]\nname = \"no rr\"\noptions = \"--rr off\"\n",
    );
    let file = write(&d, "ok.toml", text);
    let out = d.join("ok-out");
    let (code, _, err) = kalos(&["experiment", &file, "--out", out.to_str().unwrap(), "-q"]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "results.csv",
        "side-by-side.png",
        "plain_path-1.exr",
        "no_rr-1.exr",
    ] {
        assert!(out.join(f).exists(), "{f} missing: {err}");
    }
}
