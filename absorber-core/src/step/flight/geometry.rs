//! Where the ball is relative to the housing: the beam end, the ball's centre and their
//! relative motion, the crossing of a stop in flight, the free flight over a step, and the
//! track's forces on a rolling ball.

use super::roots::{hermite_root, polar_angle, wrap};
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::Flight;
use crate::state::{Contact, Side, State};
use crate::step::system::System;
use crate::step::tip;
use nalgebra::SVector;

/// A flying ball whose polar angle starts a step this close beyond a stop \[rad\], moving
/// back towards the track, is still on the track's side of it (an impact put it on the stop
/// line, to rounding).
const STOP_MARGIN: f64 = 1e-3;

/// The kinematics of the ball relative to the track's centre.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Relative<T> {
    /// c − A \[m\].
    pub d: [T; 2],
    /// ċ − Ȧ \[m/s\].
    pub rate: [T; 2],
    /// |c − A| \[m\].
    pub r: T,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The beam end A and its velocity in the base frame (the clamp at the origin).
    pub(crate) fn end_point(&self, s: &State<T, D>) -> ([T; 2], [T; 2]) {
        let at = |x: &SVector<T, D>, k: usize| x.get(Self::END + k).copied().unwrap_or(T::zero());
        (
            [self.params.beam.length + at(&s.q, 0), at(&s.q, 1)],
            [at(&s.v, 0), at(&s.v, 1)],
        )
    }

    /// The ball's centre and its velocity: on the track from the rolling kinematics
    /// `c = A + ρ (sin θ, −cos θ)`, `ċ = Ȧ + ρ θ̇ (cos θ, sin θ)`, in flight the flying state.
    pub(crate) fn ball_centre(&self, s: &State<T, D>) -> ([T; 2], [T; 2]) {
        if s.contact == Contact::InFlight {
            return (s.flight.centre, s.flight.velocity);
        }
        let (a, a_rate) = self.end_point(s);
        let x = Self::local(&s.q, &s.v, &s.a);
        let (theta, theta_rate) = tip::orbit_angle(&self.inertia, &x);
        let (sin, cos) = theta.fast_sin_cos();
        let rho = self.params.ball.path_radius();
        (
            [a[0] + rho * sin, a[1] - rho * cos],
            [
                a_rate[0] + rho * theta_rate * cos,
                a_rate[1] + rho * theta_rate * sin,
            ],
        )
    }

    /// The flying ball relative to the track's centre.
    pub(crate) fn relative(&self, s: &State<T, D>) -> Relative<T> {
        let (a, a_rate) = self.end_point(s);
        let f = &s.flight;
        let d = [f.centre[0] - a[0], f.centre[1] - a[1]];
        Relative {
            d,
            rate: [f.velocity[0] - a_rate[0], f.velocity[1] - a_rate[1]],
            r: (d[0] * d[0] + d[1] * d[1]).sqrt(),
        }
    }

    /// Polar angle of the flying ball relative to the housing, `α_f = θ_f − ψ` on the branch
    /// of `(−π, π]`, and its rate `t_f·(ċ − Ȧ)/r − ψ̇`.
    pub(crate) fn flight_relative_angle(&self, s: &State<T, D>) -> (T, T) {
        let rel = self.relative(s);
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, psi_rate) = tip::psi_and_rate(&x);
        let alpha = wrap(polar_angle(rel.d) - psi);
        // (cos θ_f, sin θ_f) = (−d_y, d_x)/r.
        let tangential = (-rel.d[1] * rel.rate[0] + rel.d[0] * rel.rate[1]) / (rel.r * rel.r);
        (alpha, tangential - psi_rate)
    }

    /// The flying ball reaches the stops' height: its centre is beyond `ρ − r_b` from A (a stop
    /// is a block on the track as tall as the ball's radius; nearer the centre the ball passes
    /// over it).
    pub(crate) fn at_stop_height(&self, s: &State<T, D>) -> bool {
        let b = &self.params.ball;
        self.relative(s).r > b.path_radius() - b.radius
    }

    /// A stop met by the flying ball between `from` and `to`: at the stops' height at both
    /// ends, its polar angle crossed `±α_max` (from the track's side, `inside`, or from the arc
    /// beyond the stop); the side, `inside` and the crossing fraction (cubic Hermite).
    pub(crate) fn stop_crossing(
        &self,
        from: &State<T, D>,
        to: &State<T, D>,
        h: T,
    ) -> Option<(Side, bool, T)> {
        if !S::STOPS || !self.at_stop_height(from) || !self.at_stop_height(to) {
            return None;
        }
        let stop = self.params.ball.stop_angle;
        let (alpha0, rate0) = self.flight_relative_angle(from);
        let (raw1, rate1) = self.flight_relative_angle(to);
        let alpha1 = alpha0 + wrap(raw1 - alpha0);
        // A ball just put on the stop line by an impact (to rounding) is on the side it came
        // from: from the track's side it moves back towards the track, and the margin keeps it
        // there (without it the rest of the step would reverse its impulse). From beyond, a
        // perfectly elastic ball is put beyond the line (`BEYOND_OFFSET`) and moves away from
        // the track; counted on the track's side (as the margin alone does, and still does for
        // other balls: the default trajectories stay as they were) it gets a second impulse,
        // from the track's face, at the end of the rest of its step, with the projection there
        // (the ball moved by up to |α̇|h: 2 % of an elastic bouncing ball's energy).
        let outward = self.perfectly_elastic() && is_positive(alpha0 * rate0);
        let inside = alpha0.abs() <= stop || (!outward && alpha0.abs() <= stop + lit(STOP_MARGIN));
        if inside == (alpha1.abs() <= stop) {
            return None;
        }
        let outer = if inside { alpha1 } else { alpha0 };
        let side = if is_positive(outer) {
            Side::Positive
        } else {
            Side::Negative
        };
        let target = side.sign::<T>() * stop;
        let tau = hermite_root(alpha0 - target, rate0 * h, alpha1 - target, rate1 * h);
        Some((side, inside, tau))
    }

    /// The flight sub-step of the ball's centre over `h`, from the effective gravity at its start
    /// (`f.accel`) to `g_end` at its end, exact: the centre's acceleration `(0, −g_eff(t))` is
    /// known, and with the base acceleration linear between the samples (the input's
    /// interpolation, as the sub-steps to an event use it) its integrals are
    /// `Δċ = h (a₀ + a₁)/2`, `Δc = h ċ₀ + h² (a₀/3 + a₁/6)`. So the ball's path in the inertial
    /// frame is the parabola of a free fall whatever the base does (relative to a base that moves
    /// with the interpolated acceleration). The scene's integrator, used here before, is exact
    /// only for a constant acceleration: under a moving base its `γ ≠ ½` (or generalized-α)
    /// weighting of the two ends drifted the ball's energy by O(h) per flight (3.9e-5 J per
    /// flight at 3 ms, 4.10 Hz; docs/model.md).
    pub(crate) fn fly(&self, f: &Flight<T>, h: T, g_end: T) -> Flight<T> {
        let (two, three, six) = (lit::<T>(2.0), lit::<T>(3.0), lit::<T>(6.0));
        let a0 = f.accel;
        let a1 = [T::zero(), -g_end];
        let mut next = *f;
        for k in 0..2 {
            let (Some(c), Some(v), Some(x0), Some(x1)) = (
                next.centre.get_mut(k),
                next.velocity.get_mut(k),
                a0.get(k),
                a1.get(k),
            ) else {
                continue;
            };
            *c += h * *v + h * h * (*x0 / three + *x1 / six);
            *v += h * (*x0 + *x1) / two;
        }
        next.accel = a1;
        next.pseudo_accel = a1;
        next
    }

    /// The normal force of the track on a rolling ball (`N` of [`crate::ContactForces`]) \[N\];
    /// zero in flight: `N = m_b [−ẍ_A sin θ + (ÿ_A + g_eff) cos θ + ρ θ̇²]` with
    /// `θ = (R_tr/ρ) ψ − (r_b/ρ) φ`, `ψ = atan2(a₄, a₃)`, `ψ̇ = (a₃ ȧ₄ − a₄ ȧ₃)/|a|²`. It runs
    /// after every rolling step (the separation test): one `atan2`, one division, one
    /// `sin_cos`, no copy of the state.
    pub(crate) fn normal_force(&self, s: &State<T, D>) -> T {
        if S::EXTRA_DOFS != 1 || s.contact == Contact::InFlight {
            return T::zero();
        }
        let at = |x: &SVector<T, D>, k: usize| x.get(k).copied().unwrap_or(T::zero());
        let e = Self::END;
        let (a3, a4) = (T::one() + at(&s.q, e + 2), at(&s.q, e + 3));
        let (v3, v4) = (at(&s.v, e + 2), at(&s.v, e + 3));
        let psi = a4.atan2(a3);
        let psi_rate = (a3 * v4 - a4 * v3) / (a3 * a3 + a4 * a4);
        let i = &self.inertia;
        let theta = i.orbit_per_tilt * psi - i.orbit_per_spin * at(&s.q, Self::SPIN);
        let theta_rate = i.orbit_per_tilt * psi_rate - i.orbit_per_spin * at(&s.v, Self::SPIN);
        let (sin, cos) = theta.fast_sin_cos();
        let ball = &self.params.ball;
        let ya_g = at(&s.a, e + 1) + self.effective_gravity(s.base_accel);
        ball.mass * (-at(&s.a, e) * sin + ya_g * cos + ball.path_radius() * theta_rate * theta_rate)
    }

    /// `(N, F_t)` of the track on the ball (module doc; zero in flight): N from
    /// [`System::normal_force`], `F_t = m_b [ẍ_A cos θ + (ÿ_A + g_eff) sin θ + ρ θ̈]`.
    pub(crate) fn track_forces(&self, s: &State<T, D>) -> (T, T) {
        if s.contact == Contact::InFlight {
            return (T::zero(), T::zero());
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _, psi_accel) = tip::psi_all(&x);
        let i = &self.inertia;
        let theta = i.orbit_per_tilt * psi - i.orbit_per_spin * x.q[4];
        let theta_accel = i.orbit_per_tilt * psi_accel - i.orbit_per_spin * x.a[4];
        let (sin, cos) = theta.fast_sin_cos();
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let (xa, ya_g) = (x.a[0], x.a[1] + self.effective_gravity(s.base_accel));
        (
            self.normal_force(s),
            ball.mass * (xa * cos + ya_g * sin + rho * theta_accel),
        )
    }
}
