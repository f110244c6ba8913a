//! Structured LU of the full solver's matrices: block tridiagonal with 4 × 4 node blocks, the
//! last node and the bodies' border (tip, ball, spin) as one dense tail block.
//!
//! **Structure.** Unknown `4k + p` belongs to free node `k`; an element couples two
//! neighbouring nodes, so node `k` couples only with `k − 1` and `k + 1`. The border unknowns
//! after the last node (the ball's spin on the track, the flying ball's centre, the bodies of
//! the mass matrix) couple only with the last node and each other. The matrix is stored as the
//! diagonal blocks `D_k`, the blocks `L_k = A[k+1, k]` and `U_k = A[k, k+1]` of the first
//! `m = nodes − 1` nodes, and the tail `T` (last node and border, `s = 4 + border ≤ 10`
//! unknowns), whose coupling with node `m − 1` is the 4 × 4 `L_{m−1}`, `U_{m−1}`.
//!
//! **Factorization.** Gaussian elimination node block by node block, with partial pivoting
//! inside each diagonal block and none across blocks: `S_0 = D_0`, `S_k = P_k⁻¹ L̃_k Ũ_k`
//! (in-block pivoting), `G_k = L_k Ũ_k⁻¹` (the multipliers of the next block's rows),
//! `H_k = L̃_k⁻¹ P_k U_k`, `S_{k+1} = D_{k+1} − G_k H_k`; the tail's Schur complement
//! `T − G_{m−1} H_{m−1}` (top-left 4 × 4) is factored dense with partial pivoting. That is the
//! elimination of the band without row exchanges across nodes, so it costs `O(N)` with fixed
//! 4 × 4 arithmetic (unrolled, no index checks) and allocates nothing.
//!
//! **Why no pivoting across blocks.** The Newmark matrix `c_m M + c_v C + c_q K` is the
//! consistent mass (symmetric positive definite) plus `βh²` times the tangent stiffness (SPD at
//! a stable configuration) plus small unsymmetric velocity and constraint terms; the static
//! matrix is the stiffness of a stable equilibrium. Gaussian elimination without row exchanges
//! is stable for SPD matrices and for matrices close to them (the embedded core's band LU relies
//! on the same, `absorber_core::linalg`): the Schur complements do not grow (for an SPD matrix
//! each entry of `S_{k+1}` is at most the largest diagonal entry of `D_{k+1}`). The multipliers
//! themselves may be large (positions and slopes have different units: at N = 512 a position
//! row's multiplier on a slope pivot is ~`1/l` ≈ 1400), which is harmless. It is checked, not
//! assumed: the largest entry of each Schur complement block (and of the tail's) must stay
//! within `1 / PIVOT_RATIO` = 1000 times the largest entry of its original block (the core's
//! growth bound per step), every pivot finite and nonzero; otherwise [`Matrix::factor`] factors
//! the same values with the kept sparse LU (faer, partial pivoting over the whole column),
//! which stays the reference (docs/full-solver.md).

use super::sparse::{Lu as SparseLu, Order, Pattern};
use absorber_core::linalg::PIVOT_RATIO;
use std::sync::Arc;

/// Largest tail block: the end node and the six body coordinates of the mass matrix.
pub const TAIL: usize = 10;

type Block = [[f64; 4]; 4];

const ZERO: Block = [[0.0; 4]; 4];

/// Where an unknown lives: node block `k`, row `p`; or tail row `t`.
#[derive(Clone, Copy)]
enum Slot {
    Node(usize, usize),
    Tail(usize),
}

/// The block-tridiagonal matrix, its values and its factors (module documentation).
#[derive(Clone, Debug)]
pub struct BlockLu {
    /// Node blocks before the tail.
    m: usize,
    /// Tail size (last node + border).
    s: usize,
    diag: Vec<Block>,
    lower: Vec<Block>,
    upper: Vec<Block>,
    tail: [[f64; TAIL]; TAIL],
    /// In-block LU of `S_k` (rows in pivot order: unit `L̃` below the diagonal, `Ũ` on and
    /// above).
    lu: Vec<Block>,
    /// `1 / Ũ_k[p][p]`.
    inv: Vec<[f64; 4]>,
    /// Pivot order: row `p` of the factors is row `perm[p]` of the block.
    perm: Vec<[usize; 4]>,
    g: Vec<Block>,
    h: Vec<Block>,
    tail_lu: Option<DenseLu<TAIL>>,
    factored: bool,
}

impl BlockLu {
    /// Zero matrix of `4 · nodes + border` unknowns; `None` unless `nodes ≥ 1` and
    /// `4 + border ≤ TAIL`.
    pub fn new(nodes: usize, border: usize) -> Option<Self> {
        let m = nodes.checked_sub(1)?;
        let s = 4 + border;
        if s > TAIL {
            return None;
        }
        Some(Self {
            m,
            s,
            diag: vec![ZERO; m],
            lower: vec![ZERO; m],
            upper: vec![ZERO; m],
            tail: [[0.0; TAIL]; TAIL],
            lu: vec![ZERO; m],
            inv: vec![[0.0; 4]; m],
            perm: vec![[0, 1, 2, 3]; m],
            g: vec![ZERO; m],
            h: vec![ZERO; m],
            tail_lu: None,
            factored: false,
        })
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        4 * self.m + self.s
    }

    fn slot(&self, i: usize) -> Option<Slot> {
        let t = i.checked_sub(4 * self.m);
        match t {
            None => Some(Slot::Node(i / 4, i % 4)),
            Some(t) if t < self.s => Some(Slot::Tail(t)),
            _ => None,
        }
    }

    /// The stored entry (i, j), `None` outside the block structure.
    fn entry_mut(&mut self, i: usize, j: usize) -> Option<&mut f64> {
        let m = self.m;
        match (self.slot(i)?, self.slot(j)?) {
            (Slot::Tail(a), Slot::Tail(b)) => self.tail.get_mut(a)?.get_mut(b),
            (Slot::Node(k, p), Slot::Node(l, q)) => {
                let blk = if k == l {
                    self.diag.get_mut(k)
                } else if l == k + 1 {
                    self.upper.get_mut(k)
                } else if k == l + 1 {
                    self.lower.get_mut(l)
                } else {
                    None
                };
                blk?.get_mut(p)?.get_mut(q)
            }
            (Slot::Node(k, p), Slot::Tail(b)) if k + 1 == m && b < 4 => {
                self.upper.get_mut(k)?.get_mut(p)?.get_mut(b)
            }
            (Slot::Tail(a), Slot::Node(l, q)) if l + 1 == m && a < 4 => {
                self.lower.get_mut(l)?.get_mut(a)?.get_mut(q)
            }
            _ => None,
        }
    }

    /// Entry (i, j) (zero outside the structure).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let m = self.m;
        let v = match (self.slot(i), self.slot(j)) {
            (Some(Slot::Tail(a)), Some(Slot::Tail(b))) => self.tail.get(a).and_then(|r| r.get(b)),
            (Some(Slot::Node(k, p)), Some(Slot::Node(l, q))) => {
                let blk = if k == l {
                    self.diag.get(k)
                } else if l == k + 1 {
                    self.upper.get(k)
                } else if k == l + 1 {
                    self.lower.get(l)
                } else {
                    None
                };
                blk.and_then(|b| b.get(p)).and_then(|r| r.get(q))
            }
            (Some(Slot::Node(k, p)), Some(Slot::Tail(b))) if k + 1 == m && b < 4 => self
                .upper
                .get(k)
                .and_then(|x| x.get(p))
                .and_then(|r| r.get(b)),
            (Some(Slot::Tail(a)), Some(Slot::Node(l, q))) if l + 1 == m && a < 4 => self
                .lower
                .get(l)
                .and_then(|x| x.get(a))
                .and_then(|r| r.get(q)),
            _ => None,
        };
        v.copied().unwrap_or(0.0)
    }

    /// Sets every value to zero (the factors become stale).
    pub fn clear(&mut self) {
        self.diag.fill(ZERO);
        self.lower.fill(ZERO);
        self.upper.fill(ZERO);
        self.tail = [[0.0; TAIL]; TAIL];
        self.factored = false;
    }

    /// Adds `v` to entry (i, j); false if (i, j) is outside the structure (nothing stored).
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> bool {
        self.factored = false;
        match self.entry_mut(i, j) {
            Some(x) => {
                *x += v;
                true
            }
            None => false,
        }
    }

    /// Adds an element's 8 × 8 block: rows/columns 0..4 node `e − 1`, 4..8 node `e` (the
    /// first four skipped for `e = 0`, the clamped root).
    #[inline]
    pub fn add_element(&mut self, e: usize, b: &[[f64; 8]; 8]) -> bool {
        self.factored = false;
        let m = self.m;
        if e > m {
            return false;
        }
        // Adds the quarter of `b` at (r0, c0) into `dst` (4 × 4 window of rows of `dst`).
        fn put<const W: usize>(dst: &mut [[f64; W]], b: &[[f64; 8]; 8], r0: usize, c0: usize) {
            for (row, src) in dst.iter_mut().zip(b.iter().skip(r0)) {
                for (d, s) in row.iter_mut().zip(src.iter().skip(c0).take(4)) {
                    *d += *s;
                }
            }
        }
        if e > 0 {
            let k = e - 1;
            if let Some(d) = self.diag.get_mut(k) {
                put(d, b, 0, 0);
            }
            if let Some(u) = self.upper.get_mut(k) {
                put(u, b, 0, 4);
            }
            if let Some(l) = self.lower.get_mut(k) {
                put(l, b, 4, 0);
            }
        }
        if e < m {
            if let Some(d) = self.diag.get_mut(e) {
                put(d, b, 4, 4);
            }
        } else {
            put(&mut self.tail[..4], b, 4, 4);
        }
        true
    }

    /// Dense copy of the values.
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let n = self.n();
        nalgebra::DMatrix::from_fn(n, n, |i, j| self.get(i, j))
    }

    /// Factors the current values (module documentation); false if a pivot is zero or not
    /// finite, or a Schur complement block grew beyond `1 / PIVOT_RATIO` times its diagonal
    /// block.
    #[allow(clippy::needless_range_loop)] // fixed 4 × 4 arithmetic, by index
    pub fn factor(&mut self) -> bool {
        self.factored = false;
        let growth = 1.0 / PIVOT_RATIO;
        let mut carry = ZERO; // G_{k−1} H_{k−1}
        let blocks = self
            .diag
            .iter()
            .zip(self.lower.iter())
            .zip(self.upper.iter())
            .zip(self.lu.iter_mut())
            .zip(self.inv.iter_mut())
            .zip(self.perm.iter_mut())
            .zip(self.g.iter_mut().zip(self.h.iter_mut()));
        for ((((((d, l), u), lu), inv), perm), (g, h)) in blocks {
            let mut s = *d;
            let (mut big_d, mut big_s) = (0.0f64, 0.0f64);
            for (sr, cr) in s.iter_mut().zip(carry.iter()) {
                for (x, c) in sr.iter_mut().zip(cr.iter()) {
                    big_d = big_d.max(x.abs());
                    *x -= *c;
                    big_s = big_s.max(x.abs());
                }
            }
            // (false for a NaN too)
            let within = big_s <= growth * big_d;
            if !within {
                return false;
            }
            let Some((piv, iv)) = lu4(&mut s) else {
                return false;
            };
            *lu = s;
            *inv = iv;
            *perm = piv;
            // G = L Ũ⁻¹ (row by row: g Ũ = l).
            for (gr, lr) in g.iter_mut().zip(l.iter()) {
                for c in 0..4 {
                    let mut x = lr[c];
                    for k in 0..4 {
                        if k < c {
                            x -= gr[k] * s[k][c];
                        }
                    }
                    gr[c] = x * iv[c];
                }
            }
            // H = L̃⁻¹ P U (column by column).
            for c in 0..4 {
                let mut col = [u[piv[0]][c], u[piv[1]][c], u[piv[2]][c], u[piv[3]][c]];
                for i in 0..4 {
                    for k in 0..4 {
                        if k < i {
                            col[i] -= s[i][k] * col[k];
                        }
                    }
                }
                for (hr, x) in h.iter_mut().zip(col.iter()) {
                    hr[c] = *x;
                }
            }
            // Carry G H to the next diagonal block.
            for (cr, gr) in carry.iter_mut().zip(g.iter()) {
                for (c, x) in cr.iter_mut().enumerate() {
                    *x = gr[0] * h[0][c] + gr[1] * h[1][c] + gr[2] * h[2][c] + gr[3] * h[3][c];
                }
            }
        }
        let mut t = self.tail;
        let (mut big_d, mut big_s) = (0.0f64, 0.0f64);
        for (tr, cr) in t.iter_mut().zip(carry.iter()) {
            for (x, c) in tr.iter_mut().zip(cr.iter()) {
                big_d = big_d.max(x.abs());
                *x -= *c;
                big_s = big_s.max(x.abs());
            }
        }
        let within = big_s <= growth * big_d;
        if !within {
            return false;
        }
        let mut lu = DenseLu::new(self.s);
        lu.a = t;
        self.factored = lu.factor();
        self.tail_lu = Some(lu);
        self.factored
    }

    /// Solves `A x = b` in place with the last factors; false if there are none, `b` has the
    /// wrong length or the result is not finite.
    pub fn solve(&self, b: &mut [f64]) -> bool {
        self.solve_part(b, true)
    }

    /// [`BlockLu::solve`] for the tail's unknowns only (end node and border, the last
    /// `n − 4(nodes − 1)` entries of `b`, the same values bit for bit: the back substitution,
    /// which does not change them, is skipped); the other entries are left intermediate.
    pub fn solve_tail(&self, b: &mut [f64]) -> bool {
        self.solve_part(b, false)
    }

    #[allow(clippy::needless_range_loop)] // fixed 4 × 4 arithmetic, by index
    fn solve_part(&self, b: &mut [f64], back_substitution: bool) -> bool {
        let Some(tail_lu) = self.tail_lu.as_ref().filter(|_| self.factored) else {
            return false;
        };
        if b.len() != self.n() {
            return false;
        }
        let (nodes, tail) = b.split_at_mut(4 * self.m);
        // Forward: y_k = L̃_k⁻¹ P_k (b_k − G_{k−1} y_{k−1}).
        let mut prev = [0.0; 4];
        let mut gprev = &ZERO;
        let fwd = nodes
            .chunks_exact_mut(4)
            .zip(self.lu.iter())
            .zip(self.perm.iter())
            .zip(self.g.iter());
        for (((bk, lu), perm), g) in fwd {
            let mut z = [0.0; 4];
            for (zi, (bi, gr)) in z.iter_mut().zip(bk.iter().zip(gprev.iter())) {
                *zi = *bi - (gr[0] * prev[0] + gr[1] * prev[1] + gr[2] * prev[2] + gr[3] * prev[3]);
            }
            let mut y = [z[perm[0]], z[perm[1]], z[perm[2]], z[perm[3]]];
            for i in 0..4 {
                for k in 0..4 {
                    if k < i {
                        y[i] -= lu[i][k] * y[k];
                    }
                }
            }
            bk.copy_from_slice(&y);
            prev = y;
            gprev = g;
        }
        // Tail: T' x_t = b_t − G_{m−1} y_{m−1} (top four rows).
        let mut z = [0.0; TAIL];
        for (zi, bi) in z.iter_mut().zip(tail.iter()) {
            *zi = *bi;
        }
        if self.m > 0 {
            for (zi, gr) in z.iter_mut().zip(gprev.iter()) {
                *zi -= gr[0] * prev[0] + gr[1] * prev[1] + gr[2] * prev[2] + gr[3] * prev[3];
            }
        }
        tail_lu.solve(&mut z);
        for (bi, zi) in tail.iter_mut().zip(z.iter()) {
            *bi = *zi;
        }
        if !back_substitution {
            return tail.iter().all(|x| x.is_finite());
        }
        // Back: x_k = Ũ_k⁻¹ (y_k − H_k x_{k+1}).
        let mut next = [z[0], z[1], z[2], z[3]];
        let back = nodes
            .chunks_exact_mut(4)
            .zip(self.lu.iter())
            .zip(self.inv.iter())
            .zip(self.h.iter())
            .rev();
        for (((bk, lu), inv), h) in back {
            let mut x = [0.0; 4];
            for (xi, (yi, hr)) in x.iter_mut().zip(bk.iter().zip(h.iter())) {
                *xi = *yi - (hr[0] * next[0] + hr[1] * next[1] + hr[2] * next[2] + hr[3] * next[3]);
            }
            for ii in 0..4 {
                let i = 3 - ii;
                for k in 0..4 {
                    if k > i {
                        x[i] -= lu[i][k] * x[k];
                    }
                }
                x[i] *= inv[i];
            }
            bk.copy_from_slice(&x);
            next = x;
        }
        b.iter().all(|x| x.is_finite())
    }
}

/// In-place LU of a 4 × 4 block with partial pivoting (rows exchanged: the result's row `p`
/// is the input's row `perm[p]`); the pivot order and the pivots' reciprocals, `None` if a
/// pivot is zero or not finite.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // elimination over a fixed 4 × 4 array, by index
fn lu4(a: &mut Block) -> Option<([usize; 4], [f64; 4])> {
    let mut perm = [0, 1, 2, 3];
    let mut inv = [0.0; 4];
    for k in 0..4 {
        let mut p = k;
        let mut big = a[k][k].abs();
        for i in 0..4 {
            let v = a[i][k].abs();
            if i > k && v > big {
                big = v;
                p = i;
            }
        }
        if !(big > 0.0 && big.is_finite()) {
            return None;
        }
        if p != k {
            a.swap(p, k);
            perm.swap(p, k);
        }
        let r = 1.0 / a[k][k];
        inv[k] = r;
        let pivot_row = a[k];
        for (i, row) in a.iter_mut().enumerate() {
            if i > k {
                let l = row[k] * r;
                row[k] = l;
                for c in 0..4 {
                    if c > k {
                        row[c] -= l * pivot_row[c];
                    }
                }
            }
        }
    }
    Some((perm, inv))
}

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

    /// A block-tridiagonal matrix with a border (the shape of the full solver's matrices),
    /// diagonally weighted so that no pivoting across blocks is needed but some inside the
    /// blocks is (zero diagonal entries): the block solve equals nalgebra's dense LU, and the
    /// sparse reference agrees.
    #[test]
    fn block_lu_matches_dense_lu() {
        for (nodes, border) in [(1usize, 0usize), (2, 1), (7, 0), (9, 1), (6, 3), (5, 6)] {
            let n = 4 * nodes + border;
            let m = nodes - 1;
            let node = |i: usize| (i / 4).min(m);
            let entry = |i: usize, j: usize| -> Option<f64> {
                let tail = |x: usize| x >= 4 * m;
                let coupled = if tail(i) && tail(j) {
                    true
                } else {
                    node(i).abs_diff(node(j)) <= 1 && i < 4 * m + 4 && j < 4 * m + 4
                };
                if !coupled {
                    return None;
                }
                let v = ((i * 7 + j * 3) as f64).sin() + 0.1;
                Some(if i == j {
                    if i.is_multiple_of(4) {
                        0.0
                    } else {
                        20.0 + v
                    }
                } else if i / 4 == j / 4 && i.min(j).is_multiple_of(4) && i.abs_diff(j) == 1 {
                    15.0 // the zero diagonal needs an in-block exchange
                } else {
                    v
                })
            };
            let entries: Vec<(usize, usize)> = (0..n)
                .flat_map(|i| (0..n).map(move |j| (i, j)))
                .filter(|&(i, j)| entry(i, j).is_some())
                .collect();
            for linear in [Linear::Block, Linear::Sparse] {
                let mut a =
                    Matrix::new(nodes, border, entries.iter().copied(), linear).expect("shape");
                for &(i, j) in &entries {
                    assert!(a.add(i, j, entry(i, j).unwrap_or(0.0)));
                }
                let dense = a.to_dense();
                let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
                let b = &dense * nalgebra::DVector::from_column_slice(&x);
                let xd = dense.clone().lu().solve(&b).expect("regular");
                assert!(a.factor());
                assert_eq!(a.fallbacks(), 0);
                let mut y = b.as_slice().to_vec();
                assert!(a.solve(&mut y));
                // The tail-only solve: the same tail, bit for bit.
                let mut t = b.as_slice().to_vec();
                assert!(a.solve_tail(&mut t));
                let t0 = 4 * (nodes - 1);
                assert_eq!(t[t0..], y[t0..], "{nodes} {border} {linear:?}");
                for i in 0..n {
                    assert!(
                        (y[i] - xd[i]).abs() <= 1e-12 * xd.amax(),
                        "{nodes} {border} {linear:?} {i}: {} vs {}",
                        y[i],
                        xd[i]
                    );
                }
            }
        }
    }

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
