//! The `host-sim` command line: its commands and options (clap). What each command does is in
//! [`crate::commands`]; the studies they run are their own modules.

use absorber_core::monitor::DetailCategory;
use absorber_sim::scene::{Kind, Overrides, Plot, Precision, Scene, Solver};
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Free pendulum vibration absorber on a flexible cantilever (Gumus & Ertas): run scenes,
/// sweep the excitation frequency, compute static deflection and modes, tune the track radius.
///
/// Without a command: `paper` (a short summary of the paper's scene at 4.13 Hz).
/// Units are SI throughout (m, s, kg, rad; frequencies in Hz).
///
/// Outputs: every file is written under a hidden temporary name and renamed into place when
/// complete; `run`, `sweep` and `fatigue` write `<name>.manifest.json` last (status, files);
/// one command at a time writes into a directory (lock file `.host-sim.lock`, others wait).
///
/// Exit codes: 0 success; 1 error (bad input, failed run, unwritable output; one line on
/// stderr naming the field or file); 2 command-line usage error; 3 completed, outputs written,
/// but some points of `sweep`/`fatigue` failed (marked FAILED in table, CSV and
/// plot); 101 internal error (a bug).
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about)]
pub struct Cli {
    /// What to do (default: paper).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Short summary of a scene (default the paper's, 4.13 Hz, 60 s): static deflection,
    /// frequencies, tip and ball amplitudes, energy flow from the beam to the ball.
    Paper(PaperArgs),
    /// Static tip deflection under gravity [m].
    Static(InfoArgs),
    /// Natural frequencies about the static equilibrium [Hz].
    Modes(ModesArgs),
    /// Time history of a scene: CSV and PNG plots (paper Figs. 11–23).
    ///
    /// Writes `<out>/<name>.csv`, one row per step (every n-th with --every), SI units, angles
    /// in rad, documented in the file's `#` header: t [s]; base_y = y_b [m]; tip_y = y_b +
    /// deflection, the absolute height of the beam end [m]; tip_deflection, relative to the
    /// base, static sag included [m]; tip_angle ψ [rad]; ball_angle θ from the downward
    /// vertical [rad]; ball_rel_angle θ − ψ [rad]; beam_strain, beam_kinetic, beam_potential,
    /// tip_kinetic, tip_potential, ball_kinetic, ball_potential [J] (kinetic with absolute
    /// velocities, i.e. with the base velocity; potentials as changes from the static state,
    /// with the base displacement); iterations (Newton, per step); impact (1 if the ball hit a
    /// stop); then base_accel [m/s²], tip_velocity [m/s], tip_rate, ball_rate, ball_rel_rate
    /// [rad/s], ball_spin φ [rad], ball_spin_rate [rad/s], normal_force and tangential_force of
    /// the track on a free ball [N] (N < 0: the track would have to pull: a real ball would
    /// leave it); contact (1 on the track, 0 in flight); tip_acceleration, the absolute
    /// acceleration of the beam end [m/s²] (what a tip accelerometer reads; the column
    /// `identify` reads by default). Base velocity and displacement are closed form for a
    /// harmonic excitation. A CSV acceleration record is processed as strong-motion records
    /// are, so that the base starts and ends at rest: mean removed, zero-padded and high-passed
    /// by a zero-phase (forward–backward) 2nd-order Butterworth filter with corner
    /// `excitation.highpass` (default 0.1 Hz; gain ½ there), integrated from rest, and a
    /// linear acceleration baseline that brings velocity and displacement to zero at the
    /// record's end; the solver is driven by the processed record. The summary says how long
    /// the track pulled and how long rolling without slip needed more friction than
    /// `ball.friction`; its steady figures are over t ≥ the transient to the end (the window
    /// of `paper`, `sweep` and `fatigue`).
    ///
    /// Plots `<out>/<name>_{time,fft,phase,energy}.png` (lengths in mm, angles in degrees,
    /// energies in mJ): time histories (min/max envelopes), FFT of tip and ball after the
    /// transient (at most the last 2^20 samples), phase planes (y–ẏ, θ–θ̇, φ–φ̇, θ–ψ; the
    /// transient grey, the steady state in colour), energies from rest as running means over
    /// 2 s (the beam → ball transfer). Then `<out>/<name>.manifest.json`: the command,
    /// its status and files. The CSV is streamed (fixed memory); a run has at most 10^9 steps
    /// and its CSV at most 2·10^7 rows (use --every), else it is refused before any work.
    Run(RunArgs),
    /// Frequency response (paper Fig. 10): one run per frequency in parallel, steady-state
    /// amplitudes of the tip [m] and the ball [deg], impacts and flight fraction, every column
    /// over the steady window (t ≥ `outputs.transient` to the end, as `run` and `paper`; or
    /// `--last`); table, CSV, JSON and plot (in mm) add the ball locked (the passive case, one
    /// more run per frequency); CSV, PNG and `sweep.manifest.json`. A run that fails is marked FAILED (no numbers) in the table, the
    /// CSV (`status` column) and the plot (a cross), and the command exits with code 3.
    Sweep(SweepArgs),
    /// Track radius R that puts the ball at half the beam's first frequency (coupled
    /// linearized model), by bisection.
    Tune(TuneArgs),
    /// Fatigue damage rate at the clamp vs frequency, free vs locked ball (root stress,
    /// rainflow, AASHTO S–N, Miner): CSV, PNG and `fatigue.manifest.json`; failed points are
    /// marked as in `sweep` (exit code 3). Every column is over the steady window (t ≥
    /// `outputs.transient` to the end, as `run`, `paper` and `sweep`): damage, S_eq, impacts,
    /// flight and tip RMS count the same samples, and the damage rate is the window's damage
    /// per hour of it. The start-up from rest is left out because it is not service loading:
    /// a life is the steady hourly rate extrapolated, and the ring-up would bias it.
    Fatigue(FatigueArgs),
    /// Fits the calibration of an N-element model (factors on E·I and E·a, lumped mass
    /// fraction) to the converged full solver (f₁, f₂ with the ball locked, the free-ball beam
    /// mode, the static sag) or to a measured pole (`--target-f1`/`--target-zeta`,
    /// `--from-identified`); prints the residuals and writes a complete scene file.
    Calibrate(CalibrateArgs),
    /// Identifies the first pole f₁, ζ₁ with uncertainties from a measured record (free decay
    /// or ambient response) in a CSV; prints it and writes it as TOML for `calibrate
    /// --from-identified`.
    Identify(IdentifyArgs),
    /// The monitor's estimators against the full solver (16 elements, f64): on a real arm
    /// under the scene's `[[loads]]`, or (`--lab`) on the paper's arm with its free ball under
    /// a wind-like tip force; read by the scene's `[[sensors]]`; the extended Kalman filter
    /// (core, 3 elements, f32, calibrated) with each sensor set, and the constant-gain
    /// baseline. Prints per estimator the stress RMS error, the Miner damage ratio, the mean
    /// NIS, the health verdict (the monitor's own check on the device) and a grade against the
    /// truth: each quality figure (NIS, coverage of ±2 sd, innovation ratio, stress error,
    /// damage ratio) beside its expected range with ok / poor / failed, the grade the worst of
    /// them; `--json` for the same as JSON (`quality`, `grade`); `--out` for CSV, JSON and
    /// plots (`estimate_*` or, with `--lab`, `lab*` files).
    Estimate(EstimateArgs),
    /// Packages the reduced model of a scene as an FMI 3.0 or 2.0 co-simulation FMU (inputs:
    /// base acceleration, tip load; outputs: tip deflection and acceleration, root stress,
    /// ball angle, contact, normal force, Miner damage; fixed step h; docs/fmu.md).
    Fmu(FmuArgs),
}

/// FMI version of the FMU (command-line spelling).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FmiVersion {
    /// FMI 3.0 (Simulink, FMPy, OpenModelica ≥ 1.21, Dymola 2023x).
    #[value(name = "3")]
    V3,
    /// FMI 2.0 (most tools).
    #[value(name = "2")]
    V2,
}

/// `fmu`.
#[derive(Args, Debug)]
pub struct FmuArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// FMI version of the FMU.
    #[arg(long, value_enum)]
    pub fmi_version: FmiVersion,
    /// The FMU file to write (e.g. absorber.fmu).
    #[arg(long, short)]
    pub out: PathBuf,
    /// The FMU's shared library to package (default: `libabsorber_fmu.so` beside this
    /// executable or in its `deps/`, where cargo builds it with host-sim).
    #[arg(long)]
    pub library: Option<PathBuf>,
}

/// `estimate`.
#[derive(Args, Debug)]
pub struct EstimateArgs {
    /// Scene TOML file with `[arm]`, `[[sensors]]` and `[[loads]]` (e.g.
    /// scenes/mast-arm.toml); with `--lab`, a free-ball scene (`paper`, built in; its
    /// `[[sensors]]`, or a tip accelerometer, a ball-angle encoder and a root strain gauge).
    #[arg(long, short, default_value = "paper")]
    pub scene: String,
    /// Simulated time [s] (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Standard deviation of the constant-gain baseline's tip-load random walk per sample [N]
    /// (default: 0.5; with `--lab`, the tip force's largest change per sample, 2π f A h).
    #[arg(long, allow_negative_numbers = true)]
    pub load_step: Option<f64>,
    /// Time constant of the constant-gain baseline's tip-load model (Gauss–Markov) [s].
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
    pub load_time: f64,
    /// Directory for the CSV, plots and JSON.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
    /// The lab study instead of the twin: the scene's free ball (e.g. `paper`) under a
    /// wind-like tip force; truth with the ball free and with it locked.
    #[arg(long)]
    pub lab: bool,
    /// `--lab`: amplitude of the tip force [N] (at the scene's excitation frequency).
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub tip_force: f64,
    /// `--lab`: the tip force's frequency [Hz] (default: the scene's excitation frequency).
    #[arg(long, allow_negative_numbers = true)]
    pub frequency: Option<f64>,
}

/// Scene selection and the overrides of the model alone (`static`, `modes`, `tune`: no
/// excitation, duration or step, which they do not use).
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// `paper` (built in) or a scene TOML file (e.g. `scenes/mast-arm.toml`).
    #[arg(long, short, default_value = "paper")]
    pub scene: String,
    /// Solver (overrides the scene).
    #[arg(long, value_enum)]
    pub solver: Option<Solver>,
    /// Bodies (overrides the scene).
    #[arg(long, value_enum)]
    pub kind: Option<Kind>,
    /// Beam elements: core 1, 2, 3, 4, 6, 8 or 16; full any (overrides the scene).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Scalar (overrides the scene).
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
}

impl Default for ModelArgs {
    /// The paper's scene, nothing overridden (what the command line gives without options).
    fn default() -> Self {
        Self {
            scene: "paper".into(),
            solver: None,
            kind: None,
            elements: None,
            precision: None,
        }
    }
}

impl ModelArgs {
    /// The same selection as [`SceneArgs`] (no run overrides).
    pub fn scene_args(&self) -> SceneArgs {
        SceneArgs {
            model: self.clone(),
            ..SceneArgs::default()
        }
    }
}

/// Scene selection and overrides shared by all commands that run the model in time.
#[derive(Args, Debug, Clone, Default)]
pub struct SceneArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Harmonic excitation frequency [Hz] (overrides the scene).
    #[arg(long, allow_negative_numbers = true)]
    pub frequency: Option<f64>,
    /// Harmonic base amplitude [m] (overrides the scene; paper 0.5e-3).
    #[arg(long, allow_negative_numbers = true)]
    pub amplitude: Option<f64>,
    /// Simulated time [s] (overrides the scene).
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Time step h [s] (overrides the scene).
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
}

impl SceneArgs {
    /// Loads the scene and applies the overrides, then validates the result (a scene value that
    /// an override replaces is never held against it).
    pub fn load(&self) -> Result<Scene> {
        let spec = &self.model.scene;
        let s = self.apply(Scene::read(spec)?);
        if spec == "paper" {
            return s;
        }
        s.with_context(|| format!("scene `{spec}`"))
    }

    /// Applies the overrides to a loaded scene (`self.model.scene` is not read) and validates it
    /// ([`Overrides::apply`]).
    pub fn apply(&self, s: Scene) -> Result<Scene> {
        self.overrides().apply(s)
    }

    /// The overrides of these options.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            solver: self.model.solver,
            kind: self.model.kind,
            elements: self.model.elements,
            precision: self.model.precision,
            frequency: self.frequency,
            amplitude: self.amplitude,
            duration: self.duration,
            step: self.step,
        }
    }
}

/// `static`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: ModelArgs,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}

/// `modes`.
#[derive(Args, Debug)]
pub struct ModesArgs {
    #[command(flatten)]
    pub scene: ModelArgs,
    /// How many of the lowest frequencies to print.
    #[arg(long, default_value_t = 4)]
    pub count: usize,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}

/// `--ensemble` and `--seed` of `run`, `sweep` and `fatigue`.
#[derive(Args, Debug, Clone, Copy)]
pub struct EnsembleArgs {
    /// Runs of an ensemble: K runs from seeded perturbations of the ball's initial state
    /// (angle ± 0.1°, orbit rate ± 0.01 rad/s, uniform; member 0 is the scene itself), in
    /// parallel; every statistic is then reported as mean ± sd (min–max) over the K runs, and
    /// in JSON as {"mean", "sd", "min", "max", "k"}. 1 (the default): the plain run.
    #[arg(long, default_value_t = 1)]
    pub ensemble: usize,
    /// Seed of the ensemble's perturbations (the same seed gives the same members).
    #[arg(long, default_value_t = absorber_sim::ensemble::DEFAULT_SEED)]
    pub seed: u64,
}

impl EnsembleArgs {
    /// The checked ensemble.
    pub fn ensemble(&self) -> Result<absorber_sim::ensemble::Ensemble> {
        absorber_sim::ensemble::Ensemble::new(self.ensemble, self.seed)
    }
}

/// `run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub ensemble: EnsembleArgs,
    /// Output directory (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Plots to draw (default: the scene's `outputs.plots`).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub plots: Option<Vec<Plot>>,
    /// Write the CSV only.
    #[arg(long)]
    pub no_plots: bool,
    /// Write every n-th step to the CSV (default: the scene's `outputs.every`).
    #[arg(long)]
    pub every: Option<usize>,
    /// Transient left out of the FFT and the amplitudes [s] (default: `outputs.transient`).
    #[arg(long, allow_negative_numbers = true)]
    pub transient: Option<f64>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub ensemble: EnsembleArgs,
    /// Excitation frequencies [Hz] (default: the paper's 14, 3.50 … 4.70).
    #[arg(long, value_delimiter = ',', num_args = 1.., allow_negative_numbers = true)]
    pub freqs: Option<Vec<f64>>,
    /// Steady-state window: the last `LAST` seconds of each run [s] (default: the run after the
    /// transient `outputs.transient`, 20 s: the window `run` and `paper` call steady). Every
    /// column (amplitudes, impacts, flight fraction) is over this window.
    #[arg(long, allow_negative_numbers = true)]
    pub last: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Output directory (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Skip the PNG.
    #[arg(long)]
    pub no_plots: bool,
    /// Print the result as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `tune`.
#[derive(Args, Debug)]
pub struct TuneArgs {
    #[command(flatten)]
    pub scene: ModelArgs,
    /// Target ball / beam frequency ratio.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub ratio: f64,
    /// Write the scene with the tuned R (and name "tuned") to this TOML file (a `[ball]`
    /// scene; an `[arm]` scene only gets the ball it would need printed).
    #[arg(long)]
    pub write: Option<PathBuf>,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}

/// `paper`.
#[derive(Args, Debug, Default)]
pub struct PaperArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}

/// AASHTO detail category (command-line spelling).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Category {
    /// A
    A,
    /// B
    B,
    /// B′
    #[value(name = "b-prime")]
    BPrime,
    /// C
    C,
    /// C′
    #[value(name = "c-prime")]
    CPrime,
    /// D
    D,
    /// E
    E,
    /// E′ (fillet-welded mast-arm socket; default)
    #[value(name = "e-prime")]
    EPrime,
}

impl Category {
    /// The core's detail category.
    pub fn detail(self) -> DetailCategory {
        match self {
            Self::A => DetailCategory::A,
            Self::B => DetailCategory::B,
            Self::BPrime => DetailCategory::BPrime,
            Self::C => DetailCategory::C,
            Self::CPrime => DetailCategory::CPrime,
            Self::D => DetailCategory::D,
            Self::E => DetailCategory::E,
            Self::EPrime => DetailCategory::EPrime,
        }
    }
}

/// Root-moment estimate (command-line spelling).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Moment {
    /// Clamp reaction on the root slope coordinate (exact statics; default).
    Reaction,
    /// E I r″ at the root node (5.8 % low in statics with 3 elements).
    Curvature,
}

/// `fatigue`.
#[derive(Args, Debug)]
pub struct FatigueArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub ensemble: EnsembleArgs,
    /// Excitation frequencies [Hz] (default: the paper's 14, 3.50 … 4.70).
    #[arg(long, value_delimiter = ',', num_args = 1.., allow_negative_numbers = true)]
    pub freqs: Option<Vec<f64>>,
    /// Base amplitudes [m] (default: the scene's, paper 0.5e-3).
    #[arg(long, value_delimiter = ',', num_args = 1.., allow_negative_numbers = true)]
    pub amplitudes: Option<Vec<f64>>,
    /// AASHTO detail category of the root connection.
    #[arg(long, value_enum, default_value_t = Category::EPrime)]
    pub category: Category,
    /// Root-moment estimate.
    #[arg(long, value_enum, default_value_t = Moment::Reaction)]
    pub moment: Moment,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Also run the scene's model calibrated against the full solver with this many elements
    /// (as `calibrate` does) and the core with that many elements (3, 8 or 16), and write their
    /// damage rates side by side (`fatigue_calibrated.csv`, `fatigue_calibrated.png`).
    #[arg(long)]
    pub calibrate_against: Option<usize>,
    /// Output directory for fatigue.csv and fatigue.png (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Skip the PNG.
    #[arg(long)]
    pub no_plots: bool,
}

/// `calibrate`.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The calibrated scene file to write (TOML; `run`, `sweep`, `modes`, `static`, `fatigue`
    /// take it as is).
    #[arg(long, short)]
    pub out: PathBuf,
    /// Elements of the converged full-solver reference.
    #[arg(long, default_value_t = 16)]
    pub reference_elements: usize,
    /// Measured first beam frequency [Hz]: fit E·I to it (after the converged calibration).
    #[arg(long, allow_negative_numbers = true)]
    pub target_f1: Option<f64>,
    /// Measured first-mode damping ratio [-]: set the scene's damping (and, if its integrator
    /// alone damps more, a lower Newmark γ) so that the discrete mode has it.
    #[arg(long, allow_negative_numbers = true)]
    pub target_zeta: Option<f64>,
    /// The TOML written by `identify` (its f1 and zeta as the targets).
    #[arg(long, conflicts_with_all = ["target_f1", "target_zeta"])]
    pub from_identified: Option<PathBuf>,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}

/// `identify`.
#[derive(Args, Debug)]
pub struct IdentifyArgs {
    /// Measured record: CSV with a header row of column names (`#` comment lines allowed).
    #[arg(long)]
    pub csv: PathBuf,
    /// Column to identify (acceleration, velocity or displacement of the tip or root).
    #[arg(long, default_value = "tip_acceleration")]
    pub column: String,
    /// Time column [s] (uniformly sampled).
    #[arg(long, default_value = "t")]
    pub time_column: String,
    /// Free decay or ambient response (random decrement first).
    #[arg(long, value_enum, default_value_t = absorber_sim::identify::RecordKind::Decay)]
    pub record: absorber_sim::identify::RecordKind,
    /// Frequency band to look for the mode in, `lo,hi` [Hz] (default 0.1 Hz … a quarter of the
    /// sampling rate).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub band: Option<Vec<f64>>,
    /// Write the result as TOML here (for `calibrate --from-identified`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    pub json: bool,
}
