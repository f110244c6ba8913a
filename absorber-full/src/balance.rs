//! The ingredients of the energy balance of a step with applied loads (docs/model.md, "Energy
//! balance of a step") in the solver's maximal coordinates `z`: the generalized force of the
//! applied loads, the inner product of the constant mass matrix, and generalized-α's lag of its
//! acceleration-like variable behind the acceleration.
//!
//! The balance `[T + V + b h² A] = [z]ᵀ⟨F⟩ − φ [z]ᵀ M [a − z̈] − …` holds in these coordinates
//! with the constraint forces' work `[z]ᵀ C_zᵀ ⟨λ⟩` added; for the clamp alone (a bare beam or
//! arm, `SceneKind::BeamOnly`: linear constraints, the root node fixed) that work is zero, and
//! the root node's entries of `[z]` and of `a − z̈` are zero, so the balance is the core's in
//! the same free coordinates. With the bodies' nonlinear constraints it holds to the
//! constraints' curvature over a step.

use super::FullSolver;
use absorber_core::shared::ElementVector;

impl FullSolver {
    /// Generalized force `F` (length `4(N + 1) + bodies`, the layout of `z`) of a vertical tip
    /// force `tip` \[N\] at the beam end and the line loads `line` \[N/m\] per element, positive
    /// up: each element's [`absorber_core::shared::Element::line_load_force`] on its nodes and the
    /// tip force on the end node's vertical displacement (the vectors the step adds to its
    /// right-hand side, `set_loads`). Missing line loads count as zero.
    pub fn load_vector(&self, tip: f64, line: &[f64]) -> Vec<f64> {
        let mut f = vec![0.0; self.nz];
        for (e, w) in line.iter().enumerate().take(self.n) {
            let (element, _, _) = self.element_of(e);
            let q = element.line_load_force(*w);
            for (d, x) in f.iter_mut().skip(4 * e).zip(q.iter()) {
                *d += x;
            }
        }
        if let Some(d) = f.get_mut(4 * self.n + 1) {
            *d += tip;
        }
        f
    }

    /// `xᵀ M y` with the constant mass matrix of `z`: each element's mass matrix (the arm's
    /// section or the uniform beam's, as the step and [`crate::sim::Simulator::energies`] use)
    /// on its two nodes, and `diag(m_t, m_t, J_t, J_b, m_b, m_b)` on the bodies. Entries of `x`
    /// or `y` beyond their length count as zero.
    pub fn mass_inner(&self, x: &[f64], y: &[f64]) -> f64 {
        let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
        let mut s = 0.0;
        for e in 0..self.n {
            let (_, me, _) = self.element_of(e);
            let u = ElementVector::<f64>::from_fn(|i, _| at(x, 4 * e + i));
            let w = ElementVector::<f64>::from_fn(|i, _| at(y, 4 * e + i));
            // By reference: `me * w` would copy the 8 × 8 matrix.
            #[allow(clippy::op_ref)]
            let mw = me * &w;
            s += u.dot(&mw);
        }
        for j in 4..4 + self.n_body {
            let z = self.zloc(j);
            s += self.bodies.mass[j] * at(x, z) * at(y, z);
        }
        s
    }

    /// `a − z̈`: generalized-α's acceleration-like variable minus the acceleration (zero for
    /// Newmark, and on the dependent coordinates).
    pub fn filter_lag(&self) -> Vec<f64> {
        let s = &self.state;
        s.pa.iter().zip(&s.a).map(|(p, a)| p - a).collect()
    }

    /// `½ aᵀ M a` of the scheme's acceleration-like variable (`FullState::pa`) \[J/s²\].
    pub fn pseudo_accel_energy(&self) -> f64 {
        0.5 * self.mass_inner(&self.state.pa, &self.state.pa)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Simulator;
    use crate::SceneKind;
    use absorber_core::{ArmParams, Params};
    use rand::rngs::ChaCha8Rng;
    use rand::{RngExt, SeedableRng};

    /// The shipped mast arm's parameters and arm (N = 3).
    fn mast_arm() -> (Params<f64>, ArmParams<f64>) {
        let sc = absorber_sim::scene::Scene::from_toml(include_str!("../../scenes/mast-arm.toml"))
            .unwrap();
        let arm = sc.file.arm.as_ref().unwrap().params().unwrap();
        (sc.params().unwrap(), arm)
    }

    /// A deterministic pseudo-random sequence in [−1, 1) (ChaCha8).
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| rng.random_range(-1.0..1.0)).collect()
    }

    /// Rigid vertical translation (`uy = 1` at every node) and the small rigid rotation about
    /// the root (`uy = x`, `uy′ = 1`) of the beam's coordinates.
    fn rigid(solver: &FullSolver) -> (Vec<f64>, Vec<f64>) {
        let n = solver.elements();
        let l = solver.params.beam.length / n as f64;
        let mut lift = vec![0.0; solver.nz];
        let mut turn = vec![0.0; solver.nz];
        for k in 0..=n {
            lift[4 * k + 1] = 1.0;
            turn[4 * k + 1] = k as f64 * l;
            turn[4 * k + 3] = 1.0;
        }
        (lift, turn)
    }

    #[test]
    fn load_vector_does_the_virtual_work_of_the_loads_on_rigid_motions() {
        let (p, arm) = mast_arm();
        for n in [1, 3, 7] {
            let s = FullSolver::with_arm(p, SceneKind::BeamOnly, n, &arm).unwrap();
            let len = p.beam.length;
            let l = len / n as f64;
            let tip = 123.4;
            let line: Vec<f64> = (0..n).map(|e| 10.0 + 7.0 * e as f64).collect();
            let f = s.load_vector(tip, &line);
            let (lift, turn) = rigid(&s);
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            // Translation: the resultant, P + Σ w_e l.
            let resultant = tip + line.iter().map(|w| w * l).sum::<f64>();
            assert!((dot(&f, &lift) - resultant).abs() <= 1e-12 * resultant);
            // Rotation about the root: the moment, P L + Σ w_e ∫ x dx.
            let moment = tip * len
                + line
                    .iter()
                    .enumerate()
                    .map(|(e, w)| w * 0.5 * (((e + 1) as f64 * l).powi(2) - (e as f64 * l).powi(2)))
                    .sum::<f64>();
            assert!(
                (dot(&f, &turn) - moment).abs() <= 1e-12 * moment,
                "N = {n}: {} vs {moment}",
                dot(&f, &turn)
            );
        }
    }

    #[test]
    fn mass_inner_is_twice_the_kinetic_energy_and_the_mass_of_a_lift() {
        let (p, arm) = mast_arm();
        let mut s = FullSolver::with_arm(p, SceneKind::BeamOnly, 3, &arm).unwrap();
        // A rigid lift carries the whole mass: tube and heads, as their weights say.
        let (lift, _) = rigid(&s);
        let m = s.mass_inner(&lift, &lift);
        assert!(
            (m - s.beam_mass()).abs() <= 1e-12 * m,
            "{m} vs {}",
            s.beam_mass()
        );
        // ½ vᵀ M v is the kinetic energy of `energies()` at 20 random velocities (root node
        // clamped), and the product is symmetric.
        for seed in 1..=20u64 {
            let mut v = noise(s.nz, seed);
            v[..4].fill(0.0);
            let w = noise(s.nz, seed + 100);
            s.state.v.clone_from(&v);
            let e = Simulator::energies(&s, 0.0, 0.0);
            let t = 0.5 * s.mass_inner(&v, &v);
            assert!(
                (t - e.beam_kinetic).abs() <= 1e-13 * t,
                "{t} vs {}",
                e.beam_kinetic
            );
            let (a, b) = (s.mass_inner(&v, &w), s.mass_inner(&w, &v));
            assert!((a - b).abs() <= 1e-13 * t.max(1.0));
        }
    }

    #[test]
    fn mass_inner_of_the_bodies_is_their_kinetic_energy() {
        let p = Params::<f64>::default();
        let mut s = FullSolver::new(p, SceneKind::FreeBall, 3).unwrap();
        for seed in 1..=5u64 {
            let mut v = noise(s.nz, seed);
            v[..4].fill(0.0);
            s.state.v.clone_from(&v);
            let e = Simulator::energies(&s, 0.0, 0.0);
            let kinetic = e.beam_kinetic + e.tip_kinetic + e.ball_kinetic;
            let t = 0.5 * s.mass_inner(&v, &v);
            assert!((t - kinetic).abs() <= 1e-13 * t, "{t} vs {kinetic}");
        }
    }
}
