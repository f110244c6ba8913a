//! `fw-monitor-loop`: the pole monitor's sample on the paper's absorber: sensor read, extended
//! Kalman filter step (free ball, stops and flight, N = 3, f32), monitor record.
//!
//! On `thumbv7em-none-eabihf` this is the firmware; on the host it prints the reference.
#![cfg_attr(target_os = "none", no_std, no_main)]

type M = absorber_firmware::monitor_loop::MonitorLoop;

absorber_firmware::firmware_main!(M);
