//! `fw-free`: the paper's absorber: beam + tip mass + free ball with stops, 3 elements, D = 13.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::FwFreeBall<3, 13>;

absorber_firmware::firmware_main!(M);
