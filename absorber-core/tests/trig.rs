//! `absorber_core::shared::trig::sincosf` (single-precision kernels, the step path's `sin`/`cos` in
//! `f32`) against the `f64` functions of the standard library, the independent reference.
//!
//! Budget: 2 ULP of the `f32` result wherever |sin| or |cos| ≥ 2⁻⁸, and an absolute error of
//! 2·2⁻²⁴·(1 + |x|/4096) everywhere below `FAST_LIMIT` (the Cody–Waite reduction's rounding
//! grows with the quadrant count). Why 2: each polynomial term and the reduction round once in
//! `f32`; Cephes documents ~1 ULP for its kernels on |r| ≤ π/4, and the quadrant folding adds
//! the reduction's half ULP. Measured: 1.55 ULP, 1.55 in the absolute form; beyond the limit
//! (exact integer reduction, all binades to 2¹²⁸) 1.54 ULP.

use absorber_core::shared::trig::{sincosf, FAST_LIMIT};

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

/// Beyond the limit (the exact integer reduction), every finite `f32` up to the largest: within
/// 2 ULP of `f64` where |sin| or |cos| ≥ 2⁻⁸ — over every binade from 2¹³ to 2¹²⁸, 20,000 mantissas
/// each — and NaN for NaN and infinities.
#[test]
fn large_arguments_are_reduced_exactly() {
    let mut worst = 0.0f64;
    for e in 13..128 {
        for i in 0..20_000u32 {
            // Mantissas spread over the binade (a multiplicative hash of i).
            let frac = i.wrapping_mul(2_654_435_761) >> 9;
            let x = f32::from_bits(((127 + e) << 23) | frac);
            for x in [x, -x] {
                let (s, c) = sincosf(x);
                let xd = f64::from(x);
                for (got, want) in [(s, xd.sin()), (c, xd.cos())] {
                    let e = (f64::from(got) - want).abs();
                    assert!(e <= 2.0 * 2f64.powi(-24), "x = {x}: {got} vs {want}");
                    if want.abs() >= 1.0 / 256.0 {
                        worst = worst.max(e / ulp(want as f32));
                        assert!(e <= 2.0 * ulp(want as f32), "x = {x}: {got} vs {want}");
                    }
                }
            }
        }
    }
    assert!(worst > 0.0);
    let (s, c) = sincosf(f32::NAN);
    assert!(s.is_nan() && c.is_nan());
    for x in [f32::INFINITY, f32::NEG_INFINITY] {
        let (s, c) = sincosf(x);
        assert!(s.is_nan() && c.is_nan());
    }
    // Just beyond the limit the two reductions meet.
    let x = FAST_LIMIT;
    let above = f32::from_bits(x.to_bits() + 1);
    let (s0, c0) = sincosf(x);
    let (s1, c1) = sincosf(above);
    assert!((s1 - s0).abs() < 1e-3 && (c1 - c0).abs() < 1e-3);
}

/// The table of 2/π bits is 2/π: an integer evaluation of Machin's formula
/// `π = 16 arctan(1/5) − 4 arctan(1/239)` to 320 bits gives the same 256 (and π/2 in Q62).
#[test]
fn two_over_pi_bits_are_two_over_pi() {
    // Fixed point with P fractional bits, in u64 limbs via u128 arithmetic on a small bignum.
    const P: usize = 320;
    let pi = machin_pi(P);
    // 2/π · 2^P = 2^(2P+1) / (π · 2^P).
    let q = div_pow2(2 * P + 1, &pi);
    for (j, w) in absorber_core::shared::trig::TWO_OVER_PI_BITS
        .iter()
        .enumerate()
    {
        let shift = P - 32 * (j + 1);
        assert_eq!(bits_at(&q, shift) as u32, *w, "word {j}");
    }
    // π/2 · 2^62 = π · 2^P / 2^(P − 61).
    assert_eq!(
        bits_at(&pi, P - 61) as i64,
        absorber_core::shared::trig::FRAC_PI_2_Q62,
        "π/2 in Q62"
    );
}

// A minimal unsigned bignum (little-endian u32 limbs), enough for Machin's series.
type Big = Vec<u32>;

fn big_from_pow2(p: usize) -> Big {
    let mut v = vec![0u32; p / 32 + 1];
    v[p / 32] = 1 << (p % 32);
    v
}

fn big_div_small(a: &Big, d: u32) -> Big {
    let mut out = vec![0u32; a.len()];
    let mut rem = 0u64;
    for i in (0..a.len()).rev() {
        let cur = (rem << 32) | u64::from(a[i]);
        out[i] = (cur / u64::from(d)) as u32;
        rem = cur % u64::from(d);
    }
    out
}

fn big_add(a: &Big, b: &Big) -> Big {
    let n = a.len().max(b.len()) + 1;
    let mut out = vec![0u32; n];
    let mut carry = 0u64;
    for (i, o) in out.iter_mut().enumerate() {
        let s = u64::from(*a.get(i).unwrap_or(&0)) + u64::from(*b.get(i).unwrap_or(&0)) + carry;
        *o = s as u32;
        carry = s >> 32;
    }
    out
}

fn big_sub(a: &Big, b: &Big) -> Big {
    let mut out = vec![0u32; a.len()];
    let mut borrow = 0i64;
    for (i, o) in out.iter_mut().enumerate() {
        let s = i64::from(a[i]) - i64::from(*b.get(i).unwrap_or(&0)) - borrow;
        *o = s.rem_euclid(1 << 32) as u32;
        borrow = i64::from(s < 0);
    }
    out
}

fn big_is_zero(a: &Big) -> bool {
    a.iter().all(|x| *x == 0)
}

fn big_mul_small(a: &Big, m: u32) -> Big {
    let mut out = vec![0u32; a.len() + 1];
    let mut carry = 0u64;
    for i in 0..a.len() {
        let s = u64::from(a[i]) * u64::from(m) + carry;
        out[i] = s as u32;
        carry = s >> 32;
    }
    out[a.len()] = carry as u32;
    out
}

/// `arctan(1/x) · 2^p` by its series, truncated.
fn arctan_inv(x: u32, p: usize) -> Big {
    let mut term = big_div_small(&big_from_pow2(p), x);
    let (mut pos, mut neg) = (vec![0u32], vec![0u32]);
    let mut n = 1u32;
    let mut plus = true;
    while !big_is_zero(&term) {
        let t = big_div_small(&term, n);
        if plus {
            pos = big_add(&pos, &t);
        } else {
            neg = big_add(&neg, &t);
        }
        term = big_div_small(&big_div_small(&term, x), x);
        n += 2;
        plus = !plus;
    }
    big_sub(&pos, &neg)
}

fn machin_pi(p: usize) -> Big {
    // Guard bits: evaluate at p + 32 and drop them.
    let g = p + 32;
    let a = big_mul_small(&arctan_inv(5, g), 16);
    let b = big_mul_small(&arctan_inv(239, g), 4);
    let pi = big_sub(&a, &b);
    shift_right(&pi, 32)
}

fn shift_right(a: &Big, s: usize) -> Big {
    (0..a.len())
        .map(|i| bits_at(a, 32 * i + s) as u32)
        .collect()
}

/// The 64 bits of `a` from bit `s` up.
fn bits_at(a: &Big, s: usize) -> u64 {
    let mut v = 0u64;
    for k in 0..64 {
        let bit = s + k;
        if a.get(bit / 32).is_some_and(|w| (w >> (bit % 32)) & 1 == 1) {
            v |= 1 << k;
        }
    }
    v
}

/// `2^e / d` by long division, bit by bit (d a bignum).
fn div_pow2(e: usize, d: &Big) -> Big {
    let mut q = vec![0u32; e / 32 + 2];
    let mut rem: Big = vec![0u32];
    for bit in (0..=e).rev() {
        rem = big_mul_small(&rem, 2);
        if bit == e {
            rem = big_add(&rem, &vec![1u32]);
        }
        if !less(&rem, d) {
            rem = big_sub(&rem, d);
            q[bit / 32] |= 1 << (bit % 32);
        }
    }
    q
}

fn less(a: &Big, b: &Big) -> bool {
    let n = a.len().max(b.len());
    for i in (0..n).rev() {
        let (x, y) = (*a.get(i).unwrap_or(&0), *b.get(i).unwrap_or(&0));
        if x != y {
            return x < y;
        }
    }
    false
}
