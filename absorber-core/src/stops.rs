//! The ±stops of the free ball (paper §3.5; MODEL.md, MODEL-DERIVATION §6): crossing, impact,
//! stick and release.
//!
//! A step whose trial end has the ball beyond a stop is split at the crossing:
//! 1. the crossing fraction τ is the root of the cubic Hermite interpolant of α = θ − ψ
//!    through both step ends with their rates ([`System::crossing_fraction`]);
//! 2. a Newmark sub-step of length τh reaches the crossing;
//! 3. the impact ([`System::impact`]) projects the ball onto the stop and applies the impulse
//!    with the Newmark matrix `W = M + γhC + βh²K` at the crossing;
//! 4. the consistent acceleration after the impulse and the Newmark rest of the step,
//!    `(1 − τ)h`, follow.
//!
//! Each of these solves has its own Newton matrix (another step length, or the mass matrix
//! alone), reused within it ([`crate::newton`]): an impact step factors about five times where
//! an ordinary step factors once (docs/embedded.md measures the worst step).
//!
//! With events at the step end ([`crate::EventLocation::StepEnd`]) the trial stands and the
//! impact acts at its end (`impact_at_end`): no sub-steps, no consistent acceleration.
//!
//! A ball resting on a stop is held there (`φ = ψ − (ρ/r_b) α_stop`) until the stop would have
//! to pull it.

use crate::error::Error;
use crate::model::{Contact, Impact, Side, State, StepReport};
use crate::newton::Workspace;
use crate::params::{EventLocation, ImpactModel};
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::system::{Problem, System};
use crate::tip::{self, Chain};
use nalgebra::SVector;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The stop events of a step from `start` whose trial end is `next`: an impact when the
    /// ball crossed a stop (`next` becomes the step redone with it), a release when a held ball
    /// would be pulled.
    pub(crate) fn stop_events(
        &self,
        start: &State<T, D>,
        next: &mut State<T, D>,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        if !(S::STOPS && S::EXTRA_DOFS == 1) {
            return Ok(());
        }
        match next.contact {
            Contact::Off => {
                let alpha = self.relative_angle(next);
                if alpha.abs() > self.params.ball.stop_angle {
                    if self.event_at_end(ws) {
                        let side = Side::of(alpha);
                        self.impact_at_end(start, next, side, true, ws, report)?;
                    } else {
                        *next = self.impact_step(start, next, true, base_accel, ws, report)?;
                    }
                }
            }
            // A ball that flew over a stop rolls on the arc beyond it: crossing back is an
            // impact on the stop's other face.
            Contact::Beyond if S::FLIGHT => {
                let (a0, a1) = self.branch_angles(start, next);
                if a1.abs() < self.params.ball.stop_angle {
                    if self.event_at_end(ws) {
                        let side = Side::of(a0);
                        self.impact_at_end(start, next, side, false, ws, report)?;
                    } else {
                        *next = self.impact_step(start, next, false, base_accel, ws, report)?;
                    }
                }
            }
            Contact::OnStop(side) => {
                if side.sign::<T>() * self.contact_force(next) > T::zero() {
                    next.contact = Contact::Off;
                }
            }
            Contact::InFlight | Contact::Beyond => {} // (flight events: crate::flight)
        }
        Ok(())
    }

    /// Events are put at the end of their step ([`EventLocation::StepEnd`]).
    #[inline]
    pub(crate) fn events_at_step_end(&self) -> bool {
        self.params.integrator.events == EventLocation::StepEnd
    }

    /// The impact of a step whose trial end `s` crossed a stop, put at the step's end
    /// ([`EventLocation::StepEnd`]): `s` projected onto the stop and the impulse in the trial's
    /// own Newton matrix (the over-step metric, already factored); the acceleration stays the
    /// trial's (docs/model.md: a consistent one made the next step's Newton slow). Kept out of
    /// line (rare).
    #[inline(never)]
    #[cold]
    fn impact_at_end(
        &self,
        start: &State<T, D>,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        s.time = start.time + self.params.integrator.step;
        // The acceleration stays the trial's (a stuck ball's is made consistent by `impact`).
        report.impact = Some(self.impact(s, side, inside, ws)?);
        Ok(())
    }

    /// The relative angles of two states on one branch: `α₀` in `(−π, π]` and `α₁` the nearest
    /// to it (a ball beyond the stops may roll past the top, where θ − ψ leaves `(−π, π]`).
    pub(crate) fn branch_angles(&self, a: &State<T, D>, b: &State<T, D>) -> (T, T) {
        let (raw0, raw1) = (self.relative_angle(a), self.relative_angle(b));
        let a0 = crate::flight::wrap(raw0);
        (a0, a0 + crate::flight::wrap(raw1 - raw0))
    }

    /// Splits a step that crossed a stop (module doc), from the span between the stops
    /// (`inside`) or from the arc beyond them. Kept out of line (rare): the ordinary step's
    /// frame does not carry its states.
    #[inline(never)]
    fn impact_step(
        &self,
        start: &State<T, D>,
        trial: &State<T, D>,
        inside: bool,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<State<T, D>, Error> {
        let kind = self.params.integrator.newton;
        let h = self.params.integrator.step;
        let stop = self.params.ball.stop_angle;
        let tau;
        let side;
        if inside {
            side = if self.relative_angle(trial) > T::zero() {
                Side::Positive
            } else {
                Side::Negative
            };
            tau = self.crossing_fraction(start, trial, h, side.sign::<T>() * stop);
        } else {
            let (a0, a1) = self.branch_angles(start, trial);
            let outer = if inside { a1 } else { a0 };
            side = if outer > T::zero() {
                Side::Positive
            } else {
                Side::Negative
            };
            let target = side.sign::<T>() * stop;
            tau = crate::flight::hermite_root(
                a0 - target,
                self.relative_rate(start) * h,
                a1 - target,
                self.relative_rate(trial) * h,
            );
        }
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = *start;
        self.sub_step(start, h1, accel_mid, ws, report, &mut mid)?;
        mid.time = start.time + h1;
        let impact = self.impact(&mut mid, side, inside, ws)?;
        if !impact.stuck {
            let acc = self.consistent_acceleration(&mid, ws, kind)?;
            report.iterations += acc.iterations;
            mid.a = acc.x;
        }
        // The velocity jumped: the generalized-α recursion restarts from the new acceleration.
        mid.pseudo_accel = mid.a;
        let rest = h - tau * h;
        let mut end = mid;
        self.sub_step(&mid, rest, base_accel, ws, report, &mut end)?;
        // A second crossing within the same (remaining) step: the ball came straight back
        // onto the stop; end the step with it resting there (plastic).
        if inside && end.contact == Contact::Off && self.relative_angle(&end).abs() > stop {
            self.rest_on_stop(&mut end, ws, report)?;
        }
        report.impact = Some(impact);
        Ok(end)
    }

    /// Fraction τ ∈ \[0, 1\] of the step at which α reaches `target`: root of the cubic Hermite
    /// interpolant of α through both step ends with their rates (error O(h⁴); a linear
    /// interpolant, error O(h²), misplaces the ball by ~α̈h²/8, which the projection onto the
    /// stop then turns into a potential-energy error).
    fn crossing_fraction(&self, start: &State<T, D>, end: &State<T, D>, h: T, target: T) -> T {
        crate::flight::hermite_root(
            self.relative_angle(start) - target,
            self.relative_rate(start) * h,
            self.relative_angle(end) - target,
            self.relative_rate(end) * h,
        )
    }

    /// Stop impact (MODEL.md, MODEL-DERIVATION §6): projects the ball onto the stop, applies the
    /// generalized impulse `Λ = −(1+e) Ġ⁻ / (∇G W⁻¹ ∇Gᵀ)` along `∇G = ∂(θ − ψ)/∂q`,
    /// `q̇⁺ = q̇⁻ + W⁻¹ ∇Gᵀ Λ`, and decides whether the ball stays on the stop. `W` is the
    /// step's factored Newmark matrix ([`ImpactModel::OverStep`]) or the mass matrix at the
    /// impact ([`ImpactModel::Instantaneous`]); either way `Ġ⁺ = −e Ġ⁻` exactly.
    pub(crate) fn impact(
        &self,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
    ) -> Result<Impact<T>, Error> {
        let ball = &self.params.ball;
        let lock = side.sign::<T>() * ball.stop_angle;
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _) = tip::psi_and_rate(&x);
        if let Some(spin) = s.q.get_mut(Self::SPIN) {
            *spin = psi - lock / self.inertia.orbit_per_spin;
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let grad_local = tip::gap_gradient(&self.inertia, &x);
        let mut grad = SVector::<T, D>::zeros();
        if let Some(dst) = grad.as_mut_slice().get_mut(Self::END..) {
            for (g, gk) in dst.iter_mut().zip(grad_local.iter()) {
                *g = *gk;
            }
        }
        let speed = grad.dot(&s.v);
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: T::zero(),
            energy_loss: T::zero(),
            stuck: false,
        };
        let plastic = speed.abs() < ball.stick_speed;
        // Towards the stop's face: outwards from between the stops, inwards from beyond.
        let towards = if inside {
            side.sign::<T>() * speed
        } else {
            -side.sign::<T>() * speed
        };
        if towards > T::zero() {
            let e = if plastic { T::zero() } else { ball.restitution };
            let mut y = grad;
            self.impulse_metric(s, Contact::Off, true, ws, &mut y)?;
            y = grad;
            ws.solve(&mut y)?;
            let w = grad.dot(&y);
            if !is_positive(w) {
                return Err(Error::Singular);
            }
            let lambda = -(T::one() + e) * speed / w;
            s.v.axpy(lambda, &y, T::one());
            // Λ is conjugate to α (N·m·s); the contact point moves at ρ α̇ along the track.
            impact.impulse = lambda / ball.path_radius();
            impact.energy_loss = lit::<T>(0.5) * (T::one() - e * e) * speed * speed / w;
        }
        s.contact = if inside {
            Contact::Off
        } else {
            Contact::Beyond
        };
        // (The stick test's residual is charged to the work cap; unaffordable, no test: the
        // ball rebounds plastically and the step is flagged.)
        if plastic && inside && ws.afford_event(crate::newton::work::RESIDUAL) {
            // Stay on the stop if the contact force is compressive. Tried on `s` itself (what
            // holding changes is saved and put back otherwise: no second state in the frame).
            let saved = (s.contact, s.a, s.pseudo_accel, Self::spin_of(s));
            s.contact = Contact::OnStop(side);
            self.hold_on_stop(s, side);
            let acc = self.consistent_acceleration(s, ws, self.params.integrator.newton)?;
            s.a = acc.x;
            s.pseudo_accel = s.a;
            if side.sign::<T>() * self.contact_force(s) <= T::zero() {
                impact.stuck = true;
            } else {
                let (contact, a, pseudo_accel, spin) = saved;
                (s.contact, s.a, s.pseudo_accel) = (contact, a, pseudo_accel);
                Self::set_spin(s, spin);
            }
        }
        Ok(impact)
    }

    /// Makes the impulse metric of the mode `contact` the current factors: the Newmark matrix
    /// `W = M + γhC + βh²K` of a whole step ([`ImpactModel::OverStep`]: the impulse spread over
    /// the step does not kick the housing's stiff end-rotation mode), or the mass matrix
    /// ([`ImpactModel::Instantaneous`]). With `reuse`, the current factors serve when they were
    /// built for that matrix (the step's own: an impact at the step's start, or at its end);
    /// else it is assembled and factored at the configuration of `s`. `scratch` takes the
    /// assembly's residual (not needed; no vector of its own in the frame). The stops' and the
    /// flying ball's impulses share it.
    pub(crate) fn impulse_metric(
        &self,
        s: &State<T, D>,
        contact: Contact,
        reuse: bool,
        ws: &mut Workspace<T, D>,
        scratch: &mut SVector<T, D>,
    ) -> Result<(), Error> {
        let ch = if self.params.ball.impact_model == ImpactModel::OverStep {
            self.newmark_chain(self.params.integrator.step)
        } else {
            Chain {
                c_q: T::zero(),
                c_v: T::zero(),
                c_m: T::one(),
            }
        };
        if reuse && ws.has_factors(ch.c_q, contact) {
            return Ok(());
        }
        // Assembled at (q, v, a) of `s` as given to `refresh_at`; the problem's own chain
        // origin is not used by an assembly.
        let p = Problem {
            q0: &s.q,
            v0: &s.v,
            a0: &s.a,
            ch,
            c_pos: T::one(),
            g_eff: self.effective_gravity(s.base_accel),
            contact,
            plumb: false,
        };
        self.refresh_at(&p, [&s.q, &s.v, &s.a], ws, scratch)
    }

    /// The spin's position and rate `(φ, φ̇)` (zeros without a free ball).
    fn spin_of(s: &State<T, D>) -> (T, T) {
        (
            s.q.get(Self::SPIN).copied().unwrap_or(T::zero()),
            s.v.get(Self::SPIN).copied().unwrap_or(T::zero()),
        )
    }

    /// Sets the spin's position and rate (no effect without a free ball).
    fn set_spin(s: &mut State<T, D>, (q, v): (T, T)) {
        if let (Some(x), Some(y)) = (s.q.get_mut(Self::SPIN), s.v.get_mut(Self::SPIN)) {
            (*x, *y) = (q, v);
        }
    }

    /// Projects a ball resting on a stop onto α = side·α_max: φ = ψ − (ρ/r_b) α, φ̇ = ψ̇, φ̈ = ψ̈
    /// (and the generalized-α variable of φ likewise: a held φ is no unknown of its own).
    pub(crate) fn hold_on_stop(&self, s: &mut State<T, D>, side: Side) {
        let (psi, rate, acc) = tip::psi_all(&Self::local(&s.q, &s.v, &s.a));
        let lock = side.sign::<T>() * self.params.ball.stop_angle;
        let k = self.inertia.orbit_per_spin;
        if let (Some(q), Some(v), Some(a)) = (
            s.q.get_mut(Self::SPIN),
            s.v.get_mut(Self::SPIN),
            s.a.get_mut(Self::SPIN),
        ) {
            *q = psi - lock / k;
            *v = rate;
            *a = acc;
        }
        if let Some(p) = s.pseudo_accel.get_mut(Self::SPIN) {
            *p = acc;
        }
    }
}
