//! The ball leaves the track: separation where the track would have to pull the
//! ball, free flight inside the housing, landing, and the stops in flight (docs/model.md,
//! "Contact and flight").
//!
//! The frame translates with the base: x along the undeformed beam from the clamp, y up,
//! effective gravity `g_eff = g + ÿ_b`. `A` is the beam end (the track's centre), `ψ` the tip
//! rotation, `ρ = R − r_b` the radius of the ball centre's circle, `R_tr = ρ + r_b`.
//!
//! **On the track** the ball rolls (the model of [`crate::step::tip`]): `c − A = ρ (sin θ, −cos θ)`,
//! and the track's normal force on it, positive towards `A`, is
//! `N = m_b [−ẍ_A sin θ + (ÿ_A + g_eff) cos θ + ρ θ̇²]` ([`crate::ContactForces`]).
//!
//! **Separation.** A real track only pushes. When a step ends with `N < 0` the ball left the
//! track during it, at the fraction `τ = N₀ / (N₀ − N₁)` of the step (linear in `N`;
//! [`separation_fraction`]): the step is redone as a rolling sub-step of `τh` and a flight
//! sub-step of `(1 − τ)h`. Positions and velocities are continuous at the take-off.
//!
//! **Flight.** The ball is a free planar rigid body: its centre `c` follows
//! `c̈ = (0, −g_eff(t))`, its spin rate `ω = φ̇` stays constant (no torque); the housing (beam and
//! tip body) moves without it, integrated by the scene's integrator. The centre is integrated
//! exactly ([`System::fly`]: its acceleration is known and linear in time over a step), so its
//! path in the inertial frame is a free-fall parabola whatever the base does; the full solver
//! (`host-sim`), which releases the ball's constraints, does the same with its coordinates.
//!
//! **Landing** when the centre reaches the circle, `|c − A| = ρ` (crossing fraction: the cubic
//! Hermite root of `d = |c − A| − ρ`, [`hermite_root`]). The centre is put on the circle, and
//! with the normal speed `v_n = n·(ċ − Ȧ) > 0` (`n = (c − A)/|c − A|`):
//! - **bounce** if `e_n v_n ≥ ρ ω_stick` (`e_n` = `ball.landing_restitution`, `ω_stick` =
//!   `ball.stick_speed`, the stops' threshold as a speed) and the bounce's flight is longer than
//!   a step ([`landing_bounces`]): a frictionless normal impulse
//!   `P = (1 + e_n) v_n / K`, `K = 1/m_b + f_nᵀ M_h⁻¹ f_n` ([`bounce_impulse`]), on the ball `−P n`
//!   and on the housing `P n` at `A` (`f_n`: the end node's position rows); the ball flies on;
//! - otherwise a **plastic, rough landing**: rolling resumes, with the rolling velocities that
//!   keep the generalized momentum, `M_roll v⁺ = Bᵀ M_fl v⁻` (`B` the rolling velocity map).
//!   Written with the ball's momentum mismatch `Δ = m_b (ċ⁻ − ċ_roll(v⁻))`:
//!   `v⁺ = v⁻ + M_roll⁻¹ B_bᵀ Δ` — one factorization of the rolling mass matrix. The impulse the
//!   ball received, `J = m_b (ċ⁺ − ċ⁻)`, gives the normal and tangential impulses and the
//!   friction the landing needed (reported; the model rolls on whatever it is).
//!
//! **Counted.** The motion is the same for every hop, but the step report counts a flight
//! ([`crate::EventCounts`]: a separation, and its landings and bounces) only once it reaches
//! `ball.lift_height` (0, the default: every take-off): its gap to the track `ρ − |c − A|` at a
//! step's end, or at a landing the apex `v_n² / (2 a_p)` of a hop arriving at `v_n` while pressed
//! on at `a_p` (a hop shorter than a step), is higher. The rigid unilateral track on a flexible
//! housing makes hops of every height, down to nanometres, whose number grows without bound as
//! h shrinks (the housing's higher modes, rung by the landings and the stops, resolved by the
//! step); above a fixed height the count converges (docs/model.md, "Contact statistics").
//!
//! **Stops in flight**: a stop is a block on the track as tall as the ball's radius, so the
//! flying ball meets it where its centre is beyond `ρ − r_b` from A and its polar angle relative
//! to the housing, `α_f = atan2(c_x − A_x, A_y − c_y) − ψ`, reaches `±α_max`: a frictionless
//! impulse along `∇α_f` with the stops' restitution (plastic below `stick_speed`), the ball
//! kept in flight; the crossing is detected when the ball is at the stops' height at both ends
//! of a step, from either face. Nearer the centre the ball flies over the stops, onto the arc
//! beyond them, where it may land and roll like on the track (the stops then act on it from
//! their other face, [`crate::step::stops`]).
//!
//! Impulses use the stops' metric ([`crate::ImpactModel`]): the step's Newmark matrix by default
//! (an impulse in the mass-matrix metric kicks the housing's stiff end-rotation mode; a stop's
//! with its own contact time when `ball.stop_contact_time` is set), the mass matrix for an
//! instantaneous impact. A perfectly elastic ball's impulses keep the kinetic energy in either
//! metric ([`crate::step::stops`]), and it has every event of a step split at its crossing
//! ([`System::perfectly_elastic`]; docs/model.md, "Elastic bounces at the paper's step").
//! After an impulse the accelerations go on from before it
//! ([`System::after_impulse`]); a take-off and a rolling landing (a change of mode) restart from
//! the consistent acceleration of the new mode. At most one event splits a step (every event,
//! up to four, for a perfectly elastic ball); an event found at the end of the rest of the step
//! is applied there, and a ball on the track at the end of an
//! event step takes off there if the track pulls (`take_off_at_end`). The step report counts
//! every event ([`crate::EventCounts`]). With events at the step end
//! ([`crate::EventLocation::StepEnd`]) nothing splits a step: the events act at its end, without
//! a consistent acceleration (`flight_events_at_end`, docs/model.md).

mod events;
mod geometry;
mod landing;
pub(crate) mod roots;
mod separation;
mod stops;

#[cfg(test)]
mod tests;
