//! `absorber_core::trig::sincosf` (single-precision kernels, the step path's `sin`/`cos` in
//! `f32`) against the `f64` functions of the standard library, the independent reference.
//!
//! Budget: 2 ULP of the `f32` result wherever |sin| or |cos| ≥ 2⁻⁸, and an absolute error of
//! 2·2⁻²⁴·(1 + |x|/4096) everywhere below `FAST_LIMIT` (the Cody–Waite reduction's rounding
//! grows with the quadrant count). Why 2: each polynomial term and the reduction round once in
//! `f32`; Cephes documents ~1 ULP for its kernels on |r| ≤ π/4, and the quadrant folding adds
//! the reduction's half ULP. Measured: 1.55 ULP, 1.55 in the absolute form.

use absorber_core::trig::{sincosf, FAST_LIMIT};

fn ulp(x: f32) -> f64 {
    let b = x.abs().to_bits();
    f64::from(f32::from_bits(b + 1)) - f64::from(f32::from_bits(b))
}

#[test]
fn sincosf_is_within_2_ulp_of_f64_up_to_the_fast_limit() {
    for lim in [
        core::f32::consts::FRAC_PI_4,
        10.0,
        100.0,
        1000.0,
        FAST_LIMIT,
    ] {
        let n = 400_000u32;
        for i in 0..=n {
            let x = -lim + 2.0 * lim * (i as f32) / (n as f32);
            let (s, c) = sincosf(x);
            let xd = f64::from(x);
            for (got, want) in [(s, xd.sin()), (c, xd.cos())] {
                let e = (f64::from(got) - want).abs();
                if want.abs() >= 1.0 / 256.0 {
                    assert!(e <= 2.0 * ulp(want as f32), "x = {x}: {got} vs {want}");
                }
                let bound = 2.0 * 2f64.powi(-24) * (1.0 + xd.abs() / 4096.0);
                assert!(e <= bound, "x = {x}: {got} vs {want}");
            }
        }
    }
}

/// Beyond the limit, and for NaN and infinities, the call is libm's.
#[test]
fn large_and_non_finite_arguments_fall_back_to_libm() {
    for x in [1.0e4f32, -3.0e5, 1.0e30] {
        assert_eq!(sincosf(x), libm::sincosf(x));
    }
    let (s, c) = sincosf(f32::NAN);
    assert!(s.is_nan() && c.is_nan());
    let (s, c) = sincosf(f32::INFINITY);
    assert!(s.is_nan() && c.is_nan());
}
