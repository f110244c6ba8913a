//! `fw-free-rolling`: the paper's absorber with the ball held on its track (the bilateral track
//! of the paper, `FreeBallNoFlight`): the rolling model flight is compared with. 3 elements,
//! D = 13.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_core::Model<f32, absorber_core::FreeBallNoFlight, 3, 13>;

absorber_firmware::firmware_main!(M);
