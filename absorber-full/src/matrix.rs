//! A matrix of the full solver (the constant mass matrix or a reduced Newton matrix) with its
//! factorization: the block LU ([`BlockLu`]), or the kept sparse LU (faer) as the guarded
//! fallback and the reference.

use super::block::BlockLu;
use super::sparse::{Lu as SparseLu, Order, Pattern};
use std::sync::Arc;

/// Which factorization [`Matrix`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Linear {
    /// The block LU ([`BlockLu`]), the kept sparse LU as the guarded fallback.
    Block,
    /// The kept sparse LU (faer) always: the reference.
    Sparse,
}

/// A matrix of the full solver (the constant mass matrix or a reduced Newton matrix): values
/// in the block structure, factored by [`BlockLu`] or, as the reference and the guarded
/// fallback, by the kept sparse LU on the matrix's own pattern (built on first use).
#[derive(Clone, Debug)]
pub struct Matrix {
    block: BlockLu,
    entries: Arc<[(usize, usize)]>,
    sparse: Option<SparseLu>,
    linear: Linear,
    /// Which factors the last successful factorization left: `Some(true)` the sparse ones.
    factored: Option<bool>,
    /// Factorizations that fell back to the sparse LU (diagnostics, tests).
    fallbacks: u64,
}

impl Matrix {
    /// Zero matrix of `4 · nodes + border` unknowns with the nonzero pattern `entries` (all
    /// inside the block structure); `None` if the shape is not supported.
    pub fn new(
        nodes: usize,
        border: usize,
        entries: impl IntoIterator<Item = (usize, usize)>,
        linear: Linear,
    ) -> Option<Self> {
        let block = BlockLu::new(nodes, border)?;
        let n = block.n();
        let mut entries: Vec<(usize, usize)> = entries
            .into_iter()
            .filter(|&(i, j)| i < n && j < n)
            .collect();
        entries.sort_unstable();
        entries.dedup();
        let mut probe = block.clone();
        if !entries.iter().all(|&(i, j)| probe.add(i, j, 0.0)) {
            return None;
        }
        Some(Self {
            block,
            entries: entries.into(),
            sparse: None,
            linear,
            factored: None,
            fallbacks: 0,
        })
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.block.n()
    }

    /// Sets every value to zero (the factors become stale).
    pub fn clear(&mut self) {
        self.block.clear();
        self.factored = None;
    }

    /// Adds `v` to entry (i, j); false if it is outside the structure.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> bool {
        self.factored = None;
        self.block.add(i, j, v)
    }

    /// Adds an element's 8 × 8 block ([`BlockLu::add_element`]).
    #[inline]
    pub fn add_element(&mut self, e: usize, b: &[[f64; 8]; 8]) -> bool {
        self.factored = None;
        self.block.add_element(e, b)
    }

    /// Dense copy of the values.
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        self.block.to_dense()
    }

    /// The same values with the other factorization (tests: the reference solve).
    #[cfg(test)]
    pub fn with_linear(&self, linear: Linear) -> Self {
        let mut m = self.clone();
        m.linear = linear;
        m.factored = None;
        m
    }

    /// Factorizations that fell back to the sparse LU so far.
    #[allow(dead_code)] // tests and diagnostics
    pub fn fallbacks(&self) -> u64 {
        self.fallbacks
    }

    /// The values copied into the kept sparse LU and factored there.
    fn factor_sparse(&mut self) -> bool {
        if self.sparse.is_none() {
            let n = self.n();
            let Some(p) = Pattern::new(n, self.entries.iter().copied(), Order::Natural) else {
                return false;
            };
            self.sparse = Some(SparseLu::new(Arc::new(p)));
        }
        let Some(lu) = self.sparse.as_mut() else {
            return false;
        };
        lu.clear();
        for &(i, j) in self.entries.iter() {
            lu.add(i, j, self.block.get(i, j));
        }
        lu.factor()
    }

    /// Factors the values: the block LU, or the sparse LU (always with [`Linear::Sparse`], else
    /// when the block LU's checks fail); false if both fail.
    pub fn factor(&mut self) -> bool {
        self.factored = None;
        if self.linear == Linear::Block && self.block.factor() {
            self.factored = Some(false);
            return true;
        }
        if self.linear == Linear::Block {
            self.fallbacks += 1;
        }
        if self.factor_sparse() {
            self.factored = Some(true);
            return true;
        }
        false
    }

    /// Solves `A x = b` in place with the last factors; false if there are none or the result
    /// is not finite.
    pub fn solve(&mut self, b: &mut [f64]) -> bool {
        match self.factored {
            Some(false) => self.block.solve(b),
            Some(true) => self.sparse.as_mut().is_some_and(|lu| lu.solve(b)),
            None => false,
        }
    }

    /// [`Matrix::solve`] where only the tail's unknowns (end node and border) are wanted:
    /// [`BlockLu::solve_tail`] (the same values), a whole solve with the sparse factors.
    pub fn solve_tail(&mut self, b: &mut [f64]) -> bool {
        match self.factored {
            Some(false) => self.block.solve_tail(b),
            Some(true) => self.sparse.as_mut().is_some_and(|lu| lu.solve(b)),
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A matrix that needs exchanges across blocks (a tiny diagonal block over a large
    /// coupling) fails the block LU's check and is solved by the sparse fallback.
    #[test]
    fn growth_falls_back_to_the_sparse_lu() {
        let nodes = 4;
        let n: usize = 16;
        let entries: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|&(i, j)| (i / 4).abs_diff(j / 4) <= 1)
            .collect();
        let mut a = Matrix::new(nodes, 0, entries.iter().copied(), Linear::Block).expect("shape");
        for &(i, j) in &entries {
            let v = if i / 4 == j / 4 {
                if i == j {
                    1e-6
                } else {
                    0.0
                }
            } else {
                ((i * 7 + j * 3) as f64).sin() + if i % 4 == j % 4 { 3.0 } else { 0.0 }
            };
            a.add(i, j, v);
        }
        let dense = a.to_dense();
        let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let b = &dense * nalgebra::DVector::from_column_slice(&x);
        assert!(a.factor());
        assert_eq!(a.fallbacks(), 1);
        let mut y = b.as_slice().to_vec();
        assert!(a.solve(&mut y));
        for i in 0..n {
            assert!(
                (y[i] - x[i]).abs() <= 1e-8 * 16.0,
                "{i}: {} vs {}",
                y[i],
                x[i]
            );
        }
        // Singular: no usable factors.
        a.clear();
        assert!(!a.factor() || !a.solve(&mut y));
    }
}
