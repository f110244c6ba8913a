//! The tip body and ball's block: their reduced residual on the local independent coordinates
//! and its Newton block, exact from the core's tip rows in dual numbers or by central
//! differences (the static solve's plumb ball, and the reference of the tests).

use super::kin::{Mode, MC, NI, NW, RB2, RT2};
use super::partition::Kin;
use super::FullSolver;
use absorber_core::shared::tip::{self, BallMode, LocalState, TipInertia, D5, LOCAL};
use absorber_core::shared::Chain;
use absorber_core::BallKind;
use absorber_core::Error;

impl FullSolver {
    /// Reduced residual of the tip body and ball on the local independent coordinates:
    /// `B_localᵀ (M ẅ − Q_e)` over the local coordinates.
    pub(super) fn local_residual(
        &self,
        kin: &Kin,
        mode: Mode,
        ai: &[f64],
        g_eff: f64,
    ) -> Result<[f64; NI], Error> {
        let wdd = self.local_accel(kin, mode, ai)?;
        let (mt, mb) = self.bodies.weights;
        let mut gw = [0.0; NW];
        for j in 0..NW {
            gw[j] = self.bodies.mass[j] * wdd[j];
        }
        gw[RT2] += mt * g_eff;
        gw[RB2] += mb * g_eff;
        // r = gw_i + B_dᵀ gw_d with B_dᵀ gw_d = −C_iᵀ (C_d⁻ᵀ gw_d): one transposed solve
        // instead of B_d's columns (not built for these local kinematics).
        let m = mode.m();
        let mut t = [0.0; MC];
        for (x, &j) in t.iter_mut().zip(mode.dependent().iter()) {
            *x = gw[j];
        }
        if m > 0 {
            kin.lu_dep.solve_transposed(&mut t);
            if !t.iter().all(|v| v.is_finite()) {
                return Err(Error::Singular);
            }
        }
        let mut r = [0.0; NI];
        for (rk, &jk) in r.iter_mut().zip(mode.independent().iter()) {
            *rk = gw[jk]
                - kin
                    .cons
                    .grad
                    .iter()
                    .zip(t.iter())
                    .take(m)
                    .map(|(g, x)| g[jk] * x)
                    .sum::<f64>();
        }
        Ok(r)
    }

    /// The tip/ball block of the Newton matrix, `c_m ∂r/∂ä + c_v ∂r/∂ȧ + c_q ∂r/∂q` of the
    /// reduced local residual over the local independent coordinates (end node, then φ for a
    /// free ball), from the core's tip rows in dual numbers ([`absorber_core::shared::tip::residual`]).
    ///
    /// The reduced residual here, `Bᵀ M B δ`, equals `Bᵀ (M ẅ − Q)` with `ẅ = B x + γ` (the
    /// augmented system's solution satisfies `Bᵀ (M ẅ_aug − Q) = 0`), which are Lagrange's
    /// equations in the independent coordinates: the core's tip rows (docs/derivation.md §§2–5),
    /// the same function of the local state. Only the Newton matrix comes from the core; the
    /// residual, which alone fixes the solution, stays the one in maximal coordinates, and a
    /// test checks this block against central differences of that residual. `None` for the
    /// static solve's plumb ball (θ pinned to 0, not a core ball mode): differences there.
    pub(super) fn tip_block(
        &self,
        mode: Mode,
        ql: &[f64],
        vl: &[f64],
        al: &[f64],
        c: &Chain<f64>,
        g_eff: f64,
    ) -> Option<[[f64; LOCAL]; LOCAL]> {
        let (ball, bm, spin) = match mode {
            Mode::Beam | Mode::Plumb => return None,
            Mode::Tip => (BallKind::None, BallMode::Absent, false),
            Mode::Flying => (BallKind::None, BallMode::Flying, false),
            Mode::Free => (BallKind::Free, BallMode::Free, true),
            Mode::Held(lock) => (BallKind::Free, BallMode::Held(lock), false),
        };
        let inertia = TipInertia::new(&self.params, true, ball);
        let take = |src: &[f64]| {
            let mut d = [0.0; LOCAL];
            for (k, x) in d.iter_mut().enumerate().take(if spin { LOCAL } else { 4 }) {
                *x = src.get(k).copied().unwrap_or(0.0);
            }
            d
        };
        let x = LocalState {
            q: take(ql),
            v: take(vl),
            a: take(al),
        };
        let (rows, _) = tip::residual::<f64, D5<f64>>(&inertia, &x, c, g_eff, bm, false);
        Some(rows.map(|r| r.du))
    }

    /// The tip/ball block by central differences of the local residual
    /// ([`FullSolver::local_residual`]): the plumb ball of the static solve, and the reference
    /// that [`FullSolver::tip_block`] is tested against.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn tip_block_differences(
        &self,
        kin: &Kin,
        mode: Mode,
        ql: &[f64],
        vl: &[f64],
        al: &[f64],
        c: &Chain<f64>,
        g_eff: f64,
        theta_ref: f64,
    ) -> Result<[[f64; LOCAL]; LOCAL], Error> {
        let nl = mode.independent().len();
        let coupled = if mode == Mode::Flying { 4 } else { nl };
        let mut block = [[0.0; LOCAL]; LOCAL];
        let denom = c.c_q.abs() + c.c_v.abs() * 1e-2 + c.c_m.abs() * 1e-4;
        // (One scratch for all columns: every field is rewritten per solve.)
        let mut kp = Kin::new(mode.m());
        for k in 0..coupled {
            let s = if k < 2 { self.params.beam.length } else { 1.0 };
            let eps = 1e-6 * s / denom;
            let mut cols = [[0.0; NI]; 2];
            for (side, sign) in [(0usize, 1.0f64), (1, -1.0)] {
                let (mut q, mut v, mut a) = ([0.0; NI], [0.0; NI], [0.0; NI]);
                for (dst, src) in [(&mut q, ql), (&mut v, vl), (&mut a, al)] {
                    for (d, s) in dst.iter_mut().zip(src.iter()) {
                        *d = *s;
                    }
                }
                q[k] += sign * eps * c.c_q;
                v[k] += sign * eps * c.c_v;
                a[k] += sign * eps * c.c_m;
                // Start from the first-order prediction w_d + B_d δq_i, iterate with the
                // unperturbed C_d (a chord): one factorization, at the end.
                let mut pred = kin.w;
                let dq = q[k] - ql[k];
                for (row, &j) in mode.dependent().iter().enumerate() {
                    pred[j] += kin.bd[row][k] * dq;
                }
                self.local_kin_into(
                    mode,
                    &q[..nl],
                    &v[..nl],
                    &pred,
                    theta_ref,
                    Some(&kin.lu_dep),
                    false,
                    &mut kp,
                )?;
                cols[side] = self.local_residual(&kp, mode, &a[..nl], g_eff)?;
            }
            for (row, (p, m)) in cols[0].iter().zip(cols[1].iter()).enumerate().take(coupled) {
                block[row][k] = (p - m) / (2.0 * eps);
            }
        }
        Ok(block)
    }
}
