//! Take-off: the ball leaves the track where the track would have to pull it (at the
//! crossing of the normal force, or at the step's end), and the flights' lift is counted.

use super::roots::separation_fraction;
use crate::error::Error;
use crate::scalar::{is_positive, Real};
use crate::scene::Scene;
use crate::state::Flight;
use crate::state::{Contact, State, StepReport};
use crate::step::newton::Workspace;
use crate::step::system::System;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
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
    pub(super) fn take_off_at_end(
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
    pub(super) fn restart_acceleration(
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
}
