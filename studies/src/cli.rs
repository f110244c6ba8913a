//! The `absorber-studies` command line: the studies that write docs/, with the checks of their
//! options.

use crate::accuracy::AccuracyArgs;
use crate::chaos::ChaosArgs;
use crate::stability::StabilityArgs;
use anyhow::{bail, Result};
use clap::{Args, Parser, Subcommand};
use host_sim::output::PointsFailed;

/// The studies that regenerate the measured documents of docs/ (a developer tool; the user's
/// command line is `host-sim`). Run from the workspace root: the defaults write into docs/.
///
/// Outputs: every file is written under a hidden temporary name and renamed into place when
/// complete.
///
/// Exit codes: 0 success; 1 error (bad input, failed run, unwritable output; one line on
/// stderr naming the field or file); 2 command-line usage error; 3 completed, outputs written,
/// but some points of `validation` failed (marked FAILED in its table and figure); 101
/// internal error (a bug).
#[derive(Parser, Debug)]
#[command(name = "absorber-studies", version, about, long_about)]
pub struct Cli {
    /// The study to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The studies.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Numerical stability matrix (stiff and extreme cases, bad input, f32/f64 drift);
    /// writes docs/stability.md.
    Stability(StabilityArgs),
    /// Writes docs/chaos.md: the free ball's statistics (amplitude, tip RMS, impact rate,
    /// flight share, separation rate) over steps, meshes and solvers, each an ensemble with its
    /// spread, and whether the embedded model's converge to the reference.
    Chaos(ChaosArgs),
    /// Writes docs/accuracy.md: error of embedded configurations (elements, step, precision,
    /// Newton budget) against a converged full-solver reference, and their run time.
    Accuracy(AccuracyArgs),
    /// Writes docs/validation.md: every quantitative claim of the paper beside this model's
    /// numbers (3 elements and a converged mesh), with verdicts, reasons and figures.
    Validation(ValidationArgs),
}

/// `validation` options.
#[derive(Args, Debug, Clone)]
pub struct ValidationArgs {
    /// Output document.
    #[arg(long, default_value = "docs/validation.md")]
    pub out: std::path::PathBuf,
    /// Directory of its figures (the document links them as `img/...`).
    #[arg(long, default_value = "docs/img")]
    pub img: std::path::PathBuf,
    /// Elements of the converged mesh.
    #[arg(long, default_value_t = 16)]
    pub converged: usize,
}

/// Runs the parsed command line.
pub fn main(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Stability(a) => stability(&a),
        Command::Chaos(a) => crate::chaos::run(&a),
        Command::Accuracy(a) => accuracy(&a),
        Command::Validation(a) => validation(&a),
    }
}

fn stability(a: &StabilityArgs) -> Result<()> {
    if !(a.drift_duration.is_finite() && a.drift_duration > 0.0) {
        bail!(
            "invalid value for `--drift-duration`: {} (must be finite and positive) [s]",
            a.drift_duration
        );
    }
    if a.jobs == Some(0) {
        bail!("invalid value for `--jobs`: 0 (must be at least 1)");
    }
    if a.only.is_some()
        && (a.out == std::path::Path::new("docs/stability.md") || is_the_document(&a.out))
    {
        bail!(
            "`--only` runs a subset of the matrix, which must not replace docs/stability.md: give \
             `--out` another file (e.g. --out /tmp/stability-subset.md)"
        );
    }
    crate::stability::command(a)
}

fn accuracy(a: &AccuracyArgs) -> Result<()> {
    if a.repeats == Some(0) {
        bail!("invalid value for `--repeats`: 0 (must be at least 1)");
    }
    crate::accuracy::run(a)
}

fn validation(a: &ValidationArgs) -> Result<()> {
    let t0 = std::time::Instant::now();
    let failed = crate::validation::write(&a.out, &a.img, a.converged, &|stage| {
        eprintln!("validation: {stage}…")
    })?;
    eprintln!(
        "validation: wrote {} in {:.1} s",
        a.out.display(),
        t0.elapsed().as_secs_f64()
    );
    if failed > 0 {
        return Err(PointsFailed(format!(
            "{failed} validation sweep run(s) failed (marked FAILED in {} and its figure)",
            a.out.display()
        ))
        .into());
    }
    Ok(())
}

/// `path` is docs/stability.md (of the working directory or of this workspace), however spelt.
fn is_the_document(path: &std::path::Path) -> bool {
    let canon = |p: &std::path::Path| -> Option<std::path::PathBuf> {
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => std::path::Path::new("."),
        };
        Some(std::fs::canonicalize(parent).ok()?.join(p.file_name()?))
    };
    let Some(target) = canon(path) else {
        return false;
    };
    let ours = [
        std::path::PathBuf::from("docs/stability.md"),
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/stability.md"),
    ];
    ours.iter().any(|p| canon(p) == Some(target.clone()))
}
