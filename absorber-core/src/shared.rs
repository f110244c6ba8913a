//! The element and tip code the full solver shares; not API. What the other crates of the
//! workspace (the full solver, the host tools and the core's own tests) take from the step's
//! machinery, each item re-exported by name.

pub use crate::error::{END_BEYOND_STOP, START_BEYOND_STOP};
pub use crate::step::ancf::{AxialQuadrature, Element, ElementMatrix, ElementVector};
pub use crate::step::beam::{gather, global_index, Beam};
pub use crate::step::convergence::{DAMPING_TRIALS, KEPT_ITERATIONS, MAX_STEP, SETTLE, SLOW};
pub use crate::step::flight::roots::{
    bounce_impulse, hermite_root, landing_bounces, separation_fraction, GRAZING,
};
pub use crate::step::linalg::PIVOT_RATIO;
pub use crate::step::scheme::{AlphaRecursion, Chain};

/// The tip body and ball on the local coordinates (the core's residual of them, its kinematics
/// and inertia).
pub mod tip {
    pub use crate::step::tip::{residual, BallMode, LocalState, TipInertia, D5, LOCAL};
}

/// The single-precision sine and cosine of the step path, and the constants of its argument
/// reduction.
pub mod trig {
    pub use crate::step::trig::{sincosf, FAST_LIMIT, FRAC_PI_2_Q62, TWO_OVER_PI_BITS};
}
