//! One step and its events: the Newmark (or generalized-α) step of the independent
//! coordinates, the stop impacts that split it, stick and release (the core's algorithm,
//! `absorber-core/src/step/stops`, with the relative angle from the maximal coordinates).

use super::kin::{Mode, NW, PHI};
use super::newton::Solved;
use super::{flight, zeros, FullSolver, FullState, Work};
use absorber_core::shared::AlphaRecursion;
use absorber_core::shared::Chain;
use absorber_core::{Contact, Error, Impact, ImpactModel, NewtonKind, Side, StepReport};

impl FullSolver {
    /// How long an impulse of the over-step metric lasts \[s\]: the stop's contact time
    /// (`ball.stop_contact_time`) for a `stop` impulse when it is set, else the step.
    pub(super) fn impulse_duration(&self, stop: bool) -> f64 {
        let tau = self.params.ball.stop_contact_time;
        if stop && tau > 0.0 {
            tau
        } else {
            self.params.integrator.step
        }
    }

    /// The Newton chain of a step of length `h`: `(κβh², κγh, 1)`, `κ = (1 − α_f)/(1 − α_m)`
    /// (`κ = 1` for Newmark; `absorber-core/src/step/newmark`).
    pub(super) fn step_chain(&self, h: f64) -> Chain<f64> {
        let it = &self.params.integrator;
        AlphaRecursion::chain(it, AlphaRecursion::of(it).as_ref(), h)
    }

    /// One Newmark (or generalized-α) step of the independent coordinates
    /// (`absorber-core/src/step/newmark` states the scheme).
    pub(super) fn newmark(
        &self,
        s: &FullState,
        h: f64,
        base_accel: f64,
    ) -> Result<(FullState, Solved), Error> {
        let it = &self.params.integrator;
        let alpha = AlphaRecursion::of(it);
        let mode = self.mode(s.contact);
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        let pa_alpha = alpha.map(|_| self.gather_ind(&s.pa, mode));
        let pai: &[f64] = pa_alpha.as_deref().unwrap_or(&ai);
        let ni = qi.len();
        // Generalized-α: the known part of a_{n+1}.
        let known: Vec<f64> = match alpha {
            Some(g) => ai
                .iter()
                .zip(pai.iter())
                .map(|(a, p)| g.from_accel * a + g.from_pseudo * p)
                .collect(),
            // (Read only with generalized-α.)
            None => Vec::new(),
        };
        let (cq, cv) = (h * h * (0.5 - it.beta), h * (1.0 - it.gamma));
        let mut q_pred: Vec<f64> = qi
            .iter()
            .zip(vi.iter().zip(pai.iter()))
            .map(|(q, (v, p))| q + v * h + p * cq)
            .collect();
        let mut v_pred: Vec<f64> = vi.iter().zip(pai.iter()).map(|(v, p)| v + p * cv).collect();
        if alpha.is_some() {
            for i in 0..ni {
                q_pred[i] += known[i] * (it.beta * h * h);
                v_pred[i] += known[i] * (it.gamma * h);
            }
        }
        let ch = self.step_chain(h);
        let z = zeros(ni);
        // The dependent positions' iteration starts from their Taylor prediction.
        let mut warm = self.local_of(&s.q);
        let (wv, wa) = (self.local_of(&s.v), self.local_of(&s.a));
        for &j in mode.dependent() {
            warm[j] += h * wv[j] + 0.5 * h * h * wa[j];
        }
        let solved = self.newton(
            &q_pred,
            &v_pred,
            &z,
            ai,
            &ch,
            ch.c_q,
            self.effective_gravity(base_accel),
            mode,
            &mut warm,
            s.theta_ref,
            self.params.integrator.newton == NewtonKind::Full,
        )?;
        let a = &solved.x;
        // q_{n+1} and v_{n+1} in place of the predictors (no longer needed).
        let (mut qn, mut vn) = (q_pred, v_pred);
        for ((q, v), x) in qn.iter_mut().zip(vn.iter_mut()).zip(a.iter()) {
            *q += x * ch.c_q;
            *v += x * ch.c_v;
        }
        // The dependent positions start from those of the last Newton iterate.
        let mut next = self.complete_warm(
            &qn,
            &vn,
            a,
            mode,
            s,
            &warm,
            s.time + h,
            base_accel,
            s.contact,
        )?;
        if let Some(g) = alpha {
            for i in 0..ni {
                next.pa[self.ind_to_z(i)] = known[i] + g.ratio * a[i];
            }
        }
        if mode == Mode::Flying {
            self.fly_exactly(s, h, &mut next);
        }
        Ok((next, solved))
    }

    /// Relative ball angle α = θ − ψ (0 without a free ball).
    pub(super) fn relative_angle(&self, s: &FullState) -> f64 {
        if !self.scene.free_ball() {
            return 0.0;
        }
        let w = self.local_of(&s.q);
        self.bodies.relative_angle(&w, &[0.0; NW], s.theta_ref).0
    }

    /// Relative ball angle rate α̇ = θ̇ − ψ̇ (0 without a free ball).
    pub(super) fn relative_rate(&self, s: &FullState) -> f64 {
        if !self.scene.free_ball() {
            return 0.0;
        }
        let w = self.local_of(&s.q);
        let wd = self.local_of(&s.v);
        self.bodies.relative_angle(&w, &wd, s.theta_ref).2
    }

    /// Fraction τ ∈ [0, 1] of the step at which α reaches `target`: root of the cubic Hermite
    /// interpolant of α through both step ends with their rates
    /// ([`absorber_core::shared::hermite_root`], shared with the core).
    pub(super) fn crossing_fraction(
        &self,
        start: &FullState,
        end: &FullState,
        h: f64,
        target: f64,
    ) -> f64 {
        absorber_core::shared::hermite_root(
            self.relative_angle(start) - target,
            self.relative_rate(start) * h,
            self.relative_angle(end) - target,
            self.relative_rate(end) * h,
        )
    }

    /// Advances one step to the input `base_accel` = ÿ_b(t + h). On error the state is kept.
    pub fn step(&mut self, base_accel: f64) -> Result<StepReport<f64>, Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        // The core's input range (absorber_core::MAX_BASE_ACCEL): a sensor fault.
        if base_accel.abs() > absorber_core::MAX_BASE_ACCEL {
            return Err(Error::InputOutOfRange);
        }
        let h = self.params.integrator.step;
        // (Borrowed, not cloned: the events only read it, and it is replaced at the end.)
        let start = &self.state;
        self.work.borrow_mut().projection = 0.0;
        let (trial, solved) = self.newmark(start, h, base_accel)?;
        let mut report = StepReport {
            iterations: solved.iterations,
            increment: solved.increment,
            impact: None,
            separation: None,
            landing: None,
            work: 0,
            outcome: absorber_core::Outcome::Converged,
            events: absorber_core::EventCounts::default(),
        };
        let mut next = if start.contact == Contact::InFlight {
            // In flight: a landing or a stop splits the step at the crossing (flight.rs).
            self.flight_events(start, trial, base_accel, &mut report)?
        } else {
            let next = self.stop_events(start, trial, h, base_accel, &mut report)?;
            // Separation: a track that would pull the ball lets it fly (after a stop impact, at
            // the step's end).
            if self.flies() {
                self.separation(start, next, base_accel, &mut report)?
            } else {
                next
            }
        };
        // A flight counts as a separation once it is higher than `ball.lift_height`.
        self.note_gap(&mut next, &mut report);
        self.last_landing = report.landing;
        self.state = next;
        Ok(report)
    }

    /// The stop events of a rolling step from `start` with trial end `next`: an impact when
    /// the ball crossed a stop (from between the stops, or — with flight, after flying over a
    /// stop — from the arc beyond it: spec revision 4), a release when a held ball would be
    /// pulled.
    pub(super) fn stop_events(
        &self,
        start: &FullState,
        mut next: FullState,
        h: f64,
        base_accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        if !self.scene.stops() {
            return Ok(next);
        }
        let stop = self.params.ball.stop_angle;
        match next.contact {
            Contact::Off => {
                if !self.flies() {
                    if self.relative_angle(&next).abs() > stop {
                        return self.step_with_impact(start, &next, h, base_accel, true, report);
                    }
                    return Ok(next);
                }
                let (a0, a1) = self.branch_angles(start, &next);
                let inside = a0.abs() <= stop + flight::BEYOND_MARGIN;
                if inside == (a1.abs() <= stop) {
                    return Ok(next);
                }
                self.step_with_impact(start, &next, h, base_accel, inside, report)
            }
            Contact::OnStop(side) => {
                if side.sign::<f64>() * self.contact_force(&next)? > 0.0 {
                    next.contact = Contact::Off;
                }
                Ok(next)
            }
            // (Beyond is the core's marker; this solver tells a ball beyond the stops by its
            // angle, the Off arm above.)
            Contact::InFlight | Contact::Beyond => Ok(next),
        }
    }

    /// Splits a rolling step that crossed a stop (from between the stops, `inside`, or from
    /// the arc beyond them) at the crossing, applies the impact, and integrates the rest.
    pub(super) fn step_with_impact(
        &self,
        start: &FullState,
        trial: &FullState,
        h: f64,
        base_accel: f64,
        inside: bool,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        let stop = self.params.ball.stop_angle;
        let (side, tau) = if inside && !self.flies() {
            let side = if self.relative_angle(trial) > 0.0 {
                Side::Positive
            } else {
                Side::Negative
            };
            let target = side.sign::<f64>() * stop;
            (side, self.crossing_fraction(start, trial, h, target))
        } else {
            let (a0, a1) = self.branch_angles(start, trial);
            let outer = if inside { a1 } else { a0 };
            let side = if outer > 0.0 {
                Side::Positive
            } else {
                Side::Negative
            };
            let target = side.sign::<f64>() * stop;
            let tau = absorber_core::shared::hermite_root(
                a0 - target,
                self.relative_rate(start) * h,
                a1 - target,
                self.relative_rate(trial) * h,
            );
            (side, tau)
        };
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = if h1 > h * 1e-6 {
            let (m, s) = self.newmark(start, h1, accel_mid)?;
            report.iterations += s.iterations;
            report.increment = report.increment.max(s.increment);
            m
        } else {
            start.clone()
        };
        self.event_accel(start, trial, tau, &mut mid)?;
        let before = mid.clone();
        let impact = self.impact(&mut mid, side, inside)?;
        report.events.impacts += 1;
        if !impact.stuck {
            // The velocities jumped; the accelerations go on from before the impulse (the
            // core's `System::after_impulse`).
            self.after_impulse(&mut mid, &before);
        }
        let rest = h - h1;
        let mut end = if rest > h * 1e-6 {
            let (e, s) = self.newmark(&mid, rest, base_accel)?;
            report.iterations += s.iterations;
            report.increment = report.increment.max(s.increment);
            e
        } else {
            mid
        };
        // A second crossing within the same (remaining) step: the ball came straight back
        // onto the stop; end the step with it resting there (plastic).
        if inside && end.contact == Contact::Off && self.relative_angle(&end).abs() > stop {
            let side2 = if self.relative_angle(&end) > 0.0 {
                Side::Positive
            } else {
                Side::Negative
            };
            end = self.rest_on_stop(&end, side2)?;
            report.events.impacts += 1;
        }
        report.impact = Some(impact);
        Ok(end)
    }

    /// The beam's accelerations at an event a fraction `tau` into a step from `start` whose
    /// trial end is `trial`, with a dissipative scheme (γ > ½): the step's ends' interpolated
    /// linearly in place of the short sub-step's own, whose stiff modes carry their full
    /// acceleration into the rest of the step (the core's `System::event_accel`, which gives
    /// the numbers). The ball's independent entries (its spin; in flight its centre) keep the
    /// sub-step's; the bodies' dependent accelerations are completed from these, so the state
    /// stays consistent with the constraints.
    pub(super) fn event_accel(
        &self,
        start: &FullState,
        trial: &FullState,
        tau: f64,
        mid: &mut FullState,
    ) -> Result<(), Error> {
        if self.params.integrator.gamma <= 0.5 {
            return Ok(());
        }
        let nb = 4 * self.n;
        let lerp = |x0: &[f64], x1: &[f64], k: usize| {
            let (a, b) = (
                x0.get(4 + k).copied().unwrap_or(0.0),
                x1.get(4 + k).copied().unwrap_or(0.0),
            );
            (1.0 - tau) * a + tau * b
        };
        let mode = self.mode(mid.contact);
        let mut ai = self.gather_ind(&mid.a, mode);
        for (k, a) in ai.iter_mut().take(nb).enumerate() {
            *a = lerp(&start.a, &trial.a, k);
        }
        let pa_kept: Vec<(usize, f64)> = (nb..ai.len())
            .map(|i| {
                let z = self.ind_to_z(i);
                (z, mid.pa.get(z).copied().unwrap_or(mid.a[z]))
            })
            .collect();
        let mut out = self.with_accel(mid, &ai)?;
        for k in 0..nb {
            out.pa[4 + k] = lerp(&start.pa, &trial.pa, k);
        }
        for (z, p) in pa_kept {
            out.pa[z] = p;
        }
        *mid = out;
        Ok(())
    }

    /// The rolling ball put on the stop `side` and held there (plastic), with its consistent
    /// acceleration; released at once if the stop would pull.
    pub(super) fn rest_on_stop(&self, s: &FullState, side: Side) -> Result<FullState, Error> {
        let mut end = self.hold(s, side)?;
        let acc = self.consistent_acceleration(&end)?;
        end = self.with_accel(&end, &acc.x)?;
        if side.sign::<f64>() * self.contact_force(&end)? > 0.0 {
            end.contact = Contact::Off;
        }
        Ok(end)
    }

    /// The state with the ball put on the stop and held there (φ becomes dependent).
    ///
    /// The held constraint `θ − ψ = ±α_max` is met on the branch of θ nearest the ball's:
    /// a ball that rolled over the top beyond the stops (α = θ − ψ unwrapped past ±π) meets
    /// a stop at `±α_max + 2πk`, and θ is re-based by −2πk first (the orbit angle's branch,
    /// `theta_ref`; φ, dependent here, follows from the no-slip constraint), as the core's
    /// impact sets its spin so that α = ±α_max. Held on the old branch, the constraint
    /// asked the ball's centre to turn 2πk about A in one solve: Newton diverged (elastic
    /// stops at 5 mm, 4.13 Hz, a ball beyond the stops rolling back onto one at 2.127 s).
    pub(super) fn hold(&self, s: &FullState, side: Side) -> Result<FullState, Error> {
        let contact = Contact::OnStop(side);
        let mode = self.mode(contact);
        let lock = side.sign::<f64>() * self.params.ball.stop_angle;
        let turn = 2.0 * core::f64::consts::PI;
        let k = ((self.relative_angle(s) - lock) / turn).round();
        let rebased;
        let s = if k != 0.0 {
            let mut r = s.clone();
            r.theta_ref -= turn * k;
            rebased = r;
            &rebased
        } else {
            s
        };
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, contact)
    }

    /// Stop impact: projects the ball onto the stop, applies `Λ ∇αᵀ` with
    /// `Λ = −(1+e) α̇⁻ / (∇α W⁻¹ ∇αᵀ)` if the ball moves towards the stop's face (outwards from
    /// between the stops, `inside`, inwards from the arc beyond), decides whether the ball stays
    /// on the stop (only from between the stops).
    pub(super) fn impact(
        &self,
        s: &mut FullState,
        side: Side,
        inside: bool,
    ) -> Result<Impact<f64>, Error> {
        let ball = &self.params.ball;
        let loc0 = 4 * self.n - 4;
        // Projection: the held configuration gives φ on the stop; velocities are kept.
        let held = self.hold(s, side)?;
        let phi = self.zloc(PHI);
        s.q[phi] = held.q[phi];
        // (On the held state's branch of θ: φ was re-based with it.)
        s.theta_ref = held.theta_ref;
        s.contact = Contact::Off;
        let mode = Mode::Free;
        let qi = self.gather_ind(&s.q, mode);
        let mut vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        *s = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, Contact::Off)?;
        let w = self.local_of(&s.q);
        let kin = self.local_kin(mode, &qi[loc0..], &vi[loc0..], &w, s.theta_ref)?;
        let (_, g, _) = self.bodies.relative_angle(&kin.w, &kin.wd, s.theta_ref);
        let ni = qi.len();
        let grad = self.ind_gradient(mode, &kin, &g, ni);
        let speed: f64 = grad.iter().zip(vi.iter()).map(|(a, b)| a * b).sum();
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: 0.0,
            energy_loss: 0.0,
            stuck: false,
        };
        let plastic = speed.abs() < ball.stick_speed;
        let towards = if inside {
            side.sign::<f64>() * speed
        } else {
            -side.sign::<f64>() * speed
        };
        if towards > 0.0 {
            let e = if plastic { 0.0 } else { ball.restitution };
            let ch = if ball.impact_model == ImpactModel::OverStep {
                self.step_chain(self.impulse_duration(true))
            } else {
                Chain {
                    c_q: 0.0,
                    c_v: 0.0,
                    c_m: 1.0,
                }
            };
            let mut warm = w;
            let mut y = grad.clone();
            {
                let mut guard = self.work.borrow_mut();
                let Work { mass, reduced, .. } = &mut *guard;
                let lu = self.reduced_lu(reduced, ni)?;
                self.evaluate(
                    mass,
                    Some((&mut *lu, &ch)),
                    &qi,
                    &vi,
                    &ai,
                    self.effective_gravity(s.base_accel),
                    mode,
                    &mut warm,
                    s.theta_ref,
                )?;
                if !lu.factor() || !lu.solve(&mut y) {
                    return Err(Error::Singular);
                }
            }
            let wgt: f64 = grad.iter().zip(y.iter()).map(|(a, b)| a * b).sum();
            if !wgt.is_finite() || wgt <= 0.0 {
                return Err(Error::Singular);
            }
            let lambda = -(1.0 + e) * speed / wgt;
            vi.iter_mut()
                .zip(y.iter())
                .for_each(|(v, yy)| *v += yy * lambda);
            *s = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, Contact::Off)?;
            impact.impulse = lambda / ball.path_radius();
            impact.energy_loss = 0.5 * (1.0 - e * e) * speed * speed / wgt;
        }
        if plastic && inside {
            let mut held = self.hold(s, side)?;
            let acc = self.consistent_acceleration(&held)?;
            held = self.with_accel(&held, &acc.x)?;
            if side.sign::<f64>() * self.contact_force(&held)? <= 0.0 {
                *s = held;
                impact.stuck = true;
            }
        }
        Ok(impact)
    }
}
