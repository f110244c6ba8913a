//! Newmark's method (paper §4, eqs. 29–31): predictor, and the corrector solved for the new
//! acceleration by Newton ([`crate::newton`]).
//!
//! With `ã = q̈_{n+1}` the unknown:
//! `q_{n+1} = q_n + h q̇_n + h²(½ − β) q̈_n + βh² ã`, `q̇_{n+1} = q̇_n + h(1 − γ) q̈_n + γh ã`,
//! so the Newton matrix along the unknown is `M + γh C + βh² K` (chain `c_m = 1`, `c_v = γh`,
//! `c_q = βh²`).

use crate::error::Error;
use crate::model::State;
use crate::newton::{Solved, Workspace};
use crate::params::NewtonKind;
use crate::scalar::{lit, Real};
use crate::scene::Scene;
use crate::system::{Problem, System};
use crate::tip::Chain;
use nalgebra::SVector;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The Newton chain of a Newmark step of length `h`: `(c_q, c_v, c_m) = (βh², γh, 1)`.
    pub(crate) fn newmark_chain(&self, h: T) -> Chain<T> {
        let i = &self.params.integrator;
        Chain {
            c_q: i.beta * h * h,
            c_v: i.gamma * h,
            c_m: T::one(),
        }
    }

    /// One Newmark step of length `h` from `s` to the input `base_accel` at its end; the
    /// ball's contact is kept (a ball on a stop stays projected on it). Time and step count are
    /// the caller's.
    pub(crate) fn newmark(
        &self,
        s: &State<T, D>,
        h: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        kind: NewtonKind,
    ) -> Result<(State<T, D>, Solved<T, D>), Error> {
        let i = &self.params.integrator;
        let half = lit::<T>(0.5);
        let mut q_pred = s.q;
        q_pred.axpy(h, &s.v, T::one());
        q_pred.axpy(h * h * (half - i.beta), &s.a, T::one());
        let mut v_pred = s.v;
        v_pred.axpy(h * (T::one() - i.gamma), &s.a, T::one());
        let ch = self.newmark_chain(h);
        let zero = SVector::zeros();
        let p = Problem {
            q0: &q_pred,
            v0: &v_pred,
            a0: &zero,
            ch,
            c_pos: ch.c_q,
            g_eff: self.effective_gravity(base_accel),
            contact: s.contact,
            plumb: false,
        };
        let solved = self.newton(&p, s.a, ws, kind, true)?;
        let a = solved.x;
        let mut next = State {
            q: q_pred,
            v: v_pred,
            a,
            time: s.time,
            steps: s.steps,
            base_accel,
            contact: s.contact,
        };
        next.q.axpy(ch.c_q, &a, T::one());
        next.v.axpy(ch.c_v, &a, T::one());
        if let crate::model::Contact::OnStop(side) = next.contact {
            self.hold_on_stop(&mut next, side);
        }
        Ok((next, solved))
    }
}
