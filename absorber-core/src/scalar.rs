//! The scalar the model is generic over: `f32` on a Cortex-M4F FPU, `f64` on the host.

use nalgebra::RealField;

/// A real scalar usable by the model (`f32` or `f64`; with nalgebra's `libm-force` feature the
/// transcendental functions come from `libm`, so host and firmware results are bit-identical).
///
/// Implemented for `f32` and `f64` only, so that each precision can pick its own kernels for
/// the few transcendental calls of the step ([`Real::fast_sin_cos`]).
pub trait Real: RealField + Copy {
    /// `(sin x, cos x)` for the step path: `trig::sincosf` in `f32` (single-precision
    /// kernels, about 50× cheaper than `libm::sincosf` on a Cortex-M4F, ≤ 2 ULP), `libm`'s in
    /// `f64`.
    fn fast_sin_cos(self) -> (Self, Self);
    /// A count (of steps) as a scalar, rounded once to nearest (for `f32` the same value as
    /// through `f64`, without the soft-float `f64` detour on a Cortex-M4F).
    fn from_count(n: u64) -> Self;
}

impl Real for f32 {
    #[inline]
    fn fast_sin_cos(self) -> (f32, f32) {
        crate::step::trig::sincosf(self)
    }
    #[inline]
    fn from_count(n: u64) -> f32 {
        n as f32
    }
}

impl Real for f64 {
    #[inline]
    fn fast_sin_cos(self) -> (f64, f64) {
        nalgebra::ComplexField::sin_cos(self)
    }
    #[inline]
    fn from_count(n: u64) -> f64 {
        n as f64
    }
}

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
