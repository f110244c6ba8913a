//! A flight step's events: the first landing or stop crossing of the step, the step split at
//! it (every event, for a perfectly elastic ball), or the events applied at the step's end.

use super::geometry::Relative;
use super::roots::{hermite_rate, hermite_root, wrap};
use crate::error::Error;
use crate::scalar::{is_positive, Real};
use crate::scene::Scene;
use crate::state::{Contact, Side, State, StepReport};
use crate::step::newton::Workspace;
use crate::step::system::System;

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

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
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
    pub(super) fn rest_in_flight(
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
    /// exactly in either metric ([`crate::step::stops`]), and every event of its flight steps is split
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
    pub(super) fn flight_events_at_end(
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
}
