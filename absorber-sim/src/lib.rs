//! The absorber's simulations on the host: the library of the `host-sim` command line, the
//! studies' developer tool `absorber-studies` and the Python package (the CLI parses options,
//! reads and writes files and prints; everything it computes is here).
//!
//! Modules (dependencies point down only, to the solvers):
//! - [`scene`]: the TOML scene (every parameter, its sections, sensors, arm, checks);
//! - [`excitation`]: the base excitation, harmonic or a measured record;
//! - [`run`]: one scene in time, streamed ([`run::Row`], its statistics, CSV rows);
//! - [`sweep`]: the frequency response, one run per frequency in parallel;
//! - [`simulate`]: the commands' simulations in memory (`run`, `sweep`, `static`, `modes`), as
//!   the command line, the Python package and the studies call them;
//! - [`ensemble`]: K seeded members of a chaotic run and their statistics;
//! - [`fatigue`]: the clamp's fatigue damage rate vs frequency and amplitude;
//! - [`tune`]: the track radius for a ball frequency half the beam's;
//! - [`calibrate`]: the reduced beam's stiffness and mass factors fitted to the full solver;
//! - [`identify`]: the first pole from a measured response record;
//! - [`estimate`]: the monitor's estimators against the full solver;
//! - [`wind`]: wind and traffic loads on an arm as load time histories;
//! - [`fleet`]: one wind record of a fleet study;
//! - [`integrator`]: the time integrator's damping and spectral radius on one mode;
//! - [`lm`]: Levenberg–Marquardt for the small box-constrained fits;
//! - [`fft`]: amplitude spectra;
//! - [`figures`]: the paper's figures from a run; [`plot`]: PNG plots;
//! - [`csvio`]: the user's CSV files (records, decays, load tables);
//! - [`output`]: the one writer of every file (atomic, manifest, lock);
//! - [`interrupt`]: stopping a long computation from outside (Python's Ctrl-C);
//! - [`process`]: a command-line tool as a process (arguments, exit codes, panics);
//! - [`core_sim`]: the embedded core behind [`absorber_full::sim::Simulator`] (N picked at
//!   compile time by the one macro [`with_elements!`]); the full solver is [`absorber_full`].
pub use absorber_core;
pub mod calibrate;
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
pub mod process;
pub mod run;
pub mod scene;
pub mod simulate;
pub mod sweep;
pub mod tune;
pub mod wind;
