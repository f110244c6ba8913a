//! Parameters, with the paper's Table 1 as default, validated on construction.
//!
//! All quantities in SI units. Which parts are used depends on the [`crate::Scene`]: a beam-only
//! model ignores (and does not validate) the tip and ball parameters.

use crate::error::Error;
use crate::scalar::{lit, Real};

/// The flexible cantilever (paper Table 1, "Flexible beam").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamParams<T> {
    /// Total length L \[m\] (Table 1: 3 elements of 0.365/3 m).
    pub length: T,
    /// Total mass \[kg\] (Table 1: 3 × 0.116/3 kg).
    pub mass: T,
    /// Cross-section area a \[m²\].
    pub area: T,
    /// Young's modulus E \[Pa\].
    pub modulus: T,
    /// Second moment of area I \[m⁴\].
    pub inertia: T,
}

/// The rigid tip mass welded to the beam end (Table 1, "Tip mass").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipParams<T> {
    /// Mass m_t \[kg\].
    pub mass: T,
    /// Moment of inertia about its centre of mass J_t \[kg·m²\].
    pub inertia: T,
    /// Distance u_t2 from the tip mass centre B up to the beam end A \[m\] (B lies below A).
    pub offset: T,
}

/// The ball rolling in the circular track of the housing (Table 1, "Ball"; stops of §3.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BallParams<T> {
    /// Mass m_b \[kg\].
    pub mass: T,
    /// Moment of inertia about its centre J_b \[kg·m²\] (solid sphere: 0.4 m_b r_b²).
    pub inertia: T,
    /// Ball radius r_b \[m\].
    pub radius: T,
    /// Track (contact) radius R \[m\]; the ball centre moves on ρ = R − r_b about the beam end.
    pub track_radius: T,
    /// Stop angle: the ball hits the housing when |θ − ψ| reaches it \[rad\] (paper: 65°).
    pub stop_angle: T,
    /// Coefficient of restitution of a stop impact \[-\] (not in the paper; default 0.5).
    pub restitution: T,
    /// Below this relative speed |θ̇ − ψ̇| an impact is plastic and the ball may stay on the
    /// stop \[rad/s\] (keeps a fixed step from chattering on a resting ball).
    pub stick_speed: T,
    /// Ball angle θ(0) from the downward vertical at the start of a run \[rad\] (1°).
    pub initial_angle: T,
    /// How the stop impulse is distributed over the system.
    pub impact_model: ImpactModel,
    /// Duration τ_s of a stop impact \[s\] for the over-step impulse metric
    /// ([`ImpactModel::OverStep`]): the stops' impulses (on the track and in flight) act through
    /// `W = M + γτ_s C + βτ_s² K`, as a contact lasting τ_s would. 0 (the default) means the
    /// time step h, the paper's model: the response of the stiff modes to a stop impact then
    /// depends on h. A compliant stop (an elastomer bumper) has a contact time of its own
    /// (Hertz: about 3 ms for a 14 g ball on a 5 MPa pad at 0.1–0.5 m/s; docs/model.md,
    /// "Stops"), and with it every step sees the same impact. Ignored by the instantaneous
    /// model.
    pub stop_contact_time: T,
    /// The ball may leave the track when the track would have to pull it (normal force
    /// `N < 0`), fly inside the housing and land again (`flight`). `false`
    /// keeps the bilateral track of the paper (the ball is held on its circle by any force),
    /// bit-identical to the rolling model. Only scenes whose type allows flight
    /// ([`crate::Scene::FLIGHT`]) read it. Default `true`.
    pub flight: bool,
    /// Coefficient of normal restitution e_n of a landing on the track \[-\] (not in the paper;
    /// default 0.5, the stops' value: the same ball on the same housing). A landing slower
    /// than `ρ · stick_speed` along the normal is plastic and the ball rolls on.
    pub landing_restitution: T,
    /// Shortest flight a bounce may start \[s\]: a landing whose rebound would fly for less
    /// (`2 e_n v_n / a_p`, pressed onto the track at `a_p`) is a rolling landing
    /// (`flight::landing_bounces`). 0 (the default) means the time step h, the
    /// shortest flight a step resolves: the number of bounces then grows as h shrinks (a
    /// bouncing ball's rebounds shorten geometrically). A fixed time makes the cut the same
    /// for every step not longer than it (3 ms: rebounds lower than about 10 µm at 1 g roll
    /// on; docs/model.md, "Contact statistics").
    pub min_bounce_time: T,
    /// Height a flight must reach to count as a separation \[m\]: the ball's gap to the track,
    /// `ρ − |c − A|`, exceeds it at a step's end, or the hop's apex `v_n² / (2 a_p)` at its
    /// landing does (normal speed `v_n`, pressed onto the track at `a_p`). Lower hops are
    /// flown all the same (the motion does not change); they are not counted in
    /// [`crate::EventCounts`]' separations and landings. 0 (the default) counts every take-off.
    /// The rigid unilateral track on the flexible housing makes hops of every height down to
    /// nanometres whose number grows as h shrinks (the housing's higher modes resolved);
    /// counted above 10 µm (the physics scene: the apex of the shortest bounce,
    /// `ball.min_bounce_time` = 3 ms, at 1 g) the separation rate converges (docs/model.md,
    /// "Contact statistics").
    pub lift_height: T,
}

/// How a stop impulse `Λ ∇Gᵀ` changes the velocities (both give `Ġ⁺ = −e Ġ⁻` exactly).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpactModel {
    /// Instantaneous impact of the discrete model, `Δq̇ = M⁻¹ ∇Gᵀ Λ` (docs/derivation.md, "Conventions"): conserves
    /// kinetic energy for e = 1 exactly, but drives the end node's slope-stretch modes
    /// (kHz, far above 1/h), which Newmark then rings down over many steps and Newton must
    /// fight (up to ~40 iterations a step, and no convergence for e = 1 in the paper scene).
    Instantaneous,
    /// Impulse spread over the time step: `Δq̇ = W⁻¹ ∇Gᵀ Λ` with the Newmark matrix
    /// `W = M + γh C + βh² K`. Modes well below 1/h take the impulse as `M⁻¹` does, modes far
    /// above it respond quasi-statically, as they would to a contact lasting about h.
    /// Newton needs at most 3–4 iterations; the kinetic energy change for e = 1 is no longer
    /// exactly zero (measured in `docs/model.md`). Default.
    OverStep,
}

impl<T: Real> BallParams<T> {
    /// Radius of the ball centre's path ρ = R − r_b \[m\].
    pub fn path_radius(&self) -> T {
        self.track_radius - self.radius
    }

    /// Small-oscillation frequency of the ball in a fixed housing, `√(m_b g ρ / J_θ) / 2π`
    /// with `J_θ = (m_b + J_b/r_b²) ρ²` (= √(g / 1.4ρ) / 2π for a solid ball) \[Hz\].
    pub fn fixed_housing_frequency(&self, gravity: T) -> T {
        let rho = self.path_radius();
        let j_theta = (self.mass + self.inertia / (self.radius * self.radius)) * rho * rho;
        (self.mass * gravity * rho / j_theta).sqrt() / T::two_pi()
    }
}

/// Newmark integrator with Newton–Raphson (Table 1, "Numerical integration parameters"), or its
/// generalization, the generalized-α scheme ([`Integrator::generalized_alpha`]).
///
/// With `α_m = α_f = 0` (the default) it is Newmark's method. Otherwise it is the
/// generalized-α method of Chung & Hulbert (1993) in the form of Arnold & Brüls (2007,
/// *Multibody Syst. Dyn.* 18:185): the equations of motion hold at `t_{n+1}` and the Newmark
/// formulas run on an acceleration-like variable `a` (`State::pseudo_accel`) with
/// `(1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integrator<T> {
    /// Newmark γ \[-\]: 0.5 conserves energy, larger values damp (paper: 0.7).
    pub gamma: T,
    /// Newmark β \[-\]: unconditionally stable for β ≥ (γ + ½)²/4 (paper: 0.36).
    pub beta: T,
    /// Generalized-α weight of the previous acceleration in the inertia, α_m \[-\] (0: Newmark).
    pub alpha_m: T,
    /// Generalized-α weight of the previous acceleration in the forces, α_f \[-\] (0: Newmark).
    pub alpha_f: T,
    /// Time step h \[s\] (paper: 0.003).
    pub step: T,
    /// Newton tolerance \[-\]: iterations stop when the position increment, in units of the
    /// beam length for positions and in radians for slopes and angles, is at most this.
    pub tolerance: T,
    /// Hard maximum of Newton iterations per solve (paper: 100).
    pub max_iterations: u32,
    /// When the Newton matrix is rebuilt.
    pub newton: NewtonKind,
    /// Fixed Newton budget: after `max_iterations` iterations of a step solve, accept the
    /// iterate instead of failing with `NoConvergence` (bounded work for firmware that prefers
    /// a slightly inexact step to a skipped one; the report's `increment` shows how inexact).
    /// Non-finite values are still errors. Off by default.
    pub accept_after_budget: bool,
    /// Where a stop impact of the rolling ball inside a step is put (the flight events, the
    /// ball leaving and landing on the track, always split the step at their crossing).
    pub events: EventLocation,
    /// Hard cap on the work of one step, in work units ([`crate::work`]: an assembly
    /// with its factorization 16, a residual 5, a back-substitution 1), summed over every
    /// solve of the step: the Newmark solve, an event's sub-steps, impulses and consistent
    /// accelerations, the damping trials. A solve that reaches it stops with its iterate and
    /// the step is flagged ([`crate::Outcome::Capped`]); repeated capped or failed steps make
    /// the model restart itself ([`crate::Model::step`]). Default
    /// [`work::UNLIMITED`](crate::work::UNLIMITED) (the iteration limits alone);
    /// firmware with a deadline per sample sets it with `events` (`docs/embedded.md`). At
    /// least [`work::MIN_CAP`](crate::work::MIN_CAP), at most
    /// [`work::UNLIMITED`](crate::work::UNLIMITED) (a step's time stays bounded).
    pub max_work: u32,
    /// What a step whose Newton solve stopped at the work cap does ([`AtCap`]; default
    /// `Take`: measured in `docs/accuracy.md`, "The work cap").
    pub at_cap: AtCap,
}

/// What a step does when a Newton solve stops at the work cap ([`Integrator::at_cap`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtCap {
    /// Take the iterate: the step is taken, flagged [`crate::Outcome::Capped`] (inexact by its
    /// report's `increment`). Default.
    Take,
    /// Keep the state: the step returns [`Error::WorkCap`] and the state is exactly as before
    /// (the sample is lost, as after any failed step).
    Keep,
}

/// Where an event inside a time step is put ([`Integrator::events`]): a stop impact, the
/// ball's separation from the track, its landing, a stop hit in flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventLocation {
    /// At its crossing inside the step (default): the step is redone as a sub-step to the
    /// crossing, the event, and a sub-step for the rest. Exact event timing (the crossing of
    /// a cubic Hermite interpolant, error O(h⁴)); an event step solves up to five Newton
    /// matrices (the trial, the sub-step, the impulse metric, the consistent acceleration,
    /// the rest).
    Crossing,
    /// At the end of the step in which it happened: the trial step stands; at its end the
    /// ball is put back on the stop or the circle, the impulse is applied with the trial's
    /// own Newton matrix as metric (a plastic landing factors the rolling one), a separation
    /// switches the ball to flight; the acceleration stays the trial's (no consistent
    /// acceleration: the next step's Newton then starts near its solution). A landing bounces,
    /// and rebounds at `−e_n` times, the normal speed at its crossing (Hermite rate), not at the
    /// step's end: deciding on the end's speed made landings chatter. An event is late by less
    /// than one step (its effect on the response and the restitution law is measured in
    /// `docs/accuracy.md`), and no step costs more than about two ordinary ones: a bounded worst
    /// case for firmware with a hard deadline per sample (`docs/embedded.md`).
    StepEnd,
}

impl<T: Real> Integrator<T> {
    /// The generalized-α scheme with high-frequency spectral radius `rho_inf` ∈ \[0, 1\]
    /// (Chung & Hulbert 1993, eqs. 25, 17, 20): `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`,
    /// `α_f = ρ∞/(ρ∞ + 1)`, `γ = ½ − α_m + α_f`, `β = ¼(1 − α_m + α_f)²`. Second-order
    /// accurate and unconditionally stable for linear systems; modes the step cannot resolve
    /// (ωh → ∞) are multiplied by ρ∞ per step, while the numerical damping ratio at ωh ≪ 1
    /// grows only like (ωh)³ (docs/model.md gives it per mode). ρ∞ = 1 is the trapezoidal rule.
    /// The step, tolerance and Newton settings are kept. A `rho_inf` outside \[0, 1\] gives
    /// parameters that [`Params::validate`] rejects.
    pub fn generalized_alpha(self, rho_inf: T) -> Self {
        let (one, half) = (T::one(), lit::<T>(0.5));
        let alpha_m = (lit::<T>(2.0) * rho_inf - one) / (rho_inf + one);
        let alpha_f = rho_inf / (rho_inf + one);
        let gamma = half - alpha_m + alpha_f;
        let s = one - alpha_m + alpha_f;
        Self {
            alpha_m,
            alpha_f,
            gamma,
            beta: lit::<T>(0.25) * s * s,
            ..self
        }
    }

    /// Whether this is Newmark's method (`α_m = α_f = 0`).
    pub fn is_newmark(&self) -> bool {
        self.alpha_m == T::zero() && self.alpha_f == T::zero()
    }
}

/// Newton variant of the step solve (all converge to the same tolerance; `step::newton`
/// states the rule).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NewtonKind {
    /// One Newton matrix per step (default): assembled and factored at the first iterate of the
    /// step, reused by the later iterations and sub-solves of that step while each correction
    /// is at most half the previous one, rebuilt otherwise. Converges to the same tolerance as
    /// full Newton with about half its factorizations.
    PerStep,
    /// Full Newton–Raphson: the exact Jacobian is assembled and factored every iteration
    /// (quadratic convergence; the paper's method, kept as a reference).
    Full,
    /// Modified Newton: the factored Jacobian is kept across iterations and steps and rebuilt
    /// only when an iteration contracts by less than half, or the step length or the ball's
    /// contact changes, and at once in a step that starts with the ball in flight (where the
    /// landings are, `step::newton`). Iterations then cost a residual (no dual numbers, no axial tangent)
    /// and a triangular solve. Convergence is linear but fast, because the Newton matrix
    /// `M + γhC + βh²K` changes little from step to step.
    Modified,
}

/// Optional structural damping (off by default: the paper's only damping is γ > ½).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Damping<T> {
    /// Stiffness-proportional coefficient c in `C = c K_b` \[s\]; modal damping ratio
    /// ζ = c ω / 2 (use [`Damping::from_ratio`]).
    pub stiffness_proportional: T,
}

impl<T: Real> Damping<T> {
    /// The coefficient that gives damping ratio `zeta` at `frequency_hz`.
    pub fn from_ratio(zeta: T, frequency_hz: T) -> Self {
        Self {
            stiffness_proportional: lit::<T>(2.0) * zeta / (T::two_pi() * frequency_hz),
        }
    }
}

/// Calibration of the reduced beam: factors folded into the element matrices at construction
/// (no cost per step), fitted by `host-sim calibrate` so that an N-element model matches a
/// converged mesh (or a measured pole). `Calibration::default()` is the identity (the paper's
/// model, bit for bit).
///
/// Why these three (docs/model.md, "Calibration"): with gravity the beam hangs curved, and the
/// Green-strain cable element (eq. 11) cannot bend a curved element without stretching it — its
/// axial strain `d₁ + ½|d|²` mixes a quadratic `d₁` with a quartic `½ d₂²` — so a few elements
/// carry a spurious axial strain energy ∝ EA (membrane locking): N = 3 is 0.92 % stiff in f₁
/// and 0.8 % short in sag, while without gravity its f₁ is exact to 5 digits. Scaling EA acts
/// on that cause; it leaves the physical axial strain (≤ 1e-6 here) and the kHz axial modes
/// irrelevant to the motion. The bending factor takes up the Hermite discretization error of the
/// bending modes, and the mass blend (consistent ↔ HRZ lumped) the dispersion of the second
/// mode, as an averaged mass matrix does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration<T> {
    /// Factor on the bending rigidity E·I of every element \[-\] (1: none). Also scales the
    /// stiffness-proportional damping matrix `C = c K_b`.
    pub bending_stiffness: T,
    /// Factor on the axial rigidity E·a of every element \[-\] (1: none).
    pub axial_stiffness: T,
    /// Fraction μ of the HRZ-lumped mass in the element mass matrix,
    /// `M = (1 − μ) M_consistent + μ M_lumped` \[-\] (0: the paper's consistent mass, eq. 8).
    pub mass_lumping: T,
    /// Linear gradient `g` of the bending factor along an arm (per-element sections): the
    /// rigidity of the section at `x` is `E·I(x) · bending_stiffness · (1 + g (2x/L − 1))`
    /// \[-\] (0: none; `|g| ≤ 0.5`). A second stiffness lever with another modal weight than the
    /// uniform factor: the first mode's strain energy lies at the clamp, the second's further
    /// out, so `g` moves f₂ against f₁ (docs/monitoring.md, "Calibrated on f₁ and f₂"). A
    /// uniform beam has no sections: only 0 is accepted there.
    pub bending_gradient: T,
}

impl<T: Real> Default for Calibration<T> {
    fn default() -> Self {
        Self {
            bending_stiffness: T::one(),
            axial_stiffness: T::one(),
            mass_lumping: T::zero(),
            bending_gradient: T::zero(),
        }
    }
}

impl<T: Real> Calibration<T> {
    /// The identity: the paper's model.
    pub fn is_identity(&self) -> bool {
        *self == Self::default()
    }
}

/// Everything the model needs. `Params::default()` is the paper's Table 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params<T> {
    /// Cantilever.
    pub beam: BeamParams<T>,
    /// Tip mass (used by scenes with a tip).
    pub tip: TipParams<T>,
    /// Ball (used by scenes with a ball).
    pub ball: BallParams<T>,
    /// Integrator.
    pub integrator: Integrator<T>,
    /// Structural damping.
    pub damping: Damping<T>,
    /// Gravity g \[m/s²\] along −y (9.81; zero is allowed).
    pub gravity: T,
    /// Calibration of the reduced beam (default: none).
    pub calibration: Calibration<T>,
}

impl<T: Real> Default for Params<T> {
    fn default() -> Self {
        Self {
            beam: BeamParams {
                length: lit(0.365),
                mass: lit(0.116),
                area: lit(4.06e-5),
                modulus: lit(200e9),
                inertia: lit(8.47e-12),
            },
            tip: TipParams {
                mass: lit(0.1154),
                inertia: lit(1.871e-5),
                offset: lit(0.0204),
            },
            ball: BallParams {
                mass: lit(0.014),
                inertia: lit(3.15e-7),
                radius: lit(0.0075),
                track_radius: lit(0.0395),
                stop_angle: lit(65.0f64.to_radians()),
                restitution: lit(0.5),
                stick_speed: lit(0.02),
                initial_angle: lit(1.0f64.to_radians()),
                impact_model: ImpactModel::OverStep,
                stop_contact_time: T::zero(),
                flight: true,
                landing_restitution: lit(0.5),
                min_bounce_time: T::zero(),
                lift_height: T::zero(),
            },
            integrator: Integrator {
                gamma: lit(0.7),
                beta: lit(0.36),
                alpha_m: T::zero(),
                alpha_f: T::zero(),
                step: lit(0.003),
                tolerance: lit(1e-5),
                max_iterations: 100,
                newton: NewtonKind::PerStep,
                accept_after_budget: false,
                events: EventLocation::Crossing,
                max_work: crate::work::UNLIMITED,
                at_cap: AtCap::Take,
            },
            damping: Damping {
                stiffness_proportional: T::zero(),
            },
            gravity: lit(9.81),
            calibration: Calibration::default(),
        }
    }
}

fn positive<T: Real>(x: T, field: &'static str) -> Result<(), Error> {
    if !x.is_finite() {
        Err(Error::InvalidParameter {
            field,
            reason: "must be finite",
        })
    } else if x <= T::zero() {
        Err(Error::InvalidParameter {
            field,
            reason: "must be positive",
        })
    } else {
        Ok(())
    }
}

fn non_negative<T: Real>(x: T, field: &'static str) -> Result<(), Error> {
    if !x.is_finite() {
        Err(Error::InvalidParameter {
            field,
            reason: "must be finite",
        })
    } else if x < T::zero() {
        Err(Error::InvalidParameter {
            field,
            reason: "must not be negative",
        })
    } else {
        Ok(())
    }
}

impl<T: Real> Params<T> {
    /// Checks every field the scene uses; the error names the first bad field.
    pub fn validate(&self, has_tip: bool, has_ball: bool) -> Result<(), Error> {
        let b = &self.beam;
        positive(b.length, "beam.length")?;
        positive(b.mass, "beam.mass")?;
        positive(b.area, "beam.area")?;
        positive(b.modulus, "beam.modulus")?;
        positive(b.inertia, "beam.inertia")?;
        if has_tip {
            positive(self.tip.mass, "tip.mass")?;
            positive(self.tip.inertia, "tip.inertia")?;
            non_negative(self.tip.offset, "tip.offset")?;
        }
        if has_ball {
            let bl = &self.ball;
            positive(bl.mass, "ball.mass")?;
            non_negative(bl.inertia, "ball.inertia")?;
            positive(bl.radius, "ball.radius")?;
            positive(bl.track_radius, "ball.track_radius")?;
            if bl.track_radius <= bl.radius {
                return Err(Error::InvalidParameter {
                    field: "ball.track_radius",
                    reason: "must exceed ball.radius",
                });
            }
            positive(bl.stop_angle, "ball.stop_angle")?;
            if bl.stop_angle >= T::pi() {
                return Err(Error::InvalidParameter {
                    field: "ball.stop_angle",
                    reason: "must be below pi",
                });
            }
            non_negative(bl.restitution, "ball.restitution")?;
            if bl.restitution > T::one() {
                return Err(Error::InvalidParameter {
                    field: "ball.restitution",
                    reason: "must be at most 1",
                });
            }
            non_negative(bl.landing_restitution, "ball.landing_restitution")?;
            if bl.landing_restitution > T::one() {
                return Err(Error::InvalidParameter {
                    field: "ball.landing_restitution",
                    reason: "must be at most 1",
                });
            }
            non_negative(bl.stick_speed, "ball.stick_speed")?;
            non_negative(bl.stop_contact_time, "ball.stop_contact_time")?;
            non_negative(bl.min_bounce_time, "ball.min_bounce_time")?;
            let lift = bl.lift_height;
            if !(lift >= T::zero() && lift < bl.path_radius()) {
                return Err(Error::InvalidParameter {
                    field: "ball.lift_height",
                    reason:
                        "allowed: 0 <= lift_height < R - r_b, the path radius of the ball's centre",
                });
            }
            if !bl.initial_angle.is_finite() {
                return Err(Error::InvalidParameter {
                    field: "ball.initial_angle",
                    reason: "must be finite",
                });
            }
            if bl.initial_angle.abs() >= bl.stop_angle {
                return Err(Error::InvalidParameter {
                    field: "ball.initial_angle",
                    reason: "must lie inside the stops",
                });
            }
        }
        let i = &self.integrator;
        // Chung & Hulbert (1993): unconditional stability needs α_m ≤ α_f ≤ ½ and
        // γ ≥ ½ − α_m + α_f (ρ∞ ≥ 0 gives α_m ≥ −1).
        if !i.alpha_f.is_finite() || i.alpha_f < T::zero() || i.alpha_f > lit(0.5) {
            return Err(Error::InvalidParameter {
                field: "integrator.alpha_f",
                reason: "must lie in [0, 0.5]",
            });
        }
        if !i.alpha_m.is_finite() || i.alpha_m < -T::one() || i.alpha_m > i.alpha_f {
            return Err(Error::InvalidParameter {
                field: "integrator.alpha_m",
                reason: "must lie in [-1, alpha_f] for unconditional stability",
            });
        }
        let gamma_min = lit::<T>(0.5) - i.alpha_m + i.alpha_f;
        if i.gamma.is_finite() && i.gamma < gamma_min * lit(1.0 - 1e-6) {
            return Err(Error::InvalidParameter {
                field: "integrator.gamma",
                reason: "must be at least 1/2 - alpha_m + alpha_f for unconditional stability",
            });
        }
        // Newmark: γ ≤ 1; generalized-α needs up to ½ − α_m + α_f (1.5 at ρ∞ = 0).
        if !i.gamma.is_finite() || i.gamma < lit(0.5) || i.gamma > T::one() + i.alpha_f - i.alpha_m
        {
            return Err(Error::InvalidParameter {
                field: "integrator.gamma",
                reason: "must lie in [0.5, 1 + alpha_f - alpha_m] (γ < 0.5 amplifies)",
            });
        }
        let beta_min = (i.gamma + lit(0.5)) * (i.gamma + lit(0.5)) / lit(4.0);
        // Allow one part in 10⁶ so that γ = 0.7, β = 0.36 passes after rounding to f32.
        if !i.beta.is_finite() || i.beta < beta_min * lit(1.0 - 1e-6) || i.beta > T::one() {
            return Err(Error::InvalidParameter {
                field: "integrator.beta",
                reason: "must lie in [(γ+½)²/4, 1] for unconditional stability",
            });
        }
        positive(i.step, "integrator.step")?;
        positive(i.tolerance, "integrator.tolerance")?;
        // Position increments below ~7 ε are rounding (observed floor of the f32 static solve:
        // 8.8e-7): a tighter tolerance could never be met.
        if i.tolerance < T::default_epsilon() * lit(8.0) {
            return Err(Error::InvalidParameter {
                field: "integrator.tolerance",
                reason: "is below what this precision resolves (8 ε; f32: 9.5e-7)",
            });
        }
        if i.max_iterations == 0 {
            return Err(Error::InvalidParameter {
                field: "integrator.max_iterations",
                reason: "must be at least 1",
            });
        }
        if i.max_work < crate::work::MIN_CAP {
            return Err(Error::InvalidParameter {
                field: "integrator.max_work",
                reason:
                    "must afford the event tests, one refreshed Newton iteration and the reserve (24 units)",
            });
        }
        if i.max_work > crate::work::UNLIMITED {
            return Err(Error::InvalidParameter {
                field: "integrator.max_work",
                reason: "must be at most 50,000 units (`work::UNLIMITED`, the default: the work the iteration limits allow); more would leave a step unbounded in time",
            });
        }
        non_negative(
            self.damping.stiffness_proportional,
            "damping.stiffness_proportional",
        )?;
        if !self.gravity.is_finite() {
            return Err(Error::InvalidParameter {
                field: "gravity",
                reason: "must be finite",
            });
        }
        self.calibration.validate()
    }
}

impl<T: Real> Params<T> {
    /// The value of the numeric field named `field` (its dotted name, as
    /// [`Error::InvalidParameter`] and the scene files spell it: `"beam.modulus"`), so that an
    /// error can be reported with the key, its value and the allowed range without the error
    /// carrying a number; `None` for a name that is no numeric field of `Params` (`"elements"`,
    /// `"loads"`, an enumeration). Counts come as scalars ([`Real::from_count`]).
    pub fn value_of(&self, field: &str) -> Option<T> {
        let (b, t, bl, i, c) = (
            &self.beam,
            &self.tip,
            &self.ball,
            &self.integrator,
            &self.calibration,
        );
        Some(match field {
            "beam.length" => b.length,
            "beam.mass" => b.mass,
            "beam.area" => b.area,
            "beam.modulus" => b.modulus,
            "beam.inertia" => b.inertia,
            "tip.mass" => t.mass,
            "tip.inertia" => t.inertia,
            "tip.offset" => t.offset,
            "ball.mass" => bl.mass,
            "ball.inertia" => bl.inertia,
            "ball.radius" => bl.radius,
            "ball.track_radius" => bl.track_radius,
            "ball.stop_angle" => bl.stop_angle,
            "ball.restitution" => bl.restitution,
            "ball.landing_restitution" => bl.landing_restitution,
            "ball.stick_speed" => bl.stick_speed,
            "ball.stop_contact_time" => bl.stop_contact_time,
            "ball.min_bounce_time" => bl.min_bounce_time,
            "ball.lift_height" => bl.lift_height,
            "ball.initial_angle" => bl.initial_angle,
            "integrator.alpha_f" => i.alpha_f,
            "integrator.alpha_m" => i.alpha_m,
            "integrator.gamma" => i.gamma,
            "integrator.beta" => i.beta,
            "integrator.step" => i.step,
            "integrator.tolerance" => i.tolerance,
            "integrator.max_iterations" => T::from_count(u64::from(i.max_iterations)),
            "integrator.max_work" => T::from_count(u64::from(i.max_work)),
            "damping.stiffness_proportional" => self.damping.stiffness_proportional,
            "gravity" => self.gravity,
            "calibration.bending_stiffness" => c.bending_stiffness,
            "calibration.axial_stiffness" => c.axial_stiffness,
            "calibration.mass_lumping" => c.mass_lumping,
            "calibration.bending_gradient" => c.bending_gradient,
            _ => return None,
        })
    }
}

impl<T: Real> Calibration<T> {
    /// Checks the factors; the error names the first bad field. The ranges are what a
    /// calibration of a discretization may do, not a different beam: E·I within a factor of 2,
    /// E·a reduced by at most 10⁶ (its axial modes stay far above the bending modes) and not
    /// raised, the lumped fraction in [0, 1].
    pub fn validate(&self) -> Result<(), Error> {
        let c = self;
        positive(c.bending_stiffness, "calibration.bending_stiffness")?;
        if c.bending_stiffness < lit(0.5) || c.bending_stiffness > lit(2.0) {
            return Err(Error::InvalidParameter {
                field: "calibration.bending_stiffness",
                reason: "must lie in [0.5, 2]",
            });
        }
        positive(c.axial_stiffness, "calibration.axial_stiffness")?;
        if c.axial_stiffness < lit(1e-6) || c.axial_stiffness > T::one() {
            return Err(Error::InvalidParameter {
                field: "calibration.axial_stiffness",
                reason: "must lie in [1e-6, 1]",
            });
        }
        non_negative(c.mass_lumping, "calibration.mass_lumping")?;
        if c.mass_lumping > T::one() {
            return Err(Error::InvalidParameter {
                field: "calibration.mass_lumping",
                reason: "must lie in [0, 1]",
            });
        }
        if !c.bending_gradient.is_finite() || c.bending_gradient.abs() > lit(0.5) {
            return Err(Error::InvalidParameter {
                field: "calibration.bending_gradient",
                reason: "must lie in [-0.5, 0.5]",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
