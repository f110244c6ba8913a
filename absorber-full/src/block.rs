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
//! **Why no pivoting across blocks.** The Newmark matrix `c_m M + c_v C + c_q K` is the consistent
//! mass (symmetric positive definite) plus `βh²` times the tangent stiffness (SPD at a stable
//! configuration) plus small unsymmetric velocity and constraint terms; the static matrix is the
//! stiffness of a stable equilibrium. Gaussian elimination without row exchanges is stable for SPD
//! matrices and for matrices close to them (the embedded core's band LU relies on the same,
//! `absorber-core/src/step/linalg`): the Schur complements do not grow (for an SPD matrix each entry of
//! `S_{k+1}` is at most the largest diagonal entry of `D_{k+1}`). The multipliers themselves may be
//! large (positions and slopes have different units: at N = 512 a position row's multiplier on a
//! slope pivot is ~`1/l` ≈ 1400), which is harmless. It is checked, not assumed: the largest entry
//! of each Schur complement block (and of the tail's) must stay within `1 / PIVOT_RATIO` = 1000
//! times the largest entry of its original block (the core's growth bound per step), every pivot
//! finite and nonzero; otherwise [`Matrix::factor`](super::matrix::Matrix::factor) factors the same
//! values with the kept sparse LU (faer, partial pivoting over the whole column), which stays the
//! reference (docs/full-solver.md).

use super::dense::DenseLu;
use absorber_core::shared::PIVOT_RATIO;

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

#[cfg(test)]
mod tests {
    use crate::matrix::{Linear, Matrix};

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
}
