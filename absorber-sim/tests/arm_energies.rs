//! The shipped mast arm's energies in the core against the full solver at the same mesh
//! (N = 3): both assemble the arm from the same sections (`absorber_core::loads::arm_section`)
//! but solve the statics and the dynamics on their own (the full solver with maximal
//! coordinates and its own Newton), so their strain and kinetic energies of the same arm agree
//! only if the core's `energies()` sums the arm's sections and heads.

use absorber_core::{Arm, BeamOnly, Loads, Model};
use absorber_full::sim::Simulator;
use absorber_full::{FullSolver, SceneKind};

fn mast_arm() -> (absorber_core::Params<f64>, absorber_core::ArmParams<f64>) {
    let scene = absorber_sim::scene::Scene::from_toml(include_str!("../../scenes/mast-arm.toml"))
        .expect("scene");
    let arm = scene
        .file
        .arm
        .as_ref()
        .expect("[arm]")
        .params()
        .expect("arm");
    (scene.params().expect("params"), arm)
}

/// At the static equilibrium: the strain energy (343 J, the arm's own sag under its weight)
/// agrees to 1e-9 (two Newton solves, each to its tolerance on a 0.40 m sag). Then 300 steps
/// (3 s) under a 200 N tip force and a 20 N/m line load, both solvers stepped with the same
/// loads: kinetic and strain energies agree to 1e-6 of the energy exchanged (the two Newton
/// solves per step each stop at their tolerance; measured: 1e-13). The gravitational energy
/// too (before, the full solver summed the uniform root element's weight without the heads:
/// 313.31 J against the core's 257.44 J after 50 steps), and with a base displacement the
/// `m g y_b` term with the arm's modelled mass.
#[test]
fn core_arm_energies_match_the_full_solver() {
    let (p, arm) = mast_arm();
    let mut core = Model::<f64, Arm<BeamOnly>, 3, 12>::arm_at_rest(p, &arm, 0.0).expect("core");
    let mut full = FullSolver::arm_at_rest(p, SceneKind::BeamOnly, 3, &arm, 0.0).expect("full");
    let (ec, ef) = (
        core.energies(0.0, 0.0),
        Simulator::energies(&full, 0.0, 0.0),
    );
    assert!(ec.beam_strain > 300.0, "{}", ec.beam_strain);
    assert!(
        (ec.beam_strain / ef.beam_strain - 1.0).abs() < 1e-9,
        "{} vs {}",
        ec.beam_strain,
        ef.beam_strain
    );
    let strain0 = ec.beam_strain;
    let loads = Loads::<f64, 3>::uniform(200.0, 20.0);
    full.set_loads(200.0, &[20.0; 3]).expect("loads");
    for k in 1..=300 {
        core.step_with_loads(0.0, &loads).expect("core step");
        Simulator::step(&mut full, 0.0).expect("full step");
        if k % 50 != 0 {
            continue;
        }
        let (ec, ef) = (
            core.energies(0.0, 0.0),
            Simulator::energies(&full, 0.0, 0.0),
        );
        let scale = (ec.beam_strain - strain0).abs().max(ec.beam_kinetic);
        assert!(
            (ec.beam_kinetic - ef.beam_kinetic).abs() < 1e-6 * scale,
            "step {k}: kinetic {} vs {}",
            ec.beam_kinetic,
            ef.beam_kinetic
        );
        assert!(
            (ec.beam_strain - ef.beam_strain).abs() < 1e-6 * scale,
            "step {k}: strain {} vs {}",
            ec.beam_strain,
            ef.beam_strain
        );
        assert!(
            (ec.beam_potential - ef.beam_potential).abs() < 1e-6 * scale,
            "step {k}: gravity {} vs {}",
            ec.beam_potential,
            ef.beam_potential
        );
        let (bc, bf) = (
            core.energies(0.0, 0.01).beam_potential,
            Simulator::energies(&full, 0.0, 0.01).beam_potential,
        );
        assert!(
            (bc - bf).abs() < 1e-6 * scale,
            "step {k}: gravity with the base 10 mm up {bc} vs {bf}"
        );
    }
}
