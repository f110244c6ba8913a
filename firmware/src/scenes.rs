//! Scenes built on a model: driven in flight, with changed parameters, with a panic planted,
//! and the model-less baseline.

use crate::{firmware_params, spin_start, Setup, Sim, STEP_MS};
use absorber_core::{Error, Model, Params, Scene, StepReport};
use core::mem::MaybeUninit;

/// The same model driven at 4.10 Hz, where the paper's free ball spends about 40 % of the time
/// in flight (docs/model.md, "Contact and flight"): the flight steps' cost.
pub struct InFlight<M>(pub M);

impl<M: Sim> Sim for InFlight<M> {
    fn name() -> &'static str {
        "driven at 4.10 Hz (ball in flight)"
    }

    fn init() -> Result<Self, Error> {
        M::init().map(InFlight)
    }

    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        M::init_in(field!(slot, 0), setup)?;
        // SAFETY: the only field was just initialized.
        Ok(unsafe { slot.assume_init_mut() })
    }

    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        self.0.spin_start(rate)
    }

    fn work_cap(&self) -> u32 {
        self.0.work_cap()
    }

    /// Inlined: the counted function is the wrapped model's `Sim::step`.
    #[inline(always)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        self.0.step(base_accel)
    }

    fn h(&self) -> f32 {
        self.0.h()
    }

    fn tip(&self) -> f32 {
        self.0.tip()
    }

    fn ball(&self) -> f32 {
        self.0.ball()
    }

    fn static_tip(&self) -> f32 {
        self.0.static_tip()
    }

    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.0.state_words(f)
    }

    fn frequency() -> f32 {
        4.10
    }
}

/// A change of [`firmware_params`] that a firmware scene runs with.
pub trait Config {
    /// Scene name as printed.
    const NAME: &'static str;
    /// The scene's work cap (`Integrator::max_work`): the work of the hardest step of its
    /// paper run plus the events' reserve, so that the paper's input is never capped
    /// (`docs/embedded.md`, "Work cap").
    const MAX_WORK: u32 = absorber_core::work::DEADLINE;
    /// Applies the change (the cap is set after it).
    fn apply(p: &mut Params<f32>) {
        let _ = p;
    }
}

/// Modified Newton (`NewtonKind::Modified`: the factored Newton matrix is kept across
/// iterations and steps).
pub struct Modified;

impl Config for Modified {
    const NAME: &'static str = "modified Newton";
    /// Its hardest paper step takes 47 units (five iterations with the kept factors and a
    /// refresh: `absorber_core::shared::KEPT_ITERATIONS`).
    const MAX_WORK: u32 = 49;
    fn apply(p: &mut Params<f32>) {
        p.integrator.newton = absorber_core::NewtonKind::Modified;
    }
}

/// The work cap `W` (units) instead of [`absorber_core::work::DEADLINE`], for a scene
/// whose hardest paper step takes `W − 2`: the beam only and the locked ball (23 units), the
/// free ball on 6 elements (46); and for the ball held on the track, 47 (its hardest paper step
/// converges in 41 units instead of 46, with the factors in hand: `fw-free-rolling`).
pub struct Cap<const W: u32>;

impl<const W: u32> Config for Cap<W> {
    const NAME: &'static str = "work cap";
    const MAX_WORK: u32 = W;
}

/// The model with [`firmware_params`] changed by `C`.
pub struct Configured<M, C>(pub M, core::marker::PhantomData<C>);

/// The model stepped with modified Newton, otherwise [`firmware_params`].
pub type ModifiedNewton<M> = Configured<M, Modified>;

impl<S: Scene, const N: usize, const D: usize, C: Config> Sim
    for Configured<Model<f32, S, N, D>, C>
{
    fn name() -> &'static str {
        C::NAME
    }

    fn init() -> Result<Self, Error> {
        let mut p = firmware_params(&Setup::default());
        C::apply(&mut p);
        p.integrator.max_work = C::MAX_WORK;
        Model::at_rest(p, 0.0).map(|m| Configured(m, core::marker::PhantomData))
    }

    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        let mut p = firmware_params(setup);
        C::apply(&mut p);
        p.integrator.max_work = C::MAX_WORK;
        Model::<f32, S, N, D>::at_rest_in(field!(slot, 0), p, 0.0)?;
        // SAFETY: the model was just initialized; the other field is a zero-sized marker.
        Ok(unsafe { slot.assume_init_mut() })
    }

    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        spin_start(&mut self.0, rate)
    }

    fn work_cap(&self) -> u32 {
        self.0.work_cap()
    }

    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        Model::step(&mut self.0, base_accel)
    }

    fn h(&self) -> f32 {
        self.0.h()
    }

    fn tip(&self) -> f32 {
        self.0.tip()
    }

    fn ball(&self) -> f32 {
        self.0.ball()
    }

    fn static_tip(&self) -> f32 {
        self.0.static_tip()
    }

    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.0.state_words(f)
    }
}

/// A model whose `step` can panic (`fw-planted`, never run): the panic check of
/// `scripts/embedded-report.py` must find the planted path, or it proves nothing.
pub struct Planted<M>(pub M);

impl<M: Sim> Sim for Planted<M> {
    fn name() -> &'static str {
        "planted panic"
    }

    fn init() -> Result<Self, Error> {
        M::init().map(Planted)
    }

    /// The wrapped step, then a panic on one input bit pattern (the optimizer cannot remove it).
    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        let r = self.0.step(base_accel)?;
        if base_accel.to_bits() == 0x4049_0fdb {
            panic!("planted");
        }
        Ok(r)
    }

    fn h(&self) -> f32 {
        self.0.h()
    }

    fn tip(&self) -> f32 {
        self.0.tip()
    }

    fn ball(&self) -> f32 {
        self.0.ball()
    }

    fn static_tip(&self) -> f32 {
        self.0.static_tip()
    }

    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.0.state_words(f)
    }
}

/// No model at all: the same driver, printing and hashing, for the flash/RAM baseline.
pub struct Empty {
    last: f32,
}

impl Sim for Empty {
    fn name() -> &'static str {
        "empty"
    }

    fn init() -> Result<Self, Error> {
        Ok(Empty { last: 0.0 })
    }

    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        self.last = base_accel;
        Ok(StepReport {
            iterations: 1,
            increment: 0.0,
            impact: None,
            separation: None,
            landing: None,
            work: 0,
            outcome: absorber_core::Outcome::Converged,
            // (The step report counts its events since the flight/stop changes: none here.)
            events: Default::default(),
        })
    }

    fn h(&self) -> f32 {
        STEP_MS as f32 * 1e-3
    }

    fn tip(&self) -> f32 {
        self.last
    }

    fn ball(&self) -> f32 {
        0.0
    }

    fn static_tip(&self) -> f32 {
        0.0
    }

    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        f(self.last.to_bits());
    }
}
