//! Work units of the operations a step is made of ([`crate::Integrator::max_work`] caps their
//! sum per step). The weights follow the operations' measured costs on a Cortex-M4F, each with
//! the Newton iteration's own code around it (free ball, N = 3, `f32`: a back-substitution 468
//! instructions, a residual 1,846 and about 400 for the iteration, an assembly with its banded
//! factorization 6,992 and the same 400; `docs/embedded.md`), so that one unit is about 460
//! instructions whatever the operation.

/// A back-substitution with the current factors.
pub const SOLVE: u32 = 1;
/// A residual of the equations of motion (a reused matrix's iteration, a damping trial).
pub const RESIDUAL: u32 = 5;
/// An assembly of the residual and the Newton matrix, and its banded factorization.
pub const REFRESH: u32 = 16;
/// The pivoting fallback on top of a refresh: the assembly again and the dense LU with
/// partial pivoting (`step::linalg`). Only without a cap ([`UNLIMITED`]): under a cap a
/// matrix the banded LU refuses stops the solve at the cap instead.
pub const FALLBACK: u32 = 32;
/// Units the Newmark solves of a step leave to the events at its end: the back-substitutions
/// of a stop's and a landing's impulse in the trial's own factors (an event that needs a
/// matrix of its own, a plastic landing, charges it against the rest of the cap).
pub const RESERVE: u32 = 2 * SOLVE;
/// The event tests of a step that starts with the ball in flight (where the ball is
/// against the circle and the stops: square roots, arc tangents, cubic roots), charged
/// before the step's solves: about 1,900 instructions on the M4F.
pub const FLIGHT_TESTS: u32 = 4;
/// Units a split at an event's crossing needs beyond the trial step (a sub-step, the
/// impulse metric, the consistent acceleration and the rest of the step, each with a refresh
/// and a few iterations); a step that cannot afford it puts the event at its end.
pub const SPLIT: u32 = 4 * REFRESH + 8 * (RESIDUAL + SOLVE);
/// A restart of the model ([`crate::Model::step`], "Recovery": the failed step's state put
/// back, the start state with the input's consistent acceleration, about 1,300 instructions
/// on the M4F), reserved in advance: a step that restarts the model if it fails or is capped
/// runs with its cap lower by this much, so that the restart too stays within the cap.
pub const RESTART: u32 = 3;
/// The firmware's cap with events at the step end (`docs/embedded.md`): what the paper's
/// free ball needs in its hardest step, so that its input is never capped, and no more.
pub const DEADLINE: u32 = 48;
/// The smallest cap a model accepts: the event tests of a step ([`FLIGHT_TESTS`] or a
/// ball's release test, a residual), one refreshed Newton iteration and the reserve.
pub const MIN_CAP: u32 = RESIDUAL + REFRESH + SOLVE + RESERVE;
/// No cap (the default): about the work the iteration limits alone allow (five solves of 100
/// iterations with 12 damping trials each).
pub const UNLIMITED: u32 = 50_000;
