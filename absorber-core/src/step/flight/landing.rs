//! Landing on the track: a frictionless bounce, or a plastic, rough landing that keeps the
//! generalized momentum and rolls on.

use super::roots::{bounce_impulse, landing_bounces, polar_angle, wrap, GRAZING};
use crate::error::Error;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::Landing;
use crate::state::{Contact, State, StepReport};
use crate::step::newton::Workspace;
use crate::step::system::System;
use crate::step::tip;
use nalgebra::SVector;

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// The landing at the crossing `s` (module doc): the centre put on the circle, then a
    /// bounce or a plastic, rough landing; the accelerations go on from before the impulse
    /// ([`Self::after_impulse`]).
    pub(super) fn land(
        &self,
        s: &mut State<T, D>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<(), Error> {
        if self.land_impulse(s, None, ws, report)? {
            if s.contact == Contact::InFlight {
                self.after_impulse(s);
            } else {
                self.restart_acceleration(s, ws, report)?;
            }
        }
        Ok(())
    }

    /// The landing's projection and impulse at `s` (no acceleration): whether the velocities
    /// jumped. `crossing_speed`: the normal speed at the crossing when `s` is a step's end past
    /// it ([`Self::flight_events_at_end`]); it decides the bounce and sets the rebound to
    /// `−e_n` times it. `None`: `s` is the crossing.
    pub(super) fn land_impulse(
        &self,
        s: &mut State<T, D>,
        crossing_speed: Option<T>,
        ws: &mut Workspace<T, D>,
        report: &mut StepReport<T>,
    ) -> Result<bool, Error> {
        let ball = &self.params.ball;
        let rho = ball.path_radius();
        let rel = self.relative(s);
        if !is_positive(rel.r) {
            return Err(Error::NonFiniteState);
        }
        let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
        let (a, _) = self.end_point(s);
        s.flight.centre = [a[0] + rho * n[0], a[1] + rho * n[1]];
        let normal_speed = n[0] * rel.rate[0] + n[1] * rel.rate[1];
        if normal_speed.partial_cmp(&lit(GRAZING)) != Some(core::cmp::Ordering::Greater) {
            return Ok(false); // grazing: no impulse, the ball flies on
        }
        let speed = crossing_speed.map_or(normal_speed, |c| c.max(T::zero()));
        let mut landing = Landing {
            time: s.time,
            normal_speed: speed,
            normal_impulse: T::zero(),
            tangential_impulse: T::zero(),
            bounced: false,
        };
        let before = s.flight.velocity;
        // The ball is pressed onto the track at a_p = ((0, −g_eff) − Ä)·n + v_t²/ρ.
        let accel_end = [
            s.a.get(Self::END).copied().unwrap_or(T::zero()),
            s.a.get(Self::END + 1).copied().unwrap_or(T::zero()),
        ];
        let tangential = n[0] * rel.rate[1] - n[1] * rel.rate[0];
        let pressed = (-self.effective_gravity(s.base_accel) - accel_end[1]) * n[1]
            - accel_end[0] * n[0]
            + tangential * tangential / rho;
        // The hop's apex v_n² / (2 a_p): a hop shorter than a step is seen only here.
        if is_positive(pressed) {
            self.note_lift(s, speed * speed / (pressed + pressed), report);
        }
        let counted = s.flight.lifted;
        let bounces = landing_bounces(
            ball.landing_restitution,
            speed,
            rho * ball.stick_speed,
            pressed * self.params.integrator.step.max(ball.min_bounce_time),
        );
        if bounces {
            let mut y = SVector::<T, D>::zeros();
            // With events at the step end the trial's own factors serve (docs/model.md).
            let reuse = self.events_at_step_end();
            self.impulse_metric(s, Contact::InFlight, reuse, false, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, [n[0], n[1], T::zero(), T::zero()]);
            ws.solve(&mut y)?;
            let k = T::one() / ball.mass + self.end_dot(&y, [n[0], n[1], T::zero(), T::zero()]);
            if !is_positive(k) {
                return Err(Error::Singular);
            }
            let mut p = match crossing_speed {
                None => bounce_impulse(normal_speed, k, ball.landing_restitution),
                // From the end's normal speed to −e_n times the crossing's.
                Some(_) => (normal_speed + ball.landing_restitution * speed) / k,
            };

            if crossing_speed.is_none() && self.perfectly_elastic() {
                // Perfectly elastic: the kinetic energy is kept exactly in any metric. Along
                // (ball, housing) = (−n/m_b, y): b = −n·ċ + q̇ᵀM y, c = 1/m_b + yᵀM y.
                if let Some(e) = self
                    .mass_products(s, Contact::InFlight, &mut y, ws)
                    .and_then(|(uy, yy)| {
                        let b = uy - (n[0] * before[0] + n[1] * before[1]);
                        crate::step::stops::energy_exact_impulse(
                            -normal_speed,
                            b,
                            T::one() / ball.mass + yy,
                        )
                    })
                {
                    p = e;
                }
            }
            s.v.axpy(p, &y, T::one());
            for (c, nk) in s.flight.velocity.iter_mut().zip(n.iter()) {
                *c -= p / ball.mass * *nk;
            }
            landing.normal_impulse = p;
            landing.bounced = true;
        } else {
            // The rolling metric costs a refresh: unaffordable, the landing waits (the state
            // is not touched further; docs/embedded.md, "Work cap").
            if !ws.affords(crate::work::REFRESH + crate::work::SOLVE, 0) {
                return Err(Error::WorkCap);
            }
            // θ on the branch of ψ, and φ re-based so that r_b φ = R_tr ψ − ρ θ.
            let x = Self::local(&s.q, &s.v, &s.a);
            let (psi, _) = tip::psi_and_rate(&x);
            let theta = psi + wrap(polar_angle(n) - psi);
            let i = &self.inertia;
            if let Some(spin) = s.q.get_mut(Self::SPIN) {
                *spin = (i.orbit_per_tilt * psi - theta) / i.orbit_per_spin;
            }
            // On the track between the stops, or on the arc beyond them.
            s.contact = if S::STOPS && wrap(theta - psi).abs() > self.params.ball.stop_angle {
                Contact::Beyond
            } else {
                Contact::Off
            };
            // v⁺ = v⁻ + M_roll⁻¹ B_bᵀ Δ, Δ = m_b (ċ⁻ − ċ_roll(v⁻)).
            let (_, rolling) = self.ball_centre(s);
            let delta = [
                ball.mass * (before[0] - rolling[0]),
                ball.mass * (before[1] - rolling[1]),
            ];
            let (sin, cos) = theta.fast_sin_cos();
            let along = cos * delta[0] + sin * delta[1];
            let a3 = T::one() + x.q[2];
            let a4 = x.q[3];
            let s2 = a3 * a3 + a4 * a4;
            let w = rho * i.orbit_per_tilt * along / s2;
            let mut y = SVector::<T, D>::zeros();
            self.impulse_metric(s, s.contact, false, false, ws, &mut y)?;
            y.fill(T::zero());
            self.put_end(&mut y, [delta[0], delta[1], -w * a4, w * a3]);
            if let Some(spin) = y.get_mut(Self::SPIN) {
                *spin = -rho * i.orbit_per_spin * along;
            }
            ws.solve(&mut y)?;
            s.v += y;
            let (_, after) = self.ball_centre(s);
            let jx = ball.mass * (after[0] - before[0]);
            let jy = ball.mass * (after[1] - before[1]);
            landing.normal_impulse = -(n[0] * jx + n[1] * jy);
            landing.tangential_impulse = cos * jx + sin * jy;
        }
        report.landing = Some(landing);
        if counted {
            report.events.landings += 1;
            report.events.bounces += u8::from(landing.bounced);
        }
        Ok(true)
    }
}
