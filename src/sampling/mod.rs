//! Sampling: random streams (random or Owen-scrambled Sobol, independent or dependent)
//! and warps from the unit square, each paired with its density.

pub mod rng;
pub mod warp;

#[cfg(test)]
pub(crate) mod chi2;

pub use rng::{SampleStream, SamplerConfig, SamplerKind, SeqRng};
pub use warp::*;
