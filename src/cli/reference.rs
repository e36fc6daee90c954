//! The CLI reference as markdown, generated from the clap definition itself, so that
//! `docs/guide/cli.md` cannot drift from the options the binary parses: each option's name,
//! default, choices and help text are written once, on the clap struct.
//!
//! `cargo run --release --example cli_reference > docs/guide/cli.md` writes the page;
//! `tests/cli_reference.rs` fails when the committed page differs from this output.

use super::Cli;
use clap::{Arg, ArgAction, Command, CommandFactory};

/// The command that regenerates `docs/guide/cli.md`.
pub const REGENERATE: &str = "cargo run --release --example cli_reference > docs/guide/cli.md";

/// The whole reference: every subcommand (depth first, in clap's order), its usage, its
/// arguments and options.
pub fn markdown() -> String {
    let mut cmd = Cli::command();
    // usage strings are filled in by clap's build step
    cmd.build();
    let mut out = String::new();
    out.push_str("# kalos command-line reference\n\n");
    out.push_str(&format!(
        "Generated from the clap definition (`src/cli/`) by `{REGENERATE}`; \
         a test (`tests/cli_reference.rs`) fails when this page is stale. \
         `kalos COMMAND --help` prints the same text.\n\n"
    ));
    let subs: Vec<&Command> = visible_subcommands(&cmd);
    for sub in &subs {
        out.push_str(&format!(
            "- [`kalos {}`](#kalos-{}): {}\n",
            sub.get_name(),
            sub.get_name(),
            first_line(&about(sub))
        ));
    }
    out.push('\n');
    for sub in subs {
        command(&mut out, sub, "kalos");
    }
    out
}

fn visible_subcommands(cmd: &Command) -> Vec<&Command> {
    cmd.get_subcommands()
        .filter(|c| !c.is_hide_set() && c.get_name() != "help")
        .collect()
}

fn about(cmd: &Command) -> String {
    cmd.get_long_about()
        .or(cmd.get_about())
        .map(|s| s.to_string())
        .unwrap_or_default()
}

fn first_line(text: &str) -> &str {
    text.lines()
        .next()
        .unwrap_or_default()
        .trim_end_matches('.')
}

fn command(out: &mut String, cmd: &Command, parent: &str) {
    let path = format!("{parent} {}", cmd.get_name());
    out.push_str(&format!("## {path}\n\n"));
    let text = about(cmd);
    if !text.is_empty() {
        out.push_str(&format!("{}\n\n", text.trim_end()));
    }
    let mut c = cmd.clone();
    let usage = c.render_usage().to_string();
    let usage = usage.trim_start_matches("Usage: ").trim();
    let usage = match usage.strip_prefix(cmd.get_name()) {
        Some(rest) => format!("{path}{rest}"),
        None => usage.to_string(),
    };
    out.push_str(&format!("```\n{usage}\n```\n\n"));
    let args: Vec<&Arg> = cmd
        .get_arguments()
        .filter(|a| {
            !a.is_hide_set() && !matches!(a.get_action(), ArgAction::Help | ArgAction::Version)
        })
        .collect();
    let (positional, options): (Vec<&Arg>, Vec<&Arg>) =
        args.into_iter().partition(|a| a.is_positional());
    if !positional.is_empty() {
        out.push_str("Arguments:\n\n");
        for a in positional {
            argument(out, a);
        }
        out.push('\n');
    }
    if !options.is_empty() {
        out.push_str("Options:\n\n");
        for a in options {
            argument(out, a);
        }
        out.push('\n');
    }
    for sub in visible_subcommands(cmd) {
        command(out, sub, &path);
    }
}

fn argument(out: &mut String, a: &Arg) {
    let mut name = String::new();
    if let Some(s) = a.get_short() {
        name.push_str(&format!("-{s}"));
    }
    if let Some(l) = a.get_long() {
        if !name.is_empty() {
            name.push_str(", ");
        }
        name.push_str(&format!("--{l}"));
    }
    let takes_value = a.get_num_args().is_some_and(|n| n.takes_values());
    if takes_value || a.is_positional() {
        let value = a
            .get_value_names()
            .map(|v| {
                v.iter()
                    .map(|s| format!("<{s}>"))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .unwrap_or_else(|| format!("<{}>", a.get_id().as_str().to_uppercase()));
        if !name.is_empty() {
            name.push(' ');
        }
        name.push_str(&value);
        if matches!(a.get_action(), ArgAction::Append)
            || a.get_num_args().is_some_and(|n| n.max_values() > 1)
        {
            name.push_str("...");
        }
    }
    let help = a
        .get_long_help()
        .or(a.get_help())
        .map(|s| s.to_string())
        .unwrap_or_default();
    // one list item: continuation lines indented under it
    let help = help.trim().replace('\n', "\n  ");
    out.push_str(&format!("- `{name}`"));
    if !help.is_empty() {
        out.push_str(&format!(": {help}"));
    }
    let mut extra = Vec::new();
    if takes_value && !a.is_hide_possible_values_set() {
        let choices: Vec<String> = a
            .get_possible_values()
            .iter()
            .filter(|p| !p.is_hide_set())
            .map(|p| format!("`{}`", p.get_name()))
            .collect();
        if !choices.is_empty() {
            extra.push(format!("choices: {}", choices.join(", ")));
        }
    }
    if takes_value && !a.is_hide_default_value_set() {
        let defaults: Vec<String> = a
            .get_default_values()
            .iter()
            .map(|d| format!("`{}`", d.to_string_lossy()))
            .collect();
        if !defaults.is_empty() {
            extra.push(format!("default: {}", defaults.join(" ")));
        }
    }
    if a.is_required_set() && !a.is_positional() {
        extra.push("required".to_string());
    }
    if !extra.is_empty() {
        out.push_str(&format!(" ({})", extra.join("; ")));
    }
    out.push('\n');
}
