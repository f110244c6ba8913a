//! What a step reads and writes: the state ([`State`], the ball's [`Contact`] and, in flight,
//! its centre [`Flight`]), the step's report ([`StepReport`]: its [`Impact`], [`Landing`],
//! [`EventCounts`] and [`Outcome`]) and the limits on a step's input and on the restart rule.

use crate::scalar::{is_positive, Real};
use nalgebra::SVector;

/// Largest base acceleration a step accepts, |ÿ_b| \[m/s²\] (≈ 1000 g): a finite sample beyond
/// it is a sensor or wiring fault, not a motion the model can represent.
pub const MAX_BASE_ACCEL: f64 = 1.0e4;

/// Where the free ball is: rolling on the track (off the stops or resting on one), or flying.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Ball on the track, off the stops (or no stops / no free ball).
    Off,
    /// Ball resting on the stop at `+φ_max` (`Positive`) or `−φ_max` (`Negative`).
    OnStop(Side),
    /// Ball in flight inside the housing (`flight`; its centre is the state's
    /// [`State::flight`]).
    InFlight,
    /// Ball rolling on the arc beyond the stops: it flew over one and landed there
    /// (`flight`); the stops act on it from their other face.
    Beyond,
}

/// Which stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Relative angle θ − ψ = +φ_max.
    Positive,
    /// Relative angle θ − ψ = −φ_max.
    Negative,
}

impl Side {
    /// The side of a relative angle: positive for `α > 0`, else negative.
    pub(crate) fn of<T: Real>(alpha: T) -> Self {
        if alpha > T::zero() {
            Side::Positive
        } else {
            Side::Negative
        }
    }

    /// +1 or −1.
    pub fn sign<T: Real>(self) -> T {
        match self {
            Side::Positive => T::one(),
            Side::Negative => -T::one(),
        }
    }
}

/// The full dynamic state: everything needed to continue a run. `D` = number of unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State<T, const D: usize> {
    /// Displacements of the free nodal coordinates from the straight reference \[m, -\], then
    /// the ball's spin angle φ \[rad\] (free-ball scenes; paper eq. 28).
    pub q: SVector<T, D>,
    /// Velocities relative to the base.
    pub v: SVector<T, D>,
    /// Accelerations relative to the base.
    pub a: SVector<T, D>,
    /// The generalized-α scheme's acceleration-like variable `a_n` (Arnold & Brüls 2007;
    /// [`crate::Integrator`]). Newmark's method never reads it (it equals `a` there); after an
    /// impact or a start it restarts at `a` (a state given to `set_state` keeps its own).
    pub pseudo_accel: SVector<T, D>,
    /// Time since the start \[s\], `steps · h` (not a running sum: in `f32` adding 3 ms to an
    /// hour drifts by tens of seconds).
    pub time: T,
    /// Whole steps taken since the start.
    pub steps: u64,
    /// Base acceleration ÿ_b of the last step (the input at `time`) \[m/s²\].
    pub base_accel: T,
    /// Track and stop contact.
    pub contact: Contact,
    /// The flying ball's centre (read only while `contact` is [`Contact::InFlight`]).
    pub flight: Flight<T>,
}

/// A stop impact that happened during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impact<T> {
    /// Time of the impact \[s\].
    pub time: T,
    /// Which stop.
    pub side: Side,
    /// Relative angular speed θ̇ − ψ̇ before the impact \[rad/s\].
    pub relative_speed: T,
    /// Contact impulse on the ball along the track, Λ/ρ \[N·s\].
    pub impulse: T,
    /// Kinetic energy dissipated, ½(1−e²)Ġ²/(∇G M⁻¹ ∇Gᵀ) \[J\].
    pub energy_loss: T,
    /// The ball stayed on the stop (plastic, compressive contact).
    pub stuck: bool,
}

/// How a step ended ([`StepReport::outcome`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Outcome {
    /// Every Newton solve of the step reached the tolerance.
    #[default]
    Converged,
    /// A Newton solve stopped at the work cap ([`crate::Integrator::max_work`]) and its
    /// iterate was taken: the step is inexact (its `increment` says by how much, in the
    /// tolerance's units).
    Capped,
    /// The model restarted itself after [`RESTART_AFTER`] failed or capped steps in a row
    /// (this one included): at rest at the static equilibrium, the ball at its initial angle,
    /// with the consistent acceleration of this step's input; the clock counts every sample.
    Restarted,
}

/// Failed steps, or steps capped far from convergence, in a row after which a step restarts the
/// model ([`crate::Model::step`]).
pub const RESTART_AFTER: u32 = 3;
/// A capped step whose last Newton correction is at most this many tolerances is near
/// convergence: it ends a run of failed steps instead of extending it ([`crate::Model::step`]).
pub const RESTART_INCREMENT: f64 = 100.0;

/// Work units as reported ([`StepReport::work`]): saturated at `u16::MAX`.
pub(crate) fn units(used: u32) -> u16 {
    u16::try_from(used).unwrap_or(u16::MAX)
}

/// How many events of each kind a step had. A step can hold more than one (a bounce and a
/// stop hit in the rest of the step, a landing and a take-off at the step's end); the report's
/// `impact` and `landing` describe one of them, these count all. Bytes: a step holds a few
/// events at most (each sub-step of the step ends at one), and the report stays small enough
/// to be moved inline (at most 64 B on a Cortex-M4F; larger, every copy is a `memcpy` call).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EventCounts {
    /// Take-offs from the track (with `ball.lift_height` > 0: flights, once they rise above
    /// it; `flight`, "Counted").
    pub separations: u8,
    /// Landings on the track (bounces and rolling landings; with `ball.lift_height` > 0, of
    /// the counted flights).
    pub landings: u8,
    /// The landings that bounced (the ball flew on).
    pub bounces: u8,
    /// Stop impacts (on the track and in flight, a plastic return onto the stop included).
    pub impacts: u8,
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport<T> {
    /// Newton iterations used, summed over the sub-solves of the step.
    pub iterations: u32,
    /// Largest final scaled position increment of the Newton solves \[-\].
    pub increment: T,
    /// Stop impact within the step, if any (on the track or in flight).
    pub impact: Option<Impact<T>>,
    /// Time at which the ball left the track within the step, if it did \[s\].
    pub separation: Option<T>,
    /// Landing on the track within the step, if any (the last one).
    pub landing: Option<Landing<T>>,
    /// Work units the step used ([`crate::work`]; at most
    /// [`crate::Integrator::max_work`], and shown saturated at 65,535: the unlimited cap of
    /// the host's default is [`crate::work::UNLIMITED`], 50,000).
    pub work: u16,
    /// Whether the step converged, was capped or restarted the model.
    pub outcome: Outcome,
    /// How many separations, landings and stop impacts the step had.
    pub events: EventCounts,
}

impl<T: Real> StepReport<T> {
    /// The report in `f64` (exact from `f32`), for host tools comparing precisions.
    pub fn to_f64(&self) -> StepReport<f64> {
        let f = crate::scalar::to_f64::<T>;
        StepReport {
            iterations: self.iterations,
            increment: f(self.increment),
            impact: self.impact.map(|i| Impact {
                time: f(i.time),
                side: i.side,
                relative_speed: f(i.relative_speed),
                impulse: f(i.impulse),
                energy_loss: f(i.energy_loss),
                stuck: i.stuck,
            }),
            separation: self.separation.map(f),
            landing: self.landing.map(|l| Landing {
                time: f(l.time),
                normal_speed: f(l.normal_speed),
                normal_impulse: f(l.normal_impulse),
                tangential_impulse: f(l.tangential_impulse),
                bounced: l.bounced,
            }),
            work: self.work,
            outcome: self.outcome,
            events: self.events,
        }
    }
}

/// The ball's centre while it flies, in the frame translating with the base (x along the
/// undeformed beam from the clamp, y up): position \[m\], velocity \[m/s\], acceleration
/// \[m/s²\] and the generalized-α variable of the acceleration. Read only while the state's
/// contact is [`Contact::InFlight`] (the spin is the state's φ, its rate ω = φ̇).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Flight<T> {
    /// Centre c \[m\].
    pub centre: [T; 2],
    /// ċ \[m/s\].
    pub velocity: [T; 2],
    /// c̈ = (0, −g_eff) \[m/s²\].
    pub accel: [T; 2],
    /// The generalized-α scheme's acceleration-like variable (= `accel` for Newmark).
    pub pseudo_accel: [T; 2],
    /// The flight has reached `ball.lift_height` (it counts as a separation; module doc).
    pub lifted: bool,
}

impl<T: Real> Flight<T> {
    /// All zero (the ball on the track).
    pub fn zero() -> Self {
        let z = [T::zero(); 2];
        Self {
            centre: z,
            velocity: z,
            accel: z,
            pseudo_accel: z,
            lifted: false,
        }
    }
}

/// A landing of the ball on the track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing<T> {
    /// Time of the landing \[s\].
    pub time: T,
    /// Normal speed towards the track before the landing, `n·(ċ − Ȧ)` \[m/s\] (with events at
    /// the step end: at the crossing, the rate of the Hermite interpolant whose root it is).
    pub normal_speed: T,
    /// Normal impulse of the track on the ball, towards A \[N·s\].
    pub normal_impulse: T,
    /// Tangential impulse of the track on the ball along `t = (cos θ, sin θ)` \[N·s\] (zero
    /// for a bounce, which is frictionless).
    pub tangential_impulse: T,
    /// The ball bounced back into flight (else it rolls on).
    pub bounced: bool,
}

impl<T: Real> Landing<T> {
    /// The friction coefficient the landing needed, `|P_t| / P_n`; `None` without a normal
    /// impulse.
    pub fn required_friction(&self) -> Option<T> {
        is_positive(self.normal_impulse)
            .then(|| self.tangential_impulse.abs() / self.normal_impulse)
    }
}
