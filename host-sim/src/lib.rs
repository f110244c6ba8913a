//! `host-sim`, the command line on the simulation library [`absorber_sim`]: [`cli`] (the
//! options) → [`commands`] (what each command does: it loads the scene, calls the library, writes
//! the files through [`absorber_sim::output`] and prints); `main` runs it as a process
//! ([`absorber_sim::process`]: exit codes, errors).
pub mod cli;
pub mod commands;
