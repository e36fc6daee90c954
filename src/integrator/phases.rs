//! Cycle counts of [`super::path::radiance_batch`]'s phases, for throughput work: this
//! project's machines run `perf` with the clock as its only event, whose samples skid onto
//! the wrong instructions (2026-12-05, b4ac6ed), so the time-stamp counter is read at each phase's end
//! instead.
//!
//! Built only with the cargo feature `phase-timers`
//! (`cargo build --release --features phase-timers`), on x86-64; without it a [`Timer`] is
//! empty, its calls compile to nothing and the renderer's code is as without them. A batch
//! sums its phases in its own [`Timer`] and adds them to the process's totals once, at its
//! end: a shared counter touched at every step, contended by two threads, halved the
//! render's speed (2026-12-05, ad7e6d4). `kalos render` prints the totals ([`report`]).

/// The phases of one step of a batch, in their order.
#[derive(Clone, Copy)]
pub enum Phase {
    /// The paths' ray queries gathered into one list.
    Gather,
    /// `Bvh::trace` answering them.
    Trace,
    /// The paths' advance: the answers taken, hit records, emission, BSDFs, random
    /// numbers, next-event estimation and continuation (or their hand-over to the lanes).
    Advance,
    /// The SIMD lanes' loop (`Lanes::finish`).
    Lanes,
    /// The lanes' results back to their paths.
    Ending,
}

const PHASES: usize = 5;
const NAMES: [&str; PHASES + 1] = ["gather", "trace", "advance", "lanes", "ending", "batch"];

#[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
static TOTALS: [std::sync::atomic::AtomicU64; PHASES + 1] =
    [const { std::sync::atomic::AtomicU64::new(0) }; PHASES + 1];

/// The time-stamp counter.
#[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
#[inline(always)]
#[allow(unsafe_code)]
fn now() -> u64 {
    // SAFETY: RDTSC exists on every x86-64 CPU and reads no memory.
    unsafe { std::arch::x86_64::_rdtsc() }
}

/// One batch's cycles per phase (empty without the feature).
pub struct Timer {
    #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
    sums: [u64; PHASES],
    #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
    start: u64,
    #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
    last: u64,
}

impl Timer {
    /// A batch starts.
    #[inline(always)]
    pub fn start() -> Timer {
        #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
        {
            let t = now();
            Timer {
                sums: [0; PHASES],
                start: t,
                last: t,
            }
        }
        #[cfg(not(all(feature = "phase-timers", target_arch = "x86_64")))]
        Timer {}
    }

    /// `phase` ends: the cycles since the last phase's end are its.
    #[inline(always)]
    pub fn lap(&mut self, phase: Phase) {
        #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
        {
            let t = now();
            self.sums[phase as usize] += t - self.last;
            self.last = t;
        }
        #[cfg(not(all(feature = "phase-timers", target_arch = "x86_64")))]
        let _ = phase;
    }

    /// A phase not timed ends (its cycles count toward the batch's only).
    #[inline(always)]
    pub fn skip(&mut self) {
        #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
        {
            self.last = now();
        }
    }

    /// The batch ends: its sums and its whole time go to the process's totals.
    #[inline(always)]
    pub fn finish(self) {
        #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
        {
            use std::sync::atomic::Ordering::Relaxed;
            for (total, v) in TOTALS.iter().zip(self.sums) {
                total.fetch_add(v, Relaxed);
            }
            TOTALS[PHASES].fetch_add(now() - self.start, Relaxed);
        }
    }
}

/// The totals so far over all threads, in 10^9 cycles of the time-stamp counter, one line
/// (`phases Gcycles: gather 0.181 trace 1.770 ... batch 3.301`); `None` without the
/// feature or before any batch.
pub fn report() -> Option<String> {
    #[cfg(all(feature = "phase-timers", target_arch = "x86_64"))]
    {
        use std::sync::atomic::Ordering::Relaxed;
        let v: Vec<u64> = TOTALS.iter().map(|t| t.load(Relaxed)).collect();
        if v[PHASES] == 0 {
            return None;
        }
        let parts: Vec<String> = NAMES
            .iter()
            .zip(&v)
            .map(|(n, c)| format!("{n} {:.3}", *c as f64 / 1e9))
            .collect();
        Some(format!("phases Gcycles: {}", parts.join(" ")))
    }
    #[cfg(not(all(feature = "phase-timers", target_arch = "x86_64")))]
    {
        let _ = NAMES;
        None
    }
}
