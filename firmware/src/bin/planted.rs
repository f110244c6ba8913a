//! `fw-planted`: `fw-free` with a panic planted on the step path (`absorber_firmware::Planted`).
//! Never run: `scripts/embedded-report.py` checks that its call-graph panic check finds it.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::Planted<absorber_firmware::FwFreeBall<3, 13>>;

absorber_firmware::firmware_main!(M);
