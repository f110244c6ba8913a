//! The model: its state and parameters, its start, and one step ([`Model::step`]): the input
//! checked, the step run by the machinery of `step/` (its `mod.rs` lays the step out top to
//! bottom), and the restart rule ("Recovery") applied to a run of failed or capped steps. Every
//! expensive operation of the step is charged to its work cap ([`crate::work`]). The Newton
//! matrices live in the model ([`crate::Workspace`]), not on the stack.

use crate::error::Error;
use crate::params::Params;
use crate::scalar::Real;
use crate::scene::{BallKind, Scene};
use crate::state::{units, Contact, EventCounts, Outcome, State, StepReport, RESTART_AFTER};
use crate::step::newton::Workspace;
use crate::step::system::System;
use crate::step::tip::LocalState;
use nalgebra::SVector;

/// The reduced model of scene `S` with `N` elements and `D = 4N + S::EXTRA_DOFS` unknowns.
#[derive(Clone, Debug)]
pub struct Model<T: Real, S: Scene, const N: usize, const D: usize> {
    /// The equations (parameters and everything precomputed from them).
    pub(crate) sys: System<T, S, N, D>,
    pub(crate) state: State<T, D>,
    /// The Newton matrices (a cache, not part of the state).
    pub(crate) work: Workspace<T, D>,
    /// [`MAX_BASE_ACCEL`] in the scalar.
    max_input: T,
    /// Failed or capped steps in a row, and restarts so far.
    recovery: Recovery,
}

/// The restart rule's counters.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Recovery {
    /// Failed or capped steps in a row.
    run: u32,
    /// Of those, failed steps (their samples did not advance the state).
    kept: u32,
    /// Restarts since the model was built.
    restarts: u32,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
    const CHECK: () = {
        assert!(N >= 1, "a beam needs at least one element");
        assert!(
            D == 4 * N + S::EXTRA_DOFS,
            "D must equal 4N + the scene's extra unknowns"
        );
    };

    /// Builds the model, solves the static equilibrium under gravity by load stepping and starts
    /// from it at rest relative to the base (ball at `ball.initial_angle`), with the base
    /// acceleration `base_accel` \[m/s²\] as the input at t = 0.
    pub fn at_rest(params: Params<T>, base_accel: T) -> Result<Self, Error> {
        let mut m = Self::new(params)?;
        m.solve_static()?;
        m.restart(base_accel)?;
        Ok(m)
    }

    /// Builds the model in the undeformed reference configuration, at rest, without solving
    /// the static equilibrium (see [`Model::at_rest`]).
    pub fn new(params: Params<T>) -> Result<Self, Error> {
        Self::check_params(&params)?;
        Ok(Self::fresh(params))
    }

    /// Builds the model into caller storage, solves the static equilibrium and starts from it
    /// at rest ([`Model::at_rest`]), without a copy of the model on the stack: a firmware keeps
    /// it in a `static` (`MaybeUninit`) and its boot needs only the solve's own stack
    /// (`docs/embedded.md`, boot RAM). On error `slot` holds a valid model or nothing usable:
    /// use only the returned reference.
    pub fn at_rest_in(
        slot: &mut core::mem::MaybeUninit<Self>,
        params: Params<T>,
        base_accel: T,
    ) -> Result<&mut Self, Error> {
        let m = Self::new_in(slot, params)?;
        m.solve_static()?;
        m.restart(base_accel)?;
        Ok(m)
    }

    /// [`Model::new`] into caller storage: only the fixed data is built on the stack, the
    /// state and the Newton matrices are written in place. Not inlined: whatever temporaries
    /// the construction needs live in this frame, which is gone before the static solve runs
    /// (inlined into [`Model::at_rest_in`]'s caller, they stayed in its frame under the whole
    /// solve: the boot's stack from reset 5,408 -> 4,164 B at N = 3, 10,800 -> 9,228 B at N = 6,
    /// `docs/embedded.md`).
    #[inline(never)]
    pub fn new_in(
        slot: &mut core::mem::MaybeUninit<Self>,
        params: Params<T>,
    ) -> Result<&mut Self, Error> {
        Self::check_params(&params)?;
        Ok(slot.write(Self::fresh(params)))
    }

    /// What [`Model::new`] checks: the element count and unknowns of the scene, the
    /// parameters. A model built in a larger value's storage (the estimator's) checks first,
    /// then writes [`Model::fresh`] in place.
    pub(crate) fn check_params(params: &Params<T>) -> Result<(), Error> {
        #[allow(clippy::let_unit_value)]
        let () = Self::CHECK;
        params.validate(S::HAS_TIP, !matches!(S::BALL, BallKind::None))?;
        if !S::ELASTIC_RULES
            && params.ball.restitution >= T::one()
            && params.integrator.events == crate::params::EventLocation::Crossing
        {
            return Err(Error::InvalidParameter {
                field: "ball.restitution",
                reason: "the scene leaves the perfectly elastic rules out (Scene::ELASTIC_RULES): below 1, or events at the step end",
            });
        }
        if !S::GENERALIZED_ALPHA && !params.integrator.is_newmark() {
            return Err(Error::InvalidParameter {
                field: "integrator.alpha_m",
                reason:
                    "the scene is Newmark's method only (Scene::GENERALIZED_ALPHA): α_m = α_f = 0",
            });
        }
        if !S::EVENTS_AT_CROSSING
            && params.integrator.events == crate::params::EventLocation::Crossing
        {
            return Err(Error::InvalidParameter {
                field: "integrator.events",
                reason: "the scene puts every event at the step end (Scene::EVENTS_AT_CROSSING)",
            });
        }
        if !<S::Data<T, N> as crate::loads::SceneData<T, N>>::SECTIONS
            && params.calibration.bending_gradient != T::zero()
        {
            return Err(Error::InvalidParameter {
                field: "calibration.bending_gradient",
                reason: "needs an arm (per-element sections); a uniform beam takes 0",
            });
        }
        Ok(())
    }

    /// The undeformed model at rest from checked parameters ([`Model::check_params`]): a plain
    /// value expression, inlined so that it is written straight into its destination.
    #[inline(always)]
    pub(crate) fn fresh(params: Params<T>) -> Self {
        let z = SVector::<T, D>::zeros();
        Self {
            sys: System::new(params),
            state: State {
                q: z,
                v: z,
                a: z,
                pseudo_accel: z,
                time: T::zero(),
                steps: 0,
                base_accel: T::zero(),
                contact: Contact::Off,
                flight: crate::state::Flight::zero(),
            },
            work: Workspace::default(),
            max_input: crate::scalar::lit(crate::state::MAX_BASE_ACCEL),
            recovery: Recovery::default(),
        }
    }

    /// Gives an arm scene ([`crate::scene::Arm`]) the sections of `arm` in place of the uniform
    /// beam's (the length and modulus of `params.beam` are used): [`Model::with_arm`] for a
    /// model already built, e.g. in caller storage. The model is left undeformed: call
    /// [`Model::solve_static`] and [`Model::restart`] after it. On error nothing changed.
    pub fn set_arm(&mut self, arm: &crate::loads::ArmParams<T>) -> Result<(), Error> {
        use crate::loads::SceneData as _;
        let p = self.sys.params;
        arm.validate(&p.beam)?;
        let sections = self
            .sys
            .data
            .sections_mut()
            .ok_or(Error::InvalidParameter {
                field: "arm",
                reason: "the scene has no per-element sections (use scene::Arm<S>)",
            })?;
        for (k, sec) in sections.iter_mut().enumerate() {
            *sec = crate::loads::arm_section(
                arm,
                &p.beam,
                &p.calibration,
                p.damping.stiffness_proportional,
                k,
                N,
            );
        }
        self.work.clear();
        Ok(())
    }

    /// The parameters.
    pub fn params(&self) -> &Params<T> {
        &self.sys.params
    }

    /// The current state.
    pub fn state(&self) -> &State<T, D> {
        &self.state
    }

    /// The static equilibrium the model started from.
    pub fn equilibrium(&self) -> &SVector<T, D> {
        &self.sys.equilibrium
    }

    pub(crate) fn local(q: &SVector<T, D>, v: &SVector<T, D>, a: &SVector<T, D>) -> LocalState<T> {
        System::<T, S, N, D>::local(q, v, a)
    }

    /// Static equilibrium under gravity (zero base acceleration), a free ball hanging plumb
    /// below the beam end, by load stepping (see `statics`). Returns the Newton iterations
    /// used. Sets the state to the equilibrium, at rest, and remembers it as the reference of
    /// the potentials. On error the model is unchanged.
    pub fn solve_static(&mut self) -> Result<u32, Error> {
        let (q, iterations) = self.sys.solve_static(&mut self.work)?;
        self.work.clear();
        self.sys.equilibrium = q;
        self.state = State {
            q,
            v: SVector::zeros(),
            a: SVector::zeros(),
            pseudo_accel: SVector::zeros(),
            time: T::zero(),
            steps: 0,
            base_accel: T::zero(),
            contact: Contact::Off,
            flight: crate::state::Flight::zero(),
        };
        self.prepare_rest();
        Ok(iterations)
    }

    /// Computes where a restart puts the model (`system::Rest`): the start of [`Model::restart`] at
    /// two inputs, 0 and 100 m/s², whose accelerations give `a₀` and `a₁`. Without a possible
    /// start (the ball beyond a stop) the model has no restart state.
    fn prepare_rest(&mut self) {
        let angle = self.sys.params.ball.initial_angle;
        let eq = self.sys.equilibrium;
        let du: T = crate::scalar::lit(100.0);
        let at = |m: &mut Self, u: T| {
            let s = m
                .sys
                .start_state(eq, SVector::zeros(), Some(angle), u, &mut m.work);
            m.work.clear();
            s
        };
        self.sys.rest.ready = false;
        if let (Ok(s0), Ok(s1)) = (at(self, T::zero()), at(self, du)) {
            self.sys.rest.q = s0.q;
            self.sys.rest.a0 = s0.a;
            self.sys.rest.a1 = (s1.a - s0.a) / du;
            self.sys.rest.ready = true;
        }
    }

    /// Restarts the run at time 0 from the static equilibrium, at rest relative to the base, the
    /// ball at `ball.initial_angle` from the vertical, with input `base_accel` at t = 0; computes
    /// the consistent initial acceleration. Forgets every cached Newton matrix, so a restart
    /// recovers from any state a failed run can leave.
    pub fn restart(&mut self, base_accel: T) -> Result<(), Error> {
        self.check_input(base_accel)?;
        self.work.clear();
        self.recovery.run = 0;
        self.recovery.kept = 0;
        let angle = self.sys.params.ball.initial_angle;
        let s = self.sys.start_state(
            self.sys.equilibrium,
            SVector::zeros(),
            Some(angle),
            base_accel,
            &mut self.work,
        );
        self.work.clear();
        self.state = s?;
        Ok(())
    }

    /// Replaces the state (e.g. restored from storage). The caller vouches for consistency.
    pub fn set_state(&mut self, state: State<T, D>) {
        self.work.clear();
        self.recovery.run = 0;
        self.recovery.kept = 0;
        self.state = state;
    }

    /// Starts from the configuration `q` with velocities `v` (relative to the base) at time 0,
    /// with input `base_accel`; computes the consistent acceleration. The ball is off the stops.
    /// On error the state is unchanged.
    pub fn set_configuration(
        &mut self,
        q: SVector<T, D>,
        v: SVector<T, D>,
        base_accel: T,
    ) -> Result<(), Error> {
        self.check_input(base_accel)?;
        if !q.iter().chain(v.iter()).all(|z| z.is_finite()) {
            return Err(Error::NonFiniteState);
        }
        self.work.clear();
        let s = self.sys.start_state(q, v, None, base_accel, &mut self.work);
        self.work.clear();
        self.state = s?;
        Ok(())
    }

    fn check_input(&self, base_accel: T) -> Result<(), Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        if base_accel.abs() > self.max_input {
            return Err(Error::InputOutOfRange);
        }
        Ok(())
    }

    /// Advances the model by one step `h` to the new input `base_accel` = ÿ_b(t + h) \[m/s²\]
    /// (the acceleration of the base, measured, positive up).
    ///
    /// **Work.** The step does at most [`crate::Integrator::max_work`] units of work
    /// ([`crate::work`]). A Newton solve that reaches the cap stops with its iterate:
    /// the step is taken and flagged [`Outcome::Capped`]. A step that would restart the model
    /// (below) runs with [`crate::work::RESTART`] units less, the restart's own.
    ///
    /// **Errors.** On error the state is left exactly as it was, and so is everything that
    /// influences later steps (modified Newton's kept matrix included). An input that is not
    /// finite or out of range is refused before any work.
    ///
    /// **Recovery.** A step that fails or is capped while the [`RESTART_AFTER`] − 1 steps
    /// before it failed or were capped too restarts the model instead: the state becomes the
    /// start of [`Model::restart`] (static equilibrium, at rest, the ball at its initial
    /// angle) with the consistent acceleration of this input, precomputed, so within the step's
    /// work; the step count goes on as if every sample had been stepped; the step returns
    /// `Ok` with [`Outcome::Restarted`]. So no run of failed or capped steps is longer than
    /// `RESTART_AFTER`, whatever the input, and the next step is an ordinary one from rest.
    ///
    /// Never inlined: every caller (the firmware, the C API's five variants) runs the same
    /// code, whatever the optimizer decides around the call.
    #[inline(never)]
    pub fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error> {
        self.check_input(base_accel)?;
        let mut cap = self.sys.params.integrator.max_work;
        if self.recovery.run + 1 >= RESTART_AFTER {
            // This step restarts the model if it fails or is capped far: the restart's work is
            // reserved (the cap is then met by the restart step too).
            cap = cap
                .saturating_sub(crate::work::RESTART)
                .max(crate::work::MIN_CAP);
        }
        let in_flight = self.state.contact == Contact::InFlight;
        self.work
            .begin_step(self.sys.params.integrator.newton, cap, in_flight);
        let result = self
            .sys
            .advance(&mut self.state, base_accel, &mut self.work);
        let capped = self.work.capped();
        match result {
            Ok(mut report) => {
                self.work.commit();
                report.work = units(self.work.used());
                if capped {
                    report.outcome = Outcome::Capped;
                }
                // A step taken near convergence (converged, or capped within
                // `RESTART_INCREMENT` tolerances) ends a run; one capped farther away extends it.
                if self.work.capped_far() {
                    self.recovery.run += 1;
                    if self.recovery.run >= RESTART_AFTER {
                        return Ok(self.recover(base_accel, report.work));
                    }
                } else {
                    self.recovery.run = 0;
                    self.recovery.kept = 0;
                }
                Ok(report)
            }
            Err(e) => {
                // A state that was not finite before the step (set from outside, e.g. restored
                // from corrupted storage) is named as such, whatever the solve reported (a NaN
                // pivot reads as singular). Checked on the failure path only.
                let e = if System::<T, S, N, D>::is_finite(&self.state).is_err() {
                    Error::NonFiniteState
                } else {
                    e
                };
                self.recovery.run += 1;
                self.recovery.kept += 1;
                if self.recovery.run >= RESTART_AFTER {
                    return Ok(self.recover(base_accel, units(self.work.used())));
                }
                Err(e)
            }
        }
    }

    /// Restarts the model at the step to the input `base_accel` (see [`Model::step`]); returns
    /// the step's report. Without a restart state (a start that is not possible) the model
    /// goes on from where it is. Kept out of line (rare): the step's frame does not carry the
    /// new state.
    #[inline(never)]
    #[cold]
    fn recover(&mut self, base_accel: T, work: u16) -> StepReport<T> {
        let report = StepReport {
            iterations: 0,
            increment: T::zero(),
            impact: None,
            separation: None,
            landing: None,
            work,
            outcome: Outcome::Restarted,
            events: EventCounts::default(),
        };
        if !self.sys.rest.ready {
            return report;
        }
        let r = &self.sys.rest;
        // Samples so far: the state's (those it advanced through, this one if it was taken)
        // and the failed ones of this run (this one if it failed).
        let steps = self
            .state
            .steps
            .saturating_add(u64::from(self.recovery.kept));
        let mut a = r.a0;
        a.axpy(base_accel, &r.a1, T::one());
        self.state = State {
            q: r.q,
            v: SVector::zeros(),
            a,
            pseudo_accel: a,
            time: T::from_count(steps) * self.sys.params.integrator.step,
            steps,
            base_accel,
            contact: Contact::Off,
            flight: crate::state::Flight::zero(),
        };
        self.work.clear();
        self.recovery.run = 0;
        self.recovery.kept = 0;
        self.recovery.restarts = self.recovery.restarts.saturating_add(1);
        report
    }

    /// Replaces the state just stepped to by a corrected one (an estimator's update), keeping
    /// the recovery rule's count ([`Model::step`], "Recovery"): a run of far-capped steps goes
    /// on counting through the corrections, where [`Model::set_state`] would end it.
    pub(crate) fn correct_state(&mut self, state: State<T, D>) {
        self.work.clear();
        self.state = state;
    }

    /// The recovery rule's counters, to be handed back to [`Model::refuse_step`].
    pub(crate) fn recovery(&self) -> Recovery {
        self.recovery
    }

    /// Takes back the step just taken (an estimator refused its correction): the state and the
    /// recovery rule's counters become `before`'s (taken just before the step), and the sample
    /// counts as a failed step, so the [`RESTART_AFTER`]-th refusal or failure in a row
    /// restarts the model at rest with the input `base_accel` ([`Model::step`], "Recovery";
    /// a step that restarted the model is not taken back). Returns whether it restarted.
    pub(crate) fn refuse_step(&mut self, before: (State<T, D>, Recovery), base_accel: T) -> bool {
        if self.recovery.restarts != before.1.restarts {
            self.work.clear();
            return true;
        }
        self.recovery = before.1;
        self.recovery.run += 1;
        self.recovery.kept += 1;
        self.state = before.0;
        if self.recovery.run >= RESTART_AFTER {
            let _ = self.recover(base_accel, units(self.work.used()));
            return true;
        }
        self.work.clear();
        false
    }

    /// Restarts the model made itself since it was built ([`Model::step`], "Recovery").
    pub fn restarts(&self) -> u32 {
        self.recovery.restarts
    }

    /// The Newton workspace after the last step: its work units, whether it was capped, and
    /// how many banded factorizations fell back to pivoting ([`Workspace::fallbacks`]).
    pub fn workspace(&self) -> &Workspace<T, D> {
        &self.work
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ImpactModel;
    use crate::scene::{FreeBall, LockedBall};
    use crate::state::Side;
    use crate::step::scheme::Chain;
    use crate::step::tip;

    /// The assembled Newton matrix is the exact derivative of the residual along the Newmark
    /// chain (central differences, relative 1e-6), at a deformed, fast-moving state, for every
    /// ball mode.
    fn check_jacobian<S: Scene, const N: usize, const D: usize>(contact: Contact) {
        let m = Model::<f64, S, N, D>::new(Params::default()).expect("valid");
        let mut q = SVector::<f64, D>::zeros();
        let mut v = SVector::<f64, D>::zeros();
        let mut a = SVector::<f64, D>::zeros();
        for i in 0..D {
            let f = (i as f64 + 1.0) * 0.37;
            q[i] = 0.01 * f.sin();
            v[i] = 0.5 * (1.3 * f).cos();
            a[i] = 20.0 * (0.7 * f).sin();
        }
        if S::EXTRA_DOFS == 1 {
            q[4 * N] = -2.5;
            v[4 * N] = -40.0;
        }
        let ch = Chain {
            c_q: 0.36 * 9e-6,
            c_v: 0.7 * 3e-3,
            c_m: 1.0,
        };
        let (r0, jac, f0) = m.sys.assemble(&q, &v, &a, 9.0, &ch, contact, false);
        // The banded LU works in the node envelope: nothing may be assembled outside it.
        for i in 0..D {
            for j in 0..D {
                assert!(
                    crate::step::linalg::in_envelope(i, j) || jac[(i, j)] == 0.0,
                    "J[{i},{j}] = {} outside the node envelope",
                    jac[(i, j)]
                );
            }
        }
        // The residual alone (reused-matrix iterations) is the same residual.
        let mut r1 = SVector::<f64, D>::zeros();
        let f1 = m.sys.residual([&q, &v, &a], 9.0, contact, false, &mut r1);
        assert!((r1 - r0).amax() <= 1e-12 * r0.amax(), "{r0} vs {r1}");
        assert!((f1 - f0).abs() <= 1e-12 * f0.abs().max(1.0));
        for j in 0..D {
            let h = 1e-3;
            let mut e = SVector::<f64, D>::zeros();
            e[j] = h;
            let rp = m
                .sys
                .assemble(
                    &(q + e * ch.c_q),
                    &(v + e * ch.c_v),
                    &(a + e),
                    9.0,
                    &ch,
                    contact,
                    false,
                )
                .0;
            let rm = m
                .sys
                .assemble(
                    &(q - e * ch.c_q),
                    &(v - e * ch.c_v),
                    &(a - e),
                    9.0,
                    &ch,
                    contact,
                    false,
                )
                .0;
            let fd = (rp - rm) / (2.0 * h);
            for i in 0..D {
                assert!(
                    (fd[i] - jac[(i, j)]).abs() <= 1e-6 * jac.amax(),
                    "J[{i},{j}] = {} but finite differences give {}",
                    jac[(i, j)],
                    fd[i]
                );
            }
        }
    }

    /// The impact operator alone, on a state exactly at the stop: the relative speed reverses
    /// to −e times its value for both impulse metrics, and with the instantaneous metric the
    /// kinetic energy changes by exactly −½(1 − e²) Ġ² / (∇G M⁻¹ ∇Gᵀ) (zero for e = 1),
    /// to rounding (1e-12 of the kinetic energy).
    #[test]
    fn impact_operator_reverses_relative_speed_and_obeys_the_restitution_energy_law() {
        for model in [ImpactModel::Instantaneous, ImpactModel::OverStep] {
            for e in [1.0, 0.5, 0.0] {
                let mut p = Params::<f64>::default();
                p.ball.restitution = e;
                p.ball.impact_model = model;
                let mut m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("valid");
                let mut s = m.state;
                for i in 0..12 {
                    s.v[i] = 0.05 * ((i as f64) * 1.7).sin();
                }
                // Put the ball on the + stop moving outward at 4 rad/s relative to the housing.
                m.sys.hold_on_stop(&mut s, Side::Positive);
                let k = m.sys.inertia.orbit_per_spin;
                let (_, psi_rate) =
                    tip::psi_and_rate(&Model::<f64, FreeBall, 3, 13>::local(&s.q, &s.v, &s.a));
                s.v[12] = psi_rate - 4.0 / k;
                m.state = s;
                let before = m.sys.relative_rate(&s);
                let t0 = m.energies(0.0, 0.0);
                let mut after = s;
                let imp = m
                    .sys
                    .impact(&mut after, Side::Positive, true, &mut m.work)
                    .expect("impact");
                m.state = after;
                let t1 = m.energies(0.0, 0.0);
                let kinetic =
                    |x: &crate::Energies<f64>| x.beam_kinetic + x.tip_kinetic + x.ball_kinetic;
                assert!((before - 4.0).abs() < 1e-9);
                assert!(
                    (m.sys.relative_rate(&after) + e * before).abs() < 1e-9,
                    "{model:?} e={e}"
                );
                assert!(
                    (t1.total() - t0.total() - (kinetic(&t1) - kinetic(&t0))).abs() < 1e-15,
                    "positions unchanged"
                );
                if model == ImpactModel::Instantaneous {
                    let d = kinetic(&t1) - kinetic(&t0);
                    assert!(
                        (d + imp.energy_loss).abs() < 1e-12 * kinetic(&t0),
                        "e={e}: {d} vs {}",
                        imp.energy_loss
                    );
                }
            }
        }
    }

    #[test]
    fn newton_matrix_is_exact_derivative_of_residual() {
        check_jacobian::<FreeBall, 2, 9>(Contact::Off);
        check_jacobian::<FreeBall, 2, 9>(Contact::OnStop(Side::Positive));
        check_jacobian::<FreeBall, 2, 9>(Contact::InFlight);
        check_jacobian::<LockedBall, 2, 8>(Contact::Off);
        check_jacobian::<FreeBall, 3, 13>(Contact::Off);
        check_jacobian::<FreeBall, 5, 21>(Contact::Off);
    }
}
