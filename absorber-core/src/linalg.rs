//! Dense LU with partial pivoting for the Newton systems (`D` ≤ a few dozen).
//!
//! nalgebra's `lu()` needs typenum bounds that a generic `const D` cannot satisfy; this one is
//! generic, allocation-free, and has no panic path: loop bounds are the compile-time `D`.

use crate::scalar::{is_positive, Real};
use nalgebra::{SMatrix, SVector};

/// An LU factorization with partial pivoting, `P A = L U` (unit lower L and U stored in one
/// matrix), to solve many right-hand sides with one factorization (modified Newton).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lu<T, const D: usize> {
    lu: SMatrix<T, D, D>,
    pivots: [usize; D],
}

/// Factors `A`; `None` if it is singular (a zero pivot) or not finite.
pub fn factor<T: Real, const D: usize>(mut a: SMatrix<T, D, D>) -> Option<Lu<T, D>> {
    let mut pivots = [0usize; D];
    for k in 0..D {
        // Pivot: largest |a[i,k]| for i ≥ k.
        let mut p = k;
        let mut best = a[(k, k)].abs();
        for i in (k + 1)..D {
            let v = a[(i, k)].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        if !is_positive(best) || !best.is_finite() {
            return None;
        }
        if let Some(slot) = pivots.get_mut(k) {
            *slot = p;
        }
        if p != k {
            swap_rows(&mut a, p, k);
        }
        let inv = T::one() / a[(k, k)];
        for i in (k + 1)..D {
            let f = a[(i, k)] * inv;
            a[(i, k)] = f;
            if f != T::zero() {
                for j in (k + 1)..D {
                    let akj = a[(k, j)];
                    a[(i, j)] -= f * akj;
                }
            }
        }
    }
    Some(Lu { lu: a, pivots })
}

impl<T: Real, const D: usize> Lu<T, D> {
    /// Solves `A x = b`; `None` if the result is not finite.
    pub fn solve(&self, mut b: SVector<T, D>) -> Option<SVector<T, D>> {
        for (k, p) in self.pivots.iter().enumerate() {
            if *p != k {
                let _ = b
                    .as_mut_slice()
                    .get_disjoint_mut([*p, k])
                    .map(|[x, y]| core::mem::swap(x, y));
            }
        }
        for k in 0..D {
            let mut s = b[k];
            for j in 0..k {
                s -= self.lu[(k, j)] * b[j];
            }
            b[k] = s;
        }
        for k in (0..D).rev() {
            let mut s = b[k];
            for j in (k + 1)..D {
                s -= self.lu[(k, j)] * b[j];
            }
            b[k] = s / self.lu[(k, k)];
        }
        if b.iter().all(|x| x.is_finite()) {
            Some(b)
        } else {
            None
        }
    }
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting; `None` if `A` is singular
/// (a zero pivot) or a value is not finite.
pub fn solve<T: Real, const D: usize>(
    a: SMatrix<T, D, D>,
    b: SVector<T, D>,
) -> Option<SVector<T, D>> {
    factor(a)?.solve(b)
}

/// Swaps rows `p` and `k` of a column-major matrix without an index assertion (nalgebra's
/// `swap_rows` asserts, and at opt-level "s" that panic path survives into firmware).
fn swap_rows<T: Real, const D: usize>(a: &mut SMatrix<T, D, D>, p: usize, k: usize) {
    for column in a.as_mut_slice().chunks_exact_mut(D) {
        if let Ok([x, y]) = column.get_disjoint_mut([p, k]) {
            core::mem::swap(x, y);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        let a = SMatrix::<f64, 3, 3>::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 4.0, -1.0, 3.0);
        let x = SVector::<f64, 3>::new(1.0, -2.0, 0.5);
        let got = solve(a, a * x).expect("regular");
        assert!((got - x).amax() < 1e-14);
        assert!(solve(
            SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 4.0),
            SVector::<f64, 2>::new(1.0, 1.0)
        )
        .is_none());
        // One factorization, several right-hand sides.
        let lu = factor(a).expect("regular");
        for y in [x, SVector::<f64, 3>::new(-4.0, 0.25, 9.0)] {
            assert!((lu.solve(a * y).expect("finite") - y).amax() < 1e-14);
        }
    }
}
