//! Newmark's method (paper §4, eqs. 29–31) and its generalization, the generalized-α scheme
//! (Chung & Hulbert 1993, in the form of Arnold & Brüls 2007): predictor, and the corrector
//! solved for the new acceleration by Newton ([`crate::step::newton`]).
//!
//! With `x = q̈_{n+1}` the unknown and `a` the acceleration-like variable of the scheme
//! (`a = q̈` for Newmark):
//! - `a_{n+1} = b + κ x`, `b = (α_f q̈_n − α_m a_n)/(1 − α_m)`, `κ = (1 − α_f)/(1 − α_m)`;
//! - `q_{n+1} = q_n + h q̇_n + h²(½ − β) a_n + βh² a_{n+1}`,
//!   `q̇_{n+1} = q̇_n + h(1 − γ) a_n + γh a_{n+1}`;
//!
//! so the Newton matrix along the unknown is `M + κγh C + κβh² K` (chain `c_m = 1`,
//! `c_v = κγh`, `c_q = κβh²`), and the equations of motion hold at `t_{n+1}` exactly as in
//! Newmark's method (`α_m = α_f = 0`: `b = 0`, `κ = 1`; that path never touches `b`).

use crate::error::Error;
use crate::params::NewtonKind;
use crate::scalar::{lit, Real};
use crate::scene::Scene;
use crate::state::{State, StepReport};
use crate::step::newton::{Solved, Workspace};
use crate::step::scheme::AlphaRecursion;
use crate::step::scheme::Chain;
use crate::step::system::{Problem, System};
use nalgebra::SVector;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The Newton chain of a step of length `h`: `(c_q, c_v, c_m) = (κβh², κγh, 1)` (`κ = 1`
    /// for Newmark).
    pub(crate) fn newmark_chain(&self, h: T) -> Chain<T> {
        AlphaRecursion::chain(&self.params.integrator, self.alpha(), h)
    }

    /// The generalized-α recursion's constants (`None`: Newmark's method; always for a scene
    /// without [`Scene::GENERALIZED_ALPHA`], whose code then has no generalized-α branch).
    #[inline(always)]
    pub(crate) fn alpha(&self) -> Option<&AlphaRecursion<T>> {
        if S::GENERALIZED_ALPHA {
            self.alpha.as_ref()
        } else {
            None
        }
    }

    /// The beam's accelerations at an event a fraction `tau` into a step from `start` whose
    /// trial end is `trial`, with a dissipative scheme (γ > ½): interpolated linearly between
    /// the step's ends, in place of the sub-step's (`mid`'s) own; the ball's spin keeps the
    /// sub-step's (its rolling at the crossing is what the event acts on).
    ///
    /// The scheme's damping keeps the stiff modes (end slopes, axial stretch) out of balance
    /// from step to step, and after an impulse the accelerations go on from before it
    /// ([`Self::after_impulse`]). A sub-step of length τh ≪ h undoes both: it solves the
    /// equations of motion at the event almost exactly, with the stiff modes' full
    /// acceleration (2.4·10⁵ s⁻² where the step's own were 4.7·10³, τ = 0.019). The rest of
    /// the step, `(1 − τ)h`, extrapolated it in its predictor by `(½ − β)(1 − τ)²h² a`
    /// (0.3 rad of end slope) and ended on another root of the step's equations, the beam's end
    /// folded by half a turn: kinetic energy 9 mJ → 49 J in one step, beam speeds of 10³ m/s,
    /// then a failed Newton solve (plastic stops at 5 mm and 4.13 Hz in every Newton mode and
    /// both precisions; the default stops at 46–54 mm, 6 of 30 runs of 300 s). Interpolating
    /// the spin too failed one sample of 10⁶ under ±5 g of random input (ball on the track).
    /// With the trapezoidal rule (γ = ½) nothing is damped, the ends' accelerations swing with
    /// the stiff modes and their interpolation misses the sub-step's: the sub-step's are kept
    /// (the energy through an elastic impact stays within 1 % of the impact energy;
    /// interpolated it drifted by 3 %).
    ///
    /// Kept out of line (events are rare): the split steps' frames do not grow with it.
    #[inline(never)]
    pub(crate) fn event_accel(
        &self,
        start: &State<T, D>,
        trial: &State<T, D>,
        tau: T,
        mid: &mut State<T, D>,
    ) {
        if self.params.integrator.gamma <= lit(0.5) {
            return;
        }
        lerp(&mut mid.a, &start.a, &trial.a, tau, Self::SPIN);
        lerp(
            &mut mid.pseudo_accel,
            &start.pseudo_accel,
            &trial.pseudo_accel,
            tau,
            Self::SPIN,
        );
    }

    /// `out` = `s` advanced by a sub-step of length `len` to the input `accel` at its end (to
    /// an event inside a step), or `s` itself when the sub-step is shorter than 10⁻⁶ of a step;
    /// its Newton iterations join `report`. Time and step count are the caller's.
    pub(crate) fn sub_step(
        &self,
        s: &State<T, D>,
        len: T,
        accel: T,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
        out: &mut State<T, D>,
    ) -> Result<(), Error> {
        if len > self.params.integrator.step * lit(1e-6) {
            let solved = self.newmark(s, len, accel, ws, self.params.integrator.newton, out)?;
            report.iterations += solved.iterations;
            report.increment = report.increment.max(solved.increment);
        } else {
            *out = *s;
        }
        Ok(())
    }

    /// One step of length `h` from `s` to the input `base_accel` at its end, into `out`
    /// (whose content on error is unspecified: every caller discards it); the ball's contact is
    /// kept (a ball on a stop stays projected on it). Time and step count are the caller's.
    /// The predictor, the known part of the generalized-α variable and the zero of the Newton
    /// chain are built in `out`'s own vectors: no state-sized temporaries in the frame.
    pub(crate) fn newmark(
        &self,
        s: &State<T, D>,
        h: T,
        base_accel: T,
        ws: &mut Workspace<T, D>,
        kind: NewtonKind,
        out: &mut State<T, D>,
    ) -> Result<Solved<T, D>, Error> {
        let i = &self.params.integrator;
        let half = lit::<T>(0.5);
        let pseudo = if self.alpha().is_some() {
            &s.pseudo_accel
        } else {
            &s.a
        };
        // Predictor: out.q, out.v.
        out.q = s.q;
        out.q.axpy(h, &s.v, T::one());
        out.q.axpy(h * h * (half - i.beta), pseudo, T::one());
        out.v = s.v;
        out.v.axpy(h * (T::one() - i.gamma), pseudo, T::one());
        // Generalized-α: the known part b of a_{n+1} (in out.pseudo_accel) enters the
        // predictor like a Newmark acceleration (module doc).
        out.pseudo_accel.fill(T::zero());
        if let Some(g) = self.alpha() {
            let known = &mut out.pseudo_accel;
            known.axpy(g.from_accel, &s.a, T::zero());
            known.axpy(g.from_pseudo, &s.pseudo_accel, T::one());
            out.q.axpy(i.beta * h * h, &out.pseudo_accel, T::one());
            out.v.axpy(i.gamma * h, &out.pseudo_accel, T::one());
        }
        let ch = self.newmark_chain(h);
        out.a.fill(T::zero());
        let p = Problem {
            q0: &out.q,
            v0: &out.v,
            a0: &out.a,
            ch,
            c_pos: ch.c_q,
            g_eff: self.effective_gravity(base_accel),
            contact: s.contact,
            plumb: false,
        };
        let solved = self.newton(&p, s.a, ws, kind, true)?;
        let a = &solved.x;
        out.a = *a;
        out.time = s.time;
        out.steps = s.steps;
        out.base_accel = base_accel;
        out.contact = s.contact;
        out.flight = s.flight;
        out.q.axpy(ch.c_q, a, T::one());
        out.v.axpy(ch.c_v, a, T::one());
        match self.alpha() {
            Some(g) => out.pseudo_accel.axpy(g.ratio, a, T::one()),
            None => out.pseudo_accel = *a,
        }
        match out.contact {
            crate::state::Contact::OnStop(side) => self.hold_on_stop(out, side),
            crate::state::Contact::InFlight if S::FLIGHT => {
                out.flight = self.fly(&s.flight, h, self.effective_gravity(base_accel));
            }
            _ => {}
        }
        Ok(solved)
    }
}

/// `dst[k] = (1 − τ) x₀[k] + τ x₁[k]` for the first `n` entries.
#[inline(never)]
fn lerp<T: Real, const D: usize>(
    dst: &mut SVector<T, D>,
    x0: &SVector<T, D>,
    x1: &SVector<T, D>,
    tau: T,
    n: usize,
) {
    let w0 = T::one() - tau;
    let (x0, x1) = (x0.as_slice().iter(), x1.as_slice().iter());
    for ((d, a), b) in dst.as_mut_slice().iter_mut().zip(x0).zip(x1).take(n) {
        *d = w0 * *a + tau * *b;
    }
}
