//! `sin` and `cos` of an `f32` in `f32` arithmetic only.
//!
//! `libm::sincosf` (musl) evaluates its kernels in `f64`, which a Cortex-M4F has no hardware
//! for: about 2,200 instructions a call in soft-float. This one reduces the argument by
//! Cody–Waite with π/2 split in three `f32` parts (Cephes' `DP1..DP3`, doubled) and evaluates
//! Cephes' minimax polynomials on `|r| ≤ π/4` (Moshier, *Methods and Programs for Mathematical
//! Functions*, 1989; `sinf.c`): about 40 instructions on the M4F. The split keeps `k·P1` exact
//! for `|k| < 2¹⁵`, so the reduction is accurate while `|x| ≤` [`FAST_LIMIT`]; beyond it (a ball
//! that has spun for tens of thousands of turns) the call falls back to `libm::sincosf`.
//!
//! Accuracy, tested against `f64` in `absorber-core/tests/trig.rs`: at most 2 ULP of the
//! result for `|x| ≤` [`FAST_LIMIT`] where `|sin|` or `|cos|` is at least 2⁻⁸, and an absolute
//! error of at most 2·2⁻²⁴·(1 + |x|/4096) everywhere below the limit (measured: 1.55 ULP).
//!
//! Only `+ − ×` and one conversion to an integer: correctly rounded IEEE-754 single operations,
//! so the host and the Cortex-M4F give the same bits.

// The constants are written as published (Cephes); each rounds to the f32 it names.
#![allow(clippy::excessive_precision)]

/// Largest |x| reduced here; beyond it `libm::sincosf` is called.
pub const FAST_LIMIT: f32 = 8192.0;

const TWO_OVER_PI: f32 = core::f32::consts::FRAC_2_PI;
// π/2 = P1 + P2 + P3; P1 and P2 have few significant bits, so k·P1 and k·P2 are exact.
const P1: f32 = 1.570_312_5;
const P2: f32 = 4.837_512_969_970_703_125e-4;
const P3: f32 = 7.549_789_954_891_882_16e-8;

/// `(sin x, cos x)`.
#[inline]
pub fn sincosf(x: f32) -> (f32, f32) {
    // NaN and ±inf fail the comparison too and take libm's path (NaN results).
    if x.abs() <= FAST_LIMIT {
        fast(x)
    } else {
        slow(x)
    }
}

#[inline(never)]
#[cold]
fn slow(x: f32) -> (f32, f32) {
    libm::sincosf(x)
}

#[inline]
fn fast(x: f32) -> (f32, f32) {
    // Nearest quadrant k = round(x·2/π); |k| ≤ 5216 for |x| ≤ 8192.
    let t = x * TWO_OVER_PI;
    let k = if t >= 0.0 {
        (t + 0.5) as i32
    } else {
        (t - 0.5) as i32
    };
    let kf = k as f32;
    let r = ((x - kf * P1) - kf * P2) - kf * P3;
    let z = r * r;
    let s = r + r * z * ((-1.951_529_589_1e-4 * z + 8.332_160_873_6e-3) * z - 1.666_665_461_1e-1);
    let c = 1.0 - 0.5 * z
        + z * z
            * ((2.443_315_711_809_948e-5 * z - 1.388_731_625_493_765e-3) * z
                + 4.166_664_568_298_827e-2);
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}
