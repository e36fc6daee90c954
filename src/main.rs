//! The `kalos` binary: parse the command line, call the library, report errors on one line.

fn main() {
    // Rust ignores SIGPIPE, so a print to a closed pipe (`kalos info x | head -1`) would
    // panic; a command-line tool ends quietly there, as cat and grep do.
    #[cfg(unix)]
    // SAFETY: called once at start-up, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = kalos::cli::parse_args();
    if let Err(e) = kalos::cli::run(cli) {
        eprintln!("kalos: error: {e}");
        std::process::exit(1);
    }
}
