//! Workspace root: holds the cross-crate tests (`tests/`) and benchmarks (`benches/`).
//! The library itself only re-exports the two crates.
pub use absorber_core as core_model;
pub use absorber_sim;
