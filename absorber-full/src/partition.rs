//! Constraints and partitioning: the maximal coordinates' indices, the independent coordinates
//! of each contact mode (eq. 28), and the local kinematics — the dependent positions from
//! `C = 0`, the dependent velocities from `C_q q̇ = 0`, `B_d` and the dependent accelerations.

use super::dense::DenseLu;
use super::kin::{Cons, Mode, MC, NI, NW, PHI, RB1, RB2};
use super::{FullSolver, SceneKind};
use absorber_core::{Contact, Error};

/// Local kinematics at one configuration: positions and velocities of the 10 local
/// coordinates, the constraints, `B_d = ∂w_d/∂w_i`, and the LU of `C_d = ∂C/∂w_d` at the
/// configuration, shared by the velocity projection, `B_d` and the acceleration constraints.
#[derive(Clone)]
pub(super) struct Kin {
    pub(super) w: [f64; NW],
    pub(super) wd: [f64; NW],
    pub(super) cons: Cons,
    pub(super) lu_dep: DenseLu<MC>,
    pub(super) bd: [[f64; NI]; MC],
}

impl Kin {
    pub(super) fn new(m: usize) -> Self {
        Self {
            w: [0.0; NW],
            wd: [0.0; NW],
            cons: Cons::ZERO,
            lu_dep: DenseLu::new(m),
            bd: [[0.0; NI]; MC],
        }
    }
}

/// A constraint correction this small (scaled, as the 1e-13 convergence test) is rounding: the
/// dependent positions it would correct are a root of `C = 0` already (a few ulps of 1).
pub(super) const ROOT_TO_ROUNDING: f64 = 4.0 * f64::EPSILON;

impl FullSolver {
    pub(super) fn b0(&self) -> usize {
        4 * (self.n + 1)
    }

    /// z index of local coordinate j.
    pub(super) fn zloc(&self, j: usize) -> usize {
        if j < 4 {
            4 * self.n + j
        } else {
            self.b0() + j - 4
        }
    }

    pub(super) fn mode(&self, contact: Contact) -> Mode {
        match self.scene {
            SceneKind::BeamOnly => Mode::Beam,
            SceneKind::TipMass => Mode::Tip,
            SceneKind::LockedBall => Mode::Held(0.0),
            SceneKind::FreeBall | SceneKind::FreeBallNoStops => match contact {
                Contact::Off => Mode::Free,
                Contact::OnStop(side) => {
                    Mode::Held(side.sign::<f64>() * self.params.ball.stop_angle)
                }
                Contact::InFlight => Mode::Flying,
                // (the core's "rolling beyond the stops"; this solver tells it by the angle)
                Contact::Beyond => Mode::Free,
            },
        }
    }

    /// Number of independent coordinates: the free beam coordinates, φ of a ball on the track
    /// off the stops, φ and the centre `(R_b1, R_b2)` of a flying ball.
    pub(super) fn n_ind(&self, mode: Mode) -> usize {
        4 * self.n
            + match mode {
                Mode::Free => 1,
                Mode::Flying => 3,
                _ => 0,
            }
    }

    /// z index of independent coordinate `i` (beam, then φ, R_b1, R_b2 as the mode has them).
    pub(super) fn ind_to_z(&self, i: usize) -> usize {
        match i.checked_sub(4 * self.n) {
            None => 4 + i,
            Some(0) => self.zloc(PHI),
            Some(1) => self.zloc(RB1),
            _ => self.zloc(RB2),
        }
    }

    /// Scale of independent coordinate `i` for the convergence test: the beam length for
    /// positions (nodal positions, the flying ball's centre), 1 otherwise.
    pub(super) fn scale(&self, i: usize) -> f64 {
        match i.checked_sub(4 * self.n) {
            None if i % 4 < 2 => self.params.beam.length,
            Some(1) | Some(2) => self.params.beam.length,
            _ => 1.0,
        }
    }

    /// The ball may leave its track in this run: a free-ball scene and `ball.flight`.
    pub(super) fn flies(&self) -> bool {
        self.scene.free_ball() && self.params.ball.flight
    }

    pub(super) fn gather_ind(&self, z: &[f64], mode: Mode) -> Vec<f64> {
        let nb = 4 * self.n;
        let ni = self.n_ind(mode);
        let mut out = Vec::with_capacity(ni);
        out.extend_from_slice(&z[4..4 + nb]);
        out.extend((nb..ni).map(|i| z[self.ind_to_z(i)]));
        out
    }

    pub(super) fn local_of(&self, z: &[f64]) -> [f64; NW] {
        let mut w = [0.0; NW];
        for (j, wj) in w.iter_mut().enumerate() {
            if j < 4 || j - 4 < self.n_body {
                *wj = z[self.zloc(j)];
            }
        }
        w
    }

    pub(super) fn effective_gravity(&self, base_accel: f64) -> f64 {
        self.params.gravity + base_accel
    }

    /// Dependent local positions from `C = 0` (Newton–Raphson to rounding), dependent
    /// velocities from `C_q q̇ = 0`, and `B_d = −C_d⁻¹ C_i`.
    pub(super) fn local_kin(
        &self,
        mode: Mode,
        qi: &[f64],
        vi: &[f64],
        warm: &[f64; NW],
        theta_ref: f64,
    ) -> Result<Kin, Error> {
        let mut kin = Kin::new(mode.m());
        self.local_kin_into(mode, qi, vi, warm, theta_ref, None, true, &mut kin)?;
        Ok(kin)
    }

    /// [`FullSolver::local_kin`] without `B_d` (left zero; for callers that use only the
    /// positions, velocities, constraints and `C_d`'s LU: the multipliers, the new state's
    /// accelerations): the same values, 5 fewer solves.
    pub(super) fn local_kin_no_bd(
        &self,
        mode: Mode,
        qi: &[f64],
        vi: &[f64],
        warm: &[f64; NW],
        theta_ref: f64,
    ) -> Result<Kin, Error> {
        let mut kin = Kin::new(mode.m());
        self.local_kin_into(mode, qi, vi, warm, theta_ref, None, false, &mut kin)?;
        Ok(kin)
    }

    /// [`FullSolver::local_kin`] written into `out` (no copy of the result); `B_d` only
    /// `with_bd` (the finite differences of the Newton matrix pass a chord and need none:
    /// `local_residual` uses `C_d⁻ᵀ`). With `chord`, the iterations on `C = 0` use that LU of
    /// `C_d` (from a configuration close by: the finite differences) instead of refactoring at
    /// each iterate: the same root, to rounding, and `C_d` is factored once, at the converged
    /// positions.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn local_kin_into(
        &self,
        mode: Mode,
        qi: &[f64],
        vi: &[f64],
        warm: &[f64; NW],
        theta_ref: f64,
        chord: Option<&DenseLu<MC>>,
        with_bd: bool,
        out: &mut Kin,
    ) -> Result<(), Error> {
        let ind = mode.independent();
        let dep = mode.dependent();
        let m = mode.m();
        let Kin {
            w,
            wd,
            cons: c0,
            lu_dep,
            bd,
        } = out;
        *w = *warm;
        *wd = [0.0; NW];
        if with_bd {
            *bd = [[0.0; NI]; MC];
        }
        lu_dep.resize(m);
        for (k, &j) in ind.iter().enumerate() {
            w[j] = qi.get(k).copied().unwrap_or(0.0);
            wd[j] = vi.get(k).copied().unwrap_or(0.0);
        }
        // C_d: the gradients' dependent columns (m × m, leading part of the array).
        let build = |c: &Cons, lu: &mut DenseLu<MC>| {
            for (row, grad) in lu.a.iter_mut().zip(c.grad.iter()).take(m) {
                for (x, &j) in row.iter_mut().zip(dep.iter()) {
                    *x = grad[j];
                }
            }
            lu.factor()
        };
        // Newton–Raphson on C(w) = 0 for the dependent coordinates; the loop ends at the
        // converged w with its constraints and the LU of C_d there (the one shared below).
        let mut converged = m == 0;
        let mut last: f64 = 0.0;
        let mut iterations = 0;
        loop {
            self.bodies.values_into(w, mode, theta_ref, c0);
            if (converged || chord.is_none()) && !build(c0, lu_dep) {
                return Err(Error::Singular);
            }
            if converged {
                break;
            }
            if iterations == 60 {
                // The constraint solve for the dependent coordinates (tip pose, ball centre).
                return Err(Error::NoConvergence {
                    iterations: 60,
                    increment: last,
                });
            }
            let mut dx = [0.0; MC];
            for (d, v) in dx.iter_mut().zip(c0.val.iter()).take(m) {
                *d = -v;
            }
            chord.unwrap_or(lu_dep).solve(&mut dx);
            if !dx.iter().all(|v| v.is_finite()) {
                return Err(Error::Singular);
            }
            let mut inc: f64 = 0.0;
            for (d, &j) in dx.iter().zip(dep.iter()) {
                inc = inc.max(d.abs() / self.bodies.scale(j));
            }
            if !inc.is_finite() {
                return Err(Error::NonFiniteState);
            }
            if chord.is_none() && inc <= ROOT_TO_ROUNDING {
                // w is a root to rounding, and the values, gradients and LU in hand are its
                // own: stop here rather than apply the correction and evaluate once more.
                break;
            }
            for (d, &j) in dx.iter().zip(dep.iter()) {
                w[j] += d;
            }
            converged = inc <= 1e-13;
            last = inc;
            iterations += 1;
        }
        if m > 0 {
            let mut rhs = [0.0; MC];
            for (x, grad) in rhs.iter_mut().zip(c0.grad.iter()).take(m) {
                *x = -ind.iter().map(|&j| grad[j] * wd[j]).sum::<f64>();
            }
            lu_dep.solve(&mut rhs);
            if !rhs.iter().all(|v| v.is_finite()) {
                return Err(Error::Singular);
            }
            for (x, &j) in rhs.iter().zip(dep.iter()) {
                wd[j] = *x;
            }
            for (k, &jk) in ind.iter().enumerate().filter(|_| with_bd) {
                let mut col = [0.0; MC];
                for (x, grad) in col.iter_mut().zip(c0.grad.iter()).take(m) {
                    *x = -grad[jk];
                }
                lu_dep.solve(&mut col);
                if !col.iter().all(|v| v.is_finite()) {
                    return Err(Error::Singular);
                }
                for (row, x) in bd.iter_mut().zip(col.iter()).take(m) {
                    row[k] = *x;
                }
            }
        }
        // The constraints with the velocities: values and gradients are those at rest.
        c0.quad = self.bodies.quad(w, wd, mode);
        Ok(())
    }

    /// Dependent local accelerations from the acceleration constraints `C_q q̈ = Q_d`.
    pub(super) fn local_accel(
        &self,
        kin: &Kin,
        mode: Mode,
        ai: &[f64],
    ) -> Result<[f64; NW], Error> {
        let ind = mode.independent();
        let dep = mode.dependent();
        let m = mode.m();
        let mut wdd = [0.0; NW];
        for (k, &j) in ind.iter().enumerate() {
            wdd[j] = ai.get(k).copied().unwrap_or(0.0);
        }
        if m > 0 {
            let mut x = [0.0; MC];
            let rows = kin.cons.quad.iter().zip(kin.cons.grad.iter());
            for (xr, (quad, grad)) in x.iter_mut().zip(rows).take(m) {
                *xr = -quad - ind.iter().map(|&j| grad[j] * wdd[j]).sum::<f64>();
            }
            kin.lu_dep.solve(&mut x);
            if !x.iter().all(|v| v.is_finite()) {
                return Err(Error::Singular);
            }
            for (r, &j) in dep.iter().enumerate() {
                wdd[j] = x[r];
            }
        }
        Ok(wdd)
    }
}
