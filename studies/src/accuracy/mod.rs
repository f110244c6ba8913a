//! Error against run time: how far an embedded configuration (element count, step,
//! precision, Newton budget) is from a converged reference of the full solver, and what it
//! costs. `absorber-studies accuracy` regenerates `docs/accuracy.md` and `docs/img/accuracy_*.png`.
//!
//! **The truth.** Newmark with γ > ½ damps (ζ ≈ (γ − ½) ω h / 2): the paper's steady states
//! rely on that damping, and it vanishes as h → 0. A reference at a small step with the paper's
//! γ would therefore be a *different*, undamped system. The reference physics here is the
//! continuous model the paper's discretization approximates: Table 1 plus stiffness-proportional
//! beam damping `C = c₀ K_t` with `c₀ = (γ₀ − ½) h₀ = 0.2 · 3 ms = 6e-4 s` (the same ζ = c₀ω/2 on
//! every beam mode as the paper's integrator, to first order). Every configuration — reference
//! and candidates — integrates that physics with the **damping-matched Newmark rule**
//! ([`integrator_for`]): γ = ½ + min(0.2, c₀/h), β = (γ + ½)²/4, C = (c₀ − (γ − ½) h) K_t. At
//! h = 3 ms it is exactly the paper's (and the firmware's) integrator, γ = 0.7, β = 0.36, C = 0.
//! One candidate keeps the paper's γ, β at h = 1 ms without C to show what that costs.

mod compare;
mod config;
mod scenes;

pub use compare::*;
pub use config::*;
pub use scenes::*;

use absorber_full::{FullSolver, SceneKind};
use anyhow::{anyhow, Result};
pub use report::{run, AccuracyArgs};
use serde::{Deserialize, Serialize};
pub use sim::build_embedded;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod cap;

pub mod report;

pub mod sim;

/// The paper's step h₀ \[s\].
pub const PAPER_STEP: f64 = 0.003;

/// The paper's γ₀.
pub const PAPER_GAMMA: f64 = 0.7;

/// Stiffness-proportional damping of the reference physics, c₀ = (γ₀ − ½) h₀ \[s\].
pub const C0: f64 = (PAPER_GAMMA - 0.5) * PAPER_STEP;

/// Spacing of the common comparison grid \[s\] (all outputs are interpolated to it).
pub const GRID: f64 = 0.01;

/// `(γ, β, c)` of the damping-matched Newmark rule at step `h` (see the module doc).
pub fn integrator_for(h: f64) -> (f64, f64, f64) {
    let gamma = 0.5 + (C0 / h).min(PAPER_GAMMA - 0.5);
    let beta = (gamma + 0.5) * (gamma + 0.5) / 4.0;
    let c = (C0 - (gamma - 0.5) * h).max(0.0);
    (gamma, beta, c)
}

/// A run sampled on the common grid t_j = j · [`GRID`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    /// Tip deflection relative to the base (static sag included) \[m\].
    pub tip: Vec<f64>,
    /// Ball orbit angle θ \[rad\] (NaN for a locked ball).
    pub ball: Vec<f64>,
    /// Impact times \[s\].
    pub impacts: Vec<f64>,
    /// Static tip deflection \[m\].
    pub static_tip: f64,
    /// Steps taken and Newton iterations summed.
    pub steps: u64,
    /// Newton iterations summed over the steps.
    pub iterations: u64,
    /// Wall time of the run \[s\].
    pub wall: f64,
    /// Why the run stopped early.
    pub error: Option<String>,
}

impl Trajectory {
    /// Grid time of sample `j`.
    pub fn time(j: usize) -> f64 {
        j as f64 * GRID
    }
    /// Simulated time covered \[s\].
    pub fn duration(&self) -> f64 {
        (self.tip.len().saturating_sub(1)) as f64 * GRID
    }
}

/// What [`simulate`] needs from a solver.
pub trait Probe {
    /// One step to the base acceleration at its end.
    fn advance(&mut self, base_accel: f64) -> Result<(u32, Option<f64>), String>;
    /// (t, tip, tip rate, θ, θ̇).
    fn sample(&self) -> [f64; 5];
    /// Static tip deflection.
    fn static_tip(&self) -> f64;
}

impl<S: absorber_full::sim::Simulator + ?Sized> Probe for S {
    fn advance(&mut self, a: f64) -> Result<(u32, Option<f64>), String> {
        let r = self.step(a).map_err(|e| format!("{e:?}"))?;
        Ok((r.iterations, r.impact.map(|i| i.time)))
    }
    fn sample(&self) -> [f64; 5] {
        let o = self.observe();
        [
            o.time,
            o.tip_deflection,
            o.tip_velocity,
            o.ball_angle,
            o.ball_rate,
        ]
    }
    fn static_tip(&self) -> f64 {
        self.static_tip_deflection()
    }
}

fn hermite(t0: f64, y0: f64, d0: f64, t1: f64, y1: f64, d1: f64, t: f64) -> f64 {
    let h = t1 - t0;
    let s = (t - t0) / h;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * d1
}

/// Runs `sim` (step `h`) for `duration` s under `input` and samples it on the common grid by
/// cubic Hermite interpolation (values and rates at both step ends; exact at grid-aligned steps).
pub fn simulate<P: Probe + ?Sized>(
    sim: &mut P,
    h: f64,
    input: &Input,
    duration: f64,
) -> Trajectory {
    let start = Instant::now();
    // Enough steps to reach the last grid point (3 ms does not divide 10 s).
    let steps = (duration / h - 1e-9).ceil() as usize;
    let grid = (duration / GRID).round() as usize;
    let mut tr = Trajectory {
        tip: Vec::with_capacity(grid + 1),
        ball: Vec::with_capacity(grid + 1),
        impacts: Vec::new(),
        static_tip: sim.static_tip(),
        steps: 0,
        iterations: 0,
        wall: 0.0,
        error: None,
    };
    let mut prev = sim.sample();
    tr.tip.push(prev[1]);
    tr.ball.push(prev[3]);
    let mut next_j = 1usize;
    for k in 1..=steps {
        let t1 = k as f64 * h;
        match sim.advance(input.accel(t1)) {
            Ok((it, imp)) => {
                tr.iterations += u64::from(it);
                tr.steps += 1;
                if let Some(t) = imp {
                    tr.impacts.push(t);
                }
            }
            Err(e) => {
                tr.error = Some(format!("t = {:.3} s: {e}", t1 - h));
                break;
            }
        }
        let cur = sim.sample();
        let t0 = (k - 1) as f64 * h;
        while next_j <= grid && Trajectory::time(next_j) <= t1 + 1e-9 {
            let t = Trajectory::time(next_j);
            if (t - t1).abs() < 1e-9 {
                tr.tip.push(cur[1]);
                tr.ball.push(cur[3]);
            } else {
                tr.tip
                    .push(hermite(t0, prev[1], prev[2], t1, cur[1], cur[2], t));
                tr.ball
                    .push(hermite(t0, prev[3], prev[4], t1, cur[3], cur[4], t));
            }
            next_j += 1;
        }
        prev = cur;
    }
    tr.wall = start.elapsed().as_secs_f64();
    tr
}

/// Builds the embedded core for `cfg` and `scene`, at rest with the scene's input at t = 0.
pub fn embedded(cfg: &Config, scene: &TestScene) -> Result<Box<dyn absorber_full::sim::Simulator>> {
    build_embedded(
        scene.body,
        cfg.elements,
        cfg.f32,
        &cfg.params(),
        scene.input.accel(0.0),
    )
    .map_err(|e| anyhow!("{}: {e:?}", cfg.label()))
}

/// Builds the full solver for `cfg` (f64; `cfg.f32` ignored) and `scene`.
pub fn full(cfg: &Config, scene: &TestScene) -> Result<FullSolver> {
    let kind = match scene.body {
        Body::Free => SceneKind::FreeBall,
        Body::Locked => SceneKind::LockedBall,
    };
    FullSolver::at_rest(cfg.params(), kind, cfg.elements, scene.input.accel(0.0))
        .map_err(|e| anyhow!("full solver {}: {e:?}", cfg.label()))
}

/// Runs the embedded core.
pub fn run_embedded(cfg: &Config, scene: &TestScene, duration: f64) -> Result<Trajectory> {
    let mut s = embedded(cfg, scene)?;
    Ok(simulate(s.as_mut(), cfg.step, &scene.input, duration))
}

/// Runs the full solver (uncached).
pub fn run_full(cfg: &Config, scene: &TestScene, duration: f64) -> Result<Trajectory> {
    let mut s = full(cfg, scene)?;
    Ok(simulate(&mut s, cfg.step, &scene.input, duration))
}

/// The reference configuration: full solver, `n` elements, step `h`, f64, tolerance 1e-10.
pub fn reference_config(n: usize, h: f64) -> Config {
    Config {
        elements: n,
        step: h,
        f32: false,
        newton: Newton::Converged,
        tolerance: 1e-10,
        rule: Rule::Matched,
        calibration: None,
        step_end: false,
        capped: false,
    }
}

/// `cfg` with its element count calibrated by `host-sim calibrate`'s fit against the full
/// solver with `reference` elements (Table 1, ball locked; f₁, f₂, the free-ball beam mode,
/// the static sag).
pub fn calibrated(cfg: Config, reference: usize) -> Result<Config> {
    let mut scene = absorber_sim::scene::Scene::paper();
    scene.file.kind = absorber_sim::scene::Kind::Locked;
    let (r, free) = absorber_sim::calibrate::reference(&scene, reference)?;
    let fit = absorber_sim::calibrate::fit(&scene, cfg.elements, &r, free)?;
    let c = fit.calibration;
    Ok(
        cfg.with(|x| {
            x.calibration = Some([c.bending_stiffness, c.axial_stiffness, c.mass_lumping])
        }),
    )
}

/// Version of the cached files (bump when the solver or the sampling changes).
const CACHE_VERSION: u32 = 5; // 5: the start from rest without the equilibrium's own acceleration; 4: the full solver's event accelerations (free-ball references); 3: the noise scenes on ChaCha8 (`rand`); 2: per-solve Newton matrix with the settled-error test, faer LU

/// Full-solver run, cached in `cache` (JSON) under a name made of everything it depends on.
pub fn cached_full(
    cache: &Path,
    cfg: &Config,
    scene: &TestScene,
    duration: f64,
) -> Result<Trajectory> {
    let name = format!(
        "v{CACHE_VERSION}-{}-N{}-h{}us-tol{:e}-T{}s.json",
        scene.name,
        cfg.elements,
        (cfg.step * 1e6).round(),
        cfg.tolerance,
        duration
    );
    let path = cache.join(name);
    if let Ok(text) = std::fs::read_to_string(&path) {
        if let Ok(t) = serde_json::from_str::<Trajectory>(&text) {
            return Ok(t);
        }
    }
    let t = run_full(cfg, scene, duration)?;
    absorber_sim::output::atomic_write(&path, serde_json::to_string(&t)?.as_bytes())?;
    Ok(t)
}

/// First natural frequency of the locked scene (the beam mode) of the embedded core.
pub fn embedded_f1(cfg: &Config) -> Result<f64> {
    let locked = TestScene {
        name: "locked",
        title: "",
        body: Body::Locked,
        input: harmonic(4.13),
    };
    // Frequencies do not depend on the Newton variant (see `build_embedded` on budgets).
    let s = embedded(&cfg.with(|c| c.newton = Newton::Converged), &locked)?;
    s.natural_frequencies()
        .map_err(|e| anyhow!("{e:?}"))?
        .first()
        .copied()
        .ok_or_else(|| anyhow!("no frequency"))
}

/// First natural frequency of the locked scene from the full solver with `n` elements.
pub fn full_f1(n: usize) -> Result<f64> {
    let locked = TestScene {
        name: "locked",
        title: "",
        body: Body::Locked,
        input: harmonic(4.13),
    };
    let s = full(&reference_config(n, 0.0005), &locked)?;
    s.frequencies()
        .map_err(|e| anyhow!("{e:?}"))?
        .first()
        .copied()
        .ok_or_else(|| anyhow!("no frequency"))
}

/// Default cache directory: `$CARGO_TARGET_DIR/accuracy-cache`, else `target/accuracy-cache`
/// in the workspace.
pub fn default_cache() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) => PathBuf::from(d).join("accuracy-cache"),
        None => workspace_root().join("target").join("accuracy-cache"),
    }
}

/// The workspace root (where `docs/` lives).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}
