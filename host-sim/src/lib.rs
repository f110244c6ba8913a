//! Host tools for the absorber: full solver, scenes, sweeps, plots, reports.
pub use absorber_core;
pub mod full;
pub mod sim;
// Command-line tool: scenes, excitation, the core behind `Simulator`, runs, sweeps, plots.
pub mod accuracy;
pub mod cli;
pub mod commands;
pub mod core_sim;
pub mod excitation;
pub mod fatigue;
pub mod fft;
pub mod figures;
pub mod output;
pub mod plot;
pub mod run;
pub mod scene;
pub mod stability;
pub mod sweep;
pub mod tune;
pub mod validation;
