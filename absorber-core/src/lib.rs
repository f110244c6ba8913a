//! # absorber-core
//!
//! The embeddable reduced model of a **free pendulum vibration absorber** on a flexible
//! cantilever (Gumus & Ertas): a planar ANCF beam, a rigid tip mass welded to its end, and a
//! ball rolling without slip in a circular track inside the tip mass, between two stops.
//!
//! **Promise**: fixed step, no heap, no panic, bounded work. Every step does at most
//! [`Integrator::max_work`] units of work ([`work`]: assemblies, factorizations,
//! residuals, back-substitutions, counted across every solve of the step), allocates nothing,
//! and on failure returns an [`Error`] and leaves the state exactly as it was; a step that
//! reaches the cap is taken and flagged, and a run of failed steps restarts the model by itself
//! ([`Model::step`]). The crate is `#![no_std]` without `alloc`, generic over `f32`/`f64` and
//! over the number of elements `N`; scenes ([`Scene`]) leave out at compile time what they do
//! not contain.
//!
//! ```
//! use absorber_core::{FreeBallModel, Params};
//!
//! // Paper scene (Table 1), 3 elements, f32 as on a Cortex-M4F; start from static equilibrium.
//! let mut model: FreeBallModel<f32, 3, 13> = FreeBallModel::at_rest(Params::default(), 0.0)?;
//! let (amp, omega) = (0.5e-3f32, 2.0 * core::f32::consts::PI * 4.13);
//! for k in 1..=1000 {
//!     let t = k as f32 * 0.003;
//!     let base_accel = -amp * omega * omega * (omega * t).sin(); // from the accelerometer
//!     match model.step(base_accel) {
//!         Ok(report) => assert!(report.iterations <= 100),
//!         Err(e) => return Err(e), // state kept: log it, feed the next sample
//!     }
//! }
//! let deflection = model.tip_deflection(); // m, relative to the base
//! let (ball, _) = model.ball_relative_angle().unwrap_or((0.0, 0.0)); // rad
//! assert!(deflection < 0.0 && ball.abs() < 1.2);
//! # Ok::<(), absorber_core::Error>(())
//! ```
//!
//! # What the crate holds
//!
//! The model and its scenes:
//! - [`Model`]: the reduced model of a scene with `N` elements and `D` unknowns; [`Model::step`].
//! - [`BeamModel`], [`TipModel`], [`LockedBallModel`], [`FreeBallModel`]: the four basic scenes.
//! - [`Scene`]: what a scene contains, at compile time; [`BallKind`]: its ball.
//! - [`BeamOnly`], [`TipMass`], [`LockedBall`], [`FreeBall`]: the basic scenes.
//! - [`FreeBallNoFlight`], [`FreeBallNoStops`]: the free ball without flight, without stops.
//! - [`Loaded`], [`Arm`]: a scene with loads on the beam, on a real arm's sections.
//! - [`Lean`], [`AtStepEnd`]: a scene without the code of rules its runs never use, and also
//!   without that of events at their crossings (the firmware's scenes).
//! - [`Loads`], [`PointMass`], [`ArmParams`]: loads on the beam and an arm's sections ([`loads`]).
//!
//! Parameters:
//! - [`Params`]: everything a model is built from ([`BeamParams`], [`TipParams`],
//!   [`BallParams`], [`Damping`], [`Calibration`], [`Integrator`]).
//! - [`NewtonKind`], [`AtCap`], [`EventLocation`], [`ImpactModel`]: the integrator's choices.
//!
//! State and step report:
//! - [`State`]: everything needed to continue a run; [`Contact`], [`Side`], [`Flight`]: the ball.
//! - [`StepReport`]: what one step did; [`Impact`], [`Landing`], [`EventCounts`], [`Outcome`].
//! - [`MAX_BASE_ACCEL`], [`RESTART_AFTER`], [`RESTART_INCREMENT`]: the input and restart limits.
//! - [`Workspace`]: the Newton matrices a model keeps; [`work`]: the work units of a step.
//! - [`Energies`], [`ContactForces`]: outputs of a state.
//! - [`Error`]: why a step or a start failed.
//!
//! On the model: [`monitor`] (stress, rainflow, fatigue, indicators, impacts) and
//! [`estimator`] (the state and load estimators). [`Real`] and [`scalar`]: `f32` or `f64`.
//!
//! Conventions (frames, units, the choices the paper leaves open) are in `docs/model.md`.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

mod energy;
mod error;
pub mod estimator;
pub mod loads;
mod model;
mod modes;
pub mod monitor;
mod outputs;
mod params;
pub mod scalar;
mod scene;
#[doc(hidden)]
pub mod shared;
mod state;
mod step;
pub mod work;

pub use energy::Energies;
pub use error::Error;
pub use loads::{ArmParams, Loads, PointMass};
pub use model::Model;
pub use outputs::ContactForces;
pub use params::{
    AtCap, BallParams, BeamParams, Calibration, Damping, EventLocation, ImpactModel, Integrator,
    NewtonKind, Params, TipParams,
};
pub use scalar::Real;
pub use scene::{
    Arm, AtStepEnd, BallKind, BeamOnly, FreeBall, FreeBallNoFlight, FreeBallNoStops, Lean, Loaded,
    LockedBall, Scene, TipMass,
};
pub use state::{
    Contact, EventCounts, Flight, Impact, Landing, Outcome, Side, State, StepReport,
    MAX_BASE_ACCEL, RESTART_AFTER, RESTART_INCREMENT,
};
pub use step::newton::Workspace;

/// Beam alone, `N` elements, `D = 4N` unknowns.
pub type BeamModel<T, const N: usize, const D: usize> = Model<T, BeamOnly, N, D>;
/// Beam + tip mass, `D = 4N`.
pub type TipModel<T, const N: usize, const D: usize> = Model<T, TipMass, N, D>;
/// Beam + tip mass + locked ball (passive), `D = 4N`.
pub type LockedBallModel<T, const N: usize, const D: usize> = Model<T, LockedBall, N, D>;
/// Beam + tip mass + free ball with stops (the paper's absorber), `D = 4N + 1`.
pub type FreeBallModel<T, const N: usize, const D: usize> = Model<T, FreeBall, N, D>;
