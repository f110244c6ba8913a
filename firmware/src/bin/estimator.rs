//! `fw-estimator`: the mast-arm root-stress estimator (model + `Estimator::update`), N = 3, f32.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::estimator::EstimatorSim;

absorber_firmware::firmware_main!(M);
