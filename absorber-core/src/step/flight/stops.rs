//! The stops in flight: a frictionless impulse along the polar angle's gradient with the stops'
//! restitution, and a ball put back at rest on a stop.

use crate::error::Error;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::{Contact, Impact, Side, State, StepReport};
use crate::step::newton::Workspace;
use crate::step::system::System;
use crate::step::tip;
use nalgebra::SVector;

/// A perfectly elastic flying ball ([`System::perfectly_elastic`]) that hits a stop from the
/// arc beyond it is put this far beyond the stop line \[rad\] (0.3 µm at the stops' height;
/// above the rounding of the polar angle in `f32`), so that it starts the rest of its step,
/// moving away from the stop, on the side it came from.
const BEYOND_OFFSET: f64 = 1e-5;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// A stop hit by the flying ball at `s` (module doc): the centre rotated about A onto the
    /// stop line, a frictionless impulse along `∇α_f`; the ball flies on, the accelerations go
    /// on from before the impulse ([`Self::after_impulse`]).
    pub(super) fn stop_in_flight(
        &self,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
    ) -> Result<Impact<T>, Error> {
        let impact = self.stop_impulse(s, side, inside, ws)?;
        self.after_impulse(s);
        Ok(impact)
    }

    /// The projection and impulse of [`Self::stop_in_flight`] (no acceleration).
    pub(super) fn stop_impulse(
        &self,
        s: &mut State<T, D>,
        side: Side,
        inside: bool,
        ws: &mut Workspace<T, D>,
    ) -> Result<Impact<T>, Error> {
        let ball = &self.params.ball;
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _) = tip::psi_and_rate(&x);
        let rel = self.relative(s);
        let line = if inside || !self.perfectly_elastic() {
            ball.stop_angle
        } else {
            ball.stop_angle + lit(BEYOND_OFFSET)
        };
        let theta = psi + side.sign::<T>() * line;
        let (sin, cos) = theta.fast_sin_cos();
        let (a, _) = self.end_point(s);
        s.flight.centre = [a[0] + rel.r * sin, a[1] - rel.r * cos];
        let (_, speed) = self.flight_relative_angle(s);
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: T::zero(),
            energy_loss: T::zero(),
            stuck: false,
        };
        // Towards the stop's face: outwards from the track's side, inwards from beyond.
        let towards = if inside {
            side.sign::<T>() * speed
        } else {
            -side.sign::<T>() * speed
        };
        if towards > T::zero() {
            let e = if speed.abs() < ball.stick_speed {
                T::zero()
            } else {
                ball.restitution
            };
            // ∇α_f on the housing: −t_f/r on A, −∂ψ/∂(a₃, a₄) = −(−a₄, a₃)/s² on the slope.
            let a3 = T::one() + x.q[2];
            let a4 = x.q[3];
            let s2 = a3 * a3 + a4 * a4;
            let grad = [-cos / rel.r, -sin / rel.r, a4 / s2, -a3 / s2];
            let mut y = SVector::<T, D>::zeros();
            // With events at the step end the trial's own factors serve (docs/model.md).
            let reuse = self.events_at_step_end();
            self.impulse_metric(s, Contact::InFlight, reuse, true, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, grad);
            ws.solve(&mut y)?;
            let k = T::one() / (ball.mass * rel.r * rel.r) + self.end_dot(&y, grad);
            if !is_positive(k) {
                return Err(Error::Singular);
            }
            let mut lambda = -(T::one() + e) * speed / k;
            if e >= T::one() && self.perfectly_elastic() {
                // Perfectly elastic: the kinetic energy is kept exactly in any metric. Along
                // (ball, housing) = ((cos, sin)/(m_b r), y): b = t·ċ/r + q̇ᵀM y,
                // c = 1/(m_b r²) + yᵀM y.
                let v = s.flight.velocity;
                if let Some(l) = self
                    .mass_products(s, Contact::InFlight, &mut y, ws)
                    .and_then(|(uy, yy)| {
                        let b = uy + (cos * v[0] + sin * v[1]) / rel.r;
                        let c = T::one() / (ball.mass * rel.r * rel.r) + yy;
                        crate::step::stops::energy_exact_impulse(speed, b, c)
                    })
                {
                    lambda = l;
                }
            }
            s.v.axpy(lambda, &y, T::one());
            let dv = lambda / (ball.mass * rel.r);
            s.flight.velocity[0] += dv * cos;
            s.flight.velocity[1] += dv * sin;
            impact.impulse = lambda / rel.r;
            impact.energy_loss = lit::<T>(0.5) * (T::one() - e * e) * speed * speed / k;
        }
        Ok(impact)
    }

    /// `y[END..END+4] = v` (the end node's coordinates).
    pub(super) fn put_end(&self, y: &mut SVector<T, D>, v: [T; 4]) {
        if let Some(dst) = y.as_mut_slice().get_mut(Self::END..Self::END + 4) {
            for (d, x) in dst.iter_mut().zip(v.iter()) {
                *d = *x;
            }
        }
    }

    /// `y[END..END+4] · v`.
    pub(super) fn end_dot(&self, y: &SVector<T, D>, v: [T; 4]) -> T {
        let mut sum = T::zero();
        if let Some(src) = y.as_slice().get(Self::END..Self::END + 4) {
            for (a, b) in src.iter().zip(v.iter()) {
                sum += *a * *b;
            }
        }
        sum
    }

    /// A rolling ball beyond a stop at the end of a step's rest: held on it (plastic), released
    /// at once if the stop would pull.
    pub(crate) fn rest_on_stop(
        &self,
        end: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        let side = if self.relative_angle(end) > T::zero() {
            Side::Positive
        } else {
            Side::Negative
        };
        self.hold_on_stop(end, side);
        end.contact = Contact::OnStop(side);
        let acc = self.consistent_acceleration(end, ws, self.params.integrator.newton)?;
        report.iterations += acc.iterations;
        end.a = acc.x;
        end.pseudo_accel = end.a;
        // (The release test's residual is charged to the work cap; unaffordable, released.)
        if !ws.afford_event(crate::work::RESIDUAL)
            || side.sign::<T>() * self.contact_force(end) > T::zero()
        {
            end.contact = Contact::Off;
        }
        Ok(())
    }
}
