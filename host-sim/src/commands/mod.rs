//! What each command does. The options are in [`crate::cli`]; the computations in the library
//! [`absorber_sim`] (its in-memory runs in [`absorber_sim::simulate`]); every file goes through
//! [`absorber_sim::output`].

mod calibrate;
mod estimate;
mod fatigue;
pub mod fmu;
mod info;
mod run;
mod sweep;

pub use run::step_damping_line;

use crate::cli::{Cli, Command, PaperArgs, SceneArgs};
use absorber_sim::scene::{ExcitationType, Precision, Scene};
use anyhow::Result;
use std::path::Path;

/// Runs the parsed command line.
pub fn dispatch(cli: Cli) -> Result<()> {
    match cli.command.unwrap_or(Command::Paper(PaperArgs {
        scene: SceneArgs::default(),
        json: false,
    })) {
        Command::Paper(a) => run::paper(&a),
        Command::Static(a) => info::static_cmd(&a),
        Command::Modes(a) => info::modes(&a),
        Command::Run(a) => run::run(&a),
        Command::Sweep(a) => sweep::sweep_cmd(&a),
        Command::Tune(a) => info::tune_cmd(&a),
        Command::Fatigue(a) => fatigue::run(&a),
        Command::Calibrate(a) => calibrate::calibrate(&a),
        Command::Identify(a) => calibrate::identify(&a),
        Command::Estimate(a) => estimate::run(&a),
        Command::Fmu(a) => fmu::run(&a),
    }
}

/// Loads the scene of the options and prints its warnings.
fn load(a: &SceneArgs) -> Result<Scene> {
    let s = a.load()?;
    for w in s.warnings() {
        eprintln!("{w}");
    }
    Ok(s)
}

/// One line describing a scene.
pub fn describe(s: &Scene) -> String {
    let f = &s.file;
    let exc = match f.excitation.kind {
        ExcitationType::Harmonic => format!(
            "base {:.3} mm at {} Hz",
            f.excitation.amplitude_or_paper() * 1e3,
            f.excitation.frequency_or_paper()
        ),
        ExcitationType::Csv => format!(
            "base acceleration from {}",
            f.excitation
                .file
                .as_deref()
                .map(Path::display)
                .map(|d| d.to_string())
                .unwrap_or_default()
        ),
    };
    let scheme = match f.integrator.rho_inf {
        Some(r) => format!(" (generalized-α, ρ∞ = {r})"),
        None => String::new(),
    };
    format!(
        "scene {}: {}, {} elements, {}, {} solver; {}; {} s with h = {} s{scheme}",
        f.name,
        f.kind.name(),
        f.elements,
        match f.precision {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        },
        f.solver.name(),
        exc,
        f.duration,
        f.integrator.step
    )
}
