//! The simulations of the commands in memory, as the command line, the Python package and the
//! studies run them: the same checks, the same streamed computation, the same summaries (the
//! command line adds files and printing).
//! - [`time`]: one scene in time (`run`, `paper`): the plan, the stream, an ensemble's members;
//! - [`response`]: the frequency response (`sweep`), with the locked ball's beside it;
//! - [`linear`]: the linearized model at rest (`static`, `modes`).
//!
//! Here too what the parallel commands share: the worker pool, the progress bar, the check of
//! the excitations given as options.

pub mod linear;
pub mod response;
pub mod time;

pub use linear::{lowest_frequencies, static_summary};
pub use response::{sweep_ensemble_in_memory, sweep_in_memory};
pub use time::{run_ensemble_in_memory, run_in_memory, summary_in_memory};

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar of `total` units on stderr, labelled `what` (drawn on a terminal only).
pub fn progress_bar(total: u64, what: &str) -> ProgressBar {
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
pub fn pool(jobs: Option<usize>, tasks: usize) -> Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let wanted = match jobs {
        Some(0) => anyhow::bail!(
            "invalid value for `{}`: 0 (must be at least 1)",
            crate::output::option("jobs")
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
pub fn check_excitations(
    freqs: &[f64],
    amps: &[f64],
    h: f64,
    fkey: &str,
    akey: &str,
) -> Result<()> {
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
            crate::scene::check_harmonic(a, f, h, akey, fkey)?;
        }
        if let Some(w) = crate::scene::harmonic_warning(f, h, fkey) {
            eprintln!("{w}");
        }
    }
    Ok(())
}
