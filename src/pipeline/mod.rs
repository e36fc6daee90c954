//! Pipelines turn an estimator into images: `render` runs sample passes over the film in
//! parallel (plain rendering, and the phases of the filtering methods).

pub mod render;

pub use render::{render, render_into, Budget, Counts, RenderOutput, RenderSettings};
