//! Ball flight in the full solver (docs/model.md, "Contact and flight"; the embedded
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
//! After an impulse the velocities have jumped and the accelerations (and the generalized-α
//! variable) go on from before it, as the core's (`System::after_impulse`: the impulse is the
//! nonsmooth part of the motion); a take-off (no impulse) restarts from the consistent
//! acceleration of the flight mode. A ball on the track at the end of a step that had an event
//! takes off there if the track pulls. The flying ball's centre is integrated exactly (the
//! core's `System::fly`: its acceleration `(0, −g_eff)` is known, linear in time over a step).

use super::{FullSolver, FullState, Work};
use crate::full::kin::{Mode, NW, PHI, PSI, RB1, RB2};
use absorber_core::flight::{bounce_impulse, hermite_root, landing_bounces, separation_fraction};
use absorber_core::tip::Chain;
use absorber_core::{Contact, Error, Impact, ImpactModel, Landing, Side, StepReport};

/// A rolling ball starting a step this far beyond a stop \[rad\] still counts as between the
/// stops (put on the stop by an impact, to rounding): the core's `stops::BEYOND_MARGIN`.
pub(super) const BEYOND_MARGIN: f64 = 1e-3;

/// `x > 0` (false for NaN).
fn positive(x: f64) -> bool {
    x > 0.0
}

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

    /// The track's normal force on a rolling ball for the separation test \[N\]; zero in
    /// flight: the first of [`Self::track_force`].
    pub(super) fn normal_force(&self, s: &FullState) -> Result<f64, Error> {
        if s.contact == Contact::InFlight {
            return Ok(0.0);
        }
        Ok(self.track_force(s)?.0)
    }

    /// The track's force on a ball on the track, `(N, F_t)` \[N\], from the ball's own equation
    /// of motion with the state's accelerations (the integrator's, `R̈_b` from the acceleration
    /// constraints): the force on the ball is `F = m_b (R̈_b + g_eff ŷ)`, its inward component
    /// `N = −n·F` and its component along increasing θ `F_t = t·F`, with
    /// `n = (R_b − A)/|R_b − A|`, `t = (−n_y, n_x)` — the core's formulas `m_b [−ẍ_A sin θ +
    /// (ÿ_A + g_eff) cos θ + ρ θ̇²]` and `m_b [ẍ_A cos θ + (ÿ_A + g_eff) sin θ + ρ θ̈]` written in
    /// maximal coordinates. The multipliers of the augmented system
    /// ([`Self::contact_forces_from_multipliers`]) are the same force from the exact dynamics
    /// at (q, q̇); they differ from this by the Newton residual of the step.
    pub(super) fn track_force(&self, s: &FullState) -> Result<(f64, f64), Error> {
        let rel = self.relative(s);
        if !positive(rel.r) {
            return Err(Error::NonFiniteState);
        }
        let (i1, i2) = (self.zloc(RB1), self.zloc(RB2));
        let force = [
            self.bodies.weights.1 * s.a[i1],
            self.bodies.weights.1 * (s.a[i2] + self.effective_gravity(s.base_accel)),
        ];
        Ok((
            -(rel.d[0] * force[0] + rel.d[1] * force[1]) / rel.r,
            (rel.d[0] * force[1] - rel.d[1] * force[0]) / rel.r,
        ))
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
    /// side, whether it came from between the stops (within [`BEYOND_MARGIN`], as on the
    /// track), crossing fraction.
    fn stop_crossing(&self, from: &FullState, to: &FullState) -> Option<(Side, bool, f64)> {
        if !self.scene.stops() || !self.at_stop_height(from) || !self.at_stop_height(to) {
            return None;
        }
        let stop = self.params.ball.stop_angle;
        let (alpha0, alpha1) = self.branch_angles(from, to);
        // A ball put onto the stop line by a stop impact sits on it to rounding: it starts
        // between the stops (the rolling rule's margin; without it, a start at α_max + 1 ulp
        // counted as beyond the stop and the impulse of the rest of the step was reversed).
        let inside = alpha0.abs() <= stop + BEYOND_MARGIN;
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

    /// After an impulse at `s` that began at `before`: the accelerations and the generalized-α
    /// variable are `before`'s (the core's `System::after_impulse`); `complete` recomputed the
    /// dependent coordinates' accelerations from the new velocities. A flying ball's centre keeps
    /// its known acceleration.
    pub(super) fn after_impulse(&self, s: &mut FullState, before: &FullState) {
        s.pa.clone_from(&before.pa);
        if s.contact == Contact::InFlight {
            let g = self.effective_gravity(s.base_accel);
            for (z, a) in [(self.zloc(RB1), 0.0), (self.zloc(RB2), -g)] {
                s.a[z] = a;
                s.pa[z] = a;
            }
        }
    }

    /// The exact flight of the ball's centre over a step of `h` from `s` into `next` (the core's
    /// `System::fly`): with `(0, −g_eff)` linear in time from its value at `s` to `next`'s,
    /// `Δċ = h (a₀ + a₁)/2`, `Δc = h ċ₀ + h² (a₀/3 + a₁/6)` (the scheme's own integration of the
    /// decoupled ball rows drifted under a moving base).
    pub(super) fn fly_exactly(&self, s: &FullState, h: f64, next: &mut FullState) {
        let (g0, g1) = (
            self.effective_gravity(s.base_accel),
            self.effective_gravity(next.base_accel),
        );
        for (z, a0, a1) in [(self.zloc(RB1), 0.0, 0.0), (self.zloc(RB2), -g0, -g1)] {
            next.q[z] = s.q[z] + h * s.v[z] + h * h * (a0 / 3.0 + a1 / 6.0);
            next.v[z] = s.v[z] + h * (a0 + a1) / 2.0;
            next.a[z] = a1;
            next.pa[z] = a1;
        }
    }

    /// A ball on the track at the end `end` of a step that had an event (a stop impact, a
    /// landing) leaves the track there if it pulls (the core's `take_off_at_end`); `time` is the
    /// step's end.
    pub(super) fn take_off_at_end(
        &self,
        end: &mut FullState,
        time: f64,
        report: &mut StepReport<f64>,
    ) -> Result<(), Error> {
        if end.contact == Contact::InFlight || !positive(-self.normal_force(end)?) {
            return Ok(());
        }
        end.contact = Contact::InFlight;
        end.lifted = false;
        self.restart_acceleration(end, report)?;
        report.separation = Some(time);
        self.note_lift(end, 0.0, report);
        Ok(())
    }

    /// The flight at `s` reaches the counted height: `height` \[m\] (the gap at a step's end
    /// or a hop's apex; 0 at the take-off) above `ball.lift_height`, or that height 0 (every
    /// take-off counts): it counts once, as a separation (the core's `System::note_lift`).
    fn note_lift(&self, s: &mut FullState, height: f64, report: &mut StepReport<f64>) {
        if s.contact != Contact::InFlight || s.lifted {
            return;
        }
        let lift = self.params.ball.lift_height;
        if !positive(lift) || height > lift {
            s.lifted = true;
            report.events.separations += 1;
        }
    }

    /// A flying ball at a step's end `s`: its gap to the track `ρ − |c − A|` counts towards
    /// the flight's height ([`Self::note_lift`]).
    pub(super) fn note_gap(&self, s: &mut FullState, report: &mut StepReport<f64>) {
        if s.contact != Contact::InFlight || s.lifted {
            return;
        }
        let gap = self.params.ball.path_radius() - self.relative(s).r;
        self.note_lift(s, gap, report);
    }

    /// The consistent acceleration after a change of mode (the generalized-α recursion
    /// restarts from it).
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

    /// The ball leaves the track if the rolling step from `start` to `next` ends with the track
    /// pulling it (spec rule 1); after a stop impact in the step, at its end.
    pub(super) fn separation(
        &self,
        start: &FullState,
        mut next: FullState,
        base_accel: f64,
        report: &mut StepReport<f64>,
    ) -> Result<FullState, Error> {
        let n_end = self.normal_force(&next)?;
        if !positive(-n_end) {
            return Ok(next);
        }
        let h = self.params.integrator.step;
        if report.impact.is_some() {
            self.take_off_at_end(&mut next, start.time + h, report)?;
            return Ok(next);
        }
        let tau = separation_fraction(self.normal_force(start)?, n_end);
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = self.sub_step(start, h1, accel_mid, report)?;
        // Take-off: positions and velocities are the maximal coordinates (continuous).
        mid.contact = Contact::InFlight;
        mid.lifted = false;
        self.note_lift(&mut mid, 0.0, report);
        self.restart_acceleration(&mut mid, report)?;
        report.separation = Some(mid.time);
        let mut end = self.rest_of_step(&mid, h - h1, base_accel, report)?;
        self.take_off_at_end(&mut end, start.time + h, report)?;
        Ok(end)
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
                let impact = self.stop_in_flight(&mut mid, side, inside)?;
                report.impact = Some(impact);
                report.events.impacts += 1;
            }
        }
        let mut end = self.rest_of_step(&mid, h - h1, base_accel, report)?;
        self.take_off_at_end(&mut end, start.time + h, report)?;
        Ok(end)
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
                let impact = self.stop_in_flight(&mut end, side, inside)?;
                report.impact = report.impact.or(Some(impact));
                report.events.impacts += 1;
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
                    let before = end.clone();
                    let impact = self.impact(&mut end, side, false)?;
                    self.after_impulse(&mut end, &before);
                    report.impact = report.impact.or(Some(impact));
                    report.events.impacts += 1;
                }
            }
        }
        Ok(end)
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
        if normal_speed.partial_cmp(&absorber_core::flight::GRAZING)
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
    fn bounce(&self, s: &mut FullState, n: [f64; 2], normal_speed: f64) -> Result<f64, Error> {
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
    fn roll_on(
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
    fn stop_in_flight(
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
    pub(super) fn ind_gradient(
        &self,
        mode: Mode,
        kin: &super::partition::Kin,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::full::SceneKind;
    use crate::sim::Simulator;
    use absorber_core::Params;

    /// (a) The first test, as the core's (`absorber-core/tests/flight.rs`): a stiff beam
    /// (E × 10⁴, first mode ≈ 400 Hz) makes the housing follow the base, which accelerates
    /// down at 1.5 g from rest. The ball leaves the track in the step where the rolling
    /// model's normal force first turns negative (the same run with `ball.flight = false`,
    /// bit-identical until then), and from the first state in flight it follows the closed-form
    /// ballistic path relative to the base, `c(t) = c₁ + ċ₁ (t − t₁) − ½ g_eff (t − t₁)² ŷ`, until
    /// it lands. Reference: the closed form; budget: Newmark (any γ, β) is exact for a constant
    /// acceleration, so only rounding remains: 1e-12 m (positions, and velocities times h).
    #[test]
    fn ball_separates_where_n_turns_negative_and_flies_ballistically_until_it_lands() {
        let mut p = Params::<f64>::default();
        p.beam.modulus *= 1e4;
        let h = p.integrator.step;
        let u = -1.5 * p.gravity;
        let g_eff = p.gravity + u;
        let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        let mut held_p = p;
        held_p.ball.flight = false;
        let mut held = FullSolver::at_rest(held_p, SceneKind::FreeBall, 3, 0.0).expect("start");
        let mut first = None;
        for k in 1..=100 {
            let r = s.step(u).expect("step");
            held.step(u).expect("step");
            let pulls = held.contact_forces().expect("ball").0 < 0.0;
            if r.separation.is_some() {
                assert!(pulls, "step {k}: separated where the track still pushes");
                first = Some(k);
                break;
            }
            assert!(!pulls, "step {k}: the track pulls and the ball stays");
            assert_eq!(s.state, held.state, "step {k}: rolling, bit-identical");
        }
        let k1 = first.expect("the ball leaves the track");
        assert!(s.in_flight());
        let t1 = s.state.time;
        let (c1, v1) = s.ball_centre().expect("ball");
        let spin = s.state.v[s.zloc(PHI)];
        let (mut worst, mut landed) = (0.0f64, None);
        for _ in 0..400 {
            let r = s.step(u).expect("step");
            if let Some(l) = r.landing {
                landed = Some(l);
                break;
            }
            assert!(s.in_flight());
            assert_eq!(s.contact_forces(), Some((0.0, 0.0)));
            let t = s.state.time - t1;
            let (c, v) = s.ball_centre().expect("ball");
            let exact = [c1[0] + v1[0] * t, c1[1] + v1[1] * t - 0.5 * g_eff * t * t];
            worst = worst
                .max((c[0] - exact[0]).abs())
                .max((c[1] - exact[1]).abs())
                .max((v[0] - v1[0]).abs() * h)
                .max((v[1] - (v1[1] - g_eff * t)).abs() * h);
            assert_eq!(s.state.v[s.zloc(PHI)], spin, "no torque on the spin");
        }
        let l = landed.expect("the ball lands on the top of the track");
        println!(
            "separated in step {k1} (t = {t1:.4} s), landed at {:.4} s (v_n = {:.3} m/s, \
             bounced: {}); worst ballistic error {worst:.2e} m",
            l.time, l.normal_speed, l.bounced
        );
        // It falls up across the housing, about 2ρ = 64 mm at 0.5 g: ≈ 0.16 s.
        assert!((0.08..0.3).contains(&(l.time - t1)), "{}", l.time - t1);
        assert!(worst < 1e-12, "{worst:e}");
    }

    /// (b) Elastic landings and stops, as the core's test: e_n = e = 1, frictionless bounces,
    /// the instantaneous impulse (mass metric: ½(1 − e²) v_n²/K = 0), the trapezoidal rule
    /// (γ = ½, β = ¼, h = 0.1 ms) and a constant effective gravity (−0.5 g: the ball falls
    /// across the housing and bounces), 1 s. Reference: the initial energy in the base frame.
    /// Budget: the core's, 1 % of the ball's drop energy m_b g_eff 2ρ — each instantaneous
    /// bounce kicks the housing's stiff end-rotation mode, whose energy the trapezoidal rule
    /// keeps only to O((ωh)²) in the nonlinear beam — and it must exceed the potential energy
    /// moved by the radial projections onto the circle, `m_b |g_eff| Σ|r − ρ|` (printed).
    #[test]
    fn elastic_landings_conserve_energy() {
        let mut p = Params::<f64> {
            gravity: -0.5 * 9.81,
            ..Default::default()
        };
        p.integrator.gamma = 0.5;
        p.integrator.beta = 0.25;
        p.integrator.step = 1e-4;
        p.ball.landing_restitution = 1.0;
        p.ball.restitution = 1.0;
        p.ball.stick_speed = 0.0;
        p.ball.impact_model = ImpactModel::Instantaneous;
        let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        let energy = |s: &FullSolver| s.energies(0.0, 0.0).total();
        let e0 = energy(&s);
        let scale = p.ball.mass * 0.5 * 9.81 * 2.0 * p.ball.path_radius();
        let (mut worst, mut projection, mut landings) = (0.0f64, 0.0f64, 0);
        for _ in 0..10_000 {
            let r = s.step(0.0).expect("step");
            if let Some(l) = r.landing {
                assert!(l.bounced, "elastic landings bounce");
                landings += 1;
                projection += s.work.borrow_mut().projection;
            }
            worst = worst.max((energy(&s) - e0).abs());
        }
        let moved = p.ball.mass * p.gravity.abs() * projection;
        println!(
            "{landings} bounces in 1 s: worst |ΔE| = {worst:.2e} J = {:.2e} of m_b g 2ρ; \
             projections Σ|r − ρ| = {projection:.2e} m ({:.2e} of m_b g 2ρ)",
            worst / scale,
            moved / scale
        );
        assert!(landings >= 2, "{landings}");
        assert!(moved < 1e-2 * scale);
        assert!(worst < 1e-2 * scale, "{:e}", worst / scale);
    }

    /// (c) Small amplitudes: the paper scene at 3.5 Hz, 0.2 mm, 2 s keeps N > 0 throughout, and
    /// the runs with flight on and off are bit-identical (reference: the run without flight;
    /// budget: zero).
    #[test]
    fn small_amplitudes_are_bit_identical_with_and_without_flight() {
        let mut p = Params::<f64>::default();
        let mut on = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        p.ball.flight = false;
        let mut off = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        let h = p.integrator.step;
        let w = 2.0 * core::f64::consts::PI * 3.5;
        let mut n_min = f64::INFINITY;
        for k in 1..=(2.0 / h) as usize {
            let u = -0.2e-3 * w * w * (w * k as f64 * h).sin();
            let (ra, rb) = (on.step(u).expect("on"), off.step(u).expect("off"));
            assert_eq!(ra, rb);
            assert_eq!(on.state, off.state, "step {k}");
            n_min = n_min.min(on.contact_forces().expect("ball").0);
        }
        println!("3.5 Hz, 0.2 mm: min N = {n_min:.4e} N");
        assert!(n_min > 0.0);
    }

    /// (d) The plastic landing's momentum projection of a ball already on the circle, moving
    /// tangentially without slip and with zero normal speed (a rolling state relabelled as in
    /// flight) changes nothing: positions and velocities to rounding (1e-12 relative).
    #[test]
    fn plastic_landing_of_a_rolling_ball_changes_nothing() {
        let mut p = Params::<f64>::default();
        p.ball.initial_angle = 30f64.to_radians();
        let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        for _ in 0..40 {
            s.step(0.0).expect("step");
        }
        let rolling = s.state.clone();
        assert_eq!(rolling.contact, Contact::Off);
        let mut f = rolling.clone();
        f.contact = Contact::InFlight;
        let rel = s.relative(&f);
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
        let before = [f.v[i1], f.v[i2]];
        let vt = (rel.rate[0].powi(2) + rel.rate[1].powi(2)).sqrt();
        assert!(vt > 0.05, "rolls: {vt} m/s");
        let (p_n, p_t) = s.roll_on(&mut f, n, before).expect("projection");
        let scale = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let dq = rolling
            .q
            .iter()
            .zip(f.q.iter())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let dv = rolling
            .v
            .iter()
            .zip(f.v.iter())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        println!(
            "plastic projection of a rolling ball: |Δq| = {dq:.2e}, |Δv| = {dv:.2e}, \
             P = ({p_n:.2e}, {p_t:.2e}) N·s"
        );
        assert_eq!(f.contact, Contact::Off);
        assert!(dq <= 1e-12 * scale(&rolling.q), "{dq:e}");
        assert!(dv <= 1e-12 * scale(&rolling.v), "{dv:e}");
    }

    /// The generalized momentum of the rolling coordinates, `Bᵀ M v` (B the rolling mode's
    /// velocity transformation at `s`'s configuration, M the constant mass matrix, `v` any
    /// velocity over the maximal coordinates).
    fn rolling_momentum(solver: &FullSolver, s: &FullState, v: &[f64]) -> Vec<f64> {
        let n = solver.n;
        let mut mv = vec![0.0; solver.nz];
        for e in 0..n {
            for i in 0..8 {
                mv[4 * e + i] += (0..8)
                    .map(|j| solver.me[(i, j)] * v[4 * e + j])
                    .sum::<f64>();
            }
        }
        for jb in 0..solver.n_body {
            mv[solver.b0() + jb] += solver.bodies.mass[4 + jb] * v[solver.b0() + jb];
        }
        let mode = Mode::Free;
        let loc0 = 4 * n - 4;
        let qi = solver.gather_ind(&s.q, mode);
        let vi = solver.gather_ind(&s.v, mode);
        let kin = solver
            .local_kin(
                mode,
                &qi[loc0..],
                &vi[loc0..],
                &solver.local_of(&s.q),
                s.theta_ref,
            )
            .expect("kinematics");
        let mut p: Vec<f64> = (0..qi.len()).map(|i| mv[solver.ind_to_z(i)]).collect();
        for (k, pk) in p[loc0..].iter_mut().enumerate() {
            for (r, &j) in mode.dependent().iter().enumerate() {
                *pk += kin.bd[r][k] * mv[solver.zloc(j)];
            }
        }
        p
    }

    /// (d′) The plastic landing is the momentum projection `v_r⁺ = (Bᵀ M B)⁻¹ Bᵀ M v⁻` (mass
    /// metric, `impact_model = Instantaneous`): a ball on the circle moving in and slipping
    /// (0.02 m/s outwards, 0.05 m/s along the track relative to rolling) rolls on afterwards —
    /// no normal speed, the rolling kinematics — and `Bᵀ M v` is unchanged (reference: before
    /// the landing; budget 1e-10 of its largest entry, rounding of the sparse solves).
    #[test]
    fn plastic_landing_keeps_the_rolling_momentum() {
        let mut p = Params::<f64>::default();
        p.ball.initial_angle = 30f64.to_radians();
        p.ball.impact_model = ImpactModel::Instantaneous;
        let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        for _ in 0..40 {
            s.step(0.0).expect("step");
        }
        let mut f = s.state.clone();
        f.contact = Contact::InFlight;
        let rel = s.relative(&f);
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
        f.v[i1] += 0.02 * n[0] - 0.05 * n[1];
        f.v[i2] += 0.02 * n[1] + 0.05 * n[0];
        let before_v = f.v.clone();
        let centre_rate = [f.v[i1], f.v[i2]];
        let (p_n, p_t) = s.roll_on(&mut f, n, centre_rate).expect("projection");
        let before = rolling_momentum(&s, &f, &before_v);
        let after = rolling_momentum(&s, &f, &f.v);
        let big = before.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = before
            .iter()
            .zip(after.iter())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let rel = s.relative(&f);
        let vn = rel.radial_rate();
        println!(
            "plastic landing with slip: |Δ(Bᵀ M v)| = {diff:.2e} of {big:.2e}; normal speed \
             after {vn:.2e} m/s; P = ({p_n:.3e}, {p_t:.3e}) N·s"
        );
        assert!(diff <= 1e-10 * big, "{diff:e}");
        assert!(vn.abs() < 1e-12, "{vn:e}");
        assert!(p_n > 0.0, "the track pushes: {p_n:e}");
    }
}
