//! Kept sparse LU of the full solver's matrices (faer's sparse LU: COLAMD fill-reducing column
//! order and the elimination structure computed once per sparsity pattern, then a numeric
//! factorization with partial pivoting per refresh, reusing its storage).
//!
//! A [`Pattern`] is the compressed-column structure of one matrix (the constant mass matrix, or
//! the reduced Newton matrix of one partition) with its symbolic analysis; an [`Lu`] holds the
//! values in that pattern, the numeric factors and the workspace, so refactoring and solving
//! allocate nothing once the factor storage has grown to its size (the first factorization).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::lu::simplicial::{self, SimplicialLu};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};
use std::sync::Arc;

/// Column order of the factorization.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// The given order. For the full solver's matrices (node-ordered bands) it is already a
    /// fill-reducing order: partial pivoting keeps L within the lower and U within twice the
    /// upper bandwidth, so the factors cost `O(n)`.
    Natural,
    /// COLAMD's approximate minimum degree order (faer's symbolic LU analysis).
    #[allow(dead_code)] // kept for the comparison in docs/full-solver.md and the tests
    Colamd,
}

enum Analysis {
    Natural { fwd: Vec<usize>, inv: Vec<usize> },
    Colamd(SymbolicLu<usize>),
}

/// Sparsity pattern (compressed columns, rows sorted) and its symbolic LU analysis.
pub struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    analysis: Analysis,
    scratch: StackReq,
}

impl core::fmt::Debug for Pattern {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Pattern")
            .field("n", &self.n)
            .field("nnz", &self.row_idx.len())
            .finish()
    }
}

impl Pattern {
    /// The `n × n` pattern holding `entries` (row, column); duplicates are merged, entries
    /// outside the matrix ignored. `None` if the symbolic analysis fails (out of memory).
    pub fn new(
        n: usize,
        entries: impl IntoIterator<Item = (usize, usize)>,
        order: Order,
    ) -> Option<Self> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (i, j) in entries {
            if i < n {
                if let Some(c) = cols.get_mut(j) {
                    c.push(i);
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(&c);
            col_ptr.push(row_idx.len());
        }
        let (analysis, scratch) = match order {
            Order::Natural => {
                let scratch =
                    simplicial::factorize_simplicial_numeric_lu_scratch::<usize, f64>(n, n).or(
                        simplicial::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq),
                    );
                let fwd: Vec<usize> = (0..n).collect();
                (
                    Analysis::Natural {
                        inv: fwd.clone(),
                        fwd,
                    },
                    scratch,
                )
            }
            Order::Colamd => {
                let a = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
                // Simplicial (left-looking, Gilbert–Peierls): the supernodes of these narrow
                // bands are too small to pay for the supernodal bookkeeping.
                let params = LuSymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
                    ..Default::default()
                };
                let symbolic = factorize_symbolic_lu(a, params).ok()?;
                let scratch = symbolic
                    .factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default())
                    .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
                (Analysis::Colamd(symbolic), scratch)
            }
        };
        Some(Self {
            n,
            col_ptr,
            row_idx,
            analysis,
            scratch,
        })
    }

    /// Position of entry (i, j) in the value array, `None` if it is not in the pattern.
    #[inline]
    fn slot(&self, i: usize, j: usize) -> Option<usize> {
        let lo = *self.col_ptr.get(j)?;
        let hi = *self.col_ptr.get(j + 1)?;
        let rows = self.row_idx.get(lo..hi)?;
        rows.binary_search(&i).ok().map(|k| lo + k)
    }
}

/// Values in a [`Pattern`], their LU factors and the factorization/solve workspace.
pub struct Lu {
    pattern: Arc<Pattern>,
    values: Vec<f64>,
    numeric: NumericLu<usize, f64>,
    simplicial: SimplicialLu<usize, f64>,
    row_fwd: Vec<usize>,
    row_inv: Vec<usize>,
    mem: MemBuffer,
    factored: bool,
}

impl Clone for Lu {
    fn clone(&self) -> Self {
        Self {
            pattern: Arc::clone(&self.pattern),
            values: self.values.clone(),
            numeric: self.numeric.clone(),
            simplicial: self.simplicial.clone(),
            row_fwd: self.row_fwd.clone(),
            row_inv: self.row_inv.clone(),
            mem: MemBuffer::new(self.pattern.scratch),
            factored: self.factored,
        }
    }
}

impl core::fmt::Debug for Lu {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Lu")
            .field("pattern", &self.pattern)
            .field("factored", &self.factored)
            .finish()
    }
}

impl Lu {
    /// A zero matrix in `pattern`.
    pub fn new(pattern: Arc<Pattern>) -> Self {
        Self {
            values: vec![0.0; pattern.row_idx.len()],
            numeric: NumericLu::new(),
            simplicial: SimplicialLu::new(),
            row_fwd: vec![0; pattern.n],
            row_inv: vec![0; pattern.n],
            mem: MemBuffer::new(pattern.scratch),
            factored: false,
            pattern,
        }
    }

    /// Sets every value to zero (the factors become stale).
    pub fn clear(&mut self) {
        self.values.fill(0.0);
        self.factored = false;
    }

    /// Adds `v` to entry (i, j); false if (i, j) is not in the pattern (nothing stored).
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> bool {
        match self.pattern.slot(i, j).and_then(|s| self.values.get_mut(s)) {
            Some(x) => {
                *x += v;
                self.factored = false;
                true
            }
            None => false,
        }
    }

    /// Dense copy of the assembled values (tests).
    #[cfg(test)]
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let p = &self.pattern;
        let mut d = nalgebra::DMatrix::zeros(p.n, p.n);
        for j in 0..p.n {
            for s in p.col_ptr[j]..p.col_ptr[j + 1] {
                d[(p.row_idx[s], j)] = self.values[s];
            }
        }
        d
    }

    /// LU factorization of the current values (partial pivoting); false if it fails
    /// (structurally singular, or a pivot that is zero or not finite).
    pub fn factor(&mut self) -> bool {
        self.factored = false;
        if !self.values.iter().all(|v| v.is_finite()) {
            return false;
        }
        let p = &*self.pattern;
        let sym = SymbolicSparseColMatRef::new_checked(p.n, p.n, &p.col_ptr, None, &p.row_idx);
        let a = SparseColMatRef::new(sym, &self.values);
        let stack = MemStack::new(&mut self.mem);
        self.factored = match &p.analysis {
            Analysis::Natural { fwd, inv } => simplicial::factorize_simplicial_numeric_lu(
                &mut self.row_fwd,
                &mut self.row_inv,
                &mut self.simplicial,
                a,
                PermRef::new_checked(fwd, inv, p.n),
                stack,
            )
            .is_ok(),
            Analysis::Colamd(symbolic) => symbolic
                .factorize_numeric_lu(&mut self.numeric, a, Par::Seq, stack, Default::default())
                .is_ok(),
        };
        self.factored
    }

    /// Solves `A x = b` in place with the last factors; false if there are none or the
    /// result is not finite (a zero pivot).
    pub fn solve(&mut self, b: &mut [f64]) -> bool {
        let p = &*self.pattern;
        if !self.factored || b.len() != p.n {
            return false;
        }
        let n = p.n;
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        let stack = MemStack::new(&mut self.mem);
        match &p.analysis {
            Analysis::Natural { fwd, inv } => self.simplicial.solve_in_place_with_conj(
                PermRef::new_checked(&self.row_fwd, &self.row_inv, n),
                PermRef::new_checked(fwd, inv, n),
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            ),
            Analysis::Colamd(symbolic) => {
                faer::sparse::linalg::lu::LuRef::new_unchecked(symbolic, &self.numeric)
                    .solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack)
            }
        }
        b.iter().all(|x| x.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bordered banded matrix (the shape of the full solver's systems) with zero diagonal
    /// entries that need pivoting: the sparse solve equals nalgebra's dense LU solve.
    #[test]
    fn sparse_lu_matches_dense_lu_with_pivoting() {
        let n = 41;
        let border = 5;
        let entry = |i: usize, j: usize| -> Option<f64> {
            let banded = i.abs_diff(j) <= 3;
            let bordered = i >= n - border || j >= n - border;
            if !(banded || bordered) {
                return None;
            }
            Some(if i == j && i.is_multiple_of(4) {
                0.0
            } else {
                ((i * 7 + j * 3) as f64).sin() + 0.1
            })
        };
        let entries: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|&(i, j)| entry(i, j).is_some())
            .collect();
        for order in [Order::Natural, Order::Colamd] {
            let pattern =
                Arc::new(Pattern::new(n, entries.iter().copied(), order).expect("symbolic"));
            let mut lu = Lu::new(pattern);
            for &(i, j) in &entries {
                assert!(lu.add(i, j, entry(i, j).unwrap_or(0.0)));
            }
            assert!(!lu.add(0, n - border - 1, 1.0), "outside the pattern");
            let dense = lu.to_dense();
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
            let b = &dense * nalgebra::DVector::from_column_slice(&x);
            let xd = dense.clone().lu().solve(&b).expect("regular");
            assert!(lu.factor());
            let mut y = b.as_slice().to_vec();
            assert!(lu.solve(&mut y));
            for i in 0..n {
                assert!(
                    (y[i] - xd[i]).abs() <= 1e-12 * xd.amax(),
                    "{i}: {} vs {}",
                    y[i],
                    xd[i]
                );
                assert!((y[i] - x[i]).abs() <= 1e-10, "{i}: {} vs {}", y[i], x[i]);
            }
            // Refactoring new values in the same pattern reuses the analysis.
            lu.clear();
            for &(i, j) in &entries {
                lu.add(i, j, 2.0 * entry(i, j).unwrap_or(0.0));
            }
            assert!(lu.factor());
            let mut y2 = b.as_slice().to_vec();
            assert!(lu.solve(&mut y2));
            for i in 0..n {
                assert!((2.0 * y2[i] - xd[i]).abs() <= 1e-12 * xd.amax());
            }
            // A singular matrix is reported, not solved.
            lu.clear();
            assert!(!lu.factor() || !lu.solve(&mut y2));
        }
    }
}
