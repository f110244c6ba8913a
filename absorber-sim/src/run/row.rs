//! One output row of a run and its CSV line (a fast, exact float formatter: the same digits as
//! `format!("{:e}")`).

/// One output sample. SI units, angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Time \[s\].
    pub t: f64,
    /// Base displacement y_b \[m\].
    pub base_y: f64,
    /// Absolute vertical position of the beam end, y_b + deflection \[m\].
    pub tip_y: f64,
    /// Deflection of the beam end relative to the base (static sag included) \[m\].
    pub tip_deflection: f64,
    /// Tip mass rotation ψ \[rad\].
    pub tip_angle: f64,
    /// Ball orbit angle θ from the downward vertical \[rad\] (NaN without a free ball: a
    /// locked ball turns with the tip mass, [`Row::tip_angle`]; so are its rates and spin).
    pub ball_angle: f64,
    /// Ball angle relative to the housing α = θ − ψ \[rad\].
    pub ball_rel_angle: f64,
    /// Energies \[J\] with absolute velocities (base velocity included).
    pub energies: absorber_core::Energies<f64>,
    /// Newton iterations of the step that ended here (0 at t = 0).
    pub iterations: u32,
    /// A stop impact happened in the step that ended here.
    pub impact: bool,
    /// Base acceleration ÿ_b \[m/s²\].
    pub base_accel: f64,
    /// Relative tip velocity ẏ \[m/s\].
    pub tip_velocity: f64,
    /// ψ̇ \[rad/s\].
    pub tip_rate: f64,
    /// θ̇ \[rad/s\].
    pub ball_rate: f64,
    /// α̇ \[rad/s\].
    pub ball_rel_rate: f64,
    /// Ball spin angle φ = ψ − (ρ/r_b) α \[rad\] (paper eq. 28; 0 in the static state).
    pub ball_spin: f64,
    /// φ̇ \[rad/s\].
    pub ball_spin_rate: f64,
    /// Normal force of the track on the ball \[N\] (negative: the track pulls, which a real
    /// track cannot; NaN without a free ball; `absorber_core::ContactForces`).
    pub normal_force: f64,
    /// Tangential force of the track on the ball \[N\] (rolling friction; plus the stop's
    /// reaction while the ball rests on a stop; NaN without a free ball).
    pub tangential_force: f64,
    /// 1: the ball is on the track, 0: in flight (NaN without a free ball).
    pub contact: f64,
    /// Absolute vertical acceleration of the beam end, ÿ_b + the relative acceleration
    /// \[m/s²\] (gravity not included: what a tip accelerometer reads).
    pub tip_acceleration: f64,
    /// The ball left the track during the step (not a CSV column).
    pub separated: bool,
    /// A landing during the step: `(bounced, required friction |P_t|/P_n)` (not a CSV column).
    pub landing: Option<(bool, f64)>,
    /// How many separations, landings and stop impacts the step had (a step can hold several;
    /// not a CSV column: `impact` says whether there was one).
    pub events: absorber_core::EventCounts,
}

/// The CSV header (also documents the columns).
pub const CSV_HEADER: &str = "\
# host-sim run: one row per output step. SI units, angles in rad.
# t [s]; base_y: base displacement y_b [m]; tip_y: absolute vertical position of the beam end (y_b + deflection) [m];
# tip_deflection: beam end relative to the base, static sag included [m]; tip_angle: tip mass rotation psi [rad];
# ball_angle: ball orbit angle theta from the downward vertical [rad]; ball_rel_angle: theta - psi [rad]
#   (these, the ball's rates and spin are NaN unless the ball is free: a locked ball turns with the tip mass, tip_angle);
# beam_strain, beam_kinetic, beam_potential, tip_kinetic, tip_potential, ball_kinetic, ball_potential [J]
#   (kinetic with absolute velocities, potentials as changes from the static state plus the base displacement);
# iterations: Newton iterations of the step; impact: 1 if the ball hit a stop in the step;
# base_accel [m/s^2]; tip_velocity [m/s]; tip_rate, ball_rate, ball_rel_rate [rad/s];
# ball_spin: phi = psi - (rho/r_b)(theta - psi) [rad]; ball_spin_rate [rad/s];
# normal_force: track on ball, towards the track centre [N] (< 0: the track pulls: a real ball would leave it);
# tangential_force: track on ball along increasing theta [N] (friction rolling needs; plus a stop's reaction);
# contact: 1 the ball is on the track, 0 it flies inside the housing (then ball_angle is the polar angle of its centre);
# tip_acceleration: absolute vertical acceleration of the beam end, base_accel + relative [m/s^2] (what a tip accelerometer reads, gravity not included)
t,base_y,tip_y,tip_deflection,tip_angle,ball_angle,ball_rel_angle,beam_strain,beam_kinetic,beam_potential,tip_kinetic,tip_potential,ball_kinetic,ball_potential,iterations,impact,base_accel,tip_velocity,tip_rate,ball_rate,ball_rel_rate,ball_spin,ball_spin_rate,normal_force,tangential_force,contact,tip_acceleration";

/// Names of the CSV columns, in order (the last line of [`CSV_HEADER`]).
pub fn csv_columns() -> Vec<&'static str> {
    CSV_HEADER
        .lines()
        .last()
        .unwrap_or_default()
        .split(',')
        .collect()
}

impl Row {
    /// The row's values in the order of [`csv_columns`] (`iterations` and `impact` as numbers).
    pub fn values(&self) -> [f64; 27] {
        let e = &self.energies;
        [
            self.t,
            self.base_y,
            self.tip_y,
            self.tip_deflection,
            self.tip_angle,
            self.ball_angle,
            self.ball_rel_angle,
            e.beam_strain,
            e.beam_kinetic,
            e.beam_potential,
            e.tip_kinetic,
            e.tip_potential,
            e.ball_kinetic,
            e.ball_potential,
            f64::from(self.iterations),
            f64::from(u8::from(self.impact)),
            self.base_accel,
            self.tip_velocity,
            self.tip_rate,
            self.ball_rate,
            self.ball_rel_rate,
            self.ball_spin,
            self.ball_spin_rate,
            self.normal_force,
            self.tangential_force,
            self.contact,
            self.tip_acceleration,
        ]
    }

    /// The row as a CSV line (no newline): [`Row::values`], `iterations` and `impact` as
    /// integers, `contact` as 0 or 1 (or NaN), everything else with 10 significant digits in
    /// Rust's `{:.9e}` form, byte for byte (`push_sci10`, checked against `format!`).
    pub fn csv(&self) -> String {
        let mut b = Vec::with_capacity(27 * 17);
        self.write_csv(&mut b);
        // (ASCII only: the conversion cannot fail.)
        String::from_utf8(b).unwrap_or_default()
    }

    /// [`Row::csv`] appended to `b` as ASCII bytes (no allocation when `b` has room).
    pub fn write_csv(&self, b: &mut Vec<u8>) {
        for (i, x) in self.values().iter().enumerate() {
            if i > 0 {
                b.push(b',');
            }
            match i {
                14 => push_u32(b, self.iterations),
                15 => b.push(if self.impact { b'1' } else { b'0' }),
                25 if x.is_finite() => b.push(if *x > 0.5 { b'1' } else { b'0' }),
                _ => push_sci10(b, *x),
            }
        }
    }
}

/// Appends `n` in decimal (as `n.to_string()`).
fn push_u32(b: &mut Vec<u8>, n: u32) {
    let mut buf = [0u8; 10];
    let mut k = buf.len();
    let mut n = n;
    loop {
        k -= 1;
        buf[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    b.extend_from_slice(&buf[k..]);
}

/// `10^k`, k = 0..=22: exact in `f64` (`5^22 < 2^53`).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Appends `x` exactly as `format!("{x:.9e}")` does (the exact binary value rounded to 10
/// significant digits, `d.ddddddddde±x`), at a fraction of its cost. With `E` the decimal
/// exponent of `|x|` and `|9 − E| ≤ 44`, `y = |x|·10^(9−E)` (or `|x| / 10^(E−9)`) takes one
/// or two correctly rounded operations by exact powers of ten (`10^k`, `k ≤ 22`), so
/// `|y − Y| ≤ 2⁻⁵²·Y < 2.3·10⁻⁶` for the exact `Y ∈ [10⁹, 10¹⁰)` (each rounding at most
/// 2⁻⁵³ relative); the 10 digits are `round(Y)`, which is `round(y)` unless `Y`'s fraction
/// is within that of ½ (an error across an integer moves `⌊y⌋` and the fraction together:
/// the same rounded integer). Values whose
/// fraction `y − ⌊y⌋` is within 10⁻⁴ of ½ (about 2·10⁻⁴ of all), `E` outside `−35..=53` and
/// subnormals go through `format!` itself; zeros, NaN and ±∞ are written as `format!` spells
/// them. Checked against `format!` in the tests.
fn push_sci10(b: &mut Vec<u8>, x: f64) {
    let fallback = |b: &mut Vec<u8>| b.extend_from_slice(format!("{x:.9e}").as_bytes());
    let a = x.abs();
    // `format!`'s spelling of the special values (the columns without a ball are NaN).
    let special: Option<&[u8]> = if x.is_nan() {
        Some(b"NaN")
    } else if x == f64::INFINITY {
        Some(b"inf")
    } else if x == f64::NEG_INFINITY {
        Some(b"-inf")
    } else if x == 0.0 {
        Some(if x.is_sign_negative() {
            b"-0.000000000e0"
        } else {
            b"0.000000000e0"
        })
    } else {
        None
    };
    if let Some(text) = special {
        return b.extend_from_slice(text);
    }
    if a < f64::MIN_POSITIVE {
        return fallback(b);
    }
    let scaled = |e10: i32| -> Option<f64> {
        let k = 9 - e10;
        let (big, rest) = match k.unsigned_abs() as usize {
            j if j > 22 => (true, j - 22),
            j => (false, j),
        };
        let p = *POW10.get(rest)?;
        Some(match (k >= 0, big) {
            (true, false) => a * p,
            (true, true) => a * 1e22 * p,
            (false, false) => a / p,
            (false, true) => a / 1e22 / p,
        })
    };
    // E is ⌊e₂ log₁₀ 2⌋ or one more (a ∈ [2^e₂, 2^(e₂+1))). The floor in integers,
    // log₁₀ 2 ≈ 78913 / 2¹⁸ with an arithmetic shift: equal to the floating-point floor for
    // every normal exponent (test `log10_floor_in_integers`), without a libm call on a target
    // without SSE4.1.
    let e2 = ((a.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let mut e10 = (e2 * 78_913) >> 18;
    let Some(mut y) = scaled(e10) else {
        return fallback(b);
    };
    if y < 1e9 {
        // (Not reached: E ≥ the estimate.)
        return fallback(b);
    }
    if y >= 1e10 {
        e10 += 1;
        // (y may now round to just below 10⁹; round(y) below gives 10⁹ then.)
        match scaled(e10) {
            Some(v) => y = v,
            None => return fallback(b),
        }
    }
    // ⌊y⌋ by truncation (y ∈ [10⁹, 10¹⁰) is positive; exact, no libm `floor`).
    let whole = y as u64;
    let frac = y - whole as f64;
    if (frac - 0.5).abs() <= 1e-4 {
        return fallback(b);
    }
    let mut mant = whole + u64::from(frac > 0.5);
    if mant == 10_000_000_000 {
        mant = 1_000_000_000;
        e10 += 1;
    }
    // Sign, d.ddddddddd, e, sign, at most 2 exponent digits (|E| ≤ 54 here).
    if e10.unsigned_abs() >= 100 {
        return fallback(b);
    }
    let mut out = [0u8; 17];
    let mut k = usize::from(x < 0.0);
    out[0] = b'-';
    // The 9 digits after the point two at a time (mant < 10¹⁰: its first digit is < 10).
    let mut rest = mant % 1_000_000_000;
    let mut pos = k + 10;
    let pair = |r: u64, pos: usize, out: &mut [u8; 17]| {
        out[pos] = b'0' + (r % 10) as u8;
        out[pos - 1] = b'0' + (r / 10) as u8;
    };
    for _ in 0..4 {
        pair(rest % 100, pos, &mut out);
        rest /= 100;
        pos -= 2;
    }
    out[k + 2] = b'0' + rest as u8;
    out[k] = b'0' + (mant / 1_000_000_000) as u8;
    out[k + 1] = b'.';
    out[k + 11] = b'e';
    k += 12;
    if e10 < 0 {
        out[k] = b'-';
        k += 1;
    }
    let e = e10.unsigned_abs();
    if e >= 10 {
        pair(u64::from(e), k + 1, &mut out);
        k += 2;
    } else {
        out[k] = b'0' + e as u8;
        k += 1;
    }
    b.extend_from_slice(&out[..k]);
}

#[cfg(test)]
mod tests {
    use super::{push_sci10, push_u32};

    fn agrees(x: f64) {
        let mut s = Vec::new();
        push_sci10(&mut s, x);
        assert_eq!(
            s,
            format!("{x:.9e}").as_bytes(),
            "bits {:#018x}",
            x.to_bits()
        );
    }

    /// `push_sci10`'s decimal exponent estimate in integers equals the floating-point floor
    /// of `e₂ log₁₀ 2` for every normal binary exponent.
    #[test]
    fn log10_floor_in_integers() {
        for e2 in -1022i32..=1023 {
            let exact = (f64::from(e2) * std::f64::consts::LOG10_2).floor() as i32;
            assert_eq!((e2 * 78_913) >> 18, exact, "e2 = {e2}");
        }
    }

    /// The CSV's number format is `format!("{x:.9e}")` byte for byte: random bit patterns,
    /// random magnitudes of the output's range, and values at and next to the midpoints of
    /// the 10th digit (where the shortest digits are a tie), powers of ten, carries.
    #[test]
    fn sci10_is_std_format() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..100_000 {
            agrees(f64::from_bits(next()));
            // Integers and values just below a power of ten (the carry).
            let m = next() % 100_000_000_000;
            let e = (next() % 30) as i32 - 15;
            agrees(m as f64 * 10f64.powi(e));
            agrees((1.0 - (next() % 1000) as f64 * f64::EPSILON) * 10f64.powi(e));
            let mag = (next() % 100) as i32 - 45;
            let unit = (next() >> 11) as f64 / (1u64 << 53) as f64;
            agrees((unit - 0.5) * 10f64.powi(mag));
            // A midpoint of the 10th digit (11 digits ending in 5) and its neighbours.
            let m = 10_000_000_000 + next() % 90_000_000_000;
            let tie: f64 = format!("{}.{:010}5e{mag}", m / 10_000_000_000, m % 10_000_000_000)
                .parse()
                .unwrap_or(0.0);
            for y in [tie, tie.next_up(), tie.next_down(), -tie] {
                agrees(y);
            }
        }
        for x in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            9.9999999995,
            9.999999999499999,
            99_999_999_995.0,
            1e-300,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 3.0,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            agrees(x);
        }
        for e in -320..=308 {
            let p: f64 = format!("1e{e}").parse().unwrap_or(0.0);
            for y in [p, p.next_up(), p.next_down()] {
                agrees(y);
            }
        }
    }

    #[test]
    fn u32_is_to_string() {
        for n in [0, 1, 9, 10, 99, 100, 12_345, u32::MAX] {
            let mut s = Vec::new();
            push_u32(&mut s, n);
            assert_eq!(s, n.to_string().as_bytes());
        }
    }
}
