//! `fw-free-flight-step-end`: `fw-free-step-end` driven at 4.10 Hz (`fw-free-flight`), where the
//! ball spends much of the time in flight: the bounded worst step with many separations and
//! landings.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::InFlight<
    absorber_firmware::StepEnd<absorber_core::FreeBallModel<f32, 3, 13>>,
>;

absorber_firmware::firmware_main!(M);
