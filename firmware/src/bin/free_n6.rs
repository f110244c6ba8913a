//! `fw-free-n6`: the free-ball scene on 6 elements, D = 25 (what a finer beam costs).
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M =
    absorber_firmware::Configured<absorber_firmware::FwFreeBall<6, 25>, absorber_firmware::Cap<48>>;

absorber_firmware::firmware_main!(M);
