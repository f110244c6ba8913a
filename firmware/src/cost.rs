//! Instructions per step of a configuration chosen at run time: the cost column of
//! `docs/accuracy.md` (`scripts/accuracy-cost.sh` runs `fw-cost` under QEMU with the step
//! counter, once per configuration, and checks it against the host run of the same bin).
//!
//! Arguments (`key=value`, on the host command line or as semihosting arguments):
//! `kind=free|locked`, `elements=1|2|3|4|6`, `precision=f32|f64`, `step=` \[s\], `gamma=`,
//! `beta=`, `damping=` (stiffness-proportional c \[s\]), `tolerance=`, `newton=per-step|full|
//! modified`, `budget=K` (exactly K iterations, the iterate accepted), `seconds=` (simulated),
//! `frequency=` \[Hz\], `amplitude=` \[m\] (harmonic base motion, the paper scene's by default),
//! `bending=`, `axial=`, `lumping=` (`absorber_core::Calibration`; identity by default),
//! `events=crossing|step-end` (`absorber_core::EventLocation`), `work=` (`Integrator::max_work`, work
//! units; unlimited by default).
//! Unknown keys and bad values are errors (exit 4), never ignored.
//!
//! Every step goes through [`cost_step`], never inlined, one symbol for every variant, so the
//! counter needs one entry address; its own dispatch adds a few instructions (stated in the
//! report). The output ends with `state_hash=`, a fingerprint of every step's state.

use crate::{error_name, Fnv};
use absorber_core::scalar::{lit, to_f64};
use absorber_core::{
    Error, EventLocation, FreeBallModel, LockedBallModel, Model, NewtonKind, Params, Real, Scene,
};
use core::fmt::Write;

/// One configuration.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    free: bool,
    elements: u32,
    f64: bool,
    step: f64,
    gamma: f64,
    beta: f64,
    damping: f64,
    tolerance: f64,
    newton: NewtonKind,
    budget: Option<u32>,
    seconds: f64,
    frequency: f64,
    amplitude: f64,
    calibration: [f64; 3],
    events: EventLocation,
    max_work: u32,
}

impl Default for Config {
    fn default() -> Self {
        let p = Params::<f64>::default();
        Self {
            free: true,
            elements: 3,
            f64: false,
            step: p.integrator.step,
            gamma: p.integrator.gamma,
            beta: p.integrator.beta,
            damping: 0.0,
            tolerance: p.integrator.tolerance,
            newton: p.integrator.newton,
            budget: None,
            seconds: 10.0,
            frequency: 4.13,
            amplitude: 0.5e-3,
            calibration: [1.0, 1.0, 0.0],
            events: p.integrator.events,
            max_work: p.integrator.max_work,
        }
    }
}

impl Config {
    /// Applies one `key=value` argument; the key is the error.
    pub fn set<'a>(&mut self, arg: &'a str) -> Result<(), &'a str> {
        let (key, value) = arg.split_once('=').ok_or(arg)?;
        let num = || {
            value
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or(key)
        };
        match key {
            "kind" => {
                self.free = match value {
                    "free" => true,
                    "locked" => false,
                    _ => return Err(key),
                }
            }
            "elements" => {
                self.elements = value
                    .parse()
                    .ok()
                    .filter(|n| matches!(n, 1 | 2 | 3 | 4 | 6))
                    .ok_or(key)?
            }
            "precision" => {
                self.f64 = match value {
                    "f32" => false,
                    "f64" => true,
                    _ => return Err(key),
                }
            }
            "step" => self.step = num()?,
            "gamma" => self.gamma = num()?,
            "beta" => self.beta = num()?,
            "damping" => self.damping = num()?,
            "tolerance" => self.tolerance = num()?,
            "newton" => {
                self.newton = match value {
                    "per-step" => NewtonKind::PerStep,
                    "full" => NewtonKind::Full,
                    "modified" => NewtonKind::Modified,
                    _ => return Err(key),
                }
            }
            "budget" => self.budget = Some(value.parse().ok().filter(|k| *k > 0).ok_or(key)?),
            "seconds" => self.seconds = num()?,
            "frequency" => self.frequency = num()?,
            "amplitude" => self.amplitude = num()?,
            "bending" => self.calibration[0] = num()?,
            "axial" => self.calibration[1] = num()?,
            "lumping" => self.calibration[2] = num()?,
            "events" => {
                self.events = match value {
                    "crossing" => EventLocation::Crossing,
                    "step-end" => EventLocation::StepEnd,
                    _ => return Err(key),
                }
            }
            "work" => self.max_work = value.parse().ok().ok_or(key)?,
            _ => return Err(key),
        }
        Ok(())
    }

    fn params<T: Real>(&self) -> Params<T> {
        let mut p = Params::<T>::default();
        let i = &mut p.integrator;
        i.step = lit(self.step);
        i.gamma = lit(self.gamma);
        i.beta = lit(self.beta);
        i.tolerance = lit(self.tolerance);
        i.newton = self.newton;
        i.events = self.events;
        i.max_work = self.max_work;
        if let Some(k) = self.budget {
            i.max_iterations = k;
            i.accept_after_budget = true;
        }
        p.damping.stiffness_proportional = lit(self.damping);
        let [bending, axial, lumping] = self.calibration;
        p.calibration.bending_stiffness = lit(bending);
        p.calibration.axial_stiffness = lit(axial);
        p.calibration.mass_lumping = lit(lumping);
        p
    }

    fn steps(&self) -> u32 {
        let n = libm::round(self.seconds / self.step);
        if (1.0..1e7).contains(&n) {
            n as u32
        } else {
            0
        }
    }
}

/// A model behind one object-safe interface, whatever its scalar, scene and size.
pub trait Step {
    /// One step to base acceleration `u` \[m/s²\]: the Newton iterations, or the error.
    fn step(&mut self, u: f64) -> Result<u32, Error>;
    /// Feeds the state (each value as the bits of its `f64` value) to `f`.
    fn words(&self, f: &mut dyn FnMut(u32));
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Step for Model<T, S, N, D> {
    fn step(&mut self, u: f64) -> Result<u32, Error> {
        Model::step(self, lit(u)).map(|r| r.iterations)
    }

    fn words(&self, f: &mut dyn FnMut(u32)) {
        let s = self.state();
        for x in s.q.iter().chain(s.v.iter()).chain(s.a.iter()) {
            let b = to_f64(*x).to_bits();
            f(b as u32);
            f((b >> 32) as u32);
        }
    }
}

/// The counted step: every variant's step, called through one non-inlined function.
#[inline(never)]
pub fn cost_step(m: &mut dyn Step, u: f64) -> Result<u32, Error> {
    m.step(u)
}

fn drive<W: Write>(m: &mut dyn Step, c: &Config, out: &mut W) -> u8 {
    let omega = 2.0 * core::f64::consts::PI * c.frequency;
    let mut hash = Fnv::default();
    let (mut iterations, mut failed) = (0u64, 0u32);
    let steps = c.steps();
    for k in 1..=steps {
        let t = f64::from(k) * c.step;
        let u = -c.amplitude * omega * omega * libm::sin(omega * t);
        match cost_step(m, u) {
            Ok(it) => iterations += u64::from(it),
            Err(e) => {
                failed += 1;
                if failed == 1 {
                    let _ = writeln!(out, "first failure: step {k}: {}", error_name(&e));
                }
            }
        }
        m.words(&mut |w| hash.word(w));
    }
    let _ = writeln!(
        out,
        "steps={steps} failed={failed} iterations={iterations} state_hash=0x{:016x}",
        hash.0
    );
    0
}

fn start<M: Step, W: Write>(
    c: &Config,
    out: &mut W,
    init: impl FnOnce() -> Result<M, Error>,
) -> u8 {
    match init() {
        Ok(mut m) => drive(&mut m, c, out),
        Err(e) => {
            let _ = writeln!(out, "init failed: {}", error_name(&e));
            3
        }
    }
}

/// The model of `c` at static equilibrium. A fixed Newton budget applies to the steps: the
/// static solve and the start run with the default budget, as in host-sim (`core_sim`'s
/// converged boot), and the run continues from that state.
fn boot<T: Real, S: Scene, const N: usize, const D: usize>(
    c: &Config,
) -> Result<Model<T, S, N, D>, Error> {
    let p = c.params::<T>();
    if c.budget.is_none() {
        return Model::at_rest(p, T::zero());
    }
    let mut converged = p;
    converged.integrator.max_iterations = Params::<T>::default().integrator.max_iterations;
    converged.integrator.accept_after_budget = false;
    let first = Model::<T, S, N, D>::at_rest(converged, T::zero())?;
    let mut m = Model::new(p)?;
    m.set_state(*first.state());
    Ok(m)
}

macro_rules! variant {
    ($c:expr, $out:expr, $model:ident, $t:ty, $n:literal, $d:literal) => {
        start($c, $out, || {
            boot::<$t, _, $n, $d>($c).map(|m: $model<$t, $n, $d>| m)
        })
    };
}

/// Runs configuration `c`, printing to `out`; the exit code (0: ran, 3: the start failed).
pub fn run<W: Write>(c: &Config, out: &mut W) -> u8 {
    let _ = writeln!(out, "config {c:?}");
    match (c.free, c.f64, c.elements) {
        (true, false, 1) => variant!(c, out, FreeBallModel, f32, 1, 5),
        (true, false, 2) => variant!(c, out, FreeBallModel, f32, 2, 9),
        (true, false, 3) => variant!(c, out, FreeBallModel, f32, 3, 13),
        (true, false, 4) => variant!(c, out, FreeBallModel, f32, 4, 17),
        (true, false, 6) => variant!(c, out, FreeBallModel, f32, 6, 25),
        (true, true, 1) => variant!(c, out, FreeBallModel, f64, 1, 5),
        (true, true, 2) => variant!(c, out, FreeBallModel, f64, 2, 9),
        (true, true, 3) => variant!(c, out, FreeBallModel, f64, 3, 13),
        (true, true, 4) => variant!(c, out, FreeBallModel, f64, 4, 17),
        (true, true, 6) => variant!(c, out, FreeBallModel, f64, 6, 25),
        (false, false, 3) => variant!(c, out, LockedBallModel, f32, 3, 12),
        (false, true, 3) => variant!(c, out, LockedBallModel, f64, 3, 12),
        _ => {
            let _ = writeln!(out, "not built: kind/elements/precision combination");
            4
        }
    }
}
