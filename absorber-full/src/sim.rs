//! The common face of the two solvers (the embedded core and the full solver), so that every
//! command, report and test can run either one.

use absorber_core::{Energies, Error, Impact, StepReport};

/// What a solver shows after a step. SI units; angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// Time \[s\].
    pub time: f64,
    /// Vertical deflection of the beam end A relative to the base (static sag included) \[m\].
    pub tip_deflection: f64,
    /// Its rate \[m/s\].
    pub tip_velocity: f64,
    /// Its acceleration relative to the base \[m/s²\] (the integrator's `a` at the step's end).
    pub tip_acceleration: f64,
    /// Tip mass rotation ψ \[rad\].
    pub tip_angle: f64,
    /// ψ̇ \[rad/s\].
    pub tip_rate: f64,
    /// Ball orbit angle θ from the downward vertical (NaN without a ball) \[rad\].
    pub ball_angle: f64,
    /// θ̇ \[rad/s\].
    pub ball_rate: f64,
    /// Relative ball angle α = θ − ψ (NaN without a ball) \[rad\].
    pub ball_relative_angle: f64,
    /// α̇ \[rad/s\].
    pub ball_relative_rate: f64,
}

/// A solver that advances a scene by fixed steps driven by the base acceleration.
pub trait Simulator: Send {
    /// Advances one step to the base acceleration `base_accel` at the end of the step \[m/s²\].
    /// On error the state is unchanged.
    fn step(&mut self, base_accel: f64) -> Result<StepReport<f64>, Error>;
    /// The current outputs.
    fn observe(&self) -> Observation;
    /// Energies for the base moving at `base_velocity` and displaced by `base_displacement`.
    fn energies(&self, base_velocity: f64, base_displacement: f64) -> Energies<f64>;
    /// Natural frequencies about the static equilibrium, ascending \[Hz\].
    fn natural_frequencies(&self) -> Result<Vec<f64>, Error>;
    /// Static tip deflection \[m\].
    fn static_tip_deflection(&self) -> f64;
    /// The track's force on the ball, `(N, F_t)` \[N\]: normal (negative: the track would have
    /// to pull) and tangential (rolling friction, plus a stop's reaction while the ball rests
    /// on it); `absorber_core::ContactForces`. `None` without a free ball.
    fn contact_forces(&self) -> Option<(f64, f64)>;
    /// The ball flies inside the housing (`absorber-core/src/step/flight`; false without a free ball or
    /// for a solver that keeps it on the track).
    fn in_flight(&self) -> bool {
        false
    }
    /// Short name of the solver ("core" or "full").
    fn solver_name(&self) -> &'static str;
    /// At the start of a run (the ball rolling, the housing at rest): sets the ball's orbit
    /// rate θ̇ to `rate` \[rad/s\] (its spin rate `φ̇ = −(ρ/r_b) θ̇`) and the consistent
    /// acceleration. No effect without a free ball.
    fn set_ball_rate(&mut self, rate: f64) -> Result<(), Error>;
}

/// Impacts are reported in the step report.
pub type ImpactEvent = Impact<f64>;
