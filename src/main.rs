//! The `kalos` binary: parse the command line, call the library, report errors on one line.

fn main() {
    let cli = kalos::cli::parse_args();
    if let Err(e) = kalos::cli::run(cli) {
        eprintln!("kalos: error: {e}");
        std::process::exit(1);
    }
}
