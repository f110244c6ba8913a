//! `fw-estimator`: the mast-arm root-stress estimator (model + `Estimator::update`), N = 3, f32.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::estimator::EstimatorSim;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    static mut MODEL: core::mem::MaybeUninit<M> = core::mem::MaybeUninit::uninit();
    absorber_firmware::target::target_main::<M>(MODEL)
}

#[cfg(not(target_os = "none"))]
fn main() {
    absorber_firmware::host_main::<M>()
}
