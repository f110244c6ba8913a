//! What each command does. The options are in [`crate::cli`]; the computations in the library
//! modules (`run`, `sweep`, `fatigue`, `tune`); every file goes through [`absorber_sim::output`].

mod calibrate;
mod estimate;
mod fatigue;
pub mod fmu;
mod info;
mod run;
mod sweep;

pub use info::{lowest_frequencies, static_summary};
pub use run::{run_ensemble_in_memory, run_in_memory, step_damping_line, summary_in_memory};
pub use sweep::{sweep_ensemble_in_memory, sweep_in_memory};

use crate::cli::{Cli, Command, PaperArgs, SceneArgs};
use absorber_sim::scene::{ExcitationType, Precision, Scene};
use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
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

fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// Worker pool of `jobs` threads (default: all cores) with big stacks for large models.
/// The worker threads of a parallel command: `--jobs` (default: every core), capped at the
/// `tasks` there are and at the cores: a thread more than either only costs memory (each gets a
/// 64 MiB stack; the full solver's frames are large).
fn pool(jobs: Option<usize>, tasks: usize) -> Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let wanted = match jobs {
        Some(0) => anyhow::bail!(
            "invalid value for `{}`: 0 (must be at least 1)",
            absorber_sim::output::option("jobs")
        ),
        Some(j) => j,
        None => cores,
    };
    let threads = wanted.min(cores).min(tasks.max(1));
    if jobs.is_some_and(|j| j > threads) {
        eprintln!("note: --jobs {wanted} runs on {threads} threads ({tasks} tasks, {cores} cores)");
    }
    Ok(rayon::ThreadPoolBuilder::new()
        .stack_size(64 << 20)
        .num_threads(threads)
        .build()?)
}

/// Checks excitation frequencies and amplitudes given on the command line against the step
/// (Nyquist, peak acceleration); warns when a period is poorly resolved.
fn check_excitations(freqs: &[f64], amps: &[f64], h: f64, fkey: &str, akey: &str) -> Result<()> {
    for &f in freqs {
        if !f.is_finite() || f <= 0.0 {
            anyhow::bail!("invalid value for `{fkey}`: {f} (must be finite and positive)");
        }
    }
    for &a in amps {
        if !a.is_finite() || a < 0.0 {
            anyhow::bail!("invalid value for `{akey}`: {a} (must be finite and not negative)");
        }
    }
    for &f in freqs {
        for &a in amps {
            absorber_sim::scene::check_harmonic(a, f, h, akey, fkey)?;
        }
        if let Some(w) = absorber_sim::scene::harmonic_warning(f, h, fkey) {
            eprintln!("{w}");
        }
    }
    Ok(())
}
