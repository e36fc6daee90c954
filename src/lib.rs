//! kalos: a Monte-Carlo global illumination renderer.
#![forbid(unsafe_code)]

pub mod film;
pub mod filter;
pub mod image_io;
pub mod math;
pub mod metrics;
pub mod sampling;
pub mod spectrum;
