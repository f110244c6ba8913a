//! The ball leaves the track: separation where the track would have to pull the
//! ball, free flight inside the housing, landing, and the stops in flight (docs/model.md,
//! "Contact and flight").
//!
//! The frame translates with the base: x along the undeformed beam from the clamp, y up,
//! effective gravity `g_eff = g + ÿ_b`. `A` is the beam end (the track's centre), `ψ` the tip
//! rotation, `ρ = R − r_b` the radius of the ball centre's circle, `R_tr = ρ + r_b`.
//!
//! **On the track** the ball rolls (the model of [`crate::tip`]): `c − A = ρ (sin θ, −cos θ)`,
//! and the track's normal force on it, positive towards `A`, is
//! `N = m_b [−ẍ_A sin θ + (ÿ_A + g_eff) cos θ + ρ θ̇²]` ([`crate::ContactForces`]).
//!
//! **Separation.** A real track only pushes. When a step ends with `N < 0` the ball left the
//! track during it, at the fraction `τ = N₀ / (N₀ − N₁)` of the step (linear in `N`;
//! [`separation_fraction`]): the step is redone as a rolling sub-step of `τh` and a flight
//! sub-step of `(1 − τ)h`. Positions and velocities are continuous at the take-off.
//!
//! **Flight.** The ball is a free planar rigid body: its centre `c` follows
//! `c̈ = (0, −g_eff(t))`, its spin rate `ω = φ̇` stays constant (no torque); the housing (beam and
//! tip body) moves without it, integrated by the scene's integrator. The centre is integrated
//! exactly ([`System::fly`]: its acceleration is known and linear in time over a step), so its
//! path in the inertial frame is a free-fall parabola whatever the base does; the full solver
//! (`host-sim`), which releases the ball's constraints, does the same with its coordinates.
//!
//! **Landing** when the centre reaches the circle, `|c − A| = ρ` (crossing fraction: the cubic
//! Hermite root of `d = |c − A| − ρ`, [`hermite_root`]). The centre is put on the circle, and
//! with the normal speed `v_n = n·(ċ − Ȧ) > 0` (`n = (c − A)/|c − A|`):
//! - **bounce** if `e_n v_n ≥ ρ ω_stick` (`e_n` = `ball.landing_restitution`, `ω_stick` =
//!   `ball.stick_speed`, the stops' threshold as a speed) and the bounce's flight is longer than
//!   a step ([`landing_bounces`]): a frictionless normal impulse
//!   `P = (1 + e_n) v_n / K`, `K = 1/m_b + f_nᵀ M_h⁻¹ f_n` ([`bounce_impulse`]), on the ball `−P n`
//!   and on the housing `P n` at `A` (`f_n`: the end node's position rows); the ball flies on;
//! - otherwise a **plastic, rough landing**: rolling resumes, with the rolling velocities that
//!   keep the generalized momentum, `M_roll v⁺ = Bᵀ M_fl v⁻` (`B` the rolling velocity map).
//!   Written with the ball's momentum mismatch `Δ = m_b (ċ⁻ − ċ_roll(v⁻))`:
//!   `v⁺ = v⁻ + M_roll⁻¹ B_bᵀ Δ` — one factorization of the rolling mass matrix. The impulse the
//!   ball received, `J = m_b (ċ⁺ − ċ⁻)`, gives the normal and tangential impulses and the
//!   friction the landing needed (reported; the model rolls on whatever it is).
//!
//! **Counted.** The motion is the same for every hop, but the step report counts a flight
//! ([`crate::EventCounts`]: a separation, and its landings and bounces) only once it reaches
//! `ball.lift_height` (0, the default: every take-off): its gap to the track `ρ − |c − A|` at a
//! step's end, or at a landing the apex `v_n² / (2 a_p)` of a hop arriving at `v_n` while pressed
//! on at `a_p` (a hop shorter than a step), is higher. The rigid unilateral track on a flexible
//! housing makes hops of every height, down to nanometres, whose number grows without bound as
//! h shrinks (the housing's higher modes, rung by the landings and the stops, resolved by the
//! step); above a fixed height the count converges (docs/model.md, "Contact statistics").
//!
//! **Stops in flight**: a stop is a block on the track as tall as the ball's radius, so the
//! flying ball meets it where its centre is beyond `ρ − r_b` from A and its polar angle relative
//! to the housing, `α_f = atan2(c_x − A_x, A_y − c_y) − ψ`, reaches `±α_max`: a frictionless
//! impulse along `∇α_f` with the stops' restitution (plastic below `stick_speed`), the ball
//! kept in flight; the crossing is detected when the ball is at the stops' height at both ends
//! of a step, from either face. Nearer the centre the ball flies over the stops, onto the arc
//! beyond them, where it may land and roll like on the track (the stops then act on it from
//! their other face, [`crate::stops`]).
//!
//! Impulses use the stops' metric ([`crate::ImpactModel`]): the step's Newmark matrix by default
//! (an impulse in the mass-matrix metric kicks the housing's stiff end-rotation mode; a stop's
//! with its own contact time when `ball.stop_contact_time` is set), the mass matrix for an
//! instantaneous impact. A perfectly elastic ball's impulses keep the kinetic energy in either
//! metric ([`crate::stops`]), and it has every event of a step split at its crossing
//! ([`System::perfectly_elastic`]; docs/model.md, "Elastic bounces at the paper's step").
//! After an impulse the accelerations go on from before it
//! ([`System::after_impulse`]); a take-off and a rolling landing (a change of mode) restart from
//! the consistent acceleration of the new mode. At most one event splits a step (every event,
//! up to four, for a perfectly elastic ball); an event found at the end of the rest of the step
//! is applied there, and a ball on the track at the end of an
//! event step takes off there if the track pulls (`take_off_at_end`). The step report counts
//! every event ([`crate::EventCounts`]). With events at the step end
//! ([`crate::EventLocation::StepEnd`]) nothing splits a step: the events act at its end, without
//! a consistent acceleration (`flight_events_at_end`, docs/model.md).

use crate::error::Error;
use crate::newton::Workspace;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::{Contact, Impact, Side, State, StepReport};
pub use crate::state::{Flight, Landing};
use crate::system::System;
use crate::tip;
use nalgebra::SVector;

/// A flying ball whose polar angle starts a step this close beyond a stop \[rad\], moving
/// back towards the track, is still on the track's side of it (an impact put it on the stop
/// line, to rounding).
const STOP_MARGIN: f64 = 1e-3;

/// A perfectly elastic flying ball ([`System::perfectly_elastic`]) that hits a stop from the
/// arc beyond it is put this far beyond the stop line \[rad\] (0.3 µm at the stops' height;
/// above the rounding of the polar angle in `f32`), so that it starts the rest of its step,
/// moving away from the stop, on the side it came from.
const BEYOND_OFFSET: f64 = 1e-5;

/// Events split at their crossings in the rest of one flight step of a perfectly elastic ball
/// ([`System::perfectly_elastic`]), beyond the step's first.
const MAX_SPLITS: usize = 3;

/// The first event of a flight step ([`System::first_flight_event`]).
#[derive(Clone, Copy)]
struct FlightEvent<T> {
    /// Its fraction of the step.
    tau: T,
    /// A stop (its side and whether the ball hits it from the track's side), or `None`: a
    /// landing.
    stop: Option<(Side, bool)>,
    /// The normal speed at the landing's crossing, if the step ends beyond the circle.
    landing_speed: Option<T>,
    /// The stop crossed in the step, if any (first or not).
    crossed_stop: Option<(Side, bool)>,
}

/// A ball meeting the circle slower than this along the normal \[m/s\] grazes it: no impulse,
/// it flies on. A ball that took off at a step's end meets the circle again at the next step's
/// start with a normal speed of rounding size and either sign; without the margin the two
/// solvers took different branches there (a rolling landing with a normal impulse of rounding
/// size, or none).
pub const GRAZING: f64 = 1e-6;

/// Fraction τ ∈ \[0, 1\] of a step at which the normal force, `n_start` at its start and
/// `n_end < 0` at its end, crosses zero (linear in N); 0 when it was not positive at the start.
pub fn separation_fraction<T: Real>(n_start: T, n_end: T) -> T {
    if !is_positive(n_start) {
        return T::zero();
    }
    let tau = n_start / (n_start - n_end);
    if tau.is_finite() {
        tau.max(T::zero()).min(T::one())
    } else {
        T::zero()
    }
}

/// Fraction τ ∈ \[0, 1\] of a step at which a function with values `a0`, `a1` and scaled rates
/// `d0 = ȧ₀h`, `d1 = ȧ₁h` at the step ends crosses zero: the root of its cubic Hermite
/// interpolant (error O(h⁴)), by Newton from the linear root, six iterations at most. The stop
/// crossing, the landing and the stops in flight of both solvers use it.
pub fn hermite_root<T: Real>(a0: T, d0: T, a1: T, d1: T) -> T {
    let (two, three) = (lit::<T>(2.0), lit::<T>(3.0));
    let linear = a0 / (a0 - a1);
    let mut tau = if linear.is_finite() {
        linear.max(T::zero()).min(T::one())
    } else {
        T::zero()
    };
    for _ in 0..6 {
        let (t2, t3) = (tau * tau, tau * tau * tau);
        let p = (two * t3 - three * t2 + T::one()) * a0
            + (t3 - two * t2 + tau) * d0
            + (three * t2 - two * t3) * a1
            + (t3 - t2) * d1;
        let dp = hermite_rate(a0, d0, a1, d1, tau);
        if !is_positive(dp.abs()) {
            break;
        }
        let next = tau - p / dp;
        if !next.is_finite() {
            break;
        }
        tau = next.max(T::zero()).min(T::one());
    }
    tau
}

/// Rate of the cubic Hermite interpolant of [`hermite_root`] at the fraction `tau`, in units of
/// the scaled rates: `dp/dτ`, so that the function's time derivative there is `dp/dτ / h`.
pub fn hermite_rate<T: Real>(a0: T, d0: T, a1: T, d1: T, tau: T) -> T {
    let (two, three, six) = (lit::<T>(2.0), lit::<T>(3.0), lit::<T>(6.0));
    let t2 = tau * tau;
    (six * t2 - six * tau) * (a0 - a1)
        + (three * t2 - lit::<T>(4.0) * tau + T::one()) * d0
        + (three * t2 - two * tau) * d1
}

/// The landing bounces (the ball flies on) unless it is slow, `e_n v_n < v_stick`, or the
/// bounce's flight would be shorter than a step: pressed onto the track at `a_p > 0`, a ball
/// leaving it at `e_n v_n` returns after `2 e_n v_n / a_p`, which a step `h` cannot resolve
/// when `2 e_n v_n < a_p h` (`pressed_over_step` = `a_p h` \[m/s\]; with
/// `ball.min_bounce_time` τ_b longer than the step, `a_p τ_b`). A ball skimming along the
/// curved track would otherwise be found beyond the circle at every step end, with a normal
/// speed of about `v_t² h / ρ` made by the step, and bounce for ever. A perfectly elastic
/// landing (`e_n = 1`) always bounces: nothing would end its bounces.
pub fn landing_bounces<T: Real>(
    restitution: T,
    normal_speed: T,
    stick: T,
    pressed_over_step: T,
) -> bool {
    let rebound = restitution * normal_speed;
    let elastic = restitution >= T::one();
    rebound >= stick
        && (elastic || !(is_positive(pressed_over_step) && rebound + rebound < pressed_over_step))
}

/// Normal impulse of a frictionless bounce, `P = (1 + e_n) v_n / K` \[N·s\], with `K` the
/// inverse effective mass along the normal \[1/kg\]: the normal speed becomes `−e_n v_n`.
pub fn bounce_impulse<T: Real>(normal_speed: T, inverse_mass: T, restitution: T) -> T {
    (T::one() + restitution) * normal_speed / inverse_mass
}

/// Polar angle of `d = c − A` from the downward vertical, `atan2(d_x, −d_y)` \[rad\] (the orbit
/// angle θ of a ball on the track).
pub fn polar_angle<T: Real>(d: [T; 2]) -> T {
    d[0].atan2(-d[1])
}

/// `x` shifted by whole turns into `(−π, π]`.
pub(crate) fn wrap<T: Real>(x: T) -> T {
    let two_pi = T::two_pi();
    let k = (x / two_pi).round();
    x - k * two_pi
}

/// The kinematics of the ball relative to the track's centre.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Relative<T> {
    /// c − A \[m\].
    pub d: [T; 2],
    /// ċ − Ȧ \[m/s\].
    pub rate: [T; 2],
    /// |c − A| \[m\].
    pub r: T,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The beam end A and its velocity in the base frame (the clamp at the origin).
    pub(crate) fn end_point(&self, s: &State<T, D>) -> ([T; 2], [T; 2]) {
        let at = |x: &SVector<T, D>, k: usize| x.get(Self::END + k).copied().unwrap_or(T::zero());
        (
            [self.params.beam.length + at(&s.q, 0), at(&s.q, 1)],
            [at(&s.v, 0), at(&s.v, 1)],
        )
    }

    /// The ball's centre and its velocity: on the track from the rolling kinematics
    /// `c = A + ρ (sin θ, −cos θ)`, `ċ = Ȧ + ρ θ̇ (cos θ, sin θ)`, in flight the flying state.
    pub(crate) fn ball_centre(&self, s: &State<T, D>) -> ([T; 2], [T; 2]) {
        if s.contact == Contact::InFlight {
            return (s.flight.centre, s.flight.velocity);
        }
        let (a, a_rate) = self.end_point(s);
        let x = Self::local(&s.q, &s.v, &s.a);
        let (theta, theta_rate) = tip::orbit_angle(&self.inertia, &x);
        let (sin, cos) = theta.fast_sin_cos();
        let rho = self.params.ball.path_radius();
        (
            [a[0] + rho * sin, a[1] - rho * cos],
            [
                a_rate[0] + rho * theta_rate * cos,
                a_rate[1] + rho * theta_rate * sin,
            ],
        )
    }

    /// The flying ball relative to the track's centre.
    pub(crate) fn relative(&self, s: &State<T, D>) -> Relative<T> {
        let (a, a_rate) = self.end_point(s);
        let f = &s.flight;
        let d = [f.centre[0] - a[0], f.centre[1] - a[1]];
        Relative {
            d,
            rate: [f.velocity[0] - a_rate[0], f.velocity[1] - a_rate[1]],
            r: (d[0] * d[0] + d[1] * d[1]).sqrt(),
        }
    }

    /// Polar angle of the flying ball relative to the housing, `α_f = θ_f − ψ` on the branch
    /// of `(−π, π]`, and its rate `t_f·(ċ − Ȧ)/r − ψ̇`.
    pub(crate) fn flight_relative_angle(&self, s: &State<T, D>) -> (T, T) {
        let rel = self.relative(s);
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, psi_rate) = tip::psi_and_rate(&x);
        let alpha = wrap(polar_angle(rel.d) - psi);
        // (cos θ_f, sin θ_f) = (−d_y, d_x)/r.
        let tangential = (-rel.d[1] * rel.rate[0] + rel.d[0] * rel.rate[1]) / (rel.r * rel.r);
        (alpha, tangential - psi_rate)
    }

    /// The flying ball reaches the stops' height: its centre is beyond `ρ − r_b` from A (a stop
    /// is a block on the track as tall as the ball's radius; nearer the centre the ball passes
    /// over it).
    pub(crate) fn at_stop_height(&self, s: &State<T, D>) -> bool {
        let b = &self.params.ball;
        self.relative(s).r > b.path_radius() - b.radius
    }

    /// A stop met by the flying ball between `from` and `to`: at the stops' height at both
    /// ends, its polar angle crossed `±α_max` (from the track's side, `inside`, or from the arc
    /// beyond the stop); the side, `inside` and the crossing fraction (cubic Hermite).
    pub(crate) fn stop_crossing(
        &self,
        from: &State<T, D>,
        to: &State<T, D>,
        h: T,
    ) -> Option<(Side, bool, T)> {
        if !S::STOPS || !self.at_stop_height(from) || !self.at_stop_height(to) {
            return None;
        }
        let stop = self.params.ball.stop_angle;
        let (alpha0, rate0) = self.flight_relative_angle(from);
        let (raw1, rate1) = self.flight_relative_angle(to);
        let alpha1 = alpha0 + wrap(raw1 - alpha0);
        // A ball just put on the stop line by an impact (to rounding) is on the side it came
        // from: from the track's side it moves back towards the track, and the margin keeps it
        // there (without it the rest of the step would reverse its impulse). From beyond, a
        // perfectly elastic ball is put beyond the line (`BEYOND_OFFSET`) and moves away from
        // the track; counted on the track's side (as the margin alone does, and still does for
        // other balls: the default trajectories stay as they were) it gets a second impulse,
        // from the track's face, at the end of the rest of its step, with the projection there
        // (the ball moved by up to |α̇|h: 2 % of an elastic bouncing ball's energy).
        let outward = self.perfectly_elastic() && is_positive(alpha0 * rate0);
        let inside = alpha0.abs() <= stop || (!outward && alpha0.abs() <= stop + lit(STOP_MARGIN));
        if inside == (alpha1.abs() <= stop) {
            return None;
        }
        let outer = if inside { alpha1 } else { alpha0 };
        let side = if is_positive(outer) {
            Side::Positive
        } else {
            Side::Negative
        };
        let target = side.sign::<T>() * stop;
        let tau = hermite_root(alpha0 - target, rate0 * h, alpha1 - target, rate1 * h);
        Some((side, inside, tau))
    }

    /// The flight sub-step of the ball's centre over `h`, from the effective gravity at its start
    /// (`f.accel`) to `g_end` at its end, exact: the centre's acceleration `(0, −g_eff(t))` is
    /// known, and with the base acceleration linear between the samples (the input's
    /// interpolation, as the sub-steps to an event use it) its integrals are
    /// `Δċ = h (a₀ + a₁)/2`, `Δc = h ċ₀ + h² (a₀/3 + a₁/6)`. So the ball's path in the inertial
    /// frame is the parabola of a free fall whatever the base does (relative to a base that moves
    /// with the interpolated acceleration). The scene's integrator, used here before, is exact
    /// only for a constant acceleration: under a moving base its `γ ≠ ½` (or generalized-α)
    /// weighting of the two ends drifted the ball's energy by O(h) per flight (3.9e-5 J per
    /// flight at 3 ms, 4.10 Hz; docs/model.md).
    pub(crate) fn fly(&self, f: &Flight<T>, h: T, g_end: T) -> Flight<T> {
        let (two, three, six) = (lit::<T>(2.0), lit::<T>(3.0), lit::<T>(6.0));
        let a0 = f.accel;
        let a1 = [T::zero(), -g_end];
        let mut next = *f;
        for k in 0..2 {
            let (Some(c), Some(v), Some(x0), Some(x1)) = (
                next.centre.get_mut(k),
                next.velocity.get_mut(k),
                a0.get(k),
                a1.get(k),
            ) else {
                continue;
            };
            *c += h * *v + h * h * (*x0 / three + *x1 / six);
            *v += h * (*x0 + *x1) / two;
        }
        next.accel = a1;
        next.pseudo_accel = a1;
        next
    }

    /// The normal force of the track on a rolling ball (`N` of [`crate::ContactForces`]) \[N\];
    /// zero in flight: `N = m_b [−ẍ_A sin θ + (ÿ_A + g_eff) cos θ + ρ θ̇²]` with
    /// `θ = (R_tr/ρ) ψ − (r_b/ρ) φ`, `ψ = atan2(a₄, a₃)`, `ψ̇ = (a₃ ȧ₄ − a₄ ȧ₃)/|a|²`. It runs
    /// after every rolling step (the separation test): one `atan2`, one division, one
    /// `sin_cos`, no copy of the state.
    pub(crate) fn normal_force(&self, s: &State<T, D>) -> T {
        if S::EXTRA_DOFS != 1 || s.contact == Contact::InFlight {
            return T::zero();
        }
        let at = |x: &SVector<T, D>, k: usize| x.get(k).copied().unwrap_or(T::zero());
        let e = Self::END;
        let (a3, a4) = (T::one() + at(&s.q, e + 2), at(&s.q, e + 3));
        let (v3, v4) = (at(&s.v, e + 2), at(&s.v, e + 3));
        let psi = a4.atan2(a3);
        let psi_rate = (a3 * v4 - a4 * v3) / (a3 * a3 + a4 * a4);
        let i = &self.inertia;
        let theta = i.orbit_per_tilt * psi - i.orbit_per_spin * at(&s.q, Self::SPIN);
        let theta_rate = i.orbit_per_tilt * psi_rate - i.orbit_per_spin * at(&s.v, Self::SPIN);
        let (sin, cos) = theta.fast_sin_cos();
        let ball = &self.params.ball;
        let ya_g = at(&s.a, e + 1) + self.effective_gravity(s.base_accel);
        ball.mass * (-at(&s.a, e) * sin + ya_g * cos + ball.path_radius() * theta_rate * theta_rate)
    }

    /// `(N, F_t)` of the track on the ball (module doc; zero in flight): N from
    /// [`System::normal_force`], `F_t = m_b [ẍ_A cos θ + (ÿ_A + g_eff) sin θ + ρ θ̈]`.
    pub(crate) fn track_forces(&self, s: &State<T, D>) -> (T, T) {
        if s.contact == Contact::InFlight {
            return (T::zero(), T::zero());
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _, psi_accel) = tip::psi_all(&x);
        let i = &self.inertia;
        let theta = i.orbit_per_tilt * psi - i.orbit_per_spin * x.q[4];
        let theta_accel = i.orbit_per_tilt * psi_accel - i.orbit_per_spin * x.a[4];
        let (sin, cos) = theta.fast_sin_cos();
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let (xa, ya_g) = (x.a[0], x.a[1] + self.effective_gravity(s.base_accel));
        (
            self.normal_force(s),
            ball.mass * (xa * cos + ya_g * sin + rho * theta_accel),
        )
    }

    /// The ball leaves the track if the step from `start` to `next` (rolling, no stop impact)
    /// ends with the track pulling it: the step is redone as a rolling sub-step to the
    /// separation and a flight sub-step for the rest (module doc).
    pub(crate) fn separation(
        &self,
        start: &State<T, D>,
        next: &mut State<T, D>,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        let n_end = self.normal_force(next);
        if n_end >= T::zero() || !n_end.is_finite() {
            return Ok(()); // the track pushes: the step stands (the common case, no copy)
        }
        if report.impact.is_some() {
            // A stop impact split this step already: the ball takes off at its end.
            return self.take_off_at_end(start, next, ws, report);
        }
        self.separate(start, n_end, base_accel, ws, report, next)
    }

    /// A ball on the track (rolling, beyond the stops or held on one) at the end `end` of a step
    /// from `start` that had an event (a stop impact, a landing) leaves the track there if it
    /// pulls (`N < 0`): the event step is not split again, and before, the ball stayed on a
    /// pulling track until the next step's start, where it left at once (`τ = 0`) — the same
    /// motion, but the step's row said `contact = 1` with the track pulling. Positions and
    /// velocities are continuous; the acceleration is the flight mode's.
    #[inline(never)]
    #[cold]
    fn take_off_at_end(
        &self,
        start: &State<T, D>,
        end: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        if end.contact == Contact::InFlight {
            return Ok(());
        }
        let n = self.normal_force(end);
        if n >= T::zero() || !n.is_finite() {
            return Ok(());
        }
        report.separation = Some(start.time + self.params.integrator.step);
        self.fly_from_track(end);
        self.note_lift(end, T::zero(), report);
        if self.event_at_end(ws) {
            return Ok(()); // (the acceleration stays the trial's, as every step-end event's)
        }
        self.restart_acceleration(end, ws, report)
    }

    /// The step from `start` redone with the separation inside it (`n_end` < 0 at its end),
    /// into `next`. Kept out of line (rare).
    #[inline(never)]
    #[cold]
    fn separate(
        &self,
        start: &State<T, D>,
        n_end: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        next: &mut State<T, D>,
    ) -> Result<(), Error> {
        let h = self.params.integrator.step;
        if self.event_at_end(ws) {
            // At the step's end: the trial stands and the ball takes off where it ended.
            report.separation = Some(start.time + h);
            self.fly_from_track(next);
            self.note_lift(next, T::zero(), report);
            return Ok(());
        }
        let tau = separation_fraction(self.normal_force(start), n_end);
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = *start;
        self.sub_step(start, h1, accel_mid, ws, report, &mut mid)?;
        mid.time = start.time + h1;
        self.take_off(&mut mid, ws, report)?;
        self.note_lift(&mut mid, T::zero(), report);
        report.separation = Some(mid.time);
        self.rest_in_flight(&mut mid, h - h1, base_accel, ws, report, next)?;
        // Landed in the rest of the step: a pulling track lets it go again at the end.
        self.take_off_at_end(start, next, ws, report)
    }

    /// The rolling ball leaves the track at `s`: the flying state from the rolling kinematics
    /// (continuous), then the consistent acceleration of the flight mode.
    fn take_off(
        &self,
        s: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        self.fly_from_track(s);
        self.restart_acceleration(s, ws, report)
    }

    /// The flying state of a rolling ball at `s`: its centre and velocity from the rolling
    /// kinematics (continuous), the effective gravity as its acceleration.
    fn fly_from_track(&self, s: &mut State<T, D>) {
        let (c, c_rate) = self.ball_centre(s);
        let g = [T::zero(), -self.effective_gravity(s.base_accel)];
        s.flight = Flight {
            centre: c,
            velocity: c_rate,
            accel: g,
            pseudo_accel: g,
            lifted: false,
        };
        s.contact = Contact::InFlight;
    }

    /// The flight at `s` reaches the counted height: `height` \[m\] (the gap at a step's end
    /// or a hop's apex; 0 at the take-off) above `ball.lift_height`, or that height 0 (every
    /// take-off counts). A flight counts once, as a separation (module doc, "Counted").
    pub(crate) fn note_lift(&self, s: &mut State<T, D>, height: T, report: &mut StepReport<T>) {
        if s.contact != Contact::InFlight || s.flight.lifted {
            return;
        }
        let lift = self.params.ball.lift_height;
        if !is_positive(lift) || height > lift {
            s.flight.lifted = true;
            report.events.separations += 1;
        }
    }

    /// A flying ball at a step's end `s`: its gap to the track `ρ − |c − A|` counts towards
    /// the flight's height ([`Self::note_lift`]).
    pub(crate) fn note_gap(&self, s: &mut State<T, D>, report: &mut StepReport<T>) {
        if s.contact != Contact::InFlight || s.flight.lifted {
            return;
        }
        let gap = self.params.ball.path_radius() - self.relative(s).r;
        self.note_lift(s, gap, report);
    }

    /// The consistent acceleration after a jump of velocity or mode; the generalized-α
    /// recursion restarts from it.
    fn restart_acceleration(
        &self,
        s: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        let acc = self.consistent_acceleration(s, ws, self.params.integrator.newton)?;
        report.iterations += acc.iterations;
        s.a = acc.x;
        s.pseudo_accel = s.a;
        if s.contact == Contact::InFlight {
            s.flight.pseudo_accel = s.flight.accel;
        }
        Ok(())
    }

    /// The rest `h_rest` of a step after an event at `mid` that left the ball flying (a
    /// take-off, a stop hit in flight, a bounce), to the input `base_accel`; a stop or a landing
    /// at its end is applied there (no further split; a perfectly elastic ball's are split,
    /// [`Self::rest_in_flight`]). The rolling rest is [`Self::landed_rest`]: kept apart, the
    /// static stack bound does not count a chain (take-off, then a rolling rest) that no step
    /// can take.
    #[inline(never)]
    fn flying_rest(
        &self,
        mid: &State<T, D>,
        h_rest: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        end: &mut State<T, D>,
    ) -> Result<(), Error> {
        self.sub_step(mid, h_rest, base_accel, ws, report, end)?;
        self.events_at_rest_end(mid, end, h_rest, ws, report)
    }

    /// The flying rest of a step after an event at `mid`: [`Self::flying_rest`], or for a
    /// perfectly elastic ball [`Self::split_rest`] (chosen here, in the caller's frame: the
    /// split does not deepen the static stack bound's chain).
    #[inline(always)]
    fn rest_in_flight(
        &self,
        mid: &mut State<T, D>,
        h_rest: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        end: &mut State<T, D>,
    ) -> Result<(), Error> {
        if self.perfectly_elastic() {
            self.split_rest(mid, h_rest, base_accel, ws, report, end)
        } else {
            self.flying_rest(mid, h_rest, base_accel, ws, report, end)
        }
    }

    /// The events of a flight step's rest from `mid` to `end` (`len` apart) that act at its end
    /// (no further split): the stop crossed, then the landing if the ball ended beyond the
    /// circle.
    fn events_at_rest_end(
        &self,
        mid: &State<T, D>,
        end: &mut State<T, D>,
        len: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        if let Some((side, inside, _)) = self.stop_crossing(mid, end, len) {
            let impact = self.stop_in_flight(end, side, inside, ws)?;
            report.impact = report.impact.or(Some(impact));
            report.events.impacts += 1;
        }
        if self.relative(end).r > self.params.ball.path_radius() {
            self.land(end, ws, report)?;
        }
        Ok(())
    }

    /// A perfectly elastic ball: every contact it can have is elastic (`ball.restitution` 1,
    /// and `ball.landing_restitution` 1 if it may fly), its events at their crossings (with
    /// events at the step end every event is late, and the kinematic law and its cost stay: the
    /// firmware, which runs them so, is unchanged). Its impulses keep the kinetic energy
    /// exactly in either metric ([`crate::stops`]), and every event of its flight steps is split
    /// at its crossing (up to [`MAX_SPLITS`]), so that none is applied late. A late event acts
    /// where the ball has gone on beyond the circle or the stop line for the rest of the step,
    /// and its projection back moves the ball by up to its speed times the step: with
    /// e = e_n = 1 that changes the energy, which nothing then removes (1–2 % of the drop energy
    /// of a ball bouncing in a stiff housing, at a stop impact followed by a landing within one
    /// 3 ms step). Other balls keep the kinematic rebound law and one split a step (a late
    /// impact is then a lossy one; docs/model.md): their trajectories are those of before.
    #[inline]
    pub(crate) fn perfectly_elastic(&self) -> bool {
        let b = &self.params.ball;
        S::ELASTIC_RULES
            && b.restitution >= T::one()
            && (b.landing_restitution >= T::one() || !self.flies())
            && !self.events_at_step_end()
    }

    /// The first event of a flying ball between `start` and `trial`, `h` apart: a landing (the
    /// cubic Hermite root of `|c − A| − ρ`, and the normal speed there) or a stop crossed in
    /// flight, whichever comes first.
    fn first_flight_event(
        &self,
        start: &State<T, D>,
        trial: &State<T, D>,
        h: T,
    ) -> Option<FlightEvent<T>> {
        let rho = self.params.ball.path_radius();
        let mut tau = T::one();
        let mut event = None;
        let mut landing_speed = None;
        let end_rel = self.relative(trial);
        if end_rel.r > rho {
            let (r0, r1) = (self.relative(start), end_rel);
            let rate = |r: &Relative<T>| (r.d[0] * r.rate[0] + r.d[1] * r.rate[1]) / r.r;
            let (d0, m0, d1, m1) = (r0.r - rho, rate(&r0) * h, r1.r - rho, rate(&r1) * h);
            tau = hermite_root(d0, m0, d1, m1);
            event = Some(None);
            landing_speed = Some(hermite_rate(d0, m0, d1, m1, tau) / h);
        }
        let stop = self.stop_crossing(start, trial, h);
        if let Some((side, inside, t)) = stop {
            if event.is_none() || t < tau {
                tau = t;
                event = Some(Some((side, inside)));
            }
        }
        event.map(|stop_event| FlightEvent {
            tau,
            stop: stop_event,
            landing_speed,
            crossed_stop: stop.map(|(side, inside, _)| (side, inside)),
        })
    }

    /// [`Self::flying_rest`] of a perfectly elastic ball: `end` becomes the rest's trial from
    /// `mid` over `h_rest`; while it holds an event, the rest is redone to the event's
    /// crossing, the event acts there, and the rest goes on from it (`mid` and `end` take
    /// turns: no state of its own in the frame; `mid` is scratch on return). After
    /// [`MAX_SPLITS`] splits, or when the work cap cannot afford another, the events left act
    /// at the end, as in [`Self::flying_rest`]; so does a landing that would roll on (a rebound
    /// slower than the stick speed). The extra splits keep the sub-step's accelerations (the
    /// trapezoidal rule's choice, [`System::event_accel`]).
    #[inline(never)]
    #[cold]
    fn split_rest(
        &self,
        mid: &mut State<T, D>,
        h_rest: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        end: &mut State<T, D>,
    ) -> Result<(), Error> {
        self.sub_step(mid, h_rest, base_accel, ws, report, end)?;
        let mut len = h_rest;
        for _ in 0..MAX_SPLITS {
            let Some(event) = self.first_flight_event(mid, end, len) else {
                return Ok(());
            };
            // A landing that would roll on is not split (the rolling rest is not chained
            // here: the static stack bound); it acts at the end.
            let b = &self.params.ball;
            let rolls = event.stop.is_none()
                && event
                    .landing_speed
                    .is_none_or(|v| b.landing_restitution * v < b.path_radius() * b.stick_speed);
            if rolls || !ws.affords_split() {
                break;
            }
            let len1 = event.tau * len;
            let frac = (len - len1) / len;
            let accel_mid = base_accel + (mid.base_accel - base_accel) * frac;
            let t1 = mid.time + len1;
            self.sub_step(mid, len1, accel_mid, ws, report, end)?;
            end.time = t1;
            match event.stop {
                None => self.land(end, ws, report)?,
                Some((side, inside)) => {
                    let impact = self.stop_in_flight(end, side, inside, ws)?;
                    report.impact = report.impact.or(Some(impact));
                    report.events.impacts += 1;
                }
            }
            *mid = *end;
            len -= len1;
            self.sub_step(mid, len, base_accel, ws, report, end)?;
            if mid.contact != Contact::InFlight {
                // Rolled on after all (the landing's own speed was below the stick speed).
                return Ok(());
            }
        }
        // Events left: at the end (as `flying_rest`).
        self.events_at_rest_end(mid, end, len, ws, report)
    }

    /// The rest `h_rest` of a step after a plastic landing at `mid` (the ball rolling, between
    /// the stops or beyond them), to the input `base_accel`; a stop reached at its end acts
    /// there (no further split).
    #[inline(never)]
    fn landed_rest(
        &self,
        mid: &State<T, D>,
        h_rest: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        end: &mut State<T, D>,
    ) -> Result<(), Error> {
        self.sub_step(mid, h_rest, base_accel, ws, report, end)?;
        if S::STOPS {
            let stop = self.params.ball.stop_angle;
            let alpha = wrap(self.relative_angle(end));
            if end.contact == Contact::Off && alpha.abs() > stop {
                // Landed and rolled onto a stop within the rest: it rests there (plastic).
                self.rest_on_stop(end, ws, report)?;
            } else if end.contact == Contact::Beyond && alpha.abs() < stop {
                // Landed beyond a stop and rolled back onto its other face: an impact there.
                let side = if is_positive(alpha) {
                    Side::Positive
                } else {
                    Side::Negative
                };
                let impact = self.impact(end, side, false, ws)?;
                report.impact = report.impact.or(Some(impact));
                report.events.impacts += 1;
                self.after_impulse(end);
            }
        }
        Ok(())
    }

    /// The events of a flight step from `start` whose trial end is `trial`: a landing or a stop,
    /// whichever comes first, splits the step (module doc; `trial` becomes the step redone
    /// with it). Kept out of line: the rolling step's frame does not carry its states.
    #[inline(never)]
    pub(crate) fn flight_events(
        &self,
        start: &State<T, D>,
        trial: &mut State<T, D>,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        let h = self.params.integrator.step;
        let Some(first) = self.first_flight_event(start, trial, h) else {
            return Ok(());
        };
        let FlightEvent {
            tau,
            stop: event,
            landing_speed,
            crossed_stop: stop,
        } = first;
        if self.event_at_end(ws) {
            return self.flight_events_at_end(start, trial, stop, landing_speed, ws, report);
        }
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = *start;
        self.sub_step(start, h1, accel_mid, ws, report, &mut mid)?;
        mid.time = start.time + h1;
        self.event_accel(start, trial, tau, &mut mid);
        match event {
            None => self.land(&mut mid, ws, report)?,
            Some((side, inside)) => {
                let impact = self.stop_in_flight(&mut mid, side, inside, ws)?;
                report.impact = Some(impact);
                report.events.impacts += 1;
            }
        }
        if mid.contact == Contact::InFlight {
            self.rest_in_flight(&mut mid, h - h1, base_accel, ws, report, trial)?;
        } else {
            self.landed_rest(&mid, h - h1, base_accel, ws, report, trial)?;
        }
        // On the track at the end with the track pulling: off again.
        self.take_off_at_end(start, trial, ws, report)
    }

    /// The flight events of a step put at its end ([`crate::EventLocation::StepEnd`]): the
    /// trial from `start` stands as `s`; the stop it crossed, if any, and then the landing, if
    /// its end is beyond the circle, act there, with the trial's own factors as the flight
    /// metric ([`Self::impulse_metric`]). The acceleration stays the trial's ([`crate::EventLocation::StepEnd`]: the next
    /// step starts from it, not from a consistent one). The landing's bounce is decided, and its
    /// rebound set, by `landing_speed`, the normal speed at the crossing (the rate of the
    /// Hermite interpolant whose root is the crossing): at the step's end the ball has been
    /// pressed on for the rest of the step, and deciding on that speed made landings chatter
    /// (docs/model.md). Kept out of line (rare).
    #[inline(never)]
    #[cold]
    fn flight_events_at_end(
        &self,
        start: &State<T, D>,
        s: &mut State<T, D>,
        stop: Option<(Side, bool)>,
        landing_speed: Option<T>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        s.time = start.time + self.params.integrator.step;
        if let Some((side, inside)) = stop {
            report.impact = Some(self.stop_impulse(s, side, inside, ws)?);
            report.events.impacts += 1;
        }
        if let Some(speed) = landing_speed {
            if self.relative(s).r > self.params.ball.path_radius() {
                self.land_impulse(s, Some(speed), ws, report)?;
            }
        }
        self.take_off_at_end(start, s, ws, report)
    }

    /// The landing at the crossing `s` (module doc): the centre put on the circle, then a
    /// bounce or a plastic, rough landing; the accelerations go on from before the impulse
    /// ([`Self::after_impulse`]).
    fn land(
        &self,
        s: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        if self.land_impulse(s, None, ws, report)? {
            if s.contact == Contact::InFlight {
                self.after_impulse(s);
            } else {
                self.restart_acceleration(s, ws, report)?;
            }
        }
        Ok(())
    }

    /// The landing's projection and impulse at `s` (no acceleration): whether the velocities
    /// jumped. `crossing_speed`: the normal speed at the crossing when `s` is a step's end past
    /// it ([`Self::flight_events_at_end`]); it decides the bounce and sets the rebound to
    /// `−e_n` times it. `None`: `s` is the crossing.
    fn land_impulse(
        &self,
        s: &mut State<T, D>,
        crossing_speed: Option<T>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<bool, Error> {
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let rel = self.relative(s);
        if !is_positive(rel.r) {
            return Err(Error::NonFiniteState);
        }
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (a, _) = self.end_point(s);
        s.flight.centre = [a[0] + rho * n[0], a[1] + rho * n[1]];
        let normal_speed = n[0] * rel.rate[0] + n[1] * rel.rate[1];
        if normal_speed.partial_cmp(&lit(GRAZING)) != Some(core::cmp::Ordering::Greater) {
            return Ok(false); // grazing: no impulse, the ball flies on
        }
        let speed = crossing_speed.map_or(normal_speed, |c| c.max(T::zero()));
        let mut landing = Landing {
            time: s.time,
            normal_speed: speed,
            normal_impulse: T::zero(),
            tangential_impulse: T::zero(),
            bounced: false,
        };
        let before = s.flight.velocity;
        // The ball is pressed onto the track at a_p = ((0, −g_eff) − Ä)·n + v_t²/ρ.
        let accel_end = [
            s.a.get(Self::END).copied().unwrap_or(T::zero()),
            s.a.get(Self::END + 1).copied().unwrap_or(T::zero()),
        ];
        let tangential = n[0] * rel.rate[1] - n[1] * rel.rate[0];
        let pressed = (-self.effective_gravity(s.base_accel) - accel_end[1]) * n[1]
            - accel_end[0] * n[0]
            + tangential * tangential / rho;
        // The hop's apex v_n² / (2 a_p): a hop shorter than a step is seen only here.
        if is_positive(pressed) {
            self.note_lift(s, speed * speed / (pressed + pressed), report);
        }
        let counted = s.flight.lifted;
        let bounces = landing_bounces(
            ball.landing_restitution,
            speed,
            rho * ball.stick_speed,
            pressed * self.params.integrator.step.max(ball.min_bounce_time),
        );
        if bounces {
            let mut y = SVector::<T, D>::zeros();
            // With events at the step end the trial's own factors serve (docs/model.md).
            let reuse = self.events_at_step_end();
            self.impulse_metric(s, Contact::InFlight, reuse, false, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, [n[0], n[1], T::zero(), T::zero()]);
            ws.solve(&mut y)?;
            let k = T::one() / ball.mass + self.end_dot(&y, [n[0], n[1], T::zero(), T::zero()]);
            if !is_positive(k) {
                return Err(Error::Singular);
            }
            let mut p = match crossing_speed {
                None => bounce_impulse(normal_speed, k, ball.landing_restitution),
                // From the end's normal speed to −e_n times the crossing's.
                Some(_) => (normal_speed + ball.landing_restitution * speed) / k,
            };

            if crossing_speed.is_none() && self.perfectly_elastic() {
                // Perfectly elastic: the kinetic energy is kept exactly in any metric. Along
                // (ball, housing) = (−n/m_b, y): b = −n·ċ + q̇ᵀM y, c = 1/m_b + yᵀM y.
                if let Some(e) = self
                    .mass_products(s, Contact::InFlight, &mut y, ws)
                    .and_then(|(uy, yy)| {
                        let b = uy - (n[0] * before[0] + n[1] * before[1]);
                        crate::stops::energy_exact_impulse(
                            -normal_speed,
                            b,
                            T::one() / ball.mass + yy,
                        )
                    })
                {
                    p = e;
                }
            }
            s.v.axpy(p, &y, T::one());
            for (c, nk) in s.flight.velocity.iter_mut().zip(n.iter()) {
                *c -= p / ball.mass * *nk;
            }
            landing.normal_impulse = p;
            landing.bounced = true;
        } else {
            // The rolling metric costs a refresh: unaffordable, the landing waits (the state
            // is not touched further; docs/embedded.md, "Work cap").
            if !ws.affords(crate::newton::work::REFRESH + crate::newton::work::SOLVE, 0) {
                return Err(Error::WorkCap);
            }
            // θ on the branch of ψ, and φ re-based so that r_b φ = R_tr ψ − ρ θ.
            let x = Self::local(&s.q, &s.v, &s.a);
            let (psi, _) = tip::psi_and_rate(&x);
            let theta = psi + wrap(polar_angle(n) - psi);
            let i = &self.inertia;
            if let Some(spin) = s.q.get_mut(Self::SPIN) {
                *spin = (i.orbit_per_tilt * psi - theta) / i.orbit_per_spin;
            }
            // On the track between the stops, or on the arc beyond them.
            s.contact = if S::STOPS && wrap(theta - psi).abs() > self.params.ball.stop_angle {
                Contact::Beyond
            } else {
                Contact::Off
            };
            // v⁺ = v⁻ + M_roll⁻¹ B_bᵀ Δ, Δ = m_b (ċ⁻ − ċ_roll(v⁻)).
            let (_, rolling) = self.ball_centre(s);
            let delta = [
                ball.mass * (before[0] - rolling[0]),
                ball.mass * (before[1] - rolling[1]),
            ];
            let (sin, cos) = theta.fast_sin_cos();
            let along = cos * delta[0] + sin * delta[1];
            let a3 = T::one() + x.q[2];
            let a4 = x.q[3];
            let s2 = a3 * a3 + a4 * a4;
            let w = rho * i.orbit_per_tilt * along / s2;
            let mut y = SVector::<T, D>::zeros();
            self.impulse_metric(s, s.contact, false, false, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, [delta[0], delta[1], -w * a4, w * a3]);
            if let Some(spin) = y.get_mut(Self::SPIN) {
                *spin = -rho * i.orbit_per_spin * along;
            }
            ws.solve(&mut y)?;
            s.v += y;
            let (_, after) = self.ball_centre(s);
            let jx = ball.mass * (after[0] - before[0]);
            let jy = ball.mass * (after[1] - before[1]);
            landing.normal_impulse = -(n[0] * jx + n[1] * jy);
            landing.tangential_impulse = cos * jx + sin * jy;
        }
        report.landing = Some(landing);
        if counted {
            report.events.landings += 1;
            report.events.bounces += u8::from(landing.bounced);
        }
        Ok(true)
    }

    /// A stop hit by the flying ball at `s` (module doc): the centre rotated about A onto the
    /// stop line, a frictionless impulse along `∇α_f`; the ball flies on, the accelerations go
    /// on from before the impulse ([`Self::after_impulse`]).
    fn stop_in_flight(
        &self,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
    ) -> Result<Impact<T>, Error> {
        let impact = self.stop_impulse(s, side, inside, ws)?;
        self.after_impulse(s);
        Ok(impact)
    }

    /// The projection and impulse of [`Self::stop_in_flight`] (no acceleration).
    fn stop_impulse(
        &self,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
    ) -> Result<Impact<T>, Error> {
        let ball = &self.params.ball;
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _) = tip::psi_and_rate(&x);
        let rel = self.relative(s);
        let line = if inside || !self.perfectly_elastic() {
            ball.stop_angle
        } else {
            ball.stop_angle + lit(BEYOND_OFFSET)
        };
        let theta = psi + side.sign::<T>() * line;
        let (sin, cos) = theta.fast_sin_cos();
        let (a, _) = self.end_point(s);
        s.flight.centre = [a[0] + rel.r * sin, a[1] - rel.r * cos];
        let (_, speed) = self.flight_relative_angle(s);
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: T::zero(),
            energy_loss: T::zero(),
            stuck: false,
        };
        // Towards the stop's face: outwards from the track's side, inwards from beyond.
        let towards = if inside {
            side.sign::<T>() * speed
        } else {
            -side.sign::<T>() * speed
        };
        if towards > T::zero() {
            let e = if speed.abs() < ball.stick_speed {
                T::zero()
            } else {
                ball.restitution
            };
            // ∇α_f on the housing: −t_f/r on A, −∂ψ/∂(a₃, a₄) = −(−a₄, a₃)/s² on the slope.
            let a3 = T::one() + x.q[2];
            let a4 = x.q[3];
            let s2 = a3 * a3 + a4 * a4;
            let grad = [-cos / rel.r, -sin / rel.r, a4 / s2, -a3 / s2];
            let mut y = SVector::<T, D>::zeros();
            // With events at the step end the trial's own factors serve (docs/model.md).
            let reuse = self.events_at_step_end();
            self.impulse_metric(s, Contact::InFlight, reuse, true, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, grad);
            ws.solve(&mut y)?;
            let k = T::one() / (ball.mass * rel.r * rel.r) + self.end_dot(&y, grad);
            if !is_positive(k) {
                return Err(Error::Singular);
            }
            let mut lambda = -(T::one() + e) * speed / k;
            if e >= T::one() && self.perfectly_elastic() {
                // Perfectly elastic: the kinetic energy is kept exactly in any metric. Along
                // (ball, housing) = ((cos, sin)/(m_b r), y): b = t·ċ/r + q̇ᵀM y,
                // c = 1/(m_b r²) + yᵀM y.
                let v = s.flight.velocity;
                if let Some(l) = self
                    .mass_products(s, Contact::InFlight, &mut y, ws)
                    .and_then(|(uy, yy)| {
                        let b = uy + (cos * v[0] + sin * v[1]) / rel.r;
                        let c = T::one() / (ball.mass * rel.r * rel.r) + yy;
                        crate::stops::energy_exact_impulse(speed, b, c)
                    })
                {
                    lambda = l;
                }
            }
            s.v.axpy(lambda, &y, T::one());
            let dv = lambda / (ball.mass * rel.r);
            s.flight.velocity[0] += dv * cos;
            s.flight.velocity[1] += dv * sin;
            impact.impulse = lambda / rel.r;
            impact.energy_loss = lit::<T>(0.5) * (T::one() - e * e) * speed * speed / k;
        }
        Ok(impact)
    }

    /// `y[END..END+4] = v` (the end node's coordinates).
    fn put_end(&self, y: &mut SVector<T, D>, v: [T; 4]) {
        if let Some(dst) = y.as_mut_slice().get_mut(Self::END..Self::END + 4) {
            for (d, x) in dst.iter_mut().zip(v.iter()) {
                *d = *x;
            }
        }
    }

    /// `y[END..END+4] · v`.
    fn end_dot(&self, y: &SVector<T, D>, v: [T; 4]) -> T {
        let mut sum = T::zero();
        if let Some(src) = y.as_slice().get(Self::END..Self::END + 4) {
            for (a, b) in src.iter().zip(v.iter()) {
                sum += *a * *b;
            }
        }
        sum
    }

    /// A rolling ball beyond a stop at the end of a step's rest: held on it (plastic), released
    /// at once if the stop would pull.
    pub(crate) fn rest_on_stop(
        &self,
        end: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        let side = if self.relative_angle(end) > T::zero() {
            Side::Positive
        } else {
            Side::Negative
        };
        self.hold_on_stop(end, side);
        end.contact = Contact::OnStop(side);
        let acc = self.consistent_acceleration(end, ws, self.params.integrator.newton)?;
        report.iterations += acc.iterations;
        end.a = acc.x;
        end.pseudo_accel = end.a;
        // (The release test's residual is charged to the work cap; unaffordable, released.)
        if !ws.afford_event(crate::newton::work::RESIDUAL)
            || side.sign::<T>() * self.contact_force(end) > T::zero()
        {
            end.contact = Contact::Off;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::{FreeBall, ImpactModel, Model, Params};

    /// A flying state on the circle at 40° from the bottom, moving outwards at 0.3 m/s and
    /// along the track at 0.2 m/s relative to a moving housing.
    fn at_landing(e_n: f64) -> (Model<f64, FreeBall, 3, 13>, State<f64, 13>) {
        at_landing_in(e_n, ImpactModel::Instantaneous)
    }

    /// [`at_landing`] with the impulse metric `model`.
    fn at_landing_in(
        e_n: f64,
        model: ImpactModel,
    ) -> (Model<f64, FreeBall, 3, 13>, State<f64, 13>) {
        let mut p = Params::<f64>::default();
        p.ball.landing_restitution = e_n;
        p.ball.restitution = e_n;
        p.ball.impact_model = model;
        let m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("start");
        let mut s = m.state;
        for i in 0..12 {
            s.v[i] = 0.05 * ((i as f64) * 1.7).sin();
        }
        s.v[12] = 3.0;
        let (a, a_rate) = m.sys.end_point(&s);
        let rho = p.ball.path_radius();
        let th = 40f64.to_radians();
        let (n, t) = ([th.sin(), -th.cos()], [th.cos(), th.sin()]);
        s.contact = Contact::InFlight;
        s.flight.centre = [a[0] + rho * n[0], a[1] + rho * n[1]];
        s.flight.velocity = [
            a_rate[0] + 0.3 * n[0] + 0.2 * t[0],
            a_rate[1] + 0.3 * n[1] + 0.2 * t[1],
        ];
        (m, s)
    }

    fn kinetic(m: &mut Model<f64, FreeBall, 3, 13>, s: &State<f64, 13>) -> f64 {
        m.state = *s;
        let e = m.energies(0.0, 0.0);
        e.beam_kinetic + e.tip_kinetic + e.ball_kinetic
    }

    /// The landing operator alone. Elastic (e_n = 1): the normal speed reverses and the
    /// kinetic energy is unchanged to rounding (1e-12 of it). Plastic (e_n = 0): the ball rolls
    /// on (its centre velocity is the rolling kinematics' and has no normal component), the
    /// track pushed (P_n > 0), and kinetic energy was lost, at most the normal part m_b v_n²/2
    /// plus the slip's.
    #[test]
    fn landing_operator_conserves_energy_when_elastic_and_rolls_on_when_plastic() {
        let (mut m, s0) = at_landing(1.0);
        let before = kinetic(&mut m, &s0);
        let mut s = s0;
        let mut ws = Workspace::default();
        let mut report = StepReport {
            iterations: 0,
            increment: 0.0,
            impact: None,
            separation: None,
            landing: None,
            work: 0,
            outcome: crate::Outcome::Converged,
            events: crate::state::EventCounts::default(),
        };
        m.sys.land(&mut s, &mut ws, &mut report).expect("land");
        let l = report.landing.expect("landed");
        assert!(l.bounced && (l.normal_speed - 0.3).abs() < 1e-12);
        let after = kinetic(&mut m, &s);
        assert!(
            (after - before).abs() < 1e-12 * before,
            "{before} → {after}"
        );
        let rel = m.sys.relative(&s);
        let vn = (rel.d[0] * rel.rate[0] + rel.d[1] * rel.rate[1]) / rel.r;
        assert!((vn + 0.3).abs() < 1e-12, "{vn}");

        let (mut m, s0) = at_landing(0.0);
        let before = kinetic(&mut m, &s0);
        let mut s = s0;
        report.landing = None;
        m.sys.land(&mut s, &mut ws, &mut report).expect("land");
        let l = report.landing.expect("landed");
        assert!(!l.bounced && s.contact == Contact::Off);
        assert!(l.normal_impulse > 0.0);
        let after = kinetic(&mut m, &s);
        assert!(after < before && before - after < 0.5 * 0.014 * (0.3f64 * 0.3 + 0.2 * 0.2));
        let (c, cd) = m.sys.ball_centre(&s);
        let (a, ad) = m.sys.end_point(&s);
        let n = [(c[0] - a[0]) / 0.032, (c[1] - a[1]) / 0.032];
        let vn = n[0] * (cd[0] - ad[0]) + n[1] * (cd[1] - ad[1]);
        assert!(vn.abs() < 1e-12, "rolls on: normal speed {vn}");
    }

    fn empty_report() -> StepReport<f64> {
        StepReport {
            iterations: 0,
            increment: 0.0,
            impact: None,
            separation: None,
            landing: None,
            work: 0,
            outcome: crate::Outcome::Converged,
            events: crate::state::EventCounts::default(),
        }
    }

    /// Perfectly elastic impulses in the over-step metric (the default `W = M + γhC + βh²K`,
    /// here h = 3 ms) keep the kinetic energy to rounding (1e-12 of it): a landing, and a stop
    /// hit in flight from the track's side and from beyond, on a moving housing. The impulse
    /// along the metric's direction is the one that conserves it
    /// ([`crate::stops::energy_exact_impulse`]); the kinematic law of the other restitutions
    /// (the normal or angular rate reversed exactly in that metric) changed it (measured
    /// below). The rebound then differs from the reversed rate by the housing's velocity in
    /// the modes the metric holds back (its stiff modes, here moving at random); on a housing
    /// at rest by the housing's small share only (checked: 1 %).
    #[test]
    fn elastic_impulses_keep_the_kinetic_energy_in_the_over_step_metric() {
        for moving in [true, false] {
            let (mut m, mut s) = at_landing_in(1.0, ImpactModel::OverStep);
            if !moving {
                // The housing at rest, the ball meeting it at 0.3 m/s along the normal.
                let (a, _) = m.sys.end_point(&s);
                let d = [s.flight.centre[0] - a[0], s.flight.centre[1] - a[1]];
                let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
                s.v.fill(0.0);
                let n = [d[0] / r, d[1] / r];
                s.flight.velocity = [0.3 * n[0] - 0.2 * n[1], 0.3 * n[1] + 0.2 * n[0]];
            }
            let before = kinetic(&mut m, &s);
            let mut ws = Workspace::default();
            let mut report = empty_report();
            m.sys.land(&mut s, &mut ws, &mut report).expect("land");
            assert!(report.landing.expect("landed").bounced);
            let after = kinetic(&mut m, &s);
            let rel = m.sys.relative(&s);
            let vn = (rel.d[0] * rel.rate[0] + rel.d[1] * rel.rate[1]) / rel.r;
            println!("landing (housing moving: {moving}): {before} → {after}, rebound {vn}");
            assert!(
                (after - before).abs() < 1e-12 * before,
                "{before} → {after}"
            );
            assert!(
                vn < 0.0 && (moving || (vn + 0.3).abs() < 0.01 * 0.3),
                "{vn}"
            );
        }

        // A stop at the stops' height: the ball at 64° on the circle, moving outwards along
        // the track at 2 rad/s relative to the housing (towards the + stop), and at −66°
        // beyond the − stop, moving away from the track (towards the − stop's outer face).
        for (angle, rate, inside) in [(64.0f64, 2.0, true), (-66.0, 2.0, false)] {
            let (mut m, mut s) = at_landing_in(1.0, ImpactModel::OverStep);
            let (a, a_rate) = m.sys.end_point(&s);
            let x = System::<f64, FreeBall, 3, 13>::local(&s.q, &s.v, &s.a);
            let (psi, psi_rate) = tip::psi_and_rate(&x);
            let rho = 0.99 * m.sys.params.ball.path_radius();
            let th = psi + angle.to_radians();
            let w = psi_rate + rate;
            s.flight.centre = [a[0] + rho * th.sin(), a[1] - rho * th.cos()];
            s.flight.velocity = [
                a_rate[0] + rho * w * th.cos(),
                a_rate[1] + rho * w * th.sin(),
            ];
            let before = kinetic(&mut m, &s);
            let side = if inside {
                Side::Positive
            } else {
                Side::Negative
            };
            let (_, speed) = m.sys.flight_relative_angle(&s);
            let mut ws = Workspace::default();
            m.sys
                .stop_impulse(&mut s, side, inside, &mut ws)
                .expect("stop");
            let after = kinetic(&mut m, &s);
            let (alpha, rebound) = m.sys.flight_relative_angle(&s);
            println!("stop at {angle}°: {before} → {after}, rate {speed} → {rebound}, α {alpha}");
            assert!(
                (after - before).abs() < 1e-12 * before,
                "{before} → {after}"
            );
            assert!(rebound * speed < 0.0, "{speed} → {rebound}");
        }
    }

    /// Where a bounce's energy goes (docs/model.md, "Elastic bounces at the paper's step"): the
    /// stiff housing (E × 10⁴) at rest, the ball meeting the track's bottom at 1.1 m/s (a drop
    /// from 0.95ρ above A), e_n = 1. The housing's effective mass at A along the vertical is
    /// `m_eff = 1/(e_yᵀ M⁻¹ e_y)` (M: the flight mode's mass matrix, beam and tip body) =
    /// 0.126 kg, 87 % of its compliance in the first mode (429 Hz), 6.5 % at 4.1 kHz, the rest in
    /// modes up to 4 MHz (the end node's axial and slope-stretch modes; printed). An
    /// instantaneous impulse (the mass metric) is the collision of two free masses: the ball
    /// rebounds at `(1 − μ)/(1 + μ)` of its speed, μ = m_b/m_eff = 0.111, and hands the housing
    /// `4μ/(1 + μ)²` = 36 % of its kinetic energy (checked to 1e-9). The over-step metric
    /// (h = 3 ms) spreads the impulse over the step, which the 429 Hz mode (ωh = 8) follows
    /// quasi-statically: the housing takes 0.065 % (checked: below 0.1 %).
    #[test]
    fn a_bounce_on_a_stiff_housing_hands_it_a_third_of_the_energy_if_instantaneous() {
        let v = 1.1;
        let mut shares = [0.0; 2];
        for (i, model) in [ImpactModel::Instantaneous, ImpactModel::OverStep]
            .into_iter()
            .enumerate()
        {
            let mut p = Params::<f64>::default();
            p.beam.modulus *= 1e4;
            p.ball.landing_restitution = 1.0;
            p.ball.restitution = 1.0;
            p.ball.impact_model = model;
            let mut m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("start");
            let mut s = m.state;
            let (a, _) = m.sys.end_point(&s);
            let rho = p.ball.path_radius();
            s.contact = Contact::InFlight;
            s.flight.centre = [a[0], a[1] - rho];
            s.flight.velocity = [0.0, -v];
            let before = kinetic(&mut m, &s);
            let mut ws = Workspace::default();
            let mut report = empty_report();
            m.sys.land(&mut s, &mut ws, &mut report).expect("land");
            let ball =
                0.5 * p.ball.mass * (s.flight.velocity[0].powi(2) + s.flight.velocity[1].powi(2));
            let after = kinetic(&mut m, &s);
            assert!(
                (after - before).abs() < 1e-12 * before,
                "{before} → {after}"
            );
            shares[i] = (after - ball) / before;
            if model == ImpactModel::Instantaneous {
                let z = SVector::<f64, 13>::zeros();
                let matrix = |q: &SVector<f64, 13>, c_q: f64, c_m: f64| {
                    let ch = crate::scheme::Chain { c_q, c_v: 0.0, c_m };
                    let (_, j, _) =
                        m.sys
                            .assemble(q, &z, &z, p.gravity, &ch, Contact::InFlight, false);
                    j
                };
                let mass = matrix(&s.q, 0.0, 1.0);
                let mut e_y = SVector::<f64, 13>::zeros();
                e_y[System::<f64, FreeBall, 3, 13>::END + 1] = 1.0;
                let compliance = e_y.dot(&mass.lu().solve(&e_y).expect("M"));
                let mu = p.ball.mass * compliance;
                println!("m_eff = {:.4} kg, μ = {mu:.4}", 1.0 / compliance);
                assert!((1.0 / compliance - 0.126).abs() < 0.001);
                let rebound = (1.0 - mu) / (1.0 + mu) * v;
                assert!(
                    (s.flight.velocity[1] - rebound).abs() < 1e-9,
                    "{:?}",
                    s.flight.velocity
                );
                assert!((shares[i] - 4.0 * mu / (1.0 + mu).powi(2)).abs() < 1e-9);
                // The compliance at A by mode (M = LLᵀ, modes of L⁻¹KL⁻ᵀ; the spin, free in
                // flight, is left out).
                let eq = m.sys.equilibrium;
                let (mass, stiffness) = (matrix(&eq, 0.0, 1.0), matrix(&eq, 1.0, 0.0));
                let sub = |x: &nalgebra::SMatrix<f64, 13, 13>| {
                    let y = x.fixed_view::<12, 12>(0, 0).into_owned();
                    (y + y.transpose()) * 0.5
                };
                let l = sub(&mass).cholesky().expect("M > 0").l();
                let x = l.solve_lower_triangular(&sub(&stiffness)).expect("L");
                let k = l.solve_lower_triangular(&x.transpose()).expect("L");
                let eig = ((k + k.transpose()) * 0.5).symmetric_eigen();
                let mut f = nalgebra::SVector::<f64, 12>::zeros();
                f[System::<f64, FreeBall, 3, 13>::END + 1] = 1.0;
                let zf = l.solve_lower_triangular(&f).expect("L");
                let mut modes: std::vec::Vec<(f64, f64)> = (0..12)
                    .map(|j| {
                        let hz = eig.eigenvalues[j].max(0.0).sqrt() / core::f64::consts::TAU;
                        (
                            hz,
                            eig.eigenvectors.column(j).dot(&zf).powi(2) / zf.norm_squared(),
                        )
                    })
                    .collect();
                modes.sort_by(|a, b| a.0.total_cmp(&b.0));
                for (hz, share) in &modes {
                    println!("{hz:12.1} Hz: {share:.4} of the compliance at A");
                }
                let (first, second) = (modes[0], modes[1]);
                assert!((first.0 - 429.0).abs() < 1.0 && (first.1 - 0.872).abs() < 0.001);
                assert!((second.0 - 4103.0).abs() < 5.0 && (second.1 - 0.065).abs() < 0.001);
            }
        }
        println!(
            "housing's share: instantaneous {:.4}, over-step {:.2e}",
            shares[0], shares[1]
        );
        assert!(shares[1] < 1e-3, "{}", shares[1]);
    }

    #[test]
    fn separation_fraction_is_the_linear_zero_and_zero_without_positive_start() {
        assert_eq!(separation_fraction(1.0f64, -3.0), 0.25);
        assert_eq!(separation_fraction(0.0f64, -3.0), 0.0);
        assert_eq!(separation_fraction(-1.0f64, -3.0), 0.0);
    }

    #[test]
    fn hermite_root_is_exact_for_a_cubic() {
        // f(τ) = (τ − 0.3)(1 + τ²): values and scaled rates at both ends.
        let f = |t: f64| (t - 0.3) * (1.0 + t * t);
        let df = |t: f64| (1.0 + t * t) + 2.0 * t * (t - 0.3);
        let tau = hermite_root(f(0.0), df(0.0), f(1.0), df(1.0));
        assert!((tau - 0.3).abs() < 1e-12, "{tau}");
    }

    #[test]
    fn bounce_impulse_reverses_normal_speed() {
        let (v, k, e) = (0.2f64, 1.0 / 0.014 + 3.0, 0.5);
        let p = bounce_impulse(v, k, e);
        assert!((v - p * k + e * v).abs() < 1e-15);
        assert!(landing_bounces(0.5, 0.01, 0.0008, 0.0));
        assert!(!landing_bounces(0.0, 0.01, 0.0008, 0.0));
        // Pressed at 15 m/s² over 3 ms: a rebound at 5 mm/s is back within 0.7 ms.
        assert!(!landing_bounces(0.5, 0.01, 0.0008, 0.045));
        assert!(landing_bounces(0.5, 0.1, 0.0008, 0.045));
        assert!(
            landing_bounces(1.0, 0.1, 0.0, 0.045),
            "elastic, a flight of 13 ms"
        );
    }
}
