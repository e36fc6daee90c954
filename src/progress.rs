//! Progress of long work as a small trait (it sits below every stage that reports: the
//! radiosity preprocess, the pipelines): they report the work they plan and the
//! work done, and ask whether to stop (Ctrl-C, a Python KeyboardInterrupt). The CLI's
//! progress bar and log lines are one implementation (`cli::progress`); `Silent` is none.

/// What a pipeline tells about its progress, in camera samples.
pub trait Progress: Sync {
    /// A new stage of work begins (the radiosity preprocess, the samples of a render),
    /// with `total` units of `unit` planned; what was done before does not count.
    fn begin(&self, _unit: &str, total: u64) {
        self.set_total(total)
    }
    /// The total work changed (units planned so far in this stage).
    fn set_total(&self, _samples: u64) {}
    /// `samples` more samples are done.
    fn advance(&self, _samples: u64) {}
    /// A line of news (predicted work, phase changes).
    fn message(&self, _text: &str) {}
    /// A pass of samples is done: `image` computes the mean image so far (`width` x
    /// `height` linear RGB, row-major) for a live preview; only a listener calls it.
    fn pass_image(&self, _width: u32, _height: u32, _image: &dyn Fn() -> Vec<[f32; 3]>) {}
    /// The render is over.
    fn finish(&self) {}
    /// True when the user asked to stop: the pipeline ends at the next row and returns
    /// what it has.
    fn cancelled(&self) -> bool {
        false
    }
}

/// No progress reporting.
pub struct Silent;
impl Progress for Silent {}
