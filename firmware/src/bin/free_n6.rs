//! `fw-free-n6`: the free-ball scene on 6 elements, D = 25 (what a finer beam costs).
//!
//! It keeps the full scene (`FreeBall`), not the firmware's `FwFreeBall`: without the code of
//! the events at their crossings its step took 3.0 % more instructions at opt 3 (26,120 ->
//! 26,904 per step, every state the same: the optimizer's inlining moved across the step),
//! for 6.6 KB less flash at opt s, and time per sample is what the bins are budgeted on.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::Configured<
    absorber_core::FreeBallModel<f32, 6, 25>,
    absorber_firmware::Cap<48>,
>;

absorber_firmware::firmware_main!(M);
