//! The ±stops of the free ball (paper §3.5; docs/derivation.md §6): crossing, impact,
//! stick and release.
//!
//! A step whose trial end has the ball beyond a stop is split at the crossing:
//! 1. the crossing fraction τ is the root of the cubic Hermite interpolant of α = θ − ψ
//!    through both step ends with their rates ([`System::crossing_fraction`]);
//! 2. a Newmark sub-step of length τh reaches the crossing;
//! 3. the impact ([`System::impact`]) projects the ball onto the stop and applies the impulse
//!    with the Newmark matrix `W = M + γτC + βτ²K` at the crossing (τ the stop's contact time,
//!    `ball.stop_contact_time`, or the step h); a perfectly elastic ball's
//!    ([`System::perfectly_elastic`]) along the same direction, sized to keep the kinetic energy
//!    ([`energy_exact_impulse`]);
//! 4. the Newmark rest of the step, `(1 − τ)h`, follows from the velocities after the impulse
//!    and the accelerations before it ([`System::after_impulse`]).
//!
//! Each of these solves has its own Newton matrix (another step length, or the mass matrix
//! alone), reused within it ([`crate::step::newton`]): an impact step factors about four times where
//! an ordinary step factors once (docs/embedded.md measures the worst step).
//!
//! With events at the step end ([`crate::EventLocation::StepEnd`]) the trial stands and the
//! impact acts at its end (`impact_at_end`): no sub-steps, no consistent acceleration.
//!
//! A ball resting on a stop is held there (`φ = ψ − (ρ/r_b) α_stop`) until the stop would have
//! to pull it.

use crate::error::Error;
use crate::params::{EventLocation, ImpactModel};
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::{Contact, Impact, Side, State, StepReport};
use crate::step::newton::Workspace;
use crate::step::scheme::Chain;
use crate::step::system::{Problem, System};
use crate::step::tip;
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
                        self.impact_step(start, next, true, base_accel, ws, report)?;
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
                        self.impact_step(start, next, false, base_accel, ws, report)?;
                    }
                }
            }
            Contact::OnStop(side) => {
                if side.sign::<T>() * self.contact_force(next) > T::zero() {
                    next.contact = Contact::Off;
                }
            }
            Contact::InFlight | Contact::Beyond => {} // (flight events: crate::step::flight)
        }
        Ok(())
    }

    /// Events are put at the end of their step ([`EventLocation::StepEnd`]).
    #[inline]
    pub(crate) fn events_at_step_end(&self) -> bool {
        !S::EVENTS_AT_CROSSING || self.params.integrator.events == EventLocation::StepEnd
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
        report.events.impacts += 1;
        Ok(())
    }

    /// The relative angles of two states on one branch: `α₀` in `(−π, π]` and `α₁` the nearest
    /// to it (a ball beyond the stops may roll past the top, where θ − ψ leaves `(−π, π]`).
    pub(crate) fn branch_angles(&self, a: &State<T, D>, b: &State<T, D>) -> (T, T) {
        let (raw0, raw1) = (self.relative_angle(a), self.relative_angle(b));
        let a0 = crate::step::flight::roots::wrap(raw0);
        (a0, a0 + crate::step::flight::roots::wrap(raw1 - raw0))
    }

    /// Splits a step that crossed a stop (module doc), from the span between the stops
    /// (`inside`) or from the arc beyond them: `trial`, the step's trial end, becomes the step
    /// redone with the impact, and stays the trial on error. Kept out of line (rare): the
    /// ordinary step's frame does not carry its states (nor a returned one: the result is
    /// written into `trial` here).
    #[inline(never)]
    fn impact_step(
        &self,
        start: &State<T, D>,
        trial: &mut State<T, D>,
        inside: bool,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
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
            tau = crate::step::flight::roots::hermite_root(
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
        self.event_accel(start, trial, tau, &mut mid);
        let impact = self.impact(&mut mid, side, inside, ws)?;
        report.events.impacts += 1;
        if !impact.stuck {
            // The velocities jumped; the accelerations go on from before the impulse.
            self.after_impulse(&mut mid);
        }
        let rest = h - tau * h;
        let mut end = mid;
        self.sub_step(&mid, rest, base_accel, ws, report, &mut end)?;
        // A second crossing within the same (remaining) step: the ball came straight back
        // onto the stop; end the step with it resting there (plastic: a second impact).
        if inside && end.contact == Contact::Off && self.relative_angle(&end).abs() > stop {
            self.rest_on_stop(&mut end, ws, report)?;
            report.events.impacts += 1;
        }
        report.impact = Some(impact);
        *trial = end;
        Ok(())
    }

    /// Fraction τ ∈ \[0, 1\] of the step at which α reaches `target`: root of the cubic Hermite
    /// interpolant of α through both step ends with their rates (error O(h⁴); a linear
    /// interpolant, error O(h²), misplaces the ball by ~α̈h²/8, which the projection onto the
    /// stop then turns into a potential-energy error).
    fn crossing_fraction(&self, start: &State<T, D>, end: &State<T, D>, h: T, target: T) -> T {
        crate::step::flight::roots::hermite_root(
            self.relative_angle(start) - target,
            self.relative_rate(start) * h,
            self.relative_angle(end) - target,
            self.relative_rate(end) * h,
        )
    }

    /// Stop impact (docs/derivation.md §6): projects the ball onto the stop, applies the
    /// generalized impulse `Λ = −(1+e) Ġ⁻ / (∇G W⁻¹ ∇Gᵀ)` along `∇G = ∂(θ − ψ)/∂q`,
    /// `q̇⁺ = q̇⁻ + W⁻¹ ∇Gᵀ Λ`, and decides whether the ball stays on the stop. `W` is the
    /// step's factored Newmark matrix ([`ImpactModel::OverStep`]) or the mass matrix at the
    /// impact ([`ImpactModel::Instantaneous`]); either way `Ġ⁺ = −e Ġ⁻` exactly — but for a
    /// perfectly elastic ball ([`System::perfectly_elastic`]), where `Λ` along the same
    /// direction keeps the kinetic energy ([`energy_exact_impulse`]; the same in the mass
    /// metric).
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
            self.impulse_metric(s, Contact::Off, true, true, ws, &mut y)?;
            y = grad;
            ws.solve(&mut y)?;
            let w = grad.dot(&y);
            if !is_positive(w) {
                return Err(Error::Singular);
            }
            let mut lambda = -(T::one() + e) * speed / w;
            if e >= T::one() && self.perfectly_elastic() {
                // Perfectly elastic: the kinetic energy is kept exactly in any metric.
                if let Some(l) = self
                    .mass_products(s, Contact::Off, &mut y, ws)
                    .and_then(|(b, c)| energy_exact_impulse(speed, b, c))
                {
                    lambda = l;
                }
            }
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
        if plastic && inside && ws.afford_event(crate::work::RESIDUAL) {
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
    /// `W = M + γτC + βτ²K` of a contact lasting τ ([`ImpactModel::OverStep`]: the impulse
    /// spread over τ does not kick the housing's stiff end-rotation mode), or the mass matrix
    /// ([`ImpactModel::Instantaneous`]). τ is the stop's contact time
    /// (`ball.stop_contact_time`) for a `stop` impulse when it is set, else the step h. With
    /// `reuse`, the current factors serve when they were built for that matrix (the step's own:
    /// an impact at the step's start, or at its end); else it is assembled and factored at the
    /// configuration of `s`. `scratch` takes the assembly's residual (not needed; no vector of
    /// its own in the frame). The stops' and the flying ball's impulses share it.
    pub(crate) fn impulse_metric(
        &self,
        s: &State<T, D>,
        contact: Contact,
        reuse: bool,
        stop: bool,
        ws: &mut Workspace<T, D>,
        scratch: &mut SVector<T, D>,
    ) -> Result<(), Error> {
        let ch = if self.params.ball.impact_model == ImpactModel::OverStep {
            let tau = self.params.ball.stop_contact_time;
            let duration = if stop && is_positive(tau) {
                tau
            } else {
                self.params.integrator.step
            };
            self.newmark_chain(duration)
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

    /// The products `(q̇ᵀ M y, yᵀ M y)` of the mass matrix `M(q)` of the mode `contact` at `s`
    /// with the velocities `q̇` of `s` and a direction `y` (an impulse's response `W⁻¹ g`), for
    /// the energy law of a perfectly elastic ball's impulse ([`energy_exact_impulse`]). The
    /// residual is linear in the accelerations, `r(q, q̇, a) = M(q) a + f(q, q̇)`, so
    /// `M y = (r(q, q̇, y) − r(q, q̇, −y)) / 2` (to the rounding of the forces that cancel),
    /// without a matrix: two residuals (charged to the work cap; `None` when it cannot afford
    /// them, or `y` is zero). `y` is negated and restored in place (no second vector in the
    /// frame).
    #[inline(never)]
    #[cold]
    pub(crate) fn mass_products(
        &self,
        s: &State<T, D>,
        contact: Contact,
        y: &mut SVector<T, D>,
        ws: &mut Workspace<T, D>,
    ) -> Option<(T, T)> {
        if !ws.afford_event(2 * crate::work::RESIDUAL) {
            return None;
        }
        let g = self.effective_gravity(s.base_accel);
        let mut r = SVector::<T, D>::zeros();
        self.residual([&s.q, &s.v, y], g, contact, false, &mut r);
        let (mut uy, mut yy) = (s.v.dot(&r), y.dot(&r));
        y.neg_mut();
        self.residual([&s.q, &s.v, y], g, contact, false, &mut r);
        y.neg_mut();
        let half = lit::<T>(0.5);
        uy = half * (uy - s.v.dot(&r));
        yy = half * (yy - y.dot(&r));
        (is_positive(yy) && uy.is_finite()).then_some((uy, yy))
    }

    /// After an impulse (a stop impact, a bounce, a rolling landing) the velocities have jumped;
    /// the accelerations and the generalized-α variable go on from before it. The impulse is the
    /// nonsmooth part of the motion and leaves its smooth part (the accelerations) continuous,
    /// as in the nonsmooth generalized-α scheme (Brüls, Acary & Cardona 2014, *Comput. Methods
    /// Appl. Mech. Eng.* 281:131). A restart from the consistent acceleration would instead carry
    /// the stiff modes' instantaneous response to the jump (with stiffness-proportional damping
    /// `c K Δq̇`: slope accelerations of 10⁶ s⁻² after a bounce of 10⁻⁴ N·s), which the predictor
    /// of the rest of the step extrapolates over up to a whole step: the beam end folds over and
    /// Newton fails (generalized-α, 16 elements, 3 ms;
    /// docs/model.md, "Events and the integrator"). A flying ball's centre keeps its known
    /// acceleration `(0, −g_eff)`.
    pub(crate) fn after_impulse(&self, s: &mut State<T, D>) {
        if s.contact == Contact::InFlight {
            let g = [T::zero(), -self.effective_gravity(s.base_accel)];
            s.flight.accel = g;
            s.flight.pseudo_accel = g;
        }
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

/// The multiplier `Λ` of a perfectly elastic impulse along a direction `y` that conserves the
/// kinetic energy exactly in any impulse metric: with `b = uᵀ M y` (`u` the velocities before)
/// and `c = yᵀ M y`, the kinetic energy after `u + Λ y` changes by
/// `ΔT = Λ b + ½ Λ² c`, which is zero for `Λ = −2b/c` (docs/model.md, "Stops"). In the mass
/// metric (`y = M⁻¹ gᵀ`) `b` is the gap rate and `c` the inverse effective mass: the rebound
/// `Ġ⁺ = −Ġ⁻` of the kinematic law. `None` unless the impulse separates (`b` has the sign of
/// the approach `speed` of the kinematic law, whose `Λ` is then kept).
pub(crate) fn energy_exact_impulse<T: Real>(speed: T, b: T, c: T) -> Option<T> {
    let lambda = -(b + b) / c;
    (lambda.is_finite() && is_positive(b * speed)).then_some(lambda)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FreeBall, Model, Params};

    /// `mass_products` against the assembled mass matrix (`∂r/∂a`) at a deformed, moving state,
    /// in flight and rolling. Budget 1e-10 of `|M y||v|`: the two residuals hold the beam's
    /// elastic forces (EA times the strain of this 1e-4 perturbation, about 1e3 N), which cancel
    /// in the difference and leave their rounding, 1e-16 of them (measured 1e-12 to 2e-11).
    #[test]
    fn mass_products_are_the_assembled_mass_matrix() {
        let p = Params::<f64>::default();
        let m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("start");
        let mut s = m.state;
        for i in 0..13 {
            s.q[i] += 1e-4 * ((i as f64) * 0.7).cos();
            s.v[i] = 0.3 * ((i as f64) * 1.3).sin();
            s.a[i] = 2.0 * ((i as f64) * 0.4).cos();
        }
        for contact in [Contact::InFlight, Contact::Off] {
            let (_, mass, _) = m.sys.assemble(
                &s.q,
                &s.v,
                &s.a,
                9.81,
                &Chain {
                    c_q: 0.0,
                    c_v: 0.0,
                    c_m: 1.0,
                },
                contact,
                false,
            );
            let mut y = SVector::<f64, 13>::from_fn(|i, _| ((i as f64) * 2.1).sin());
            let y0 = y;
            let mut ws = Workspace::default();
            ws.begin_step(crate::NewtonKind::Full, crate::work::UNLIMITED, false);
            let (uy, yy) = m
                .sys
                .mass_products(&s, contact, &mut y, &mut ws)
                .expect("products");
            assert_eq!(y, y0);
            let my = mass * y0;
            let (e1, e2) = (
                (uy - s.v.dot(&my)).abs() / (my.norm() * s.v.norm()),
                (yy - y0.dot(&my)).abs() / (my.norm() * y0.norm()),
            );
            println!(
                "{contact:?}: {uy} vs {}, {yy} vs {}; {e1:.1e} {e2:.1e}",
                s.v.dot(&my),
                y0.dot(&my)
            );
            assert!(e1 < 1e-10 && e2 < 1e-10, "{e1:e} {e2:e}");
        }
    }
}
