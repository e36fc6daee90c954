//! kalos: a Monte-Carlo global illumination renderer.
//!
//! Data flows one way: scene files -> `scene::SceneDesc` -> `scene::Scene` (+ BVH) ->
//! estimators (`integrator`) driven by `sampling` streams -> `film` statistics ->
//! `pipeline`s -> images (`image_io`), metrics and reports. The entry point is
//! [`render`] with a [`RenderJob`].
// Unsafe code is denied everywhere but `accel`, whose run-time dispatched SIMD traversal
// must call `#[target_feature]` functions (after checking the CPU) and keeps its stack
// uninitialised, the one `#[target_feature]` call of `integrator::lanes`, and the
// time-stamp counter's read in `integrator::phases` (cargo feature `phase-timers`).
#![deny(unsafe_code)]

pub use render::{render, render_scene, RenderJob, Rendered};

#[allow(unsafe_code)]
pub mod accel;
pub mod cli;
pub mod film;
pub mod filter;
pub mod image_io;
pub mod input;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod metrics;
pub mod options;
pub mod pipeline;
pub mod progress;
pub mod radiosity;
pub mod render;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod spectrum;
pub mod texture;
