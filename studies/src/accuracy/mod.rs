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

pub mod cap;
pub mod report;
pub mod sim;

use absorber_core::{NewtonKind, Params};
use absorber_full::{FullSolver, SceneKind};
use anyhow::{anyhow, Result};
use host_sim::scene::Precision;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use sim::build_embedded;

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

/// How a configuration solves the Newmark equations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Newton {
    /// Full Newton to the tolerance (hard maximum 100).
    Converged,
    /// Full Newton, fixed budget: exactly k iterations, the iterate accepted after them.
    Budget(u32),
    /// Modified Newton (factored matrix reused) to the tolerance.
    Modified,
}

/// Which integrator parameters a configuration uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rule {
    /// The damping-matched rule ([`integrator_for`]).
    Matched,
    /// The paper's γ = 0.7, β = 0.36, no C, at any step (damping then scales with h).
    Paper,
}

/// One embedded (or reference) configuration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// Beam elements.
    pub elements: usize,
    /// Step h \[s\].
    pub step: f64,
    /// Scalar.
    pub f32: bool,
    /// Newton variant.
    pub newton: Newton,
    /// Newton tolerance (position increment in units of L / rad).
    pub tolerance: f64,
    /// Integrator rule.
    pub rule: Rule,
    /// Calibration factors (bending, axial, lumped fraction; [`calibrated`]) or none.
    pub calibration: Option<[f64; 3]>,
    /// Events (stop impacts, separation, landing) at the end of their step
    /// (`EventLocation::StepEnd`) instead of their crossing.
    #[serde(default)]
    pub step_end: bool,
    /// The firmware's work cap per step (`absorber_core::newton::work::DEADLINE`; else none).
    #[serde(default)]
    pub capped: bool,
}

impl Config {
    /// The firmware's default: N = 3, h = 3 ms, `f32`, full Newton to 1e-5 (the paper's).
    pub const DEFAULT: Config = Config {
        elements: 3,
        step: 0.003,
        f32: true,
        newton: Newton::Converged,
        tolerance: 1e-5,
        rule: Rule::Matched,
        calibration: None,
        step_end: false,
        capped: false,
    };

    /// The same with other fields.
    pub fn with(self, f: impl FnOnce(&mut Config)) -> Config {
        let mut c = self;
        f(&mut c);
        c
    }

    /// Short label, e.g. `N3 h3 f32 newton`.
    pub fn label(&self) -> String {
        let n = match self.newton {
            Newton::Converged => "newton".to_string(),
            Newton::Budget(k) => format!("budget {k}"),
            Newton::Modified => "modified".to_string(),
        };
        let h = self.step * 1e3;
        let hs = if (h - h.round()).abs() < 1e-9 {
            format!("{}", h.round())
        } else {
            format!("{h}")
        };
        let rule = match self.rule {
            Rule::Matched => "",
            Rule::Paper => " paper-γ",
        };
        format!(
            "N{} h{} {} {}{}{}{}{}",
            self.elements,
            hs,
            if self.f32 { "f32" } else { "f64" },
            n,
            rule,
            if self.calibration.is_some() {
                " calibrated"
            } else {
                ""
            },
            if self.step_end { " step-end" } else { "" },
            if self.capped { " capped" } else { "" }
        )
    }

    /// The parameters of this configuration (Table 1, the integrator of [`Rule`]).
    pub fn params(&self) -> Params<f64> {
        let mut p = Params::<f64>::default();
        let (gamma, beta, c) = match self.rule {
            Rule::Matched => integrator_for(self.step),
            Rule::Paper => (PAPER_GAMMA, 0.36, 0.0),
        };
        p.integrator.gamma = gamma;
        p.integrator.beta = beta;
        p.integrator.step = self.step;
        p.integrator.tolerance = self.tolerance;
        p.damping.stiffness_proportional = c;
        if let Some([bending, axial, lumping]) = self.calibration {
            p.calibration = absorber_core::Calibration {
                bending_stiffness: bending,
                axial_stiffness: axial,
                mass_lumping: lumping,
                bending_gradient: 0.0,
            };
        }
        match self.newton {
            Newton::Converged => {}
            Newton::Budget(k) => {
                p.integrator.max_iterations = k;
                p.integrator.accept_after_budget = true;
            }
            Newton::Modified => p.integrator.newton = NewtonKind::Modified,
        }
        if self.step_end {
            p.integrator.events = absorber_core::EventLocation::StepEnd;
        }
        if self.capped {
            p.integrator.max_work = absorber_core::newton::work::DEADLINE;
        }
        p
    }

    /// The arguments of `fw-cost` (absorber_firmware::cost) that run this configuration on the
    /// paper scene (free ball, 4.13 Hz, 10 s) on the Cortex-M4F; `None` for an element count
    /// the firmware does not build.
    pub fn firmware_args(&self) -> Option<String> {
        if ![1, 2, 3, 4, 6].contains(&self.elements) {
            return None;
        }
        let p = self.params();
        let i = &p.integrator;
        let mut a = format!(
            "kind=free elements={} precision={} step={:?} gamma={:?} beta={:?} damping={:?} tolerance={:?} newton={}",
            self.elements,
            if self.f32 { "f32" } else { "f64" },
            i.step,
            i.gamma,
            i.beta,
            p.damping.stiffness_proportional,
            i.tolerance,
            match i.newton {
                NewtonKind::PerStep => "per-step",
                NewtonKind::Full => "full",
                NewtonKind::Modified => "modified",
            }
        );
        if let Newton::Budget(k) = self.newton {
            a.push_str(&format!(" budget={k}"));
        }
        if let Some([b, x, l]) = self.calibration {
            a.push_str(&format!(" bending={b:?} axial={x:?} lumping={l:?}"));
        }
        if self.step_end {
            a.push_str(" events=step-end");
        }
        if self.capped {
            a.push_str(&format!(" work={}", absorber_core::newton::work::DEADLINE));
        }
        Some(a)
    }

    /// The precision as the scene's enum.
    pub fn precision(&self) -> Precision {
        if self.f32 {
            Precision::F32
        } else {
            Precision::F64
        }
    }
}

/// The bodies of a test scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Body {
    /// Free ball between the stops.
    Free,
    /// Ball locked in the housing.
    Locked,
}

/// Sum of sines: band-limited, deterministic, defined at every time (so runs with different
/// steps see the same signal).
#[derive(Clone, Debug, PartialEq)]
pub struct Noise {
    /// (amplitude \[m/s²\], ω \[rad/s\], phase \[rad\]).
    pub parts: Vec<(f64, f64, f64)>,
}

impl Noise {
    /// `count` components spread evenly (jittered) over `[f_lo, f_hi]` Hz, random phases from
    /// `seed` ([`host_sim::wind::Rng`]), equal amplitudes giving the RMS `rms` \[m/s²\].
    pub fn new(seed: u64, count: usize, f_lo: f64, f_hi: f64, rms: f64) -> Self {
        let mut rng = host_sim::wind::seeded(seed);
        let mut uniform = move || rand::RngExt::random::<f64>(&mut rng);
        let amp = rms * (2.0 / count as f64).sqrt();
        let parts = (0..count)
            .map(|i| {
                let f = f_lo + (f_hi - f_lo) * (i as f64 + uniform()) / count as f64;
                (
                    amp,
                    std::f64::consts::TAU * f,
                    std::f64::consts::TAU * uniform(),
                )
            })
            .collect();
        Self { parts }
    }

    /// ÿ_b(t).
    pub fn accel(&self, t: f64) -> f64 {
        self.parts
            .iter()
            .map(|&(a, w, p)| a * (w * t + p).sin())
            .sum()
    }
}

/// Base input of a test scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// y_b = A sin(2π f t).
    Harmonic {
        /// A \[m\].
        amplitude: f64,
        /// f \[Hz\].
        frequency: f64,
    },
    /// Band-limited noise acceleration.
    Random(Noise),
}

impl Input {
    /// ÿ_b(t) \[m/s²\].
    pub fn accel(&self, t: f64) -> f64 {
        match self {
            Input::Harmonic {
                amplitude,
                frequency,
            } => {
                let w = std::f64::consts::TAU * frequency;
                -amplitude * w * w * (w * t).sin()
            }
            Input::Random(n) => n.accel(t),
        }
    }
}

/// A fixed scene of the report.
#[derive(Clone, Debug, PartialEq)]
pub struct TestScene {
    /// Short name (file names, tables).
    pub name: &'static str,
    /// Description.
    pub title: &'static str,
    /// Bodies.
    pub body: Body,
    /// Base input.
    pub input: Input,
}

/// The noise of the random scenes: 200 sines over 1–10 Hz, RMS 1 m/s², seed 4.
pub fn paper_noise() -> Noise {
    Noise::new(4, 200, 1.0, 10.0, 1.0)
}

fn harmonic(f: f64) -> Input {
    Input::Harmonic {
        amplitude: 0.5e-3,
        frequency: f,
    }
}

/// The report's scenes.
pub fn scenes() -> Vec<TestScene> {
    vec![
        TestScene {
            name: "free-3.70",
            title: "free ball, 3.70 Hz",
            body: Body::Free,
            input: harmonic(3.70),
        },
        TestScene {
            name: "free-4.13",
            title: "free ball, 4.13 Hz (paper)",
            body: Body::Free,
            input: harmonic(4.13),
        },
        TestScene {
            name: "free-4.25",
            title: "free ball, 4.25 Hz",
            body: Body::Free,
            input: harmonic(4.25),
        },
        TestScene {
            name: "locked-4.13",
            title: "locked ball, 4.13 Hz",
            body: Body::Locked,
            input: harmonic(4.13),
        },
        TestScene {
            name: "locked-noise",
            title: "locked ball, noise 1–10 Hz, 1 m/s² RMS",
            body: Body::Locked,
            input: Input::Random(paper_noise()),
        },
        TestScene {
            name: "free-noise",
            title: "free ball, noise 1–10 Hz, 1 m/s² RMS",
            body: Body::Free,
            input: Input::Random(paper_noise()),
        },
    ]
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
    let mut scene = host_sim::scene::Scene::paper();
    scene.file.kind = host_sim::scene::Kind::Locked;
    let (r, free) = host_sim::calibrate::reference(&scene, reference)?;
    let fit = host_sim::calibrate::fit(&scene, cfg.elements, &r, free)?;
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
    host_sim::output::atomic_write(&path, serde_json::to_string(&t)?.as_bytes())?;
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

/// Errors of a candidate against the reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Errors {
    /// Window of the pointwise errors \[s\] (the whole comparison, or up to the reference's
    /// first impact for chaotic scenes).
    pub window: f64,
    /// RMS and max tip error over [0, min(5 s, window)] \[m\].
    pub tip_rms_5: f64,
    /// Max tip error, first 5 s \[m\].
    pub tip_max_5: f64,
    /// RMS tip error over the window \[m\].
    pub tip_rms: f64,
    /// Max tip error over the window \[m\].
    pub tip_max: f64,
    /// Max ball angle error over the first 5 s (or the window) \[rad\] (NaN: locked).
    pub ball_max_5: f64,
    /// Max ball angle error over the window \[rad\].
    pub ball_max: f64,
    /// Steady-state tip amplitude (half peak-to-peak over the last 20 s) \[m\].
    pub amplitude: f64,
    /// First time the tip error exceeds 10 % of the reference's peak dynamic deflection \[s\]
    /// (None: never).
    pub separation: Option<f64>,
    /// RMS dynamic tip deflection (about its mean) over [10 s, end] \[m\].
    pub dyn_rms: f64,
    /// Impacts per second.
    pub impacts_per_s: f64,
    /// RMS of θ over [10 s, end] \[rad\].
    pub ball_rms: f64,
}

/// Whole-run statistics of one trajectory.
pub fn statistics(t: &Trajectory, last: f64) -> (f64, f64, f64, f64) {
    let n = t.tip.len();
    let from_ss = ((t.duration() - last).max(0.0) / GRID).round() as usize;
    let from10 = ((10.0f64).min(t.duration() * 0.5) / GRID).round() as usize;
    let ss = &t.tip[from_ss.min(n)..];
    let (lo, hi) = ss
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let amplitude = if lo <= hi { 0.5 * (hi - lo) } else { f64::NAN };
    let w = &t.tip[from10.min(n)..];
    let mean = w.iter().sum::<f64>() / w.len().max(1) as f64;
    let dyn_rms =
        (w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / w.len().max(1) as f64).sqrt();
    let b = &t.ball[from10.min(n)..];
    let ball_rms = if b.iter().all(|x| x.is_finite()) {
        (b.iter().map(|x| x * x).sum::<f64>() / b.len().max(1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let ips = t.impacts.len() as f64 / t.duration().max(GRID);
    (amplitude, dyn_rms, ball_rms, ips)
}

/// Peak dynamic deflection of the reference, max |tip − static| \[m\].
pub fn peak_dynamic(r: &Trajectory) -> f64 {
    r.tip
        .iter()
        .map(|x| (x - r.static_tip).abs())
        .fold(0.0, f64::max)
}

/// Compares `c` with the reference `r` (same grid). `window`: end of the pointwise comparison.
pub fn compare(c: &Trajectory, r: &Trajectory, window: f64, last: f64) -> Errors {
    let n = c.tip.len().min(r.tip.len());
    let jw = ((window / GRID).round() as usize + 1).min(n);
    let j5 = ((5.0f64.min(window) / GRID).round() as usize + 1).min(n);
    let err = |j: usize| (c.tip[j] - r.tip[j]).abs();
    let berr = |j: usize| (c.ball[j] - r.ball[j]).abs();
    let rms = |m: usize| ((0..m).map(|j| err(j).powi(2)).sum::<f64>() / m.max(1) as f64).sqrt();
    let max = |m: usize, f: &dyn Fn(usize) -> f64| (0..m).map(f).fold(0.0, f64::max);
    let ball_locked = r.ball.first().is_none_or(|x| !x.is_finite());
    let scale = peak_dynamic(r);
    let separation = (0..n).find(|&j| err(j) > 0.1 * scale).map(Trajectory::time);
    let (amplitude, dyn_rms, ball_rms, impacts_per_s) = statistics(c, last);
    // A run that stopped early has no error bound: infinite.
    let short = c.tip.len() < r.tip.len();
    let inf_if = |x: f64| if short { f64::INFINITY } else { x };
    Errors {
        window,
        tip_rms_5: rms(j5),
        tip_max_5: max(j5, &err),
        tip_rms: inf_if(rms(jw)),
        tip_max: inf_if(max(jw, &err)),
        ball_max_5: if ball_locked {
            f64::NAN
        } else {
            max(j5, &berr)
        },
        ball_max: if ball_locked {
            f64::NAN
        } else {
            inf_if(max(jw, &berr))
        },
        amplitude: inf_if(amplitude),
        separation,
        dyn_rms,
        impacts_per_s,
        ball_rms,
    }
}

/// Host time of `cfg` relative to `reference` on `scene`: the median of `repeats` ratios of
/// runs taken in interleaved pairs (so that drifts of a shared machine cancel), which of the
/// two runs first alternating from pair to pair (a warm cache favours the second) \[-\].
pub fn paired_ratio(
    cfg: &Config,
    reference: &Config,
    scene: &TestScene,
    seconds: f64,
    repeats: usize,
) -> Result<f64> {
    let mut v = Vec::new();
    for k in 0..repeats.max(1) {
        let (r, c) = if k % 2 == 0 {
            let r = time_per_second(reference, scene, seconds, 1)?;
            (r, time_per_second(cfg, scene, seconds, 1)?)
        } else {
            let c = time_per_second(cfg, scene, seconds, 1)?;
            (time_per_second(reference, scene, seconds, 1)?, c)
        };
        v.push(c / r);
    }
    v.sort_by(f64::total_cmp);
    Ok(v[v.len() / 2])
}

/// Median host time per simulated second of `cfg` on `scene` (`seconds` simulated per
/// repetition, `repeats` repetitions) \[s/s\].
pub fn time_per_second(
    cfg: &Config,
    scene: &TestScene,
    seconds: f64,
    repeats: usize,
) -> Result<f64> {
    let mut v = Vec::new();
    for _ in 0..repeats.max(1) {
        let mut s = embedded(cfg, scene)?;
        let steps = (seconds / cfg.step).round() as usize;
        let start = Instant::now();
        for k in 1..=steps {
            if s.step(scene.input.accel(k as f64 * cfg.step)).is_err() {
                break;
            }
        }
        v.push(start.elapsed().as_secs_f64() / seconds);
    }
    v.sort_by(f64::total_cmp);
    Ok(v[v.len() / 2])
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

pub use report::{run, AccuracyArgs};
