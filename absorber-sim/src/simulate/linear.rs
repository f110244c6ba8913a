//! The linearized model at rest (`static`, `modes`): the scene's solver, or an arm scene's arm.

use crate::scene::Scene;
use crate::tune::ARM_ELEMENTS;
use anyhow::Result;
use serde_json::json;

/// The structure `static` and `modes` describe: the scene's solver at rest, or for a scene with
/// an `[arm]` the arm itself (full solver, [`ARM_ELEMENTS`] elements, f64), with its
/// (solver, elements) as printed.
pub fn structure(s: &Scene) -> Result<(Box<dyn absorber_full::sim::Simulator>, usize)> {
    let Some(arm) = &s.file.arm else {
        return Ok((crate::run::build_simulator(s, 0.0)?, s.file.elements));
    };
    use crate::scene::Kind;
    use absorber_full::{FullSolver, SceneKind};
    let kind = match s.file.kind {
        Kind::Beam => SceneKind::BeamOnly,
        Kind::Tip => SceneKind::TipMass,
        Kind::Locked => SceneKind::LockedBall,
        Kind::Free => SceneKind::FreeBall,
        Kind::FreeNostops => SceneKind::FreeBallNoStops,
    };
    let sim = FullSolver::arm_at_rest(s.params()?, kind, ARM_ELEMENTS, &arm.params()?, 0.0)
        .map_err(|e| crate::scene::map_core_error(e, s))?;
    Ok((Box::new(sim), ARM_ELEMENTS))
}

/// What `static --json` prints: scene, kind, elements, solver and the static tip deflection \[m\]
/// (for a scene with an `[arm]`: of the arm, full solver, [`ARM_ELEMENTS`] elements).
pub fn static_summary(s: &Scene) -> Result<serde_json::Value> {
    let (sim, elements) = structure(s)?;
    let d = sim.static_tip_deflection();
    Ok(
        json!({ "scene": s.file.name, "kind": s.file.kind.name(), "arm": s.file.arm.is_some(), "elements": elements, "solver": sim.solver_name(), "static_tip_deflection": d }),
    )
}

/// The `count` lowest natural frequencies of the linearized model at the static equilibrium \[Hz\]
/// (what `modes` prints; for a scene with an `[arm]`: of the arm, full solver,
/// [`ARM_ELEMENTS`] elements).
pub fn lowest_frequencies(s: &Scene, count: usize) -> Result<Vec<f64>> {
    let (sim, _) = structure(s)?;
    let f = sim
        .natural_frequencies()
        .map_err(|e| crate::scene::map_core_error(e, s))?;
    Ok(f.into_iter().take(count).collect())
}
