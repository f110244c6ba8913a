//! Running a scene: the solver chosen by the scene, the excitation on the step grid, one
//! [`Row`] per step, CSV output.

mod row;
mod stats;

pub use row::*;
pub use stats::*;

use crate::excitation::{self, Excitation};
use crate::scene::{Scene, Solver};
use absorber_full::sim::Simulator;
use anyhow::{anyhow, bail, Result};

/// Builds the scene's solver at rest in the static equilibrium with input `base_accel0` at t = 0.
pub fn build_simulator(scene: &Scene, base_accel0: f64) -> Result<Box<dyn Simulator>> {
    let mut sim = build_at_rest(scene, base_accel0)?;
    let rate = scene.file.ball.initial_rate;
    if rate != 0.0 && scene.file.kind.free_ball() {
        sim.set_ball_rate(rate).map_err(|e| {
            anyhow!(
                "cannot start with `ball.initial_rate` = {rate} rad/s: {}",
                crate::scene::physical_failure(e, scene)
            )
        })?;
    }
    Ok(sim)
}

/// The scene's solver at rest in the static equilibrium (the ball at `ball.initial_angle_deg`,
/// without its initial rate).
fn build_at_rest(scene: &Scene, base_accel0: f64) -> Result<Box<dyn Simulator>> {
    let f = &scene.file;
    let params = scene.params()?;
    match f.solver {
        Solver::Core => {
            crate::core_sim::build(f.kind, f.elements, f.precision, &params, base_accel0)
                .map_err(|e| start_error(e, scene))
        }
        Solver::Full => {
            use crate::scene::{Kind, Precision};
            use absorber_full::{FullSolver, SceneKind};
            if f.precision != Precision::F64 {
                bail!("the full solver is f64 only (use --precision f64 or --solver core)");
            }
            if params.integrator.events != absorber_core::EventLocation::Crossing {
                bail!(
                    "`integrator.events = \"step-end\"` is an option of the embedded core; the \
                     full solver, the reference, always splits the step at an event (use \
                     --solver core, or events = \"crossing\")"
                );
            }
            let kind = match f.kind {
                Kind::Beam => SceneKind::BeamOnly,
                Kind::Tip => SceneKind::TipMass,
                Kind::Locked => SceneKind::LockedBall,
                Kind::Free => SceneKind::FreeBall,
                Kind::FreeNostops => SceneKind::FreeBallNoStops,
            };
            let sim = FullSolver::at_rest(params, kind, f.elements, base_accel0)
                .map_err(|e| start_error(e, scene))?;
            Ok(Box::new(sim))
        }
    }
}

/// A failure to start: a parameter error names its key; a failed static solve says so.
fn start_error(e: absorber_core::Error, scene: &Scene) -> anyhow::Error {
    match e {
        absorber_core::Error::InvalidParameter { .. } => crate::scene::map_core_error(e, scene),
        other => anyhow!(
            "cannot start: the static equilibrium under gravity could not be solved ({}); check \
             that the magnitudes of `beam.*`, `tip.*`, `ball.*` and `gravity` describe a beam that \
             can carry its load",
            crate::scene::physical_failure(other, scene)
        ),
    }
}

/// Steps a scene through `steps` steps, calling `sink` with the initial row and after every
/// step. `progress(k)` is called every 500 steps. A failed step ends the run with an error
/// naming the time.
pub fn simulate(
    scene: &Scene,
    exc: &Excitation,
    steps: usize,
    mut sink: impl FnMut(&Row),
    progress: impl FnMut(usize),
) -> Result<()> {
    simulate_with(
        scene,
        exc,
        steps,
        |r| {
            sink(r);
            Ok(())
        },
        progress,
    )
}

/// As [`simulate`], with a sink that can fail (e.g. a full disk): its error ends the run.
pub fn simulate_with(
    scene: &Scene,
    exc: &Excitation,
    steps: usize,
    mut sink: impl FnMut(&Row) -> Result<()>,
    mut progress: impl FnMut(usize),
) -> Result<()> {
    let params = scene.params()?;
    let spin_ratio = params.ball.path_radius() / params.ball.radius;
    let b0 = exc.at(0);
    let mut sim = build_simulator(scene, b0.accel)?;
    // A locked ball has no angle of its own: it turns with the tip mass (θ = ψ), which the
    // `tip_angle` column already gives; its angle columns are NaN, as without a ball.
    let free = scene.file.kind.free_ball();
    let row = |sim: &dyn Simulator, k: usize, report: Option<&absorber_core::StepReport<f64>>| {
        let mut o = sim.observe();
        if !free {
            o.ball_angle = f64::NAN;
            o.ball_rate = f64::NAN;
            o.ball_relative_angle = f64::NAN;
            o.ball_relative_rate = f64::NAN;
        }
        let contact = sim.contact_forces();
        let b = exc.at(k);
        Row {
            t: o.time,
            base_y: b.displacement,
            tip_y: b.displacement + o.tip_deflection,
            tip_deflection: o.tip_deflection,
            tip_angle: o.tip_angle,
            ball_angle: o.ball_angle,
            ball_rel_angle: o.ball_relative_angle,
            energies: sim.energies(b.velocity, b.displacement),
            iterations: report.map_or(0, |r| r.iterations),
            impact: report.is_some_and(|r| r.impact.is_some()),
            base_accel: b.accel,
            tip_velocity: o.tip_velocity,
            tip_rate: o.tip_rate,
            ball_rate: o.ball_rate,
            ball_rel_rate: o.ball_relative_rate,
            ball_spin: o.tip_angle - spin_ratio * o.ball_relative_angle,
            ball_spin_rate: o.tip_rate - spin_ratio * o.ball_relative_rate,
            normal_force: contact.map_or(f64::NAN, |c| c.0),
            tangential_force: contact.map_or(f64::NAN, |c| c.1),
            contact: contact.map_or(f64::NAN, |_| if sim.in_flight() { 0.0 } else { 1.0 }),
            tip_acceleration: b.accel + o.tip_acceleration,
            separated: report.is_some_and(|r| r.separation.is_some()),
            landing: report
                .and_then(|r| r.landing)
                .map(|l| (l.bounced, l.required_friction().unwrap_or(f64::NAN))),
            events: report.map_or_else(Default::default, |r| r.events),
        }
    };
    sink(&row(sim.as_ref(), 0, None))?;
    for k in 1..=steps {
        let b = exc.at(k);
        let report = sim.step(b.accel).map_err(|e| {
            anyhow!(
                "step {k} of {steps} (t = {:.4} s, base acceleration {:.4e} m/s²) failed: {}",
                k as f64 * scene.file.integrator.step,
                b.accel,
                scene_error(e, scene)
            )
        })?;
        sink(&row(sim.as_ref(), k, Some(&report)))?;
        if k % 500 == 0 {
            progress(k);
            crate::interrupt::check()?;
        }
    }
    progress(steps);
    Ok(())
}

fn scene_error(e: absorber_core::Error, scene: &Scene) -> anyhow::Error {
    crate::scene::map_core_error(e, scene)
}

/// The excitation of a scene for its duration.
pub fn scene_excitation(scene: &Scene) -> Result<Excitation> {
    excitation::of_scene(scene, scene.steps())
}

/// Runs a scene for its duration and keeps every row (for the fixed, short runs of the
/// reports; commands stream with [`simulate`] and [`RunStats`]).
pub fn run_rows(scene: &Scene, progress: impl FnMut(usize)) -> Result<Vec<Row>> {
    let exc = scene_excitation(scene)?;
    let steps = scene.steps();
    let mut rows = Vec::new();
    rows.try_reserve(steps + 1)
        .map_err(|_| anyhow!("a run of {steps} steps does not fit in memory here"))?;
    simulate(scene, &exc, steps, |r| rows.push(*r), progress)?;
    Ok(rows)
}

/// The one definition of "steady" of `paper`, `run`, `sweep` and `fatigue`: every sample with
/// t ≥ `from` (the transient `outputs.transient`, 20 s by default, or `sweep --last`'s start),
/// to the end of the run; every steady figure of a table row is over this window. The label
/// their tables and JSON carry.
pub fn steady_label(from: f64) -> String {
    format!("steady: t ≥ {} s to the end", secs(from))
}

/// A time in seconds as a reader writes it: to the microsecond, trailing zeros dropped
/// (`4.999`, not the sum's `4.9990000000000006`).
pub fn secs(t: f64) -> String {
    trimmed(t, 6)
}

/// `x` with `decimals` decimals, trailing zeros and a trailing point dropped.
pub fn trimmed(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}
