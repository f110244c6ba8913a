//! The Newton solve's limits (the solve itself: [`crate::step::newton`]): the trust radius of a
//! correction, the damping trials of an iteration, when a reused matrix has converged or must be
//! refreshed, and how long factors kept from an earlier step may be reused.

/// Trust radius of a Newton correction, in units of the beam length for positions and in
/// radians for slopes and angles: a correction beyond it is damped (`damping` in the Newton solve), never
/// below it. A linearization about a state with a large (transient) axial force can be nearly
/// singular in bending, and its raw correction would leave the physical range.
pub const MAX_STEP: f64 = 0.05;

/// Most damping factors tried per Newton iteration (λ = 1, ½, …, 1/2048), each one residual and one
/// back-substitution: the work per iteration stays bounded.
pub const DAMPING_TRIALS: u32 = 12;

/// A reused matrix's iteration is converged when its estimated remaining error
/// `θ/(1−θ)‖dx‖` is below `SETTLE · tolerance` (but not below `8ε`, the rounding floor of the
/// scalar), and `‖dx‖` below the tolerance.
pub const SETTLE: f64 = 1e-4;

/// A reused matrix whose correction contracted by less than this factor is refreshed at the
/// next iteration (the correction itself is taken when it contracts by half).
pub const SLOW: f64 = 0.25;

/// Most iterations a Newton solve gives the factors kept from an earlier step (modified
/// Newton): a solve that has not converged after this many refreshes at the next iteration.
/// Why: near the rounding floor of `f32` (the settled test asks for `8ε` there) a kept matrix's
/// corrections stop contracting steadily (θ = 0.13, 0.20, 0.23, 0.19, 0.31 in the paper run's
/// hardest step), and each further reused iteration costs [`crate::work::RESIDUAL`] +
/// [`crate::work::SOLVE`] = 6 units against a refresh's 17, which converges at once from there. Five
/// reused iterations (30 units, the correction contracted by about 0.2⁵ ≈ 3e-4) bound a
/// rolling step at 47 units: the paper run's hardest step took six and a refresh, 53
/// (`docs/embedded.md`, "Firmware defaults"). Factors built in the same step (every
/// `PerStep` reuse) are not limited.
pub const KEPT_ITERATIONS: u32 = 5;
