//! Pipelines turn an estimator into images: `render` runs sample passes over the film in
//! parallel (plain rendering, the one pixel loop); `dtf` runs the two phases and the filter
//! of dependent-tests driven filtering on top of the same passes, so it works with any
//! estimator. `progress` is the small trait they report to.

pub mod auto;
pub mod dtf;
pub mod render;
pub mod rw;
pub mod rw_bias;
pub mod rw_depth;
pub mod strategies;

pub use crate::progress::{Progress, Silent};
pub use dtf::{
    render_dtf, render_dtf_with, run_dtf_pass, run_dtf_pass_rest, DtfBudget, DtfPass, DtfPasses,
    DtfRun, LocalPasses,
};
pub use render::{
    render, render_light_pass, render_pass, Budget, Counts, Pass, RenderOutput, RenderSettings,
};
pub use rw::{render_rw, RwBudget, RwParams, RwRun, RwStats};
