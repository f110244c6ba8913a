//! On-device monitoring: root stress, streaming rainflow fatigue damage, impact log and
//! absorber effectiveness — no heap, memory fixed at compile time, bounded work per sample.
//!
//! Feed the monitor after every step of the model; read its figures whenever you like:
//!
//! ```
//! use absorber_core::monitor::{Monitor, MonitorConfig};
//! use absorber_core::{FreeBallModel, LockedBallModel, Params};
//!
//! let p = Params::<f32>::default();
//! let mut model: FreeBallModel<f32, 3, 13> = FreeBallModel::at_rest(p, 0.0)?;
//! // Without a twin: `Monitor<f32>`; with a locked-ball twin for the effectiveness figure:
//! let twin: LockedBallModel<f32, 3, 12> = LockedBallModel::at_rest(p, 0.0)?;
//! let mut monitor: Monitor<f32, _> = Monitor::with_twin(MonitorConfig::paper(&p)?, &model, twin)?;
//! let w = 2.0 * core::f32::consts::PI * 3.7;
//! for k in 1..=400 {
//!     let base_accel = -0.5e-3 * w * w * (w * k as f32 * 0.003).sin();
//!     let report = model.step(base_accel)?;
//!     monitor.record(&model, &report, base_accel)?;
//! }
//! let fatigue = monitor.fatigue(); // Miner damage, S_eq [Pa], cycles, incl. the residue
//! let view = monitor.indicators(); // RMS / peak tip [m], ball RMS [rad], energies [J], ratio
//! assert!(fatigue.cycles > 0.0 && view.effectiveness.is_some());
//! # Ok::<(), absorber_core::Error>(())
//! ```
//!
//! Parts (one module each): [`stress`] (root moment and stress from the ANCF curvature),
//! [`rainflow`] (ASTM E1049 counting with a fixed residue), [`fatigue`] (AASHTO S–N curves,
//! Miner's rule), [`impacts`] (ring of the last stop impacts), [`indicators`] (windowed RMS,
//! peak, energies, effectiveness). `docs/monitoring.md` explains every output.
//!
//! **Memory** is `size_of::<Monitor<T, Twin, CAP, K, W>>()`, a compile-time constant: `CAP`
//! residue points, `K` impact records, `W` window blocks, plus the twin model if there is one.
//! With the defaults (`CAP = 128, K = 16, W = 256`) and `f32` it is 7.2 kB without a twin
//! (printed by `tests/monitor_model.rs`). `CAP = 128` holds the converging residue a start-up
//! transient leaves (about 65 points in the paper scene at 3.70 Hz, see [`rainflow`]).
//! **Work per sample**: one root moment (row r₂′ of element 0's residual for the reaction
//! estimate, axial force without its tangent), the turning-point test, amortized O(1) rainflow
//! rules (a closed cycle costs one `powf`), one energy evaluation (the static strain energy and
//! heights are kept from the start; ψ by `atan2` with cos ψ, sin ψ from the end slope, one
//! `sin_cos` of θ, and α from the same angles), O(1) window update; plus one step of the twin if
//! present. No panic path: the residue and the window are written through checked accesses.
//! Residue and window reads are O(CAP) and O(W).

pub mod fatigue;
pub mod impacts;
pub mod indicators;
pub mod rainflow;
pub mod stress;

pub use fatigue::{DetailCategory, FatigueSummary, Miner, SnCurve, StressDamage, ThresholdRule};
pub use impacts::ImpactLog;
pub use indicators::{IndicatorValues, Indicators, Sample, TwinTip, TwinValue};
pub use rainflow::{Cycle, Rainflow, TurningPoints};
pub use stress::{
    root_curvature, root_curvature_of, root_reaction_moment, static_root_moment, MomentEstimate,
    RootSection,
};

use crate::energy::Heights;
use crate::error::Error;
use crate::model::Model;
use crate::params::Params;
use crate::scalar::{lit, Real};
use crate::scene::{LockedBall, Scene};
use crate::state::StepReport;

/// A model advanced beside the monitored one on the same input, for comparison.
pub trait Twin<T: Real> {
    /// What the twin adds to each window block (`()` for [`NoTwin`]).
    type Value: TwinValue<T>;
    /// Advances the twin by one step with the same base acceleration \[m/s²\].
    fn advance(&mut self, base_accel: T) -> Result<(), Error>;
    /// The twin's tip deflection about its static value \[m\].
    fn tip(&self) -> Self::Value;
}

/// No twin: zero-sized, adds nothing to the window and no work per sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoTwin;

impl<T: Real> Twin<T> for NoTwin {
    type Value = ();
    fn advance(&mut self, _: T) -> Result<(), Error> {
        Ok(())
    }
    fn tip(&self) {}
}

/// The locked-ball model (the paper's passive absorber) as the twin.
impl<T: Real, const N: usize, const D: usize> Twin<T> for Model<T, LockedBall, N, D> {
    type Value = TwinTip<T>;
    fn advance(&mut self, base_accel: T) -> Result<(), Error> {
        self.step(base_accel).map(|_| ())
    }
    fn tip(&self) -> TwinTip<T> {
        TwinTip(self.tip_deflection() - self.static_tip_deflection())
    }
}

/// What a monitor takes from `model` at its start (its first sample): the root stress of the
/// state and of the static equilibrium (`config`'s section and moment estimate, checked
/// finite), the equilibrium's strain energy and heights, the time and whether the ball flies.
struct Start<T> {
    stress: T,
    static_stress: T,
    static_strain: T,
    static_heights: Heights<T>,
    time: T,
    in_flight: bool,
}

impl<T: Real> Start<T> {
    fn of<S: Scene, const N: usize, const D: usize>(
        config: &MonitorConfig<T>,
        model: &Model<T, S, N, D>,
    ) -> Result<Self, Error> {
        let section = config.section;
        let estimate = config.moment;
        let stress = section.stress_of_moment(section.root_moment(model, estimate));
        let static_moment = match estimate {
            MomentEstimate::Reaction => static_root_moment(model),
            MomentEstimate::Curvature => {
                section.moment(root_curvature_of(model, model.equilibrium()))
            }
        };
        let static_stress = section.stress_of_moment(static_moment);
        if !stress.is_finite() || !static_stress.is_finite() {
            return Err(Error::NonFiniteState);
        }
        Ok(Self {
            stress,
            static_stress,
            static_strain: model.strain_energy_of(model.equilibrium()),
            static_heights: model.equilibrium_heights(),
            time: model.time(),
            in_flight: model.in_flight(),
        })
    }
}

/// Monitor settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonitorConfig<T> {
    /// Section at the clamp (moment → stress).
    pub section: RootSection<T>,
    /// How the root moment is obtained.
    pub moment: MomentEstimate,
    /// S–N curve for Miner's rule.
    pub curve: SnCurve<T>,
    /// Rainflow hysteresis gate \[Pa\]: reversals of at most this are ignored (0 = none).
    pub gate: T,
    /// Samples per window block (≥ 1); the window covers `W · block` samples.
    pub block: u16,
}

impl<T: Real> MonitorConfig<T> {
    /// Defaults for a scene: the rectangle implied by the beam's a and I
    /// ([`RootSection::rectangle`]), the clamp-reaction moment, AASHTO category E′ (fillet-welded mast-arm socket) with the
    /// CAFT cutoff, no gate, blocks of 8 samples.
    pub fn paper(params: &Params<T>) -> Result<Self, Error> {
        Ok(Self {
            section: RootSection::rectangle(&params.beam)?,
            moment: MomentEstimate::Reaction,
            curve: DetailCategory::EPrime.curve(ThresholdRule::Cutoff),
            gate: T::zero(),
            block: 8,
        })
    }
}

/// The monitor. `Tw` = [`NoTwin`] (default, costs nothing) or a
/// [`LockedBallModel`](crate::LockedBallModel) advanced beside the monitored model;
/// `CAP` = rainflow residue capacity (≥ 5), `K` = impacts kept, `W` = window blocks.
#[derive(Clone, Debug)]
pub struct Monitor<
    T: Real,
    Tw: Twin<T> = NoTwin,
    const CAP: usize = 128,
    const K: usize = 16,
    const W: usize = 256,
> {
    section: RootSection<T>,
    estimate: MomentEstimate,
    rainflow: Rainflow<T, CAP>,
    miner: Miner<T>,
    impacts: ImpactLog<T, K>,
    window: Indicators<T, Tw::Value, W>,
    twin: Tw,
    /// Constant for the run, kept so that `record` does not recompute them: the strain energy
    /// and the heights of the static equilibrium.
    static_strain: T,
    static_heights: Heights<T>,
    static_stress: T,
    stress: T,
    start_time: T,
    time: T,
    samples: u64,
    rejected: u32,
    twin_failures: u32,
    flight: FlightLog<T>,
}

/// What the ball's contact did (free-ball scenes; `step::flight`): samples in flight,
/// separations, landings and bounces, and the largest friction coefficient rolling needed, on
/// the track (`|F_t|/N`, off the stops) and in a rolling landing (`|P_t|/P_n`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlightLog<T> {
    /// Samples recorded with the ball in flight.
    pub samples_in_flight: u64,
    /// Times the ball left the track.
    pub separations: u32,
    /// Landings (bounces included).
    pub landings: u32,
    /// Landings after which the ball flew on.
    pub bounces: u32,
    /// Largest `|F_t|/N` of a rolling ball off the stops \[-\].
    pub peak_rolling_friction: T,
    /// Largest `|P_t|/P_n` of a landing after which the ball rolls \[-\].
    pub peak_landing_friction: T,
}

impl<T: Real, const CAP: usize, const K: usize, const W: usize> Monitor<T, NoTwin, CAP, K, W> {
    /// Monitor of `model` without a twin; the model's current state is the first sample.
    pub fn new<S: Scene, const N: usize, const D: usize>(
        config: MonitorConfig<T>,
        model: &Model<T, S, N, D>,
    ) -> Result<Self, Error> {
        Self::with_twin(config, model, NoTwin)
    }

    /// [`Monitor::new`] into caller storage ([`Monitor::with_twin_in`]).
    pub fn new_in<'a, S: Scene, const N: usize, const D: usize>(
        slot: &'a mut core::mem::MaybeUninit<Self>,
        config: MonitorConfig<T>,
        model: &Model<T, S, N, D>,
    ) -> Result<&'a mut Self, Error> {
        Self::with_twin_in(slot, config, model, NoTwin)
    }
}

impl<T: Real, Tw: Twin<T>, const CAP: usize, const K: usize, const W: usize>
    Monitor<T, Tw, CAP, K, W>
{
    /// Monitor of `model` with `twin` (which must start in the same state of the same input).
    pub fn with_twin<S: Scene, const N: usize, const D: usize>(
        config: MonitorConfig<T>,
        model: &Model<T, S, N, D>,
        twin: Tw,
    ) -> Result<Self, Error> {
        let start = Start::of(&config, model)?;
        let stress = start.stress;
        let counters = (Rainflow::new(config.gate)?, Miner::new(config.curve)?);
        let mut m = Self::fresh(&config, twin, counters, start);
        m.first_sample(stress)?;
        Ok(m)
    }

    /// [`Monitor::with_twin`] into caller storage: no monitor passes through the stack (its
    /// window alone is `W` blocks; a firmware keeps it in a `static`, `docs/embedded.md`, boot
    /// RAM). The twin is moved in. On error `slot` holds nothing usable: use only the returned
    /// reference.
    pub fn with_twin_in<'a, S: Scene, const N: usize, const D: usize>(
        slot: &'a mut core::mem::MaybeUninit<Self>,
        config: MonitorConfig<T>,
        model: &Model<T, S, N, D>,
        twin: Tw,
    ) -> Result<&'a mut Self, Error> {
        let start = Start::of(&config, model)?;
        let stress = start.stress;
        let counters = (Rainflow::new(config.gate)?, Miner::new(config.curve)?);
        let m = slot.write(Self::fresh(&config, twin, counters, start));
        m.first_sample(stress)?;
        Ok(m)
    }

    /// The monitor before its first sample, from its checked counters: a value expression,
    /// inlined so that it is written straight into its destination.
    #[inline(always)]
    fn fresh(
        config: &MonitorConfig<T>,
        twin: Tw,
        (rainflow, miner): (Rainflow<T, CAP>, Miner<T>),
        start: Start<T>,
    ) -> Self {
        Self {
            section: config.section,
            estimate: config.moment,
            rainflow,
            miner,
            impacts: ImpactLog::new(),
            window: Indicators::new(config.block),
            twin,
            static_strain: start.static_strain,
            static_heights: start.static_heights,
            static_stress: start.static_stress,
            stress: start.stress,
            start_time: start.time,
            time: start.time,
            samples: 1,
            rejected: 0,
            twin_failures: 0,
            flight: FlightLog {
                samples_in_flight: u64::from(start.in_flight),
                separations: 0,
                landings: 0,
                bounces: 0,
                peak_rolling_friction: T::zero(),
                peak_landing_friction: T::zero(),
            },
        }
    }

    /// The model's state as the first sample: its stress into the rainflow count.
    fn first_sample(&mut self, stress: T) -> Result<(), Error> {
        let miner = &mut self.miner;
        self.rainflow.push(stress, &mut |c| miner.add(&c))
    }

    /// Records the model's state after a step: `report` is what [`Model::step`] returned and
    /// `base_accel` its input (passed on to the twin). Returns the root stress \[Pa\].
    ///
    /// A non-finite stress is rejected ([`Error::NonFiniteState`]) and nothing is recorded. A
    /// failing twin step is counted ([`Monitor::twin_failures`]), the twin keeps its state.
    pub fn record<S: Scene, const N: usize, const D: usize>(
        &mut self,
        model: &Model<T, S, N, D>,
        report: &StepReport<T>,
        base_accel: T,
    ) -> Result<T, Error> {
        let stress = self
            .section
            .stress_of_moment(self.section.root_moment(model, self.estimate));
        if !stress.is_finite() {
            self.rejected = self.rejected.saturating_add(1);
            return Err(Error::NonFiniteState);
        }
        let miner = &mut self.miner;
        self.rainflow.push(stress, &mut |c| miner.add(&c))?;
        self.stress = stress;
        self.time = model.time();
        self.samples += 1;
        self.impacts.record_step(report);
        self.record_contact(model, report);
        if self.twin.advance(base_accel).is_err() {
            self.twin_failures = self.twin_failures.saturating_add(1);
        }
        let z = T::zero();
        // `Model::energies` with the static heights kept, and the angles it used for α.
        let (e, angles) = model.energies_about(&self.static_heights, z, z);
        self.window.push(Sample {
            tip: model.tip_deflection() - model.static_tip_deflection(),
            ball: angles.ball_relative().map(|(a, _)| a).unwrap_or(z),
            beam_energy: e.beam_strain - self.static_strain + e.beam_kinetic + e.beam_potential,
            ball_energy: e.ball_kinetic + e.ball_potential,
            twin: self.twin.tip(),
        });
        Ok(stress)
    }

    /// The ball's contact in this sample ([`FlightLog`]).
    fn record_contact<S: Scene, const N: usize, const D: usize>(
        &mut self,
        model: &Model<T, S, N, D>,
        report: &StepReport<T>,
    ) {
        // Every event of the step (a coarse step can hold several of a kind; the report keeps
        // the last landing's record).
        let f = &mut self.flight;
        let e = &report.events;
        f.separations = f.separations.saturating_add(u32::from(e.separations));
        f.landings = f.landings.saturating_add(u32::from(e.landings));
        f.bounces = f.bounces.saturating_add(u32::from(e.bounces));
        if let Some(l) = &report.landing {
            if let (false, Some(mu)) = (l.bounced, l.required_friction()) {
                f.peak_landing_friction = f.peak_landing_friction.max(mu);
            }
        }
        if model.in_flight() {
            f.samples_in_flight = f.samples_in_flight.saturating_add(1);
        } else if matches!(
            model.state().contact,
            crate::Contact::Off | crate::Contact::Beyond
        ) {
            if let Some(mu) = model.contact_forces().and_then(|c| c.required_friction()) {
                f.peak_rolling_friction = f.peak_rolling_friction.max(mu);
            }
        }
    }

    /// The ball's contact so far ([`FlightLog`]).
    pub fn flight(&self) -> &FlightLog<T> {
        &self.flight
    }

    /// Fraction of the recorded samples with the ball in flight \[-\].
    pub fn flight_fraction(&self) -> T {
        if self.samples == 0 {
            return T::zero();
        }
        T::from_count(self.flight.samples_in_flight) / T::from_count(self.samples)
    }

    /// Root stress of the last sample (top fibre, tension positive) \[Pa\].
    pub fn root_stress(&self) -> T {
        self.stress
    }

    /// Root stress of the static equilibrium \[Pa\].
    pub fn static_root_stress(&self) -> T {
        self.static_stress
    }

    /// Root bending moment of the last sample (sagging positive) \[N·m\].
    pub fn root_moment(&self) -> T {
        -self.stress * self.section.bending_rigidity / self.section.stress_per_curvature
    }

    /// Fatigue so far, the residue counted as half cycles (as if the history ended now).
    pub fn fatigue(&self) -> FatigueSummary<T> {
        self.miner.with_residue(&self.rainflow).summary()
    }

    /// Fatigue of the closed cycles only (the residue left out: a lower bound).
    pub fn fatigue_closed(&self) -> FatigueSummary<T> {
        self.miner.summary()
    }

    /// Miner damage per hour of monitored time, residue included \[1/h\].
    pub fn damage_rate_per_hour(&self) -> T {
        let t = self.elapsed();
        if t > T::zero() {
            self.fatigue().damage * lit::<T>(3600.0) / t
        } else {
            T::zero()
        }
    }

    /// The running Miner accumulator (closed cycles).
    pub fn miner(&self) -> &Miner<T> {
        &self.miner
    }

    /// The rainflow counter.
    pub fn rainflow(&self) -> &Rainflow<T, CAP> {
        &self.rainflow
    }

    /// The impact log.
    pub fn impacts(&self) -> &ImpactLog<T, K> {
        &self.impacts
    }

    /// Window indicators (O(W)).
    pub fn indicators(&self) -> IndicatorValues<T> {
        self.window.values()
    }

    /// The twin.
    pub fn twin(&self) -> &Tw {
        &self.twin
    }

    /// Monitored time \[s\].
    pub fn elapsed(&self) -> T {
        self.time - self.start_time
    }

    /// Samples recorded (the initial state included).
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Samples rejected as non-finite.
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// Twin steps that failed.
    pub fn twin_failures(&self) -> u32 {
        self.twin_failures
    }
}
