//! Print the CLI reference as markdown, generated from the clap definition:
//! `cargo run --release --example cli_reference > docs/guide/cli.md`.

fn main() {
    print!("{}", kalos::cli::reference::markdown());
}
