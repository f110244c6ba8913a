//! Ball flight in the full solver (issue 13; the law: /work/flight-spec.md, the embedded
//! core's `absorber_core::flight` implements the same physics in minimal coordinates).
//!
//! **Flight mode** ([`Mode::Flying`]): the rolling contact constraints `c₄` (circle) and `c₅`
//! (no slip) are released; only the fixed joint `c₁…c₃` welds the tip body to the beam end. The
//! ball's `(φ, R_b1, R_b2)` become independent coordinates (`n_ind = 4N + 3`) integrated by the
//! scene's integrator with no constraint: their rows of the augmented system (22) are
//! `J_b φ̈ = 0`, `m_b R̈_b = (0, −m_b g_eff)`, so the ball flies ballistically relative to the
//! base and the housing moves without it. The stops' lock `c₆` does not apply in flight.
//!
//! **Events** at the end of each step, at most one split per step (spec "Events"):
//! - *separation* (ball on the track): the track's normal force `N = λ₄` (the multiplier of
//!   the circle constraint, [`FullSolver::contact_forces`]) is negative at the step's end and
//!   the step had no stop impact: `τ = N₀ / (N₀ − N₁)` (0 if `N₀ ≤ 0`,
//!   [`absorber_core::flight::separation_fraction`]); rolling sub-step `τh`, take-off (positions
//!   and velocities are the maximal coordinates already: continuous), consistent acceleration
//!   of the flight mode, flight sub-step `(1 − τ)h`;
//! - *landing* (in flight): `d = |c − A| − ρ > 0` at the end: `τ` = the cubic Hermite root of `d`
//!   with rates `ḋ h`, `ḋ = n·(ċ − Ȧ)` ([`absorber_core::flight::hermite_root`]);
//! - *stop in flight*: at the stops' height (`|c − A| > ρ − r_b`) at both ends, the polar angle
//!   relative to the housing `α_f = atan2(c_x − A_x, A_y − c_y) − ψ` crosses `±α_max` from either
//!   face: `τ` = the Hermite root of `α_f ∓ α_max`. The earlier of landing and stop wins;
//! - an event found at the end of a step's rest is applied there, without another split.
//!
//! **Impulses** in the metric of `ball.impact_model` (as the stops): the reduced Newton matrix
//! of a whole step `W = Bᵀ (M + γhC + βh²K) B` of the mode concerned (`OverStep`), or the reduced
//! mass matrix `Bᵀ M B` (`Instantaneous`). The ball's own block is its mass in both.
//! - *bounce*: along `∇d = (−n on r_A, +n on c)`: `P = (1 + e_n) v_n / K`, `K = ∇d W⁻¹ ∇dᵀ =
//!   1/m_b + f_nᵀ W_h⁻¹ f_n`, `q̇_i⁺ = q̇_i⁻ − P W⁻¹ ∇dᵀ` (the ball keeps flying);
//! - *plastic rough landing*: the momentum projection onto the rolling partition,
//!   `v_r⁺ = (Bᵀ W_fl B)⁻¹ Bᵀ W_fl v⁻ = v_r⁻ + W_roll⁻¹ B_bᵀ Δ`, `Δ = m_b (ċ⁻ − ċ_roll(v_r⁻))`
//!   (`B` the velocity transformation of the rolling mode, `B_b` its ball-centre rows), with φ
//!   re-based so that `r_b φ = R_tr ψ − ρ θ`;
//! - *stop in flight*: along `∇α_f` (on the ball `t_f / r`, on the housing `−t_f / r` at `A` and
//!   `−∇ψ`), `Λ = −(1 + e) α̇_f / (∇α_f W⁻¹ ∇α_fᵀ)`, towards the face met only, plastic below
//!   `stick_speed`; the ball flies on.
//!
//! Then the consistent acceleration of the mode the event leaves (the generalized-α recursion
//! restarts from it), as after a stop impact.

use super::{lock, FullSolver, FullState, Work};
use crate::full::kin::{Mode, NW, PHI, PSI, RB1, RB2};
use absorber_core::flight::{bounce_impulse, hermite_root, landing_bounces, separation_fraction};
use absorber_core::tip::Chain;
use absorber_core::{Contact, Error, Impact, ImpactModel, Landing, Side, StepReport};

/// A rolling ball starting a step this far beyond a stop \[rad\] still counts as between the
/// stops (put on the stop by an impact, to rounding): the core's `stops::BEYOND_MARGIN`.
pub(super) const BEYOND_MARGIN: f64 = 1e-3;

/// `x` shifted by whole turns into `(−π, π]`.
pub(super) fn wrap(x: f64) -> f64 {
    let two_pi = 2.0 * core::f64::consts::PI;
    x - two_pi * (x / two_pi).round()
}

/// The flying ball relative to the track's centre A.
#[derive(Clone, Copy, Debug)]
pub(super) struct Relative {
    /// c − A \[m\].
    pub d: [f64; 2],
    /// ċ − Ȧ \[m/s\].
    pub rate: [f64; 2],
    /// |c − A| \[m\].
    pub r: f64,
}

impl Relative {
    /// `ḋ = n·(ċ − Ȧ)`, the rate of `|c − A|` \[m/s\].
    fn radial_rate(&self) -> f64 {
        (self.d[0] * self.rate[0] + self.d[1] * self.rate[1]) / self.r
    }
}

/// Which event splits a flight step.
#[derive(Clone, Copy, Debug)]
enum FlightEvent {
    Landing,
    Stop(Side, bool),
}

impl FullSolver {
    /// The ball is in flight.
    pub fn in_flight(&self) -> bool {
        self.state.contact == Contact::InFlight
    }

    /// The ball's centre `c` and its velocity `ċ` in the frame translating with the base
    /// \[m, m/s\], on the track and in flight (the maximal coordinates `R_b`); `None` without a
    /// ball.
    pub fn ball_centre(&self) -> Option<([f64; 2], [f64; 2])> {
        if !self.scene.has_ball() {
            return None;
        }
        let s = &self.state;
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        Some(([s.q[i1], s.q[i2]], [s.v[i1], s.v[i2]]))
    }

    /// The landing of the last step, if the ball landed in it.
    pub fn last_landing(&self) -> Option<Landing<f64>> {
        self.last_landing
    }

    /// The beam end A and its velocity (clamp at the origin of the base frame).
    fn end_point(&self, s: &FullState) -> ([f64; 2], [f64; 2]) {
        let i = 4 * self.n;
        (
            [self.params.beam.length + s.q[i], s.q[i + 1]],
            [s.v[i], s.v[i + 1]],
        )
    }

    /// The ball relative to A (any mode).
    pub(super) fn relative(&self, s: &FullState) -> Relative {
        let (a, ad) = self.end_point(s);
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        let d = [s.q[i1] - a[0], s.q[i2] - a[1]];
        Relative {
            d,
            rate: [s.v[i1] - ad[0], s.v[i2] - ad[1]],
            r: (d[0] * d[0] + d[1] * d[1]).sqrt(),
        }
    }

    /// The track's normal force on a rolling ball, `N = λ₄` (the circle constraint's
    /// multiplier) \[N\]; zero in flight.
    pub(super) fn normal_force(&self, s: &FullState) -> Result<f64, Error> {
        if s.contact == Contact::InFlight {
            return Ok(0.0);
        }
        Ok(self.multipliers(s)?[3])
    }

    /// Relative angles of two states on one branch: `α₀` wrapped to `(−π, π]` and `α₁` the
    /// nearest to it (the core's `branch_angles`).
    pub(super) fn branch_angles(&self, a: &FullState, b: &FullState) -> (f64, f64) {
        let (raw0, raw1) = (self.relative_angle(a), self.relative_angle(b));
        let a0 = wrap(raw0);
        (a0, a0 + wrap(raw1 - raw0))
    }

    /// The flying ball is at the stops' height: its centre beyond `ρ − r_b` from A (a stop is
    /// a block on the track as tall as the ball's radius).
    fn at_stop_height(&self, s: &FullState) -> bool {
        let b = &self.params.ball;
        self.relative(s).r > b.path_radius() - b.radius
    }

    /// A stop met by the flying ball between `from` and `to` (spec rule 3 with revision 4):
    /// side, whether it came from between the stops, crossing fraction.
    fn stop_crossing(&self, from: &FullState, to: &FullState) -> Option<(Side, bool, f64)> {
        if !self.scene.stops() || !self.at_stop_height(from) || !self.at_stop_height(to) {
            return None;
        }
        let stop = self.params.ball.stop_angle;
        let (alpha0, alpha1) = self.branch_angles(from, to);
        let inside = alpha0.abs() <= stop;
        if inside == (alpha1.abs() <= stop) {
            return None;
        }
        let outer = if inside { alpha1 } else { alpha0 };
        let side = if outer > 0.0 {
            Side::Positive
        } else {
            Side::Negative
        };
        let target = side.sign::<f64>() * stop;
        let h = self.params.integrator.step;
        let tau = hermite_root(
            alpha0 - target,
            self.relative_rate(from) * h,
            alpha1 - target,
            self.relative_rate(to) * h,
        );
        Some((side, inside, tau))
    }

    /// The consistent acceleration after a jump of velocity or mode (the generalized-α
    /// recursion restarts from it).
    fn restart_acceleration(
        &self,
        s: &mut FullState,
        report: &mut StepReport<f64>,
    ) -> Result<(), Error> {
        let acc = self.consistent_acceleration(s)?;
        report.iterations += acc.iterations;
        *s = self.with_accel(s, &acc.x)?;
        Ok(())
    }

    /// A sub-step of `h1` from `s` to the input `accel` (the state itself when `h1` is below
    /// `1e-6 h`).
    fn sub_step(
        &self,
        s: &FullState,
        h1: f64,
        accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        if h1 > self.params.integrator.step * 1e-6 {
            let (m, solved) = self.newmark(s, h1, accel)?;
            report.iterations += solved.iterations;
            report.increment = report.increment.max(solved.increment);
            Ok(m)
        } else {
            Ok(s.clone())
        }
    }

    /// `W⁻¹ g` for the impulse metric of `ball.impact_model` in `mode` at the configuration of
    /// `s` (the reduced Newton matrix of a whole step, or the reduced mass matrix).
    pub(super) fn metric_solve(
        &self,
        s: &FullState,
        mode: Mode,
        g: &[f64],
    ) -> Result<Vec<f64>, Error> {
        let ch = if self.params.ball.impact_model == ImpactModel::OverStep {
            self.step_chain(self.params.integrator.step)
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
        let mut guard = lock(&self.work);
        let Work { mass, reduced } = &mut *guard;
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

    /// The ball leaves the track if the rolling step from `start` to `next` (no stop impact)
    /// ends with the track pulling it (spec rule 1).
    pub(super) fn separation(
        &self,
        start: &FullState,
        next: FullState,
        base_accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        let n_end = self.normal_force(&next)?;
        if !(n_end < 0.0) {
            return Ok(next);
        }
        let h = self.params.integrator.step;
        let tau = separation_fraction(self.normal_force(start)?, n_end);
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = self.sub_step(start, h1, accel_mid, report)?;
        // Take-off: positions and velocities are the maximal coordinates (continuous).
        mid.contact = Contact::InFlight;
        self.restart_acceleration(&mut mid, report)?;
        report.separation = Some(mid.time);
        self.rest_of_step(&mid, h - h1, base_accel, report)
    }

    /// The events of a flight step from `start` whose trial end is `trial` (spec rules 2, 3).
    pub(super) fn flight_events(
        &self,
        start: &FullState,
        trial: FullState,
        base_accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        let h = self.params.integrator.step;
        let rho = self.params.ball.path_radius();
        let mut tau = 1.0;
        let mut event = None;
        let r1 = self.relative(&trial);
        if r1.r > rho {
            let r0 = self.relative(start);
            tau = hermite_root(
                r0.r - rho,
                r0.radial_rate() * h,
                r1.r - rho,
                r1.radial_rate() * h,
            );
            event = Some(FlightEvent::Landing);
        }
        if let Some((side, inside, t)) = self.stop_crossing(start, &trial) {
            if event.is_none() || t < tau {
                tau = t;
                event = Some(FlightEvent::Stop(side, inside));
            }
        }
        let Some(event) = event else {
            return Ok(trial);
        };
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = self.sub_step(start, h1, accel_mid, report)?;
        match event {
            FlightEvent::Landing => self.land(&mut mid, report)?,
            FlightEvent::Stop(side, inside) => {
                let impact = self.stop_in_flight(&mut mid, side, inside, report)?;
                report.impact = Some(impact);
            }
        }
        self.rest_of_step(&mid, h - h1, base_accel, report)
    }

    /// The rest `h_rest` of a step after an event at `mid`, in the mode the event left; an
    /// event at its end is applied there, without another split (spec rule 4).
    fn rest_of_step(
        &self,
        mid: &FullState,
        h_rest: f64,
        base_accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        let mut end = self.sub_step(mid, h_rest, base_accel, report)?;
        if end.contact == Contact::InFlight {
            if let Some((side, inside, _)) = self.stop_crossing(mid, &end) {
                let impact = self.stop_in_flight(&mut end, side, inside, report)?;
                report.impact = report.impact.or(Some(impact));
            }
            if self.relative(&end).r > self.params.ball.path_radius() {
                self.land(&mut end, report)?;
            }
        } else if self.scene.stops() && end.contact == Contact::Off {
            // Landed (plastic) and rolled across a stop within the rest: from between the
            // stops it rests there (plastic, released at once if the stop would pull); from
            // the arc beyond, the stop's other face pushes it back (never sticks).
            let stop = self.params.ball.stop_angle;
            let (a0, a1) = self.branch_angles(mid, &end);
            let inside = a0.abs() <= stop + BEYOND_MARGIN;
            if inside != (a1.abs() <= stop) {
                let outer = if inside { a1 } else { a0 };
                let side = if outer > 0.0 {
                    Side::Positive
                } else {
                    Side::Negative
                };
                if inside {
                    end = self.rest_on_stop(&end, side)?;
                } else {
                    let impact = self.impact(&mut end, side, false)?;
                    self.restart_acceleration(&mut end, report)?;
                    report.impact = report.impact.or(Some(impact));
                }
            }
        }
        Ok(end)
    }

    /// The landing at the crossing `s` (spec "Impacts, Landing"): the centre put on the circle,
    /// then a bounce or a plastic, rough landing; the consistent acceleration of the mode left.
    pub(super) fn land(
        &self,
        s: &mut FullState,
        report: &mut StepReport<f64>,
    ) -> Result<(), Error> {
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let rel = self.relative(s);
        if !(rel.r > 0.0) {
            return Err(Error::NonFiniteState);
        }
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (a, _) = self.end_point(s);
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        s.q[i1] = a[0] + rho * n[0];
        s.q[i2] = a[1] + rho * n[1];
        let normal_speed = n[0] * rel.rate[0] + n[1] * rel.rate[1];
        if !(normal_speed > 0.0) {
            return Ok(()); // grazing: no impulse, the ball flies on
        }
        let mut landing = Landing {
            time: s.time,
            normal_speed,
            normal_impulse: 0.0,
            tangential_impulse: 0.0,
            bounced: false,
        };
        let before = [s.v[i1], s.v[i2]];
        // Pressed onto the track at a_p = ((0, −g_eff) − Ä)·n + v_t²/ρ.
        let end = 4 * self.n;
        let tangential = n[0] * rel.rate[1] - n[1] * rel.rate[0];
        let pressed = (-self.effective_gravity(s.base_accel) - s.a[end + 1]) * n[1]
            - s.a[end] * n[0]
            + tangential * tangential / rho;
        let bounces = landing_bounces(
            ball.landing_restitution,
            normal_speed,
            rho * ball.stick_speed,
            pressed * self.params.integrator.step,
        );
        let loc0 = end - 4;
        if bounces {
            let mode = Mode::Flying;
            let qi = self.gather_ind(&s.q, mode);
            let mut grad = vec![0.0; qi.len()];
            grad[loc0] = -n[0];
            grad[loc0 + 1] = -n[1];
            grad[end + 1] = n[0];
            grad[end + 2] = n[1];
            let y = self.metric_solve(s, mode, &grad)?;
            let k: f64 = grad.iter().zip(y.iter()).map(|(g, y)| g * y).sum();
            if !(k > 0.0) || !k.is_finite() {
                return Err(Error::Singular);
            }
            let p = bounce_impulse(normal_speed, k, ball.landing_restitution);
            let mut vi = self.gather_ind(&s.v, mode);
            vi.iter_mut().zip(y.iter()).for_each(|(v, y)| *v -= p * y);
            let ai = self.gather_ind(&s.a, mode);
            *s = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, s.contact)?;
            landing.normal_impulse = p;
            landing.bounced = true;
        } else {
            // θ on the branch of ψ, φ re-based so that r_b φ = R_tr ψ − ρ θ.
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
            // The rolling kinematics of v_r⁻ at the landing configuration: ċ_roll and B_b.
            let kin =
                self.local_kin(mode, &qi[loc0..], &vi[loc0..], &self.local_of(&s.q), theta)?;
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
            // Evaluated on the rolling state (positions on the circle, v_r⁻).
            let rolling = self.complete(&qi, &vi, &ai, mode, s, s.time, s.base_accel, s.contact)?;
            let y = self.metric_solve(&rolling, mode, &rhs)?;
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
            let (jx, jy) = (
                ball.mass * (s.v[i1] - before[0]),
                ball.mass * (s.v[i2] - before[1]),
            );
            let (sin, cos) = theta.sin_cos();
            landing.normal_impulse = -(n[0] * jx + n[1] * jy);
            landing.tangential_impulse = cos * jx + sin * jy;
        }
        report.landing = Some(landing);
        self.restart_acceleration(s, report)
    }

    /// A stop met by the flying ball at `s` (spec "Stop in flight"): the centre rotated about A
    /// onto the stop line, a frictionless impulse along `∇α_f` towards the face met; the ball
    /// flies on.
    fn stop_in_flight(
        &self,
        s: &mut FullState,
        side: Side,
        inside: bool,
        report: &mut StepReport<f64>,
    ) -> Result<Impact<f64>, Error> {
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
            let y = self.metric_solve(s, mode, &grad)?;
            let k: f64 = grad.iter().zip(y.iter()).map(|(g, y)| g * y).sum();
            if !(k > 0.0) || !k.is_finite() {
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
        self.restart_acceleration(s, report)?;
        Ok(impact)
    }

    /// A local gradient `g` (over the 10 local coordinates) on the independent coordinates of
    /// `mode`: `gᵀ B` (zero on the beam's interior coordinates).
    pub(super) fn ind_gradient(
        &self,
        mode: Mode,
        kin: &super::Kin,
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
