//! Dense LU with partial pivoting of a small matrix (at most 10 × 10): the tail block of
//! [`BlockLu`](super::block::BlockLu) and the local constraint Jacobians `C_d`.

/// Dense LU with partial pivoting of the leading `n × n` part of an `S × S` array (the tail
/// block; the local constraint Jacobians): `a` holds the unit lower factor below the
/// diagonal and the upper one on and above, rows in pivot order. Factored and solved in place
/// with `n` as a compile-time bound (one instantiation per size: unrolled, no index checks).
#[derive(Clone, Copy, Debug)]
pub struct DenseLu<const S: usize> {
    /// The matrix (set before [`DenseLu::factor`]), then its factors.
    pub a: [[f64; S]; S],
    perm: [usize; S],
    n: usize,
}

/// Calls `$f::<N>` for `N = $n` in 0..=10.
macro_rules! by_size {
    ($self:ident, $n:expr, $f:ident ( $($arg:expr),* )) => {
        match $n {
            0 => $self.$f::<0>($($arg),*),
            1 => $self.$f::<1>($($arg),*),
            2 => $self.$f::<2>($($arg),*),
            3 => $self.$f::<3>($($arg),*),
            4 => $self.$f::<4>($($arg),*),
            5 => $self.$f::<5>($($arg),*),
            6 => $self.$f::<6>($($arg),*),
            7 => $self.$f::<7>($($arg),*),
            8 => $self.$f::<8>($($arg),*),
            9 => $self.$f::<9>($($arg),*),
            _ => $self.$f::<10>($($arg),*),
        }
    };
}

impl<const S: usize> DenseLu<S> {
    /// The zero `n × n` matrix (`n ≤ min(S, 10)`, else [`DenseLu::factor`] fails).
    pub fn new(n: usize) -> Self {
        Self {
            a: [[0.0; S]; S],
            perm: [0; S],
            n,
        }
    }

    /// Sets the size to `n` (the entries must be written again before [`DenseLu::factor`]).
    pub fn resize(&mut self, n: usize) {
        self.n = n;
    }

    /// Factors `a` in place; false if a pivot is zero or not finite (or `n` is too large).
    pub fn factor(&mut self) -> bool {
        if self.n > S || self.n > 10 {
            return false;
        }
        by_size!(self, self.n, factor_n())
    }

    // The loops below run over constant ranges with the triangular bounds as conditions, so
    // that the compiler unrolls them completely for each `N` (a triangular range would be left
    // as a loop with index checks).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // elimination over fixed arrays, by index
    fn factor_n<const N: usize>(&mut self) -> bool {
        if N > S {
            return false;
        }
        let a = &mut self.a;
        for (i, p) in self.perm.iter_mut().enumerate() {
            *p = i;
        }
        for k in 0..N {
            let mut p = k;
            let mut big = a[k][k].abs();
            for i in 0..N {
                if i > k {
                    let v = a[i][k].abs();
                    if v > big {
                        big = v;
                        p = i;
                    }
                }
            }
            if !(big > 0.0 && big.is_finite()) {
                return false;
            }
            if p != k {
                a.swap(p, k);
                self.perm.swap(p, k);
            }
            let r = 1.0 / a[k][k];
            let pivot_row = a[k];
            for i in 0..N {
                // (The constraint Jacobians are sparse: most multipliers are zero.)
                if i > k && a[i][k] != 0.0 {
                    let l = a[i][k] * r;
                    a[i][k] = l;
                    for c in 0..N {
                        if c > k {
                            a[i][c] -= l * pivot_row[c];
                        }
                    }
                }
            }
        }
        true
    }

    /// Solves in place (the leading `n` entries of `z`) with the factors.
    pub fn solve(&self, z: &mut [f64; S]) {
        if self.n > S || self.n > 10 {
            return;
        }
        by_size!(self, self.n, solve_n(z))
    }

    /// Solves `Aᵀ x = b` in place (the leading `n` entries of `z`) with the factors of `A`.
    pub fn solve_transposed(&self, z: &mut [f64; S]) {
        if self.n > S || self.n > 10 {
            return;
        }
        by_size!(self, self.n, solve_transposed_n(z))
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn solve_transposed_n<const N: usize>(&self, z: &mut [f64; S]) {
        if N > S {
            return;
        }
        // P A = L U, so Aᵀ = Uᵀ Lᵀ P: Uᵀ y = b, Lᵀ w = y, x = Pᵀ w.
        let a = &self.a;
        let mut y = [0.0; S];
        for i in 0..N {
            let mut x = z[i];
            for k in 0..N {
                if k < i {
                    x -= a[k][i] * y[k];
                }
            }
            y[i] = x / a[i][i];
        }
        for ii in 0..N {
            let i = N - 1 - ii;
            let mut x = y[i];
            for k in 0..N {
                if k > i {
                    x -= a[k][i] * y[k];
                }
            }
            y[i] = x;
        }
        for i in 0..N {
            z[self.perm[i]] = y[i];
        }
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn solve_n<const N: usize>(&self, z: &mut [f64; S]) {
        if N > S {
            return;
        }
        let a = &self.a;
        let mut y = [0.0; S];
        for i in 0..N {
            y[i] = z[self.perm[i]];
        }
        for i in 0..N {
            let mut x = y[i];
            for k in 0..N {
                if k < i {
                    x -= a[i][k] * y[k];
                }
            }
            y[i] = x;
        }
        for ii in 0..N {
            let i = N - 1 - ii;
            let mut x = y[i];
            for k in 0..N {
                if k > i {
                    x -= a[i][k] * y[k];
                }
            }
            y[i] = x / a[i][i];
        }
        z[..N].copy_from_slice(&y[..N]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The small dense LU solves `A x = b` and `Aᵀ x = b` (with row exchanges).
    #[test]
    fn dense_lu_solves_and_solves_transposed() {
        let n = 5;
        let mut lu = DenseLu::<6>::new(n);
        for i in 0..n {
            for j in 0..n {
                lu.a[i][j] = if i == j && i == 0 {
                    0.0
                } else {
                    ((i * 5 + j * 3) as f64).sin() + if i == j { 2.0 } else { 0.0 }
                };
            }
        }
        let dense = nalgebra::DMatrix::from_fn(n, n, |i, j| lu.a[i][j]);
        assert!(lu.factor());
        let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        for (m, solve) in [
            (
                dense.clone(),
                DenseLu::<6>::solve as fn(&DenseLu<6>, &mut [f64; 6]),
            ),
            (dense.transpose(), DenseLu::<6>::solve_transposed),
        ] {
            let b = &m * nalgebra::DVector::from_column_slice(&x);
            let mut z = [0.0; 6];
            z[..n].copy_from_slice(b.as_slice());
            solve(&lu, &mut z);
            for i in 0..n {
                assert!(
                    (z[i] - x[i]).abs() <= 1e-12 * 5.0,
                    "{i}: {} vs {}",
                    z[i],
                    x[i]
                );
            }
        }
    }
}
