//! The filter's covariance in U-D factors, `P = U D Uᵀ` (U unit upper triangular, D
//! diagonal): Bierman's scalar measurement update and Thornton's modified weighted
//! Gram–Schmidt time update (Bierman 1977, *Factorization Methods for Discrete Sequential
//! Estimation*), with the small products the filter reads the factors through. Private to the
//! estimator.

use crate::scalar::{is_positive, Real};
use crate::step::linalg::dot;
use nalgebra::{SMatrix, SVector};

/// `hᵀ U D Uᵀ h`.
pub(super) fn quadratic<T: Real, const X: usize>(
    u: &SMatrix<T, X, X>,
    d: &SVector<T, X>,
    h: &SVector<T, X>,
) -> T {
    quadratic_f(&u.tr_mul(h), d)
}

/// `Σ_j f_j² d_j` for `f = Uᵀ h` given.
pub(super) fn quadratic_f<T: Real, const X: usize>(f: &SVector<T, X>, d: &SVector<T, X>) -> T {
    f.iter()
        .zip(d.iter())
        .fold(T::zero(), |acc, (fi, di)| acc + *fi * *fi * *di)
}

/// Row `k` of `u` (`Uᵀ e_k`, the same numbers `u.tr_mul` gives for the unit vector: one
/// nonzero product per entry), read through its storage; zero if `k` is out of range.
pub(super) fn row_of<T: Real, const X: usize>(u: &SMatrix<T, X, X>, k: usize) -> SVector<T, X> {
    let mut f = SVector::<T, X>::zeros();
    for (fj, col) in f.iter_mut().zip(u.as_slice().chunks_exact(X)) {
        *fj = col.get(k).copied().unwrap_or(T::zero());
    }
    f
}

/// Bierman's scalar measurement update of `P = U D Uᵀ` for the row `h` and noise variance
/// `r`: updates `U`, `D` in place and returns the gain `K = P hᵀ / s` and the innovation's
/// variance `s = h P hᵀ + r`; `None` (factors unchanged in meaning: the caller discards them)
/// if `s` is not positive and finite.
#[cfg(test)]
pub(super) fn bierman<T: Real, const X: usize>(
    u: &mut SMatrix<T, X, X>,
    d: &mut SVector<T, X>,
    h: &SVector<T, X>,
    r: T,
) -> Option<(SVector<T, X>, T)> {
    let f = u.tr_mul(h);
    bierman_f(u, d, f, r)
}

/// [`bierman`] with `f = Uᵀ h` given.
pub(super) fn bierman_f<T: Real, const X: usize>(
    u: &mut SMatrix<T, X, X>,
    d: &mut SVector<T, X>,
    f: SVector<T, X>,
    r: T,
) -> Option<(SVector<T, X>, T)> {
    let g = f.component_mul(d);
    let mut b = g;
    let mut alpha = r;
    for j in 0..X {
        // A zero entry of `f = Uᵀ h` leaves `α`, `d_j`, column `j` of `U` and `b` as they are
        // (exactly): skipped. Rows of unit vectors (the load's mean) and of sensors that see
        // only some coordinates have many.
        if f[j] == T::zero() {
            continue;
        }
        let prev = alpha;
        alpha += f[j] * g[j];
        if !is_positive(alpha) || !alpha.is_finite() {
            return None;
        }
        d[j] *= prev / alpha;
        let lambda = -f[j] / prev;
        for i in 0..j {
            let uij = u[(i, j)];
            u[(i, j)] = uij + b[i] * lambda;
            b[i] += uij * g[j];
        }
    }
    if !is_positive(alpha) || !alpha.is_finite() {
        return None;
    }
    Some((b / alpha, alpha))
}

/// Thornton's modified weighted Gram–Schmidt time update: `U D Uᵀ = W₁ D₁ W₁ᵀ + W₂ Q W₂ᵀ`
/// (rows of `W = [W₁ W₂]` orthogonalized from the last up, in the weights `diag(D₁, Q)`).
/// `W₁`, `W₂` are given by rows, of which the first `n1` and `n2` columns count (columns of
/// zero weight add nothing and are left out); they are overwritten. The columns beyond `n1`
/// and `n2` must be zero.
///
/// Each step's sums and updates run over fixed windows of the rows ([`thornton_step`]): the
/// window of `W₁` covers the pivot row's nonzero entries (from its first nonzero, the load's
/// and the biases' rows of F U start at the load's column, and the rows below only remove
/// such rows, to `n1`), that of `W₂` its first `n2` columns. The entries the window adds
/// beyond those are exact zeros of the pivot row, so every sum takes the same nonzero terms in
/// the same order as over the used entries alone, with fewer loop instructions.
#[allow(clippy::too_many_arguments)]
pub(super) fn thornton<T: Real, const X: usize, const Q: usize>(
    w1: &mut [[T; X]; X],
    d1: &[T; X],
    n1: usize,
    w2: &mut [[T; Q]; X],
    q: &[T; Q],
    n2: usize,
    u: &mut SMatrix<T, X, X>,
    d: &mut SVector<T, X>,
) {
    u.as_mut_slice().fill(T::zero());
    for j in (0..X).rev() {
        let Some(wj1) = w1.get(j) else {
            continue;
        };
        let wj1 = wj1.get(..n1).unwrap_or(wj1);
        let s1 = wj1
            .iter()
            .position(|x| *x != T::zero())
            .unwrap_or(wj1.len());
        let len = wj1.len() - s1;
        // The narrowest window that holds the used entries (`len` from `s1`).
        let narrow = len <= 4 && X >= 4;
        let wide2 = n2 > 4 || Q < 4;
        let dj = match (narrow, wide2) {
            (true, false) => thornton_step::<T, X, Q, 4, 4>(w1, d1, s1, w2, q, j, u),
            (true, true) => thornton_step::<T, X, Q, 4, Q>(w1, d1, s1, w2, q, j, u),
            (false, false) => thornton_step::<T, X, Q, X, 4>(w1, d1, s1, w2, q, j, u),
            (false, true) => thornton_step::<T, X, Q, X, Q>(w1, d1, s1, w2, q, j, u),
        };
        if let Some(x) = d.get_mut(j) {
            *x = if is_positive(dj) { dj } else { T::zero() };
        }
    }
}

/// Step `j` of [`thornton`] over a window of `A` columns of `W₁` (from `s1`, moved left to fit
/// in the row; the entries left of `s1` are the pivot row's leading zeros) and the first `B`
/// of `W₂`: `D_j = Σ_k w_jk² weight_k`, then for every row above `U_ij = (w_i · v_j) / D_j`
/// and `w_i −= U_ij w_j` (`v_j` the weighted pivot row). Returns `D_j`; nothing changes but
/// `U_jj = 1` if it is not positive.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn thornton_step<T: Real, const X: usize, const Q: usize, const A: usize, const B: usize>(
    w1: &mut [[T; X]; X],
    d1: &[T; X],
    s1: usize,
    w2: &mut [[T; Q]; X],
    q: &[T; Q],
    j: usize,
    u: &mut SMatrix<T, X, X>,
) -> T {
    let a = s1.min(X.saturating_sub(A));
    let (up1, rest1) = w1.split_at_mut(j);
    let (up2, rest2) = w2.split_at_mut(j);
    let (Some(wj1), Some(wj2), Some(d1)) = (
        rest1
            .first()
            .and_then(|r| r.get(a..))
            .and_then(|r| r.first_chunk::<A>()),
        rest2.first().and_then(|r| r.first_chunk::<B>()),
        d1.get(a..).and_then(|r| r.first_chunk::<A>()),
    ) else {
        return T::zero();
    };
    let Some(q) = q.first_chunk::<B>() else {
        return T::zero();
    };
    // The weighted row `w_jk weight_k`.
    let mut v1 = [T::zero(); A];
    for ((v, w), x) in v1.iter_mut().zip(wj1.iter()).zip(d1.iter()) {
        *v = *w * *x;
    }
    let mut v2 = [T::zero(); B];
    for ((v, w), x) in v2.iter_mut().zip(wj2.iter()).zip(q.iter()) {
        *v = *w * *x;
    }
    let dj = dot(wj1, &v1) + dot(wj2, &v2);
    if let Some(x) = u.get_mut((j, j)) {
        *x = T::one();
    }
    if !is_positive(dj) {
        return dj;
    }
    for (i, (wi1, wi2)) in up1.iter_mut().zip(up2.iter_mut()).enumerate() {
        let (Some(x1), Some(x2)) = (
            wi1.get_mut(a..).and_then(|r| r.first_chunk_mut::<A>()),
            wi2.first_chunk_mut::<B>(),
        ) else {
            continue;
        };
        let uij = (dot(x1, &v1) + dot(x2, &v2)) / dj;
        if let Some(x) = u.get_mut((i, j)) {
            *x = uij;
        }
        let c = -uij;
        for (x, y) in x1.iter_mut().zip(wj1.iter()) {
            *x += c * *y;
        }
        for (x, y) in x2.iter_mut().zip(wj2.iter()) {
            *x += c * *y;
        }
    }
    dj
}

/// Column `j` of `m`, owned, read through its storage (a column view's arithmetic reaches a
/// panicking allocation path; this does not). Zero if `j` is out of range.
pub(super) fn column<T: Real, const R: usize, const C: usize>(
    m: &SMatrix<T, R, C>,
    j: usize,
) -> SVector<T, R> {
    let mut v = SVector::<T, R>::zeros();
    if let Some(c) = m.as_slice().chunks_exact(R).nth(j) {
        for (x, y) in v.iter_mut().zip(c.iter()) {
            *x = *y;
        }
    }
    v
}

/// Sets column `j` of `m` to `v` through its storage (nothing if `j` is out of range).
pub(super) fn set_column<T: Real, const R: usize, const C: usize>(
    m: &mut SMatrix<T, R, C>,
    j: usize,
    v: &SVector<T, R>,
) {
    if let Some(c) = m.as_mut_slice().chunks_exact_mut(R).nth(j) {
        for (x, y) in c.iter_mut().zip(v.iter()) {
            *x = *y;
        }
    }
}
