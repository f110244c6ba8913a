//! Root bending moment and bending stress at the clamp, from the ANCF curvature.
//!
//! **Curvature.** At the clamp (x = 0 of element 0) the slope is fixed, r′ = (1, 0), so the
//! signed curvature `κ = (r′ × r″) / |r′|³` reduces exactly to the component of
//! `r″ = S_xx(0) u` normal to the root tangent: **κ = r″_y** \[1/m\]
//! ([`crate::ancf::Element::curvature_vector`] of element 0 at ξ = 0). Positive κ is concave
//! up (sagging).
//!
//! **Moment** `M = E I κ` \[N·m\] (Euler–Bernoulli, the bending term of paper eq. 10), sagging
//! positive: gravity makes it negative (hogging) at the clamp of the horizontal cantilever.
//!
//! **Stress** at the top fibre, tension positive: `σ = −M c / I = −E c κ` \[Pa\], with `c` the
//! distance from the neutral axis to the extreme fibre. The top fibre is the one in tension
//! under gravity (where a mast-arm weld toe cracks), so the static stress is positive.
//!
//! **Accuracy.** Cubic Hermite elements reproduce the nodal displacements of Euler–Bernoulli
//! statics exactly, but their curvature is linear in each element, so under a distributed load
//! `q` the node value misses the element's fixed-end moment `q l²/12` (l = L/N): at the root the
//! model's |M| is low by `μ g_eff l² / 12` (paper scene: 0.57 % of the static moment for N = 3,
//! 0.08 % for N = 8). Tip loads (linear moment) are exact. The displacements converge faster
//! than this end-of-element curvature, which is why the test tolerance scales with l².

use crate::beam::gather;
use crate::error::Error;
use crate::model::Model;
use crate::params::BeamParams;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;

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
}

/// Signed root curvature κ = r″_y at x = 0 of element 0 \[1/m\] (see the module doc).
pub fn root_curvature<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
) -> T {
    let u = gather(&model.state().q, 0);
    model.beam.element.curvature_vector(&u, T::zero()).y
}

/// Signed root curvature of an arbitrary configuration `q` of `model` (e.g. its static
/// equilibrium) \[1/m\].
pub fn root_curvature_of<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &Model<T, S, N, D>,
    q: &nalgebra::SVector<T, D>,
) -> T {
    model
        .beam
        .element
        .curvature_vector(&gather(q, 0), T::zero())
        .y
}
