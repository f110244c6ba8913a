//! Host tools for the absorber: scenes, sweeps, plots, reports.
//!
//! Layout (dependencies point down only):
//! - [`cli`] (options) → [`commands`] (what each command does);
//! - the studies: [`fatigue`], [`ensemble`], [`sweep`], [`tune`], [`calibrate`], [`identify`]
//!   (the studies that write docs/ are the developer tool `absorber-studies`);
//! - running a scene: [`scene`], [`excitation`], [`run`] (streamed), [`figures`], [`plot`];
//! - the solvers behind [`absorber_full::sim::Simulator`]: [`core_sim`] (the embedded core; N is
//!   picked at compile time by the one macro [`with_elements!`]) and [`absorber_full`] (the full
//!   solver, its own crate);
//! - [`output`]: the one writer of every file (atomic, manifest, lock).
pub use absorber_core;
// Command-line tool: scenes, excitation, the core behind `Simulator`, runs, sweeps, plots.
pub mod calibrate;
pub mod cli;
pub mod commands;
pub mod core_sim;
pub mod csvio;
pub mod ensemble;
pub mod estimate;
pub mod excitation;
pub mod fatigue;
pub mod fft;
pub mod figures;
pub mod fleet;
pub mod identify;
pub mod integrator;
pub mod interrupt;
pub mod lm;
pub mod output;
pub mod plot;
pub mod run;
pub mod scene;
pub mod sweep;
pub mod tune;
pub mod wind;
