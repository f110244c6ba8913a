//! `fw-free-rolling`: the paper's absorber with the ball held on its track (the bilateral track
//! of the paper, `FreeBallNoFlight`): the rolling model flight is compared with. 3 elements,
//! D = 13. Its work cap is 47 units, one under the free ball's: with 48 its hardest paper step
//! (46 units: two refreshed Newton iterations) fits, and under noise at the input limit a capped
//! step took 2.02 times the mean; with 47 that step's second refresh gives way to the factors in
//! hand (41 units, still converged: no paper step is capped) and no step of any run takes twice
//! the mean (`docs/embedded.md`, "Firmware defaults").
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::Configured<
    absorber_core::Model<f32, absorber_core::AtStepEnd<absorber_core::FreeBallNoFlight>, 3, 13>,
    absorber_firmware::Cap<47>,
>;

absorber_firmware::firmware_main!(M);
