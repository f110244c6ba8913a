//! The time update: the modal directions of the step, the covariance propagated through them
//! (Thornton), and the ball's direction.

use super::{Ekf, NOISE};
use crate::error::Error;
use crate::estimator::sensors::KINDS;
use crate::estimator::ud::{column, set_column, thornton};
use crate::model::Model;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::{BallKind, Scene};
use crate::state::StepReport;
use crate::step::ancf::TangentBlocks;
use crate::step::scheme::Chain;
use crate::step::system::Problem;
use crate::step::tip;
use nalgebra::{SMatrix, SVector};

impl<T: Real, S: Scene, const N: usize, const D: usize, const M: usize, const X: usize>
    Ekf<T, S, N, D, M, X>
{
    /// The directions of the filter's subspace through the last step: `δx` for each modal
    /// position and velocity error of the predictor and for the load, from the Newton matrix
    /// (factored again at the step's end if the step ended with other factors: an event) and
    /// `R_q`, `R_v` assembled at the step's end. Returns the root element's axial tangent
    /// blocks of the `R_q` assembly (the stress row's, [`Ekf::measurement_rows`]).
    pub(super) fn directions(
        &mut self,
        model: &mut Model<T, S, N, D>,
    ) -> Result<TangentBlocks<T>, Error> {
        let s = *model.state();
        let g_eff = model.sys.effective_gravity(s.base_accel);
        let rec = self.rec;
        if !model.work.has_factors(rec.c_q, s.contact) {
            // An event step ended with another matrix (a sub-step's, or another contact's):
            // factor the step's own at its end.
            let p = Problem {
                q0: &s.q,
                v0: &s.v,
                a0: &s.a,
                ch: Chain {
                    c_q: rec.c_q,
                    c_v: rec.c_v,
                    c_m: T::one(),
                },
                c_pos: rec.c_q,
                g_eff,
                contact: s.contact,
                plumb: false,
            };
            let mut r = SVector::<T, D>::zeros();
            model
                .sys
                .refresh_at(&p, [&s.q, &s.v, &s.a], &mut model.work, &mut r)?;
        }
        let unit = |c_q: T, c_v: T| Chain {
            c_q,
            c_v,
            c_m: T::zero(),
        };
        // R_q Φ_i → directions 0..M; R_v Φ_i → M..2M (right-hand sides, negated); the load
        // moves the predictor's positions by the residual static mode Ψ (module doc), so its
        // right-hand side is e_tip − R_q Ψ.
        let mut y: SVector<T, D>;
        let mut load_rhs = SVector::<T, D>::zeros();
        let mut root = [[[T::zero(); 3]; 4]; 4];
        for (block, ch) in [
            (0usize, unit(T::one(), T::zero())),
            (M, unit(T::zero(), T::one())),
        ] {
            let qva = [&s.q, &s.v, &s.a];
            if block == 0 {
                if let Some(t) = model
                    .sys
                    .jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch)
                {
                    root = t;
                }
            } else if let Some(damping) = &self.damping {
                // R_v: the beam's constant part, then the tip rows at the step's end.
                self.scratch = *damping;
                model
                    .sys
                    .add_tip_jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch);
            } else {
                model
                    .sys
                    .jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch);
            }
            // The products on the band (the same sums as the dense product, in the same order,
            // without the terms outside the band, which are exact zeros).
            // R_q Ψ in the same pass as R_q Φ.
            let mut rphi = SMatrix::<T, D, M>::zeros();
            if block == 0 {
                self.scratch.mul_mat_vec(
                    &self.consistent,
                    &self.residual,
                    &mut rphi,
                    &mut load_rhs,
                );
            } else {
                self.scratch.mul_mat(&self.consistent, &mut rphi);
            }
            for i in 0..M {
                y = -column(&rphi, i);
                model.work.solve(&mut y)?;
                set_column(&mut self.dx, block + i, &y);
            }
        }
        // The load: R_P = −e_tip, so J δx = e_tip − R_q Ψ.
        y = -load_rhs;
        if let Some(x) = y.get_mut(Self::TIP) {
            *x += T::one();
        }
        model.work.solve(&mut y)?;
        set_column(&mut self.dx, 2 * M, &y);
        // Only the directions' columns (the others are zero and unused).
        for c in 0..=2 * M {
            let xi = self.basis.projection * column(&self.dx, c);
            set_column(&mut self.xi, c, &xi);
        }
        // The stiff completion for the next step: the out-of-span part of the positions the
        // step gives each direction, `(I − ΦΠ)(b + c_q δx)` (the implicit step moves the stiff
        // coordinates onto their quasi-static response: `c_q J⁻¹ R_q ≈ I` on them, a
        // contraction toward the completion consistent with the current state).
        for i in 0..M {
            let b = column(&self.consistent, i) + column(&self.dx, i) * self.rec.c_q;
            let out = b - self.basis.shapes * (self.basis.projection * b);
            set_column(
                &mut self.consistent,
                i,
                &(column(&self.basis.shapes, i) + out),
            );
        }
        let b = self.residual + column(&self.dx, 2 * M) * self.rec.c_q;
        self.residual = b - self.basis.shapes * (self.basis.projection * b);
        Ok(root)
    }

    /// The time update `P ← F P Fᵀ + Q` on the factors (Thornton), with the events'
    /// treatment of the ball folded into `F` and `Q`.
    pub(super) fn propagate(
        &mut self,
        model: &Model<T, S, N, D>,
        ball_free: bool,
        ball_event: bool,
        report: &StepReport<T>,
    ) {
        let rec = self.rec;
        let (ld, off) = (Self::LD, Self::OFF);
        // F in physical coordinates, then scaled: F̃ = T⁻¹ F T.
        let mut f = SMatrix::<T, X, X>::zeros();
        for c in 0..=2 * M {
            let col = if c < 2 * M { c } else { ld };
            for i in 0..M {
                let xi = self.xi[(i, c)];
                f[(i, col)] = rec.qx * xi;
                f[(M + i, col)] = rec.vx * xi;
                if rec.blocks == 3 {
                    f[(2 * M + i, col)] = rec.bx * xi;
                }
            }
        }
        for i in 0..M {
            f[(i, i)] += T::one();
            f[(i, M + i)] += rec.h;
            f[(M + i, M + i)] += T::one();
            if rec.blocks == 3 {
                f[(i, 2 * M + i)] = rec.qb;
                f[(M + i, 2 * M + i)] = rec.vb;
                f[(2 * M + i, 2 * M + i)] = rec.bb;
            }
        }
        for (i, row) in self.load_map.iter().enumerate() {
            for (j, a) in row.iter().enumerate() {
                f[(ld + i, ld + j)] = *a;
            }
        }
        let mu = self.mean_weight;
        f[(ld + 2, ld)] = mu * self.load_map[0][0];
        f[(ld + 2, ld + 1)] = mu * self.load_map[0][1];
        f[(ld + 2, ld + 2)] = T::one() - mu;
        for k in 0..KINDS {
            f[(off + k, off + k)] = T::one();
        }
        // Only F's nonzero entries (a zero stays zero; its sign is never read: F's entries
        // enter below only as nonzero factors).
        for (j, col) in f.as_mut_slice().chunks_exact_mut(X).enumerate() {
            let sj = self.scale[j];
            for (x, si) in col.iter_mut().zip(self.scale.iter()) {
                if *x != T::zero() {
                    *x *= sj / *si;
                }
            }
        }
        // Noise columns (scaled) and their variances: the first `n` columns of `w2`, the others
        // zero (Thornton's windows read them).
        self.w2 = [[T::zero(); NOISE]; X];
        let mut q = [T::zero(); NOISE];
        let mut n = 0;
        let mut push = |col: SVector<T, X>, var: T, w2: &mut [[T; NOISE]; X]| {
            if let (Some(qn), true) = (q.get_mut(n), is_positive(var)) {
                *qn = var;
                for (row, c) in w2.iter_mut().zip(col.iter()) {
                    if let Some(x) = row.get_mut(n) {
                        *x = *c;
                    }
                }
                n += 1;
            }
        };
        let unit = |k: usize| {
            let mut e = SVector::<T, X>::zeros();
            e[k] = T::one();
            e
        };
        for c in 0..2 {
            let mut col = SVector::<T, X>::zeros();
            col[ld] = self.load_noise[0][c];
            col[ld + 1] = self.load_noise[1][c] / self.scale[ld + 1];
            col[ld + 2] = mu * self.load_noise[0][c];
            push(col, T::one(), &mut self.w2);
        }
        let half = lit::<T>(0.5);
        for i in 0..M {
            let mut col = SVector::<T, X>::zeros();
            col[i] = half * rec.h * rec.h / self.scale[i];
            col[M + i] = rec.h / self.scale[M + i];
            push(
                col,
                self.config.modal_noise * self.config.modal_noise,
                &mut self.w2,
            );
        }
        for (k, s) in self.config.sensors.slots.iter().enumerate() {
            if let Some(s) = s {
                push(unit(off + k), s.bias_walk * s.bias_walk, &mut self.w2);
            }
        }
        if matches!(S::BALL, BallKind::Free) {
            if let Some((a, u)) = self.ball_direction(model) {
                let (uq, uv) = (embed::<T, M, X>(&u, 0), embed::<T, M, X>(&u, M));
                // Rank-one maps I − c u aᵀ on the block of rows `at..at + M` (the positions' or
                // the velocities'), applied to F (scaled: ũ = T⁻¹u, ã = T a): `u` and `a` are
                // zero elsewhere, so only that block's entries of `Fᵀã` have nonzero terms
                // (summed in row order, as the full product sums them) and only its rows move.
                let scale = &self.scale;
                let mut map = |at: usize, c: T| {
                    let s = scale.as_slice().get(at..at + M).unwrap_or(&[]);
                    for col in f.as_mut_slice().chunks_exact_mut(X) {
                        let Some(col) = col.get_mut(at..at + M) else {
                            continue;
                        };
                        // (Fᵀã)_j over the block, then f −= ũ (Fᵀã)_j c.
                        let mut bj = T::zero();
                        for ((x, ak), sk) in col.iter().zip(a.iter()).zip(s.iter()) {
                            bj += *ak * *sk * *x;
                        }
                        for ((x, uk), sk) in col.iter_mut().zip(u.iter()).zip(s.iter()) {
                            *x -= *uk / *sk * bj * c;
                        }
                    }
                };
                if let Some(imp) = &report.impact {
                    // The relative rate's error reverses like the rate: v ← v − (1 + e) u (a·v),
                    // and the rebound speed's uncertainty is added.
                    let e = model.params().ball.restitution;
                    map(M, T::one() + e);
                    let sd = self.config.impact_sd * imp.relative_speed.abs();
                    push(uv.component_div(&self.scale), sd * sd, &mut self.w2);
                }
                if !ball_free {
                    // Held or flying: the relative angle is the model's; its error leaves the
                    // subspace.
                    map(0, T::one());
                    map(M, T::one());
                } else if ball_event && report.impact.is_none() {
                    // Landed or released: the relative angle and rate restart with their prior.
                    map(0, T::one());
                    map(M, T::one());
                    let [sa, sr] = self.config.ball_restart_sd;
                    push(uq.component_div(&self.scale), sa * sa, &mut self.w2);
                    push(uv.component_div(&self.scale), sr * sr, &mut self.w2);
                }
            }
        }
        // W₁ = F U by rows, only its columns of positive weight (the others add nothing to
        // U D Uᵀ): U's rows restricted to those columns, then each row of F U as the sum of
        // the rows of U that F's nonzero entries of that row pick, in order (F is sparse: 2M + 1
        // entries in a modal row, at most three in the load's and one in a bias's), over whole
        // rows (U is unit upper triangular: a row's entries left of its diagonal, and the
        // columns beyond the kept ones, are exact zeros and change no sum).
        let mut d1 = [T::zero(); X];
        let mut ur = [[T::zero(); X]; X];
        let mut n1 = 0;
        let columns = self.ud_u.as_slice().chunks_exact(X);
        for (uk, dk) in columns.zip(self.ud_d.iter()) {
            if !is_positive(*dk) {
                continue;
            }
            let Some(slot) = d1.get_mut(n1) else { break };
            *slot = *dk;
            for (row, x) in ur.iter_mut().zip(uk.iter()) {
                if let Some(y) = row.get_mut(n1) {
                    *y = *x;
                }
            }
            n1 += 1;
        }
        // F's nonzero entries of row i lie in columns `lo..=hi`: the modal rows' in the modal
        // columns and the load's, the load's block's in that block, a bias's on the diagonal
        // (the entries outside are never written, and the ball's maps move only modal rows,
        // by multiples of modal rows). F is read in place, column-major.
        let fs = f.as_slice();
        for (i, row) in self.w1.iter_mut().enumerate() {
            let (lo, hi) = if i < ld {
                (0, ld)
            } else if i < off {
                (ld, off - 1)
            } else {
                (i, i)
            };
            let mut acc = [T::zero(); X];
            for k in lo..=hi {
                let (Some(fik), Some(uk)) = (fs.get(k * X + i), ur.get(k)) else {
                    continue;
                };
                if *fik != T::zero() {
                    for (x, y) in acc.iter_mut().zip(uk.iter()) {
                        *x += *fik * *y;
                    }
                }
            }
            *row = acc;
        }
        thornton(
            &mut self.w1,
            &d1,
            n1,
            &mut self.w2,
            &q,
            n,
            &mut self.ud_u,
            &mut self.ud_d,
        );
    }

    /// The ball's relative angle as a direction of the modal coordinates, `a_i = ∇α·φ_i`,
    /// and the smallest modal change with `a·u = 1`, `u = a / |a|²`.
    fn ball_direction(&self, model: &Model<T, S, N, D>) -> Option<(SVector<T, M>, SVector<T, M>)> {
        let s = model.state();
        let x = Model::<T, S, N, D>::local(&s.q, &s.v, &s.a);
        let grad = tip::gap_gradient(&model.sys.inertia, &x);
        let end = 4 * N - 4;
        let mut a = SVector::<T, M>::zeros();
        for (i, ai) in a.iter_mut().enumerate() {
            *ai = grad
                .iter()
                .enumerate()
                .map(|(k, g)| *g * self.consistent[(end + k, i)])
                .fold(T::zero(), |u, v| u + v);
        }
        let aa = a.dot(&a);
        is_positive(aa).then(|| (a, a / aa))
    }
}

/// An `M`-vector placed at `offset` of an `X`-vector.
fn embed<T: Real, const M: usize, const X: usize>(
    v: &SVector<T, M>,
    offset: usize,
) -> SVector<T, X> {
    let mut e = SVector::<T, X>::zeros();
    for (i, x) in v.iter().enumerate() {
        if let Some(y) = e.get_mut(offset + i) {
            *y = *x;
        }
    }
    e
}
