//! Statics and modes: the static equilibrium by load stepping, the start at rest from it, and
//! the mass and stiffness linearized about it with the natural frequencies.

use super::kin::{Mode, PHI};
use super::{FullSolver, Work};
use absorber_core::shared::Chain;
use absorber_core::shared::{END_BEYOND_STOP, START_BEYOND_STOP};
use absorber_core::{Contact, Error};
use nalgebra::DMatrix;

impl FullSolver {
    /// Static equilibrium under gravity by adaptive load stepping (the core's schedule: load
    /// steps of at most g/4, halved on failure down to g/1024, doubled after a success); a free
    /// ball is pinned plumb ([`Mode::Plumb`]) during the solve. Sets the state to it.
    pub fn solve_static(&mut self) -> Result<u32, Error> {
        const QUARTER: f64 = 0.25;
        const SMALLEST: f64 = 1.0 / 1024.0;
        let mode = match self.mode(Contact::Off) {
            Mode::Free => Mode::Plumb,
            m => m,
        };
        let ni = self.n_ind(mode);
        let z = vec![0.0; ni];
        let ch = Chain {
            c_q: 1.0,
            c_v: 0.0,
            c_m: 0.0,
        };
        let mut x = z.clone();
        let mut warm = self.local_of(&self.state.q);
        let (mut done, mut step) = (0.0, QUARTER);
        let mut iterations = 0;
        while done < 1.0 {
            let target = f64::min(done + step, 1.0);
            let g = self.params.gravity * target;
            let mut trial = warm;
            match self.newton(
                &z,
                &z,
                &z,
                x.clone(),
                &ch,
                1.0,
                g,
                mode,
                &mut trial,
                0.0,
                true,
            ) {
                Ok(s) => {
                    x = s.x;
                    warm = trial;
                    iterations += s.iterations;
                    done = target;
                    step = f64::min(2.0 * step, QUARTER);
                }
                Err(e) => {
                    step *= 0.5;
                    if step < SMALLEST {
                        return Err(e);
                    }
                }
            }
        }
        let mut seed = self.state.clone();
        for (j, w) in warm.iter().enumerate().skip(4).take(self.n_body) {
            seed.q[self.zloc(j)] = *w;
        }
        let st = self.complete(&x, &z, &z, mode, &seed, 0.0, 0.0, Contact::Off)?;
        self.equilibrium = st.clone();
        self.eq_heights = self.heights(&st);
        self.state = st;
        Ok(iterations)
    }

    /// Restarts at t = 0 from the static equilibrium at rest, ball at `ball.initial_angle`, with
    /// the core's start acceleration `a₀ = a(q₀, u) − a(q_eq, 0)`: the equilibrium's own (its
    /// static solve's residual through the mass matrix) left out (docs/model.md, "The start from
    /// rest").
    pub fn restart(&mut self, base_accel: f64) -> Result<(), Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        let (s, a) = self.start(base_accel, self.params.ball.initial_angle)?;
        let (_, a_eq) = self.start(0.0, 0.0)?;
        let a: Vec<f64> = a.iter().zip(&a_eq).map(|(x, y)| x - y).collect();
        self.state = self.with_accel(&s, &a)?;
        Ok(())
    }

    /// The start from the static equilibrium at rest with the ball turned by `angle`, input
    /// `base_accel`, and its consistent (independent) acceleration.
    fn start(&self, base_accel: f64, angle: f64) -> Result<(super::FullState, Vec<f64>), Error> {
        let mut s = self.equilibrium.clone();
        s.base_accel = base_accel;
        s.contact = Contact::Off;
        let mode = self.mode(Contact::Off);
        if mode == Mode::Free {
            if self.scene.stops() && self.relative_angle(&s).abs() >= self.params.ball.stop_angle {
                return Err(END_BEYOND_STOP);
            }
            // Rotate the ball by the initial angle at fixed housing: by c₅, δφ = −(ρ/r_b) δθ.
            let phi = self.zloc(PHI);
            s.q[phi] -= angle * self.bodies.rho / self.bodies.rb;
            let qi = self.gather_ind(&s.q, mode);
            let vi = self.gather_ind(&s.v, mode);
            let ai = self.gather_ind(&s.a, mode);
            s = self.complete(&qi, &vi, &ai, mode, &s, 0.0, base_accel, Contact::Off)?;
            if self.scene.stops() && self.relative_angle(&s).abs() >= self.params.ball.stop_angle {
                return Err(START_BEYOND_STOP);
            }
        }
        let acc = self.consistent_acceleration(&s)?;
        Ok((s, acc.x))
    }

    /// At the start of a run: the ball's orbit rate θ̇ set to `rate` \[rad/s\] (the spin rate
    /// `φ̇ = −(ρ/r_b) θ̇` at a housing at rest, by `c₅`) with the consistent acceleration; no
    /// effect without a rolling free ball (the core's `set_configuration` route).
    pub fn set_ball_rate(&mut self, rate: f64) -> Result<(), Error> {
        if self.mode(self.state.contact) != Mode::Free {
            return Ok(());
        }
        let mut s = self.state.clone();
        s.v[self.zloc(PHI)] = -rate * self.bodies.rho / self.bodies.rb;
        let mode = Mode::Free;
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        s = self.complete(&qi, &vi, &ai, mode, &s, s.time, s.base_accel, s.contact)?;
        let acc = self.consistent_acceleration(&s)?;
        self.state = self.with_accel(&s, &acc.x)?;
        Ok(())
    }

    /// Mass and stiffness reduced to the independent coordinates, linearized about the static
    /// equilibrium (symmetrized): the derivatives of the reduced residual.
    pub fn linearized(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), Error> {
        let s = &self.equilibrium;
        let mode = self.mode(Contact::Off);
        let qi = self.gather_ind(&s.q, mode);
        let z = vec![0.0; qi.len()];
        let g = self.params.gravity;
        let mut warm = self.local_of(&s.q);
        let mut guard = self.work.borrow_mut();
        let Work { mass, reduced, .. } = &mut *guard;
        let lu = self.reduced_lu(reduced, qi.len())?;
        let mut derivative = |ch: Chain<f64>| {
            self.evaluate(
                mass,
                Some((&mut *lu, &ch)),
                &qi,
                &z,
                &z,
                g,
                mode,
                &mut warm,
                s.theta_ref,
            )
            .map(|_| lu.to_dense())
        };
        let m = derivative(Chain {
            c_q: 0.0,
            c_v: 0.0,
            c_m: 1.0,
        })?;
        let k = derivative(Chain {
            c_q: 1.0,
            c_v: 0.0,
            c_m: 0.0,
        })?;
        Ok(((&m + m.transpose()) * 0.5, (&k + k.transpose()) * 0.5))
    }

    /// Natural frequencies about the static equilibrium, ascending \[Hz\].
    pub fn frequencies(&self) -> Result<Vec<f64>, Error> {
        let (m, k) = self.linearized()?;
        let l = m.cholesky().ok_or(Error::Singular)?.l();
        let x = l.solve_lower_triangular(&k).ok_or(Error::Singular)?;
        let a = l
            .solve_lower_triangular(&x.transpose())
            .ok_or(Error::Singular)?;
        let a = (&a + a.transpose()) * 0.5;
        let mut ev: Vec<f64> = a
            .symmetric_eigenvalues()
            .iter()
            .map(|l| l.max(0.0).sqrt() / (2.0 * core::f64::consts::PI))
            .collect();
        ev.sort_by(|a, b| a.total_cmp(b));
        Ok(ev)
    }
}
