//! Natural frequencies of small vibration about the static equilibrium.
//!
//! Linearizing `M(q) q̈ + f(q, q̇) = 0` at rest about the equilibrium gives `M δq̈ + K δq = 0`
//! with `K = ∂r/∂q` (elastic, geometric and gravity-load stiffness of the tip and ball). Both are
//! symmetric there (the forces derive from a potential). With `M = L Lᵀ` the frequencies are
//! `√λ / 2π` for the eigenvalues λ of `L⁻¹ K L⁻ᵀ`, found by cyclic Jacobi rotations (no heap,
//! any size).

use crate::error::Error;
use crate::model::Model;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::Contact;
use crate::step::scheme::Chain;
use nalgebra::{SMatrix, SVector};

/// Eigenvalues of a symmetric matrix by cyclic Jacobi, ascending.
pub fn symmetric_eigenvalues<T: Real, const D: usize>(mut a: SMatrix<T, D, D>) -> SVector<T, D> {
    let eps = T::default_epsilon();
    for _sweep in 0..60 {
        let mut off = T::zero();
        let mut diag = T::zero();
        for i in 0..D {
            for j in 0..D {
                if i != j {
                    off += a[(i, j)] * a[(i, j)];
                } else {
                    diag += a[(i, i)] * a[(i, i)];
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
                let t = theta.signum() / (theta.abs() + (theta * theta + T::one()).sqrt());
                let t = if theta == T::zero() { T::one() } else { t };
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
            }
        }
    }
    let mut ev = a.diagonal();
    // Insertion sort (D is small).
    for i in 1..D {
        let mut j = i;
        while j > 0 && ev[j - 1] > ev[j] {
            ev.swap_rows(j - 1, j);
            j -= 1;
        }
    }
    ev
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
    /// Mass and stiffness matrices linearized about the static equilibrium (symmetrized).
    pub fn linearized(&self) -> (SMatrix<T, D, D>, SMatrix<T, D, D>) {
        let z = SVector::<T, D>::zeros();
        let g = self.sys.params.gravity;
        let zero = T::zero();
        let (_, m, _) = self.sys.assemble(
            &self.sys.equilibrium,
            &z,
            &z,
            g,
            &Chain {
                c_q: zero,
                c_v: zero,
                c_m: T::one(),
            },
            Contact::Off,
            false,
        );
        let (_, k, _) = self.sys.assemble(
            &self.sys.equilibrium,
            &z,
            &z,
            g,
            &Chain {
                c_q: T::one(),
                c_v: zero,
                c_m: zero,
            },
            Contact::Off,
            false,
        );
        let half = lit::<T>(0.5);
        ((m + m.transpose()) * half, (k + k.transpose()) * half)
    }

    /// Natural frequencies about the static equilibrium, ascending \[Hz\].
    ///
    /// When `K` is positive definite (a stable equilibrium) the eigenvalues are taken from
    /// `L_K⁻¹ M L_K⁻ᵀ` (`K = L_K L_Kᵀ`), whose largest eigenvalues 1/ω² are the lowest modes:
    /// their relative accuracy is then that of the scalar, whatever the spread to the axial
    /// modes (10¹⁰ and more in ω²). Otherwise (zero gravity, an unstable state) the direct form
    /// is used, which resolves the low modes only to about ε·ω²_max.
    pub fn natural_frequencies(&self) -> Result<SVector<T, D>, Error> {
        let (m, k) = self.linearized();
        let omega2 = match Self::inverse_form(&m, &k) {
            Some(ev) => ev,
            None => {
                let l = m.cholesky().ok_or(Error::Singular)?.l();
                let x = l.solve_lower_triangular(&k).ok_or(Error::Singular)?;
                let a = l
                    .solve_lower_triangular(&x.transpose())
                    .ok_or(Error::Singular)?;
                symmetric_eigenvalues((a + a.transpose()) * lit::<T>(0.5))
            }
        };
        Ok(omega2.map(|l| l.max(T::zero()).sqrt() / T::two_pi()))
    }

    /// ω² from the inverse problem, ascending, if K is positive definite.
    fn inverse_form(m: &SMatrix<T, D, D>, k: &SMatrix<T, D, D>) -> Option<SVector<T, D>> {
        let l = k.cholesky()?.l();
        let x = l.solve_lower_triangular(m)?;
        let a = l.solve_lower_triangular(&x.transpose())?;
        let mu = symmetric_eigenvalues((a + a.transpose()) * lit::<T>(0.5));
        if mu.iter().any(|v| !is_positive(*v)) {
            return None;
        }
        // μ ascending ⇒ ω² = 1/μ descending: reverse.
        let mut out = SVector::<T, D>::zeros();
        for (o, v) in out.iter_mut().zip(mu.iter().rev()) {
            *o = T::one() / *v;
        }
        Some(out)
    }
}
