//! `fw-free-monitor`: `fw-free` plus the on-device monitor (`Monitor<f32>`, no twin,
//! `MonitorConfig::paper`, CAP 128, K 16, W 256) recording after every step.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::WithMonitor<absorber_firmware::FwFreeBall<3, 13>>;

absorber_firmware::firmware_main!(M);
