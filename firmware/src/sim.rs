//! The driver's face of a scene ([`Sim`]) and its implementation for a bare core model.

use crate::{firmware_params, Setup, FREQUENCY_HZ};
use absorber_core::{Error, Model, Scene, StepReport};
use core::fmt::Write;
use core::mem::MaybeUninit;

/// What the driver needs from a scene.
pub trait Sim: Sized {
    /// Scene name as printed.
    fn name() -> &'static str;
    /// Builds the scene at static equilibrium, at rest, input 0 (by value).
    fn init() -> Result<Self, Error>;
    /// Builds the scene for `setup` into `slot` (a `static` on the target), in place where the
    /// scene can: its boot then needs no copy of it on the stack (`docs/embedded.md`, boot RAM).
    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        let _ = setup;
        Ok(slot.write(Self::init()?))
    }
    /// Throws the ball along its track at the relative angular speed `rate` \[rad/s\] (a
    /// stress scene's start; nothing without a free ball).
    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        let _ = rate;
        Ok(())
    }
    /// Advances what the sensors measure to the new base acceleration, before [`Sim::step`]
    /// (a scene whose sample reads a simulated structure: the test harness, not counted).
    fn environment(&mut self, base_accel: f32) {
        let _ = base_accel;
    }
    /// One model step to the new base acceleration. Never inlined: its instructions are counted.
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error>;
    /// Time step h \[s\].
    fn h(&self) -> f32;
    /// Tip deflection \[m\].
    fn tip(&self) -> f32;
    /// Ball angle relative to the housing \[rad\] (0 without a free ball).
    fn ball(&self) -> f32;
    /// Static tip deflection \[m\].
    fn static_tip(&self) -> f32;
    /// Feeds every word of the dynamic state to `f`.
    fn state_words(&self, f: &mut dyn FnMut(u32));
    /// Extra figures printed at every whole second, each also fed to `f` (none by default).
    fn second(&self, _out: &mut dyn Write, _f: &mut dyn FnMut(u32)) {}
    /// The scene's work cap per step (`Integrator::max_work`, work units), printed with the
    /// units' weights for the static work bound (`scripts/embedded-report.py`); 0 if unknown.
    fn work_cap(&self) -> u32 {
        0
    }
    /// Excitation frequency \[Hz\] ([`FREQUENCY_HZ`] unless a scene drives at another).
    fn frequency() -> f32 {
        FREQUENCY_HZ
    }
}

impl<S: Scene, const N: usize, const D: usize> Sim for Model<f32, S, N, D> {
    fn name() -> &'static str {
        core::any::type_name::<S>()
    }

    fn init() -> Result<Self, Error> {
        Model::at_rest(firmware_params(&Setup::default()), 0.0)
    }

    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        Model::at_rest_in(slot, firmware_params(setup), 0.0)
    }

    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        spin_start(self, rate)
    }

    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        Model::step(self, base_accel)
    }

    fn h(&self) -> f32 {
        self.params().integrator.step
    }

    fn work_cap(&self) -> u32 {
        self.params().integrator.max_work
    }

    fn tip(&self) -> f32 {
        self.tip_deflection()
    }

    fn ball(&self) -> f32 {
        self.ball_relative_angle().map_or(0.0, |(a, _)| a)
    }

    fn static_tip(&self) -> f32 {
        self.static_tip_deflection()
    }

    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        let s = self.state();
        for x in s.q.iter().chain(s.v.iter()).chain(s.a.iter()) {
            f(x.to_bits());
        }
        f(s.time.to_bits());
        f(s.base_accel.to_bits());
        f(match s.contact {
            absorber_core::Contact::Off => 0,
            absorber_core::Contact::OnStop(absorber_core::Side::Positive) => 1,
            absorber_core::Contact::OnStop(absorber_core::Side::Negative) => 2,
            absorber_core::Contact::InFlight => 3,
            absorber_core::Contact::Beyond => 4,
        });
        if s.contact == absorber_core::Contact::InFlight {
            let fl = &s.flight;
            for x in fl.centre.iter().chain(fl.velocity.iter()) {
                f(x.to_bits());
            }
        }
    }
}

/// Throws the free ball of `m` along its track at the relative angular speed `rate` \[rad/s\]
/// from its current configuration (φ̇ = −(ρ/r_b) α̇ with the housing at rest).
pub(crate) fn spin_start<S: Scene, const N: usize, const D: usize>(
    m: &mut Model<f32, S, N, D>,
    rate: f32,
) -> Result<(), Error> {
    if D != 4 * N + 1 {
        return Ok(());
    }
    let b = &m.params().ball;
    let mut v = m.state().v;
    v[4 * N] = -rate * b.path_radius() / b.radius;
    let q = m.state().q;
    m.set_configuration(q, v, 0.0)
}
