//! Energies as in the paper's figures 17–19 and 26–30 (docs/derivation.md §7).
//!
//! Kinetic energies use absolute velocities (relative velocity + base velocity ẏ_b along y);
//! potentials are gravitational energies as changes from the static equilibrium, plus the
//! base displacement y_b. Pass `base_velocity = base_displacement = 0` for the energies in the
//! frame moving with the base. The beam strain energy is the total (static part included).
//!
//! On a real arm ([`crate::scene::Arm`]) every sum runs over the element's own section
//! ([`crate::loads::Section`]: the tapered tube's properties, the heads folded into its mass
//! matrix and weight), the data the step assembles: `½ u̇ᵀ M_k u̇`, the strain energy with the
//! element's rigidities, and the heights `−Q_k(g = 1) · u` with the heads' weight included.

use crate::loads::SceneData as _;
use crate::model::Model;
use crate::outputs::Angles;
use crate::scalar::{lit, Real};
use crate::scene::Scene;
use crate::state::State;
use crate::step::ancf::{Element, ElementVector};
use crate::step::beam::{gather, Beam};

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
    /// Element `k`'s matrices (mass with any heads folded in, bending stiffness, axial data)
    /// and its weight per unit downward field `Q_k(g = 1)` (tube and heads): the section the
    /// step assembles ([`crate::loads::Section`] on an arm scene, the uniform beam otherwise).
    #[inline]
    pub(crate) fn element_and_unit_weight(&self, k: usize) -> (&Beam<T>, ElementVector<T>) {
        match self.sys.data.sections().and_then(|s| s.get(k)) {
            Some(sec) => (&sec.beam, sec.weight(T::one())),
            None => (
                &self.sys.beam,
                self.sys.beam.element.gravity_force(T::one()),
            ),
        }
    }

    /// Mass of the beam (tube and heads) \[kg\]: `params.beam.mass` for the uniform beam; on an
    /// arm `−Σ_k (Q_k(g = 1)_y₁ + Q_k(g = 1)_y₂)`, the weight the step applies per unit field
    /// (the value shape functions sum to one, so this is Σ ρA l + Σ m of the heads).
    pub fn beam_mass(&self) -> T {
        if self.sys.data.sections().is_none() {
            return self.sys.params.beam.mass;
        }
        let mut m = T::zero();
        for k in 0..N {
            let (_, w) = self.element_and_unit_weight(k);
            m -= w[1] + w[5];
        }
        m
    }

    /// Heights of configuration `q` with its angles `ang` and `cos_theta` = cos θ (ignored
    /// without a ball).
    fn heights(&self, q: &nalgebra::SVector<T, D>, ang: &Angles<T>, cos_theta: T) -> Heights<T> {
        let mut beam = T::zero();
        for k in 0..N {
            // ∫ μ y dx (+ Σ m y of the heads) = −Q_k(g = 1) · u (eq. 17).
            let (_, unit) = self.element_and_unit_weight(k);
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
            contact: crate::state::Contact::Off,
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
        for k in 0..N {
            let (b, _) = self.element_and_unit_weight(k);
            let u = gather(&s.q, k);
            e.beam_strain +=
                b.element.axial_energy(&u) + Element::bending_energy_with(&b.stiffness, &u);
            let mut v = gather(&s.v, k);
            v[1] += base_velocity;
            v[5] += base_velocity;
            // By reference: `b.mass * v` would copy the 8×8 matrix (256 bytes in f32).
            let mass = &b.mass;
            e.beam_kinetic += half * v.dot(&(mass * v));
        }
        let ang = self.angles_of(s);
        let (sin_theta, cos_theta) = ang.theta_sin_cos().unwrap_or((z, T::one()));
        let mut now = self.heights(&s.q, &ang, cos_theta);
        let flying = s.contact == crate::state::Contact::InFlight;
        if flying {
            now.ball = s.flight.centre[1];
        }
        e.beam_potential = g * (now.beam - eq.beam + self.beam_mass() * base_displacement);
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
            let (b, _) = self.element_and_unit_weight(k);
            let u: ElementVector<T> = gather(q, k);
            u_total += b.element.axial_energy(&u) + Element::bending_energy_with(&b.stiffness, &u);
        }
        u_total
    }
}

#[cfg(test)]
mod tests {
    use crate::loads::{ArmParams, PointMass, MAX_POINT_MASSES};
    use crate::scene::{Arm, BeamOnly, FreeBall};
    use crate::step::ancf::Element;
    use crate::step::beam::gather;
    use crate::step::scheme::Chain;
    use crate::{Contact, Model, Params};
    use nalgebra::SVector;

    /// The shipped mast arm (scenes/mast-arm.toml): 16.76 m tube tapering 330 → 134.5 mm,
    /// wall 4.55 mm, heads of 30, 30, 30 and 10 kg at 7, 11, 15 and `sign` m (shipped: the
    /// free end, 16.76 m).
    fn mast_arm(sign: f64) -> (Params<f64>, ArmParams<f64>) {
        let mut p = Params::<f64>::default();
        p.beam.length = 16.76;
        p.beam.mass = 577.0;
        p.beam.area = 4.652e-3;
        p.beam.modulus = 200e9;
        p.beam.inertia = 6.160e-5;
        let mut point_masses = [PointMass {
            position: 0.0,
            mass: 0.0,
        }; MAX_POINT_MASSES];
        for (slot, (x, m)) in
            point_masses
                .iter_mut()
                .zip([(7.0, 30.0), (11.0, 30.0), (15.0, 30.0), (sign, 10.0)])
        {
            *slot = PointMass {
                position: x,
                mass: m,
            };
        }
        let arm = ArmParams {
            root_diameter: 0.330,
            tip_diameter: 0.1345,
            wall: 0.00455,
            density: 7850.0,
            point_masses,
        };
        (p, arm)
    }

    type MastArm = Model<f64, Arm<BeamOnly>, 3, 12>;

    /// A reproducible vector of entries in [−1, 1) (a linear congruential generator).
    fn random(seed: u64) -> SVector<f64, 12> {
        let mut x = seed;
        SVector::from_fn(|_, _| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
    }

    /// Kinetic energy of an arm is `½ vᵀ M v` with the model's own assembled mass matrix
    /// (`∂r/∂q̈`, the Newton matrix along `c_m = 1`, `c_q = c_v = 0`: the matrix every step
    /// solves with, tapered sections and heads included), for 20 random velocities, to 1e-13
    /// relative (the same products, summed element by element instead of over the band).
    /// Before, the energies used the uniform `[beam]` mass: off by the taper and the heads.
    #[test]
    fn arm_kinetic_energy_is_half_v_m_v_with_the_assembled_mass_matrix() {
        let (p, arm) = mast_arm(16.76);
        let mut m = MastArm::arm_at_rest(p, &arm, 0.0).expect("arm");
        let s0 = *m.state();
        let ch = Chain {
            c_q: 0.0,
            c_v: 0.0,
            c_m: 1.0,
        };
        let zero = SVector::<f64, 12>::zeros();
        let (_, mass, _) = m
            .sys
            .assemble(&s0.q, &zero, &zero, p.gravity, &ch, Contact::Off, false);
        for seed in 1..=20u64 {
            let v = random(seed) * 0.3;
            let mut s = s0;
            s.v = v;
            m.set_state(s);
            let e = m.energies(0.0, 0.0);
            let reference = 0.5 * v.dot(&(mass * v));
            assert!(
                (e.beam_kinetic / reference - 1.0).abs() < 1e-13,
                "seed {seed}: {} vs {reference}",
                e.beam_kinetic
            );
            // With a base velocity w every point moves by w more, the root node too:
            // ½ (v + w 1_y)ᵀ M̂ (v + w 1_y) = T(v) + w p_y + ½ w² m (M̂ with the root's rows).
            let w = 0.7;
            let with_base = m.energies(w, 0.0).beam_kinetic;
            let reference =
                e.beam_kinetic + w * m.vertical_momentum() + 0.5 * w * w * m.beam_mass();
            assert!((with_base / reference - 1.0).abs() < 1e-13, "seed {seed}");
        }
    }

    /// The arm's mass and gravitational energy: a vertical shift `d` of every node (slopes
    /// unchanged) raises the energy by `m g d` with m the tube's mass by Gauss quadrature over
    /// the taper plus the heads' ([`ArmParams::total_mass`], 528.2 kg, not `[beam] mass` =
    /// 577 kg), to 1e-12; the same for a base displacement. Independent of the closed-form
    /// weight vectors the energies sum. The sign sits at the end node, where `(L − x₀)/l`
    /// rounds to `1 + 2.2e-16` (f64, N = 3): the head's owner element still holds it.
    #[test]
    fn arm_gravity_energy_counts_the_taper_and_the_heads() {
        let (p, arm) = mast_arm(16.76);
        let mut m = MastArm::arm_at_rest(p, &arm, 0.0).expect("arm");
        let total = arm.total_mass(p.beam.length);
        assert!(
            (m.beam_mass() / total - 1.0).abs() < 1e-12,
            "{}",
            m.beam_mass()
        );
        let d = 0.01;
        let lifted = m.energies(0.0, d).beam_potential;
        let reference = total * p.gravity * d;
        assert!(
            (lifted / reference - 1.0).abs() < 1e-12,
            "{lifted} vs {reference}"
        );
        // Nodes 1–3 up by d (slopes kept), the clamp fixed: every head (x > l) rises by d,
        // the tube of element 0 by d s₂(ξ) on average ½ d: ΔV = g d (m − ½ μ₀ l).
        let mut s = *m.state();
        for n in 0..3 {
            s.q[4 * n + 1] += d;
        }
        m.set_state(s);
        let l = p.beam.length / 3.0;
        let mu0 = m
            .section(0)
            .expect("arm section")
            .beam
            .element
            .mass_per_length;
        let reference = p.gravity * d * (total - 0.5 * mu0 * l);
        let e = m.energies(0.0, 0.0).beam_potential;
        assert!((e / reference - 1.0).abs() < 1e-12, "{e} vs {reference}");
    }

    /// Clapeyron's theorem at the static equilibrium of the arm: the strain energy equals half
    /// the work of its weight on the sag, `U = ½ g ∫ μ (−y) dx + ½ g Σ m (−y_p)`, with the
    /// work computed here by Gauss quadrature of `μ_k y(x)` over each element (the Hermite
    /// interpolation of the solved nodes, μ_k the element's mass per length) plus `m y(x_p)` of
    /// each head, independently of the weight vectors the model sums. Budget 1e-4: a linear
    /// structure gives equality; the geometric nonlinearity is of order (sag/L)², 6e-6 at a
    /// tenth of g (41 mm of sag; at full g, 0.40 m, it is 4e-4). The sign at the end node.
    #[test]
    fn arm_strain_energy_at_equilibrium_is_half_the_work_of_its_weight() {
        let (mut p, arm) = mast_arm(16.76);
        p.gravity = 0.981;
        let m = MastArm::arm_at_rest(p, &arm, 0.0).expect("arm");
        let q = m.state().q;
        let n = 3;
        let l = p.beam.length / n as f64;
        let y_at = |x: f64| {
            let k = ((x / l) as usize).min(n - 1);
            let xi = (x - k as f64 * l) / l;
            let s = crate::step::ancf::shape(l, xi);
            let u = gather(&q, k);
            s[0] * u[1] + s[1] * u[3] + s[2] * u[5] + s[3] * u[7]
        };
        let mut height = 0.0;
        for k in 0..n {
            let mu = m
                .section(k)
                .expect("arm section")
                .beam
                .element
                .mass_per_length;
            for (xi, w) in crate::step::ancf::GAUSS5 {
                height += w * l * mu * y_at((k as f64 + xi) * l);
            }
        }
        for h in arm.point_masses.iter().filter(|h| h.mass > 0.0) {
            height += h.mass * y_at(h.position);
        }
        let sag = m.tip_deflection();
        eprintln!("sag {sag}");
        let work = -p.gravity * height;
        let u = m.energies(0.0, 0.0).beam_strain;
        assert!(
            (u / (0.5 * work) - 1.0).abs() < 1e-4,
            "{u} vs {}",
            0.5 * work
        );
        // The tapered sections carry the strain: the root section everywhere would give more
        // than twice the energy at this sag.
        let root = Element::of_beam(&p.beam, &p.calibration, n);
        let uniform: f64 = (0..n)
            .map(|k| Element::bending_energy_with(&root.bending_stiffness(), &gather(&q, k)))
            .sum();
        assert!(uniform > 1.5 * u, "{uniform} vs {u}");
    }

    /// A scene without sections keeps its energies bit for bit: the paper's free ball in f32,
    /// 600 steps at 4.13 Hz, every term against the uniform-beam sums written out here.
    #[test]
    fn uniform_beam_energies_are_unchanged_bit_for_bit() {
        let p = Params::<f32>::default();
        let mut m = Model::<f32, FreeBall, 3, 13>::at_rest(p, 0.0).expect("paper");
        let w = 2.0 * core::f32::consts::PI * 4.13;
        let b = m.sys.beam;
        let unit = b.element.gravity_force(1.0);
        let eq = m.sys.equilibrium;
        for k in 1..=600 {
            let ydd = -0.5e-3 * w * w * (w * k as f32 * 0.003).sin();
            m.step(ydd).expect("step");
            if k % 50 != 0 {
                continue;
            }
            let (vb, yb) = (0.013f32, -0.002f32);
            let e = m.energies(vb, yb);
            let s = m.state();
            let (mut strain, mut kinetic, mut now, mut then) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
            for j in 0..3 {
                let u = gather(&s.q, j);
                strain +=
                    b.element.axial_energy(&u) + Element::bending_energy_with(&b.stiffness, &u);
                let mut v = gather(&s.v, j);
                v[1] += vb;
                v[5] += vb;
                kinetic += 0.5 * v.dot(&(b.mass * v));
                now -= unit.dot(&u);
                then -= unit.dot(&gather(&eq, j));
            }
            let potential = p.gravity * (now - then + p.beam.mass * yb);
            assert_eq!(e.beam_strain.to_bits(), strain.to_bits(), "step {k}");
            assert_eq!(e.beam_kinetic.to_bits(), kinetic.to_bits(), "step {k}");
            assert_eq!(e.beam_potential.to_bits(), potential.to_bits(), "step {k}");
        }
    }
}
