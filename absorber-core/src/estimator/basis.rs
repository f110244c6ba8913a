//! The filter's error subspace: the `M` lowest modes of the model linearized about its static
//! equilibrium.
//!
//! With the mass and stiffness matrices of [`crate::Model::linearized`] (`M δq̈ + K δq = 0`,
//! both symmetric there), the modes solve `K φ = ω² M φ`. They are found from the inverse form
//! `K = L Lᵀ`, `A = L⁻¹ M L⁻ᵀ`, `A y = μ y` with `μ = 1/ω²`, `φ = L⁻ᵀ y` (the largest μ are the
//! lowest modes, resolved to the scalar's relative precision whatever the spread to the stiff
//! axial modes), by cyclic Jacobi rotations with the eigenvectors accumulated (no heap; off the
//! step path). The modes are normalized to unit modal mass, `Φᵀ M Φ = I`, so that the
//! projection onto them is `Π = Φᵀ M` (`Π Φ = I`).
//!
//! For a free ball hanging plumb the lowest modes are the ball's pendulum mode and the beam's
//! bending modes with the ball moving in them: their span holds the ball's own coordinate and
//! the beam's lowest shapes, whatever the ball does later (the filter's linearization is the
//! step's own, at the current state; the basis only says where the errors live).

use crate::error::Error;
use crate::model::Model;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use nalgebra::{SMatrix, SVector};

/// The `M` lowest modes of a model with `D` unknowns about its static equilibrium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModalBasis<T, const D: usize, const M: usize> {
    /// Mode shapes as columns, unit modal mass (`Φᵀ M Φ = I`).
    pub shapes: SMatrix<T, D, M>,
    /// The projection `Π = Φᵀ M` onto the modal coordinates (`Π Φ = I`).
    pub projection: SMatrix<T, M, D>,
    /// Circular frequencies ω \[rad/s\], ascending.
    pub omega: [T; M],
    /// The residual static mode of a unit vertical tip force: the static deflection the
    /// truncated modes carry, `Ψ = K⁻¹ e − Σ φ_i φ_iᵀ e / ω_i²` (`Π Ψ = 0`) \[m/N\].
    pub residual: SVector<T, D>,
}

impl<T: Real, const D: usize, const M: usize> ModalBasis<T, D, M> {
    /// The lowest `M` modes of `model` about its static equilibrium. Errors: `M` is zero or
    /// larger than `D`, or the linearization is not positive definite (no stable equilibrium:
    /// zero gravity with a free ball, a beam that buckles).
    pub fn of<S: Scene, const N: usize>(model: &Model<T, S, N, D>) -> Result<Self, Error> {
        if M == 0 || M > D {
            return Err(Error::InvalidParameter {
                field: "estimator.modes",
                reason: "must lie in 1..=D",
            });
        }
        let (m, k) = model.linearized();
        let not_definite = Error::InvalidParameter {
            field: "estimator.modes",
            reason: "the model linearized about its static equilibrium is not positive definite",
        };
        let l = k.cholesky().ok_or(not_definite)?.l();
        let x = l.solve_lower_triangular(&m).ok_or(Error::Singular)?;
        let a = l
            .solve_lower_triangular(&x.transpose())
            .ok_or(Error::Singular)?;
        let (mu, y) = symmetric_eigen((a + a.transpose()) * lit::<T>(0.5));
        let lt = l.transpose();
        let mut shapes = SMatrix::<T, D, M>::zeros();
        let mut omega = [T::zero(); M];
        // Largest μ first: the lowest modes.
        let mut order: [usize; D] = core::array::from_fn(|i| i);
        order.sort_unstable_by(|&i, &j| {
            mu[j]
                .partial_cmp(&mu[i])
                .unwrap_or(core::cmp::Ordering::Equal)
        });
        for (c, (&src, w)) in order.iter().zip(omega.iter_mut()).enumerate() {
            let lam = mu[src];
            if !is_positive(lam) {
                return Err(not_definite);
            }
            let phi = lt
                .solve_upper_triangular(&y.column(src).into_owned())
                .ok_or(Error::Singular)?;
            // Unit modal mass, and a positive largest entry (a reproducible sign).
            let mass = (phi.transpose() * m * phi)[(0, 0)];
            if !is_positive(mass) {
                return Err(not_definite);
            }
            let big = phi
                .iter()
                .fold(T::zero(), |b, z| if z.abs() > b.abs() { *z } else { b });
            let sign = if big < T::zero() { -T::one() } else { T::one() };
            shapes.set_column(c, &(phi * (sign / mass.sqrt())));
            *w = (T::one() / lam).sqrt();
        }
        let projection = shapes.transpose() * m;
        // K⁻¹ e for the end node's vertical coordinate, minus its modal part.
        let mut e = SVector::<T, D>::zeros();
        if let Some(x) = e.get_mut(4 * N - 3) {
            *x = T::one();
        }
        let static_full = lt
            .solve_upper_triangular(&l.solve_lower_triangular(&e).ok_or(Error::Singular)?)
            .ok_or(Error::Singular)?;
        let mut residual = static_full;
        for (i, w) in omega.iter().enumerate() {
            let phi = shapes.column(i);
            residual -= phi * (phi.dot(&e) / (*w * *w));
        }
        Ok(Self {
            shapes,
            projection,
            omega,
            residual,
        })
    }

    /// Mode `i` as a vector (zero beyond `M`).
    pub fn shape(&self, i: usize) -> SVector<T, D> {
        if i < M {
            self.shapes.column(i).into_owned()
        } else {
            SVector::zeros()
        }
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric matrix by cyclic Jacobi rotations
/// (unsorted; `a = V diag(λ) Vᵀ`).
pub fn symmetric_eigen<T: Real, const D: usize>(
    mut a: SMatrix<T, D, D>,
) -> (SVector<T, D>, SMatrix<T, D, D>) {
    let mut v = SMatrix::<T, D, D>::identity();
    let eps = T::default_epsilon();
    for _sweep in 0..60 {
        let (mut off, mut diag) = (T::zero(), T::zero());
        for i in 0..D {
            for j in 0..D {
                let x = a[(i, j)] * a[(i, j)];
                if i == j {
                    diag += x;
                } else {
                    off += x;
                }
            }
        }
        if off <= eps * eps * diag {
            break;
        }
        for p in 0..D {
            for q in (p + 1)..D {
                let apq = a[(p, q)];
                if apq == T::zero() {
                    continue;
                }
                let theta = (a[(q, q)] - a[(p, p)]) / (lit::<T>(2.0) * apq);
                let t = if theta == T::zero() {
                    T::one()
                } else {
                    theta.signum() / (theta.abs() + (theta * theta + T::one()).sqrt())
                };
                let c = T::one() / (t * t + T::one()).sqrt();
                let s = t * c;
                for k in 0..D {
                    let (akp, akq) = (a[(k, p)], a[(k, q)]);
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..D {
                    let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                for k in 0..D {
                    let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
    }
    (a.diagonal(), v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FreeBallModel, LockedBallModel, Params};

    /// The modes' frequencies are the model's natural frequencies, the shapes are
    /// mass-orthonormal and solve `K φ = ω² M φ` (relative residual 1e-9).
    #[test]
    fn modal_basis_solves_the_eigenproblem() {
        let m = LockedBallModel::<f64, 3, 12>::at_rest(Params::default(), 0.0).expect("model");
        let b = ModalBasis::<f64, 12, 3>::of(&m).expect("basis");
        let f = m.natural_frequencies().expect("frequencies");
        let (mm, kk) = m.linearized();
        for i in 0..3 {
            let w = b.omega[i];
            assert!(
                (w / core::f64::consts::TAU / f[i] - 1.0).abs() < 1e-9,
                "{i}"
            );
            let phi = b.shape(i);
            let r = kk * phi - mm * phi * (w * w);
            assert!(r.amax() < 1e-9 * (kk * phi).amax(), "{i}: {r}");
        }
        let pi_phi = b.projection * b.shapes;
        assert!((pi_phi - SMatrix::<f64, 3, 3>::identity()).amax() < 1e-9);
        // The residual mode: M-orthogonal to the modes, and with them the static deflection
        // of a unit tip force.
        assert!((b.projection * b.residual).amax() < 1e-9 * b.residual.amax());
        let mut e = SVector::<f64, 12>::zeros();
        e[9] = 1.0;
        let u = kk.cholesky().expect("K").solve(&e);
        let mut modal = b.residual;
        for i in 0..3 {
            modal += b.shape(i) * (b.shape(i)[9] / (b.omega[i] * b.omega[i]));
        }
        assert!((modal - u).amax() < 1e-9 * u.amax());
        // The free ball: its pendulum mode comes first (2.36 Hz, README).
        let fm = FreeBallModel::<f64, 3, 13>::at_rest(Params::default(), 0.0).expect("model");
        let fb = ModalBasis::<f64, 13, 3>::of(&fm).expect("basis");
        let hz = fb.omega[0] / core::f64::consts::TAU;
        assert!((hz - 2.355).abs() < 0.01, "{hz}");
    }
}
