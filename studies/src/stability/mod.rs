//! Numerical stability on stiff and extreme cases (`absorber-studies stability`, `docs/stability.md`).
//!
//! Every case runs one solver (the embedded core in `f32` or `f64`, or the full solver) from
//! its static equilibrium under a base acceleration sequence and checks, after every step:
//!
//! - **Bounded energy.** In the frame moving with the base the only energy source is the
//!   inertial force `−m ÿ_b`, whose power is `−ÿ_b p_y` (`p_y`: vertical momentum relative to
//!   the base). The base's work is `W(t) = −∫ ÿ_b p_y dt` (trapezoid over the steps). Newmark
//!   with γ ≥ ½ and the stop impacts only dissipate, so the relative energy
//!   `E = energies(0, 0).total()` must satisfy `E(t) − E(0) ≤ W(t) + ε`. The reported *margin*
//!   is `max_t (E − E₀ − W) / scale`, `scale = max_t max(|E − E₀|, |W|)`: negative or at the
//!   rounding level (≤ [`MARGIN_TOL`]) passes. On a loaded arm W also holds the work of the
//!   applied loads, `Σ Δqᵀ⟨F⟩` minus generalized-α's filter term (docs/model.md, "Energy
//!   balance of a step").
//! - **No NaN**: every coordinate, velocity and acceleration stays finite.
//! - **Newton iterations** per step (max, mean).
//! - **Failures are clear errors**: a step that fails returns an [`absorber_core::Error`] and
//!   leaves the state bit for bit as it was (checked), a panic is caught and reported as a
//!   failure of the case.
//!
//! [`matrix`] is the list of cases, [`run_case`] runs one, [`drift()`] compares the `f32` and the
//! `f64` core over a long run, [`report()`] writes the Markdown page.

use absorber_core::{
    Arm, ArmParams, BeamOnly, Error, FreeBall, ImpactModel, Loads, LockedBall, Model, NewtonKind,
    Params, Real, Scene, StepReport,
};
use absorber_full::sim::Simulator;
use absorber_full::{FullSolver, SceneKind};
use absorber_sim::wind::{LoadComponent, LoadModel};
use std::fmt::Write as _;
use std::time::Instant;

mod cases;
mod command;
mod drift;
mod probe;
mod report;
mod run;

pub use cases::*;
pub use command::*;
pub use drift::*;
pub use probe::*;
pub use report::*;
pub use run::*;

/// Largest accepted energy margin `max (E − E₀ − W) / scale` after the start-up
/// ([`STARTUP`]): Newton residue and time discretization of the trapezoidal work.
pub const MARGIN_TOL: f64 = 1e-4;
/// Largest accepted margin during the start-up: the ball is released 1° off its equilibrium
/// from a static state, which rings the stiff axial/slope modes (ωh ≫ 1) for a few steps;
/// Newmark's energy identity holds for a linear system only, and for these nonlinear stiff
/// modes the first steps can gain up to ~1e-3 of the run's energy scale before γ > ½ damps them.
pub const STARTUP_TOL: f64 = 5e-3;
/// Length of the start-up \[s\].
pub const STARTUP: f64 = 0.1;

/// Which solver and scalar runs a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The embedded core in `f32`.
    CoreF32,
    /// The embedded core in `f64`.
    CoreF64,
    /// The full solver (`f64`).
    Full,
}

impl Engine {
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Engine::CoreF32 => "core f32",
            Engine::CoreF64 => "core f64",
            Engine::Full => "full f64",
        }
    }
}

/// The base acceleration sequence ÿ_b(t_k), t_k = k h.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// y_b = A sin(2π f t): ÿ_b = −A (2π f)² sin(2π f t).
    Harmonic {
        /// Amplitude \[m\].
        amplitude: f64,
        /// Frequency \[Hz\].
        frequency: f64,
    },
    /// Harmonic plus deterministic pseudo-random sensor noise (uniform, ±`noise` m/s²) and a
    /// spike of `spike` m/s² every `spike_every` steps (0: none).
    Noisy {
        /// Amplitude \[m\].
        amplitude: f64,
        /// Frequency \[Hz\].
        frequency: f64,
        /// Noise half-width \[m/s²\].
        noise: f64,
        /// Spike height \[m/s²\].
        spike: f64,
        /// Steps between spikes (0: no spikes).
        spike_every: usize,
    },
    /// Explicit samples ÿ_b(t_k), k = 0, 1, … (held at the last value).
    Samples(Vec<f64>),
}

impl Input {
    /// ÿ_b at grid point `k` with step `h`.
    pub fn at(&self, k: usize, h: f64) -> f64 {
        let harmonic = |a: f64, f: f64| {
            let w = std::f64::consts::TAU * f;
            -a * w * w * (w * k as f64 * h).sin()
        };
        match self {
            Input::Harmonic {
                amplitude,
                frequency,
            } => harmonic(*amplitude, *frequency),
            Input::Noisy {
                amplitude,
                frequency,
                noise,
                spike,
                spike_every,
            } => {
                let mut x = (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
                x ^= x >> 31;
                x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
                x ^= x >> 29;
                let u = (x >> 11) as f64 / (1u64 << 53) as f64; // [0, 1)
                let s = if *spike_every > 0 && k > 0 && k.is_multiple_of(*spike_every) {
                    *spike
                } else {
                    0.0
                };
                harmonic(*amplitude, *frequency) + noise * (2.0 * u - 1.0) + s
            }
            Input::Samples(v) => v.get(k).or(v.last()).copied().unwrap_or(0.0),
        }
    }

    fn describe(&self) -> String {
        match self {
            Input::Harmonic {
                amplitude,
                frequency,
            } => format!("{} mm, {} Hz", amplitude * 1e3, frequency),
            Input::Noisy {
                amplitude,
                frequency,
                noise,
                spike,
                spike_every,
            } => {
                let mut s = format!(
                    "{} mm, {} Hz + ±{noise} m/s² noise",
                    amplitude * 1e3,
                    frequency
                );
                if *spike_every > 0 {
                    let _ = write!(s, " + {spike} m/s² spike every {spike_every} steps");
                }
                s
            }
            Input::Samples(v) => format!("{} samples", v.len()),
        }
    }
}

/// Scene of a case (the core is instantiated for these).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bodies {
    /// Free ball with stops (the paper's absorber).
    Free,
    /// Locked ball (passive).
    Locked,
    /// A real arm without absorber: tapered tube and heads ([`ArmCase`]) under its loads.
    Arm,
}

/// A real arm under wind and traffic loads: the sections and heads of a scene's `[arm]` and the
/// loads of its `[[loads]]` (tip force and line load per element, sampled at every step).
#[derive(Clone, Debug)]
pub struct ArmCase {
    /// Tube and point masses.
    pub arm: ArmParams<f64>,
    /// The loads.
    pub loads: LoadModel,
}

/// What a case should do.
#[derive(Clone, Debug, PartialEq)]
pub enum Expect {
    /// Run to the end, bounded and finite.
    Bounded,
    /// Fail with a clear error whose message contains this text (construction or step).
    Error(&'static str),
}

/// One case of the matrix.
#[derive(Clone, Debug)]
pub struct Case {
    /// Group: baseline, stiff, extreme, input, long.
    pub group: &'static str,
    /// What is varied.
    pub name: String,
    /// Solver and scalar.
    pub engine: Engine,
    /// Scene.
    pub bodies: Bodies,
    /// Beam elements.
    pub elements: usize,
    /// Parameters (f64; rounded for f32).
    pub params: Params<f64>,
    /// Base acceleration.
    pub input: Input,
    /// Simulated time \[s\].
    pub duration: f64,
    /// Expected outcome.
    pub expect: Expect,
    /// Why the case is there or what it shows (optional note for the table).
    pub note: &'static str,
    /// A failure already understood and reported (bug outside this module): the case is shown
    /// as failing but does not fail the command.
    pub known_issue: Option<&'static str>,
    /// The arm and its loads ([`Bodies::Arm`] only).
    pub arm: Option<ArmCase>,
}

/// What a case did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    /// Steps done successfully.
    pub steps: usize,
    /// Steps asked for.
    pub steps_total: usize,
    /// The error that stopped the run (construction or step), if any.
    pub error: Option<String>,
    /// The failed step left the state bit for bit unchanged (`None`: no step failed).
    pub state_kept: Option<bool>,
    /// The case panicked (a bug).
    pub panicked: bool,
    /// No NaN or infinity in the state after any step.
    pub finite: bool,
    /// `max (E − E₀ − W) / scale` after the start-up.
    pub margin: f64,
    /// `max (E − E₀ − W) / scale` during the start-up (t ≤ [`STARTUP`]).
    pub margin_startup: f64,
    /// `max(|E − E₀|, |W|)` over the run \[J\].
    pub scale: f64,
    /// `max (E − E₀ − W)` after the start-up \[J\].
    pub excess: f64,
    /// `max (E − E₀ − W)` during the start-up \[J\].
    pub excess_startup: f64,
    /// When the largest excess happened \[s\].
    pub excess_at: f64,
    /// Rounding floor of the energy: 64 ε_T Σ|components of E₀| \[J\] (ε_T of the scalar).
    pub floor: f64,
    /// Largest Newton iteration count of a step.
    pub max_iterations: u32,
    /// Mean Newton iterations per step.
    pub mean_iterations: f64,
    /// Stop impacts.
    pub impacts: usize,
    /// Largest |tip deflection − static deflection| \[m\].
    pub max_tip: f64,
    /// Largest |α| (ball relative angle) \[rad\] (NaN without a free ball).
    pub max_alpha: f64,
    /// Wall time \[s\].
    pub seconds: f64,
    /// The energy margins were measured (every solver on every case: a solver without a
    /// [`Balance`] could not run an arm's loads through the check).
    pub energy_checked: bool,
    /// The work `W` of the base and the applied loads at the end of the run \[J\].
    pub work: f64,
}

impl Outcome {
    /// Did the case do what it was expected to?
    pub fn passes(&self, expect: &Expect) -> bool {
        if self.panicked || !self.finite {
            return false;
        }
        match expect {
            Expect::Bounded => {
                self.error.is_none()
                    && self.steps == self.steps_total
                    && (!self.energy_checked
                        || (self.excess <= MARGIN_TOL * self.scale + self.floor
                            && self.excess_startup <= STARTUP_TOL * self.scale + self.floor))
            }
            Expect::Error(text) => {
                self.error.as_deref().is_some_and(|e| e.contains(text))
                    && self.state_kept != Some(false)
            }
        }
    }
}

/// A running solver as the checks see it.
pub trait Probe {
    /// One step to base acceleration `a`.
    fn step(&mut self, a: f64) -> Result<StepReport<f64>, Error>;
    /// One step to base acceleration `a` with the loads `tip` \[N\] and `line` (per element,
    /// \[N/m\]) held at the end of the step (an error for a solver without loads).
    fn step_loaded(&mut self, a: f64, tip: f64, line: &[f64]) -> Result<StepReport<f64>, Error>;
    /// Relative energy `energies(0, 0).total()` \[J\].
    fn energy(&self) -> f64;
    /// Vertical momentum relative to the base \[kg·m/s\].
    fn momentum(&self) -> f64;
    /// `½ aᵀ M a`, the kinetic energy the accelerations would have as velocities \[J/s²\].
    fn accel_energy(&self) -> f64;
    /// Σ |components| of the energy \[J\] (what rounding acts on).
    fn energy_magnitude(&self) -> f64;
    /// Machine epsilon of the scalar.
    fn epsilon(&self) -> f64;
    /// The state as bits (to check that a failed step kept it), and whether it is finite.
    fn bits(&self) -> (Vec<u64>, bool);
    /// Tip deflection relative to the base, static sag included \[m\].
    fn tip(&self) -> f64;
    /// Static tip deflection \[m\].
    fn static_tip(&self) -> f64;
    /// Ball relative angle α \[rad\] (NaN without a free ball).
    fn alpha(&self) -> f64;
    /// The ingredients of the load work and of generalized-α's energy balance (docs/model.md,
    /// "Energy balance of a step"), in the solver's own coordinates; `None` for a solver without
    /// them (its loaded runs are then not energy-checked).
    fn balance(&self) -> Option<&dyn Balance> {
        None
    }
}

/// What the energy check of a loaded arm needs beyond [`Probe`]'s energy.
pub trait Balance {
    /// Generalized coordinates `q`.
    fn coordinates(&self) -> Vec<f64>;
    /// `a − q̈`: generalized-α's acceleration-like variable minus the acceleration (zero for
    /// Newmark).
    fn filter_lag(&self) -> Vec<f64>;
    /// Generalized force of a tip force `tip` \[N\] and the line loads `line` \[N/m\] per
    /// element (the vectors the step adds to its residual).
    fn load_vector(&self, tip: f64, line: &[f64]) -> Vec<f64>;
    /// `xᵀ M y` with the model's mass matrix.
    fn mass_inner(&self, x: &[f64], y: &[f64]) -> f64;
    /// `½ aᵀ M a` of the acceleration-like variable `a` of the scheme \[J/s²\].
    fn pseudo_accel_energy(&self) -> f64;
}

#[cfg(test)]
mod tests;
