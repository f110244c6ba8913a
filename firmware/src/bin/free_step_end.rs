//! `fw-free-step-end`: the paper's absorber (`fw-free`: flight on) with every event — stop
//! impacts, separation, landing, stops hit in flight — put at the end of its step
//! (`EventLocation::StepEnd`): the bounded worst case per sample.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::StepEnd<absorber_core::FreeBallModel<f32, 3, 13>>;

absorber_firmware::firmware_main!(M);
