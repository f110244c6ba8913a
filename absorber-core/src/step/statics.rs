//! Static equilibrium under gravity, consistent accelerations, and the start of a run.

use crate::error::Error;
use crate::error::{END_BEYOND_STOP, START_BEYOND_STOP};
use crate::params::NewtonKind;
use crate::scalar::{lit, to_f64, Real};
use crate::scene::Scene;
use crate::state::{Contact, State};
use crate::step::newton::{Solved, Workspace};
use crate::step::scheme::Chain;
use crate::step::system::{Problem, System};
use nalgebra::SVector;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// Static equilibrium under gravity (zero base acceleration), a free ball hanging plumb
    /// below the beam end, by load stepping: gravity in steps of at most a quarter, halved after
    /// a failed solve (down to 1/1024), doubled again after a success. Returns the equilibrium
    /// and the Newton iterations used.
    pub(crate) fn solve_static(
        &self,
        ws: &mut Workspace<T, D>,
    ) -> Result<(SVector<T, D>, u32), Error> {
        let z = SVector::<T, D>::zeros();
        let ch = Chain {
            c_q: T::one(),
            c_v: T::zero(),
            c_m: T::zero(),
        };
        let (quarter, smallest) = (lit::<T>(0.25), lit::<T>(1.0 / 1024.0));
        let (mut q, mut done, mut step) = (z, T::zero(), quarter);
        let mut iterations = 0;
        // Full Newton: off the step path, and its quadratic convergence leaves the static
        // solution (the reference of every deflection) far below the tolerance.
        let kind = NewtonKind::Full;
        while done < T::one() {
            let target = (done + step).min(T::one());
            let p = Problem {
                q0: &z,
                v0: &z,
                a0: &z,
                ch,
                c_pos: T::one(),
                g_eff: self.params.gravity * target,
                contact: Contact::Off,
                plumb: true,
            };
            ws.begin_solve();
            match self.newton(&p, q, ws, kind, false) {
                Ok(s) => {
                    q = s.x;
                    iterations += s.iterations;
                    done = target;
                    step = (step + step).min(quarter);
                }
                Err(e) => {
                    step *= lit::<T>(0.5);
                    if step < smallest {
                        return Err(Self::static_failure(e, self.params.integrator.tolerance));
                    }
                }
            }
        }
        Ok((q, iterations))
    }

    /// The error of a static solve that failed at every load step: when Newton ended within a
    /// few hundred tolerances of convergence it stagnates at the rounding floor of the stiffness
    /// (condition ∝ N⁴: f32 stalls at 1.2e-4 with 64 elements), which is a tolerance this
    /// precision cannot meet, not a hard load step; with fewer than 10 iterations allowed, the
    /// budget is the cause.
    fn static_failure(e: Error, tolerance: T) -> Error {
        match e {
            // A budget of a few iterations cannot converge from the unloaded beam at all.
            Error::NoConvergence { iterations, .. } if iterations < 10 => Error::InvalidParameter {
                field: "integrator.max_iterations",
                reason: "is too few for the static equilibrium (Newton from the unloaded beam needs up to about 10; the default is 100)",
            },
            Error::NoConvergence { increment, .. } if increment < 300.0 * to_f64(tolerance) => {
                Error::InvalidParameter {
                    field: "integrator.tolerance",
                    reason: "is below the rounding floor of this precision with this many elements (the static solve stagnates): raise it, use fewer elements or f64",
                }
            }
            e => e,
        }
    }

    /// Solves `r(q, v, a) = 0` for the acceleration at fixed q, v (linear in a; with exact
    /// factors two iterations, the second confirming). Within a step it may reuse the step's
    /// factors ([`crate::step::newton`]).
    pub(crate) fn consistent_acceleration(
        &self,
        s: &State<T, D>,
        ws: &mut Workspace<T, D>,
        kind: NewtonKind,
    ) -> Result<Solved<T, D>, Error> {
        let i = &self.params.integrator;
        let zero = SVector::zeros();
        let p = Problem {
            q0: &s.q,
            v0: &s.v,
            a0: &zero,
            ch: Chain {
                c_q: T::zero(),
                c_v: T::zero(),
                c_m: T::one(),
            },
            c_pos: i.beta * i.step * i.step,
            g_eff: self.effective_gravity(s.base_accel),
            contact: s.contact,
            plumb: false,
        };
        self.newton(&p, s.a, ws, kind, false)
    }

    /// The state at time 0 at rest relative to the base in the configuration `q`, with the
    /// ball `initial_angle` from its position in `q` (free ball), input `base_accel`, and the
    /// consistent acceleration.
    ///
    /// With `initial_angle` (the start from the static equilibrium, `q` = [`Self::equilibrium`])
    /// the acceleration leaves out the equilibrium's own: `a₀ = a(q₀, u) − a(q_eq, 0)`, the
    /// latter solved here first (at `q`, at rest, without input or offset). The exact
    /// equilibrium does not accelerate; the computed one's residual is within the static
    /// solve's tolerance in position, but the stiff axial modes turn it into accelerations (up
    /// to 93 m/s² at N = 6 in `f32`) that the first step's predictor would turn into axial
    /// strain (`docs/model.md`, "The start from rest"). What is
    /// left is what the input and the ball's offset cause.
    pub(crate) fn start_state(
        &self,
        q: SVector<T, D>,
        v: SVector<T, D>,
        initial_angle: Option<T>,
        base_accel: T,
        ws: &mut Workspace<T, D>,
    ) -> Result<State<T, D>, Error> {
        let mut s = State {
            q,
            v,
            a: SVector::zeros(),
            pseudo_accel: SVector::zeros(),
            time: T::zero(),
            steps: 0,
            base_accel,
            contact: Contact::Off,
            flight: crate::state::Flight::zero(),
        };
        // What the start's acceleration leaves out: a(q, 0), the equilibrium's own (at rest,
        // without input or offset), at the start from the equilibrium; else nothing.
        let mut a_eq = SVector::<T, D>::zeros();
        if initial_angle.is_some() {
            s.base_accel = T::zero();
            ws.begin_solve();
            a_eq = self.consistent_acceleration(&s, ws, NewtonKind::Full)?.x;
            s.base_accel = base_accel;
        }
        if S::EXTRA_DOFS == 1 {
            let stop = self.params.ball.stop_angle;
            match initial_angle {
                Some(angle) => {
                    if S::STOPS && self.relative_angle(&s).abs() >= stop {
                        return Err(END_BEYOND_STOP);
                    }
                    // θ(0) = θ_eq + initial angle, i.e. φ decreases by ρ/r_b times the angle.
                    let k = self.inertia.orbit_per_spin;
                    if let Some(spin) = s.q.get_mut(Self::SPIN) {
                        *spin -= angle / k;
                    }
                    if S::STOPS && self.relative_angle(&s).abs() >= stop {
                        return Err(START_BEYOND_STOP);
                    }
                }
                None => {
                    if S::STOPS && self.relative_angle(&s).abs() >= stop {
                        return Err(Error::InvalidParameter {
                            field: "q",
                            reason: "puts the ball beyond a stop",
                        });
                    }
                }
            }
        }
        ws.begin_solve();
        s.a = self.consistent_acceleration(&s, ws, NewtonKind::Full)?.x;
        s.a -= a_eq;
        s.pseudo_accel = s.a;
        Ok(s)
    }
}
