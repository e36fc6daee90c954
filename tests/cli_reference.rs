//! docs/guide/cli.md is generated from the clap definition (`kalos::cli::reference`); an
//! option added, renamed or given another default without regenerating the page fails here,
//! naming the command that regenerates it.

use kalos::cli::reference::{markdown, REGENERATE};

#[test]
fn cli_reference_is_current() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/guide/cli.md");
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    let generated = markdown();
    if committed != generated {
        let line = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(committed.lines().count().min(generated.lines().count()));
        panic!(
            "docs/guide/cli.md is stale (first difference at line {}): regenerate it with `{REGENERATE}`",
            line + 1
        );
    }
}

#[test]
fn cli_reference_names_every_command_and_option() {
    let md = markdown();
    for sub in [
        "render",
        "scenes",
        "compare",
        "experiment",
        "merge",
        "radiosity",
        "filter",
        "info",
    ] {
        assert!(
            md.contains(&format!("## kalos {sub}\n")),
            "no section for kalos {sub}"
        );
    }
    // options of the flattened RenderJob, with their defaults and choices
    for needle in [
        "`--spp <",
        "`--method <",
        "`--dtf-n <",
        "`--rr <",
        "`-o, --output <OUTPUT>`",
        "default: `out.exr`",
    ] {
        assert!(md.contains(needle), "the reference lacks {needle}");
    }
}
