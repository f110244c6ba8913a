//! The studies that regenerate the measured documents of docs/, a developer tool beside the
//! user's `host-sim`: [`stability`] (docs/stability.md), [`accuracy`] (docs/accuracy.md and its
//! figures), [`validation`] (docs/validation.md and its figures) and [`chaos`]
//! (docs/chaos.md); [`cli`] is the `absorber-studies` command line over them. They drive the
//! solvers through the simulation library (`absorber_sim`: scenes, runs, ensembles, output, plots) and the
//! full solver (`absorber_full`).
pub mod accuracy;
pub mod chaos;
pub mod cli;
pub mod firmware_gain;
pub mod monitoring;
pub mod stability;
pub mod validation;
