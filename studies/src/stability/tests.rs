//! The full solver's [`Balance`] against the core's on the shipped mast arm: the same load
//! vector, mass and coordinates in the free coordinates, and the same load work over a run.

use super::*;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};

/// The full-length arm case `name` (its loads) for `engine`, run for `duration` seconds.
fn arm_case(name: &str, engine: Engine, duration: f64) -> Case {
    let mut c = arm_cases(false)
        .into_iter()
        .find(|c| c.name.starts_with(name) && c.engine == engine)
        .unwrap();
    c.duration = duration;
    c
}

/// A deterministic pseudo-random sequence in [−1, 1) (ChaCha8).
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-1.0..1.0)).collect()
}

#[test]
fn full_and_core_balances_agree_on_the_mast_arm() {
    let core = build(&arm_case("storm", Engine::CoreF64, 1.0), 0.0).unwrap();
    let full = build(&arm_case("storm", Engine::Full, 1.0), 0.0).unwrap();
    let (bc, bf) = (core.balance().unwrap(), full.balance().unwrap());
    // The full solver's z: the clamped root node (4 zeros), then the core's free coordinates.
    let (qc, qf) = (bc.coordinates(), bf.coordinates());
    assert_eq!(qf.len(), qc.len() + 4);
    assert!(qf[..4].iter().all(|&x| x == 0.0));
    let scale = qc.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (a, b) in qc.iter().zip(&qf[4..]) {
        assert!(
            (a - b).abs() <= 1e-9 * scale,
            "static equilibrium: {a} vs {b}"
        );
    }
    // Load vectors: the core's (its own element integrals) and the full solver's.
    let line = [310.0, -45.0, 120.5];
    let (fc, ff) = (bc.load_vector(-812.0, &line), bf.load_vector(-812.0, &line));
    assert!(
        ff[..4].iter().any(|&x| x != 0.0),
        "the root node takes its share"
    );
    for (i, (a, b)) in fc.iter().zip(&ff[4..]).enumerate() {
        assert!((a - b).abs() <= 1e-12 * 812.0, "F[{i}]: {a} vs {b}");
    }
    // Mass: the core's by polarization of its kinetic energy, the full solver's matrix.
    for seed in 1..=10u64 {
        let (x, y) = (noise(qc.len(), seed), noise(qc.len(), seed + 50));
        let pad = |v: &[f64]| [&[0.0; 4][..], v].concat();
        let (mc, mf) = (bc.mass_inner(&x, &y), bf.mass_inner(&pad(&x), &pad(&y)));
        let norm = bc.mass_inner(&x, &x).sqrt() * bc.mass_inner(&y, &y).sqrt();
        assert!((mc - mf).abs() <= 1e-12 * norm, "xᵀMy: {mc} vs {mf}");
    }
    // At rest both schemes' variables equal the accelerations (zero lag).
    assert!(bf.filter_lag().iter().all(|&x| x == 0.0));
}

/// The work of the loads over 3 s of the storm (300 generalized-α steps, the buffeting force
/// from the first step) is the same through either solver's `Balance`, and both runs pass the
/// energy check. The solvers step the arm alike to ~1e-13 of the exchange
/// (absorber-sim/tests/arm_energies.rs), so 1e-6 of the work leaves room for the rounding of the
/// sums only.
#[test]
fn full_and_core_load_work_agree_over_a_storm() {
    let core = arm_case("storm", Engine::CoreF64, 3.0);
    let full = arm_case("storm", Engine::Full, 3.0);
    let (oc, of) = (run_case_here(&core), run_case_here(&full));
    for (c, o) in [(&core, &oc), (&full, &of)] {
        assert!(o.energy_checked, "{}", c.engine.name());
        assert!(
            o.passes(&c.expect),
            "{}: margin {:e}, start-up {:e}, error {:?}",
            c.engine.name(),
            o.margin,
            o.margin_startup,
            o.error
        );
    }
    assert!(oc.work.abs() > 1.0, "the storm does work: {} J", oc.work);
    eprintln!(
        "load work over 3 s of storm: core {} J, full {} J, relative difference {:.1e}",
        oc.work,
        of.work,
        (oc.work - of.work).abs() / oc.work.abs()
    );
    assert!(
        (oc.work - of.work).abs() <= 1e-6 * oc.work.abs(),
        "W core {} J, full {} J",
        oc.work,
        of.work
    );
}
