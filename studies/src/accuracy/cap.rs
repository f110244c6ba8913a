//! The work cap's accuracy cost: the firmware's free ball (`f32`, N = 3, events at the step end)
//! on the paper's input and on every scene of the firmware's stress set
//! (`absorber_firmware::stress`), without a cap, with the cap taking the capped iterate
//! (`AtCap::Take`, the firmware's default) and with the cap keeping the state
//! (`AtCap::Keep`). Deterministic: the same inputs as the firmware runs under QEMU.

use absorber_core::work;
use absorber_core::{AtCap, FreeBallModel, Outcome};
use absorber_firmware::stress::{Rng, Stress, SCENES};
use absorber_firmware::{firmware_params, Setup, STEPS};
use std::fmt::Write;

/// What one run of a scene did.
#[derive(Clone, Copy, Debug, Default)]
pub struct CapRun {
    /// Steps that failed (state kept), were capped (iterate taken) or restarted the model.
    pub failed: u32,
    /// Capped steps.
    pub capped: u32,
    /// Restarts.
    pub restarts: u32,
    /// Most error steps in a row.
    pub longest: u32,
    /// RMS of the dynamic tip deflection (tip − static) over the run \[mm\].
    pub tip_rms: f64,
    /// RMS of the ball's relative angle over the run \[deg\].
    pub ball_rms: f64,
    /// Stop impacts.
    pub impacts: u32,
    /// Most work units of a step.
    pub max_work: u32,
    /// Steps run.
    pub steps: u32,
}

impl CapRun {
    /// Error steps: failed, capped or restarting.
    pub fn errors(&self) -> u32 {
        self.failed + self.capped + self.restarts
    }
}

/// The free ball of the firmware with the work cap `cap` and `at_cap`, on `stress` (or the
/// paper's input).
pub fn run(stress: Option<&'static Stress>, cap: u32, at_cap: AtCap) -> anyhow::Result<CapRun> {
    let setup = Setup { stress };
    let mut p = firmware_params(&setup);
    p.integrator.max_work = cap;
    p.integrator.at_cap = at_cap;
    let mut m = FreeBallModel::<f32, 3, 13>::at_rest(p, 0.0)?;
    if let Some(rate) = stress.and_then(|s| s.spin) {
        let b = m.params().ball;
        let mut v = m.state().v;
        v[12] = -rate * b.path_radius() / b.radius;
        let q = m.state().q;
        m.set_configuration(q, v, 0.0)?;
    }
    let h = m.params().integrator.step;
    let mut rng = Rng::default();
    let mut r = CapRun {
        steps: setup.steps(),
        ..CapRun::default()
    };
    let (mut tip2, mut ball2, mut run) = (0.0, 0.0, 0u32);
    for k in 1..=r.steps {
        let a = match stress {
            Some(s) => s.accel(k, h, absorber_firmware::FREQUENCY_HZ, &mut rng),
            None => absorber_firmware::base_accel(k, h, absorber_firmware::FREQUENCY_HZ),
        };
        let normal = match m.step(a) {
            Ok(rep) => {
                r.impacts += u32::from(rep.impact.is_some());
                r.max_work = r.max_work.max(u32::from(rep.work));
                match rep.outcome {
                    Outcome::Converged => true,
                    Outcome::Capped => {
                        r.capped += 1;
                        false
                    }
                    Outcome::Restarted => {
                        r.restarts += 1;
                        false
                    }
                }
            }
            Err(_) => {
                r.failed += 1;
                false
            }
        };
        run = if normal { 0 } else { run + 1 };
        r.longest = r.longest.max(run);
        let tip = f64::from(m.tip_deflection() - m.static_tip_deflection()) * 1e3;
        let ball = f64::from(m.ball_relative_angle().map_or(0.0, |x| x.0)).to_degrees();
        tip2 += tip * tip;
        ball2 += ball * ball;
    }
    r.tip_rms = (tip2 / f64::from(r.steps)).sqrt();
    r.ball_rms = (ball2 / f64::from(r.steps)).sqrt();
    Ok(r)
}

/// The section of `docs/accuracy.md`.
pub fn section() -> anyhow::Result<String> {
    let mut m = String::new();
    writeln!(m, "## 7. The work cap: what it costs\n")?;
    writeln!(m, "{}", include_str!("cap-notes.md"))?;
    writeln!(
        m,
        "| input | steps | no cap: most units in a step | no cap: error steps / longest run / tip RMS [mm] / θ RMS [°] / impacts | cap, iterate taken (default): error steps (failed / capped / restarts) / longest run / tip RMS / θ RMS / impacts | cap, state kept: error steps (failed / capped / restarts) / longest run / tip RMS / θ RMS / impacts |"
    )?;
    writeln!(m, "|---|---:|---:|---|---|---|")?;
    let inputs = std::iter::once(None).chain(SCENES.iter().map(Some));
    for s in inputs {
        let free = run(s, work::UNLIMITED, AtCap::Take)?;
        let take = run(s, work::DEADLINE, AtCap::Take)?;
        let keep = run(s, work::DEADLINE, AtCap::Keep)?;
        let cell = |r: &CapRun, detail: bool| {
            let e = if detail {
                format!(
                    "{} ({} / {} / {})",
                    r.errors(),
                    r.failed,
                    r.capped,
                    r.restarts
                )
            } else {
                r.errors().to_string()
            };
            format!(
                "{e} / {} / {:.2} / {:.1} / {}",
                r.longest, r.tip_rms, r.ball_rms, r.impacts
            )
        };
        writeln!(
            m,
            "| {} | {} | {} | {} | {} | {} |",
            s.map_or("paper (0.5 mm, 4.13 Hz)", |s| s.name),
            free.steps,
            free.max_work,
            cell(&free, false),
            cell(&take, true),
            cell(&keep, true)
        )?;
    }
    debug_assert_eq!(STEPS, 6667);
    writeln!(m)?;
    Ok(m)
}
