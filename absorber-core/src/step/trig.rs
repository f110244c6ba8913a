//! `sin` and `cos` of an `f32` in `f32` arithmetic only.
//!
//! `libm::sincosf` (musl) evaluates its kernels in `f64`, which a Cortex-M4F has no hardware
//! for: about 2,200 instructions a call in soft-float. This one reduces the argument by
//! Cody–Waite with π/2 split in three `f32` parts (Cephes' `DP1..DP3`, doubled) and evaluates
//! Cephes' minimax polynomials on `|r| ≤ π/4` (Moshier, *Methods and Programs for Mathematical
//! Functions*, 1989; `sinf.c`): about 40 instructions on the M4F. The split keeps `k·P1` exact
//! for `|k| < 2¹⁵`, so the reduction is accurate while `|x| ≤` [`FAST_LIMIT`]. Beyond it (a ball
//! that has spun for thousands of turns) the argument is reduced exactly in integers (Payne &
//! Hanek 1983, *Radian reduction for trigonometric functions*, SIGNUM Newsletter 18): the f32
//! is `m·2^s` with a 24-bit integer `m`, so `x·2/π mod 4` needs only the 96 bits of 2/π that
//! start two places above `2^−s` ([`TWO_OVER_PI_BITS`], 2/π in hexadecimal, checked against an
//! integer evaluation of Machin's formula in the tests); one 24 × 96-bit product gives the
//! quadrant and the remainder in Q62. No `f64`, a few words of stack (libm's reduction, which
//! it replaces, took a 776-byte frame for the same).
//!
//! Accuracy, tested against `f64` in `absorber-core/tests/trig.rs`: at most 2 ULP of the
//! result where `|sin|` or `|cos|` is at least 2⁻⁸ for every finite `x` (both paths), and an
//! absolute error of at most 2·2⁻²⁴·(1 + |x|/4096) everywhere below the limit (measured:
//! 1.55 ULP).
//!
//! Only `+ − ×`, integer operations and conversions: correctly rounded IEEE-754 single
//! operations, so the host and the Cortex-M4F give the same bits.

// The constants are written as published (Cephes); each rounds to the f32 it names.
#![allow(clippy::excessive_precision)]

/// Largest |x| reduced by Cody–Waite; beyond it the exact integer reduction runs.
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

/// The first 256 bits of 2/π: word `j` holds the bits `32j + 1 … 32j + 32` after the point.
pub const TWO_OVER_PI_BITS: [u32; 8] = [
    0xA2F9_836E,
    0x4E44_1529,
    0xFC27_57D1,
    0xF534_DDC0,
    0xDB62_9599,
    0x3C43_9041,
    0xFE51_63AB,
    0xDEBB_C561,
];

/// `(sin x, cos x)` for `|x| >` [`FAST_LIMIT`] and non-finite `x` (NaN results). Not inlined:
/// the common path keeps its registers.
#[inline(never)]
#[cold]
fn slow(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let (k, r) = reduce_large(x.abs());
    let (s, c) = kernel(r, k);
    if x < 0.0 {
        (-s, c)
    } else {
        (s, c)
    }
}

/// Exact reduction of a finite `a >` [`FAST_LIMIT`] (module doc; the shifts below need its
/// exponent): the quadrant `k mod 4` and the remainder `r = a − k·π/2`, `|r| ≤ π/4`.
fn reduce_large(a: f32) -> (i32, f32) {
    let bits = a.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32;
    let m = u128::from((bits & 0x007f_ffff) | 0x0080_0000);
    // a = m·2^s; the bits b_i of 2/π with i < s − 1 only add multiples of 4 to a·2/π.
    let s = exponent - 150;
    let i0 = (s - 1).max(1);
    let (j0, off) = (((i0 - 1) / 32) as usize, ((i0 - 1) % 32) as u32);
    let word = |j: usize| u128::from(TWO_OVER_PI_BITS.get(j).copied().unwrap_or(0));
    let window = (word(j0) << 96) | (word(j0 + 1) << 64) | (word(j0 + 2) << 32) | word(j0 + 3);
    let next = word(j0 + 4);
    let window = if off == 0 {
        window
    } else {
        (window << off) | (next >> (32 - off))
    };
    // T: 96 bits of 2/π from b_{i0}, worth 2^(s − i0) at its top; a·2/π ≡ m·T·2^(s − i0 − 95).
    let t = window >> 32;
    let shift = (33 + i0 - s) as u32; // to Q62 (two bits of quadrant, 62 of fraction)
    let y = ((m * t) >> shift) as u64;
    let k = (y.wrapping_add(1 << 61) >> 62) as i32;
    let frac = y.wrapping_sub((k as u64) << 62) as i64; // in [−2⁶¹, 2⁶¹): ±½ quadrant
                                                        // r = frac·(π/2) in Q62 radians, in integers (one rounding, at the conversion to f32).
    let r = ((i128::from(frac) * i128::from(FRAC_PI_2_Q62)) >> 62) as i64;
    const TWO_POW_M62: f32 = 1.0 / 4_611_686_018_427_387_904.0;
    (k, r as f32 * TWO_POW_M62)
}

/// π/2 · 2⁶² rounded down (checked in the tests against Machin's formula).
pub const FRAC_PI_2_Q62: i64 = 0x6487_ED51_10B4_611A;

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
    kernel(r, k)
}

/// Cephes' minimax polynomials at `|r| ≤ π/4`, rotated to quadrant `k`.
#[inline]
fn kernel(r: f32, k: i32) -> (f32, f32) {
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
