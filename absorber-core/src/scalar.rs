//! The scalar the model is generic over: `f32` on a Cortex-M4F FPU, `f64` on the host.

use nalgebra::RealField;

/// A real scalar usable by the model (`f32` or `f64`; with nalgebra's `libm-force` feature the
/// transcendental functions come from `libm`, so host and firmware results are bit-identical).
pub trait Real: RealField + Copy {}
impl<T: RealField + Copy> Real for T {}

/// Converts an `f64` literal into the model's scalar (rounding to nearest for `f32`).
#[inline(always)]
pub fn lit<T: Real>(x: f64) -> T {
    nalgebra::convert(x)
}

/// Converts a model scalar to `f64` (exact for `f32`).
#[inline(always)]
pub fn to_f64<T: Real>(x: T) -> f64 {
    // `RealField` offers no direct `to_f64`; go through `SubsetOf`.
    nalgebra::try_convert(x).unwrap_or(f64::NAN)
}

/// `x > 0`, false for NaN: the guard for pivots, denominators and eigenvalues.
#[inline(always)]
pub fn is_positive<T: Real>(x: T) -> bool {
    x > T::zero()
}
