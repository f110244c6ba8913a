//! `fw-free-flight`: the paper's absorber driven at 4.10 Hz, where its ball is in flight about
//! 40 % of the time (`absorber-core/src/step/flight`): what flight steps cost. 3 elements, D = 13.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::InFlight<absorber_firmware::FwFreeBall<3, 13>>;

absorber_firmware::firmware_main!(M);
