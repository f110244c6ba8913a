//! The closed forms of flight's events: where a step's normal force and gap cross zero
//! (linear and cubic Hermite roots), whether a landing bounces and its impulse, and angles.

use crate::scalar::{is_positive, lit, Real};

/// A ball meeting the circle slower than this along the normal \[m/s\] grazes it: no impulse,
/// it flies on. A ball that took off at a step's end meets the circle again at the next step's
/// start with a normal speed of rounding size and either sign; without the margin the two
/// solvers could take different branches there (a rolling landing with a normal impulse of
/// rounding size, or none).
pub const GRAZING: f64 = 1e-6;

/// Fraction τ ∈ \[0, 1\] of a step at which the normal force, `n_start` at its start and
/// `n_end < 0` at its end, crosses zero (linear in N); 0 when it was not positive at the start.
pub fn separation_fraction<T: Real>(n_start: T, n_end: T) -> T {
    if !is_positive(n_start) {
        return T::zero();
    }
    let tau = n_start / (n_start - n_end);
    if tau.is_finite() {
        tau.max(T::zero()).min(T::one())
    } else {
        T::zero()
    }
}

/// Fraction τ ∈ \[0, 1\] of a step at which a function with values `a0`, `a1` and scaled rates
/// `d0 = ȧ₀h`, `d1 = ȧ₁h` at the step ends crosses zero: the root of its cubic Hermite
/// interpolant (error O(h⁴)), by Newton from the linear root, six iterations at most. The stop
/// crossing, the landing and the stops in flight of both solvers use it.
pub fn hermite_root<T: Real>(a0: T, d0: T, a1: T, d1: T) -> T {
    let (two, three) = (lit::<T>(2.0), lit::<T>(3.0));
    let linear = a0 / (a0 - a1);
    let mut tau = if linear.is_finite() {
        linear.max(T::zero()).min(T::one())
    } else {
        T::zero()
    };
    for _ in 0..6 {
        let (t2, t3) = (tau * tau, tau * tau * tau);
        let p = (two * t3 - three * t2 + T::one()) * a0
            + (t3 - two * t2 + tau) * d0
            + (three * t2 - two * t3) * a1
            + (t3 - t2) * d1;
        let dp = hermite_rate(a0, d0, a1, d1, tau);
        if !is_positive(dp.abs()) {
            break;
        }
        let next = tau - p / dp;
        if !next.is_finite() {
            break;
        }
        tau = next.max(T::zero()).min(T::one());
    }
    tau
}

/// Rate of the cubic Hermite interpolant of [`hermite_root`] at the fraction `tau`, in units of
/// the scaled rates: `dp/dτ`, so that the function's time derivative there is `dp/dτ / h`.
pub fn hermite_rate<T: Real>(a0: T, d0: T, a1: T, d1: T, tau: T) -> T {
    let (two, three, six) = (lit::<T>(2.0), lit::<T>(3.0), lit::<T>(6.0));
    let t2 = tau * tau;
    (six * t2 - six * tau) * (a0 - a1)
        + (three * t2 - lit::<T>(4.0) * tau + T::one()) * d0
        + (three * t2 - two * tau) * d1
}

/// The landing bounces (the ball flies on) unless it is slow, `e_n v_n < v_stick`, or the
/// bounce's flight would be shorter than a step: pressed onto the track at `a_p > 0`, a ball
/// leaving it at `e_n v_n` returns after `2 e_n v_n / a_p`, which a step `h` cannot resolve
/// when `2 e_n v_n < a_p h` (`pressed_over_step` = `a_p h` \[m/s\]; with
/// `ball.min_bounce_time` τ_b longer than the step, `a_p τ_b`). A ball skimming along the
/// curved track would otherwise be found beyond the circle at every step end, with a normal
/// speed of about `v_t² h / ρ` made by the step, and bounce for ever. A perfectly elastic
/// landing (`e_n = 1`) always bounces: nothing would end its bounces.
pub fn landing_bounces<T: Real>(
    restitution: T,
    normal_speed: T,
    stick: T,
    pressed_over_step: T,
) -> bool {
    let rebound = restitution * normal_speed;
    let elastic = restitution >= T::one();
    rebound >= stick
        && (elastic || !(is_positive(pressed_over_step) && rebound + rebound < pressed_over_step))
}

/// Normal impulse of a frictionless bounce, `P = (1 + e_n) v_n / K` \[N·s\], with `K` the
/// inverse effective mass along the normal \[1/kg\]: the normal speed becomes `−e_n v_n`.
pub fn bounce_impulse<T: Real>(normal_speed: T, inverse_mass: T, restitution: T) -> T {
    (T::one() + restitution) * normal_speed / inverse_mass
}

/// Polar angle of `d = c − A` from the downward vertical, `atan2(d_x, −d_y)` \[rad\] (the orbit
/// angle θ of a ball on the track).
pub fn polar_angle<T: Real>(d: [T; 2]) -> T {
    d[0].atan2(-d[1])
}

/// `x` shifted by whole turns into `(−π, π]`.
pub(crate) fn wrap<T: Real>(x: T) -> T {
    let two_pi = T::two_pi();
    let k = (x / two_pi).round();
    x - k * two_pi
}
