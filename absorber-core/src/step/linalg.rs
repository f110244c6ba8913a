//! In-place LU of the Newton matrix: banded without pivoting, dense with partial pivoting as the
//! guarded fallback.
//!
//! **Structure.** Unknown `i` of node `n` couples only with the coordinates of the elements that
//! share node `n`, so `|i − j| ≤ 7` for every non-zero `J[i,j]`: the beam's two nodes of 4
//! coordinates, and the tip/ball rows (end node and spin, indices `4N−4 … 4N`) lie within the
//! same band. Gaussian elimination without row exchanges keeps that band ([`BAND`]), so the
//! factorization costs `O(D·BAND²)` instead of `O(D³)` and never writes outside the band.
//!
//! Finer, the matrix lives in the **node envelope**: `J[i,j] = 0` unless the nodes `i / 4` and
//! `j / 4` are equal or neighbours (the ball's spin, index `4N`, couples only with the end node
//! `N − 1`, as a node `N` would). Row `4n + p` of `U` and column `4n + p` of `L` then end at
//! index `4n + 7`: `7 − p` entries past the diagonal, not `BAND`, and elimination without row
//! exchanges creates no fill outside the envelope. [`BandMatrix::factor`] and
//! [`BandMatrix::solve`] work on those widths only (a quarter less work); the model's tests
//! check that every assembled Newton matrix has exact zeros outside the envelope.
//!
//! **Why no pivoting.** The Newmark matrix `c_m M + c_v C + c_q K` is dominated by the
//! consistent mass `M`, which is symmetric positive definite; the stiffness and the tip's
//! velocity terms enter scaled by `βh²` and `γh`. Elimination without pivoting is stable for it
//! as for any matrix close to an SPD one. It is not *assumed*: every pivot is checked against
//! the largest entry of its column below it ([`PIVOT_RATIO`]); if one is smaller, or not
//! finite, [`BandMatrix::factor`] gives up and the caller factors a fresh copy with
//! [`factor_pivoted`] (partial pivoting, full matrix). The fallback can run: in the paper's
//! free-ball run in `f32` with events at their crossing it did once in 20 s (the rolling rest of
//! a step after a landing: a multiplier of 6,400 in column 5), about 14,000 instructions on a
//! Cortex-M4F, until the event handling kept the accelerations from before an impulse; since
//! then the paper's runs do not need it (the test `the_pivoting_fallback_in_the_paper_scene` of
//! `tests/work_cap.rs` holds that count, so a change that makes it run must say so here). Under
//! a work cap ([`crate::Integrator::max_work`]) it never
//! runs: its dense LU grows as D³ and is outside the cap's bound, so the solve stops at the
//! cap instead ([`crate::step::newton`]).
//!
//! The band is stored by rows ([`BandMatrix`]) and factored in place; the dense fallback uses
//! nalgebra's column-major `SMatrix`. Inner loops run over fixed windows through iterators, so
//! no index can panic.

use crate::scalar::{is_positive, Real};
use nalgebra::{SMatrix, SVector};

/// Half-bandwidth of every Newton matrix of the model: `J[i,j] = 0` for `|i − j| > BAND`.
pub const BAND: usize = 7;

/// A pivot smaller than this fraction of the largest entry below it in its column makes the
/// banded elimination give up (the partial-pivoting fallback takes over). LAPACK's threshold
/// pivoting uses 0.1 for sparse LU; 1e-3 still bounds the growth per step by 1000.
pub const PIVOT_RATIO: f64 = 1e-3;

/// Entries kept per row of a [`BandMatrix`]: columns `i − BAND ..= i + BAND`.
pub const WIDTH: usize = 2 * BAND + 1;

/// Coordinates per node: the envelope's period.
pub const NODE: usize = 4;

/// Whether `J[i,j]` lies in the node envelope (module doc).
#[cfg(test)]
pub fn in_envelope(i: usize, j: usize) -> bool {
    (i / NODE).abs_diff(j / NODE) <= 1
}

/// A `D×D` matrix with `J[i,j] = 0` for `|i − j| > BAND`, stored by rows of the band:
/// `rows[i][j − i + BAND] = J[i,j]` (entries outside the matrix stay zero). Every operation
/// works on fixed 7- and 8-wide windows of a row, which the compiler unrolls: no loop
/// overhead and no index check inside the elimination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandMatrix<T, const D: usize> {
    rows: [[T; WIDTH]; D],
}

impl<T: Real, const D: usize> BandMatrix<T, D> {
    /// All zeros.
    pub fn zeros() -> Self {
        Self {
            rows: [[T::zero(); WIDTH]; D],
        }
    }

    /// Sets every entry to zero.
    pub fn clear(&mut self) {
        for r in self.rows.iter_mut() {
            *r = [T::zero(); WIDTH];
        }
    }

    /// Adds `v` at `(i, j)`; entries outside the band or the matrix are ignored.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: T) {
        if let Some(x) = self
            .rows
            .get_mut(i)
            .and_then(|r| r.get_mut((j + BAND).wrapping_sub(i)))
        {
            *x += v;
        }
    }

    /// `J[i,j]` (zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> T {
        self.rows
            .get(i)
            .and_then(|r| r.get((j + BAND).wrapping_sub(i)))
            .copied()
            .unwrap_or(T::zero())
    }

    /// Adds an 8×8 block whose local row/column `a` is global `first + a`, skipping the local
    /// rows and columns below `skip` (the clamped root node: `first` is then negative, given
    /// as `first + skip ≥ 0` with `skip`).
    #[inline]
    pub fn add_block8(&mut self, first: usize, skip: usize, block: &[[T; 8]; 8]) {
        // Row first+a, columns first+b: band index b − a + BAND.
        for (a, brow) in block.iter().enumerate().skip(skip) {
            let Some(row) = (first + a)
                .checked_sub(skip)
                .and_then(|i| self.rows.get_mut(i))
            else {
                continue;
            };
            let lo = BAND - a;
            if let (Some(dst), Some(src)) = (row.get_mut(lo + skip..lo + 8), brow.get(skip..)) {
                for (d, s) in dst.iter_mut().zip(src.iter()) {
                    *d += *s;
                }
            }
        }
    }

    /// The same matrix, dense (modes and tests).
    #[allow(clippy::wrong_self_convention)] // by reference: no matrix by value in the core
    pub fn to_dense(&self) -> SMatrix<T, D, D> {
        let mut m = SMatrix::<T, D, D>::zeros();
        self.write_dense(&mut m);
        m
    }

    /// `y = J x` (the unfactored matrix; the estimator's products with `∂r/∂q` and `∂r/∂v`).
    pub fn mul_vec(&self, x: &SVector<T, D>, y: &mut SVector<T, D>) {
        self.mul_mat(x, y);
    }

    /// `Y = J X`: for every column the sums of [`BandMatrix::mul_vec`], in the same order; the
    /// columns advance together (`X` read by rows), one pass over the node envelope (the
    /// matrix's assembled structure: a Newton matrix along any chain).
    pub fn mul_mat<const K: usize>(&self, x: &SMatrix<T, D, K>, y: &mut SMatrix<T, D, K>) {
        let mut z: [T; 0] = [];
        self.mul_rows::<K, false>(x, &[T::zero(); D], y, &mut z);
    }

    /// [`BandMatrix::mul_mat`] and [`BandMatrix::mul_vec`] of one more vector, `z = J v`, in
    /// the same pass (each with its own sums, in the same order).
    pub fn mul_mat_vec<const K: usize>(
        &self,
        x: &SMatrix<T, D, K>,
        v: &SVector<T, D>,
        y: &mut SMatrix<T, D, K>,
        z: &mut SVector<T, D>,
    ) {
        let mut vr = [T::zero(); D];
        for (a, b) in vr.iter_mut().zip(v.iter()) {
            *a = *b;
        }
        self.mul_rows::<K, true>(x, &vr, y, z.as_mut_slice());
    }

    /// The pass of [`BandMatrix::mul_mat_vec`]; with `V` false `v` is not read and `z` not
    /// written.
    fn mul_rows<const K: usize, const V: bool>(
        &self,
        x: &SMatrix<T, D, K>,
        v: &[T; D],
        y: &mut SMatrix<T, D, K>,
        z: &mut [T],
    ) {
        let mut xr = [[T::zero(); K]; D];
        for (c, col) in x.as_slice().chunks_exact(D).enumerate() {
            for (row, v) in xr.iter_mut().zip(col.iter()) {
                if let Some(r) = row.get_mut(c) {
                    *r = *v;
                }
            }
        }
        for (i, row) in self.rows.iter().enumerate() {
            // Row i's node envelope (module doc): the columns of nodes i/4 − 1 … i/4 + 1, a
            // fixed window per width (8 in the first node's rows, 12 inside, 9 in the last
            // node's, 5 in the spin's). The band's other entries are exact zeros, whose terms
            // change no sum.
            let first = i / NODE * NODE;
            let lo = first.saturating_sub(NODE);
            let at = lo + BAND - i;
            let (s, sv) = match (first + 2 * NODE).min(D) - lo {
                12 => envelope_row::<T, D, K, 12, V>(row, &xr, v, at, lo),
                9 => envelope_row::<T, D, K, 9, V>(row, &xr, v, at, lo),
                8 => envelope_row::<T, D, K, 8, V>(row, &xr, v, at, lo),
                5 => envelope_row::<T, D, K, 5, V>(row, &xr, v, at, lo),
                _ => envelope_row_any::<T, D, K, V>(
                    row,
                    &xr,
                    v,
                    BAND.saturating_sub(i),
                    i.saturating_sub(BAND),
                ),
            };
            for (c, sc) in s.iter().enumerate() {
                if let Some(yi) = y.get_mut((i, c)) {
                    *yi = *sc;
                }
            }
            if V {
                if let Some(zi) = z.get_mut(i) {
                    *zi = sv;
                }
            }
        }
    }

    /// Writes the same matrix, dense, into `m` (every entry; the pivoting fallback, in place:
    /// no `D×D` matrix on the stack).
    pub fn write_dense(&self, m: &mut SMatrix<T, D, D>) {
        m.fill(T::zero());
        for (i, row) in self.rows.iter().enumerate() {
            for (k, v) in row.iter().enumerate() {
                if let Some(x) = (i + k).checked_sub(BAND).and_then(|j| m.get_mut((i, j))) {
                    *x = *v;
                }
            }
        }
    }

    /// Factors in place, `J = L U` without row exchanges (unit lower `L` below the diagonal,
    /// `U` on and above), for a matrix in the node envelope (module doc). `false` if a pivot
    /// is not finite or smaller than `ratio` times the largest entry below it in its column (the
    /// matrix is then destroyed). Not inlined: its registers and frame stay off the
    /// assembly's call chain (the deepest stack of a step).
    #[inline(never)]
    pub fn factor(&mut self, ratio: T) -> bool {
        for k in 0..D {
            // Column 4n + p: 7 − p rows below and 7 − p entries of U to the right.
            let ok = match k % NODE {
                0 => self.eliminate::<7>(k, ratio),
                1 => self.eliminate::<6>(k, ratio),
                2 => self.eliminate::<5>(k, ratio),
                _ => self.eliminate::<4>(k, ratio),
            };
            if !ok {
                return false;
            }
        }
        true
    }

    /// Eliminates column `k` from the `W` rows below it, with the `W` entries of `U` right of
    /// the pivot (fixed widths: unrolled, no index check).
    #[inline(always)]
    fn eliminate<const W: usize>(&mut self, k: usize, ratio: T) -> bool {
        const { assert!(W <= BAND) };
        let Some((head, tail)) = self.rows.split_at_mut_checked(k + 1) else {
            return false;
        };
        let Some(pivot_row) = head.last() else {
            return false;
        };
        let p = pivot_row[BAND];
        // U[k, k+1 ..= k+W], copied: the eliminations below then keep it in registers.
        let Some(&u) = pivot_row.get(BAND + 1..).and_then(|s| s.first_chunk::<W>()) else {
            return false;
        };
        let mut largest = T::zero();
        for (m, row) in tail.iter().take(W).enumerate() {
            // A comparison, not `max`: `fmaxf` is a library call on the M4.
            let v = row[BAND - 1 - m].abs();
            if v > largest {
                largest = v;
            }
        }
        if !p.is_finite() || !is_positive(p.abs()) || p.abs() < ratio * largest {
            return false;
        }
        let inv = T::one() / p;
        // Row k+1+m: its column k sits at BAND − 1 − m, columns k+1 … k+W follow.
        for (m, row) in tail.iter_mut().take(W).enumerate() {
            let c = BAND - 1 - m;
            let l = row[c] * inv;
            row[c] = l;
            if l == T::zero() {
                continue;
            }
            if let Some(dst) = row.get_mut(c + 1..).and_then(|s| s.first_chunk_mut::<W>()) {
                for (d, s) in dst.iter_mut().zip(u.iter()) {
                    *d -= l * *s;
                }
            }
        }
        true
    }

    /// Solves `J x = b` in place from [`BandMatrix::factor`]'s factors; `false` if the result
    /// is not finite.
    ///
    /// Every row's dot product runs over a window of fixed width: the full `BAND` inside the
    /// matrix, and `0 … BAND − 1` in the rows whose band reaches past an edge (the first
    /// `BAND` rows going forward, the last `BAND` going back), one instantiation per width.
    /// Sums run in index order in every row, as a plain loop would.
    pub fn solve(&self, b: &mut SVector<T, D>) -> bool {
        let x = b.as_mut_slice();
        // Forward: x_i −= Σ_m L[i, i−m] x_{i−m}.
        self.forward_edge::<0>(x);
        self.forward_edge::<1>(x);
        self.forward_edge::<2>(x);
        self.forward_edge::<3>(x);
        self.forward_edge::<4>(x);
        self.forward_edge::<5>(x);
        self.forward_edge::<6>(x);
        for (i, row) in self.rows.iter().enumerate().skip(BAND) {
            // Row 4n + p: L from column 4(n − 1), 4 + p entries.
            let s = match i % NODE {
                0 => forward_dot::<T, 4>(row, x, i),
                1 => forward_dot::<T, 5>(row, x, i),
                2 => forward_dot::<T, 6>(row, x, i),
                _ => forward_dot::<T, 7>(row, x, i),
            };
            if let Some(xi) = x.get_mut(i) {
                *xi -= s;
            }
        }
        // Backward: x_i = (x_i − Σ_m U[i, i+m] x_{i+m}) / U[i, i], from the last row.
        self.backward_edge::<0>(x);
        self.backward_edge::<1>(x);
        self.backward_edge::<2>(x);
        self.backward_edge::<3>(x);
        self.backward_edge::<4>(x);
        self.backward_edge::<5>(x);
        self.backward_edge::<6>(x);
        let inner = D.saturating_sub(BAND);
        for (i, row) in self.rows.iter().enumerate().take(inner).rev() {
            // Row 4n + p: U to column 4n + 7, 7 − p entries.
            let s = match i % NODE {
                0 => backward_dot::<T, 7>(row, x, i),
                1 => backward_dot::<T, 6>(row, x, i),
                2 => backward_dot::<T, 5>(row, x, i),
                _ => backward_dot::<T, 4>(row, x, i),
            };
            if let Some(xi) = x.get_mut(i) {
                *xi = (*xi - s) / row[BAND];
            }
        }
        x.iter().all(|v| v.is_finite())
    }

    /// Forward substitution of row `K < BAND` (its `K` entries of `L` left of the diagonal).
    #[inline(always)]
    fn forward_edge<const K: usize>(&self, x: &mut [T]) {
        const { assert!(K < BAND) };
        let (Some(row), Some(prev)) = (self.rows.get(K), window::<T, K>(x, 0)) else {
            return;
        };
        let Some(l) = row.get(BAND - K..BAND).and_then(|s| s.first_chunk::<K>()) else {
            return;
        };
        let s = dot(l, prev);
        if let Some(xi) = x.get_mut(K) {
            *xi -= s;
        }
    }

    /// Backward substitution of row `D − 1 − W` (`W < BAND` entries of `U` right of the
    /// diagonal, up to the last column).
    #[inline(always)]
    fn backward_edge<const W: usize>(&self, x: &mut [T]) {
        const { assert!(W < BAND) };
        let Some(i) = D.checked_sub(W + 1) else {
            return;
        };
        let (Some(row), Some(next)) = (self.rows.get(i), window::<T, W>(x, i + 1)) else {
            return;
        };
        let Some(u) = row.get(BAND + 1..).and_then(|s| s.first_chunk::<W>()) else {
            return;
        };
        let s = dot(u, next);
        if let Some(xi) = x.get_mut(i) {
            *xi = (*xi - s) / row[BAND];
        }
    }
}

/// `Σ_m L[i, i−W+m] x[i−W+m]`: the last `W` entries of `L` left of row `i`'s diagonal.
#[inline(always)]
fn forward_dot<T: Real, const W: usize>(row: &[T; WIDTH], x: &[T], i: usize) -> T {
    match (
        row.get(BAND - W..BAND).and_then(|s| s.first_chunk::<W>()),
        i.checked_sub(W).and_then(|start| window::<T, W>(x, start)),
    ) {
        (Some(l), Some(prev)) => dot(l, prev),
        _ => T::zero(),
    }
}

/// `Σ_m U[i, i+1+m] x[i+1+m]`: the first `W` entries of `U` right of row `i`'s diagonal.
#[inline(always)]
fn backward_dot<T: Real, const W: usize>(row: &[T; WIDTH], x: &[T], i: usize) -> T {
    match (
        row.get(BAND + 1..).and_then(|s| s.first_chunk::<W>()),
        window::<T, W>(x, i + 1),
    ) {
        (Some(u), Some(next)) => dot(u, next),
        _ => T::zero(),
    }
}

/// `Σ_k row[at + k] x[from + k]` for every column of `x` (given by rows) over a window of
/// `W`, and with `V` the same sum for `v`, each in index order from zero (zero if the window
/// does not fit).
#[inline(always)]
fn envelope_row<T: Real, const D: usize, const K: usize, const W: usize, const V: bool>(
    row: &[T; WIDTH],
    x: &[[T; K]; D],
    v: &[T; D],
    at: usize,
    from: usize,
) -> ([T; K], T) {
    let mut s = [T::zero(); K];
    let mut sv = T::zero();
    let (Some(r), Some(xw), Some(vw)) = (
        row.get(at..).and_then(|r| r.first_chunk::<W>()),
        x.get(from..).and_then(|x| x.first_chunk::<W>()),
        v.get(from..).and_then(|v| v.first_chunk::<W>()),
    ) else {
        return (s, sv);
    };
    for ((a, xk), vk) in r.iter().zip(xw.iter()).zip(vw.iter()) {
        for (sc, y) in s.iter_mut().zip(xk.iter()) {
            *sc += *a * *y;
        }
        if V {
            sv += *a * *vk;
        }
    }
    (s, sv)
}

/// [`envelope_row`] over the rest of the band row (a narrow matrix's rows).
fn envelope_row_any<T: Real, const D: usize, const K: usize, const V: bool>(
    row: &[T; WIDTH],
    x: &[[T; K]; D],
    v: &[T; D],
    at: usize,
    from: usize,
) -> ([T; K], T) {
    let mut s = [T::zero(); K];
    let mut sv = T::zero();
    let (r, xw) = (row.get(at..).unwrap_or(&[]), x.get(from..).unwrap_or(&[]));
    let vw = v.get(from..).unwrap_or(&[]);
    for ((a, xk), vk) in r.iter().zip(xw.iter()).zip(vw.iter()) {
        for (sc, y) in s.iter_mut().zip(xk.iter()) {
            *sc += *a * *y;
        }
        if V {
            sv += *a * *vk;
        }
    }
    (s, sv)
}

/// `x[start .. start + W]` as a fixed window, if it lies inside `x`.
#[inline(always)]
fn window<T, const W: usize>(x: &[T], start: usize) -> Option<&[T; W]> {
    x.get(start..).and_then(|s| s.first_chunk::<W>())
}

/// `Σ a_k b_k` over fixed windows (unrolled), summed in index order.
#[inline(always)]
pub(crate) fn dot<T: Real, const W: usize>(a: &[T; W], b: &[T; W]) -> T {
    let mut s = T::zero();
    for (x, y) in a.iter().zip(b.iter()) {
        s += *x * *y;
    }
    s
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

/// Solves `A x = b` in place (`b` becomes `x`) from [`factor_pivoted`]'s factors and row
/// exchanges; `false` if the result is not finite.
pub fn solve<T: Real, const D: usize>(
    lu: &SMatrix<T, D, D>,
    pivots: &[usize; D],
    b: &mut SVector<T, D>,
) -> bool {
    for (k, p) in pivots.iter().enumerate() {
        if *p != k {
            let _ = b
                .as_mut_slice()
                .get_disjoint_mut([*p, k])
                .map(|[x, y]| core::mem::swap(x, y));
        }
    }
    let x = b.as_mut_slice();
    // Forward: L y = b, column by column.
    for (k, col) in lu.as_slice().chunks_exact(D).enumerate() {
        let Some(xk) = x.get(k).copied() else {
            return false;
        };
        if xk == T::zero() {
            continue;
        }
        if let (Some(l), Some(dst)) = (col.get(k + 1..), x.get_mut(k + 1..)) {
            for (d, lik) in dst.iter_mut().zip(l.iter()) {
                *d -= *lik * xk;
            }
        }
    }
    // Backward: U x = y, column by column from the last.
    for (k, col) in lu.as_slice().chunks_exact(D).enumerate().rev() {
        let (Some(ukk), Some(xk)) = (col.get(k), x.get_mut(k)) else {
            return false;
        };
        *xk /= *ukk;
        let xk = *xk;
        if let (Some(u), Some(dst)) = (col.get(..k), x.get_mut(..k)) {
            for (d, uik) in dst.iter_mut().zip(u.iter()) {
                *d -= *uik * xk;
            }
        }
    }
    x.iter().all(|v| v.is_finite())
}

/// Solves `A x = b` with a copy of `A` (off the step path: tests); `None` if singular.
#[cfg(test)]
pub fn solve_dense<T: Real, const D: usize>(
    mut a: SMatrix<T, D, D>,
    mut b: SVector<T, D>,
) -> Option<SVector<T, D>> {
    let pivots = factor_pivoted(&mut a)?;
    solve(&a, &pivots, &mut b).then_some(b)
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
        let mut b = BandMatrix::<f64, 3>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                b.add(i, j, a[(i, j)]);
            }
        }
        assert!(!b.factor(PIVOT_RATIO));
    }

    /// A diagonally dominant 21×21 matrix in the node envelope (non-symmetric): the banded
    /// factors (dense storage and band storage) solve it as the pivoted dense LU does, to
    /// rounding.
    #[test]
    fn banded_factors_equal_dense_ones_on_a_band_matrix() {
        let mut a = SMatrix::<f64, 21, 21>::zeros();
        for i in 0..21usize {
            for j in 0..21usize {
                if in_envelope(i, j) {
                    a[(i, j)] = ((i * 7 + j * 3) as f64 * 0.37).sin();
                }
            }
            a[(i, i)] += 12.0;
        }
        let x = SVector::<f64, 21>::from_fn(|i, _| (i as f64 * 0.9).cos());
        let dense = solve_dense(a, a * x).expect("regular");
        assert!((dense - x).amax() < 1e-13);
        let mut band = BandMatrix::<f64, 21>::zeros();
        for i in 0..21 {
            for j in 0..21 {
                band.add(i, j, a[(i, j)]);
            }
        }
        assert_eq!(band.to_dense(), a);
        assert!(band.factor(PIVOT_RATIO));
        let mut c = a * x;
        assert!(band.solve(&mut c));
        assert!((c - x).amax() < 1e-13, "{}", (c - x).amax());
    }

    /// The band's products equal nalgebra's dense product bit for bit (the same sums in the
    /// same order; the terms outside the node envelope, where an assembled Newton matrix is
    /// zero, are exact zeros), at the estimator's sizes (a matrix narrower than the band's
    /// width, 13) and beyond it (21), in `f32`; the fused product gives both bit for bit.
    #[test]
    fn band_products_equal_the_dense_product_bit_for_bit() {
        fn check<const D: usize>() {
            let mut band = BandMatrix::<f32, D>::zeros();
            for i in 0..D {
                for j in 0..D {
                    if in_envelope(i, j) {
                        band.add(i, j, ((i * 5 + j * 11) as f32 * 0.61).sin() * 3.0);
                    }
                }
            }
            let a = band.to_dense();
            let x = SMatrix::<f32, D, 3>::from_fn(|i, c| ((i + 7 * c) as f32 * 1.3).cos() * 1e-3);
            let mut y = SMatrix::<f32, D, 3>::zeros();
            band.mul_mat(&x, &mut y);
            let dense = a * x;
            for (p, q) in y.iter().zip(dense.iter()) {
                assert_eq!(p.to_bits(), q.to_bits(), "{p} vs {q}");
            }
            let v = x.column(1).into_owned();
            let mut w = SVector::<f32, D>::zeros();
            band.mul_vec(&v, &mut w);
            assert_eq!(w, a * v);
            let v2 = SVector::<f32, D>::from_fn(|i, _| (i as f32 * 0.7).sin() * 1e-2);
            let (mut y2, mut w2) = (SMatrix::<f32, D, 3>::zeros(), SVector::<f32, D>::zeros());
            band.mul_mat_vec(&x, &v2, &mut y2, &mut w2);
            assert_eq!(y2, y);
            for (p, q) in w2.iter().zip((a * v2).iter()) {
                assert_eq!(p.to_bits(), q.to_bits(), "{p} vs {q}");
            }
        }
        check::<13>();
        check::<21>();
    }
}
