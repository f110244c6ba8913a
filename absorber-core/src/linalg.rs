//! In-place LU of the Newton matrix: banded without pivoting, dense with partial pivoting as the
//! guarded fallback.
//!
//! **Structure.** Unknown `i` of node `n` couples only with the coordinates of the elements that
//! share node `n`, so `|i − j| ≤ 7` for every non-zero `J[i,j]`: the beam's two nodes of 4
//! coordinates, and the tip/ball rows (end node and spin, indices `4N−4 … 4N`) lie within the
//! same band. Gaussian elimination without row exchanges keeps that band ([`BAND`]), so the
//! factorization costs `O(D·BAND²)` instead of `O(D³)` and never writes outside the band.
//!
//! **Why no pivoting.** The Newmark matrix `c_m M + c_v C + c_q K` is dominated by the
//! consistent mass `M`, which is symmetric positive definite; the stiffness and the tip's
//! velocity terms enter scaled by `βh²` and `γh`. Elimination without pivoting is stable for it
//! as for any matrix close to an SPD one. It is not *assumed*: every pivot is checked against
//! the largest entry of its column below it ([`PIVOT_RATIO`]); if one is smaller, or not
//! finite, [`factor_banded`] gives up and the caller factors a fresh copy with
//! [`factor_pivoted`] (partial pivoting, full matrix). `docs/stability.md` records how often the
//! fallback ran over the stiff, extreme and `f32` cases (never, so far).
//!
//! Matrices are column-major `SMatrix` (nalgebra's layout), factored in place; the inner loops
//! run down contiguous columns through iterators, so no index can panic.

use crate::scalar::{is_positive, Real};
use nalgebra::{SMatrix, SVector};

/// Half-bandwidth of every Newton matrix of the model: `J[i,j] = 0` for `|i − j| > BAND`.
pub const BAND: usize = 7;

/// A pivot smaller than this fraction of the largest entry below it in its column makes the
/// banded elimination give up (the partial-pivoting fallback takes over). LAPACK's threshold
/// pivoting uses 0.1 for sparse LU; 1e-3 still bounds the growth per step by 1000.
pub const PIVOT_RATIO: f64 = 1e-3;

/// How a factored matrix was factored (what [`solve`] must undo).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pivoting<const D: usize> {
    /// Banded, no row exchanges.
    None,
    /// Dense, partial pivoting: `pivots[k]` is the row swapped with row `k` at step `k`.
    Rows([usize; D]),
}

/// Factors `a` in place, `a = L U` (unit lower `L` below the diagonal, `U` on and above), using
/// only the band. `false` if a pivot is not finite or smaller than [`PIVOT_RATIO`] times the
/// largest entry below it (then `a` is destroyed: rebuild it and use [`factor_pivoted`]).
pub fn factor_banded<T: Real, const D: usize>(a: &mut SMatrix<T, D, D>, ratio: T) -> bool {
    let data = a.as_mut_slice();
    for k in 0..D {
        let end = (k + BAND + 1).min(D);
        let (left, right) = data.split_at_mut((k + 1) * D);
        let Some(col_k) = left.get_mut(k * D..(k + 1) * D) else {
            return false;
        };
        let Some((pivot, below)) = col_k.get_mut(k..end).and_then(|c| c.split_first_mut()) else {
            return false;
        };
        let p = *pivot;
        let mut largest = T::zero();
        for l in below.iter() {
            largest = largest.max(l.abs());
        }
        if !p.is_finite() || !is_positive(p.abs()) || p.abs() < ratio * largest {
            return false;
        }
        let inv = T::one() / p;
        for l in below.iter_mut() {
            *l *= inv;
        }
        // Columns k+1 .. end: col_j[k+1..end] -= l · U[k, j].
        for col_j in right.chunks_exact_mut(D).take(end - k - 1) {
            let Some(ukj) = col_j.get(k).copied() else {
                return false;
            };
            if ukj == T::zero() {
                continue;
            }
            if let Some(dst) = col_j.get_mut(k + 1..end) {
                for (d, l) in dst.iter_mut().zip(below.iter()) {
                    *d -= *l * ukj;
                }
            }
        }
    }
    true
}

/// Factors `a` in place with partial pivoting over the full matrix, `P a = L U`; `None` if it
/// is singular (a zero pivot) or not finite.
pub fn factor_pivoted<T: Real, const D: usize>(a: &mut SMatrix<T, D, D>) -> Option<[usize; D]> {
    let mut pivots = [0usize; D];
    for k in 0..D {
        let mut p = k;
        let mut best = T::zero();
        for i in k..D {
            let v = a.get((i, k)).map_or(T::zero(), |x| x.abs());
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
            for column in a.as_mut_slice().chunks_exact_mut(D) {
                if let Ok([x, y]) = column.get_disjoint_mut([p, k]) {
                    core::mem::swap(x, y);
                }
            }
        }
        let inv = T::one() / a.get((k, k)).copied().unwrap_or(T::one());
        let data = a.as_mut_slice();
        let (left, right) = data.split_at_mut((k + 1) * D);
        let below = left.get_mut(k * D + k + 1..(k + 1) * D)?;
        for l in below.iter_mut() {
            *l *= inv;
        }
        for col_j in right.chunks_exact_mut(D) {
            let ukj = col_j.get(k).copied().unwrap_or(T::zero());
            if ukj == T::zero() {
                continue;
            }
            if let Some(dst) = col_j.get_mut(k + 1..D) {
                for (d, l) in dst.iter_mut().zip(below.iter()) {
                    *d -= *l * ukj;
                }
            }
        }
    }
    Some(pivots)
}

/// Solves `A x = b` in place (`b` becomes `x`) from the factors of [`factor_banded`] or
/// [`factor_pivoted`]; `false` if the result is not finite.
pub fn solve<T: Real, const D: usize>(
    lu: &SMatrix<T, D, D>,
    pivoting: &Pivoting<D>,
    b: &mut SVector<T, D>,
) -> bool {
    let band = match pivoting {
        Pivoting::None => BAND,
        Pivoting::Rows(pivots) => {
            for (k, p) in pivots.iter().enumerate() {
                if *p != k {
                    let _ = b
                        .as_mut_slice()
                        .get_disjoint_mut([*p, k])
                        .map(|[x, y]| core::mem::swap(x, y));
                }
            }
            D
        }
    };
    let x = b.as_mut_slice();
    // Forward: L y = b, column by column.
    for (k, col) in lu.as_slice().chunks_exact(D).enumerate() {
        let end = (k + band + 1).min(D);
        let Some(xk) = x.get(k).copied() else {
            return false;
        };
        if xk == T::zero() {
            continue;
        }
        if let (Some(l), Some(dst)) = (col.get(k + 1..end), x.get_mut(k + 1..end)) {
            for (d, lik) in dst.iter_mut().zip(l.iter()) {
                *d -= *lik * xk;
            }
        }
    }
    // Backward: U x = y, column by column from the last.
    for (k, col) in lu.as_slice().chunks_exact(D).enumerate().rev() {
        let start = k.saturating_sub(band);
        let (Some(ukk), Some(xk)) = (col.get(k), x.get_mut(k)) else {
            return false;
        };
        *xk /= *ukk;
        let xk = *xk;
        if let (Some(u), Some(dst)) = (col.get(start..k), x.get_mut(start..k)) {
            for (d, uik) in dst.iter_mut().zip(u.iter()) {
                *d -= *uik * xk;
            }
        }
    }
    x.iter().all(|v| v.is_finite())
}

/// Solves `A x = b` with a copy of `A` (off the step path: modes, tests); `None` if singular.
pub fn solve_dense<T: Real, const D: usize>(
    mut a: SMatrix<T, D, D>,
    mut b: SVector<T, D>,
) -> Option<SVector<T, D>> {
    let pivots = factor_pivoted(&mut a)?;
    solve(&a, &Pivoting::Rows(pivots), &mut b).then_some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        let a = SMatrix::<f64, 3, 3>::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 4.0, -1.0, 3.0);
        let x = SVector::<f64, 3>::new(1.0, -2.0, 0.5);
        let got = solve_dense(a, a * x).expect("regular");
        assert!((got - x).amax() < 1e-14);
        assert!(solve_dense(
            SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 4.0),
            SVector::<f64, 2>::new(1.0, 1.0)
        )
        .is_none());
        // The banded elimination refuses the zero pivot.
        let mut b = a;
        assert!(!factor_banded(&mut b, PIVOT_RATIO));
    }

    /// A banded, diagonally dominant 20×20 matrix (half-bandwidth 7, non-symmetric): the banded
    /// factors solve it as the pivoted dense LU does, to rounding.
    #[test]
    fn banded_factors_equal_dense_ones_on_a_band_matrix() {
        let mut a = SMatrix::<f64, 20, 20>::zeros();
        for i in 0..20usize {
            for j in 0..20usize {
                if i.abs_diff(j) <= BAND {
                    a[(i, j)] = ((i * 7 + j * 3) as f64 * 0.37).sin();
                }
            }
            a[(i, i)] += 12.0;
        }
        let x = SVector::<f64, 20>::from_fn(|i, _| (i as f64 * 0.9).cos());
        let mut f = a;
        assert!(factor_banded(&mut f, PIVOT_RATIO));
        let mut b = a * x;
        assert!(solve(&f, &Pivoting::None, &mut b));
        assert!((b - x).amax() < 1e-13, "{}", (b - x).amax());
        let dense = solve_dense(a, a * x).expect("regular");
        assert!((dense - b).amax() < 1e-13);
    }
}
