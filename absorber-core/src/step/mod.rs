//! One step of the model, the machinery behind [`crate::Model::step`] (private: what other
//! crates share of it is in [`crate::shared`]). Read top to bottom, a step is [`System::advance`]:
//!
//! 0. **Work charged up front** ([`crate::work`]): the event tests the step will make whatever
//!    happens (a flying ball's tests against the circle and the stops, a held ball's release test).
//! 1. **Newmark over the whole step** (`newmark`: the predictor, the generalized-α recursion of
//!    `scheme`, the corrector solved for the new acceleration by `newton` with the limits of
//!    `convergence`), the ball keeping its contact. Each Newton iteration assembles the
//!    residual and the banded Newton matrix in `system`: the beam's elements (`beam`, `ancf`),
//!    the tip body and ball on the local coordinates (`tip`, by dual numbers, `dual`; the fast
//!    sine and cosine of `trig`), factored by `linalg`.
//! 2. **Events.** On the track: the stops (`stops`: an impact splits the step at the crossing,
//!    a held ball is released when the stop would pull it), then the separation (`flight`: a
//!    track that would pull the ball lets it fly). In flight: the landing or stop hit that splits
//!    the step (`flight`). An event the work cap cannot afford waits for the next step.
//! 3. **The clock**: whole steps times `h`; a non-finite state is refused and a capped step is
//!    kept or refused as `integrator.at_cap` says.
//!
//! The model then applies the restart rule ([`crate::Model::step`], "Recovery"). The static
//! solve and the start of a run are in `statics`. Role files (`newmark`, `newton`, `stops`,
//! `flight`, `statics`) add methods to [`System`] and import only `system` and the files below
//! it; this file calls them.

pub(crate) mod ancf;
pub(crate) mod beam;
pub(crate) mod convergence;
pub(crate) mod dual;
pub(crate) mod flight;
pub(crate) mod linalg;
pub(crate) mod newmark;
pub(crate) mod newton;
pub(crate) mod scheme;
pub(crate) mod statics;
pub(crate) mod stops;
pub(crate) mod system;
pub(crate) mod tip;
pub(crate) mod trig;

use crate::error::Error;
use crate::scalar::Real;
use crate::scene::Scene;
use crate::state::{Contact, EventCounts, Outcome, State, StepReport};
use newton::Workspace;
use system::System;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// One step from `state` to the input `base_accel` at its end: `state` becomes the next
    /// state and the report is returned, or an error (then `state` is unchanged, and nothing
    /// else is but the workspace's scratch).
    pub(crate) fn advance(
        &self,
        state: &mut State<T, D>,
        base_accel: T,
        ws: &mut Workspace<T, D>,
    ) -> Result<StepReport<T>, Error> {
        let h = self.params.integrator.step;
        let start = &*state;
        // 0. The work the step's event tests take whatever happens (no loop in them): the
        //    flying ball's tests against the circle and the stops, the release test of a ball
        //    on a stop (a residual); charged first, so that the solves have that much less.
        ws.charge_fixed(match start.contact {
            Contact::InFlight if S::FLIGHT => crate::work::FLIGHT_TESTS,
            Contact::OnStop(_) => crate::work::RESIDUAL,
            _ => 0,
        });
        // 1. Newmark over the whole step (the ball keeps its contact, on the track or flying).
        let mut next = *start;
        let solved = self.newmark(
            start,
            h,
            base_accel,
            ws,
            self.params.integrator.newton,
            &mut next,
        )?;
        let mut report = StepReport {
            iterations: solved.iterations,
            increment: solved.increment,
            impact: None,
            separation: None,
            landing: None,
            work: 0,
            outcome: Outcome::Converged,
            events: EventCounts::default(),
        };
        // An event the work cap cannot afford (a plastic landing's own matrix) leaves the state
        // as the event code found it, consistent, and waits for the next step (`waits`).
        if S::FLIGHT && start.contact == Contact::InFlight {
            // 2'. In flight: a landing or a stop splits the step at the crossing.
            let r = self.flight_events(start, &mut next, base_accel, ws, &mut report);
            waits(ws, r)?;
        } else {
            // 2. Stops: an impact splits the step at the crossing; a held ball may be released.
            let r = self.stop_events(start, &mut next, base_accel, ws, &mut report);
            waits(ws, r)?;
            // 3. Separation: a track that would pull the ball lets it fly (after a stop impact,
            // at the step's end: `separation` says how).
            if self.flies() {
                let r = self.separation(start, &mut next, base_accel, ws, &mut report);
                waits(ws, r)?;
            }
        }
        // A flight counts as a separation once it is higher than `ball.lift_height`.
        if S::FLIGHT {
            self.note_gap(&mut next, &mut report);
        }
        // 4. The clock: whole steps times h (a running sum of h drifts in f32).
        next.steps = start.steps.saturating_add(1);
        next.time = T::from_count(next.steps) * h;
        Self::is_finite(&next)?;
        if ws.capped() && self.params.integrator.at_cap == crate::params::AtCap::Keep {
            // A capped step whose iterate is not to be taken: the state as before, an error.
            return Err(Error::WorkCap);
        }
        *state = next;
        Ok(report)
    }
}

/// An event's result: one the work cap could not afford flags the step and waits for the next.
#[inline(always)]
fn waits<T: Real, const D: usize>(
    ws: &mut Workspace<T, D>,
    r: Result<(), Error>,
) -> Result<(), Error> {
    match r {
        Err(Error::WorkCap) => {
            ws.flag_capped();
            Ok(())
        }
        r => r,
    }
}
