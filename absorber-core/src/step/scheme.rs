//! The integration scheme's coefficients along the Newton unknown `x = q̈_{n+1}`: the chain
//! [`Chain`] (`q = q₀ + c_q x`, `v = v₀ + c_v x`, `a = a₀ + c_m x`) that every assembly takes,
//! and the generalized-α recursion [`AlphaRecursion`] (Chung & Hulbert 1993, in the form of
//! Arnold & Brüls 2007) that gives it for a step of length `h`.

use crate::params::Integrator;
use crate::scalar::Real;

/// Newmark chain coefficients of the unknown `x`: `q = q₀ + c_q x`, `v = v₀ + c_v x`,
/// `a = a₀ + c_m x`.
#[derive(Clone, Copy, Debug)]
pub struct Chain<T> {
    /// ∂q/∂x.
    pub c_q: T,
    /// ∂v/∂x.
    pub c_v: T,
    /// ∂a/∂x.
    pub c_m: T,
}

/// Constants of the generalized-α recursion `a_{n+1} = from_accel q̈_n + from_pseudo a_n +
/// ratio q̈_{n+1}`, computed once from the parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaRecursion<T> {
    /// `α_f / (1 − α_m)`.
    pub from_accel: T,
    /// `−α_m / (1 − α_m)`.
    pub from_pseudo: T,
    /// `κ = (1 − α_f) / (1 − α_m)`.
    pub ratio: T,
}

impl<T: Real> AlphaRecursion<T> {
    /// The constants of `integrator`, or `None` for Newmark's method.
    pub fn of(integrator: &Integrator<T>) -> Option<Self> {
        if integrator.is_newmark() {
            return None;
        }
        let one = T::one();
        let d = one - integrator.alpha_m;
        Some(Self {
            from_accel: integrator.alpha_f / d,
            from_pseudo: -integrator.alpha_m / d,
            ratio: (one - integrator.alpha_f) / d,
        })
    }

    /// The Newton chain of a step of length `h`: `(c_q, c_v, c_m) = (κβh², κγh, 1)` with the
    /// recursion `alpha` (`κ = 1` for Newmark, `None`). The one formula of the core and the
    /// full solver.
    pub fn chain(integrator: &Integrator<T>, alpha: Option<&Self>, h: T) -> Chain<T> {
        let (c_q, c_v) = (integrator.beta * h * h, integrator.gamma * h);
        match alpha {
            None => Chain {
                c_q,
                c_v,
                c_m: T::one(),
            },
            Some(g) => Chain {
                c_q: c_q * g.ratio,
                c_v: c_v * g.ratio,
                c_m: T::one(),
            },
        }
    }
}
