//! `fw-empty`: no model (same driver, printing and hashing): the flash/RAM baseline.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::Empty;

absorber_firmware::firmware_main!(M);
