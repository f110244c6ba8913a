//! # absorber-ffi — the C API of `absorber-core`
//!
//! For firmware written in C (vendor HALs, Zephyr, FreeRTOS): the same model, the same bits, the
//! same promise as the Rust core — **no heap, no panic, bounded work per step** — behind a
//! plain C interface. The header `include/absorber.h` is generated from this crate by cbindgen
//! and committed; `tests/header.rs` regenerates it in memory and fails when it drifts. The
//! `float`/`double` twins of each function are written once (the `twins!` macro); cbindgen reads the
//! macro-expanded crate, so the header declares both.
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
//!   dotted name of the field (`"beam.modulus"`, as in the core and the scene files), the
//!   reason with the allowed range (NUL-terminated `char` arrays: no pointer into the library,
//!   no lifetime to manage) and the value given for the field, as a `double` (`value`, valid
//!   when `has_value` is 1: the library formats no floats) into an [`AbsorberError`]. A failed
//!   step leaves the state exactly as it was.
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
//!     printf("bad parameter %s = %g: %s\n", err.field, err.value, err.reason);
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

/// Version of this API (major × 10000 + minor × 100 + patch). 0.2.0: [`AbsorberError`] carries
/// the value of the bad field (a larger struct: callers rebuild against this header).
pub const ABSORBER_API_VERSION: u32 = 200;

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
/// `integrator.max_work`: the firmware's cap (`absorber_core::work::DEADLINE`): with
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
    assert!(ABSORBER_WORK_UNLIMITED == absorber_core::work::UNLIMITED);
    assert!(ABSORBER_WORK_DEADLINE == absorber_core::work::DEADLINE);
};

// ---------------------------------------------------------------------------------------------
// The API, by idea: the types of the header, the storage of a handle, the model, the monitor

macro_rules! try_status {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(s) => return s,
        }
    };
}

/// The `float` and `double` twins of one C function, written once:
///
/// ```text
/// twins! {
///     /// Documentation of the `float` twin.
///     fn name_f32 / name_f64 (double model) <T> (
///         arg: SameForBoth,
///         x: f32 => f64,          // the `float` twin's type => the `double` twin's
///     ) { body }
/// }
/// ```
///
/// Both twins get the same body (generic code the argument types instantiate); `<T>`, when
/// given, names the twin's scalar inside it. The `double` twin's documentation points to the
/// `float` one, naming it a `double` model (or monitor). cbindgen reads the expanded crate
/// (`tests/header.rs`), so the header declares both.
macro_rules! twins {
    (
        $(#[doc = $doc:literal])*
        fn $f32:ident / $f64:ident (double $noun:ident) $(<$t:ident>)? (
            $($arg:ident: $t32:ty $(=> $t64:ty)?),* $(,)?
        ) $body:block
    ) => {
        $(#[doc = $doc])*
        #[no_mangle]
        pub unsafe extern "C" fn $f32($($arg: $t32),*) -> AbsorberStatus {
            $(type $t = f32;)?
            $body
        }

        #[doc = concat!(" [`", stringify!($f32), "`] for a `double` ", stringify!($noun), ".")]
        #[doc = ""]
        #[doc = " # Safety"]
        #[doc = concat!(" As [`", stringify!($f32), "`].")]
        #[no_mangle]
        pub unsafe extern "C" fn $f64($($arg: double_side!($t32 $(=> $t64)?)),*) -> AbsorberStatus {
            $(type $t = f64;)?
            $body
        }
    };
}

/// The `double` twin's type of one [`twins!`] argument: the type after `=>`, else the same.
macro_rules! double_side {
    ($same:ty) => {
        $same
    };
    ($f32:ty => $f64:ty) => {
        $f64
    };
}

mod model;
mod monitor;
mod sine;
mod storage;
mod types;

pub use model::*;
pub use monitor::*;
pub use sine::*;
use storage::*;
pub use types::*;

// ---------------------------------------------------------------------------------------------
// The panic handler of the bare-metal build

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
