//! The `absorber-studies` command line: the studies that write docs/, with the checks of their
//! options.

use crate::accuracy::AccuracyArgs;
use crate::chaos::ChaosArgs;
use crate::stability::StabilityArgs;
use absorber_sim::output::PointsFailed;
use anyhow::{bail, Result};
use clap::{Args, Parser, Subcommand};

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
    /// Writes the regimes × sensor sets × estimators table of docs/monitoring.md (lab at
    /// 3.70, 4.05, 4.10, 4.13 Hz; the mast arm's scenes of scenes/: first-mode wind, von Kármán
    /// wind, second-mode lock-in with a ±8 g and the shipped ±2 g accelerometer) between its
    /// markers, and its JSON beside it (docs/monitoring.json).
    Monitoring(MonitoringArgs),
    /// Writes the firmware's constant-gain estimator of the mast arm as Rust constants
    /// (firmware/src/estimator_gain.rs: calibrated f32 parameters, the arm and the gain as bit
    /// patterns, so the firmware builds the twin's estimator bit for bit).
    FirmwareGain(FirmwareGainArgs),
}

/// `monitoring` options.
#[derive(Args, Debug, Clone)]
pub struct MonitoringArgs {
    /// Output document (its table between the `absorber-studies monitoring` markers is replaced).
    #[arg(long, default_value = "docs/monitoring.md")]
    pub out: std::path::PathBuf,
    /// Duration of every regime [s] (default: the lab's 60 s and each scene's own).
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
}

/// `firmware-gain` options.
#[derive(Args, Debug, Clone)]
pub struct FirmwareGainArgs {
    /// The arm's scene.
    #[arg(long, default_value = "scenes/mast-arm.toml")]
    pub scene: std::path::PathBuf,
    /// The Rust file to write.
    #[arg(long, default_value = "firmware/src/estimator_gain.rs")]
    pub out: std::path::PathBuf,
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
        Command::Monitoring(a) => monitoring(&a),
        Command::FirmwareGain(a) => firmware_gain(&a),
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

fn monitoring(a: &MonitoringArgs) -> Result<()> {
    if let Some(d) = a.duration {
        // The table's regimes run at 3 ms (lab) and 10 ms (arm).
        absorber_sim::estimate::check_duration(d, 0.01)?;
        absorber_sim::estimate::check_duration(d, 0.003)?;
    }
    crate::monitoring::write(&a.out, a.duration)
}

fn firmware_gain(a: &FirmwareGainArgs) -> Result<()> {
    let scene = absorber_sim::scene::Scene::load(&a.scene.to_string_lossy())?;
    let text = crate::firmware_gain::constants(&scene)?;
    absorber_sim::output::atomic_write(&a.out, text.as_bytes())?;
    eprintln!("firmware-gain: wrote {}", a.out.display());
    Ok(())
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
