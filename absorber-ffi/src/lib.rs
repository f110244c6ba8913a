//! # absorber-ffi — the C API of `absorber-core`
//!
//! For firmware written in C (vendor HALs, Zephyr, FreeRTOS): the same model, the same bits, the
//! same promise as the Rust core — **no heap, no panic, bounded work per step** — behind a
//! plain C interface. The header `include/absorber.h` is generated from this file by cbindgen
//! and committed; `tests/header.rs` regenerates it in memory and fails when it drifts.
//!
//! ## Design
//!
//! * **The caller owns the memory.** A model lives in storage the caller provides (a `static`
//!   array, typically): `ABSORBER_MODEL_SIZE_<VARIANT>` bytes aligned to `ABSORBER_MODEL_ALIGN`.
//!   [`absorber_init`] builds the model there (static equilibrium, consistent start) and hands
//!   back an opaque [`AbsorberModel`] pointer into that storage. Nothing is allocated, nothing
//!   needs freeing; the storage may be reused by calling `absorber_init` again. The monitor
//!   ([`absorber_monitor_init`]) works the same way with `ABSORBER_MONITOR_SIZE_F32`/`_F64`.
//!   The size constants are upper bounds valid for every target (the model holds `usize`
//!   fields, so its exact size differs between a 32-bit MCU and a 64-bit host);
//!   [`absorber_model_size`] gives the exact figure of this build.
//! * **Scene, element count and scalar are fixed at compile time**, as in the Rust core, by a
//!   documented set of prebuilt **variants** (`ABSORBER_VARIANT_*`):
//!
//!   | variant | scene | elements N | unknowns D | scalar | Rust firmware twin |
//!   |---|---|---:|---:|---|---|
//!   | `ABSORBER_VARIANT_FREE_N3_F32` | beam + tip + free ball with stops (the paper's) | 3 | 13 | `float` | `fw-free` |
//!   | `ABSORBER_VARIANT_LOCKED_N3_F32` | beam + tip + locked ball (passive) | 3 | 12 | `float` | `fw-locked` |
//!   | `ABSORBER_VARIANT_BEAM_N3_F32` | beam alone | 3 | 12 | `float` | `fw-beam` |
//!   | `ABSORBER_VARIANT_FREE_N6_F32` | free ball, finer beam | 6 | 25 | `float` | `fw-free-n6` |
//!   | `ABSORBER_VARIANT_FREE_N3_F64` | free ball (host tools, FPUs with `double`) | 3 | 13 | `double` | — |
//!
//!   Each variant is a Cargo feature of this crate (`free-n3-f32`, …, all on by default). A
//!   firmware builds the library with only the variant it runs
//!   (`--no-default-features --features free-n3-f32`) so that only that model's code is linked;
//!   the header lists every variant regardless, and `absorber_init` answers
//!   `ABSORBER_STATUS_VARIANT` for one not compiled in. Another scene or element count is one
//!   line in [`variants`] plus a feature.
//! * **Two function families by scalar**: `*_f32` for the `float` variants, `*_f64` for the
//!   `double` one (a `float` model on a Cortex-M4F must not convert through `double`, a
//!   soft-float call there). Calling one on a model of the other scalar returns
//!   `ABSORBER_STATUS_PRECISION`. Parameters are always given in `double` ([`AbsorberParams`]);
//!   a `float` variant rounds each to nearest, exactly as `Params::<f32>::default()` does.
//! * **Parameters are extensible.** [`AbsorberParams`] starts with its own `size`; always fill
//!   it with [`absorber_params_default`] (the paper's Table 1, and `size = sizeof`) and then
//!   change fields. When fields are added (at the end of the struct), a caller compiled against
//!   an older header is refused with `ABSORBER_STATUS_INVALID_PARAMETER` on field `size`
//!   instead of being read past its struct.
//! * **Errors are values.** Every function returns an [`AbsorberStatus`]. [`absorber_init`]
//!   validates the parameters with the core's `Params::validate` and, on a bad one, writes the
//!   dotted name of the field (`"beam.modulus"`, as in the core and the scene files) and the
//!   reason into an [`AbsorberError`] (NUL-terminated `char` arrays: no pointer into the
//!   library, no lifetime to manage). A failed step leaves the state exactly as it was.
//! * **No panic.** No function unwraps or indexes unchecked; the `#[panic_handler]` of the
//!   bare-metal build only exists because a `no_std` static library must have one (it traps
//!   with `udf`).
//!
//! ## From C
//!
//! ```c
//! #include "absorber.h"
//! static _Alignas(ABSORBER_MODEL_ALIGN) unsigned char storage[ABSORBER_MODEL_SIZE_FREE_N3_F32];
//!
//! AbsorberParams p;
//! absorber_params_default(&p);
//! p.integrator.step = 1.0 / 333.0;            /* the accelerometer's sample period [s] */
//! AbsorberModel *m;
//! AbsorberError err;
//! if (absorber_init(storage, sizeof storage, ABSORBER_VARIANT_FREE_N3_F32, &p, 0.0, &m, &err)
//!         != ABSORBER_STATUS_OK) {
//!     printf("bad parameter %s: %s\n", err.field, err.reason);
//! }
//! for (;;) {
//!     float base_accel = read_accelerometer();  /* m/s², positive up, gravity removed */
//!     AbsorberReportF32 r;
//!     if (absorber_step_f32(m, base_accel, &r) == ABSORBER_STATUS_OK) {
//!         AbsorberOutputsF32 o;
//!         absorber_outputs_f32(m, &o);       /* o.tip_deflection [m], o.ball_relative_angle [rad] */
//!     }
//! }
//! ```
//!
//! `examples/c/` is a complete firmware for QEMU's `mps2-an386` (the board of the Rust
//! firmware); it prints the same state fingerprint as `fw-free`, bit for bit.
#![no_std]
#![deny(missing_docs)]

// On a hosted target the standard library provides the panic runtime of the static library and
// of the tests; on bare metal the handler below does.
#[cfg(not(target_os = "none"))]
extern crate std;

use absorber_core::monitor::{
    DetailCategory, MomentEstimate, Monitor, MonitorConfig, RootSection, ThresholdRule,
};
use absorber_core::scalar::{lit, Real};
use absorber_core::{
    AtCap, Contact, Error, EventLocation, Impact, ImpactModel, Model, NewtonKind, Outcome, Params,
    Scene, Side, StepReport,
};
use core::ffi::{c_char, c_void};
use core::mem::{align_of, size_of, MaybeUninit};

/// The prebuilt variants: scene, element count, unknowns, scalar.
pub mod variants {
    use absorber_core::{BeamModel, FreeBallModel, LockedBallModel};
    /// `ABSORBER_VARIANT_FREE_N3_F32`.
    pub type FreeN3F32 = FreeBallModel<f32, 3, 13>;
    /// `ABSORBER_VARIANT_LOCKED_N3_F32`.
    pub type LockedN3F32 = LockedBallModel<f32, 3, 12>;
    /// `ABSORBER_VARIANT_BEAM_N3_F32`.
    pub type BeamN3F32 = BeamModel<f32, 3, 12>;
    /// `ABSORBER_VARIANT_FREE_N6_F32`.
    pub type FreeN6F32 = FreeBallModel<f32, 6, 25>;
    /// `ABSORBER_VARIANT_FREE_N3_F64`.
    pub type FreeN3F64 = FreeBallModel<f64, 3, 13>;
}
use variants::*;

// ---------------------------------------------------------------------------------------------
// Constants of the header

/// Version of this API (major × 10000 + minor × 100 + patch).
pub const ABSORBER_API_VERSION: u32 = 100;

/// Paper scene, free ball with stops, N = 3, `float`.
pub const ABSORBER_VARIANT_FREE_N3_F32: u32 = 1;
/// Locked ball (passive absorber), N = 3, `float`.
pub const ABSORBER_VARIANT_LOCKED_N3_F32: u32 = 2;
/// Beam alone, N = 3, `float`.
pub const ABSORBER_VARIANT_BEAM_N3_F32: u32 = 3;
/// Free ball with stops, N = 6, `float`.
pub const ABSORBER_VARIANT_FREE_N6_F32: u32 = 4;
/// Free ball with stops, N = 3, `double`.
pub const ABSORBER_VARIANT_FREE_N3_F64: u32 = 5;

/// Alignment of model and monitor storage \[bytes\].
pub const ABSORBER_MODEL_ALIGN: usize = 8;
/// Storage for `ABSORBER_VARIANT_FREE_N3_F32` \[bytes\] (upper bound for every target).
pub const ABSORBER_MODEL_SIZE_FREE_N3_F32: usize = 4864;
/// Storage for `ABSORBER_VARIANT_LOCKED_N3_F32` \[bytes\].
pub const ABSORBER_MODEL_SIZE_LOCKED_N3_F32: usize = 4480;
/// Storage for `ABSORBER_VARIANT_BEAM_N3_F32` \[bytes\].
pub const ABSORBER_MODEL_SIZE_BEAM_N3_F32: usize = 4480;
/// Storage for `ABSORBER_VARIANT_FREE_N6_F32` \[bytes\].
pub const ABSORBER_MODEL_SIZE_FREE_N6_F32: usize = 10752;
/// Storage for `ABSORBER_VARIANT_FREE_N3_F64` \[bytes\].
pub const ABSORBER_MODEL_SIZE_FREE_N3_F64: usize = 9344;
/// Largest number of unknowns D of any variant (the length of the state vectors).
pub const ABSORBER_MAX_DOFS: usize = 25;
/// Storage for a `float` monitor \[bytes\] (rainflow residue 128, impacts 16, window 256 blocks).
pub const ABSORBER_MONITOR_SIZE_F32: usize = 8192;
/// Storage for a `double` monitor \[bytes\].
pub const ABSORBER_MONITOR_SIZE_F64: usize = 16384;

/// `ball.impact_model`: impulse spread over the time step (default).
pub const ABSORBER_IMPACT_OVER_STEP: u32 = 0;
/// `ball.impact_model`: instantaneous impact of the discrete model.
pub const ABSORBER_IMPACT_INSTANTANEOUS: u32 = 1;
/// `integrator.newton`: one Newton matrix per step (default).
pub const ABSORBER_NEWTON_PER_STEP: u32 = 0;
/// `integrator.newton`: full Newton–Raphson.
pub const ABSORBER_NEWTON_FULL: u32 = 1;
/// `integrator.newton`: modified Newton (matrix kept across steps).
pub const ABSORBER_NEWTON_MODIFIED: u32 = 2;
/// `integrator.events`: an event (stop impact, separation, landing) splits the step at its
/// crossing (default).
pub const ABSORBER_EVENTS_CROSSING: u32 = 0;
/// `integrator.events`: every event is put at the end of its step (bounded cost per sample:
/// worst step under twice the mean; late by less than a step).
pub const ABSORBER_EVENTS_STEP_END: u32 = 1;
/// `integrator.max_work`: no cap beyond the iteration limits (default).
pub const ABSORBER_WORK_UNLIMITED: u32 = 50_000;
/// `integrator.max_work`: the firmware's cap (`absorber_core::newton::work::DEADLINE`): with
/// `ABSORBER_EVENTS_STEP_END`, no step of the free ball costs more than twice the mean
/// (`docs/embedded.md`).
pub const ABSORBER_WORK_DEADLINE: u32 = 48;
/// `at_cap`: a step whose Newton solve reached the work cap takes its iterate (flagged
/// `ABSORBER_OUTCOME_CAPPED`; default).
pub const ABSORBER_AT_CAP_TAKE: u32 = 0;
/// `at_cap`: such a step fails with `ABSORBER_STATUS_WORK_CAP`, the state kept.
pub const ABSORBER_AT_CAP_KEEP: u32 = 1;
/// [`AbsorberReport::outcome`]: every Newton solve of the step converged.
pub const ABSORBER_OUTCOME_CONVERGED: u32 = 0;
/// [`AbsorberReport::outcome`]: a Newton solve stopped at the work cap (the step was taken).
pub const ABSORBER_OUTCOME_CAPPED: u32 = 1;
/// [`AbsorberReport::outcome`]: the model restarted itself at rest.
pub const ABSORBER_OUTCOME_RESTARTED: u32 = 2;
/// `threshold_rule` of the monitor: cycles at or below the CAFT do no damage (default).
pub const ABSORBER_THRESHOLD_CUTOFF: u32 = 0;
/// `threshold_rule`: the S–N line continues below the CAFT.
pub const ABSORBER_THRESHOLD_EXTENDED: u32 = 1;
/// `threshold_rule`: no damage until a cycle exceeds the CAFT, then every cycle counts.
pub const ABSORBER_THRESHOLD_ALL_ONCE_EXCEEDED: u32 = 2;
/// Length of [`AbsorberError::field`] including the terminating NUL.
pub const ABSORBER_FIELD_LEN: usize = 48;
/// Length of [`AbsorberError::reason`] including the terminating NUL.
pub const ABSORBER_REASON_LEN: usize = 128;

// Every size constant holds its variant on this target, and the alignment suffices.
const _: () = {
    assert!(size_of::<Slot<FreeN3F32>>() <= ABSORBER_MODEL_SIZE_FREE_N3_F32);
    assert!(size_of::<Slot<LockedN3F32>>() <= ABSORBER_MODEL_SIZE_LOCKED_N3_F32);
    assert!(size_of::<Slot<BeamN3F32>>() <= ABSORBER_MODEL_SIZE_BEAM_N3_F32);
    assert!(size_of::<Slot<FreeN6F32>>() <= ABSORBER_MODEL_SIZE_FREE_N6_F32);
    assert!(size_of::<Slot<FreeN3F64>>() <= ABSORBER_MODEL_SIZE_FREE_N3_F64);
    assert!(size_of::<Slot<Monitor<f32>>>() <= ABSORBER_MONITOR_SIZE_F32);
    assert!(size_of::<Slot<Monitor<f64>>>() <= ABSORBER_MONITOR_SIZE_F64);
    assert!(align_of::<Slot<FreeN3F32>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<LockedN3F32>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<BeamN3F32>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<FreeN6F32>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<FreeN3F64>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<Monitor<f32>>>() <= ABSORBER_MODEL_ALIGN);
    assert!(align_of::<Slot<Monitor<f64>>>() <= ABSORBER_MODEL_ALIGN);
    assert!(FreeN6F32::DOFS <= ABSORBER_MAX_DOFS);
    // The header's literals are the core's constants.
    assert!(ABSORBER_WORK_UNLIMITED == absorber_core::newton::work::UNLIMITED);
    assert!(ABSORBER_WORK_DEADLINE == absorber_core::newton::work::DEADLINE);
};

// ---------------------------------------------------------------------------------------------
// Types of the header

/// What a call did. Every function of the API returns one.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbsorberStatus {
    /// Success.
    Ok = 0,
    /// A parameter is out of range; [`AbsorberError::field`] names it.
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
    /// Why, in words, NUL-terminated (may be truncated).
    pub reason: [c_char; ABSORBER_REASON_LEN],
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
    /// Hard cap on the work of one step in work units (`absorber_core::newton::work`: an
    /// assembly with its factorization 16, a residual 5, a back-substitution 1; at least 24).
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

// ---------------------------------------------------------------------------------------------
// Storage layout and dispatch

const MODEL_MAGIC: u32 = 0x4142_534d; // "ABSM"
const MONITOR_MAGIC: u32 = 0x4142_534e; // "ABSN"

/// What lives in the caller's storage: a tag, then the value. `repr(C)`: the tag is at offset 0
/// for every `M`, so it can be read before the type is known.
#[repr(C)]
struct Slot<M> {
    magic: u32,
    tag: u32,
    value: M,
}

/// The header every slot starts with.
#[repr(C)]
struct Head {
    magic: u32,
    tag: u32,
}

/// A model of scalar `T`, its type erased (one indirect call per API call).
trait Erased<T: Real> {
    fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error>;
    fn restart(&mut self, base_accel: T) -> Result<(), Error>;
    fn outputs(&self) -> AbsorberOutputs<T>;
    fn energies(&self, base_velocity: T, base_displacement: T) -> AbsorberEnergies<T>;
    fn state(&self) -> (&[T], &[T], &[T], AbsorberStateInfo<T>);
    fn root_stress(&self) -> Result<T, Error>;
    /// Builds the monitor of this model in `slot` (in place: no monitor on the stack).
    fn new_monitor_in<'a>(
        &self,
        slot: &'a mut MaybeUninit<Monitor<T>>,
        config: MonitorConfig<T>,
    ) -> Result<&'a mut Monitor<T>, Error>;
    fn record(
        &self,
        monitor: &mut Monitor<T>,
        report: &StepReport<T>,
        base_accel: T,
    ) -> Result<T, Error>;
    fn params(&self) -> &Params<T>;
}

fn contact_code(c: Contact) -> i32 {
    match c {
        Contact::Off => 0,
        Contact::OnStop(Side::Positive) => 1,
        Contact::OnStop(Side::Negative) => -1,
        Contact::InFlight => 2,
        Contact::Beyond => 3,
    }
}

/// Number of unknowns of a model type.
trait Dofs {
    const DOFS: usize;
}
impl<T: Real, S: Scene, const N: usize, const D: usize> Dofs for Model<T, S, N, D> {
    const DOFS: usize = D;
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Erased<T> for Model<T, S, N, D> {
    #[inline]
    fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error> {
        Model::step(self, base_accel)
    }

    fn restart(&mut self, base_accel: T) -> Result<(), Error> {
        Model::restart(self, base_accel)
    }

    fn outputs(&self) -> AbsorberOutputs<T> {
        let z = T::zero();
        let s = self.state();
        let (tip_angle, tip_rate) = self.tip_angle();
        let ball = self.ball_angle();
        let rel = self.ball_relative_angle();
        AbsorberOutputs {
            time: self.time(),
            tip_deflection: self.tip_deflection(),
            tip_velocity: self.tip_velocity(),
            static_tip_deflection: self.static_tip_deflection(),
            tip_angle,
            tip_rate,
            ball_angle: ball.map_or(z, |b| b.0),
            ball_rate: ball.map_or(z, |b| b.1),
            ball_relative_angle: rel.map_or(z, |b| b.0),
            ball_relative_rate: rel.map_or(z, |b| b.1),
            has_ball: u8::from(ball.is_some()),
            contact: contact_code(s.contact),
            steps: s.steps,
        }
    }

    fn energies(&self, base_velocity: T, base_displacement: T) -> AbsorberEnergies<T> {
        let e = Model::energies(self, base_velocity, base_displacement);
        AbsorberEnergies {
            beam_strain: e.beam_strain,
            beam_kinetic: e.beam_kinetic,
            beam_potential: e.beam_potential,
            tip_kinetic: e.tip_kinetic,
            tip_potential: e.tip_potential,
            ball_kinetic: e.ball_kinetic,
            ball_potential: e.ball_potential,
            total: e.total(),
        }
    }

    fn state(&self) -> (&[T], &[T], &[T], AbsorberStateInfo<T>) {
        let s = Model::state(self);
        (s.q.as_slice(), s.v.as_slice(), s.a.as_slice(), {
            let (ball_centre, ball_velocity) = self
                .ball_centre()
                .unwrap_or(([T::zero(); 2], [T::zero(); 2]));
            AbsorberStateInfo {
                dofs: D as u32,
                contact: contact_code(s.contact),
                steps: s.steps,
                time: s.time,
                base_accel: s.base_accel,
                ball_centre,
                ball_velocity,
            }
        })
    }

    fn root_stress(&self) -> Result<T, Error> {
        let section = RootSection::rectangle(&self.params().beam)?;
        Ok(section.stress_of_moment(section.root_moment(self, MomentEstimate::Reaction)))
    }

    fn new_monitor_in<'a>(
        &self,
        slot: &'a mut MaybeUninit<Monitor<T>>,
        config: MonitorConfig<T>,
    ) -> Result<&'a mut Monitor<T>, Error> {
        Monitor::new_in(slot, config, self)
    }

    fn record(
        &self,
        monitor: &mut Monitor<T>,
        report: &StepReport<T>,
        base_accel: T,
    ) -> Result<T, Error> {
        monitor.record(self, report, base_accel)
    }

    fn params(&self) -> &Params<T> {
        Model::params(self)
    }
}

/// The scalar of a function family (`f32` or `f64`) and its variants.
trait Scalar: Real {
    /// Tag of a monitor of this scalar.
    const MONITOR_TAG: u32;
    /// The model behind `slot` if its variant has this scalar (and is compiled in).
    ///
    /// # Safety
    /// `slot` points to a live `Slot` made by [`absorber_init`] with variant `tag`.
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<Self>>;
}

/// `&mut slot.value` of a slot of type `Slot<M>`.
///
/// # Safety
/// `slot` points to a live `Slot<M>`.
unsafe fn value<'a, M>(slot: *mut Head) -> &'a mut M {
    // SAFETY: the caller guarantees a live `Slot<M>`, which starts with a `Head`.
    unsafe { &mut (*slot.cast::<Slot<M>>()).value }
}

impl Scalar for f32 {
    const MONITOR_TAG: u32 = 32;
    #[inline]
    #[allow(unused_unsafe, unused_variables)] // when no variant of this scalar is compiled in
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<f32>> {
        // SAFETY (every arm): the tag was written together with a value of that variant.
        unsafe {
            match tag {
                #[cfg(feature = "free-n3-f32")]
                ABSORBER_VARIANT_FREE_N3_F32 => Some(value::<FreeN3F32>(slot)),
                #[cfg(feature = "locked-n3-f32")]
                ABSORBER_VARIANT_LOCKED_N3_F32 => Some(value::<LockedN3F32>(slot)),
                #[cfg(feature = "beam-n3-f32")]
                ABSORBER_VARIANT_BEAM_N3_F32 => Some(value::<BeamN3F32>(slot)),
                #[cfg(feature = "free-n6-f32")]
                ABSORBER_VARIANT_FREE_N6_F32 => Some(value::<FreeN6F32>(slot)),
                _ => None,
            }
        }
    }
}

impl Scalar for f64 {
    const MONITOR_TAG: u32 = 64;
    #[inline]
    #[allow(unused_unsafe, unused_variables)] // when no variant of this scalar is compiled in
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<f64>> {
        // SAFETY: as for f32.
        unsafe {
            match tag {
                #[cfg(feature = "free-n3-f64")]
                ABSORBER_VARIANT_FREE_N3_F64 => Some(value::<FreeN3F64>(slot)),
                _ => None,
            }
        }
    }
}

/// Checks a model handle and returns the model behind it.
///
/// # Safety
/// `model` is NULL or a handle returned by [`absorber_init`] whose storage is still live and
/// not used by another call at the same time.
#[inline]
unsafe fn model_of<'a, T: Scalar>(
    model: *const AbsorberModel,
) -> Result<&'a mut dyn Erased<T>, AbsorberStatus> {
    let head = model.cast::<Head>().cast_mut();
    if head.is_null() {
        return Err(AbsorberStatus::NullPointer);
    }
    if head.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: non-null and aligned; the caller guarantees it points to live storage.
    let (magic, tag) = unsafe { ((*head).magic, (*head).tag) };
    if magic != MODEL_MAGIC {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: the magic says `absorber_init` wrote a slot with this tag.
    match unsafe { T::erased(head, tag) } {
        Some(m) => Ok(m),
        None if variant_is_known(tag) => Err(AbsorberStatus::Precision),
        None => Err(AbsorberStatus::NotInitialized),
    }
}

fn variant_is_known(tag: u32) -> bool {
    (ABSORBER_VARIANT_FREE_N3_F32..=ABSORBER_VARIANT_FREE_N3_F64).contains(&tag)
}

/// Checks a monitor handle and returns the monitor behind it.
///
/// # Safety
/// As [`model_of`], for a handle of [`absorber_monitor_init`].
unsafe fn monitor_of<'a, T: Scalar>(
    monitor: *const AbsorberMonitor,
) -> Result<&'a mut Monitor<T>, AbsorberStatus> {
    let head = monitor.cast::<Head>().cast_mut();
    if head.is_null() {
        return Err(AbsorberStatus::NullPointer);
    }
    if head.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: non-null, aligned, live by the caller's guarantee.
    let (magic, tag) = unsafe { ((*head).magic, (*head).tag) };
    if magic != MONITOR_MAGIC {
        return Err(AbsorberStatus::NotInitialized);
    }
    if tag != T::MONITOR_TAG {
        return Err(AbsorberStatus::Precision);
    }
    // SAFETY: the magic and tag say a `Slot<Monitor<T>>` lives there.
    Ok(unsafe { value::<Monitor<T>>(head) })
}

fn status_of(e: &Error) -> AbsorberStatus {
    match e {
        Error::InvalidParameter { .. } => AbsorberStatus::InvalidParameter,
        Error::NonFiniteInput => AbsorberStatus::NonFiniteInput,
        Error::InputOutOfRange => AbsorberStatus::InputOutOfRange,
        Error::NoConvergence { .. } => AbsorberStatus::NoConvergence,
        Error::NonFiniteState => AbsorberStatus::NonFiniteState,
        Error::Singular => AbsorberStatus::Singular,
        Error::WorkCap => AbsorberStatus::WorkCap,
        _ => AbsorberStatus::Other,
    }
}

/// Copies `s` into `dst` as a NUL-terminated C string (truncated to fit).
fn copy_str(dst: &mut [c_char], s: &str) {
    let n = s.len().min(dst.len().saturating_sub(1));
    for (d, b) in dst.iter_mut().zip(s.as_bytes().iter().take(n)) {
        *d = *b as c_char;
    }
    if let Some(end) = dst.get_mut(n) {
        *end = 0;
    }
}

/// Writes the error details (if `error` is not NULL) and returns the status.
///
/// # Safety
/// `error` is NULL or valid for writes.
unsafe fn fail(
    error: *mut AbsorberError,
    status: AbsorberStatus,
    field: &str,
    reason: &str,
) -> AbsorberStatus {
    if !error.is_null() {
        let mut e = AbsorberError {
            status,
            field: [0; ABSORBER_FIELD_LEN],
            reason: [0; ABSORBER_REASON_LEN],
        };
        copy_str(&mut e.field, field);
        copy_str(&mut e.reason, reason);
        // SAFETY: non-null and valid for writes by the caller's guarantee.
        unsafe { error.write(e) };
    }
    status
}

/// Writes the details of a core error.
///
/// # Safety
/// `error` is NULL or valid for writes.
unsafe fn fail_core(error: *mut AbsorberError, e: &Error) -> AbsorberStatus {
    let (field, reason) = match e {
        Error::InvalidParameter { field, reason } => (*field, *reason),
        Error::NonFiniteInput => ("", "base acceleration is not finite"),
        Error::InputOutOfRange => ("", "base acceleration beyond 1e4 m/s^2"),
        Error::NoConvergence { .. } => ("", "Newton did not converge"),
        Error::NonFiniteState => ("", "state became non-finite"),
        Error::Singular => ("", "singular system matrix"),
        Error::WorkCap => ("", "the step's work cap was reached"),
        _ => ("", "error"),
    };
    // SAFETY: forwarded from the caller.
    unsafe { fail(error, status_of(e), field, reason) }
}

fn invalid(field: &'static str, reason: &'static str) -> Error {
    Error::InvalidParameter { field, reason }
}

/// The core's parameters from the C struct (each value rounded to nearest into `T`).
fn to_params<T: Real>(p: &AbsorberParams) -> Result<Params<T>, Error> {
    if p.size as usize != size_of::<AbsorberParams>() {
        return Err(invalid(
            "size",
            "is not sizeof(AbsorberParams) of this library: fill the struct with absorber_params_default() and rebuild against this header",
        ));
    }
    let mut q = Params::<T>::default();
    q.beam.length = lit(p.beam.length);
    q.beam.mass = lit(p.beam.mass);
    q.beam.area = lit(p.beam.area);
    q.beam.modulus = lit(p.beam.modulus);
    q.beam.inertia = lit(p.beam.inertia);
    q.tip.mass = lit(p.tip.mass);
    q.tip.inertia = lit(p.tip.inertia);
    q.tip.offset = lit(p.tip.offset);
    let b = &p.ball;
    q.ball.mass = lit(b.mass);
    q.ball.inertia = lit(b.inertia);
    q.ball.radius = lit(b.radius);
    q.ball.track_radius = lit(b.track_radius);
    q.ball.stop_angle = lit(b.stop_angle);
    q.ball.restitution = lit(b.restitution);
    q.ball.stick_speed = lit(b.stick_speed);
    q.ball.initial_angle = lit(b.initial_angle);
    q.ball.impact_model = match b.impact_model {
        ABSORBER_IMPACT_OVER_STEP => ImpactModel::OverStep,
        ABSORBER_IMPACT_INSTANTANEOUS => ImpactModel::Instantaneous,
        _ => {
            return Err(invalid(
                "ball.impact_model",
                "must be ABSORBER_IMPACT_OVER_STEP or ABSORBER_IMPACT_INSTANTANEOUS",
            ))
        }
    };
    let i = &p.integrator;
    q.integrator.gamma = lit(i.gamma);
    q.integrator.beta = lit(i.beta);
    q.integrator.step = lit(i.step);
    q.integrator.tolerance = lit(i.tolerance);
    q.integrator.max_iterations = i.max_iterations;
    q.integrator.newton = match i.newton {
        ABSORBER_NEWTON_PER_STEP => NewtonKind::PerStep,
        ABSORBER_NEWTON_FULL => NewtonKind::Full,
        ABSORBER_NEWTON_MODIFIED => NewtonKind::Modified,
        _ => {
            return Err(invalid(
                "integrator.newton",
                "must be ABSORBER_NEWTON_PER_STEP, _FULL or _MODIFIED",
            ))
        }
    };
    q.integrator.accept_after_budget = match i.accept_after_budget {
        0 => false,
        1 => true,
        _ => return Err(invalid("integrator.accept_after_budget", "must be 0 or 1")),
    };
    q.integrator.events = match i.events {
        ABSORBER_EVENTS_CROSSING => EventLocation::Crossing,
        ABSORBER_EVENTS_STEP_END => EventLocation::StepEnd,
        _ => {
            return Err(invalid(
                "integrator.events",
                "must be ABSORBER_EVENTS_CROSSING or ABSORBER_EVENTS_STEP_END",
            ))
        }
    };
    q.damping.stiffness_proportional = lit(p.damping.stiffness_proportional);
    q.gravity = lit(p.gravity);
    q.integrator.alpha_m = lit(p.alpha_m);
    q.integrator.alpha_f = lit(p.alpha_f);
    q.calibration.bending_stiffness = lit(p.calibration.bending_stiffness);
    q.calibration.axial_stiffness = lit(p.calibration.axial_stiffness);
    q.calibration.mass_lumping = lit(p.calibration.mass_lumping);
    q.ball.flight = match p.flight {
        0 => false,
        1 => true,
        _ => return Err(invalid("flight", "must be 0 or 1")),
    };
    q.ball.landing_restitution = lit(p.landing_restitution);
    q.integrator.max_work = p.max_work;
    q.integrator.at_cap = match p.at_cap {
        ABSORBER_AT_CAP_TAKE => AtCap::Take,
        ABSORBER_AT_CAP_KEEP => AtCap::Keep,
        _ => {
            return Err(invalid(
                "at_cap",
                "must be ABSORBER_AT_CAP_TAKE or ABSORBER_AT_CAP_KEEP",
            ))
        }
    };
    Ok(q)
}

/// Builds a `Model<T, S, N, D>` in `storage`.
///
/// # Safety
/// `storage` is valid for writes of `size` bytes; `out` and `error` as in [`absorber_init`].
unsafe fn build<T: Real, S: Scene, const N: usize, const D: usize>(
    storage: *mut c_void,
    size: usize,
    tag: u32,
    params: &AbsorberParams,
    base_accel: f64,
    out: *mut *mut AbsorberModel,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    if size < size_of::<Slot<Model<T, S, N, D>>>() {
        // SAFETY: forwarded.
        return unsafe {
            fail(
                error,
                AbsorberStatus::Storage,
                "storage_size",
                "is smaller than ABSORBER_MODEL_SIZE_<VARIANT>",
            )
        };
    }
    let p = match to_params::<T>(params) {
        Ok(p) => p,
        // SAFETY: forwarded.
        Err(e) => return unsafe { fail_core(error, &e) },
    };
    let slot = storage.cast::<Slot<Model<T, S, N, D>>>();
    // SAFETY: the storage is large enough (checked) and aligned (checked by the caller); any
    // earlier content is plain data (no destructor to run). The model is built in place in the
    // slot's value (no model on the caller's boot stack); the header is cleared first and
    // written last, so that a failed build leaves no valid handle.
    unsafe {
        core::ptr::addr_of_mut!((*slot).magic).write(0);
        let value =
            &mut *core::ptr::addr_of_mut!((*slot).value).cast::<MaybeUninit<Model<T, S, N, D>>>();
        if let Err(e) = Model::<T, S, N, D>::at_rest_in(value, p, lit(base_accel)) {
            return fail_core(error, &e);
        }
        core::ptr::addr_of_mut!((*slot).tag).write(tag);
        core::ptr::addr_of_mut!((*slot).magic).write(MODEL_MAGIC);
        out.write(slot.cast::<AbsorberModel>());
    }
    AbsorberStatus::Ok
}

// ---------------------------------------------------------------------------------------------
// The API

/// Fills `params` with the paper's Table 1 (h = 3 ms, Newton tolerance 1e-5, at most 100
/// iterations, one Newton matrix per step, no damping, g = 9.81 m/s²) and sets `size`.
///
/// # Safety
/// `params` is NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn absorber_params_default(params: *mut AbsorberParams) -> AbsorberStatus {
    if params.is_null() {
        return AbsorberStatus::NullPointer;
    }
    let d = Params::<f64>::default();
    let p = AbsorberParams {
        size: size_of::<AbsorberParams>() as u32,
        beam: AbsorberBeamParams {
            length: d.beam.length,
            mass: d.beam.mass,
            area: d.beam.area,
            modulus: d.beam.modulus,
            inertia: d.beam.inertia,
        },
        tip: AbsorberTipParams {
            mass: d.tip.mass,
            inertia: d.tip.inertia,
            offset: d.tip.offset,
        },
        ball: AbsorberBallParams {
            mass: d.ball.mass,
            inertia: d.ball.inertia,
            radius: d.ball.radius,
            track_radius: d.ball.track_radius,
            stop_angle: d.ball.stop_angle,
            restitution: d.ball.restitution,
            stick_speed: d.ball.stick_speed,
            initial_angle: d.ball.initial_angle,
            impact_model: match d.ball.impact_model {
                ImpactModel::Instantaneous => ABSORBER_IMPACT_INSTANTANEOUS,
                ImpactModel::OverStep => ABSORBER_IMPACT_OVER_STEP,
            },
        },
        integrator: AbsorberIntegratorParams {
            gamma: d.integrator.gamma,
            beta: d.integrator.beta,
            step: d.integrator.step,
            tolerance: d.integrator.tolerance,
            max_iterations: d.integrator.max_iterations,
            newton: match d.integrator.newton {
                NewtonKind::Full => ABSORBER_NEWTON_FULL,
                NewtonKind::Modified => ABSORBER_NEWTON_MODIFIED,
                NewtonKind::PerStep => ABSORBER_NEWTON_PER_STEP,
            },
            accept_after_budget: u8::from(d.integrator.accept_after_budget),
            events: match d.integrator.events {
                EventLocation::Crossing => ABSORBER_EVENTS_CROSSING,
                EventLocation::StepEnd => ABSORBER_EVENTS_STEP_END,
            },
        },
        damping: AbsorberDampingParams {
            stiffness_proportional: d.damping.stiffness_proportional,
        },
        gravity: d.gravity,
        alpha_m: d.integrator.alpha_m,
        alpha_f: d.integrator.alpha_f,
        calibration: AbsorberCalibrationParams {
            bending_stiffness: d.calibration.bending_stiffness,
            axial_stiffness: d.calibration.axial_stiffness,
            mass_lumping: d.calibration.mass_lumping,
        },
        flight: u32::from(d.ball.flight),
        landing_restitution: d.ball.landing_restitution,
        max_work: d.integrator.max_work,
        at_cap: match d.integrator.at_cap {
            AtCap::Take => ABSORBER_AT_CAP_TAKE,
            AtCap::Keep => ABSORBER_AT_CAP_KEEP,
        },
    };
    // SAFETY: non-null, valid for writes by the caller's guarantee.
    unsafe { params.write(p) };
    AbsorberStatus::Ok
}

/// Switches `params` to the generalized-α integrator with high-frequency spectral radius
/// `rho_inf` (0 to 1): sets γ, β, α_m and α_f (`absorber_core::Integrator::generalized_alpha`;
/// Chung & Hulbert 1993). Little numerical damping at the resolved modes, `rho_inf` per step at
/// the unresolved ones: use it with structural damping (`damping.stiffness_proportional`).
/// A `rho_inf` outside \[0, 1\] gives weights that `absorber_init` rejects by name.
///
/// # Safety
/// `params` is NULL or valid for reads and writes of one `AbsorberParams`.
#[no_mangle]
pub unsafe extern "C" fn absorber_params_generalized_alpha(
    params: *mut AbsorberParams,
    rho_inf: f64,
) -> AbsorberStatus {
    // SAFETY: NULL or valid by the caller's guarantee.
    let Some(p) = (unsafe { params.as_mut() }) else {
        return AbsorberStatus::NullPointer;
    };
    let i = Params::<f64>::default()
        .integrator
        .generalized_alpha(rho_inf);
    p.integrator.gamma = i.gamma;
    p.integrator.beta = i.beta;
    p.alpha_m = i.alpha_m;
    p.alpha_f = i.alpha_f;
    AbsorberStatus::Ok
}

/// Storage a variant needs in this build \[bytes\] (at most its `ABSORBER_MODEL_SIZE_*`), or 0
/// for an unknown variant or one not compiled in.
#[no_mangle]
pub extern "C" fn absorber_model_size(variant: u32) -> usize {
    match variant {
        #[cfg(feature = "free-n3-f32")]
        ABSORBER_VARIANT_FREE_N3_F32 => size_of::<Slot<FreeN3F32>>(),
        #[cfg(feature = "locked-n3-f32")]
        ABSORBER_VARIANT_LOCKED_N3_F32 => size_of::<Slot<LockedN3F32>>(),
        #[cfg(feature = "beam-n3-f32")]
        ABSORBER_VARIANT_BEAM_N3_F32 => size_of::<Slot<BeamN3F32>>(),
        #[cfg(feature = "free-n6-f32")]
        ABSORBER_VARIANT_FREE_N6_F32 => size_of::<Slot<FreeN6F32>>(),
        #[cfg(feature = "free-n3-f64")]
        ABSORBER_VARIANT_FREE_N3_F64 => size_of::<Slot<FreeN3F64>>(),
        _ => 0,
    }
}

/// Builds a model of `variant` in `storage`: validates `params`, solves the static equilibrium
/// under gravity and starts from it at rest, with `base_accel` \[m/s²\] as the input at t = 0.
/// On success `*model` is the handle (it points into `storage`).
///
/// On failure nothing is written to `*model`; if `error` is not NULL it receives the status,
/// the bad field's dotted name (`"beam.modulus"`, `"integrator.step"`, `"size"`,
/// `"storage_size"`, `"variant"`) and the reason. The storage may have been overwritten.
///
/// # Safety
/// `storage` is valid for writes of `storage_size` bytes and not used otherwise while the model
/// is; `params` is valid for reads of `params->size` bytes (NULL is refused); `model` valid for
/// a write; `error` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_init(
    storage: *mut c_void,
    storage_size: usize,
    variant: u32,
    params: *const AbsorberParams,
    base_accel: f64,
    model: *mut *mut AbsorberModel,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all `fail`/`build` calls): `error`, `storage`, `model` forwarded from the caller.
    unsafe {
        if storage.is_null() || params.is_null() || model.is_null() {
            return fail(error, AbsorberStatus::NullPointer, "", "NULL argument");
        }
        if storage.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
            return fail(
                error,
                AbsorberStatus::Storage,
                "storage",
                "is not aligned to ABSORBER_MODEL_ALIGN",
            );
        }
        // Read the size first: an older caller's struct may be shorter than ours.
        let size = params.cast::<u32>().read();
        if size as usize != size_of::<AbsorberParams>() {
            return fail(
                error,
                AbsorberStatus::InvalidParameter,
                "size",
                "is not sizeof(AbsorberParams) of this library: fill the struct with absorber_params_default()",
            );
        }
        let p = &*params;
        let (s, a, t, m, e) = (storage_size, base_accel, variant, model, error);
        match variant {
            #[cfg(feature = "free-n3-f32")]
            ABSORBER_VARIANT_FREE_N3_F32 => {
                build::<f32, absorber_core::FreeBall, 3, 13>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "locked-n3-f32")]
            ABSORBER_VARIANT_LOCKED_N3_F32 => {
                build::<f32, absorber_core::LockedBall, 3, 12>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "beam-n3-f32")]
            ABSORBER_VARIANT_BEAM_N3_F32 => {
                build::<f32, absorber_core::BeamOnly, 3, 12>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "free-n6-f32")]
            ABSORBER_VARIANT_FREE_N6_F32 => {
                build::<f32, absorber_core::FreeBall, 6, 25>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "free-n3-f64")]
            ABSORBER_VARIANT_FREE_N3_F64 => {
                build::<f64, absorber_core::FreeBall, 3, 13>(storage, s, t, p, a, m, e)
            }
            _ => fail(
                error,
                AbsorberStatus::Variant,
                "variant",
                "is not an ABSORBER_VARIANT_* compiled into this library",
            ),
        }
    }
}

impl AbsorberStatus {
    /// Every status, in the order of their values.
    const ALL: [AbsorberStatus; 15] = [
        AbsorberStatus::Ok,
        AbsorberStatus::InvalidParameter,
        AbsorberStatus::NonFiniteInput,
        AbsorberStatus::InputOutOfRange,
        AbsorberStatus::NoConvergence,
        AbsorberStatus::NonFiniteState,
        AbsorberStatus::Singular,
        AbsorberStatus::NullPointer,
        AbsorberStatus::Storage,
        AbsorberStatus::Variant,
        AbsorberStatus::Precision,
        AbsorberStatus::NotInitialized,
        AbsorberStatus::BufferTooSmall,
        AbsorberStatus::Other,
        AbsorberStatus::WorkCap,
    ];

    /// The status whose value is `raw`, if there is one.
    fn from_raw(raw: i32) -> Option<AbsorberStatus> {
        Self::ALL.into_iter().find(|s| *s as i32 == raw)
    }
}

/// A short, static, NUL-terminated name of a status (`"ok"`, `"invalid parameter"`, …);
/// `"unknown status"` for a value that is none (the argument is the status's integer value, so
/// that any value C can pass is defined behaviour).
#[no_mangle]
pub extern "C" fn absorber_status_name(status: i32) -> *const c_char {
    let Some(status) = AbsorberStatus::from_raw(status) else {
        return c"unknown status".as_ptr();
    };
    let s: &'static core::ffi::CStr = match status {
        AbsorberStatus::Ok => c"ok",
        AbsorberStatus::InvalidParameter => c"invalid parameter",
        AbsorberStatus::NonFiniteInput => c"base acceleration not finite",
        AbsorberStatus::InputOutOfRange => c"base acceleration out of range",
        AbsorberStatus::NoConvergence => c"no convergence",
        AbsorberStatus::NonFiniteState => c"non-finite state",
        AbsorberStatus::Singular => c"singular",
        AbsorberStatus::NullPointer => c"NULL pointer",
        AbsorberStatus::Storage => c"storage too small or misaligned",
        AbsorberStatus::Variant => c"unknown variant",
        AbsorberStatus::Precision => c"wrong precision",
        AbsorberStatus::NotInitialized => c"not initialized",
        AbsorberStatus::BufferTooSmall => c"buffer too small",
        AbsorberStatus::Other => c"other error",
        AbsorberStatus::WorkCap => c"work cap reached",
    };
    s.as_ptr()
}

macro_rules! try_status {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(s) => return s,
        }
    };
}

fn report_of<T: Real>(r: &StepReport<T>) -> AbsorberReport<T> {
    let z = T::zero();
    let l = r.landing;
    let mut out = AbsorberReport {
        iterations: r.iterations,
        increment: r.increment,
        separation: u8::from(r.separation.is_some()),
        landing: l.map_or(0, |l| if l.bounced { 1 } else { 2 }),
        separation_time: r.separation.unwrap_or(z),
        landing_time: l.map_or(z, |l| l.time),
        landing_normal_speed: l.map_or(z, |l| l.normal_speed),
        landing_normal_impulse: l.map_or(z, |l| l.normal_impulse),
        landing_tangential_impulse: l.map_or(z, |l| l.tangential_impulse),
        impact: 0,
        impact_stuck: 0,
        impact_side: 0,
        impact_time: z,
        impact_relative_speed: z,
        impact_impulse: z,
        impact_energy_loss: z,
        work: u32::from(r.work),
        outcome: match r.outcome {
            Outcome::Converged => ABSORBER_OUTCOME_CONVERGED,
            Outcome::Capped => ABSORBER_OUTCOME_CAPPED,
            Outcome::Restarted => ABSORBER_OUTCOME_RESTARTED,
        },
    };
    if let Some(i) = &r.impact {
        out.impact = 1;
        out.impact_stuck = u8::from(i.stuck);
        out.impact_side = match i.side {
            Side::Positive => 1,
            Side::Negative => -1,
        };
        out.impact_time = i.time;
        out.impact_relative_speed = i.relative_speed;
        out.impact_impulse = i.impulse;
        out.impact_energy_loss = i.energy_loss;
    }
    out
}

/// Steps the model.
///
/// # Safety
/// `model` as in [`model_of`]; `report` NULL or valid for a write.
#[inline(always)]
unsafe fn step<T: Scalar>(
    model: *mut AbsorberModel,
    base_accel: T,
    report: *mut AbsorberReport<T>,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    match m.step(base_accel) {
        Ok(r) => {
            if !report.is_null() {
                // SAFETY: non-null, valid for a write by the caller's guarantee.
                unsafe { report.write(report_of(&r)) };
            }
            AbsorberStatus::Ok
        }
        Err(e) => status_of(&e),
    }
}

/// Advances a `float` model by one step h to the new base acceleration ÿ_b(t + h) \[m/s²\]
/// (measured, positive up, gravity removed). On error the state is exactly as before the call
/// (log it and feed the next sample). `report` may be NULL.
///
/// # Safety
/// `model` is a handle of [`absorber_init`] whose storage is live and not used concurrently;
/// `report` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_step_f32(
    model: *mut AbsorberModel,
    base_accel: f32,
    report: *mut AbsorberReportF32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { step(model, base_accel, report) }
}

/// [`absorber_step_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_step_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_step_f64(
    model: *mut AbsorberModel,
    base_accel: f64,
    report: *mut AbsorberReportF64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { step(model, base_accel, report) }
}

/// Restarts.
///
/// # Safety
/// `model` as in [`model_of`].
unsafe fn restart<T: Scalar>(model: *mut AbsorberModel, base_accel: T) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    match m.restart(base_accel) {
        Ok(()) => AbsorberStatus::Ok,
        Err(e) => status_of(&e),
    }
}

/// Restarts a `float` model at t = 0 from its static equilibrium, at rest, with input
/// `base_accel` \[m/s²\] (recovers from any state a run of failed steps can leave).
///
/// # Safety
/// `model` is a live handle of [`absorber_init`].
#[no_mangle]
pub unsafe extern "C" fn absorber_restart_f32(
    model: *mut AbsorberModel,
    base_accel: f32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { restart(model, base_accel) }
}

/// [`absorber_restart_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_restart_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_restart_f64(
    model: *mut AbsorberModel,
    base_accel: f64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { restart(model, base_accel) }
}

/// Writes `value(model)` to `out`.
///
/// # Safety
/// `model` as in [`model_of`]; `out` NULL or valid for a write.
unsafe fn read<T: Scalar, R>(
    model: *const AbsorberModel,
    out: *mut R,
    value: impl FnOnce(&dyn Erased<T>) -> Result<R, AbsorberStatus>,
) -> AbsorberStatus {
    if out.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    let v = try_status!(value(m));
    // SAFETY: non-null, valid for a write by the caller's guarantee.
    unsafe { out.write(v) };
    AbsorberStatus::Ok
}

/// The outputs of a `float` model now: tip deflection and rotation, ball angles, their rates.
///
/// # Safety
/// `model` is a live handle of [`absorber_init`]; `out` valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_outputs_f32(
    model: *const AbsorberModel,
    out: *mut AbsorberOutputsF32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { read::<f32, _>(model, out, |m| Ok(m.outputs())) }
}

/// [`absorber_outputs_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_outputs_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_outputs_f64(
    model: *const AbsorberModel,
    out: *mut AbsorberOutputsF64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { read::<f64, _>(model, out, |m| Ok(m.outputs())) }
}

/// Energies of a `float` model's bodies \[J\]; pass the base velocity \[m/s\] and displacement
/// \[m\] for absolute kinetic energies, or 0 and 0 for the frame moving with the base
/// (`ABSORBER_STATUS_NON_FINITE_INPUT` and nothing written if either is not finite).
///
/// # Safety
/// `model` is a live handle of [`absorber_init`]; `out` valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_energies_f32(
    model: *const AbsorberModel,
    base_velocity: f32,
    base_displacement: f32,
    out: *mut AbsorberEnergiesF32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe {
        read::<f32, _>(model, out, |m| {
            if !(base_velocity.is_finite() && base_displacement.is_finite()) {
                return Err(AbsorberStatus::NonFiniteInput);
            }
            Ok(m.energies(base_velocity, base_displacement))
        })
    }
}

/// [`absorber_energies_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_energies_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_energies_f64(
    model: *const AbsorberModel,
    base_velocity: f64,
    base_displacement: f64,
    out: *mut AbsorberEnergiesF64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe {
        read::<f64, _>(model, out, |m| {
            if !(base_velocity.is_finite() && base_displacement.is_finite()) {
                return Err(AbsorberStatus::NonFiniteInput);
            }
            Ok(m.energies(base_velocity, base_displacement))
        })
    }
}

/// Root bending stress of a `float` model now (top fibre, tension positive) \[Pa\]: the clamp
/// reaction moment over the section modulus of the rectangle implied by the beam's area and
/// second moment (as the monitor's default).
///
/// # Safety
/// `model` is a live handle of [`absorber_init`]; `stress` valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_root_stress_f32(
    model: *const AbsorberModel,
    stress: *mut f32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe {
        read::<f32, _>(model, stress, |m| {
            m.root_stress().map_err(|e| status_of(&e))
        })
    }
}

/// [`absorber_root_stress_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_root_stress_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_root_stress_f64(
    model: *const AbsorberModel,
    stress: *mut f64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe {
        read::<f64, _>(model, stress, |m| {
            m.root_stress().map_err(|e| status_of(&e))
        })
    }
}

/// Copies the state.
///
/// # Safety
/// As [`absorber_state_f32`].
unsafe fn state<T: Scalar>(
    model: *const AbsorberModel,
    info: *mut AbsorberStateInfo<T>,
    q: *mut T,
    v: *mut T,
    a: *mut T,
    capacity: usize,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    let (sq, sv, sa, i) = m.state();
    for (dst, src) in [(q, sq), (v, sv), (a, sa)] {
        if dst.is_null() {
            continue;
        }
        if capacity < src.len() {
            return AbsorberStatus::BufferTooSmall;
        }
        // SAFETY: `dst` is valid for `capacity` ≥ `src.len()` writes by the caller's guarantee
        // and does not overlap the model.
        unsafe { core::ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len()) };
    }
    if !info.is_null() {
        // SAFETY: non-null, valid for a write.
        unsafe { info.write(i) };
    }
    AbsorberStatus::Ok
}

/// The full dynamic state of a `float` model: `info` gets D, time, steps, last input and
/// contact; `q`, `v`, `a` (each NULL or an array of `capacity` ≥ D floats, e.g.
/// `ABSORBER_MAX_DOFS`) get the coordinates (displacements from the straight reference \[m, -\],
/// then the ball's spin angle \[rad\]), their velocities and accelerations relative to the base.
///
/// # Safety
/// `model` is a live handle of [`absorber_init`]; `info` NULL or valid for a write; `q`, `v`,
/// `a` NULL or valid for `capacity` writes each.
#[no_mangle]
pub unsafe extern "C" fn absorber_state_f32(
    model: *const AbsorberModel,
    info: *mut AbsorberStateInfoF32,
    q: *mut f32,
    v: *mut f32,
    a: *mut f32,
    capacity: usize,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { state(model, info, q, v, a, capacity) }
}

/// [`absorber_state_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_state_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_state_f64(
    model: *const AbsorberModel,
    info: *mut AbsorberStateInfoF64,
    q: *mut f64,
    v: *mut f64,
    a: *mut f64,
    capacity: usize,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { state(model, info, q, v, a, capacity) }
}

// ---------------------------------------------------------------------------------------------
// The monitor

/// Fills `config` with the monitor's defaults (`MonitorConfig::paper`: rectangle section,
/// clamp-reaction moment, AASHTO category E′ with the CAFT cutoff, no gate, blocks of 8).
///
/// # Safety
/// `config` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_config_default(
    config: *mut AbsorberMonitorConfig,
) -> AbsorberStatus {
    if config.is_null() {
        return AbsorberStatus::NullPointer;
    }
    let c = AbsorberMonitorConfig {
        size: size_of::<AbsorberMonitorConfig>() as u32,
        detail_category: 7,
        threshold_rule: ABSORBER_THRESHOLD_CUTOFF,
        block: 8,
        gate: 0.0,
        extreme_fibre: 0.0,
    };
    // SAFETY: non-null, valid for a write.
    unsafe { config.write(c) };
    AbsorberStatus::Ok
}

fn monitor_config<T: Real>(
    c: &AbsorberMonitorConfig,
    params: &Params<T>,
) -> Result<MonitorConfig<T>, Error> {
    if c.size as usize != size_of::<AbsorberMonitorConfig>() {
        return Err(invalid(
            "monitor.size",
            "is not sizeof(AbsorberMonitorConfig): fill it with absorber_monitor_config_default()",
        ));
    }
    let mut m = MonitorConfig::paper(params)?;
    let category = DetailCategory::ALL
        .get(c.detail_category as usize)
        .copied()
        .ok_or(invalid("monitor.detail_category", "must be 0 (A) … 7 (E')"))?;
    let rule = match c.threshold_rule {
        ABSORBER_THRESHOLD_CUTOFF => ThresholdRule::Cutoff,
        ABSORBER_THRESHOLD_EXTENDED => ThresholdRule::Extended,
        ABSORBER_THRESHOLD_ALL_ONCE_EXCEEDED => ThresholdRule::AllOnceExceeded,
        _ => {
            return Err(invalid(
                "monitor.threshold_rule",
                "must be an ABSORBER_THRESHOLD_* constant",
            ))
        }
    };
    m.curve = category.curve(rule);
    m.block = match u16::try_from(c.block) {
        Ok(b) if b >= 1 => b,
        _ => return Err(invalid("monitor.block", "must lie in 1 ..= 65535")),
    };
    m.gate = lit(c.gate);
    if c.extreme_fibre != 0.0 {
        m.section = RootSection::new(&params.beam, lit(c.extreme_fibre))?;
    }
    Ok(m)
}

/// Builds a monitor.
///
/// # Safety
/// As [`absorber_monitor_init`].
unsafe fn monitor_init<T: Scalar>(
    storage: *mut c_void,
    storage_size: usize,
    model: &dyn Erased<T>,
    config: &AbsorberMonitorConfig,
    out: *mut *mut AbsorberMonitor,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all calls): pointers forwarded from the caller.
    unsafe {
        if storage_size < size_of::<Slot<Monitor<T>>>() {
            return fail(
                error,
                AbsorberStatus::Storage,
                "storage_size",
                "is smaller than ABSORBER_MONITOR_SIZE_F32/_F64",
            );
        }
        let slot = storage.cast::<Slot<Monitor<T>>>();
        // The monitor is built in place in the slot's value (its window alone is kilobytes: a
        // C caller's boot stack does not carry a copy); the header is cleared first and
        // written last, so that a failed build leaves no valid handle.
        core::ptr::addr_of_mut!((*slot).magic).write(0);
        let value = &mut *core::ptr::addr_of_mut!((*slot).value).cast::<MaybeUninit<Monitor<T>>>();
        if let Err(e) =
            monitor_config(config, model.params()).and_then(|c| model.new_monitor_in(value, c))
        {
            return fail_core(error, &e);
        }
        core::ptr::addr_of_mut!((*slot).tag).write(T::MONITOR_TAG);
        core::ptr::addr_of_mut!((*slot).magic).write(MONITOR_MAGIC);
        out.write(slot.cast::<AbsorberMonitor>());
    }
    AbsorberStatus::Ok
}

/// Builds the on-device monitor of `model` (root stress, rainflow fatigue, impact log,
/// windowed indicators; `docs/monitoring.md`) in `storage` (`ABSORBER_MONITOR_SIZE_F32` or
/// `_F64` bytes by the model's scalar, aligned to `ABSORBER_MODEL_ALIGN`). The model's current
/// state is the first sample. `config` NULL means the defaults.
///
/// # Safety
/// `storage` valid for writes of `storage_size` bytes and not otherwise used while the monitor
/// is; `model` a live handle of [`absorber_init`]; `config` NULL or valid for reads; `monitor`
/// valid for a write; `error` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_init(
    storage: *mut c_void,
    storage_size: usize,
    model: *const AbsorberModel,
    config: *const AbsorberMonitorConfig,
    monitor: *mut *mut AbsorberMonitor,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all calls): pointers forwarded from the caller.
    unsafe {
        if storage.is_null() || monitor.is_null() {
            return fail(error, AbsorberStatus::NullPointer, "", "NULL argument");
        }
        if storage.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
            return fail(
                error,
                AbsorberStatus::Storage,
                "storage",
                "is not aligned to ABSORBER_MODEL_ALIGN",
            );
        }
        let mut c = AbsorberMonitorConfig {
            size: 0,
            detail_category: 0,
            threshold_rule: 0,
            block: 0,
            gate: 0.0,
            extreme_fibre: 0.0,
        };
        if config.is_null() {
            absorber_monitor_config_default(&mut c);
        } else {
            if config.cast::<u32>().read() as usize != size_of::<AbsorberMonitorConfig>() {
                return fail(
                    error,
                    AbsorberStatus::InvalidParameter,
                    "monitor.size",
                    "is not sizeof(AbsorberMonitorConfig): fill it with absorber_monitor_config_default()",
                );
            }
            c = *config;
        }
        match model_of::<f32>(model) {
            Ok(m) => return monitor_init::<f32>(storage, storage_size, m, &c, monitor, error),
            Err(AbsorberStatus::Precision) => {}
            Err(s) => return fail(error, s, "model", "is not a model built by absorber_init"),
        }
        match model_of::<f64>(model) {
            Ok(m) => monitor_init::<f64>(storage, storage_size, m, &c, monitor, error),
            Err(s) => fail(error, s, "model", "is not a model built by absorber_init"),
        }
    }
}

/// Records.
///
/// # Safety
/// As [`absorber_monitor_record_f32`].
unsafe fn monitor_record<T: Scalar>(
    monitor: *mut AbsorberMonitor,
    model: *const AbsorberModel,
    report: *const AbsorberReport<T>,
    base_accel: T,
    stress: *mut T,
) -> AbsorberStatus {
    if report.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded.
    let (mon, m, r) = unsafe {
        (
            try_status!(monitor_of::<T>(monitor)),
            try_status!(model_of::<T>(model)),
            &*report,
        )
    };
    let side = if r.impact_side < 0 {
        Side::Negative
    } else {
        Side::Positive
    };
    let rep = StepReport {
        iterations: r.iterations,
        increment: r.increment,
        impact: (r.impact != 0).then_some(Impact {
            time: r.impact_time,
            side,
            relative_speed: r.impact_relative_speed,
            impulse: r.impact_impulse,
            energy_loss: r.impact_energy_loss,
            stuck: r.impact_stuck != 0,
        }),
        separation: (r.separation != 0).then_some(r.separation_time),
        landing: (r.landing != 0).then_some(absorber_core::Landing {
            time: r.landing_time,
            normal_speed: r.landing_normal_speed,
            normal_impulse: r.landing_normal_impulse,
            tangential_impulse: r.landing_tangential_impulse,
            bounced: r.landing == 1,
        }),
        work: u16::try_from(r.work).unwrap_or(u16::MAX),
        outcome: match r.outcome {
            ABSORBER_OUTCOME_CAPPED => Outcome::Capped,
            ABSORBER_OUTCOME_RESTARTED => Outcome::Restarted,
            _ => Outcome::Converged,
        },
        // The C report carries one event of each kind (its flags): counted as such.
        events: absorber_core::EventCounts {
            separations: u8::from(r.separation != 0),
            landings: u8::from(r.landing != 0),
            bounces: u8::from(r.landing == 1),
            impacts: u8::from(r.impact != 0),
        },
    };
    match m.record(mon, &rep, base_accel) {
        Ok(s) => {
            if !stress.is_null() {
                // SAFETY: non-null, valid for a write.
                unsafe { stress.write(s) };
            }
            AbsorberStatus::Ok
        }
        Err(e) => status_of(&e),
    }
}

/// Records `model`'s state after a successful step into the monitor: `report` is what
/// [`absorber_step_f32`] wrote, `base_accel` its input. `stress` (may be NULL) receives the root
/// stress \[Pa\]. A non-finite stress is refused (`ABSORBER_STATUS_NON_FINITE_STATE`, counted).
///
/// # Safety
/// `monitor` a live handle of [`absorber_monitor_init`] made for `model`; `model` a live handle
/// of [`absorber_init`]; `report` valid for reads; `stress` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_record_f32(
    monitor: *mut AbsorberMonitor,
    model: *const AbsorberModel,
    report: *const AbsorberReportF32,
    base_accel: f32,
    stress: *mut f32,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { monitor_record(monitor, model, report, base_accel, stress) }
}

/// [`absorber_monitor_record_f32`] for a `double` model.
///
/// # Safety
/// As [`absorber_monitor_record_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_record_f64(
    monitor: *mut AbsorberMonitor,
    model: *const AbsorberModel,
    report: *const AbsorberReportF64,
    base_accel: f64,
    stress: *mut f64,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { monitor_record(monitor, model, report, base_accel, stress) }
}

fn reading<T: Real>(m: &Monitor<T>) -> AbsorberMonitorReading<T> {
    let f = m.fatigue();
    let c = m.fatigue_closed();
    let v = m.indicators();
    let imp = m.impacts();
    AbsorberMonitorReading {
        root_stress: m.root_stress(),
        static_root_stress: m.static_root_stress(),
        root_moment: m.root_moment(),
        damage: f.damage,
        equivalent_range: f.equivalent_range,
        cycles: f.cycles,
        max_range: f.max_range,
        closed_damage: c.damage,
        closed_equivalent_range: c.equivalent_range,
        closed_cycles: c.cycles,
        closed_max_range: c.max_range,
        damage_rate_per_hour: m.damage_rate_per_hour(),
        tip_rms: v.tip_rms,
        tip_peak: v.tip_peak,
        ball_rms: v.ball_rms,
        beam_energy: v.beam_energy,
        ball_energy: v.ball_energy,
        elapsed: m.elapsed(),
        impact_max_relative_speed: imp.max_relative_speed(),
        impact_energy_loss: imp.energy_loss(),
        samples: m.samples(),
        reversals: m.rainflow().reversals(),
        overflows: m.rainflow().overflows(),
        residue_len: m.rainflow().residue_len() as u32,
        rejected: m.rejected(),
        impacts: imp.total(),
        impacts_stuck: imp.stuck(),
        flight_fraction: m.flight_fraction(),
        peak_rolling_friction: m.flight().peak_rolling_friction,
        peak_landing_friction: m.flight().peak_landing_friction,
        separations: m.flight().separations,
        landings: m.flight().landings,
    }
}

/// Everything a `float` monitor has accumulated (fatigue with and without the residue, the
/// window indicators, impact and sample counts). O(residue + window) work.
///
/// # Safety
/// `monitor` a live handle of [`absorber_monitor_init`]; `out` valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_read_f32(
    monitor: *const AbsorberMonitor,
    out: *mut AbsorberMonitorReadingF32,
) -> AbsorberStatus {
    if out.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded; `out` non-null and valid for a write.
    unsafe {
        let m = try_status!(monitor_of::<f32>(monitor));
        out.write(reading(m));
    }
    AbsorberStatus::Ok
}

/// [`absorber_monitor_read_f32`] for a `double` monitor.
///
/// # Safety
/// As [`absorber_monitor_read_f32`].
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_read_f64(
    monitor: *const AbsorberMonitor,
    out: *mut AbsorberMonitorReadingF64,
) -> AbsorberStatus {
    if out.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded; `out` non-null and valid for a write.
    unsafe {
        let m = try_status!(monitor_of::<f64>(monitor));
        out.write(reading(m));
    }
    AbsorberStatus::Ok
}

// ---------------------------------------------------------------------------------------------
// Helpers

/// Single-precision sine of the `libm` crate (musl's algorithm), the one the Rust firmware and
/// host references use for their excitation: a C program that must reproduce a Rust run bit
/// for bit computes its input with it (a C library's `sinf` may differ in the last bit).
#[no_mangle]
pub extern "C" fn absorber_sinf(x: f32) -> f32 {
    libm::sinf(x)
}

/// Panics cannot happen on any path of this API (no unwrap, no unchecked indexing); a `no_std`
/// static library must still name a handler. It traps (HardFault on a Cortex-M).
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {
        // SAFETY: `udf` raises an undefined-instruction exception; nothing else is touched.
        #[cfg(target_arch = "arm")]
        unsafe {
            core::arch::asm!("udf #0")
        };
    }
}
