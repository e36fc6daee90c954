//! The `kalos` binary: parse the command line, call the library, report errors on one line.
use clap::Parser;

fn main() {
    let cli = kalos::cli::Cli::parse();
    if let Err(e) = kalos::cli::run(cli) {
        eprintln!("kalos: error: {e}");
        std::process::exit(1);
    }
}
