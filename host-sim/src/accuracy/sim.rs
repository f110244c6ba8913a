//! The embedded core behind [`Simulator`] for the accuracy candidates. It differs from
//! `core_sim` in one respect: a fixed Newton budget cannot run the static solve of `at_rest`
//! (that solve obeys `max_iterations` but never accepts the budget), so such a model boots with
//! the converged solver and keeps that static deflection apart ([`EmbeddedSim::static_tip`]).

use super::Body;
use crate::sim::{Observation, Simulator};
use absorber_core::{
    scalar::{lit, to_f64},
    Energies, Error, FreeBall, Impact, LockedBall, Model, Params, Real, Scene, StepReport,
};

/// The core model of one scene, size and scalar behind [`Simulator`].
pub struct EmbeddedSim<T: Real, S: Scene, const N: usize, const D: usize> {
    /// The model.
    pub model: Model<T, S, N, D>,
    /// Static tip deflection \[m\] (kept apart: see [`build_embedded`] on fixed budgets).
    pub static_tip: f64,
}

impl<T: Real + Send, S: Scene + Send, const N: usize, const D: usize> Simulator
    for EmbeddedSim<T, S, N, D>
{
    fn step(&mut self, base_accel: f64) -> Result<StepReport<f64>, Error> {
        let r = self.model.step(lit(base_accel))?;
        Ok(StepReport {
            iterations: r.iterations,
            increment: to_f64(r.increment),
            impact: r.impact.map(|i| Impact {
                time: to_f64(i.time),
                side: i.side,
                relative_speed: to_f64(i.relative_speed),
                impulse: to_f64(i.impulse),
                energy_loss: to_f64(i.energy_loss),
                stuck: i.stuck,
            }),
        })
    }

    fn observe(&self) -> Observation {
        let m = &self.model;
        let (psi, psi_dot) = m.tip_angle();
        let (th, thd) = m
            .ball_angle()
            .map(|(a, b)| (to_f64(a), to_f64(b)))
            .unwrap_or((f64::NAN, f64::NAN));
        let (al, ald) = m
            .ball_relative_angle()
            .map(|(a, b)| (to_f64(a), to_f64(b)))
            .unwrap_or((f64::NAN, f64::NAN));
        Observation {
            time: to_f64(m.time()),
            tip_deflection: to_f64(m.tip_deflection()),
            tip_velocity: to_f64(m.tip_velocity()),
            tip_angle: to_f64(psi),
            tip_rate: to_f64(psi_dot),
            ball_angle: th,
            ball_rate: thd,
            ball_relative_angle: al,
            ball_relative_rate: ald,
        }
    }

    fn energies(&self, base_velocity: f64, base_displacement: f64) -> Energies<f64> {
        let e = self
            .model
            .energies(lit(base_velocity), lit(base_displacement));
        Energies {
            beam_strain: to_f64(e.beam_strain),
            beam_kinetic: to_f64(e.beam_kinetic),
            beam_potential: to_f64(e.beam_potential),
            tip_kinetic: to_f64(e.tip_kinetic),
            tip_potential: to_f64(e.tip_potential),
            ball_kinetic: to_f64(e.ball_kinetic),
            ball_potential: to_f64(e.ball_potential),
        }
    }

    fn natural_frequencies(&self) -> Result<Vec<f64>, Error> {
        Ok(self
            .model
            .natural_frequencies()?
            .iter()
            .map(|&f| to_f64(f))
            .collect())
    }

    fn static_tip_deflection(&self) -> f64 {
        self.static_tip
    }

    fn solver_name(&self) -> &'static str {
        "core"
    }
}

/// Every field converted to `f32` (integrator included): `core_sim`'s conversion.
pub use crate::core_sim::params_f32;

fn boxed<T: Real + Send, S: Scene + Send, const N: usize, const D: usize>(
    params: Params<T>,
    a0: T,
) -> Result<Box<dyn Simulator>, Error> {
    if !params.integrator.accept_after_budget {
        let model = Model::<T, S, N, D>::at_rest(params, a0)?;
        let static_tip = to_f64(model.static_tip_deflection());
        return Ok(Box::new(EmbeddedSim { model, static_tip }));
    }
    // The static and consistent-acceleration solves of `at_rest` obey `max_iterations` too but
    // never accept the budget: a budget of 1–3 fails there. Boot with the converged solver (as
    // firmware would, once), then continue from that state with the budget.
    let mut boot = params;
    boot.integrator.max_iterations = 100;
    boot.integrator.accept_after_budget = false;
    let first = Model::<T, S, N, D>::at_rest(boot, a0)?;
    let mut model = Model::<T, S, N, D>::new(params)?;
    model.set_state(*first.state());
    Ok(Box::new(EmbeddedSim {
        model,
        static_tip: to_f64(first.static_tip_deflection()),
    }))
}

macro_rules! by_n {
    ($t:ty, $s:ty, $extra:literal, $n:expr, $p:expr, $a:expr) => {
        match $n {
            1 => boxed::<$t, $s, 1, { 4 + $extra }>($p, $a),
            2 => boxed::<$t, $s, 2, { 8 + $extra }>($p, $a),
            3 => boxed::<$t, $s, 3, { 12 + $extra }>($p, $a),
            4 => boxed::<$t, $s, 4, { 16 + $extra }>($p, $a),
            6 => boxed::<$t, $s, 6, { 24 + $extra }>($p, $a),
            8 => boxed::<$t, $s, 8, { 32 + $extra }>($p, $a),
            _ => Err(Error::InvalidParameter {
                field: "elements",
                reason: "accuracy candidates: 1, 2, 3, 4, 6, 8",
            }),
        }
    };
}

/// The embedded core for `body` with `n` elements in `f32` or `f64`, at rest with input `a0`.
/// With a fixed Newton budget (`accept_after_budget`) the static start is solved with the
/// default budget first (its solves never accept a budget), and the model continues from that
/// state; its `equilibrium()` (energies, `natural_frequencies`) is then not set.
pub fn build_embedded(
    body: Body,
    n: usize,
    f32: bool,
    params: &Params<f64>,
    a0: f64,
) -> Result<Box<dyn Simulator>, Error> {
    match (f32, body) {
        (true, Body::Free) => by_n!(f32, FreeBall, 1, n, params_f32(params), a0 as f32),
        (true, Body::Locked) => by_n!(f32, LockedBall, 0, n, params_f32(params), a0 as f32),
        (false, Body::Free) => by_n!(f64, FreeBall, 1, n, *params, a0),
        (false, Body::Locked) => by_n!(f64, LockedBall, 0, n, *params, a0),
    }
}
