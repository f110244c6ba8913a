//! A candidate configuration of the embedded model: element count, step, precision, Newton
//! budget and rule.

use super::{integrator_for, PAPER_GAMMA};
use absorber_core::{NewtonKind, Params};
use absorber_sim::scene::Precision;
use serde::{Deserialize, Serialize};

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
    /// The firmware's work cap per step (`absorber_core::work::DEADLINE`; else none).
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
            p.integrator.max_work = absorber_core::work::DEADLINE;
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
            a.push_str(&format!(" work={}", absorber_core::work::DEADLINE));
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
