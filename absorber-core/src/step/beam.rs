//! The clamped beam: N uniform ANCF elements assembled into the system unknowns.
//!
//! Unknowns are the displacements of nodes 1..N (4 each, node `n` at rows `4(n−1)..4n`); the
//! root node 0 is clamped in the frame moving with the base (r = (0,0), r′ = (1,0)), so its
//! displacement is identically zero and it is simply left out. Per element `k` (nodes k, k+1):
//!
//! `r_k = M_e ä_k + c K_b u̇_k + K_b u_k + Q_l(u_k) − Q_f(g_eff)`  (paper eqs. 8, 12, 13, 17)
//!
//! and the Newmark tangent `c_m M_e + c_v c K_b + c_q (K_b + K_l(u_k))`.
//!
//! Both directions of the plane share the Hermite shape functions, so `M_e = M₄ ⊗ I₂` and
//! `K_b = K₄ ⊗ I₂` with 4×4 scalar matrices ([`Beam::mass4`], [`Beam::stiffness4`]): the
//! assembly works on those (half the products of the 8×8 forms) and writes straight into the
//! system's residual and Newton matrix (no element matrix is built on the step path).

use crate::scalar::Real;
use crate::step::ancf::{AxialQuadrature, Element, ElementMatrix, ElementVector, TangentBlocks};
use crate::step::linalg::BandMatrix;
use crate::step::scheme::Chain;
use nalgebra::SVector;

/// Precomputed data of the uniform beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam<T> {
    /// One element (all are equal).
    pub element: Element<T>,
    /// Its consistent mass matrix.
    pub mass: ElementMatrix<T>,
    /// Its bending stiffness.
    pub stiffness: ElementMatrix<T>,
    /// Stiffness-proportional damping coefficient \[s\].
    pub damping: T,
    /// `M₄`: `mass = M₄ ⊗ I₂` \[kg, kg·m, kg·m²\].
    pub mass4: [[T; 4]; 4],
    /// `K₄`: `stiffness = K₄ ⊗ I₂`.
    pub stiffness4: [[T; 4]; 4],
    /// The axial terms' Gauss-point data.
    pub quadrature: AxialQuadrature<T>,
}

/// Global row of local coordinate `i` (0..8) of element `k`; `None` for the clamped root node.
#[inline]
pub fn global_index(k: usize, i: usize) -> Option<usize> {
    (4 * k + i).checked_sub(4)
}

/// Gathers element `k`'s 8 coordinates from a global vector (root node = 0). Fixed-size
/// copies (4 or 8 entries), which the compiler inlines: no `memcpy` call per element.
#[inline]
pub fn gather<T: Real, const D: usize>(x: &SVector<T, D>, k: usize) -> ElementVector<T> {
    let mut e = ElementVector::zeros();
    let x = x.as_slice();
    let e_mut = e.as_mut_slice();
    if k == 0 {
        if let (Some(dst), Some(src)) = (
            e_mut.get_mut(4..).and_then(|s| s.first_chunk_mut::<4>()),
            x.first_chunk::<4>(),
        ) {
            *dst = *src;
        }
    } else if let (Some(dst), Some(src)) = (
        e_mut.first_chunk_mut::<8>(),
        x.get(4 * k - 4..).and_then(|s| s.first_chunk::<8>()),
    ) {
        *dst = *src;
    }
    e
}

impl<T: Real> Beam<T> {
    /// The beam of `n` uniform elements of `element`, with damping coefficient `damping` \[s\].
    pub fn new(element: Element<T>, damping: T) -> Self {
        Self::with_lumping(element, damping, T::zero())
    }

    /// As [`Beam::new`], with the mass matrix [`Element::blended_mass_matrix`] of lumped
    /// fraction `lumping` (a calibration; 0 = the consistent mass).
    pub fn with_lumping(element: Element<T>, damping: T, lumping: T) -> Self {
        let mass = element.blended_mass_matrix(lumping);
        let stiffness = element.bending_stiffness();
        let mut mass4 = [[T::zero(); 4]; 4];
        let mut stiffness4 = [[T::zero(); 4]; 4];
        for (i, (mr, kr)) in mass4.iter_mut().zip(stiffness4.iter_mut()).enumerate() {
            for (j, (m, k)) in mr.iter_mut().zip(kr.iter_mut()).enumerate() {
                *m = mass[(2 * i, 2 * j)];
                *k = stiffness[(2 * i, 2 * j)];
            }
        }
        Self {
            element,
            mass,
            stiffness,
            damping,
            mass4,
            stiffness4,
            quadrature: element.axial_quadrature(),
        }
    }

    /// The linear part of the element's Newton matrix per direction, `c_m M₄ + (c_q + c_v c) K₄`
    /// (4×4; the 8×8 block is it `⊗ I₂` plus the axial tangent).
    #[inline]
    fn linear_newton4(&self, ch: &Chain<T>) -> [[T; 4]; 4] {
        let c_k = ch.c_q + ch.c_v * self.damping;
        let mut linear = [[T::zero(); 4]; 4];
        for (lr, (mr, kr)) in linear
            .iter_mut()
            .zip(self.mass4.iter().zip(self.stiffness4.iter()))
        {
            for (l, (m, kk)) in lr.iter_mut().zip(mr.iter().zip(kr.iter())) {
                *l = ch.c_m * *m + c_k * *kk;
            }
        }
        linear
    }

    /// Element `k`'s linear forces `M₄ ä + K₄ (u + c u̇)` per direction plus the axial force,
    /// minus the weight, added into `r`.
    #[inline]
    fn add_element_residual<const D: usize>(
        &self,
        k: usize,
        u: &ElementVector<T>,
        (v, a): (&ElementVector<T>, &ElementVector<T>),
        axial: &ElementVector<T>,
        weight: &ElementVector<T>,
        r: &mut SVector<T, D>,
    ) {
        let c = self.damping;
        for (i, (mrow, krow)) in self.mass4.iter().zip(self.stiffness4.iter()).enumerate() {
            for dir in 0..2 {
                let li = 2 * i + dir;
                // (M ä + K (u + c u̇)) + Q_l − Q_f, summed in this order: the inertia and
                // bending terms first, so that in f32 the large canceling bending forces are
                // summed among themselves before the axial force joins.
                let (mut inertia, mut elastic) = (T::zero(), T::zero());
                for (j, (m, kk)) in mrow.iter().zip(krow.iter()).enumerate() {
                    let lj = 2 * j + dir;
                    if let (Some(uj), Some(vj), Some(aj)) = (u.get(lj), v.get(lj), a.get(lj)) {
                        inertia += *m * *aj;
                        elastic += *kk * (*uj + *vj * c);
                    }
                }
                let sum = (inertia + elastic) + axial.get(li).copied().unwrap_or(T::zero())
                    - weight.get(li).copied().unwrap_or(T::zero());
                if let Some(dst) = global_index(k, li).and_then(|g| r.get_mut(g)) {
                    *dst += sum;
                }
            }
        }
    }

    /// Adds the beam's residual for all `n` elements into `r`.
    pub fn residual<const D: usize>(
        &self,
        n: usize,
        (q, v, a): (&SVector<T, D>, &SVector<T, D>, &SVector<T, D>),
        g_eff: T,
        r: &mut SVector<T, D>,
    ) {
        let weight = self.element.gravity_force(g_eff);
        for k in 0..n {
            let (u, ue, ae) = (gather(q, k), gather(v, k), gather(a, k));
            let axial = self.quadrature.force(&u);
            self.add_element_residual(k, &u, (&ue, &ae), &axial, &weight, r);
        }
    }

    /// Adds element `k`'s residual into `r` with the applied force `applied` (its weight plus
    /// any external load, [`crate::loads`]): one element of [`Beam::residual`] with this
    /// element's own matrices (a real arm's elements differ).
    pub fn element_residual<const D: usize>(
        &self,
        k: usize,
        (q, v, a): (&SVector<T, D>, &SVector<T, D>, &SVector<T, D>),
        applied: &ElementVector<T>,
        r: &mut SVector<T, D>,
    ) {
        let (u, ue, ae) = (gather(q, k), gather(v, k), gather(a, k));
        let axial = self.quadrature.force(&u);
        self.add_element_residual(k, &u, (&ue, &ae), &axial, applied, r);
    }

    /// Adds element `k`'s residual (applied force `applied`) into `r` and its Newton matrix
    /// `(c_m M₄ + (c_q + c_v c) K₄) ⊗ I₂ + c_q K_l` into `jac`: one element of
    /// [`Beam::residual_and_jacobian`] with this element's own matrices.
    #[allow(clippy::too_many_arguments)]
    pub fn element_residual_and_jacobian<const D: usize>(
        &self,
        k: usize,
        (q, v, a): (&SVector<T, D>, &SVector<T, D>, &SVector<T, D>),
        applied: &ElementVector<T>,
        ch: &Chain<T>,
        r: &mut SVector<T, D>,
        jac: &mut BandMatrix<T, D>,
    ) {
        let linear = self.linear_newton4(ch);
        let mut block = [[T::zero(); 8]; 8];
        let (u, ue, ae) = (gather(q, k), gather(v, k), gather(a, k));
        let axial = self
            .quadrature
            .tangent_block(&u, &linear, ch.c_q, &mut block);
        let (first, skip) = if k == 0 { (0, 4) } else { (4 * k - 4, 0) };
        jac.add_block8(first, skip, &block);
        self.add_element_residual(k, &u, (&ue, &ae), &axial, applied, r);
    }

    /// Adds element `k`'s Newton matrix along `ch` into `jac`, the block of
    /// [`Beam::element_residual_and_jacobian`] without the residual, and returns the blocks
    /// of its axial tangent. Where `c_q = 0` (the estimator's `∂r/∂v`) the axial tangent is
    /// left out (`None`): its terms there are `0 · K_l`, and the band holds the same numbers.
    pub fn add_element_jacobian<const D: usize>(
        &self,
        k: usize,
        q: &SVector<T, D>,
        ch: &Chain<T>,
        jac: &mut BandMatrix<T, D>,
    ) -> Option<TangentBlocks<T>> {
        let linear = self.linear_newton4(ch);
        let mut block = [[T::zero(); 8]; 8];
        let mut tangent = None;
        if ch.c_q == T::zero() {
            // `linear ⊗ I₂`: the entries `tangent_block` writes with a zero scale.
            for (rows, lin) in block.chunks_exact_mut(2).zip(linear.iter()) {
                if let [row_x, row_y] = rows {
                    let pairs = row_x.chunks_exact_mut(2).zip(row_y.chunks_exact_mut(2));
                    for ((px, py), l) in pairs.zip(lin.iter()) {
                        if let ([x0, _], [_, y1]) = (px, py) {
                            *x0 = *l;
                            *y1 = *l;
                        }
                    }
                }
            }
        } else {
            let u = gather(q, k);
            let (_, blocks) = self
                .quadrature
                .tangent_block_with(&u, &linear, ch.c_q, &mut block);
            tangent = Some(blocks);
        }
        let (first, skip) = if k == 0 { (0, 4) } else { (4 * k - 4, 0) };
        jac.add_block8(first, skip, &block);
        tangent
    }

    /// Adds the beam's residual into `r` and its Newton matrix along the chain `ch` into `jac`:
    /// per element `(c_m M₄ + (c_q + c_v c) K₄) ⊗ I₂ + c_q K_l`, built as one 8×8 block and
    /// added to the band row by row.
    pub fn residual_and_jacobian<const D: usize>(
        &self,
        n: usize,
        (q, v, a): (&SVector<T, D>, &SVector<T, D>, &SVector<T, D>),
        g_eff: T,
        ch: &Chain<T>,
        r: &mut SVector<T, D>,
        jac: &mut BandMatrix<T, D>,
    ) {
        let weight = self.element.gravity_force(g_eff);
        // The linear part, the same for every element: (c_m M₄ + c_k K₄) ⊗ I₂.
        let linear = self.linear_newton4(ch);
        let mut block = [[T::zero(); 8]; 8];
        for k in 0..n {
            let (u, ue, ae) = (gather(q, k), gather(v, k), gather(a, k));
            let axial = self
                .quadrature
                .tangent_block(&u, &linear, ch.c_q, &mut block);
            // Element k's local row 0 is global row 4k − 4; the root node (k = 0) is clamped.
            let (first, skip) = if k == 0 { (0, 4) } else { (4 * k - 4, 0) };
            jac.add_block8(first, skip, &block);
            self.add_element_residual(k, &u, (&ue, &ae), &axial, &weight, r);
        }
    }
}
