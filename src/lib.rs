//! kalos: a Monte-Carlo global illumination renderer.
//!
//! Data flows one way: scene files -> `scene::SceneDesc` -> `scene::Scene` (+ BVH) ->
//! estimators (`integrator`) driven by `sampling` streams -> `film` statistics ->
//! `pipeline`s -> images (`image_io`), metrics and reports.
#![forbid(unsafe_code)]

pub mod accel;
pub mod cli;
pub mod film;
pub mod filter;
pub mod image_io;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod metrics;
pub mod pipeline;
pub mod radiosity;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod spectrum;
