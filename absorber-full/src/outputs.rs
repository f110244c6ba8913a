//! What the full solver reports: the track's force on the ball (from the ball's equation of
//! motion, or from the multipliers of the augmented system), the constraint violation, the
//! heights and energies, and the [`Simulator`] interface shared with the core.

use super::assembly::{kron_i2, Block4};
use super::kin::{Mode, MC, NW, PHI, PSI, RB1, RB2, RT1, RT2};
use super::{FullSolver, FullState};
use crate::sim::{Observation, Simulator};
use absorber_core::shared::{Element, ElementVector};
use absorber_core::{Contact, Energies, Error, StepReport};

impl FullSolver {
    /// Generalized contact force on the ball along θ in a held state: `−λ` of the lock
    /// constraint, from the augmented system.
    pub(super) fn contact_force(&self, s: &FullState) -> Result<f64, Error> {
        if !matches!(self.mode(s.contact), Mode::Held(_)) {
            return Ok(0.0);
        }
        Ok(-self.multipliers(s)?[5])
    }

    /// The Lagrange multipliers of the local constraints at state `s` (augmented system in the
    /// state's contact mode).
    pub(super) fn multipliers(&self, s: &FullState) -> Result<[f64; MC], Error> {
        let mode = self.mode(s.contact);
        let qi = self.gather_ind(&s.q, mode);
        let vi = self.gather_ind(&s.v, mode);
        let ai = self.gather_ind(&s.a, mode);
        let mut warm = self.local_of(&s.q);
        let ev = self.evaluate_with(
            &mut self.work.borrow_mut().mass,
            None,
            &qi,
            &vi,
            &ai,
            self.effective_gravity(s.base_accel),
            mode,
            &mut warm,
            s.theta_ref,
            false,
        )?;
        Ok(ev.lambda_local)
    }

    /// The track's force on the ball at the current state, `(N, F_t)` \[N\] (normal along the
    /// inward normal, tangential along increasing θ: `absorber_core::ContactForces`), from the
    /// ball's own equation of motion with the state's accelerations
    /// (`track_force`, flight.rs): the force the separation test reads. For a ball resting
    /// on a stop `F_t` includes the stop's push, as the multipliers' `−λ₅ − λ₆/ρ` does. `(0, 0)`
    /// in flight, `None` without a free ball.
    pub fn contact_forces(&self) -> Option<(f64, f64)> {
        if !self.scene.free_ball() {
            return None;
        }
        let s = &self.state;
        if s.contact == Contact::InFlight {
            return Some((0.0, 0.0));
        }
        self.track_force(s).ok()
    }

    /// The track's force on the ball at the current state as [`FullSolver::contact_forces`],
    /// from the Lagrange multipliers of the augmented system (22) at `(q, q̇)`: the circle
    /// constraint `c₄ = |R_b − r_A| − ρ` gives `N = λ₄` and the no-slip constraint `c₅` (and,
    /// for a ball held on a stop, the lock `c₆ = θ − ψ − α`) `F_t = −λ₅ − λ₆/ρ`. An independent
    /// route (it needs every element's forces: about seven times the cost of the state's
    /// accelerations at N = 16), kept for the tests.
    pub fn contact_forces_from_multipliers(&self) -> Option<(f64, f64)> {
        if !self.scene.free_ball() {
            return None;
        }
        let s = &self.state;
        if s.contact == Contact::InFlight {
            return Some((0.0, 0.0));
        }
        let mode = self.mode(s.contact);
        let l = self.multipliers(s).ok()?;
        let lock_term = match mode {
            Mode::Held(_) => l[5] / self.params.ball.path_radius(),
            _ => 0.0,
        };
        Some((l[3], -l[4] - lock_term))
    }

    /// Largest |C(q)| of the position constraints at the current state (all of them: clamp,
    /// fixed joint, rolling contact, lock) \[m or rad\].
    pub fn constraint_violation(&self) -> f64 {
        self.violation_of(&self.state)
    }

    pub(super) fn violation_of(&self, s: &FullState) -> f64 {
        let mut worst = s.q[0..4].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mode = self.mode(s.contact);
        let w = self.local_of(&s.q);
        let c = self.bodies.constraints(&w, &[0.0; NW], mode, s.theta_ref);
        for k in 0..mode.m() {
            worst = worst.max(c.val[k].abs());
        }
        worst
    }

    /// Vertical deflection of the beam end relative to the base \[m\].
    pub fn tip_deflection(&self) -> f64 {
        self.state.q[4 * self.n + 1]
    }

    pub(super) fn heights(&self, s: &FullState) -> (f64, f64, f64) {
        let mut beam = 0.0;
        for e in 0..self.n {
            let u = ElementVector::<f64>::from_fn(|i, _| s.q[4 * e + i]);
            beam -= self.unit_weight(e).dot(&u);
        }
        let tip = if self.n_body >= 3 {
            s.q[self.zloc(RT2)]
        } else {
            0.0
        };
        let ball = if self.n_body >= 6 {
            s.q[self.zloc(RB2)]
        } else {
            0.0
        };
        (beam, tip, ball)
    }

    /// Element `e`'s weight per unit downward field, `Q_e(g = 1)` (paper eq. 17): the uniform
    /// beam's, or on an arm the element's own section with its heads (the core's
    /// [`absorber_core::loads::Section::weight`], the force the step applies).
    fn unit_weight(&self, e: usize) -> ElementVector<f64> {
        match self.arm.as_deref().and_then(|sec| sec.get(e)) {
            Some(sec) => sec.weight(1.0),
            None => self.element.gravity_force(1.0),
        }
    }

    /// Mass of the beam, tube and heads \[kg\]: `[beam] mass` for the uniform beam; on an arm
    /// `−Σ_e (Q_e(g = 1)_y₁ + Q_e(g = 1)_y₂)` (the value shape functions sum to one).
    pub(super) fn beam_mass(&self) -> f64 {
        if self.arm.is_none() {
            return self.params.beam.mass;
        }
        (0..self.n)
            .map(|e| {
                let w = self.unit_weight(e);
                -(w[1] + w[5])
            })
            .sum()
    }

    pub(super) fn tip_angle_of(&self, s: &FullState) -> (f64, f64) {
        if self.n_body >= 3 {
            (s.q[self.zloc(PSI)], s.v[self.zloc(PSI)])
        } else {
            let i = 4 * self.n;
            let (x, y) = (1.0 + s.q[i + 2], s.q[i + 3]);
            let (xd, yd) = (s.v[i + 2], s.v[i + 3]);
            (y.atan2(x), (x * yd - y * xd) / (x * x + y * y))
        }
    }
}

impl Simulator for FullSolver {
    fn step(&mut self, base_accel: f64) -> Result<StepReport<f64>, Error> {
        FullSolver::step(self, base_accel)
    }

    fn in_flight(&self) -> bool {
        FullSolver::in_flight(self)
    }

    fn observe(&self) -> Observation {
        let s = &self.state;
        let i = 4 * self.n;
        let (psi, psid) = self.tip_angle_of(s);
        let (th, thd) = if self.scene.has_ball() {
            let w = self.local_of(&s.q);
            let mut wd = [0.0; NW];
            for (j, x) in wd.iter_mut().enumerate() {
                if j < 4 || j - 4 < self.n_body {
                    *x = s.v[self.zloc(j)];
                }
            }
            self.bodies.orbit(&w, &wd, s.theta_ref)
        } else {
            (f64::NAN, f64::NAN)
        };
        Observation {
            time: s.time,
            tip_deflection: s.q[i + 1],
            tip_velocity: s.v[i + 1],
            tip_acceleration: s.a[i + 1],
            tip_angle: psi,
            tip_rate: psid,
            ball_angle: th,
            ball_rate: thd,
            ball_relative_angle: th - psi,
            ball_relative_rate: thd - psid,
        }
    }

    fn contact_forces(&self) -> Option<(f64, f64)> {
        FullSolver::contact_forces(self)
    }

    fn energies(&self, base_velocity: f64, base_displacement: f64) -> Energies<f64> {
        let s = &self.state;
        let g = self.params.gravity;
        let mut e = Energies {
            beam_strain: 0.0,
            beam_kinetic: 0.0,
            beam_potential: 0.0,
            tip_kinetic: 0.0,
            tip_potential: 0.0,
            ball_kinetic: 0.0,
            ball_potential: 0.0,
        };
        for k in 0..self.n {
            let u = ElementVector::<f64>::from_fn(|i, _| s.q[4 * k + i]);
            let mut v = ElementVector::<f64>::from_fn(|i, _| s.v[4 * k + i]);
            v[1] += base_velocity;
            v[5] += base_velocity;
            let ec = self.element_const(k);
            e.beam_strain += ec.quad.energy(&u);
            match &ec.kron {
                // ½ uᵀ (K₄ ⊗ I₂) u and ½ vᵀ (M₄ ⊗ I₂) v without the zero entries.
                Some((m4, k4)) => {
                    let quadratic = |b: &Block4, x: &ElementVector<f64>| {
                        let bx = kron_i2(b, x.as_slice());
                        0.5 * x.iter().zip(bx).map(|(x, y)| x * y).sum::<f64>()
                    };
                    e.beam_strain += quadratic(k4, &u);
                    e.beam_kinetic += quadratic(m4, &v);
                }
                None => {
                    let (_, me, kb) = self.element_of(k);
                    e.beam_strain += Element::bending_energy_with(kb, &u);
                    // By reference: `me * v` copies the 8 × 8 matrix per element and row.
                    #[allow(clippy::op_ref)]
                    let mv = me * &v;
                    e.beam_kinetic += 0.5 * v.dot(&mv);
                }
            }
        }
        let now = self.heights(s);
        let eq = self.eq_heights;
        e.beam_potential = g * (now.0 - eq.0 + self.beam_mass() * base_displacement);
        if self.n_body >= 3 {
            let p = &self.params.tip;
            let (vx, vy) = (s.v[self.zloc(RT1)], s.v[self.zloc(RT2)] + base_velocity);
            let rate = s.v[self.zloc(PSI)];
            e.tip_kinetic = 0.5 * (p.mass * (vx * vx + vy * vy) + p.inertia * rate * rate);
            e.tip_potential = g * p.mass * (now.1 - eq.1 + base_displacement);
        }
        if self.n_body >= 6 {
            let b = &self.params.ball;
            let (vx, vy) = (s.v[self.zloc(RB1)], s.v[self.zloc(RB2)] + base_velocity);
            let spin = s.v[self.zloc(PHI)];
            e.ball_kinetic = 0.5 * (b.mass * (vx * vx + vy * vy) + b.inertia * spin * spin);
            e.ball_potential = g * b.mass * (now.2 - eq.2 + base_displacement);
        }
        e
    }

    fn natural_frequencies(&self) -> Result<Vec<f64>, Error> {
        self.frequencies()
    }

    fn static_tip_deflection(&self) -> f64 {
        self.equilibrium.q[4 * self.n + 1]
    }

    fn set_ball_rate(&mut self, rate: f64) -> Result<(), Error> {
        FullSolver::set_ball_rate(self, rate)
    }

    fn solver_name(&self) -> &'static str {
        "full"
    }
}
