//! `fw-locked`: beam + tip mass + locked ball, 3 elements, D = 12.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::Configured<
    absorber_core::LockedBallModel<f32, 3, 12>,
    absorber_firmware::Cap<25>,
>;

absorber_firmware::firmware_main!(M);
