//! `fw-monitor-loop`: the pole monitor's whole sample on the paper's absorber (free ball with
//! stops and flight, N = 3, f32, [`crate::firmware_params`]: events at the step end; the work
//! cap [`MAX_WORK`]): sensor read → extended Kalman filter step (`absorber_core::estimator::Ekf::update`:
//! the model's own step under the predicted tip load, then the correction) → monitor record
//! (`Monitor::record` on the corrected model: root stress, rainflow, Miner damage, impact log,
//! window indicators). [`Sim::step`] is that sample, counted whole.
//!
//! **What the sensor reads.** A pole under the paper's base input (0.5 mm at 4.13 Hz, or a
//! stress scene's): the same core model, run beside the monitor with every event at its
//! crossing (the host's default; the monitor's model puts them at the step end, so the two
//! drift apart and the filter has something to correct), advanced by [`Sim::environment`]
//! before the sample (test harness, not the firmware's work: not counted). Its absolute tip
//! acceleration plus a tip accelerometer's 20 mg bias and white noise (ADXL355 class:
//! 25 µg/√Hz over a quarter of the sample rate, 2.2 mm/s² sd; xorshift, the same on every
//! target), saturated at ±2 g, is the reading: the sensor read of the sample.
//!
//! **The filter** carries the three lowest modes (`X = 2·3 + 6` for Newmark), the tip load as a
//! critically damped process at the first bending mode's frequency (0.05 N sd: the lab
//! scene's forcing; the paper's input has none), the accelerometer's bias (known to 3 sd of one
//! reading at rest from the zero calibration), a model error of 1 % of the reading's RMS (the
//! lab arm's measured 0.9–1.0 %), Huber's bound at 3 sd and a 1 s health window: the settings
//! `host-sim estimate --lab` uses (`docs/monitoring.md`, "Noise model"), without the site's
//! measured load history and stress factors (1).

use crate::{monitor_record, Setup, Sim, WithMonitor};
use absorber_core::estimator::{
    Ekf, EkfConfig, HealthConfig, ModalBasis, Readings, Sensor, SensorKind, SensorSet, AUGMENTED,
};
use absorber_core::monitor::stress::RootSection;
use absorber_core::work;
use absorber_core::{Error, EventLocation, FreeBall, Lean, Loaded, Model, Params, StepReport};
use core::fmt::Write;
use core::mem::MaybeUninit;

/// Elements and unknowns of the model.
const N: usize = 3;
const D: usize = 4 * N + 1;
/// Modes the filter carries, and its coordinates (Newmark).
const MODES: usize = 3;
const X: usize = 2 * MODES + AUGMENTED;

/// The scene of the monitor's model (the filter needs its tip load): the free ball without
/// the code of the run-time options this bin never takes ([`Lean`]: no perfectly elastic
/// rules; its runs are those of `Loaded<FreeBall>`, bit for bit).
type Scene = Loaded<Lean<FreeBall>>;
type Pole = Model<f32, Scene, N, D>;
/// The filter.
type Filter = Ekf<f32, Scene, N, D, MODES, X>;

/// Tip accelerometer: white noise sd \[m/s²\] (25 µg/√Hz over 83 Hz), bias \[m/s²\] (20 mg),
/// range \[m/s²\] (2 g).
const NOISE: f32 = 2.24e-3;
const BIAS: f32 = 0.196;
const RANGE: f32 = 19.61;

/// The monitor's model and monitor ([`WithMonitor`], built as `fw-free-monitor` builds them),
/// its filter, and the pole the sensor measures.
pub struct MonitorLoop {
    inner: WithMonitor<Pole>,
    ekf: Filter,
    pole: Pole,
    rng: crate::stress::Rng,
    /// Samples the filter refused (the model kept its state).
    refused: u32,
    /// Samples whose estimated root stress is beyond the filter's physical limit
    /// (`HealthConfig::stress_limit` from the static stress: verdict `failed`): not recorded.
    implausible: u32,
}

/// The filter's settings (module doc) for the model of `params`, its load model's corner at
/// `corner` \[rad/s\].
fn config(params: &Params<f32>, corner: f32) -> Result<EkfConfig<f32, MODES>, Error> {
    let sensor = Sensor {
        bias_sd: 3.0 * NOISE,
        bias_walk: 2.5e-6,
        model_error: 0.01,
        ..Sensor::new(NOISE, RANGE)
    };
    let load_sd = 0.05;
    let tau = 2.0 * core::f32::consts::PI;
    Ok(EkfConfig {
        sensors: SensorSet::empty().with(SensorKind::TipAccel, sensor),
        load_sd,
        load_corner: corner,
        load_order: 2,
        load_mean_time: 4.0 * tau / corner,
        load_mean_sd: load_sd * libm::sqrtf(2.0 / (4.0 * tau)),
        section: RootSection::rectangle(&params.beam)?,
        stress_factors: [1.0; MODES],
        initial_accel: 0.05,
        modal_noise: 0.0,
        impact_sd: 0.2,
        ball_restart_sd: [0.05, 1.0],
        rms_time: 1.0,
        health: HealthConfig::new((1.0 / params.integrator.step) as u32),
        gate: 3.0,
        event_error: 0.0,
        event_window: 30,
        adapt_time: 20.0,
    })
}

/// The monitor's model: [`crate::firmware_params`] with the work cap raised by one refresh of
/// the Newton matrix, which the filter's linearization needs (charged to the step) after a step
/// whose last matrix is another contact's (a release from a stop, a landing): with the free
/// ball's deadline alone that refresh does not fit after the hardest event steps, the sample
/// fails, and the model, kept as it was, fails the same way at every later sample.
pub const MAX_WORK: u32 = work::DEADLINE + 2 * work::REFRESH;

fn params(setup: &Setup) -> Params<f32> {
    let mut p = crate::firmware_params(setup);
    p.integrator.max_work = MAX_WORK;
    p
}

/// The first bending mode's circular frequency of `model` \[rad/s\]: the lowest of the
/// filter's modes that is not the ball's pendulum mode (less than half of its modal mass in
/// the ball's coordinate).
fn bending_corner(model: &Pole) -> Result<f32, Error> {
    let basis = ModalBasis::<f32, D, MODES>::of(model)?;
    let spin = 4 * N;
    let ball_share = |i: usize| (basis.projection[(i, spin)] * basis.shapes[(spin, i)]).abs();
    let i = (0..MODES).find(|&i| ball_share(i) < 0.5).unwrap_or(0);
    Ok(basis.omega.get(i).copied().unwrap_or(1.0))
}

impl MonitorLoop {
    /// The tip accelerometer's reading of the pole now (the sample's sensor read).
    fn read_sensor(&mut self) -> f32 {
        let s = self.pole.state();
        let tip = s.a.get(4 * N - 3).copied().unwrap_or(0.0) + s.base_accel;
        // Sum of three uniforms on [−1, 1): sd 1 (Irwin–Hall), bounded at 3.
        let n = self.rng.symmetric() + self.rng.symmetric() + self.rng.symmetric();
        (tip + BIAS + NOISE * n).clamp(-RANGE, RANGE)
    }
}

impl Sim for MonitorLoop {
    fn name() -> &'static str {
        "monitor loop: sensor read, EKF, monitor record"
    }

    fn init() -> Result<Self, Error> {
        Err(Error::InvalidParameter {
            field: "storage",
            reason: "the monitor loop is only built in place (Sim::init_in)",
        })
    }

    /// The monitor's model and monitor as `fw-free-monitor` builds them (with [`MAX_WORK`]),
    /// the pole beside them
    /// (the same model, events at the crossing), then the filter and its zero calibration on
    /// one reading at rest.
    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        let inner = WithMonitor::<Pole>::init_with(field!(slot, inner), params(setup))?;
        let p = *inner.model.params();
        let corner = bending_corner(&inner.model)?;
        Filter::new_in(field!(slot, ekf), &inner.model, config(&p, corner)?)?;
        let mut crossing = p;
        crossing.integrator.events = EventLocation::Crossing;
        Pole::at_rest_in(field!(slot, pole), crossing, 0.0)?;
        field!(slot, rng).write(crate::stress::Rng::default());
        field!(slot, refused).write(0u32);
        field!(slot, implausible).write(0u32);
        // SAFETY: every field was just initialized.
        let m = unsafe { slot.assume_init_mut() };
        let y = m.read_sensor();
        m.ekf.calibrate_zero(
            &m.inner.model,
            &Readings::none().with(SensorKind::TipAccel, y),
        )?;
        Ok(m)
    }

    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        self.inner.spin_start(rate)?;
        crate::spin_start(&mut self.pole, rate)
    }

    /// The pole to the new input (not counted: the sensor's world, not the firmware's work).
    fn environment(&mut self, base_accel: f32) {
        let _ = self.pole.step(base_accel);
    }

    /// Sensor read, filter step, monitor record: not after a refused sample (the model did
    /// not move), nor after one whose estimated stress the filter's health check calls
    /// impossible (beyond its stress limit, 250 MPa from static: the fatigue counter is fed
    /// only stresses a steel arm can carry; under noise at the input limit a correction
    /// reached 10²⁷ Pa, whose rainflow range overflows the Miner sum).
    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        let y = self.read_sensor();
        let readings = Readings::none().with(SensorKind::TipAccel, y);
        let e = match self
            .ekf
            .update(&mut self.inner.model, base_accel, &readings)
        {
            Ok(e) => e,
            Err(err) => {
                self.refused = self.refused.saturating_add(1);
                return Err(err);
            }
        };
        let limit = self.ekf.health().config().stress_limit;
        let from_static = e.root_stress - self.ekf.static_stress();
        let w = &mut self.inner;
        if from_static.is_nan() || from_static.abs() > limit {
            self.implausible = self.implausible.saturating_add(1);
        } else if monitor_record(&mut w.monitor, &w.model, &e.report, base_accel).is_err() {
            w.record_errors = w.record_errors.saturating_add(1);
        }
        Ok(e.report)
    }

    fn h(&self) -> f32 {
        self.inner.h()
    }

    fn work_cap(&self) -> u32 {
        self.inner.work_cap()
    }

    fn tip(&self) -> f32 {
        self.inner.tip()
    }

    fn ball(&self) -> f32 {
        self.inner.ball()
    }

    fn static_tip(&self) -> f32 {
        self.inner.static_tip()
    }

    /// The monitor's model and monitor ([`WithMonitor`]'s words), the filter's load, bias and
    /// verdict, the refused and the implausible samples, and the pole's state.
    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.inner.state_words(f);
        f(self.ekf.load().to_bits());
        for b in self.ekf.biases() {
            f(b.to_bits());
        }
        f(self.ekf.verdict() as u32);
        f(self.refused);
        f(self.implausible);
        self.pole.state_words(f);
    }

    /// The monitor's figures ([`WithMonitor`]), then the filter's load and verdict, the
    /// refused and the implausible samples, and the pole's tip.
    fn second(&self, out: &mut dyn Write, f: &mut dyn FnMut(u32)) {
        self.inner.second(out, f);
        let _ = writeln!(
            out,
            "  filter load={} verdict={} refused={} implausible={} pole tip={}",
            crate::F(self.ekf.load()),
            self.ekf.verdict() as u32,
            self.refused,
            self.implausible,
            crate::F(self.pole.tip())
        );
    }
}
