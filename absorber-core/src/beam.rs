//! The clamped beam: N uniform ANCF elements assembled into the system unknowns.
//!
//! Unknowns are the displacements of nodes 1..N (4 each, node `n` at rows `4(n−1)..4n`); the
//! root node 0 is clamped in the frame moving with the base (r = (0,0), r′ = (1,0)), so its
//! displacement is identically zero and it is simply left out. Per element `k` (nodes k, k+1):
//!
//! `r_k = M_e ä_k + c K_b u̇_k + K_b u_k + Q_l(u_k) − Q_f(g_eff)`  (paper eqs. 8, 12, 13, 17)
//!
//! and the Newmark tangent `c_m M_e + c_v c K_b + c_q (K_b + K_l(u_k))`.

use crate::ancf::{Element, ElementMatrix, ElementVector};
use crate::scalar::Real;
use crate::tip::Chain;
use nalgebra::{SMatrix, SVector};

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
}

/// Global row of local coordinate `i` (0..8) of element `k`; `None` for the clamped root node.
#[inline]
pub fn global_index(k: usize, i: usize) -> Option<usize> {
    (4 * k + i).checked_sub(4)
}

/// Gathers element `k`'s 8 coordinates from a global vector (root node = 0).
#[inline]
pub fn gather<T: Real, const D: usize>(x: &SVector<T, D>, k: usize) -> ElementVector<T> {
    let mut e = ElementVector::zeros();
    for (i, slot) in e.iter_mut().enumerate() {
        if let Some(v) = global_index(k, i).and_then(|g| x.get(g)) {
            *slot = *v;
        }
    }
    e
}

impl<T: Real> Beam<T> {
    /// Adds the beam's residual and, when `jac` is given, its tangent for all `n` elements.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble<const D: usize>(
        &self,
        n: usize,
        q: &SVector<T, D>,
        v: &SVector<T, D>,
        a: &SVector<T, D>,
        g_eff: T,
        ch: &Chain<T>,
        r: &mut SVector<T, D>,
        mut jac: Option<&mut SMatrix<T, D, D>>,
    ) {
        let weight = self.element.gravity_force(g_eff);
        for k in 0..n {
            let (qe, ve, ae) = (gather(q, k), gather(v, k), gather(a, k));
            let elastic = self.stiffness * (qe + ve * self.damping);
            let (qa, je) = match jac {
                Some(_) => {
                    let (qa, ka) = self.element.axial_force_and_tangent(&qe);
                    let je = self.mass * ch.c_m
                        + self.stiffness * (ch.c_q + ch.c_v * self.damping)
                        + ka * ch.c_q;
                    (qa, Some(je))
                }
                None => (self.element.axial_force(&qe), None),
            };
            let re = self.mass * ae + elastic + qa - weight;
            for i in 0..8 {
                let Some(gi) = global_index(k, i) else {
                    continue;
                };
                if let (Some(dst), Some(src)) = (r.get_mut(gi), re.get(i)) {
                    *dst += *src;
                }
                if let (Some(jac), Some(je)) = (jac.as_deref_mut(), je.as_ref()) {
                    for j in 0..8 {
                        let Some(gj) = global_index(k, j) else {
                            continue;
                        };
                        if let (Some(dst), Some(src)) = (jac.get_mut((gi, gj)), je.get((i, j))) {
                            *dst += *src;
                        }
                    }
                }
            }
        }
    }
}
