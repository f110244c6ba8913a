//! The model behind an FMU instance: the core's `Model` of the configured scene (with a tip
//! load: `Loaded<S>`, bit for bit the plain scene while the load is zero, [`Active`]) and its monitor (root
//! stress, rainflow, Miner damage), behind one object-safe trait ([`Sim`]). Scene, element
//! count and scalar are compile-time parameters of the core; [`build`] picks the instantiation
//! at run time, as `host-sim`'s `core_sim` does for the plain scenes.

use crate::config::{Config, Kind};
use absorber_core::monitor::{Monitor, MonitorConfig, ThresholdRule};
use absorber_core::scalar::{lit, to_f64};
use absorber_core::{
    BallParams, BeamOnly, BeamParams, Calibration, Contact, Damping, Error, FreeBall,
    FreeBallNoStops, Integrator, Loaded, Loads, LockedBall, Model, Params, Real, Scene, Side,
    TipMass, TipParams,
};
use core::mem::{size_of, MaybeUninit};

/// The outputs after a step (SI units), in `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs {
    /// Tip deflection relative to the base \[m\].
    pub tip_deflection: f64,
    /// Absolute vertical tip acceleration \[m/s²\].
    pub tip_acceleration: f64,
    /// Root stress \[Pa\].
    pub root_stress: f64,
    /// Ball angle θ \[rad\] (0 without a ball).
    pub ball_angle: f64,
    /// θ − ψ \[rad\] (0 without a ball).
    pub ball_relative_angle: f64,
    /// Normal force of the track on the ball \[N\] (0 without a free ball).
    pub normal_force: f64,
    /// Miner damage \[-\].
    pub damage: f64,
    /// Contact code (0, ±1, 2, 3).
    pub contact: i32,
}

/// A running model and its monitor, of any scene, size and scalar.
pub trait Sim: Send {
    /// One step of h to the base acceleration `base_accel` \[m/s²\] with the tip load
    /// `tip_load` \[N\] at its end; then the monitor records it. On error nothing changed.
    fn step(&mut self, base_accel: f64, tip_load: f64) -> Result<(), Error>;
    /// The outputs now (the damage counts the open rainflow cycles as halves).
    fn outputs(&self) -> Outputs;
    /// Whole steps since the start.
    fn steps(&self) -> u64;
    /// A copy (FMU state).
    fn clone_box(&self) -> Box<dyn Sim>;
    /// Copies `other`'s state into `self` if it is the same model type (FMU state).
    fn restore(&mut self, other: &dyn Sim) -> bool;
    /// Size of the serialized model \[bytes\].
    fn byte_len(&self) -> usize;
    /// Tag of the model's type (part of the serialized state's header).
    fn type_tag(&self) -> u64;
    /// The model's bytes into `out` (of [`Sim::byte_len`] bytes).
    fn write_bytes(&self, out: &mut [u8]) -> bool;
    /// The model from `bytes` written by [`Sim::write_bytes`] of the same type and library.
    ///
    /// # Safety
    /// `bytes` must be the output of `write_bytes` of a model of the same [`Sim::type_tag`]
    /// by this very library build (the serialized FMU state's header says so; see
    /// [`crate::instance`]).
    unsafe fn read_bytes(&mut self, bytes: &[u8]) -> bool;
    /// Down-cast helper for [`Sim::restore`].
    fn as_any(&self) -> &dyn core::any::Any;
}

/// The model of scene `S`: the plain scene while no tip load has been applied, the same bodies
/// with loads (`Loaded<S>`) from the first non-zero tip load on. The two give the same bits
/// with a zero load (the loads add exact zeros), but the plain scene skips the loads' terms
/// in every residual (about 5 % of the step): an FMU driven by the base alone costs what the
/// core's plain step costs.
#[derive(Clone)]
enum Active<T: Real, S: Scene, const N: usize, const D: usize> {
    Plain(Model<T, S, N, D>),
    Loaded(Model<T, Loaded<S>, N, D>),
}

/// The core's model of scene `S` (with a tip load when one is applied) and its monitor.
#[derive(Clone)]
pub struct CoreSim<T: Real, S: Scene, const N: usize, const D: usize> {
    model: Active<T, S, N, D>,
    monitor: Monitor<T>,
    loads: Loads<T, N>,
}

/// `$body` with `$m` bound to the active model, whichever its type.
macro_rules! active {
    ($self:expr, $m:ident => $body:expr) => {
        match &$self.model {
            Active::Plain($m) => $body,
            Active::Loaded($m) => $body,
        }
    };
}

impl<T: Real, S: Scene, const N: usize, const D: usize> CoreSim<T, S, N, D> {
    /// Switches to the loaded scene: a model of `Loaded<S>` with the same parameters, its
    /// static equilibrium solved (the same bits as the plain scene's: zero loads), continuing
    /// from the plain model's state. Kept Newton matrices are rebuilt (with per-step or full
    /// Newton, the default, nothing is kept across steps: the run continues bit for bit).
    fn load(&mut self) -> Result<(), Error> {
        if let Active::Plain(m) = &self.model {
            let mut loaded = Model::<T, Loaded<S>, N, D>::new(*m.params())?;
            loaded.solve_static()?;
            loaded.set_state(*m.state());
            self.model = Active::Loaded(loaded);
        }
        Ok(())
    }
}

fn contact_code(c: Contact) -> i32 {
    match c {
        Contact::Off => 0,
        Contact::OnStop(Side::Positive) => 1,
        Contact::OnStop(Side::Negative) => -1,
        Contact::InFlight => 2,
        Contact::Beyond => 3,
    }
}

impl<T: Real + Send, S: Scene + Send, const N: usize, const D: usize> Sim for CoreSim<T, S, N, D> {
    #[inline]
    fn step(&mut self, base_accel: f64, tip_load: f64) -> Result<(), Error> {
        let a = lit::<T>(base_accel);
        let f = lit::<T>(tip_load);
        if f != T::zero() {
            self.load()?;
        }
        // A non-finite stress is refused by the monitor and counted; the step itself stands.
        match &mut self.model {
            Active::Plain(m) => {
                let report = m.step(a)?;
                let _ = self.monitor.record(m, &report, a);
            }
            Active::Loaded(m) => {
                self.loads.tip_force = f;
                let report = m.step_with_loads(a, &self.loads)?;
                let _ = self.monitor.record(m, &report, a);
            }
        }
        Ok(())
    }

    fn outputs(&self) -> Outputs {
        let z = T::zero();
        active!(self, m => {
            let s = m.state();
            let tip_accel = s.a.get(4 * N - 3).copied().unwrap_or(z) + s.base_accel;
            Outputs {
                tip_deflection: to_f64(m.tip_deflection()),
                tip_acceleration: to_f64(tip_accel),
                root_stress: to_f64(self.monitor.root_stress()),
                ball_angle: to_f64(m.ball_angle().map_or(z, |b| b.0)),
                ball_relative_angle: to_f64(m.ball_relative_angle().map_or(z, |b| b.0)),
                normal_force: to_f64(m.contact_forces().map_or(z, |c| c.normal)),
                damage: to_f64(self.monitor.fatigue().damage),
                contact: contact_code(s.contact),
            }
        })
    }

    fn steps(&self) -> u64 {
        active!(self, m => m.state().steps)
    }

    fn clone_box(&self) -> Box<dyn Sim> {
        Box::new(self.clone())
    }

    fn restore(&mut self, other: &dyn Sim) -> bool {
        match other.as_any().downcast_ref::<Self>() {
            Some(o) => {
                self.clone_from(o);
                true
            }
            None => false,
        }
    }

    fn byte_len(&self) -> usize {
        size_of::<Self>()
    }

    fn type_tag(&self) -> u64 {
        let mut h = crate::config::Fnv::new();
        h.write(core::any::type_name::<Self>().as_bytes());
        h.write(&(size_of::<Self>() as u64).to_le_bytes());
        h.0
    }

    fn write_bytes(&self, out: &mut [u8]) -> bool {
        if out.len() != size_of::<Self>() {
            return false;
        }
        // SAFETY: `self` is valid for `size_of::<Self>()` bytes of reads and `out` for as many
        // writes; they do not overlap. The copy is untyped (padding is copied as it is).
        unsafe {
            core::ptr::copy_nonoverlapping(
                (self as *const Self).cast::<u8>(),
                out.as_mut_ptr(),
                out.len(),
            );
        }
        true
    }

    unsafe fn read_bytes(&mut self, bytes: &[u8]) -> bool {
        if bytes.len() != size_of::<Self>() {
            return false;
        }
        let mut v = MaybeUninit::<Self>::uninit();
        // SAFETY: `bytes` holds `size_of::<Self>()` bytes copied from a valid `Self` of this
        // library build (the caller's guarantee). `Self` is plain data: numbers, arrays and
        // enums, no pointer, reference or heap allocation (the core allocates nothing), so
        // those bytes are a valid `Self` wherever they are.
        unsafe {
            core::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                v.as_mut_ptr().cast::<u8>(),
                bytes.len(),
            );
            *self = v.assume_init();
        }
        true
    }

    fn as_any(&self) -> &dyn core::any::Any {
        self
    }
}

/// The parameters in the model's scalar, each rounded to nearest (as `host-sim` does for
/// `f32` runs: the same bits).
pub fn cast_params<T: Real>(p: &Params<f64>) -> Params<T> {
    let b = &p.ball;
    let i = &p.integrator;
    Params {
        beam: BeamParams {
            length: lit(p.beam.length),
            mass: lit(p.beam.mass),
            area: lit(p.beam.area),
            modulus: lit(p.beam.modulus),
            inertia: lit(p.beam.inertia),
        },
        tip: TipParams {
            mass: lit(p.tip.mass),
            inertia: lit(p.tip.inertia),
            offset: lit(p.tip.offset),
        },
        ball: BallParams {
            mass: lit(b.mass),
            inertia: lit(b.inertia),
            radius: lit(b.radius),
            track_radius: lit(b.track_radius),
            stop_angle: lit(b.stop_angle),
            restitution: lit(b.restitution),
            stick_speed: lit(b.stick_speed),
            initial_angle: lit(b.initial_angle),
            impact_model: b.impact_model,
            flight: b.flight,
            landing_restitution: lit(b.landing_restitution),
            stop_contact_time: lit(b.stop_contact_time),
            min_bounce_time: lit(b.min_bounce_time),
            lift_height: lit(b.lift_height),
        },
        integrator: Integrator {
            gamma: lit(i.gamma),
            beta: lit(i.beta),
            alpha_m: lit(i.alpha_m),
            alpha_f: lit(i.alpha_f),
            step: lit(i.step),
            tolerance: lit(i.tolerance),
            max_iterations: i.max_iterations,
            newton: i.newton,
            accept_after_budget: i.accept_after_budget,
            events: i.events,
            max_work: i.max_work,
            at_cap: i.at_cap,
        },
        damping: Damping {
            stiffness_proportional: lit(p.damping.stiffness_proportional),
        },
        gravity: lit(p.gravity),
        calibration: Calibration {
            bending_stiffness: lit(p.calibration.bending_stiffness),
            axial_stiffness: lit(p.calibration.axial_stiffness),
            mass_lumping: lit(p.calibration.mass_lumping),
            bending_gradient: lit(p.calibration.bending_gradient),
        },
    }
}

fn boxed<T: Real + Send, S: Scene + Send, const N: usize, const D: usize>(
    config: &Config,
    params: &Params<f64>,
    base_accel: f64,
    tip_load: f64,
) -> Result<Box<dyn Sim>, Error> {
    let p = cast_params::<T>(params);
    let loads = Loads::uniform(lit(tip_load), T::zero());
    let mut mc = MonitorConfig::paper(&p)?;
    mc.curve = config.detail.curve(ThresholdRule::Cutoff);
    let (model, monitor) = if loads.tip_force == T::zero() {
        let model = Model::<T, S, N, D>::at_rest(p, lit(base_accel))?;
        let monitor = Monitor::new(mc, &model)?;
        (Active::Plain(model), monitor)
    } else {
        // `Model::at_rest` with the initial tip load held during the static solve.
        let mut model = Model::<T, Loaded<S>, N, D>::new(p)?;
        model.set_loads(&loads)?;
        model.solve_static()?;
        model.restart(lit(base_accel))?;
        let monitor = Monitor::new(mc, &model)?;
        (Active::Loaded(model), monitor)
    };
    Ok(Box::new(CoreSim {
        model,
        monitor,
        loads,
    }))
}

macro_rules! by_elements {
    ($t:ty, $s:ty, $extra:tt, $n:expr, $($arg:expr),*) => {
        match $n {
            1 => boxed::<$t, $s, 1, { 4 + $extra }>($($arg),*),
            2 => boxed::<$t, $s, 2, { 8 + $extra }>($($arg),*),
            3 => boxed::<$t, $s, 3, { 12 + $extra }>($($arg),*),
            4 => boxed::<$t, $s, 4, { 16 + $extra }>($($arg),*),
            6 => boxed::<$t, $s, 6, { 24 + $extra }>($($arg),*),
            8 => boxed::<$t, $s, 8, { 32 + $extra }>($($arg),*),
            16 => boxed::<$t, $s, 16, { 64 + $extra }>($($arg),*),
            _ => Err(Error::InvalidParameter {
                field: "elements",
                reason: "supported: 1, 2, 3, 4, 6, 8, 16",
            }),
        }
    };
}

macro_rules! by_kind {
    ($t:ty, $kind:expr, $n:expr, $($arg:expr),*) => {
        match $kind {
            Kind::Beam => by_elements!($t, BeamOnly, 0, $n, $($arg),*),
            Kind::Tip => by_elements!($t, TipMass, 0, $n, $($arg),*),
            Kind::Locked => by_elements!($t, LockedBall, 0, $n, $($arg),*),
            Kind::Free => by_elements!($t, FreeBall, 1, $n, $($arg),*),
            Kind::FreeNostops => by_elements!($t, FreeBallNoStops, 1, $n, $($arg),*),
        }
    };
}

/// Builds the model of `config` with the parameters `params` (the configuration's, as set by
/// the importer): at rest in its static equilibrium under gravity and the tip load
/// `tip_load` \[N\], with the base acceleration `base_accel` \[m/s²\] at the start. Parameter
/// errors name the field.
pub fn build(
    config: &Config,
    params: &Params<f64>,
    base_accel: f64,
    tip_load: f64,
) -> Result<Box<dyn Sim>, Error> {
    let (k, n) = (config.kind, config.elements);
    if config.single {
        by_kind!(f32, k, n, config, params, base_accel, tip_load)
    } else {
        by_kind!(f64, k, n, config, params, base_accel, tip_load)
    }
}
