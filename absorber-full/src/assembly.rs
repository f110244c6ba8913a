//! Assembly: the elements' forces and Newton blocks, the constant mass matrix's factor, the
//! right-hand side of the augmented system (22), its Schur complement on the local constraints,
//! and the residual `Bᵀ M B δ` of the independent accelerations with its Newton matrix.

use super::dense::DenseLu;
use super::kin::{Bodies, Mode, MC, NW, RB2, RT2};
use super::matrix::{Linear, Matrix};
use super::partition::Kin;
use super::FullSolver;
use absorber_core::shared::Chain;
use absorber_core::shared::{AxialQuadrature, Element, ElementMatrix, ElementVector};
use absorber_core::Error;

pub(super) struct Evaluated {
    pub(super) r: Vec<f64>,
    pub(super) kin: Kin,
    pub(super) lambda_local: [f64; MC],
}

/// The constant part of the augmented system (22): the LU of the free-coordinate mass matrix
/// `M_f` (beam nodes 1..N, then the bodies; index `z − 4`), `M_f⁻¹ e_j` for the local
/// coordinates j present, and their 10 × 10 block `P = E_locᵀ M_f⁻¹ E_loc`.
#[derive(Clone, Debug)]
pub(super) struct MassFactor {
    pub(super) lu: Matrix,
    /// `M_f⁻¹ e_{zloc(j) − 4}`, column `j` at `j·n_f`, zero for absent local coordinates.
    pub(super) cols: Vec<f64>,
    pub(super) p_loc: [[f64; NW]; NW],
    /// Scratch of length `n_f` (the force, then the accelerations).
    pub(super) f: Vec<f64>,
    /// Scratch of length `n_z`: `B δ` and `M B δ` of the residual.
    pub(super) y: Vec<f64>,
    pub(super) my: Vec<f64>,
}

/// `M₄` if `m = M₄ ⊗ I₂` exactly (the ANCF cable's mass and bending matrices are).
pub(super) fn kron4(m: &ElementMatrix<f64>) -> Option<[[f64; 4]; 4]> {
    let mut k = [[0.0; 4]; 4];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            let (a, b) = (2 * i, 2 * j);
            let v = m[(a, b)];
            if m[(a + 1, b + 1)] != v || m[(a, b + 1)] != 0.0 || m[(a + 1, b)] != 0.0 {
                return None;
            }
            *x = v;
        }
    }
    Some(k)
}

pub(super) type Block4 = [[f64; 4]; 4];

/// `(B ⊗ I₂) x` for an element's 8 coordinates (`x` of length 8; nodes' `(x, y)` pairs)
/// without the zero entries of the Kronecker form: entry `2p + d` is `Σ_q B[p][q] x[2q + d]`,
/// summed in `q` order (the element mass and bending matrices are `M₄ ⊗ I₂`, `K₄ ⊗ I₂`).
pub(super) fn kron_i2(b: &Block4, x: &[f64]) -> [f64; 8] {
    let mut r = [0.0; 8];
    for (rp, row) in r.chunks_exact_mut(2).zip(b.iter()) {
        for (d, rd) in rp.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (c, xq) in row.iter().zip(x.chunks_exact(2)) {
                acc += c * xq[d];
            }
            *rd = acc;
        }
    }
    r
}

/// Constants of one element's assembly: the axial quadrature, and `(M₄, K₄)` when the mass
/// and bending matrices are `M₄ ⊗ I₂`, `K₄ ⊗ I₂` exactly (then the Newton block is built in
/// that form, the same sums: [`absorber_core::shared::AxialQuadrature::tangent_block`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct ElementConst {
    pub(super) quad: AxialQuadrature<f64>,
    pub(super) kron: Option<(Block4, Block4)>,
}

impl ElementConst {
    pub(super) fn of(
        element: &Element<f64>,
        me: &ElementMatrix<f64>,
        kb: &ElementMatrix<f64>,
    ) -> Self {
        Self {
            quad: element.axial_quadrature(),
            kron: kron4(me).zip(kron4(kb)),
        }
    }
}

/// Solves the leading `m × m` system of `a` for `b` (the rest of `b` zero); `None` if it is
/// singular or the result not finite.
pub(super) fn small_solve(a: [[f64; MC]; MC], m: usize, mut b: [f64; MC]) -> Option<[f64; MC]> {
    let mut lu = DenseLu::new(m);
    lu.a = a;
    if !lu.factor() {
        return None;
    }
    lu.solve(&mut b);
    b.iter().all(|v| v.is_finite()).then_some(b)
}

impl FullSolver {
    /// Element `e`'s assembly constants.
    pub(super) fn element_const(&self, e: usize) -> &ElementConst {
        let k = if self.consts.len() == 1 { 0 } else { e };
        &self.consts[k.min(self.consts.len() - 1)]
    }

    /// Element `e`'s properties, mass and bending stiffness matrices.
    pub(super) fn element_of(
        &self,
        e: usize,
    ) -> (&Element<f64>, &ElementMatrix<f64>, &ElementMatrix<f64>) {
        match &self.arm {
            Some(sec) => {
                let b = &sec[e].beam;
                (&b.element, &b.mass, &b.stiffness)
            }
            None => (&self.element, &self.me, &self.kb),
        }
    }

    /// Assembles and factors the free-coordinate mass matrix `M_f` (consistent beam mass of
    /// nodes 1..N, `diag(m_t, m_t, J_t, J_b, m_b, m_b)`), and solves it for the unit vectors of
    /// the local coordinates (end node, bodies).
    pub(super) fn mass_factor<'m>(
        n: usize,
        n_body: usize,
        me_of: impl Fn(usize) -> &'m ElementMatrix<f64>,
        bodies: &Bodies,
        linear: Linear,
    ) -> Result<MassFactor, Error> {
        let nf = 4 * n + n_body;
        // Element e couples z = 4e..4e+8, i.e. free indices 4e−4..4e+4 (root node dropped).
        let beam = (0..n).flat_map(|e| {
            (0..64).filter_map(move |k| {
                let (i, j) = (
                    (4 * e + k / 8).checked_sub(4)?,
                    (4 * e + k % 8).checked_sub(4)?,
                );
                Some((i, j))
            })
        });
        let diag = (4 * n..nf).map(|i| (i, i));
        let mut lu = Matrix::new(n, n_body, beam.chain(diag), linear).ok_or(Error::Singular)?;
        for e in 0..n {
            let me = me_of(e);
            for i in 0..8 {
                for j in 0..8 {
                    if let (Some(a), Some(b)) =
                        ((4 * e + i).checked_sub(4), (4 * e + j).checked_sub(4))
                    {
                        lu.add(a, b, me[(i, j)]);
                    }
                }
            }
        }
        for jb in 0..n_body {
            lu.add(4 * n + jb, 4 * n + jb, bodies.mass[4 + jb]);
        }
        if !lu.factor() {
            return Err(Error::Singular);
        }
        // Free index of local coordinate j (end node, then bodies), if present.
        let floc = |j: usize| -> Option<usize> {
            if j < 4 {
                Some(4 * n - 4 + j)
            } else if j - 4 < n_body {
                Some(4 * n + j - 4)
            } else {
                None
            }
        };
        let mut cols = vec![0.0; NW * nf];
        for j in 0..NW {
            if let Some(fj) = floc(j) {
                let col = &mut cols[j * nf..(j + 1) * nf];
                col[fj] = 1.0;
                if !lu.solve(col) {
                    return Err(Error::Singular);
                }
            }
        }
        let mut p_loc = [[0.0; NW]; NW];
        for (i, row) in p_loc.iter_mut().enumerate() {
            if let Some(fi) = floc(i) {
                for (j, pij) in row.iter_mut().enumerate() {
                    *pij = cols[j * nf + fi];
                }
            }
        }
        Ok(MassFactor {
            lu,
            cols,
            p_loc,
            f: vec![0.0; nf],
            y: vec![0.0; nf + 4],
            my: vec![0.0; nf + 4],
        })
    }

    /// The reduced Newton matrix for `ni` independent unknowns (pattern and symbolic analysis
    /// made on first use): element blocks of the free beam coordinates and the local block —
    /// dense over the end node and φ on the track; in flight the end node's block and the
    /// diagonal of the ball's `(φ, R_b1, R_b2)`, whose rows are their masses alone (no
    /// constraint couples them to the housing), so the band stays that of the beam.
    pub(super) fn reduced_lu<'w>(
        &self,
        slots: &'w mut [Option<Matrix>; 3],
        ni: usize,
    ) -> Result<&'w mut Matrix, Error> {
        let k = match ni.checked_sub(4 * self.n) {
            Some(0) => 0,
            Some(1) => 1,
            Some(3) => 2,
            _ => return Err(Error::Singular),
        };
        let slot = slots.get_mut(k).ok_or(Error::Singular)?;
        if slot.as_ref().map(Matrix::n) != Some(ni) {
            let n = self.n;
            let loc0 = 4 * n - 4;
            let beam = (0..n).flat_map(|e| {
                (0..64).filter_map(move |k| {
                    let (i, j) = (
                        (4 * e + k / 8).checked_sub(4)?,
                        (4 * e + k % 8).checked_sub(4)?,
                    );
                    Some((i, j))
                })
            });
            let nl = ni - loc0;
            let dense = if nl == 7 { 4 } else { nl };
            let local = (0..dense * dense)
                .map(move |k| (loc0 + k / dense, loc0 + k % dense))
                .chain((dense..nl).map(move |k| (loc0 + k, loc0 + k)));
            let mat = Matrix::new(n, ni - 4 * n, beam.chain(local), self.linear)
                .ok_or(Error::Singular)?;
            *slot = Some(mat);
        }
        slot.as_mut().ok_or(Error::Singular)
    }

    /// The beam's part of the right-hand side of (22) on the free coordinates (element forces
    /// and weights, into `f`), and with `jac` the elements' Newton blocks added into the matrix.
    #[inline(never)]
    pub(super) fn element_forces(
        &self,
        f: &mut [f64],
        mut jac: Option<(&mut Matrix, &Chain<f64>)>,
        qi: &[f64],
        vi: &[f64],
        g_eff: f64,
    ) {
        let n = self.n;
        let weight = self.element.gravity_force(g_eff);
        let damp = self.params.damping.stiffness_proportional;
        let line = self.loads.as_ref().map(|(_, w)| w);
        for e in 0..n {
            // Element e's coordinates: z indices 4e..4e+8, free index z − 4 (root node zero).
            let (lo, skip) = if e == 0 { (0, 4) } else { (4 * e - 4, 0) };
            let gather = |x: &[f64]| {
                let mut u = [0.0; 8];
                for (d, s) in u.iter_mut().skip(skip).zip(x.iter().skip(lo)) {
                    *d = *s;
                }
                ElementVector::<f64>::from(u)
            };
            let (u, ud) = (gather(qi), gather(vi));
            let (element, me, kb) = self.element_of(e);
            let ec = self.element_const(e);
            // Axial force, and with the matrix the element's Newton block
            // `c_m M + (c_q + c_v c) K_t + c_q K_l` (the same sums as the dense form).
            let ql = match jac.as_mut() {
                None => ec.quad.force(&u),
                Some((jb, c)) => {
                    let mut block = [[0.0; 8]; 8];
                    let ql = match &ec.kron {
                        Some((m4, k4)) => {
                            let c_k = c.c_q + c.c_v * damp;
                            let mut linear = [[0.0; 4]; 4];
                            for (lr, (mr, kr)) in linear.iter_mut().zip(m4.iter().zip(k4.iter())) {
                                for (l, (m, k)) in lr.iter_mut().zip(mr.iter().zip(kr.iter())) {
                                    *l = *m * c.c_m + *k * c_k;
                                }
                            }
                            ec.quad.tangent_block(&u, &linear, c.c_q, &mut block)
                        }
                        None => {
                            let mut kl = ElementMatrix::<f64>::zeros();
                            let ql = ec.quad.tangent(&u, |r, col, v| {
                                if let Some(t) = kl.get_mut((r, col)) {
                                    *t = v;
                                }
                            });
                            let je = me * c.c_m + kb * (c.c_q + c.c_v * damp) + kl * c.c_q;
                            for (i, row) in block.iter_mut().enumerate() {
                                for (j, x) in row.iter_mut().enumerate() {
                                    *x = je[(i, j)];
                                }
                            }
                            ql
                        }
                    };
                    // Element e couples free nodes e − 1 and e (the root node is clamped).
                    jb.add_element(e, &block);
                    ql
                }
            };
            let mut applied = match &self.arm {
                Some(sec) => sec[e].weight(g_eff),
                None => weight,
            };
            if let Some(w) = line {
                applied += element.line_load_force(w[e]);
            }
            let uc = u + ud * damp;
            let kbu = match &ec.kron {
                // K_t (u + c u̇) without the zero entries of K₄ ⊗ I₂ (the same sums).
                Some((_, k4)) => ElementVector::<f64>::from(kron_i2(k4, uc.as_slice())),
                None => kb * uc,
            };
            let fe = applied - kbu - ql;
            for (fi, x) in f.iter_mut().skip(lo).zip(fe.iter().skip(skip)) {
                *fi += x;
            }
        }
    }

    /// Residual (and, with `jac`, the Newton matrix `∂r/∂x` for the chain, assembled into the
    /// given matrix, not factored) at independent positions, velocities and accelerations.
    /// `warm` carries the dependent positions between calls. The residual does not depend on
    /// whether the matrix is assembled (bit for bit).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn evaluate(
        &self,
        mass: &mut MassFactor,
        jac: Option<(&mut Matrix, &Chain<f64>)>,
        qi: &[f64],
        vi: &[f64],
        ai: &[f64],
        g_eff: f64,
        mode: Mode,
        warm: &mut [f64; NW],
        theta_ref: f64,
    ) -> Result<Evaluated, Error> {
        self.evaluate_with(mass, jac, qi, vi, ai, g_eff, mode, warm, theta_ref, true)
    }

    /// [`FullSolver::evaluate`]; without `residual` only the local kinematics and the
    /// multipliers (`r` empty: [`FullSolver::multipliers`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn evaluate_with(
        &self,
        mass: &mut MassFactor,
        jac: Option<(&mut Matrix, &Chain<f64>)>,
        qi: &[f64],
        vi: &[f64],
        ai: &[f64],
        g_eff: f64,
        mode: Mode,
        warm: &mut [f64; NW],
        theta_ref: f64,
        residual: bool,
    ) -> Result<Evaluated, Error> {
        let n = self.n;
        let nz = self.nz;
        let ni = self.n_ind(mode);
        let loc0 = 4 * n - 4;
        let kin = if residual {
            self.local_kin(mode, &qi[loc0..], &vi[loc0..], warm, theta_ref)?
        } else {
            self.local_kin_no_bd(mode, &qi[loc0..], &vi[loc0..], warm, theta_ref)?
        };
        *warm = kin.w;
        let m = mode.m();
        let mut jac = jac;
        if let Some((jb, _)) = jac.as_mut() {
            if jb.n() != ni {
                return Err(Error::Singular);
            }
            jb.clear();
        }
        // Right-hand side of (22) on the free coordinates (index z − 4): element forces and
        // weights; the root node's rows only feed the clamp multipliers, which are not needed.
        let nf = nz - 4;
        let f = &mut mass.f;
        f.fill(0.0);
        let tip_force = self.loads.as_ref().map_or(0.0, |(p, _)| *p);
        self.element_forces(
            f,
            jac.as_mut().map(|(jb, c)| (&mut **jb, *c)),
            qi,
            vi,
            g_eff,
        );
        let b0 = self.b0();
        let (mt, mb) = self.bodies.weights;
        if tip_force != 0.0 {
            f[4 * n - 3] += tip_force;
        }
        if self.n_body >= 3 {
            f[self.zloc(RT2) - 4] -= mt * g_eff;
        }
        if self.n_body >= 6 {
            f[self.zloc(RB2) - 4] -= mb * g_eff;
        }
        // u = M_f⁻¹ f; then the Schur complement of the local constraints (module docs). The
        // multipliers alone need u on the local coordinates only, the tail of the block LU.
        let solved = if residual {
            mass.lu.solve(f)
        } else {
            mass.lu.solve_tail(f)
        };
        if !solved {
            return Err(Error::Singular);
        }
        let present = |j: usize| j < 4 || j - 4 < self.n_body;
        let mut lambda_local = [0.0; MC];
        if m > 0 {
            let g = &kin.cons.grad;
            let mut s = [[0.0; MC]; MC];
            let mut rhs = [0.0; MC];
            for k in 0..m {
                let mut gp = [0.0; NW];
                for (j, gpj) in gp.iter_mut().enumerate() {
                    *gpj = (0..NW).map(|i| g[k][i] * mass.p_loc[i][j]).sum();
                }
                for l in 0..m {
                    s[k][l] = (0..NW).map(|j| gp[j] * g[l][j]).sum();
                }
                rhs[k] = (0..NW)
                    .filter(|&j| present(j))
                    .map(|j| g[k][j] * f[self.zloc(j) - 4])
                    .sum::<f64>()
                    + kin.cons.quad[k];
            }
            let lam = small_solve(s, m, rhs).ok_or(Error::Singular)?;
            for j in (0..NW).filter(|&j| present(j) && residual) {
                let gl: f64 = (0..m).map(|k| g[k][j] * lam[k]).sum();
                if gl != 0.0 {
                    let col = &mass.cols[j * nf..(j + 1) * nf];
                    f.iter_mut().zip(col.iter()).for_each(|(a, c)| *a -= gl * c);
                }
            }
            for (k, l) in lambda_local.iter_mut().enumerate().take(m) {
                *l = lam[k];
            }
        }
        if !residual {
            return Ok(Evaluated {
                r: Vec::new(),
                kin,
                lambda_local,
            });
        }
        // z̈ (root node clamped at rest).
        let zdd = |z: usize| if z < 4 { 0.0 } else { f[z - 4] };
        // r = Bᵀ M B δ with δ = x − q̈_i(augmented), y = B δ (kept scratch vectors of length nz).
        let (y, my) = (&mut mass.y, &mut mass.my);
        y.fill(0.0);
        let nb = 4 * n;
        for (yi, (a, fi)) in y.iter_mut().skip(4).zip(ai.iter().zip(f.iter())).take(nb) {
            *yi = a - fi;
        }
        for (i, a) in ai.iter().enumerate().skip(nb) {
            let z = self.ind_to_z(i);
            y[z] = a - zdd(z);
        }
        let dep = mode.dependent();
        for (row, &j) in dep.iter().enumerate() {
            y[self.zloc(j)] = (0..mode.independent().len())
                .map(|k| kin.bd[row][k] * y[self.ind_to_z(loc0 + k)])
                .sum();
        }
        my.fill(0.0);
        for e in 0..n {
            let ye = &y[4 * e..4 * e + 8];
            match &self.element_const(e).kron {
                // The same sums without the zero entries of M₄ ⊗ I₂ (exactly the same values).
                Some((m4, _)) => {
                    let mye = &mut my[4 * e..4 * e + 8];
                    for (m, r) in mye.iter_mut().zip(kron_i2(m4, ye)) {
                        *m += r;
                    }
                }
                None => {
                    let me = self.element_of(e).1;
                    for i in 0..8 {
                        let mut s = 0.0;
                        for (j, yj) in ye.iter().enumerate() {
                            s += me[(i, j)] * yj;
                        }
                        my[4 * e + i] += s;
                    }
                }
            }
        }
        for jb in 0..self.n_body {
            my[b0 + jb] += self.bodies.mass[4 + jb] * y[b0 + jb];
        }
        let mut r: Vec<f64> = Vec::with_capacity(ni);
        r.extend_from_slice(&my[4..4 + nb]);
        r.extend((nb..ni).map(|i| my[self.ind_to_z(i)]));
        for k in 0..mode.independent().len() {
            r[loc0 + k] += dep
                .iter()
                .enumerate()
                .map(|(row, &j)| kin.bd[row][k] * my[self.zloc(j)])
                .sum::<f64>();
        }
        // Tip/ball block of the Newton matrix: the core's exact local Jacobian (module docs). A
        // flying ball's rows are `m c_m` on its own coordinates (its mass, no constraint):
        // entered exactly; the block covers the end node's columns and rows only.
        if let Some((jb, c)) = jac.as_mut() {
            let nl = mode.independent().len();
            let coupled = if mode == Mode::Flying {
                for (k, &j) in mode.independent().iter().enumerate().skip(4) {
                    jb.add(loc0 + k, loc0 + k, self.bodies.mass[j] * c.c_m);
                }
                4
            } else {
                nl
            };
            if m > 0 {
                let (ql, vl, al) = (&qi[loc0..], &vi[loc0..], &ai[loc0..]);
                let block = match self.tip_block(mode, ql, vl, al, c, g_eff) {
                    Some(b) => b,
                    None => {
                        self.tip_block_differences(&kin, mode, ql, vl, al, c, g_eff, theta_ref)?
                    }
                };
                for (row, br) in block.iter().enumerate().take(coupled) {
                    for (k, x) in br.iter().enumerate().take(coupled) {
                        jb.add(loc0 + row, loc0 + k, *x);
                    }
                }
            }
        }
        Ok(Evaluated {
            r,
            kin,
            lambda_local,
        })
    }
}
