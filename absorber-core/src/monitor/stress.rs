//! Root bending moment and bending stress at the clamp, from the ANCF curvature.
//!
//! **Curvature.** At the clamp (x = 0 of element 0) the slope is fixed, r′ = (1, 0), so the
//! signed curvature `κ = (r′ × r″) / |r′|³` reduces exactly to the component of
//! `r″ = S_xx(0) u` normal to the root tangent: **κ = r″_y** \[1/m\]
//! (`ancf::Element::curvature_vector` of element 0 at ξ = 0). Positive κ is concave
//! up (sagging).
//!
//! **Moment** \[N·m\], sagging positive: gravity makes it negative (hogging) at the clamp of the
//! horizontal cantilever. From the curvature, `M = E I κ` (Euler–Bernoulli, the bending term of
//! paper eq. 10).
//!
//! **Stress** at the top fibre, tension positive: `σ = −M c / I` \[Pa\] (`= −E c κ`), with `c`
//! the distance from the neutral axis to the extreme fibre. The top fibre is the one in tension
//! under gravity (where a mast-arm weld toe cracks), so the static stress is positive.
//!
//! **Two estimates** of the root moment ([`MomentEstimate`]):
//!
//! - [`MomentEstimate::Curvature`]: `M = E I r″_y(0)` from element 0. Cubic Hermite elements
//!   give a linear curvature per element, and with the cable's axial Green strain the coarse
//!   mesh is also stiffened by membrane locking (the quartic `½ r₂′²` part of ε cannot be
//!   balanced by the quadratic `r₁′`), so the curvature at the node converges much more slowly
//!   than the displacements: against exact statics it is 5.8 % low in magnitude with N = 3 and
//!   0.15 % with N = 8 (`tests/monitor_stress.rs`), i.e. roughly like l³·⁷, not l².
//! - [`MomentEstimate::Reaction`] (default): the generalized force the clamp exerts on the
//!   slope coordinate r₂′ of node 0, `M = −R₃` with `R = M_e ä + K_b(u + c u̇) + Q_l(u) − Q_f(g_eff)`
//!   of element 0 (the row of the clamped coordinate, which no equation of motion constrains).
//!   A virtual rigid rotation δφ about the clamp moves only that coordinate (δr′ = δφ (0, 1)),
//!   and does no internal work, so `R₃` equals the moment about the clamp of all gravity,
//!   base-inertia and inertial forces of the discrete model: exact statics to the Newton
//!   tolerance for any N, and the consistent dynamic moment. Cost: one row of one element
//!   residual (the axial force of element 0 without its tangent).

use crate::error::Error;
use crate::model::Model;
use crate::params::BeamParams;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::step::ancf::{ElementMatrix, ElementVector};
use crate::step::beam::gather;

/// Section data at the clamp that turns curvature into moment and stress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootSection<T> {
    /// Bending rigidity E·I \[N·m²\].
    pub bending_rigidity: T,
    /// E·c: stress per unit curvature at the extreme fibre \[Pa·m\] (σ = −E c κ).
    pub stress_per_curvature: T,
    /// Distance c from the neutral axis to the extreme fibre \[m\].
    pub extreme_fibre: T,
}

impl<T: Real> RootSection<T> {
    /// Section with the extreme fibre at `extreme_fibre` = c \[m\] from the neutral axis.
    pub fn new(beam: &BeamParams<T>, extreme_fibre: T) -> Result<Self, Error> {
        if !is_positive(extreme_fibre) || !extreme_fibre.is_finite() {
            return Err(Error::InvalidParameter {
                field: "monitor.extreme_fibre",
                reason: "must be finite and positive",
            });
        }
        if !is_positive(beam.modulus) || !is_positive(beam.inertia) {
            return Err(Error::InvalidParameter {
                field: "beam.modulus",
                reason: "E and I must be positive",
            });
        }
        Ok(Self {
            bending_rigidity: beam.modulus * beam.inertia,
            stress_per_curvature: beam.modulus * extreme_fibre,
            extreme_fibre,
        })
    }

    /// The solid rectangle that the beam's area `a` and second moment `I` imply (Table 1:
    /// a = 4.06e-5 m², I = 8.47e-12 m⁴): `b t = a`, `b t³/12 = I` ⇒ `t = √(12 I / a)`
    /// (1.582 mm, b = 25.7 mm), `c = t / 2` (0.791 mm).
    pub fn rectangle(beam: &BeamParams<T>) -> Result<Self, Error> {
        if !is_positive(beam.area) || !is_positive(beam.inertia) {
            return Err(Error::InvalidParameter {
                field: "beam.area",
                reason: "area and inertia must be positive",
            });
        }
        let t = (lit::<T>(12.0) * beam.inertia / beam.area).sqrt();
        Self::new(beam, t * lit::<T>(0.5))
    }

    /// Root bending moment `M = E I κ` \[N·m\], sagging positive.
    pub fn moment(&self, curvature: T) -> T {
        self.bending_rigidity * curvature
    }

    /// Top-fibre bending stress `σ = −E c κ` \[Pa\], tension positive.
    pub fn stress(&self, curvature: T) -> T {
        -self.stress_per_curvature * curvature
    }

    /// Top-fibre bending stress of a moment, `σ = −M c / I` \[Pa\].
    pub fn stress_of_moment(&self, moment: T) -> T {
        -moment * self.stress_per_curvature / self.bending_rigidity
    }

    /// Root moment of the model's current state by `estimate` \[N·m\].
    pub fn root_moment<S: Scene, const N: usize, const D: usize>(
        &self,
        model: &Model<T, S, N, D>,
        estimate: MomentEstimate,
    ) -> T {
        match estimate {
            MomentEstimate::Curvature => self.moment(root_curvature(model)),
            MomentEstimate::Reaction => root_reaction_moment(model),
        }
    }
}

/// How the root moment is obtained (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MomentEstimate {
    /// Clamp reaction on the root slope coordinate: exact statics for any N. Default.
    Reaction,
    /// `E I r″_y` at the root node: converges slowly with N (5.8 % low for N = 3).
    Curvature,
}

/// Root moment from the clamp's generalized reaction on r₂′ of node 0, `M = −R₃` \[N·m\]
/// (sagging positive; see the module doc).
pub fn root_reaction_moment<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
) -> T {
    let s = model.state();
    reaction_moment_at(model, &s.q, &s.v, &s.a, s.base_accel)
}

/// Root reaction moment of the static equilibrium the model started from \[N·m\].
pub fn static_root_moment<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
) -> T {
    let z = nalgebra::SVector::<T, D>::zeros();
    reaction_moment_at(model, model.equilibrium(), &z, &z, T::zero())
}

fn reaction_moment_at<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
    q: &nalgebra::SVector<T, D>,
    v: &nalgebra::SVector<T, D>,
    a: &nalgebra::SVector<T, D>,
    base_accel: T,
) -> T {
    // Only row 3 (r₂′ of node 0) of R = M_e ä + K_b(u + c u̇) + Q_l(u) − Q_f(g_eff): the
    // matrix rows alone, and the axial force without its tangent. Bit-identical to taking
    // row 3 of the full element residual.
    const ROW: usize = 3;
    // Element 0's own matrices and applied force: the paper's uniform beam and its weight, or
    // a real arm's first section with its point masses and line load (`crate::loads`).
    let g_eff = model.params().gravity + base_accel;
    let (b, applied) = model.sys.element_and_force(0, g_eff);
    let (u, v, a) = (gather(q, 0), gather(v, 0), gather(a, 0));
    let at = |x: &ElementVector<T>| x.get(ROW).copied().unwrap_or(T::zero());
    let r = row_times(&b.mass, ROW, &a)
        + row_times(&b.stiffness, ROW, &(u + v * b.damping))
        + at(&b.quadrature.force(&u))
        - at(&applied);
    -r
}

/// Row `i` of `m x`, accumulated column by column as nalgebra's `m * x` does
/// (`y = m₀ x₀`, then `y = mⱼ xⱼ + y`), so it equals `(m * x)[i]` bit for bit. Starting from
/// −0 (the exact additive identity) keeps the sign of a zero first product.
fn row_times<T: Real>(m: &ElementMatrix<T>, i: usize, x: &ElementVector<T>) -> T {
    let mut y = -T::zero();
    for (column, xj) in m.column_iter().zip(x.iter()) {
        if let Some(mij) = column.get(i) {
            y = *mij * *xj + y;
        }
    }
    y
}

/// Signed root curvature κ = r″_y at x = 0 of element 0 \[1/m\] (see the module doc).
pub fn root_curvature<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
) -> T {
    let u = gather(&model.state().q, 0);
    model.sys.beam.element.curvature_vector(&u, T::zero()).y
}

/// Signed root curvature of an arbitrary configuration `q` of `model` (e.g. its static
/// equilibrium) \[1/m\].
pub fn root_curvature_of<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
    q: &nalgebra::SVector<T, D>,
) -> T {
    model
        .sys
        .beam
        .element
        .curvature_vector(&gather(q, 0), T::zero())
        .y
}
