//! The types of the header: status codes, errors, parameters, and the `float`/`double`
//! report, outputs, energies, state and monitor-reading structs.

use super::*;

/// What a call did. Every function of the API returns one.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbsorberStatus {
    /// Success.
    Ok = 0,
    /// A parameter is out of range; [`AbsorberError::field`] names it, `value` gives its value
    /// and `reason` the allowed range.
    InvalidParameter = 1,
    /// The base acceleration (or another number passed in) is NaN or infinite; state unchanged,
    /// nothing written.
    NonFiniteInput = 2,
    /// The base acceleration is beyond ±1e4 m/s² (a sensor fault); state unchanged.
    InputOutOfRange = 3,
    /// Newton did not converge within `integrator.max_iterations`; state unchanged.
    NoConvergence = 4,
    /// The state became NaN or infinite (divergence); state unchanged.
    NonFiniteState = 5,
    /// A linear system was singular; state unchanged.
    Singular = 6,
    /// A required pointer argument was NULL.
    NullPointer = 7,
    /// The storage is smaller than the variant needs or not aligned to `ABSORBER_MODEL_ALIGN`.
    Storage = 8,
    /// Unknown variant, or a variant not compiled into this library.
    Variant = 9,
    /// A `*_f32` function on a `double` model or the reverse (or a monitor of the other scalar).
    Precision = 10,
    /// The handle does not point to a model (or monitor) built by this library.
    NotInitialized = 11,
    /// An output array is shorter than the model's number of unknowns.
    BufferTooSmall = 12,
    /// An error of the core this version of the API does not know.
    Other = 13,
    /// The step's work cap was reached by an operation that cannot stop early; state unchanged.
    WorkCap = 14,
}

/// Details of a failed [`absorber_init`] or [`absorber_monitor_init`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbsorberError {
    /// The status also returned.
    pub status: AbsorberStatus,
    /// Dotted name of the bad field (`"beam.modulus"`, `"size"`), NUL-terminated; empty if the
    /// error is not about one field.
    pub field: [c_char; ABSORBER_FIELD_LEN],
    /// Why, in words, NUL-terminated (may be truncated): the allowed range or the rule.
    pub reason: [c_char; ABSORBER_REASON_LEN],
    /// The value given for [`AbsorberError::field`], as the caller passed it (a parameter's
    /// `double` before a `float` variant rounds it, or the number of an enumeration, flag,
    /// size or count) when [`AbsorberError::has_value`] is 1; NaN otherwise. A number, not
    /// text: the library formats no floats.
    pub value: f64,
    /// 1 if [`AbsorberError::value`] holds the field's value, 0 if the error is not about one
    /// numeric field.
    pub has_value: u8,
}

/// The flexible cantilever (paper Table 1).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberBeamParams {
    /// Total length L \[m\].
    pub length: f64,
    /// Total mass \[kg\].
    pub mass: f64,
    /// Cross-section area a \[m²\].
    pub area: f64,
    /// Young's modulus E \[Pa\].
    pub modulus: f64,
    /// Second moment of area I \[m⁴\].
    pub inertia: f64,
}

/// The rigid tip mass welded to the beam end.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberTipParams {
    /// Mass m_t \[kg\].
    pub mass: f64,
    /// Moment of inertia about its centre of mass J_t \[kg·m²\].
    pub inertia: f64,
    /// Distance from the tip mass centre up to the beam end \[m\].
    pub offset: f64,
}

/// The ball in its circular track, with stops.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberBallParams {
    /// Mass m_b \[kg\].
    pub mass: f64,
    /// Moment of inertia about its centre J_b \[kg·m²\].
    pub inertia: f64,
    /// Ball radius r_b \[m\].
    pub radius: f64,
    /// Track radius R \[m\].
    pub track_radius: f64,
    /// Stop angle relative to the housing \[rad\] (paper: 65°).
    pub stop_angle: f64,
    /// Coefficient of restitution of a stop impact \[-\].
    pub restitution: f64,
    /// Relative speed below which an impact is plastic \[rad/s\].
    pub stick_speed: f64,
    /// Ball angle from the downward vertical at the start \[rad\].
    pub initial_angle: f64,
    /// `ABSORBER_IMPACT_OVER_STEP` or `ABSORBER_IMPACT_INSTANTANEOUS`.
    pub impact_model: u32,
}

/// Newmark integrator with Newton–Raphson.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberIntegratorParams {
    /// Newmark γ \[-\] (paper: 0.7).
    pub gamma: f64,
    /// Newmark β \[-\] (paper: 0.36).
    pub beta: f64,
    /// Time step h \[s\]: the sample period of the base acceleration.
    pub step: f64,
    /// Newton tolerance on the scaled position increment \[-\].
    pub tolerance: f64,
    /// Newton iterations per solve, at most.
    pub max_iterations: u32,
    /// `ABSORBER_NEWTON_PER_STEP`, `_FULL` or `_MODIFIED`.
    pub newton: u32,
    /// 1: accept the iterate after the budget instead of failing; 0: fail (default).
    pub accept_after_budget: u8,
    /// `ABSORBER_EVENTS_CROSSING` (default) or `ABSORBER_EVENTS_STEP_END`.
    pub events: u32,
}

/// Structural damping.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberDampingParams {
    /// Stiffness-proportional coefficient c in C = c K \[s\].
    pub stiffness_proportional: f64,
}

/// Calibration of the reduced beam (`absorber_core::Calibration`; `host-sim calibrate` writes
/// the three numbers in a scene's `[calibration]`). The identity is the paper's model.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberCalibrationParams {
    /// Factor on the bending rigidity E·I \[-\] (1: none; 0.5 to 2).
    pub bending_stiffness: f64,
    /// Factor on the axial rigidity E·a \[-\] (1: none; 1e-6 to 1).
    pub axial_stiffness: f64,
    /// Fraction of HRZ-lumped mass in the element mass matrix \[-\] (0: consistent; 0 to 1).
    pub mass_lumping: f64,
}

/// Everything the model needs, in SI units. Fill with [`absorber_params_default`], then edit.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberParams {
    /// `sizeof(AbsorberParams)` as the caller was compiled (set by `absorber_params_default`):
    /// lets later versions append fields safely.
    pub size: u32,
    /// Cantilever.
    pub beam: AbsorberBeamParams,
    /// Tip mass (scenes with a tip).
    pub tip: AbsorberTipParams,
    /// Ball (scenes with a ball).
    pub ball: AbsorberBallParams,
    /// Integrator.
    pub integrator: AbsorberIntegratorParams,
    /// Damping.
    pub damping: AbsorberDampingParams,
    /// Gravity g \[m/s²\] along −y.
    pub gravity: f64,
    /// Generalized-α weight α_m \[-\] (0 with `alpha_f` = 0: Newmark; set both, with γ and β,
    /// by [`absorber_params_generalized_alpha`]).
    pub alpha_m: f64,
    /// Generalized-α weight α_f \[-\].
    pub alpha_f: f64,
    /// Calibration of the reduced beam (identity by default).
    pub calibration: AbsorberCalibrationParams,
    /// 1 (default): the ball may leave the track where it would have to pull it, fly and
    /// land again; 0: the paper's bilateral track (`absorber_core::BallParams::flight`).
    pub flight: u32,
    /// Coefficient of normal restitution of a landing on the track \[-\] (default 0.5).
    pub landing_restitution: f64,
    /// Hard cap on the work of one step in work units (`absorber_core::work`: an
    /// assembly with its factorization 16, a residual 5, a back-substitution 1; at least 24, at most
    /// `ABSORBER_WORK_UNLIMITED`).
    /// A step that reaches it is taken with its iterate and flagged (`ABSORBER_OUTCOME_CAPPED`);
    /// default `ABSORBER_WORK_UNLIMITED`. A firmware with a deadline per sample sets
    /// `ABSORBER_WORK_DEADLINE` with `ABSORBER_EVENTS_STEP_END` (`docs/embedded.md`).
    pub max_work: u32,
    /// `ABSORBER_AT_CAP_TAKE` (default) or `ABSORBER_AT_CAP_KEEP`: what a step whose Newton
    /// solve reached the cap does (`absorber_core::AtCap`).
    pub at_cap: u32,
}

/// Opaque model: a pointer into the caller's storage, made by [`absorber_init`].
pub struct AbsorberModel {
    _opaque: [u8; 0],
}

/// Opaque monitor: a pointer into the caller's storage, made by [`absorber_monitor_init`].
pub struct AbsorberMonitor {
    _opaque: [u8; 0],
}

/// What one step did (`float` or `double` by the model's scalar).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AbsorberReport<T> {
    /// Newton iterations used, summed over the sub-solves of the step.
    pub iterations: u32,
    /// Largest final scaled position increment of the Newton solves \[-\].
    pub increment: T,
    /// 1 if the ball hit a stop in this step (the `impact_*` fields are then set), else 0.
    pub impact: u8,
    /// The ball stayed on the stop after the impact (1) or rebounded (0).
    pub impact_stuck: u8,
    /// Which stop: +1 (relative angle +stop_angle) or −1; 0 without an impact.
    pub impact_side: i32,
    /// Time of the impact \[s\].
    pub impact_time: T,
    /// Relative angular speed before the impact \[rad/s\].
    pub impact_relative_speed: T,
    /// Contact impulse on the ball along the track \[N·s\].
    pub impact_impulse: T,
    /// Kinetic energy dissipated \[J\].
    pub impact_energy_loss: T,
    /// 1 if the ball left the track in this step (at `separation_time`), else 0.
    pub separation: u8,
    /// 0 without a landing in this step, 1 a landing after which the ball flew on (a bounce),
    /// 2 a landing after which it rolls (the `landing_*` fields are then set).
    pub landing: u8,
    /// Time the ball left the track \[s\].
    pub separation_time: T,
    /// Time of the landing \[s\].
    pub landing_time: T,
    /// Normal speed towards the track before the landing \[m/s\].
    pub landing_normal_speed: T,
    /// Normal impulse of the track on the ball \[N·s\].
    pub landing_normal_impulse: T,
    /// Tangential impulse of the track on the ball \[N·s\].
    pub landing_tangential_impulse: T,
    /// Work units the step used (at most `integrator.max_work`).
    pub work: u32,
    /// `ABSORBER_OUTCOME_CONVERGED`, `_CAPPED` (a Newton solve stopped at the work cap; the
    /// step was taken, inexact) or `_RESTARTED` (the model restarted itself at rest after
    /// failed or capped steps in a row).
    pub outcome: u32,
}

/// Step report of a `float` model.
pub type AbsorberReportF32 = AbsorberReport<f32>;
/// Step report of a `double` model.
pub type AbsorberReportF64 = AbsorberReport<f64>;

/// The model's outputs now.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AbsorberOutputs<T> {
    /// Time since the start \[s\].
    pub time: T,
    /// Vertical deflection of the beam end relative to the base, static sag included \[m\].
    pub tip_deflection: T,
    /// Its rate \[m/s\].
    pub tip_velocity: T,
    /// Static tip deflection of the equilibrium the run started from \[m\].
    pub static_tip_deflection: T,
    /// Tip rotation ψ \[rad\].
    pub tip_angle: T,
    /// ψ̇ \[rad/s\].
    pub tip_rate: T,
    /// Ball angle θ from the downward vertical \[rad\] (0 without a ball).
    pub ball_angle: T,
    /// θ̇ \[rad/s\].
    pub ball_rate: T,
    /// Ball angle relative to the housing α = θ − ψ \[rad\] (0 without a ball).
    pub ball_relative_angle: T,
    /// α̇ \[rad/s\].
    pub ball_relative_rate: T,
    /// 1 if the scene has a ball (free or locked).
    pub has_ball: u8,
    /// Stop contact: 0 off, +1 resting on the positive stop, −1 on the negative one.
    pub contact: i32,
    /// Whole steps since the start.
    pub steps: u64,
}

/// Outputs of a `float` model.
pub type AbsorberOutputsF32 = AbsorberOutputs<f32>;
/// Outputs of a `double` model.
pub type AbsorberOutputsF64 = AbsorberOutputs<f64>;

/// Energies of the bodies \[J\] (kinetic with absolute velocities; potentials as changes from
/// the static state; beam strain total).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AbsorberEnergies<T> {
    /// Beam strain energy (axial + bending).
    pub beam_strain: T,
    /// Beam kinetic energy.
    pub beam_kinetic: T,
    /// Beam gravitational energy.
    pub beam_potential: T,
    /// Tip mass kinetic energy.
    pub tip_kinetic: T,
    /// Tip mass gravitational energy.
    pub tip_potential: T,
    /// Ball kinetic energy.
    pub ball_kinetic: T,
    /// Ball gravitational energy.
    pub ball_potential: T,
    /// Sum of the above.
    pub total: T,
}

/// Energies of a `float` model.
pub type AbsorberEnergiesF32 = AbsorberEnergies<f32>;
/// Energies of a `double` model.
pub type AbsorberEnergiesF64 = AbsorberEnergies<f64>;

/// The scalars of the dynamic state (the vectors q, v, a are copied into caller arrays).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AbsorberStateInfo<T> {
    /// Number of unknowns D (length of q, v, a).
    pub dofs: u32,
    /// Ball contact: 0 on the track off the stops, +1 / −1 resting on the positive / negative
    /// stop, 2 in flight, 3 rolling on the arc beyond the stops.
    pub contact: i32,
    /// Whole steps since the start.
    pub steps: u64,
    /// Time \[s\].
    pub time: T,
    /// Base acceleration of the last step \[m/s²\].
    pub base_accel: T,
    /// The ball's centre in the frame moving with the base (x along the beam from the clamp,
    /// y up) \[m\]; zero without a free ball.
    pub ball_centre: [T; 2],
    /// Its velocity \[m/s\].
    pub ball_velocity: [T; 2],
}

/// State scalars of a `float` model.
pub type AbsorberStateInfoF32 = AbsorberStateInfo<f32>;
/// State scalars of a `double` model.
pub type AbsorberStateInfoF64 = AbsorberStateInfo<f64>;

/// Monitor settings. Fill with [`absorber_monitor_config_default`], then edit.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsorberMonitorConfig {
    /// `sizeof(AbsorberMonitorConfig)` as the caller was compiled.
    pub size: u32,
    /// AASHTO detail category: 0 A, 1 B, 2 B′, 3 C, 4 C′, 5 D, 6 E, 7 E′ (default 7).
    pub detail_category: u32,
    /// `ABSORBER_THRESHOLD_CUTOFF` (default), `_EXTENDED` or `_ALL_ONCE_EXCEEDED`.
    pub threshold_rule: u32,
    /// Samples per indicator window block, ≥ 1 (default 8).
    pub block: u32,
    /// Rainflow hysteresis gate \[Pa\] (default 0: none).
    pub gate: f64,
    /// Distance from the neutral axis to the extreme fibre \[m\]; 0 (default): the rectangle
    /// implied by the beam's area and second moment.
    pub extreme_fibre: f64,
}

/// Everything the monitor has accumulated.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AbsorberMonitorReading<T> {
    /// Root stress of the last sample (top fibre, tension positive) \[Pa\].
    pub root_stress: T,
    /// Root stress of the static equilibrium \[Pa\].
    pub static_root_stress: T,
    /// Root moment of the last sample \[N·m\].
    pub root_moment: T,
    /// Miner damage, the residue counted as if the history ended now \[-\].
    pub damage: T,
    /// Equivalent constant-amplitude stress range, residue included \[Pa\].
    pub equivalent_range: T,
    /// Cycles counted, residue included.
    pub cycles: T,
    /// Largest stress range, residue included \[Pa\].
    pub max_range: T,
    /// Miner damage of the closed cycles only \[-\].
    pub closed_damage: T,
    /// Equivalent range of the closed cycles \[Pa\].
    pub closed_equivalent_range: T,
    /// Closed cycles counted.
    pub closed_cycles: T,
    /// Largest closed range \[Pa\].
    pub closed_max_range: T,
    /// Damage per hour of monitored time, residue included \[1/h\].
    pub damage_rate_per_hour: T,
    /// Tip deflection about its static value, RMS over the window \[m\].
    pub tip_rms: T,
    /// Peak |tip deflection| about its static value over the window \[m\].
    pub tip_peak: T,
    /// Ball relative angle, RMS over the window \[rad\].
    pub ball_rms: T,
    /// Mean beam energy over the window \[J\].
    pub beam_energy: T,
    /// Mean ball energy over the window \[J\].
    pub ball_energy: T,
    /// Monitored time \[s\].
    pub elapsed: T,
    /// Largest relative speed of a logged impact \[rad/s\].
    pub impact_max_relative_speed: T,
    /// Energy dissipated by the logged impacts \[J\].
    pub impact_energy_loss: T,
    /// Samples recorded.
    pub samples: u64,
    /// Rainflow reversals seen.
    pub reversals: u64,
    /// Residue points evicted because the residue was full.
    pub overflows: u64,
    /// Points in the rainflow residue.
    pub residue_len: u32,
    /// Samples refused (non-finite stress).
    pub rejected: u32,
    /// Stop impacts since the start.
    pub impacts: u32,
    /// Impacts after which the ball stayed on the stop.
    pub impacts_stuck: u32,
    /// Fraction of the samples with the ball in flight \[-\].
    pub flight_fraction: T,
    /// Largest friction coefficient rolling needed on the track, `|F_t|/N` \[-\].
    pub peak_rolling_friction: T,
    /// Largest friction coefficient a rolling landing needed, `|P_t|/P_n` \[-\].
    pub peak_landing_friction: T,
    /// Times the ball left the track.
    pub separations: u32,
    /// Landings on the track (bounces included).
    pub landings: u32,
}

/// Monitor reading of a `float` monitor.
pub type AbsorberMonitorReadingF32 = AbsorberMonitorReading<f32>;
/// Monitor reading of a `double` monitor.
pub type AbsorberMonitorReadingF64 = AbsorberMonitorReading<f64>;
