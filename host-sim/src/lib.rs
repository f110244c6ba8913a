//! `host-sim`, the command line on the simulation library [`absorber_sim`]: [`cli`] (the options,
//! and the process: exit codes, errors) → [`commands`] (what each command does: it loads the
//! scene, calls the library, writes the files through [`absorber_sim::output`] and prints).
pub mod cli;
pub mod commands;
