//! The CLI's `Progress`: an indicatif bar on a terminal; on a pipe or a log file (farm
//! jobs) a line every 5% or 10 s with the rate and the time left; Ctrl-C and SIGTERM
//! stop the render at the next row, and what was rendered is written. Outside a stage
//! that stops so (loading the scene, preparing, DTF's phases) they end the process at
//! once with a message, and a render that has not stopped 10 s after them is ended too.

use crate::pipeline::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

/// Set by the Ctrl-C / SIGTERM handler.
static STOP: AtomicBool = AtomicBool::new(false);
/// Whether the work under way stops at an interrupt and writes what it has (a stage of
/// a `CliProgress` made `stoppable`, between its `begin` and `finish`).
static STOPPABLE: AtomicBool = AtomicBool::new(false);
/// How long a stoppable stage may take to stop before the process ends anyway.
const STOP_GRACE_SECONDS: u64 = 10;
static HANDLER: OnceLock<()> = OnceLock::new();

/// Install the Ctrl-C / SIGTERM handler once (the first asks the render to stop; a
/// second Ctrl-C after that exits at once).
pub fn install_interrupt_handler() {
    install_handler("finishing the rows under way, then writing what was rendered");
}

/// The same handler, saying `what` happens after the first interrupt.
pub fn install_handler(what: &'static str) {
    HANDLER.get_or_init(|| {
        let _ = ctrlc::set_handler(move || {
            if STOP.swap(true, Ordering::SeqCst) {
                eprintln!("\nkalos: interrupted twice, exiting without writing");
                std::process::exit(130);
            }
            if !STOPPABLE.load(Ordering::SeqCst) {
                eprintln!(
                    "\nkalos: interrupted outside a stage that can stop and write what it has (loading the scene, preparing, DTF's phases): exiting without writing"
                );
                std::process::exit(130);
            }
            eprintln!("\nkalos: interrupted: {what}");
            std::thread::spawn(|| {
                std::thread::sleep(std::time::Duration::from_secs(STOP_GRACE_SECONDS));
                eprintln!(
                    "kalos: interrupted: the work did not stop within {STOP_GRACE_SECONDS} s, exiting without writing"
                );
                std::process::exit(130);
            });
        });
    });
}

/// Whether the user asked to stop.
pub fn interrupted() -> bool {
    STOP.load(Ordering::SeqCst)
}

pub struct CliProgress {
    bar: Option<ProgressBar>,
    quiet: bool,
    /// Its stages stop at an interrupt (they poll `cancelled`).
    stoppable: bool,
    /// The stage's start and unit.
    stage: Mutex<(Instant, String)>,
    total: AtomicU64,
    done: AtomicU64,
    /// Log mode: the share (in 1/20) and time of the last line printed.
    last: Mutex<(u64, f64)>,
}

impl CliProgress {
    pub fn new(quiet: bool) -> CliProgress {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let pb = ProgressBar::new(1);
            pb.set_draw_target(ProgressDrawTarget::stderr());
            pb.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {msg}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            pb
        });
        CliProgress {
            bar,
            quiet,
            stoppable: true,
            stage: Mutex::new((Instant::now(), "samples".into())),
            total: AtomicU64::new(0),
            done: AtomicU64::new(0),
            last: Mutex::new((0, 0.0)),
        }
    }
}

impl CliProgress {
    /// Stages of work that does not stop part-way (DTF): an interrupt ends the process.
    pub fn not_stoppable(mut self) -> CliProgress {
        self.stoppable = false;
        self
    }
}

/// "1.23 M samples/s" with a unit and three significant figures.
pub fn rate(per_second: f64, unit: &str) -> String {
    let (v, p) = if per_second >= 1e9 {
        (per_second * 1e-9, "G")
    } else if per_second >= 1e6 {
        (per_second * 1e-6, "M")
    } else if per_second >= 1e3 {
        (per_second * 1e-3, "k")
    } else {
        (per_second, "")
    };
    let digits = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$} {p}{unit}/s")
}

impl Progress for CliProgress {
    fn begin(&self, unit: &str, total: u64) {
        STOPPABLE.store(self.stoppable, Ordering::SeqCst);
        *self.stage.lock().unwrap_or_else(|e| e.into_inner()) = (Instant::now(), unit.to_string());
        self.done.store(0, Ordering::Relaxed);
        *self.last.lock().unwrap_or_else(|e| e.into_inner()) = (0, 0.0);
        if let Some(b) = &self.bar {
            b.reset();
        }
        self.set_total(total);
    }

    fn set_total(&self, samples: u64) {
        self.total.store(samples, Ordering::Relaxed);
        if let Some(b) = &self.bar {
            b.set_length(samples);
        }
    }

    fn advance(&self, samples: u64) {
        let done = self.done.fetch_add(samples, Ordering::Relaxed) + samples;
        let (t0, unit) = self.stage.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let el = t0.elapsed().as_secs_f64();
        if let Some(b) = &self.bar {
            b.set_position(done);
            b.set_message(rate(done as f64 / el.max(1e-9), &unit));
            return;
        }
        if self.quiet {
            return;
        }
        let total = self.total.load(Ordering::Relaxed).max(1);
        let twentieth = done * 20 / total;
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        // renders shorter than a second print nothing; then a line at 1 s, per 5% or 10 s
        let every = if last.1 == 0.0 { 1.0 } else { 10.0 };
        if el >= 1.0 && (twentieth > last.0 || el - last.1 >= every) {
            *last = (twentieth, el);
            let r = done as f64 / el.max(1e-9);
            let left = total.saturating_sub(done) as f64 / r.max(1e-9);
            eprintln!(
                "kalos: {:>3}% {done}/{total} {unit}, {}, {:.0} s elapsed, about {:.0} s left",
                (done * 100 / total).min(100),
                rate(r, &unit),
                el,
                left
            );
        }
    }

    fn message(&self, text: &str) {
        if self.quiet {
            return;
        }
        match &self.bar {
            Some(b) => b.println(format!("kalos: {text}")),
            None => eprintln!("kalos: {text}"),
        }
    }

    fn finish(&self) {
        STOPPABLE.store(false, Ordering::SeqCst);
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }

    fn cancelled(&self) -> bool {
        interrupted()
    }
}
