//! Pipelines turn an estimator into images: `render` runs sample passes over the film in
//! parallel (plain rendering); `dtf` runs the two phases and the filter of dependent-tests
//! driven filtering on top of the same passes, so it works with any estimator.

pub mod dtf;
pub mod render;

pub use dtf::{render_dtf, DtfBudget, DtfRun};
pub use render::{
    render, render_into, render_into_costed, Budget, Counts, RenderOutput, RenderSettings,
};
