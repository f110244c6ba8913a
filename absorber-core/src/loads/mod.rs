//! Loads on the arm and real-arm sections: what a scene may add to the paper's uniform
//! cantilever shaken at its base.
//!
//! **Loads** ([`Loads`]): per-sample inputs beside the base acceleration — a vertical force at
//! the beam end (the signal head's aerodynamic force, or a truck gust on it) and a vertical line
//! load on each element (wind on the arm). Positive up \[N, N/m\]. They enter the equations of
//! motion as generalized forces, `r = … − Q_ext`, with the line load's integral
//! `ancf::Element::line_load_force` (the full solver calls the same function) and the
//! tip force on the end node's `r₂`.
//!
//! **Real arms** ([`ArmParams`]): a tapered steel tube (outer diameter linear from root to tip,
//! constant wall) and point masses anywhere along it (signal heads), both fixed for a run. Each
//! element gets its own section properties ([`ArmParams::element`]) and the point masses enter
//! its mass matrix and weight through the Hermite shape functions at their position
//! ([`ArmParams::point_mass_on`]), which is exact for a rigid point mass on the element.
//!
//! **Why a scene wrapper and a separate step call.** The scene decides at compile time what a
//! model stores ([`SceneData`], an associated type of [`crate::Scene`]): the paper's scenes store
//! `()`, so they keep their RAM, flash and arithmetic bit for bit, and `Model::step(base_accel)`
//! is unchanged. [`crate::scene::Loaded`]`<S>` adds the loads ((N + 1) scalars), and
//! [`crate::scene::Arm`]`<S>` adds the loads and one precomputed element per beam element. The
//! loads are passed to [`crate::Model::step_with_loads`] by reference (a zero-order hold: they
//! hold at the end of the step, where Newmark's equations hold, like the base acceleration); a
//! plain `step` on a loaded scene keeps the last loads.

use crate::error::Error;
use crate::params::{BeamParams, Calibration};
use crate::scalar::{is_positive, lit, Real};
use crate::step::ancf::{shape, Element, ElementVector};
use crate::step::beam::Beam;
use core::fmt::Debug;

/// Largest |load| accepted per sample: tip force in N, line load in N/m (a 1 MN force on a
/// traffic arm is a wiring fault, not weather).
pub const MAX_LOAD: f64 = 1.0e6;

/// Most point masses an arm carries (signal heads, sign panels, camera).
pub const MAX_POINT_MASSES: usize = 6;

/// External loads on the beam for one sample, positive up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loads<T, const N: usize> {
    /// Vertical force at the beam end (node N) \[N\].
    pub tip_force: T,
    /// Vertical line load on each element \[N/m\].
    pub line_load: [T; N],
}

impl<T: Real, const N: usize> Default for Loads<T, N> {
    fn default() -> Self {
        Self::zero()
    }
}

impl<T: Real, const N: usize> Loads<T, N> {
    /// No load.
    pub fn zero() -> Self {
        Self {
            tip_force: T::zero(),
            line_load: [T::zero(); N],
        }
    }

    /// A tip force `tip_force` \[N\] and the same line load `line_load` \[N/m\] on every element.
    pub fn uniform(tip_force: T, line_load: T) -> Self {
        Self {
            tip_force,
            line_load: [line_load; N],
        }
    }

    /// Finite and within ±[`MAX_LOAD`] (errors name the input).
    pub fn check(&self) -> Result<(), Error> {
        let max = lit::<T>(MAX_LOAD);
        let all = core::iter::once(&self.tip_force).chain(self.line_load.iter());
        for x in all {
            if !x.is_finite() {
                return Err(Error::NonFiniteInput);
            }
            if x.abs() > max {
                return Err(Error::InputOutOfRange);
            }
        }
        Ok(())
    }
}

/// One point mass on the arm (a signal head) \[m from the root, kg\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointMass<T> {
    /// Distance from the clamp along the undeformed beam \[m\], in \[0, L\].
    pub position: T,
    /// Mass \[kg\] (0: unused slot).
    pub mass: T,
}

/// A tapered circular steel tube with point masses: the section of a traffic-signal mast arm.
///
/// Outer diameter `D(x) = D_root + (D_tip − D_root) x / L`, wall `t`:
/// `A = π t (D − t)`, `I = π (D⁴ − (D − 2t)⁴) / 64` (thin or thick wall, exact for a circular
/// ring). The modulus is the scene's `beam.modulus`; the length `beam.length`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmParams<T> {
    /// Outer diameter at the clamp \[m\].
    pub root_diameter: T,
    /// Outer diameter at the free end \[m\].
    pub tip_diameter: T,
    /// Wall thickness \[m\].
    pub wall: T,
    /// Density of the tube \[kg/m³\] (steel: 7850).
    pub density: T,
    /// Point masses; slots with zero mass are ignored.
    pub point_masses: [PointMass<T>; MAX_POINT_MASSES],
}

impl<T: Real> ArmParams<T> {
    /// Checks the taper and the point masses against the beam length (errors name the field).
    pub fn validate(&self, beam: &BeamParams<T>) -> Result<(), Error> {
        let bad = |field, reason| Err(Error::InvalidParameter { field, reason });
        for (x, field) in [
            (self.root_diameter, "arm.root_diameter"),
            (self.tip_diameter, "arm.tip_diameter"),
            (self.wall, "arm.wall"),
            (self.density, "arm.density"),
        ] {
            if !x.is_finite() || !is_positive(x) {
                return bad(field, "must be finite and positive");
            }
        }
        let two = lit::<T>(2.0);
        if two * self.wall >= self.root_diameter.min(self.tip_diameter) {
            return bad(
                "arm.wall",
                "must be less than half the smaller outer diameter",
            );
        }
        for p in &self.point_masses {
            if !p.mass.is_finite() || p.mass < T::zero() {
                return bad("arm.point_masses.mass", "must be finite and non-negative");
            }
            if !p.position.is_finite() || p.position < T::zero() || p.position > beam.length {
                return bad(
                    "arm.point_masses.position",
                    "must lie on the beam, in [0, beam.length]",
                );
            }
        }
        Ok(())
    }

    /// Outer diameter at `x` \[m\].
    pub fn diameter_at(&self, x: T, length: T) -> T {
        self.root_diameter + (self.tip_diameter - self.root_diameter) * x / length
    }

    /// Area `π t (D − t)` and second moment `π (D⁴ − (D − 2t)⁴) / 64` at `x` \[m², m⁴\].
    pub fn section_at(&self, x: T, length: T) -> (T, T) {
        let d = self.diameter_at(x, length);
        let di = d - lit::<T>(2.0) * self.wall;
        let pi = T::pi();
        let (d2, di2) = (d * d, di * di);
        (
            pi * self.wall * (d - self.wall),
            pi * (d2 * d2 - di2 * di2) / lit::<T>(64.0),
        )
    }

    /// Element `k` of `n` with constant section properties equivalent to the taper over it:
    /// the mean of `ρA` and `EA` (the element's mass and axial compliance to first order) and
    /// the harmonic mean of `EI`, `l / ∫ dx / EI` (the element's rotation under a constant
    /// moment, exactly), by 5-point Gauss over the element (`A` and `I` are polynomials of
    /// degree 1 and 3 in x: exact for the means; `1/EI` to about 1e-8 on a 2:1 taper). Times
    /// the calibration's factors, as [`Element::of_beam`], `EI(x)` times its gradient's
    /// `1 + g (2x/L − 1)` inside the mean (bit for bit the plain section when `g = 0`).
    pub fn element(
        &self,
        beam: &BeamParams<T>,
        calibration: &Calibration<T>,
        k: usize,
        n: usize,
    ) -> Element<T> {
        let l = beam.length / lit::<T>(n as f64);
        let x0 = l * lit::<T>(k as f64);
        let (mut area, mut compliance) = (T::zero(), T::zero());
        let g = calibration.bending_gradient;
        for (xi, w) in crate::step::ancf::GAUSS5 {
            let x = x0 + l * lit::<T>(xi);
            let (a, mut i) = self.section_at(x, beam.length);
            if g != T::zero() {
                i *= T::one() + g * (lit::<T>(2.0) * x / beam.length - T::one());
            }
            area += lit::<T>(w) * a;
            compliance += lit::<T>(w) / i;
        }
        Element {
            length: l,
            axial_rigidity: beam.modulus * area * calibration.axial_stiffness,
            bending_rigidity: beam.modulus / compliance * calibration.bending_stiffness,
            mass_per_length: self.density * area,
        }
    }

    /// The point masses on element `k` of `n` (a mass at a node belongs to the element on its
    /// left, the root's to element 0): their mass matrix `Σ m s(ξ) s(ξ)ᵀ` on the scalar 4×4
    /// pattern (`⊗ I₂` for the two directions) and their weight per unit downward field,
    /// `Σ m s(ξ)` on the vertical coordinates \[kg, kg·m, kg·m²\].
    ///
    /// Each mass has exactly one element, [`owner_element`] of its position, and its `ξ` there
    /// is clamped to `[0, 1]`: a mass at a node (the free end above all) cannot fall between two
    /// elements when `x/l` rounds just past the node (the shipped mast arm's 10 kg sign at the
    /// end, `N = 3`, `f64`: `ξ = 1 + 2.2e-16`). At a node the clamped `ξ` only moves the mass
    /// onto the node, where both neighbours' shape functions agree.
    pub fn point_mass_on(&self, length: T, k: usize, n: usize) -> ([[T; 4]; 4], [T; 4]) {
        let l = length / lit::<T>(n as f64);
        let x0 = l * lit::<T>(k as f64);
        let mut m4 = [[T::zero(); 4]; 4];
        let mut w4 = [T::zero(); 4];
        for p in self.point_masses.iter().filter(|p| is_positive(p.mass)) {
            if owner_element(p.position, length, n) != k {
                continue;
            }
            let xi = ((p.position - x0) / l).max(T::zero()).min(T::one());
            let s = shape(l, xi);
            for ((row, wi), si) in m4.iter_mut().zip(w4.iter_mut()).zip(s.iter()) {
                *wi += p.mass * *si;
                for (mij, sj) in row.iter_mut().zip(s.iter()) {
                    *mij += p.mass * *si * *sj;
                }
            }
        }
        (m4, w4)
    }

    /// Total mass of the tube and point masses \[kg\] (Gauss over the taper).
    pub fn total_mass(&self, length: T) -> T {
        let mut area = T::zero();
        for (xi, w) in crate::step::ancf::GAUSS5 {
            area += lit::<T>(w) * self.section_at(length * lit::<T>(xi), length).0;
        }
        let points = self
            .point_masses
            .iter()
            .fold(T::zero(), |acc, p| acc + p.mass);
        self.density * area * length + points
    }
}

/// Element `k`'s precomputed data of an arm: its own [`Beam`] (mass with the point masses
/// folded in) and the point masses' weight per unit downward field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section<T> {
    /// The element's matrices (point masses included in `mass` and `mass4`).
    pub beam: Beam<T>,
    /// `Σ m s(ξ)` of the point masses on the element, vertical coordinates \[kg, kg·m\].
    pub point_weight: [T; 4],
}

impl<T: Real> Section<T> {
    /// The generalized force of gravity on the element, tube and point masses, under the
    /// downward field `g_eff` (paper eq. 17 plus `−g_eff Σ m s(ξ)` on the vertical rows).
    #[inline]
    pub fn weight(&self, g_eff: T) -> ElementVector<T> {
        let mut w = self.beam.element.gravity_force(g_eff);
        for (i, pw) in self.point_weight.iter().enumerate() {
            if let Some(x) = w.get_mut(2 * i + 1) {
                *x -= g_eff * *pw;
            }
        }
        w
    }
}

/// What a scene stores beyond the paper's model (see the module doc): nothing (`()`), the
/// loads ([`Loads`]), or the loads and per-element sections ([`ArmData`]).
pub trait SceneData<T: Real, const N: usize>:
    Clone + Copy + Debug + PartialEq + Send + Sync + 'static
{
    /// Whether the scene has per-element sections (only then is a bending gradient of the
    /// calibration meaningful).
    const SECTIONS: bool = false;
    /// The data of a model built from the uniform beam `beam`.
    fn uniform(beam: &Beam<T>) -> Self;
    /// The current loads, if the scene has them.
    fn loads(&self) -> Option<&Loads<T, N>>;
    /// The current loads, mutably, if the scene has them.
    fn loads_mut(&mut self) -> Option<&mut Loads<T, N>>;
    /// The per-element sections, if the scene has them.
    fn sections(&self) -> Option<&[Section<T>; N]>;
    /// The per-element sections, mutably, if the scene has them.
    fn sections_mut(&mut self) -> Option<&mut [Section<T>; N]>;
}

impl<T: Real, const N: usize> SceneData<T, N> for () {
    #[inline(always)]
    fn uniform(_: &Beam<T>) -> Self {}
    #[inline(always)]
    fn loads(&self) -> Option<&Loads<T, N>> {
        None
    }
    #[inline(always)]
    fn loads_mut(&mut self) -> Option<&mut Loads<T, N>> {
        None
    }
    #[inline(always)]
    fn sections(&self) -> Option<&[Section<T>; N]> {
        None
    }
    #[inline(always)]
    fn sections_mut(&mut self) -> Option<&mut [Section<T>; N]> {
        None
    }
}

impl<T: Real, const N: usize> SceneData<T, N> for Loads<T, N> {
    fn uniform(_: &Beam<T>) -> Self {
        Self::zero()
    }
    #[inline(always)]
    fn loads(&self) -> Option<&Loads<T, N>> {
        Some(self)
    }
    #[inline(always)]
    fn loads_mut(&mut self) -> Option<&mut Loads<T, N>> {
        Some(self)
    }
    #[inline(always)]
    fn sections(&self) -> Option<&[Section<T>; N]> {
        None
    }
    #[inline(always)]
    fn sections_mut(&mut self) -> Option<&mut [Section<T>; N]> {
        None
    }
}

/// Loads and per-element sections of an arm scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmData<T, const N: usize> {
    /// The current loads.
    pub loads: Loads<T, N>,
    /// One section per element.
    pub sections: [Section<T>; N],
}

impl<T: Real, const N: usize> SceneData<T, N> for ArmData<T, N> {
    const SECTIONS: bool = true;
    fn uniform(beam: &Beam<T>) -> Self {
        Self {
            loads: Loads::zero(),
            sections: [Section {
                beam: *beam,
                point_weight: [T::zero(); 4],
            }; N],
        }
    }
    #[inline(always)]
    fn loads(&self) -> Option<&Loads<T, N>> {
        Some(&self.loads)
    }
    #[inline(always)]
    fn loads_mut(&mut self) -> Option<&mut Loads<T, N>> {
        Some(&mut self.loads)
    }
    #[inline(always)]
    fn sections(&self) -> Option<&[Section<T>; N]> {
        Some(&self.sections)
    }
    #[inline(always)]
    fn sections_mut(&mut self) -> Option<&mut [Section<T>; N]> {
        Some(&mut self.sections)
    }
}

/// The element of `n` on `[0, length]` that holds a point at `position`: `⌈n x / L⌉ − 1`
/// clamped to `0 ..= n − 1`, so a point exactly at a node belongs to the element on its left and
/// the root's to element 0. Counted as the interior nodes `j` below `n x / L` (no float-to-integer
/// conversion and no `f64` arithmetic on an `f32` target).
pub fn owner_element<T: Real>(position: T, length: T, n: usize) -> usize {
    let r = position / length * lit::<T>(n as f64);
    (1..n).filter(|&j| lit::<T>(j as f64) < r).count()
}

/// The sections of an `n`-element arm, one source for the core and the full solver: element
/// `k`'s [`Element`], its mass matrix (blended as the calibration says, plus the point masses
/// on the `⊗ I₂` pattern) and the point weight.
pub fn arm_section<T: Real>(
    arm: &ArmParams<T>,
    beam: &BeamParams<T>,
    calibration: &Calibration<T>,
    damping: T,
    k: usize,
    n: usize,
) -> Section<T> {
    let element = arm.element(beam, calibration, k, n);
    let mut b = Beam::with_lumping(element, damping, calibration.mass_lumping);
    let (m4, w4) = arm.point_mass_on(beam.length, k, n);
    for (i, row) in m4.iter().enumerate() {
        for (j, m) in row.iter().enumerate() {
            if let Some(x) = b.mass4.get_mut(i).and_then(|r| r.get_mut(j)) {
                *x += *m;
            }
            for dir in 0..2 {
                if let Some(x) = b.mass.get_mut((2 * i + dir, 2 * j + dir)) {
                    *x += *m;
                }
            }
        }
    }
    Section {
        beam: b,
        point_weight: w4,
    }
}

impl<T: Real, S: crate::Scene, const N: usize, const D: usize> crate::Model<T, S, N, D> {
    /// Advances one step as [`crate::Model::step`], with the external loads `loads` holding at
    /// the end of the step (with the base acceleration). For scenes that store loads
    /// ([`crate::scene::Loaded`], [`crate::scene::Arm`]); a paper scene returns
    /// `InvalidParameter { field: "loads" }`. Non-finite loads are `NonFiniteInput`, loads
    /// beyond ±[`MAX_LOAD`] `InputOutOfRange`. On error the state and the held loads are
    /// unchanged.
    pub fn step_with_loads(
        &mut self,
        base_accel: T,
        loads: &Loads<T, N>,
    ) -> Result<crate::StepReport<T>, Error> {
        loads.check()?;
        let Some(held) = self.sys.data.loads_mut() else {
            return Err(NO_LOADS);
        };
        let before = core::mem::replace(held, *loads);
        let result = self.step(base_accel);
        if result.is_err() {
            if let Some(held) = self.sys.data.loads_mut() {
                *held = before;
            }
        }
        result
    }

    /// The loads held since the last [`crate::Model::step_with_loads`] (`None` for a scene
    /// without loads).
    pub fn loads(&self) -> Option<&Loads<T, N>> {
        self.sys.data.loads()
    }

    /// Sets the held loads without stepping (e.g. before [`crate::Model::solve_static`], to get
    /// the equilibrium under a steady load). Checked as in `step_with_loads`.
    pub fn set_loads(&mut self, loads: &Loads<T, N>) -> Result<(), Error> {
        loads.check()?;
        let held = self.sys.data.loads_mut().ok_or(NO_LOADS)?;
        *held = *loads;
        self.work.clear();
        Ok(())
    }

    /// Builds the model of a real arm ([`crate::scene::Arm`] scenes): the sections of `arm`
    /// replace the uniform beam of `params.beam` (whose length and modulus are used), in the
    /// undeformed configuration; call [`crate::Model::solve_static`] and
    /// [`crate::Model::restart`] (or use [`crate::Model::arm_at_rest`]) before stepping.
    pub fn with_arm(params: crate::Params<T>, arm: &ArmParams<T>) -> Result<Self, Error> {
        arm.validate(&params.beam)?;
        let mut m = Self::new(params)?;
        let p = m.sys.params;
        let sections = m.sys.data.sections_mut().ok_or(Error::InvalidParameter {
            field: "arm",
            reason: "the scene has no per-element sections (use scene::Arm<S>)",
        })?;
        for (k, sec) in sections.iter_mut().enumerate() {
            *sec = arm_section(
                arm,
                &p.beam,
                &p.calibration,
                p.damping.stiffness_proportional,
                k,
                N,
            );
        }
        Ok(m)
    }

    /// [`crate::Model::with_arm`], then the static equilibrium and a start at rest.
    pub fn arm_at_rest(
        params: crate::Params<T>,
        arm: &ArmParams<T>,
        base_accel: T,
    ) -> Result<Self, Error> {
        let mut m = Self::with_arm(params, arm)?;
        m.solve_static()?;
        m.restart(base_accel)?;
        Ok(m)
    }

    /// Element `k`'s section, for scenes with sections.
    pub fn section(&self, k: usize) -> Option<&Section<T>> {
        self.sys.data.sections().and_then(|s| s.get(k))
    }
}

/// The error of a load call on a scene without loads.
const NO_LOADS: Error = Error::InvalidParameter {
    field: "loads",
    reason: "the scene has no external loads (use scene::Loaded<S> or scene::Arm<S>)",
};

#[cfg(test)]
mod tests;
