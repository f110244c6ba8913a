//! Newton–Raphson on the independent accelerations (the core's iteration, criterion, matrix
//! reuse and damping), and the full state completed from the independent coordinates.

use super::kin::{Mode, NW, PHI};
use super::{zeros, FullSolver, FullState, Work};
use absorber_core::shared::Chain;
use absorber_core::shared::{DAMPING_TRIALS, MAX_STEP};
use absorber_core::shared::{SETTLE, SLOW};
use absorber_core::{Contact, Error};

pub(super) struct Solved {
    pub(super) x: Vec<f64>,
    pub(super) iterations: u32,
    pub(super) increment: f64,
}

impl FullSolver {
    /// Newton–Raphson on `x` with `q = q₀ + c_q x`, `v = v₀ + c_v x`, `a = a₀ + c_m x` (the
    /// core's iteration, criterion and matrix reuse): the Newton matrix is built and factored
    /// at the first iterate; later iterations evaluate the residual only and reuse the
    /// factors while the scaled correction at least halves (`‖Δx‖ ≤ ½ ‖Δx_prev‖`); a
    /// correction that does not is discarded (the iteration still counts) and the matrix is
    /// rebuilt and refactored at the same iterate.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn newton(
        &self,
        q0: &[f64],
        v0: &[f64],
        a0: &[f64],
        mut x: Vec<f64>,
        ch: &Chain<f64>,
        c_pos: f64,
        g_eff: f64,
        mode: Mode,
        warm: &mut [f64; NW],
        theta_ref: f64,
        full: bool,
    ) -> Result<Solved, Error> {
        let max = self.params.integrator.max_iterations;
        let tol = self.params.integrator.tolerance;
        let ni = x.len();
        let loc0 = 4 * self.n - 4;
        let held_spin_row = if self.scene.free_ball() {
            mode.dependent().iter().position(|&j| j == PHI)
        } else {
            None
        };
        let mut guard = self.work.borrow_mut();
        let Work {
            mass,
            reduced,
            iterate,
            ..
        } = &mut *guard;
        let lu = self.reduced_lu(reduced, ni)?;
        let mut factored = false;
        let mut refresh = false;
        let mut previous = 0.0;
        let mut increment = 0.0;
        // (Kept scratch, every entry overwritten before use.)
        let [q, v, a, dx] = iterate;
        for buf in [&mut *q, &mut *v, &mut *a, &mut *dx] {
            buf.resize(ni, 0.0);
        }
        for it in 1..=max {
            for (((qi, vi), ai), ((xi, q0i), (v0i, a0i))) in q
                .iter_mut()
                .zip(v.iter_mut())
                .zip(a.iter_mut())
                .zip(x.iter().zip(q0.iter()).zip(v0.iter().zip(a0.iter())))
            {
                *qi = q0i + ch.c_q * xi;
                *vi = v0i + ch.c_v * xi;
                *ai = a0i + ch.c_m * xi;
            }
            let fresh = !factored || refresh || full;
            let jac = if fresh { Some((&mut *lu, ch)) } else { None };
            let ev = self.evaluate(mass, jac, q, v, a, g_eff, mode, warm, theta_ref)?;
            if !ev.r.iter().all(|z| z.is_finite()) {
                return Err(Error::NonFiniteState);
            }
            if fresh {
                if !lu.factor() {
                    return Err(Error::Singular);
                }
                factored = true;
                refresh = false;
            }
            dx.iter_mut().zip(ev.r.iter()).for_each(|(d, r)| *d = -r);
            if !lu.solve(dx) {
                return Err(Error::Singular);
            }
            // Scaled norm; with the ball held on a stop the core keeps φ as an unknown tied to
            // ψ, so its increment counts too.
            let norm = |d: &[f64]| {
                let mut n: f64 = 0.0;
                for (i, di) in d.iter().enumerate() {
                    n = n.max((di * c_pos).abs() / self.scale(i));
                }
                if let Some(row) = held_spin_row {
                    let dphi: f64 = (0..4).map(|k| ev.kin.bd[row][k] * d[loc0 + k]).sum();
                    n = n.max((dphi * c_pos).abs());
                }
                n
            };
            increment = norm(dx);
            if !fresh && increment > 0.5 * previous {
                // The kept matrix does not contract: rebuild it at this iterate.
                refresh = true;
                continue;
            }
            // Taken; a slowly contracting kept matrix is rebuilt at the next iteration (the
            // core's `SLOW`).
            if !fresh && increment > SLOW * previous {
                refresh = true;
            }
            // The core's damping (`Model::damping`): natural monotonicity test with the same
            // factors, λ = 1, ½, … down to the trust-region cap MAX_STEP/‖dx‖.
            let mut lambda = 1.0;
            if increment > MAX_STEP {
                let floor = MAX_STEP / increment;
                let mut accepted = false;
                for _ in 0..DAMPING_TRIALS {
                    if lambda <= floor {
                        break;
                    }
                    let xt: Vec<f64> = (0..ni).map(|i| x[i] + lambda * dx[i]).collect();
                    let qt: Vec<f64> = (0..ni).map(|i| q0[i] + ch.c_q * xt[i]).collect();
                    let vt: Vec<f64> = (0..ni).map(|i| v0[i] + ch.c_v * xt[i]).collect();
                    let at: Vec<f64> = (0..ni).map(|i| a0[i] + ch.c_m * xt[i]).collect();
                    let mut w = *warm;
                    if let Ok(et) =
                        self.evaluate(mass, None, &qt, &vt, &at, g_eff, mode, &mut w, theta_ref)
                    {
                        let mut bar: Vec<f64> = et.r.iter().map(|r| -r).collect();
                        if et.r.iter().all(|z| z.is_finite())
                            && lu.solve(&mut bar)
                            && norm(&bar) <= (1.0 - 0.25 * lambda) * increment
                        {
                            accepted = true;
                            break;
                        }
                    }
                    lambda *= 0.5;
                }
                if !accepted {
                    lambda = floor;
                }
            }
            x.iter_mut()
                .zip(dx.iter())
                .for_each(|(xi, d)| *xi += d * lambda);
            // The dependent positions' first-order prediction at the new iterate,
            // `w_d + B_d δq_i` with `δq_i = c_q λ Δx`: the next constraint solve (this step's
            // next evaluation, or the completed state) starts within O(δq²) of its root.
            let nl = mode.independent().len();
            for (row, &j) in mode.dependent().iter().enumerate() {
                let dq: f64 = (0..nl)
                    .map(|k| ev.kin.bd[row][k] * dx[loc0 + k])
                    .sum::<f64>();
                warm[j] += dq * ch.c_q * lambda;
            }
            // The core's settled test: a reused matrix's remaining error θ/(1−θ)‖dx‖ must be
            // below SETTLE·tol too (absorber-core/src/step/newton.rs).
            let settled = fresh || it == 1 || {
                let theta = increment / previous;
                theta * increment <= (1.0 - theta) * (tol * SETTLE).max(8.0 * f64::EPSILON)
            };
            if increment <= tol && settled {
                return Ok(Solved {
                    x,
                    iterations: it,
                    increment,
                });
            }
            previous = increment;
        }
        Err(Error::NoConvergence {
            iterations: max,
            increment,
        })
    }

    /// The full state from independent positions, velocities and accelerations.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn complete(
        &self,
        qi: &[f64],
        vi: &[f64],
        ai: &[f64],
        mode: Mode,
        prev: &FullState,
        time: f64,
        base_accel: f64,
        contact: Contact,
    ) -> Result<FullState, Error> {
        let warm = self.local_of(&prev.q);
        self.complete_warm(qi, vi, ai, mode, prev, &warm, time, base_accel, contact)
    }

    /// [`FullSolver::complete`] with the dependent positions' iteration started at `warm`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn complete_warm(
        &self,
        qi: &[f64],
        vi: &[f64],
        ai: &[f64],
        mode: Mode,
        prev: &FullState,
        warm: &[f64; NW],
        time: f64,
        base_accel: f64,
        contact: Contact,
    ) -> Result<FullState, Error> {
        let loc0 = 4 * self.n - 4;
        let kin = self.local_kin_no_bd(mode, &qi[loc0..], &vi[loc0..], warm, prev.theta_ref)?;
        let wdd = self.local_accel(&kin, mode, &ai[loc0..])?;
        let mut s = FullState {
            q: zeros(self.nz),
            v: zeros(self.nz),
            a: zeros(self.nz),
            pa: Vec::new(),
            time,
            base_accel,
            contact,
            theta_ref: prev.theta_ref,
            lifted: prev.lifted,
        };
        let nb = 4 * self.n;
        s.q[4..4 + nb].copy_from_slice(&qi[..nb]);
        s.v[4..4 + nb].copy_from_slice(&vi[..nb]);
        s.a[4..4 + nb].copy_from_slice(&ai[..nb]);
        for (j, acc) in wdd.iter().enumerate().skip(4).take(self.n_body) {
            let z = self.zloc(j);
            s.q[z] = kin.w[j];
            s.v[z] = kin.wd[j];
            s.a[z] = *acc;
        }
        if self.scene.has_ball() {
            s.theta_ref = self.bodies.orbit(&kin.w, &kin.wd, prev.theta_ref).0;
        }
        let finite = |x: &[f64]| x.iter().all(|z| z.is_finite());
        if !(finite(&s.q) && finite(&s.v) && finite(&s.a)) {
            return Err(Error::NonFiniteState);
        }
        // The generalized-α recursion restarts here; `newmark` sets its independent entries.
        s.pa = s.a.clone();
        Ok(s)
    }

    pub(super) fn with_accel(&self, s: &FullState, ai: &[f64]) -> Result<FullState, Error> {
        let mode = self.mode(s.contact);
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        self.complete(&qi, &vi, ai, mode, s, s.time, s.base_accel, s.contact)
    }

    pub(super) fn consistent_acceleration(&self, s: &FullState) -> Result<Solved, Error> {
        let mode = self.mode(s.contact);
        let ch = Chain {
            c_q: 0.0,
            c_v: 0.0,
            c_m: 1.0,
        };
        let i = &self.params.integrator;
        let c_pos = i.beta * i.step * i.step;
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        let z = vec![0.0; qi.len()];
        let mut warm = self.local_of(&s.q);
        self.newton(
            &qi,
            &vi,
            &z,
            ai,
            &ch,
            c_pos,
            self.effective_gravity(s.base_accel),
            mode,
            &mut warm,
            s.theta_ref,
            true,
        )
    }
}
