//! Image-space filters that read film statistics.
//!
//! [`dtf`]: dependent-tests driven filtering (Csonka, Szirmay-Kalos, Kelemen, Antal):
//! sample allocation from a phase of dependent tests, homogeneous-region forming and the
//! error-minimising filter applied to the phase of independent tests. Everything here is a
//! pure function of [`crate::film::Film`] statistics; the renderer supplies the two films.
//!
//! [`energy`]: Rushmeier and Ward's energy-preserving filter and the pilot-sample
//! quantities (S_16, L_ave, Lt_vis, Mt, Mt_ceiling, the convergence test).

pub mod dtf;
pub mod energy;

pub use dtf::{
    allocate_budget, allocate_relative, classify, color_norm, combine, dtf_filter,
    samples_for_error, sigma, Clamp, Dtf, DtfOutput, DtfParams, Kernel, Region,
};
