//! # absorber-firmware
//!
//! `absorber-core` on a Cortex-M4F, run under QEMU (`-M mps2-an386`), and the same scene run on
//! the host as the bit-for-bit reference.
//!
//! Every bin of this crate (`fw-free`, `fw-free-modified`, `fw-free-monitor`, `fw-beam`,
//! `fw-locked`, the monitor loop `fw-monitor-loop` ([`monitor_loop`]), and the model-less
//! baseline `fw-empty`, among others) builds twice from one source:
//!
//! * for `thumbv7em-none-eabihf`: `no_std`, `no_main`, cortex-m-rt, output and exit code through
//!   semihosting; the model lives in a `static` (so it shows in `.bss`);
//! * for the host: an ordinary program that prints exactly the same text, which is the
//!   reference the firmware must reproduce bit for bit.
//!
//! The scene driver, [`run`], is shared. It feeds the base acceleration
//! `ÿ_b(t_k) = −A Ω² sin(Ω t_k)`, `t_k = k h`, `k = 1..=STEPS`, computed in `f32` with `libm`,
//! prints tip deflection and ball angle at every whole second, and folds every step's full
//! state and report into a 64-bit FNV-1a fingerprint ([`Summary::hash`]). The firmware gets the
//! host's fingerprint as a semihosting argument (`expect=0x…`) and exits 0 only if they agree.
//!
//! The model step is called through [`Sim::step`], a non-inlined function per scene, so its
//! instructions can be counted between its entry and its return address (see
//! `scripts/embedded-report.sh`). In `fw-free-monitor` ([`WithMonitor`]) that step also feeds an
//! `absorber_core::monitor::Monitor`, through [`monitor_record`], itself non-inlined so the
//! monitor's share is counted on its own.
#![cfg_attr(target_os = "none", no_std)]

use absorber_core::{EventLocation, Model, Params};
#[cfg(not(target_os = "none"))]
pub use driver::host_main;
pub use driver::{error_name, run, Fnv, NoProbe, Probe, Summary};
pub use monitored::{monitor_record, WithMonitor};
pub use scenes::{Cap, Config, Configured, Empty, InFlight, Modified, ModifiedNewton, Planted};
pub use sim::Sim;
pub use stress::Setup;

// The driver's float printing and the ball's spun start, for the scenes of other modules.
use driver::F;
use sim::spin_start;

/// Excitation amplitude A \[m\] (the paper's free-ball run).
pub const AMPLITUDE: f32 = 0.5e-3;
/// Excitation frequency \[Hz\]: Ω = 2π·4.13 rad/s.
pub const FREQUENCY_HZ: f32 = 4.13;
/// Simulated time \[s\].
pub const DURATION_S: u32 = 20;
/// Time step in milliseconds (must equal `Params::default().integrator.step`).
pub const STEP_MS: u32 = 3;
/// Number of steps: ⌈20 s / 3 ms⌉ = 6667.
pub const STEPS: u32 = (DURATION_S * 1000).div_ceil(STEP_MS);

/// Base acceleration ÿ_b at the end of step `k` (time `k h`) \[m/s²\] at `frequency` \[Hz\], in
/// `f32` with `libm`.
#[inline(never)]
pub fn base_accel(k: u32, h: f32, frequency: f32) -> f32 {
    let omega = 2.0 * core::f32::consts::PI * frequency;
    let t = k as f32 * h;
    -AMPLITUDE * omega * omega * libm::sinf(omega * t)
}

/// The firmware's parameters: `Params::default()` (the paper's Table 1) with every event at
/// the end of its step and the work cap for a deadline per sample (`docs/embedded.md`,
/// "Firmware defaults": the choice measured), and a stress scene's restitution.
pub fn firmware_params(setup: &Setup) -> Params<f32> {
    let mut p = Params::<f32>::default();
    p.integrator.events = EventLocation::StepEnd;
    p.integrator.max_work = absorber_core::work::DEADLINE;
    if let Some(e) = setup.stress.and_then(|s| s.restitution) {
        p.ball.restitution = e;
        p.ball.landing_restitution = e;
    }
    p
}

/// The free ball as the firmware runs it ([`firmware_params`]: every event at the end of its
/// step): the code of events at their crossings and of the perfectly elastic ball's rules is
/// left out at compile time ([`absorber_core::AtStepEnd`]); its runs are those of
/// `FreeBallModel<f32, N, D>`, bit for bit.
pub type FwFreeBall<const N: usize, const D: usize> =
    Model<f32, absorber_core::AtStepEnd<absorber_core::FreeBall>, N, D>;

/// `&mut MaybeUninit` of the field `$f` of the value in `$slot: &mut MaybeUninit<_>`: builds the
/// parts of a scene in place.
macro_rules! field {
    ($slot:expr, $f:tt) => {{
        let slot: &mut MaybeUninit<_> = $slot;
        let p = slot.as_mut_ptr();
        // SAFETY: a pointer to a field of the value `slot` holds, computed without a reference
        // to the (uninitialized) value: as valid for writes as `slot`, for as long;
        // `MaybeUninit<F>` has the field's layout.
        unsafe { &mut *core::ptr::addr_of_mut!((*p).$f).cast::<MaybeUninit<_>>() }
    }};
}

/// The `main` of a firmware bin that runs the scene type `$m` ([`Sim`]): on the target the
/// cortex-m-rt entry with the model in a static (`target::target_main`), on the host
/// [`host_main`], which prints the reference the target must reproduce bit for bit.
#[macro_export]
macro_rules! firmware_main {
    ($m:ty) => {
        #[cfg(target_os = "none")]
        #[cortex_m_rt::entry]
        fn main() -> ! {
            static mut MODEL: core::mem::MaybeUninit<$m> = core::mem::MaybeUninit::uninit();
            $crate::target::target_main::<$m>(MODEL)
        }

        #[cfg(not(target_os = "none"))]
        fn main() {
            $crate::host_main::<$m>()
        }
    };
}

mod driver;
mod monitored;
mod scenes;
mod sim;

pub mod cost;
pub mod estimator;
pub mod monitor_loop;
pub mod stress;
#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
#[rustfmt::skip]
pub mod estimator_gain;

#[cfg(target_os = "none")]
pub mod target;
