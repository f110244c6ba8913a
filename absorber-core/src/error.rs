//! Errors as values: nothing in this crate panics on a user's input.

use core::fmt;

/// What went wrong. Every fallible call of the crate returns this.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is out of range; `field` names it as in [`crate::Params`]. Its value is
    /// [`crate::Params::value_of`]`(field)` of the parameters that were checked (the error
    /// stays two static strings: no number to format on a target without a formatter).
    InvalidParameter {
        /// Dotted path of the field, e.g. `"beam.modulus"`.
        field: &'static str,
        /// Why it was rejected: the allowed range or the rule.
        reason: &'static str,
    },
    /// The step input (base acceleration) is NaN or infinite. The state is unchanged.
    NonFiniteInput,
    /// The step input is finite but beyond [`crate::MAX_BASE_ACCEL`] (a sensor or wiring
    /// fault, not a motion the model can represent). The state is unchanged.
    InputOutOfRange,
    /// Newton did not reach the tolerance within the iteration budget. The state is unchanged.
    NoConvergence {
        /// Iterations done (= the budget).
        iterations: u32,
        /// Last scaled position increment (dimensionless, see [`crate::Integrator::tolerance`]).
        increment: f64,
    },
    /// A value became NaN or infinite during the step (divergence). The state is unchanged.
    NonFiniteState,
    /// A linear system was singular (e.g. a zero mass). The state is unchanged.
    Singular,
    /// The step's work cap ([`crate::Integrator::max_work`]) was reached by an operation that
    /// cannot stop early (an impulse's back-substitution, the pivoting fallback). The state is
    /// unchanged.
    WorkCap,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidParameter { field, reason } => write!(f, "invalid parameter `{field}`: {reason}"),
            Error::NonFiniteInput => write!(f, "base acceleration is not finite; state kept"),
            Error::InputOutOfRange => write!(
                f,
                "base acceleration beyond ±{:.0} m/s² (a sensor fault, not a motion); state kept",
                crate::state::MAX_BASE_ACCEL
            ),
            Error::NoConvergence { iterations, increment } => write!(
                f,
                "Newton did not converge in {iterations} iterations (last increment {increment:.3e}); state kept"
            ),
            Error::NonFiniteState => write!(f, "state became non-finite (divergence); state kept"),
            Error::Singular => write!(f, "singular system matrix; state kept"),
            Error::WorkCap => write!(f, "the step's work cap was reached; state kept"),
        }
    }
}

impl core::error::Error for Error {}

/// The start error when the beam end tilts beyond a stop at static equilibrium (both solvers).
pub const END_BEYOND_STOP: Error = Error::InvalidParameter {
    field: "ball.stop_angle",
    reason: "the beam end tilts beyond the stop at static equilibrium (a start with the ball resting on a stop is not supported)",
};

/// The start error when the initial ball angle lies beyond a stop (both solvers).
pub const START_BEYOND_STOP: Error = Error::InvalidParameter {
    field: "ball.initial_angle",
    reason: "puts the ball beyond a stop relative to the tilted housing",
};
