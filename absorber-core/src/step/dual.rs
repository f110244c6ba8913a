//! Forward-mode dual numbers with `K` directional derivatives.
//!
//! The tip-mass and ball terms of the equations of motion are nonlinear in five local
//! coordinates (the end-node slope and position terms and the ball angle). Evaluating them once
//! in dual arithmetic gives their value and their exact derivatives (an analytic Jacobian,
//! to rounding) without a hand-written tangent that could drift from the residual.
//! Only the operations the tip terms need are implemented.

use crate::scalar::Real;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// `re + Σ du[k] ε_k` with `ε_j ε_k = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<T, const K: usize> {
    /// Value.
    pub re: T,
    /// Derivatives along the `K` seeded directions.
    pub du: [T; K],
}

impl<T: Real, const K: usize> Dual<T, K> {
    /// A constant (all derivatives zero).
    #[inline]
    pub fn constant(re: T) -> Self {
        Self {
            re,
            du: [T::zero(); K],
        }
    }

    /// A variable with derivative `seed` along direction `k` (a constant if `k >= K`).
    #[inline]
    pub fn variable(re: T, k: usize, seed: T) -> Self {
        let mut d = Self::constant(re);
        if let Some(slot) = d.du.get_mut(k) {
            *slot = seed;
        }
        d
    }

    #[inline]
    fn chain(self, value: T, slope: T) -> Self {
        let mut du = self.du;
        for x in du.iter_mut() {
            *x *= slope;
        }
        Self { re: value, du }
    }

    /// Sine.
    #[inline]
    pub fn sin(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(s, c)
    }

    /// Cosine.
    #[inline]
    pub fn cos(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(c, -s)
    }

    /// `atan2(self, x)`: d = (x dy − y dx) / (x² + y²).
    #[inline]
    pub fn atan2(self, x: Self) -> Self {
        let r2 = x.re * x.re + self.re * self.re;
        let mut du = [T::zero(); K];
        for ((d, dy), dx) in du.iter_mut().zip(self.du.iter()).zip(x.du.iter()) {
            *d = (x.re * *dy - self.re * *dx) / r2;
        }
        Self {
            re: self.re.atan2(x.re),
            du,
        }
    }

    /// Multiplies by a plain scalar.
    #[inline]
    pub fn scale(self, s: T) -> Self {
        self.chain(self.re * s, s)
    }

    /// Adds a plain scalar.
    #[inline]
    pub fn add_re(mut self, s: T) -> Self {
        self.re += s;
        self
    }
}

impl<T: Real, const K: usize> Add for Dual<T, K> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.re += o.re;
        for (a, b) in self.du.iter_mut().zip(o.du.iter()) {
            *a += *b;
        }
        self
    }
}

impl<T: Real, const K: usize> Sub for Dual<T, K> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.re -= o.re;
        for (a, b) in self.du.iter_mut().zip(o.du.iter()) {
            *a -= *b;
        }
        self
    }
}

impl<T: Real, const K: usize> Mul for Dual<T, K> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut du = [T::zero(); K];
        for ((d, a), b) in du.iter_mut().zip(self.du.iter()).zip(o.du.iter()) {
            *d = *a * o.re + self.re * *b;
        }
        Self {
            re: self.re * o.re,
            du,
        }
    }
}

impl<T: Real, const K: usize> Div for Dual<T, K> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = T::one() / o.re;
        let q = self.re * inv;
        let mut du = [T::zero(); K];
        for ((d, a), b) in du.iter_mut().zip(self.du.iter()).zip(o.du.iter()) {
            *d = (*a - q * *b) * inv;
        }
        Self { re: q, du }
    }
}

impl<T: Real, const K: usize> Neg for Dual<T, K> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.scale(-T::one())
    }
}

/// The arithmetic the tip and ball terms need, so that one source evaluates them either with
/// their exact Jacobian ([`Dual`]) or as plain values ([`Plain`], residual only).
pub trait Number<T: Real>:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant.
    fn constant(re: T) -> Self;
    /// A variable with derivative `seed` along direction `k`.
    fn variable(re: T, k: usize, seed: T) -> Self;
    /// The value.
    fn re(&self) -> T;
    /// `(sin, cos)`.
    fn sin_cos(self) -> (Self, Self);
    /// `atan2(self, x)`.
    fn atan2(self, x: Self) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Multiplies by a plain scalar.
    fn scale(self, s: T) -> Self;
    /// Adds a plain scalar.
    fn add_re(self, s: T) -> Self;
}

impl<T: Real, const K: usize> Number<T> for Dual<T, K> {
    #[inline]
    fn constant(re: T) -> Self {
        Dual::constant(re)
    }
    #[inline]
    fn variable(re: T, k: usize, seed: T) -> Self {
        Dual::variable(re, k, seed)
    }
    #[inline]
    fn re(&self) -> T {
        self.re
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.re.fast_sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        Dual::atan2(self, x)
    }
    #[inline]
    fn sqrt(self) -> Self {
        let r = self.re.sqrt();
        self.chain(r, T::one() / (r + r))
    }
    #[inline]
    fn scale(self, s: T) -> Self {
        Dual::scale(self, s)
    }
    #[inline]
    fn add_re(self, s: T) -> Self {
        Dual::add_re(self, s)
    }
}

/// A plain value behind the [`Number`] interface (residual without Jacobian).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plain<T>(pub T);

macro_rules! plain_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<T: Real> $tr for Plain<T> {
            type Output = Self;
            #[inline]
            fn $f(self, o: Self) -> Self {
                Plain(self.0 $op o.0)
            }
        }
    };
}
plain_op!(Add, add, +);
plain_op!(Sub, sub, -);
plain_op!(Mul, mul, *);
plain_op!(Div, div, /);

impl<T: Real> Neg for Plain<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Plain(-self.0)
    }
}

impl<T: Real> Number<T> for Plain<T> {
    #[inline]
    fn constant(re: T) -> Self {
        Plain(re)
    }
    #[inline]
    fn variable(re: T, _k: usize, _seed: T) -> Self {
        Plain(re)
    }
    #[inline]
    fn re(&self) -> T {
        self.0
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.0.fast_sin_cos();
        (Plain(s), Plain(c))
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        Plain(self.0.atan2(x.0))
    }
    #[inline]
    fn sqrt(self) -> Self {
        Plain(self.0.sqrt())
    }
    #[inline]
    fn scale(self, s: T) -> Self {
        Plain(self.0 * s)
    }
    #[inline]
    fn add_re(self, s: T) -> Self {
        Plain(self.0 + s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_closed_forms() {
        let x = Dual::<f64, 2>::variable(0.3, 0, 1.0);
        let y = Dual::<f64, 2>::variable(-1.2, 1, 1.0);
        let f = (x * y).sin() / (y.atan2(x) + x.cos());
        // Closed-form partials of f = sin(xy) / (atan2(y,x) + cos x).
        let (xv, yv) = (0.3f64, -1.2f64);
        let den = yv.atan2(xv) + xv.cos();
        let dden_dx = -yv / (xv * xv + yv * yv) - xv.sin();
        let dden_dy = xv / (xv * xv + yv * yv);
        let num = (xv * yv).sin();
        let dfdx = ((xv * yv).cos() * yv * den - num * dden_dx) / (den * den);
        let dfdy = ((xv * yv).cos() * xv * den - num * dden_dy) / (den * den);
        assert!((f.re - num / den).abs() < 1e-15);
        assert!((f.du[0] - dfdx).abs() < 1e-13);
        assert!((f.du[1] - dfdy).abs() < 1e-13);
    }
}
