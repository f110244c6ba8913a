//! The full solver of the paper (§§2–4): maximal coordinates, constraints with Lagrange
//! multipliers, Wehage coordinate partitioning, Newmark with Newton–Raphson.
//!
//! **Coordinates** (`z`, in the frame translating with the base): the displacements of all
//! beam nodal coordinates from the straight reference, root node included (`4(N+1)`), then the
//! tip mass `(R_t1, R_t2, ψ)` and the ball `(φ, R_b1, R_b2)` (scenes without them leave them
//! out). The mass matrix is constant: the beam's consistent mass, `diag(m_t, m_t, J_t)`,
//! `diag(J_b, m_b, m_b)`. Forces: the element forces of [`absorber_core::shared::Element`] (the one
//! source of the element integrals), the weights under the effective gravity `g + ÿ_b`.
//!
//! **Constraints** `C(z) = 0`: the clamp of the root node (4), the fixed joint (eq. 25: 3, with
//! `atan2`), the rolling contact (eqs. 26–27 integrated: the ball centre on the circle of radius
//! ρ about A, and `r_b φ = R_tr ψ − ρ θ`), and, for a held ball (locked scene or ball resting on a
//! stop), `θ − ψ = α_lock` ([`kin`]).
//!
//! **Partitioning** (eq. 28): independent coordinates `q_i` = the free beam coordinates (nodes
//! 1..N) and φ for a free ball, the same unknowns as the embedded core; dependent ones `q_d` =
//! the root node, `R_t`, ψ, `R_b` (and φ for a held ball).
//!
//! **One Newton iteration** on the independent accelerations `x` (Newmark: `q_i = q̃ + βh² x`,
//! `q̇_i = ṽ + γh x`): (1) the dependent positions from `C = 0` by Newton–Raphson (to rounding);
//! (2) the dependent velocities from `C_q q̇ = 0`; (3) the accelerations and multipliers from the
//! augmented system (eq. 22) `[M C_qᵀ; C_q 0] [q̈; λ] = [Q_e − Q_k; Q_d]`, `Q_d = −(C_q q̇)_q q̇`
//! (eq. 23), solved by a Schur complement on the constant mass matrix (below); (4) the residual of the independent accelerations,
//! `δ = x − q̈_i`, weighted by the reduced mass, `r = Bᵀ M B δ` (B = ∂q/∂q_i, the velocity
//! transformation), which is the virtual work of the unbalanced forces along the independent
//! directions; (5) the Newton matrix `∂r/∂x`: the beam part from the element tangents (exact),
//! the tip/ball block (5×5, at the end node) exact from the core's tip rows in dual numbers:
//! `r` is Lagrange's equations in the independent coordinates, the same function of the local
//! state as the core's rows (`FullSolver::tip_block`; checked against central differences of
//! this solver's reduced local residual, which the plumb ball of the static solve still uses).
//! Only the matrix comes from the core; the residual, which alone fixes the solution, is this
//! module's. Convergence: the core's criterion, `max |c_pos Δx_i| / scale_i ≤ tolerance`.
//!
//! **Linear algebra** (see docs/full-solver.md). The mass matrix `M` is constant and the clamp
//! fixes the root node, so the augmented system (22) is solved through the free-coordinate mass
//! matrix `M_f`, factored once per solver, and the `m ≤ 6` local constraint rows `G = C_q`
//! (nonzero only on the 10 local coordinates): `q̈ = M_f⁻¹ f − M_f⁻¹ Gᵀ λ`,
//! `(G M_f⁻¹ Gᵀ) λ = G M_f⁻¹ f + (C_q q̇)_q q̇` (the Schur complement, `m × m`, from the constant
//! 10 × 10 block of `M_f⁻¹` on the local coordinates). `M_f` and the reduced Newton matrix are
//! block tridiagonal (4 × 4 node blocks) with the bodies' border after the end node; both are
//! factored by a block LU ([`block`]: pivoting inside the node blocks, checked multipliers
//! across them), with the kept sparse LU ([`sparse`], faer, partial pivoting) as its guarded
//! fallback and the reference ([`Linear`]). **Newton rule**: one Jacobian and factorization per
//! solve; a reused factorization must halve the scaled correction of the previous iteration, else
//! the correction is discarded and the matrix is rebuilt at the same iterate (the core's rule).
//!
//! **Ball flight** (`flight.rs`): with `ball.flight` a free ball leaves the track where
//! the track would have to pull it, and the partition changes: the rolling contact (`c₄`, `c₅`)
//! is released and the ball's `(φ, R_b1, R_b2)` become independent coordinates (`4N + 3`, a third
//! reduced Newton matrix: the beam's band plus the ball's diagonal masses). Landings (bounce or
//! plastic rough landing by momentum projection onto the rolling partition) and stops in flight
//! follow the same law as the core (`absorber-core/src/step/flight`).
//!
//! Stops, stick and release, impulses: the core's algorithm (`absorber-core/src/step/stops`), with the
//! relative angle `α = θ − ψ` and its gradient computed from the maximal coordinates. Newton:
//! the core's rule (`absorber-core/src/step/newton`) for step solves — one matrix per solve, reused while
//! it contracts — and a fresh matrix every iteration for static and acceleration solves.
//!
//! **Layout: the path of one step.** [`FullSolver::step`] (`step`: the Newmark or generalized-α
//! predictor, then the stop events that split the step) calls `newton` (the iteration on `x`, and
//! the state completed from the independent coordinates), whose every iterate is evaluated in
//! `assembly` (element forces and blocks, the augmented system through the mass factor, the
//! residual `Bᵀ M B δ` and its matrix) on the local kinematics of `partition` (indices, independent
//! coordinates per contact mode, dependent positions, velocities and `B_d` from the constraints of
//! `kin`), with the bodies' Newton block from `bodies`; the matrices (`matrix`) are factored by the
//! block LU of `block` (or `sparse`), the small dense systems by `dense`. Flight, landings and
//! stops in flight are in `flight` (its impulses in `flight::impulse`); the static equilibrium,
//! restart and modes in `statics`; forces, energies and the [`Simulator`](crate::sim::Simulator)
//! interface in `outputs`; the load vector and mass products of the energy balance in
//! `balance`. This file holds the public types, the constructors and the kept scratch.
//!
//! [`sim`] is the common face of this solver and the embedded core ([`sim::Simulator`],
//! [`sim::Observation`]): the host implements it for the core, so every command, report and test
//! can run either one.

mod assembly;
mod balance;
mod block;
mod bodies;
mod dense;
mod flight;
pub mod kin;
mod matrix;
mod newton;
mod outputs;
mod partition;
pub mod sim;
mod sparse;
mod statics;
mod step;

use absorber_core::loads::{arm_section, ArmParams, Section};
use absorber_core::shared::{Element, ElementMatrix};
use absorber_core::{Contact, Error, Landing, Params};
use assembly::{ElementConst, MassFactor};
use kin::Bodies;
pub use matrix::Linear;
use matrix::Matrix;
use std::cell::RefCell;
use std::sync::Arc;

/// Which bodies the full solver models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// The cantilever alone.
    BeamOnly,
    /// Cantilever + tip mass.
    TipMass,
    /// Cantilever + tip mass + ball fixed in the housing (θ = ψ).
    LockedBall,
    /// Cantilever + tip mass + free ball between the ±stops.
    FreeBall,
    /// Free ball, no stops.
    FreeBallNoStops,
}

impl SceneKind {
    fn has_tip(self) -> bool {
        !matches!(self, SceneKind::BeamOnly)
    }
    fn has_ball(self) -> bool {
        matches!(
            self,
            SceneKind::LockedBall | SceneKind::FreeBall | SceneKind::FreeBallNoStops
        )
    }
    fn free_ball(self) -> bool {
        matches!(self, SceneKind::FreeBall | SceneKind::FreeBallNoStops)
    }
    fn stops(self) -> bool {
        matches!(self, SceneKind::FreeBall)
    }
}

/// State in maximal coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct FullState {
    /// Positions `z` (beam: displacements from the reference; bodies: absolute in the base frame).
    pub q: Vec<f64>,
    /// Velocities relative to the base.
    pub v: Vec<f64>,
    /// Accelerations relative to the base.
    pub a: Vec<f64>,
    /// The generalized-α scheme's acceleration-like variable (`absorber_core::State`'s
    /// `pseudo_accel`); equal to `a` except on the independent coordinates after a
    /// generalized-α step.
    pub pa: Vec<f64>,
    /// Time \[s\].
    pub time: f64,
    /// Base acceleration input at `time` \[m/s²\].
    pub base_accel: f64,
    /// The ball's phase: on the track (`Off`, or resting on a stop) or in flight (`InFlight`:
    /// its `(φ, R_b1, R_b2)` are independent coordinates, the rolling contact is released).
    pub contact: Contact,
    /// Branch of the orbit angle θ (θ is continuous, not wrapped to ±π); in flight, of the
    /// polar angle of the ball's centre about A.
    pub theta_ref: f64,
    /// In flight: the flight has reached `ball.lift_height` and counts as a separation (the
    /// core's `Flight::lifted`).
    pub lifted: bool,
}

/// Factorizations and scratch kept between solves. The solver's methods take `&self` (a step
/// reads the solver throughout while it writes these), so the solver owns them in a
/// [`RefCell`]: one owner, no lock, cloned with the solver. No method that borrows them calls
/// another that does (a second borrow would be a bug, and panics).
#[derive(Clone, Debug)]
struct Work {
    mass: MassFactor,
    /// Reduced Newton matrix, one per partition: `[4N unknowns, 4N + 1 (free ball on the
    /// track), 4N + 3 (ball in flight)]`.
    reduced: [Option<Matrix>; 3],
    /// Diagnostics of the last step: the largest radial distance `|r − ρ|` by which a landing
    /// put the ball's centre onto its circle \[m\] (the landing's position error).
    projection: f64,
    /// Newton's iterate `(q, v, a)` and correction, kept (every entry rewritten per use).
    iterate: [Vec<f64>; 4],
}

/// The full solver (see the module documentation).
#[derive(Clone, Debug)]
pub struct FullSolver {
    params: Params<f64>,
    scene: SceneKind,
    n: usize,
    element: Element<f64>,
    me: ElementMatrix<f64>,
    kb: ElementMatrix<f64>,
    /// A real arm's per-element sections (the core's [`absorber_core::loads::arm_section`]);
    /// `None`: the uniform beam above.
    arm: Option<Arc<[Section<f64>]>>,
    /// External loads held for the next steps: tip force \[N\] and line load per element
    /// \[N/m\], positive up (`None`: none).
    loads: Option<(f64, Arc<[f64]>)>,
    bodies: Bodies,
    n_body: usize,
    nz: usize,
    state: FullState,
    equilibrium: FullState,
    /// [`FullSolver::heights`] of `equilibrium` (the energies' reference, kept with it).
    eq_heights: (f64, f64, f64),
    /// The landing of the last step.
    last_landing: Option<Landing<f64>>,
    /// The factorization of the mass and Newton matrices (docs/full-solver.md).
    linear: Linear,
    /// Per-element assembly constants: one for the uniform beam, one per element of an arm.
    consts: Arc<[ElementConst]>,
    /// The kept factorizations and scratch ([`Work`]).
    work: RefCell<Work>,
}

/// A zero vector of length `n` from the allocator's thread cache: `vec![0.0; n]` asks
/// `calloc`, which glibc serves without that cache (≈ 400 instructions per vector of a step).
fn zeros(n: usize) -> Vec<f64> {
    let mut v = Vec::with_capacity(n);
    v.extend(std::iter::repeat_n(0.0, n));
    v
}

impl FullSolver {
    /// Builds the solver for `scene` with `n_elements` elements, solves the static equilibrium
    /// by load stepping and starts from it at rest, ball at `ball.initial_angle`.
    pub fn at_rest(
        params: Params<f64>,
        scene: SceneKind,
        n_elements: usize,
        base_accel: f64,
    ) -> Result<Self, Error> {
        let mut s = Self::new(params, scene, n_elements)?;
        s.solve_static()?;
        s.restart(base_accel)?;
        Ok(s)
    }

    /// Builds the solver in the reference configuration (no static solve).
    pub fn new(params: Params<f64>, scene: SceneKind, n_elements: usize) -> Result<Self, Error> {
        if n_elements == 0 {
            return Err(Error::InvalidParameter {
                field: "n_elements",
                reason: "must be at least 1",
            });
        }
        if n_elements > 100_000 {
            return Err(Error::InvalidParameter {
                field: "n_elements",
                reason: "must be at most 100000",
            });
        }
        params.validate(scene.has_tip(), scene.has_ball())?;
        let n = n_elements;
        let b = &params.beam;
        let element = Element::of_beam(b, &params.calibration, n);
        let (mt, jt, d) = if scene.has_tip() {
            (params.tip.mass, params.tip.inertia, params.tip.offset)
        } else {
            (0.0, 0.0, 0.0)
        };
        let (mb, jb) = if scene.has_ball() {
            (params.ball.mass, params.ball.inertia)
        } else {
            (0.0, 0.0)
        };
        let rho = params.ball.path_radius();
        let bodies = Bodies {
            length: b.length,
            offset: d,
            rho,
            rb: params.ball.radius,
            rtr: rho + params.ball.radius,
            mass: [0.0, 0.0, 0.0, 0.0, mt, mt, jt, jb, mb, mb],
            weights: (mt, mb),
        };
        let n_body = if scene.has_ball() {
            6
        } else if scene.has_tip() {
            3
        } else {
            0
        };
        let nz = 4 * (n + 1) + n_body;
        let mut q = vec![0.0; nz];
        let b0 = 4 * (n + 1);
        if scene.has_tip() {
            q[b0] = b.length;
            q[b0 + 1] = -d;
        }
        if scene.has_ball() {
            q[b0 + 4] = b.length;
            q[b0 + 5] = -rho;
        }
        let state = FullState {
            q,
            v: vec![0.0; nz],
            a: vec![0.0; nz],
            pa: vec![0.0; nz],
            time: 0.0,
            base_accel: 0.0,
            contact: Contact::Off,
            theta_ref: 0.0,
            lifted: false,
        };
        let me = element.blended_mass_matrix(params.calibration.mass_lumping);
        let kb = element.bending_stiffness();
        let mass = Self::mass_factor(n, n_body, |_| &me, &bodies, Linear::Block)?;
        let mut s = Self {
            params,
            scene,
            n,
            element,
            me,
            kb,
            arm: None,
            loads: None,
            bodies,
            n_body,
            nz,
            equilibrium: state.clone(),
            eq_heights: (0.0, 0.0, 0.0),
            state,
            last_landing: None,
            linear: Linear::Block,
            consts: Arc::new([ElementConst::of(&element, &me, &kb)]),
            work: RefCell::new(Work {
                mass,
                reduced: [None, None, None],
                projection: 0.0,
                iterate: Default::default(),
            }),
        };
        s.eq_heights = s.heights(&s.equilibrium);
        Ok(s)
    }

    /// The solver of a real arm: `arm`'s sections (the core's
    /// [`absorber_core::loads::arm_section`], one source of truth) replace the uniform beam of
    /// `params.beam` (whose length and modulus are used); no static solve (see
    /// [`FullSolver::arm_at_rest`]).
    pub fn with_arm(
        params: Params<f64>,
        scene: SceneKind,
        n_elements: usize,
        arm: &ArmParams<f64>,
    ) -> Result<Self, Error> {
        arm.validate(&params.beam)?;
        let mut s = Self::new(params, scene, n_elements)?;
        let p = &s.params;
        let sections: Vec<Section<f64>> = (0..n_elements)
            .map(|k| {
                arm_section(
                    arm,
                    &p.beam,
                    &p.calibration,
                    p.damping.stiffness_proportional,
                    k,
                    n_elements,
                )
            })
            .collect();
        let mass = Self::mass_factor(
            n_elements,
            s.n_body,
            |e| &sections[e].beam.mass,
            &s.bodies,
            s.linear,
        )?;
        s.consts = sections
            .iter()
            .map(|sec| ElementConst::of(&sec.beam.element, &sec.beam.mass, &sec.beam.stiffness))
            .collect();
        s.arm = Some(sections.into());
        *s.work.get_mut() = Work {
            mass,
            reduced: [None, None, None],
            projection: 0.0,
            iterate: Default::default(),
        };
        Ok(s)
    }

    /// [`FullSolver::with_arm`], the static equilibrium and a start at rest.
    pub fn arm_at_rest(
        params: Params<f64>,
        scene: SceneKind,
        n_elements: usize,
        arm: &ArmParams<f64>,
        base_accel: f64,
    ) -> Result<Self, Error> {
        let mut s = Self::with_arm(params, scene, n_elements, arm)?;
        s.solve_static()?;
        s.restart(base_accel)?;
        Ok(s)
    }

    /// Holds the external loads for the next steps: `tip_force` \[N\] at the beam end and
    /// `line_load` \[N/m\] on each element (its length must be the number of elements),
    /// positive up; the same load integrals as the core ([`Element::line_load_force`]).
    pub fn set_loads(&mut self, tip_force: f64, line_load: &[f64]) -> Result<(), Error> {
        if line_load.len() != self.n {
            return Err(Error::InvalidParameter {
                field: "loads.line_load",
                reason: "needs one value per element",
            });
        }
        if !tip_force.is_finite() || !line_load.iter().all(|w| w.is_finite()) {
            return Err(Error::NonFiniteInput);
        }
        self.loads = Some((tip_force, line_load.into()));
        Ok(())
    }

    /// Selects the factorization of the mass and Newton matrices: the block LU (the default)
    /// or the kept sparse LU (faer), the reference (docs/full-solver.md). Results agree to
    /// rounding.
    pub fn set_linear(&mut self, linear: Linear) -> Result<(), Error> {
        let mass = match &self.arm {
            Some(sec) => Self::mass_factor(
                self.n,
                self.n_body,
                |e| &sec[e].beam.mass,
                &self.bodies,
                linear,
            )?,
            None => Self::mass_factor(self.n, self.n_body, |_| &self.me, &self.bodies, linear)?,
        };
        self.linear = linear;
        let w = self.work.get_mut();
        w.mass = mass;
        w.reduced = [None, None, None];
        Ok(())
    }

    /// The current state.
    pub fn state(&self) -> &FullState {
        &self.state
    }

    /// The static equilibrium.
    pub fn equilibrium(&self) -> &FullState {
        &self.equilibrium
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.n
    }

    /// The scene.
    pub fn scene(&self) -> SceneKind {
        self.scene
    }
}

#[cfg(test)]
mod tests;
