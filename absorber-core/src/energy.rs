//! Energies as in the paper's figures 17–19 and 26–30 (docs/derivation.md §7).
//!
//! Kinetic energies use absolute velocities (relative velocity + base velocity ẏ_b along y);
//! potentials are gravitational energies as changes from the static equilibrium, plus the
//! base displacement y_b. Pass `base_velocity = base_displacement = 0` for the energies in the
//! frame moving with the base. The beam strain energy is the total (static part included).

use crate::ancf::{Element, ElementVector};
use crate::beam::gather;
use crate::model::{Model, State};
use crate::outputs::Angles;
use crate::scalar::{lit, Real};
use crate::scene::Scene;

/// Energies of the bodies \[J\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energies<T> {
    /// Beam strain energy (axial + bending), total.
    pub beam_strain: T,
    /// Beam kinetic energy.
    pub beam_kinetic: T,
    /// Beam gravitational energy, change from the static state.
    pub beam_potential: T,
    /// Tip mass kinetic energy.
    pub tip_kinetic: T,
    /// Tip mass gravitational energy, change from the static state.
    pub tip_potential: T,
    /// Ball kinetic energy (translation + spin).
    pub ball_kinetic: T,
    /// Ball gravitational energy, change from the static state.
    pub ball_potential: T,
}

impl<T: Real> Energies<T> {
    /// Sum of all terms.
    pub fn total(&self) -> T {
        self.beam_strain
            + self.beam_kinetic
            + self.beam_potential
            + self.tip_kinetic
            + self.tip_potential
            + self.ball_kinetic
            + self.ball_potential
    }
}

/// Heights (relative to the base) of the mass centres: (∫μ y dx, y_B tip, y_D ball).
///
/// Those of the static equilibrium are constant for a run: [`Model::energies`] computes them
/// on every call, a caller evaluating energies at every sample (the monitor) keeps them from
/// [`Model::equilibrium_heights`] and calls [`Model::energies_about`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Heights<T> {
    beam: T,
    tip: T,
    ball: T,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
    /// Heights of configuration `q` with its angles `ang` and `cos_theta` = cos θ (ignored
    /// without a ball).
    fn heights(&self, q: &nalgebra::SVector<T, D>, ang: &Angles<T>, cos_theta: T) -> Heights<T> {
        let mut beam = T::zero();
        let unit = self.sys.beam.element.gravity_force(T::one());
        for k in 0..N {
            // ∫ μ y dx = −Q_f(g = 1) · u (eq. 17).
            beam -= unit.dot(&gather(q, k));
        }
        let y_a = q.get(4 * N - 3).copied().unwrap_or(T::zero());
        let tip = y_a - self.sys.params.tip.offset * ang.cos_psi;
        let ball = y_a - self.sys.params.ball.path_radius() * cos_theta;
        Heights { beam, tip, ball }
    }

    /// Heights of the static equilibrium the run started from.
    pub(crate) fn equilibrium_heights(&self) -> Heights<T> {
        let s = State {
            q: self.sys.equilibrium,
            contact: crate::model::Contact::Off,
            ..self.state
        };
        let ang = self.angles_of(&s);
        let cos_theta = ang.theta_sin_cos().map_or(T::one(), |(_, cos)| cos);
        self.heights(&s.q, &ang, cos_theta)
    }

    /// Energies of the current state, for the base moving at `base_velocity` \[m/s\] and
    /// displaced by `base_displacement` \[m\].
    pub fn energies(&self, base_velocity: T, base_displacement: T) -> Energies<T> {
        self.energies_about(
            &self.equilibrium_heights(),
            base_velocity,
            base_displacement,
        )
        .0
    }

    /// [`Model::energies`] with the static heights `eq` given ([`Model::equilibrium_heights`]),
    /// and the angles of the current state it used. Transcendental calls: `atan2` for ψ (and
    /// for θ of a free ball), one `sin_cos` of θ; cos ψ and sin ψ come from the end slope.
    pub(crate) fn energies_about(
        &self,
        eq: &Heights<T>,
        base_velocity: T,
        base_displacement: T,
    ) -> (Energies<T>, Angles<T>) {
        let s = &self.state;
        let g = self.sys.params.gravity;
        let half = lit::<T>(0.5);
        let z = T::zero();
        let mut e = Energies {
            beam_strain: z,
            beam_kinetic: z,
            beam_potential: z,
            tip_kinetic: z,
            tip_potential: z,
            ball_kinetic: z,
            ball_potential: z,
        };
        // By reference: `self.sys.beam.mass * v` would copy the 8×8 matrix (256 bytes in f32).
        let mass = &self.sys.beam.mass;
        for k in 0..N {
            let u = gather(&s.q, k);
            e.beam_strain += self.sys.beam.element.axial_energy(&u)
                + Element::bending_energy_with(&self.sys.beam.stiffness, &u);
            let mut v = gather(&s.v, k);
            v[1] += base_velocity;
            v[5] += base_velocity;
            e.beam_kinetic += half * v.dot(&(mass * v));
        }
        let ang = self.angles_of(s);
        let (sin_theta, cos_theta) = ang.theta_sin_cos().unwrap_or((z, T::one()));
        let mut now = self.heights(&s.q, &ang, cos_theta);
        let flying = s.contact == crate::model::Contact::InFlight;
        if flying {
            now.ball = s.flight.centre[1];
        }
        e.beam_potential = g * (now.beam - eq.beam + self.sys.params.beam.mass * base_displacement);
        if S::HAS_TIP {
            let rate = ang.psi_rate;
            let xd = s.v.get(4 * N - 4).copied().unwrap_or(z);
            let yd = s.v.get(4 * N - 3).copied().unwrap_or(z) + base_velocity;
            let p = &self.sys.params.tip;
            let (vx, vy) = (
                xd + p.offset * rate * ang.cos_psi,
                yd + p.offset * rate * ang.sin_psi,
            );
            e.tip_kinetic = half * (p.mass * (vx * vx + vy * vy) + p.inertia * rate * rate);
            e.tip_potential = g * p.mass * (now.tip - eq.tip + base_displacement);
            if let Some((_, theta_rate)) = ang.theta {
                let b = &self.sys.params.ball;
                let rho = b.path_radius();
                let (vx, vy, spin) = if flying {
                    let (c, w) = (&s.flight.velocity, s.v.get(4 * N).copied().unwrap_or(z));
                    (c[0], c[1] + base_velocity, w)
                } else {
                    (
                        xd + rho * theta_rate * cos_theta,
                        yd + rho * theta_rate * sin_theta,
                        ((rho + b.radius) * rate - rho * theta_rate) / b.radius,
                    )
                };
                e.ball_kinetic = half * (b.mass * (vx * vx + vy * vy) + b.inertia * spin * spin);
                e.ball_potential = g * b.mass * (now.ball - eq.ball + base_displacement);
            }
        }
        (e, ang)
    }

    /// Beam strain energy of an arbitrary displacement vector (for tests and reports) \[J\].
    pub fn strain_energy_of(&self, q: &nalgebra::SVector<T, D>) -> T {
        let mut u_total = T::zero();
        for k in 0..N {
            let u: ElementVector<T> = gather(q, k);
            u_total += self.sys.beam.element.axial_energy(&u)
                + Element::bending_energy_with(&self.sys.beam.stiffness, &u);
        }
        u_total
    }
}
