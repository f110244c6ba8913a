//! The impulses of flight (module doc of `flight`): the landing (the centre put on the circle,
//! then a bounce along `∇d` or the plastic rough landing by momentum projection onto the rolling
//! partition), the stop met in flight, and the impulse metric `W⁻¹ g` they share.

use super::super::kin::{Mode, NW, PHI, PSI, RB1, RB2};
use super::super::{FullSolver, FullState, Work};
use super::{positive, wrap};
use absorber_core::shared::Chain;
use absorber_core::shared::{bounce_impulse, landing_bounces};
use absorber_core::{Contact, Error, Impact, ImpactModel, Landing, Side, StepReport};

impl FullSolver {
    /// `W⁻¹ g` for the impulse metric of `ball.impact_model` in `mode` at the configuration of
    /// `s` (the reduced Newton matrix of a contact lasting τ — the stop's contact time for a
    /// `stop` impulse when it is set, else the step — or the reduced mass matrix).
    pub(super) fn metric_solve(
        &self,
        s: &FullState,
        mode: Mode,
        g: &[f64],
        stop: bool,
    ) -> Result<Vec<f64>, Error> {
        let ch = if self.params.ball.impact_model == ImpactModel::OverStep {
            self.step_chain(self.impulse_duration(stop))
        } else {
            Chain {
                c_q: 0.0,
                c_v: 0.0,
                c_m: 1.0,
            }
        };
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        if g.len() != qi.len() {
            return Err(Error::Singular);
        }
        let mut warm = self.local_of(&s.q);
        let mut y = g.to_vec();
        let mut guard = self.work.borrow_mut();
        let Work { mass, reduced, .. } = &mut *guard;
        let lu = self.reduced_lu(reduced, qi.len())?;
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
        if !lu.factor() || !lu.solve(&mut y) || !y.iter().all(|v| v.is_finite()) {
            return Err(Error::Singular);
        }
        Ok(y)
    }

    /// The landing at the crossing `s` (spec "Impacts, Landing"): the centre put on the circle,
    /// then a bounce or a plastic, rough landing; the accelerations go on from before it.
    pub(super) fn land(
        &self,
        s: &mut FullState,
        report: &mut StepReport<f64>,
    ) -> Result<(), Error> {
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let rel = self.relative(s);
        if !positive(rel.r) {
            return Err(Error::NonFiniteState);
        }
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (a, _) = self.end_point(s);
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        s.q[i1] = a[0] + rho * n[0];
        s.q[i2] = a[1] + rho * n[1];
        {
            let mut work = self.work.borrow_mut();
            work.projection = work.projection.max((rel.r - rho).abs());
        }
        let normal_speed = n[0] * rel.rate[0] + n[1] * rel.rate[1];
        if normal_speed.partial_cmp(&absorber_core::shared::GRAZING)
            != Some(std::cmp::Ordering::Greater)
        {
            return Ok(()); // grazing: no impulse, the ball flies on
        }
        let mut landing = Landing {
            time: s.time,
            normal_speed,
            normal_impulse: 0.0,
            tangential_impulse: 0.0,
            bounced: false,
        };
        let prior = s.clone();
        let before = [s.v[i1], s.v[i2]];
        // Pressed onto the track at a_p = ((0, −g_eff) − Ä)·n + v_t²/ρ.
        let end = 4 * self.n;
        let tangential = n[0] * rel.rate[1] - n[1] * rel.rate[0];
        let pressed = (-self.effective_gravity(s.base_accel) - s.a[end + 1]) * n[1]
            - s.a[end] * n[0]
            + tangential * tangential / rho;
        // The hop's apex v_n² / (2 a_p): a hop shorter than a step is seen only here.
        if positive(pressed) {
            self.note_lift(s, normal_speed * normal_speed / (pressed + pressed), report);
        }
        let counted = s.lifted;
        let bounces = landing_bounces(
            ball.landing_restitution,
            normal_speed,
            rho * ball.stick_speed,
            pressed * self.params.integrator.step.max(ball.min_bounce_time),
        );
        if bounces {
            landing.normal_impulse = self.bounce(s, n, normal_speed)?;
            landing.bounced = true;
        } else {
            let (p_n, p_t) = self.roll_on(s, n, before)?;
            landing.normal_impulse = p_n;
            landing.tangential_impulse = p_t;
        }
        report.landing = Some(landing);
        if counted {
            report.events.landings += 1;
            report.events.bounces += u8::from(landing.bounced);
        }
        if s.contact == Contact::InFlight {
            self.after_impulse(s, &prior);
            Ok(())
        } else {
            self.restart_acceleration(s, report)
        }
    }

    /// The bounce of the flying ball at `s` (on the circle, unit normal `n`, normal speed
    /// `v_n > 0`): the frictionless impulse `P = (1 + e_n) v_n / K` along `∇d = (−n on r_A, n on
    /// c)`, `K = ∇d W⁻¹ ∇dᵀ = 1/m_b + f_nᵀ W_h⁻¹ f_n`, `q̇_i⁺ = q̇_i⁻ − P W⁻¹ ∇dᵀ`; returns `P`.
    pub(super) fn bounce(
        &self,
        s: &mut FullState,
        n: [f64; 2],
        normal_speed: f64,
    ) -> Result<f64, Error> {
        let end = 4 * self.n;
        let mode = Mode::Flying;
        let qi = self.gather_ind(&s.q, mode);
        let mut grad = vec![0.0; qi.len()];
        grad[end - 4] = -n[0];
        grad[end - 3] = -n[1];
        grad[end + 1] = n[0];
        grad[end + 2] = n[1];
        let y = self.metric_solve(s, mode, &grad, false)?;
        let k: f64 = grad.iter().zip(y.iter()).map(|(g, y)| g * y).sum();
        if !positive(k) || !k.is_finite() {
            return Err(Error::Singular);
        }
        let e_n = self.params.ball.landing_restitution;
        let mut vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        let p = bounce_impulse(normal_speed, k, e_n);
        vi.iter_mut().zip(y.iter()).for_each(|(v, y)| *v -= p * y);
        *s = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, s.contact)?;
        Ok(p)
    }

    /// The plastic, rough landing of the flying ball at `s` (on the circle, unit normal `n`,
    /// centre velocity `before`): rolling resumes with the momentum projection
    /// `v_r⁺ = v_r⁻ + W_roll⁻¹ B_bᵀ Δ`, `Δ = m_b (ċ⁻ − ċ_roll(v_r⁻))` (module doc; for the mass
    /// metric this is `(Bᵀ M B)⁻¹ Bᵀ M v⁻`), θ from `n` on ψ's branch and φ re-based so that
    /// `r_b φ = R_tr ψ − ρ θ`. Returns the impulse on the ball, normal (towards A) and
    /// tangential along `t = (cos θ, sin θ)`.
    pub(super) fn roll_on(
        &self,
        s: &mut FullState,
        n: [f64; 2],
        before: [f64; 2],
    ) -> Result<(f64, f64), Error> {
        let ball = &self.params.ball;
        let loc0 = 4 * self.n - 4;
        let psi = s.q[self.zloc(PSI)];
        let theta = psi + wrap(n[0].atan2(-n[1]) - psi);
        let b = &self.bodies;
        s.q[self.zloc(PHI)] = (b.rtr * psi - b.rho * theta) / b.rb;
        s.theta_ref = theta;
        s.contact = Contact::Off;
        let mode = Mode::Free;
        let qi = self.gather_ind(&s.q, mode);
        let mut vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        // The rolling state of v_r⁻ at the landing configuration: ċ_roll and B_b.
        let rolling = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, s.contact)?;
        let kin = self.local_kin(
            mode,
            &qi[loc0..],
            &vi[loc0..],
            &self.local_of(&rolling.q),
            theta,
        )?;
        let delta = [
            ball.mass * (before[0] - kin.wd[RB1]),
            ball.mass * (before[1] - kin.wd[RB2]),
        ];
        // B_bᵀ Δ on the local independent coordinates (end node, φ).
        let mut rhs = vec![0.0; qi.len()];
        for (row, &j) in mode.dependent().iter().enumerate() {
            let dj = match j {
                RB1 => delta[0],
                RB2 => delta[1],
                _ => continue,
            };
            for (k, r) in rhs[loc0..].iter_mut().enumerate() {
                *r += kin.bd[row][k] * dj;
            }
        }
        let y = self.metric_solve(&rolling, mode, &rhs, false)?;
        vi.iter_mut().zip(y.iter()).for_each(|(v, y)| *v += y);
        *s = self.complete(
            &qi,
            &vi,
            &ai,
            mode,
            &rolling,
            s.time,
            s.base_accel,
            s.contact,
        )?;
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        let (jx, jy) = (
            ball.mass * (s.v[i1] - before[0]),
            ball.mass * (s.v[i2] - before[1]),
        );
        let (sin, cos) = theta.sin_cos();
        Ok((-(n[0] * jx + n[1] * jy), cos * jx + sin * jy))
    }

    /// A stop met by the flying ball at `s` (spec "Stop in flight"): the centre rotated about A
    /// onto the stop line, a frictionless impulse along `∇α_f` towards the face met; the ball
    /// flies on, the accelerations go on from before the impulse.
    pub(super) fn stop_in_flight(
        &self,
        s: &mut FullState,
        side: Side,
        inside: bool,
    ) -> Result<Impact<f64>, Error> {
        let prior = s.clone();
        let ball = &self.params.ball;
        let psi = s.q[self.zloc(PSI)];
        let rel = self.relative(s);
        let theta = psi + side.sign::<f64>() * ball.stop_angle;
        let (sin, cos) = theta.sin_cos();
        let (a, _) = self.end_point(s);
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        s.q[i1] = a[0] + rel.r * sin;
        s.q[i2] = a[1] - rel.r * cos;
        s.theta_ref = theta;
        let mode = Mode::Flying;
        let loc0 = 4 * self.n - 4;
        let qi = self.gather_ind(&s.q, mode);
        let mut vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        let kin = self.local_kin(mode, &qi[loc0..], &vi[loc0..], &self.local_of(&s.q), theta)?;
        let (_, g, _) = self.bodies.relative_angle(&kin.w, &kin.wd, theta);
        let grad = self.ind_gradient(mode, &kin, &g, qi.len());
        let speed: f64 = grad.iter().zip(vi.iter()).map(|(a, b)| a * b).sum();
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: 0.0,
            energy_loss: 0.0,
            stuck: false,
        };
        let towards = if inside {
            side.sign::<f64>() * speed
        } else {
            -side.sign::<f64>() * speed
        };
        if towards > 0.0 {
            let e = if speed.abs() < ball.stick_speed {
                0.0
            } else {
                ball.restitution
            };
            let y = self.metric_solve(s, mode, &grad, true)?;
            let k: f64 = grad.iter().zip(y.iter()).map(|(g, y)| g * y).sum();
            if !positive(k) || !k.is_finite() {
                return Err(Error::Singular);
            }
            let lambda = -(1.0 + e) * speed / k;
            vi.iter_mut()
                .zip(y.iter())
                .for_each(|(v, y)| *v += lambda * y);
            impact.impulse = lambda / rel.r;
            impact.energy_loss = 0.5 * (1.0 - e * e) * speed * speed / k;
        }
        *s = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, s.contact)?;
        self.after_impulse(s, &prior);
        Ok(impact)
    }

    /// A local gradient `g` (over the 10 local coordinates) on the independent coordinates of
    /// `mode`: `gᵀ B` (zero on the beam's interior coordinates).
    pub(crate) fn ind_gradient(
        &self,
        mode: Mode,
        kin: &super::super::partition::Kin,
        g: &[f64; NW],
        ni: usize,
    ) -> Vec<f64> {
        let loc0 = 4 * self.n - 4;
        let mut grad = vec![0.0; ni];
        for (k, &jk) in mode.independent().iter().enumerate() {
            grad[loc0 + k] = g[jk]
                + mode
                    .dependent()
                    .iter()
                    .enumerate()
                    .map(|(r, &j)| kin.bd[r][k] * g[j])
                    .sum::<f64>();
        }
        grad
    }
}
