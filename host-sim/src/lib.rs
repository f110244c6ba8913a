//! Host tools for the absorber: full solver, scenes, sweeps, plots, reports.
pub use absorber_core;
pub mod sim;
