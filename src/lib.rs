//! kalos: a Monte-Carlo global illumination renderer.
#![forbid(unsafe_code)]

pub mod accel;
pub mod math;
pub mod sampling;
pub mod spectrum;
