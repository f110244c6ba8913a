//! Ball flight in the full solver (docs/model.md, "Contact and flight"; the embedded
//! core's `absorber-core/src/step/flight` implements the same physics in minimal coordinates).
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
//!   [`absorber_core::shared::separation_fraction`]); rolling sub-step `τh`, take-off (positions
//!   and velocities are the maximal coordinates already: continuous), consistent acceleration
//!   of the flight mode, flight sub-step `(1 − τ)h`;
//! - *landing* (in flight): `d = |c − A| − ρ > 0` at the end: `τ` = the cubic Hermite root of `d`
//!   with rates `ḋ h`, `ḋ = n·(ċ − Ȧ)` ([`absorber_core::shared::hermite_root`]);
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

mod impulse;

use super::{FullSolver, FullState};
use crate::kin::{RB1, RB2};
use absorber_core::shared::{hermite_root, separation_fraction};
use absorber_core::{Contact, Error, Landing, Side, StepReport};

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
        self.event_accel(start, &trial, tau, &mut mid)?;
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
}

#[cfg(test)]
mod tests;
