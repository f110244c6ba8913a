//! State estimation: the root stress and fatigue of an arm from the sensors a monitor has.
//!
//! - [`Ekf`] ([`ekf`]): the extended Kalman filter. Its prediction is the model's own step
//!   (the ball with its stops, flight and landings included), its Jacobian that step's exact
//!   sensitivity from the already factored Newton matrix, in the error subspace of the model's
//!   lowest modes ([`basis`]); any subset of a tip accelerometer, a ball-angle sensor and a
//!   root strain gauge ([`sensors`]); a health verdict on the estimate ([`health`]).
//! - [`Estimator`] ([`constant`]): the constant-gain filter it replaces (a steady-state gain
//!   designed on the host about the static state), kept as the baseline of
//!   `docs/monitoring.md`.
//!
//! Both are `no_std`, allocate nothing, and their memory is a compile-time constant.

pub mod basis;
pub mod constant;
pub mod ekf;
pub mod health;
pub mod sensors;
mod ud;

pub use basis::ModalBasis;
pub use constant::{Estimate, Estimator, Gain};
pub use ekf::{Ekf, EkfConfig, Estimate as EkfEstimate, AUGMENTED};
pub use health::{Health, HealthConfig, Verdict};
pub use sensors::{ReadingUse, Readings, Sensor, SensorKind, SensorSet};
