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
