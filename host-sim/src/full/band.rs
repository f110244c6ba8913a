//! Banded LU with partial pivoting (the LAPACK `gbtrf` scheme, row storage).
//!
//! Both systems of the full solver are banded once the unknowns are ordered along the beam:
//! the reduced Newton matrix (half-bandwidth 7: an element couples two nodes of 4 coordinates,
//! and the ball spin sits right after the end node) and the augmented system (22) (clamp
//! multipliers before the root node, the tip and ball coordinates and their multipliers after
//! the end node: half-bandwidth at most 15). Factorization costs `O(n·kl·(kl + ku))`, so a step
//! costs `O(N)`; a dense LU would cost `O(N³)`.

/// A square band matrix with `kl` sub- and `ku` super-diagonals; row `i` stores the columns
/// `i − kl ..= i + kl + ku` (the extra `kl` hold the fill-in of row interchanges).
#[derive(Clone, Debug)]
pub struct Band {
    n: usize,
    kl: usize,
    ku: usize,
    width: usize,
    data: Vec<f64>,
}

/// A factorized band matrix.
#[derive(Clone, Debug)]
pub struct BandLu {
    a: Band,
    pivots: Vec<usize>,
}

impl Band {
    /// Zero `n × n` band matrix.
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Self {
        let width = 2 * kl + ku + 1;
        Self {
            n,
            kl,
            ku,
            width,
            data: vec![0.0; n * width],
        }
    }

    #[inline]
    fn slot(&self, i: usize, j: usize) -> Option<usize> {
        if i >= self.n || j >= self.n || j + self.kl < i || j > i + self.kl + self.ku {
            return None;
        }
        Some(i * self.width + (j + self.kl - i))
    }

    /// Entry (0 outside the band).
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.slot(i, j)
            .and_then(|s| self.data.get(s).copied())
            .unwrap_or(0.0)
    }

    /// Adds `v` to entry (i, j); returns false if (i, j) lies outside the band (not stored).
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> bool {
        if j > i + self.ku {
            return false;
        }
        match self.slot(i, j).and_then(|s| self.data.get_mut(s)) {
            Some(x) => {
                *x += v;
                true
            }
            None => false,
        }
    }

    #[inline]
    fn set(&mut self, i: usize, j: usize, v: f64) {
        if let Some(x) = self.slot(i, j).and_then(|s| self.data.get_mut(s)) {
            *x = v;
        }
    }

    /// `y = A x`.
    #[cfg(test)]
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for (i, yi) in y.iter_mut().enumerate() {
            let lo = i.saturating_sub(self.kl);
            let hi = (i + self.ku + 1).min(self.n);
            let mut s = 0.0;
            for j in lo..hi {
                s += self.get(i, j) * x.get(j).copied().unwrap_or(0.0);
            }
            *yi = s;
        }
        y
    }

    /// Dense copy (for eigenvalues and tests).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_fn(self.n, self.n, |i, j| self.get(i, j))
    }

    /// LU with partial pivoting; `None` if a pivot is zero or not finite.
    pub fn factor(mut self) -> Option<BandLu> {
        let n = self.n;
        let mut pivots = vec![0; n];
        for k in 0..n {
            let last = (k + self.kl + 1).min(n);
            let mut p = k;
            let mut best = self.get(k, k).abs();
            for i in (k + 1)..last {
                let v = self.get(i, k).abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if !best.is_finite() || best <= 0.0 {
                return None;
            }
            if let Some(slot) = pivots.get_mut(k) {
                *slot = p;
            }
            let end = (k + self.kl + self.ku + 1).min(n);
            if p != k {
                for j in k..end {
                    let (a, b) = (self.get(k, j), self.get(p, j));
                    self.set(k, j, b);
                    self.set(p, j, a);
                }
            }
            let inv = 1.0 / self.get(k, k);
            for i in (k + 1)..last {
                let f = self.get(i, k) * inv;
                self.set(i, k, f);
                if f != 0.0 {
                    for j in (k + 1)..end {
                        let v = self.get(i, j) - f * self.get(k, j);
                        self.set(i, j, v);
                    }
                }
            }
        }
        Some(BandLu { a: self, pivots })
    }
}

impl BandLu {
    /// Solves `A x = b` in place; false if the result is not finite.
    #[allow(clippy::needless_range_loop)] // banded index ranges read clearer as ranges
    pub fn solve(&self, b: &mut [f64]) -> bool {
        let a = &self.a;
        let n = a.n;
        if b.len() != n {
            return false;
        }
        for k in 0..n {
            let p = self.pivots.get(k).copied().unwrap_or(k);
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            if bk != 0.0 {
                for i in (k + 1)..(k + a.kl + 1).min(n) {
                    b[i] -= a.get(i, k) * bk;
                }
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in (k + 1)..(k + a.kl + a.ku + 1).min(n) {
                s -= a.get(k, j) * b[j];
            }
            b[k] = s / a.get(k, k);
        }
        b.iter().all(|x| x.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_lu_matches_dense_solution_with_pivoting() {
        let n = 23;
        let (kl, ku) = (3, 2);
        let mut a = Band::zeros(n, kl, ku);
        for i in 0..n {
            for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                // Zero diagonal in places: needs pivoting.
                let v = if i == j && i % 4 == 0 {
                    0.0
                } else {
                    ((i * 7 + j * 3) as f64).sin() + 0.1
                };
                assert!(a.add(i, j, v));
            }
        }
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        let mut b = a.mul(&x);
        let dense = a.to_dense();
        let lu = a.factor().expect("regular");
        assert!(lu.solve(&mut b));
        for i in 0..n {
            assert!((b[i] - x[i]).abs() < 1e-10, "{i}: {} vs {}", b[i], x[i]);
        }
        let xd = dense
            .lu()
            .solve(&nalgebra::DVector::from_column_slice(&x))
            .expect("regular");
        assert!(xd.iter().all(|v| v.is_finite()));
    }
}
