//! # absorber-firmware
//!
//! `absorber-core` on a Cortex-M4F, run under QEMU (`-M mps2-an386`), and the same scene run on
//! the host as the bit-for-bit reference.
//!
//! Every bin of this crate (`fw-free`, `fw-free-modified`, `fw-free-monitor`, `fw-beam`,
//! `fw-locked`, the monitor loop `fw-monitor-loop` ([`monitor_loop`]), and the model-less
//! baseline `fw-empty`, among others) builds twice from one source:
//!
//! * for `thumbv7em-none-eabihf`: `no_std`, `no_main`, cortex-m-rt, output and exit code through
//!   semihosting; the model lives in a `static` (so it shows in `.bss`);
//! * for the host: an ordinary program that prints exactly the same text, which is the
//!   reference the firmware must reproduce bit for bit.
//!
//! The scene driver, [`run`], is shared. It feeds the base acceleration
//! `ÿ_b(t_k) = −A Ω² sin(Ω t_k)`, `t_k = k h`, `k = 1..=STEPS`, computed in `f32` with `libm`,
//! prints tip deflection and ball angle at every whole second, and folds every step's full
//! state and report into a 64-bit FNV-1a fingerprint ([`Summary::hash`]). The firmware gets the
//! host's fingerprint as a semihosting argument (`expect=0x…`) and exits 0 only if they agree.
//!
//! The model step is called through [`Sim::step`], a non-inlined function per scene, so its
//! instructions can be counted between its entry and its return address (see
//! `scripts/embedded-report.sh`). In `fw-free-monitor` ([`WithMonitor`]) that step also feeds an
//! `absorber_core::monitor::Monitor`, through [`monitor_record`], itself non-inlined so the
//! monitor's share is counted on its own.
#![cfg_attr(target_os = "none", no_std)]

use absorber_core::monitor::{Monitor, MonitorConfig, NoTwin};
use absorber_core::{Error, EventLocation, Model, Outcome, Params, Scene, StepReport};
use core::fmt::{self, Write};
use core::mem::MaybeUninit;
pub use stress::Setup;

/// Excitation amplitude A \[m\] (the paper's free-ball run).
pub const AMPLITUDE: f32 = 0.5e-3;
/// Excitation frequency \[Hz\]: Ω = 2π·4.13 rad/s.
pub const FREQUENCY_HZ: f32 = 4.13;
/// Simulated time \[s\].
pub const DURATION_S: u32 = 20;
/// Time step in milliseconds (must equal `Params::default().integrator.step`).
pub const STEP_MS: u32 = 3;
/// Number of steps: ⌈20 s / 3 ms⌉ = 6667.
pub const STEPS: u32 = (DURATION_S * 1000).div_ceil(STEP_MS);

/// Base acceleration ÿ_b at the end of step `k` (time `k h`) \[m/s²\] at `frequency` \[Hz\], in
/// `f32` with `libm`.
#[inline(never)]
pub fn base_accel(k: u32, h: f32, frequency: f32) -> f32 {
    let omega = 2.0 * core::f32::consts::PI * frequency;
    let t = k as f32 * h;
    -AMPLITUDE * omega * omega * libm::sinf(omega * t)
}

/// The firmware's parameters: `Params::default()` (the paper's Table 1) with every event at
/// the end of its step and the work cap for a deadline per sample (`docs/embedded.md`,
/// "Firmware defaults": the choice measured), and a stress scene's restitution.
pub fn firmware_params(setup: &Setup) -> Params<f32> {
    let mut p = Params::<f32>::default();
    p.integrator.events = EventLocation::StepEnd;
    p.integrator.max_work = absorber_core::work::DEADLINE;
    if let Some(e) = setup.stress.and_then(|s| s.restitution) {
        p.ball.restitution = e;
        p.ball.landing_restitution = e;
    }
    p
}

/// The free ball as the firmware runs it ([`firmware_params`]: every event at the end of its
/// step): the code of events at their crossings and of the perfectly elastic ball's rules is
/// left out at compile time ([`absorber_core::AtStepEnd`]); its runs are those of
/// `FreeBallModel<f32, N, D>`, bit for bit.
pub type FwFreeBall<const N: usize, const D: usize> =
    Model<f32, absorber_core::AtStepEnd<absorber_core::FreeBall>, N, D>;

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
fn spin_start<S: Scene, const N: usize, const D: usize>(
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

/// `&mut MaybeUninit` of the field `$f` of the value in `$slot: &mut MaybeUninit<_>`: builds the
/// parts of a scene in place.
macro_rules! field {
    ($slot:expr, $f:tt) => {{
        let slot: &mut MaybeUninit<_> = $slot;
        let p = slot.as_mut_ptr();
        // SAFETY: a pointer to a field of the value `slot` holds, computed without a reference
        // to the (uninitialized) value: as valid for writes as `slot`, for as long;
        // `MaybeUninit<F>` has the field's layout.
        unsafe { &mut *core::ptr::addr_of_mut!((*p).$f).cast::<MaybeUninit<_>>() }
    }};
}

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

/// The model plus an on-device monitor (`Monitor<f32>`: no twin, `MonitorConfig::paper`) that
/// records after every step. `CAP`, `K`, `W` (rainflow residue, impact log, window blocks)
/// default to `Monitor`'s own defaults, the ones host-sim's `fatigue` runs with.
pub struct WithMonitor<M, const CAP: usize = 128, const K: usize = 16, const W: usize = 256> {
    /// The monitored model.
    pub model: M,
    /// The monitor.
    pub monitor: Monitor<f32, NoTwin, CAP, K, W>,
    /// Samples `Monitor::record` refused (the model still advanced).
    pub record_errors: u32,
}

/// `Monitor::record` behind its own non-inlined function, so its instructions per sample are
/// counted separately from the model's step (`scripts/embedded-report.sh`).
#[inline(never)]
pub fn monitor_record<
    S: Scene,
    const N: usize,
    const D: usize,
    const CAP: usize,
    const K: usize,
    const W: usize,
>(
    monitor: &mut Monitor<f32, NoTwin, CAP, K, W>,
    model: &Model<f32, S, N, D>,
    report: &StepReport<f32>,
    base_accel: f32,
) -> Result<f32, Error> {
    monitor.record(model, report, base_accel)
}

impl<
        S: Scene,
        const N: usize,
        const D: usize,
        const CAP: usize,
        const K: usize,
        const W: usize,
    > WithMonitor<Model<f32, S, N, D>, CAP, K, W>
{
    /// The model with `p` in place, then the monitor in place beside it (`Monitor::new_in`):
    /// neither passes through the stack.
    pub fn init_with(slot: &mut MaybeUninit<Self>, p: Params<f32>) -> Result<&mut Self, Error> {
        let model = Model::<f32, S, N, D>::at_rest_in(field!(slot, model), p, 0.0)?;
        Monitor::<f32, NoTwin, CAP, K, W>::new_in(
            field!(slot, monitor),
            MonitorConfig::paper(&p)?,
            model,
        )?;
        field!(slot, record_errors).write(0u32);
        // SAFETY: every field was just initialized.
        Ok(unsafe { slot.assume_init_mut() })
    }
}

impl<
        S: Scene,
        const N: usize,
        const D: usize,
        const CAP: usize,
        const K: usize,
        const W: usize,
    > Sim for WithMonitor<Model<f32, S, N, D>, CAP, K, W>
{
    fn name() -> &'static str {
        "free ball + monitor"
    }

    fn init() -> Result<Self, Error> {
        let p = firmware_params(&Setup::default());
        let model = Model::at_rest(p, 0.0)?;
        let monitor = Monitor::new(MonitorConfig::paper(&p)?, &model)?;
        Ok(WithMonitor {
            model,
            monitor,
            record_errors: 0,
        })
    }

    /// The model in place, then the monitor in place beside it (`Monitor::new_in`): neither
    /// passes through the stack.
    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        Self::init_with(slot, firmware_params(setup))
    }

    fn spin_start(&mut self, rate: f32) -> Result<(), Error> {
        spin_start(&mut self.model, rate)
    }

    fn work_cap(&self) -> u32 {
        self.model.work_cap()
    }

    /// Model step, then `Monitor::record` (not after a failed step: the state did not move).
    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        let r = Model::step(&mut self.model, base_accel);
        if let Ok(report) = &r {
            if monitor_record(&mut self.monitor, &self.model, report, base_accel).is_err() {
                self.record_errors = self.record_errors.saturating_add(1);
            }
        }
        r
    }

    fn h(&self) -> f32 {
        self.model.h()
    }

    fn tip(&self) -> f32 {
        self.model.tip()
    }

    fn ball(&self) -> f32 {
        self.model.ball()
    }

    fn static_tip(&self) -> f32 {
        self.model.static_tip()
    }

    /// The model's state, then what `record` changed: stress, closed-cycle Miner damage, cycle
    /// count and largest range, rainflow reversals, residue length and overflows, samples,
    /// rejections, impacts logged and refused records.
    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.model.state_words(f);
        let m = &self.monitor;
        let miner = m.miner();
        f(m.root_stress().to_bits());
        f(miner.damage().to_bits());
        f(miner.cycles().to_bits());
        f(miner.max_range().to_bits());
        let rev = m.rainflow().reversals();
        f(rev as u32);
        f((rev >> 32) as u32);
        f(m.rainflow().residue_len() as u32);
        // Low word, with the (in practice zero) high word folded in: the fingerprint of every
        // run below 2³² evictions is unchanged, and a wrap still shows.
        let ov = m.rainflow().overflows();
        f((ov ^ (ov >> 32)) as u32);
        f(m.samples() as u32);
        f(m.rejected());
        f(m.impacts().total());
        f(self.record_errors);
    }

    /// Fatigue with the residue (as if the history ended now) and the window indicators.
    fn second(&self, out: &mut dyn Write, f: &mut dyn FnMut(u32)) {
        let m = &self.monitor;
        let fat = m.fatigue();
        let v = m.indicators();
        for x in [
            m.root_stress(),
            fat.damage,
            fat.equivalent_range,
            fat.cycles,
            fat.max_range,
            v.tip_rms,
            v.tip_peak,
            v.ball_rms,
            v.beam_energy,
            v.ball_energy,
        ] {
            f(x.to_bits());
        }
        let _ = writeln!(
            out,
            "  monitor stress={} damage={} S_eq={} cycles={} max_range={}",
            F(m.root_stress()),
            F(fat.damage),
            F(fat.equivalent_range),
            F(fat.cycles),
            F(fat.max_range)
        );
        let _ = writeln!(
            out,
            "  monitor tip_rms={} tip_peak={} ball_rms={} beam_energy={} ball_energy={}",
            F(v.tip_rms),
            F(v.tip_peak),
            F(v.ball_rms),
            F(v.beam_energy),
            F(v.ball_energy)
        );
        let _ = writeln!(
            out,
            "  monitor residue={} overflows={} impacts={} rejected={} record_errors={}",
            m.rainflow().residue_len(),
            m.rainflow().overflows(),
            m.impacts().total(),
            m.rejected(),
            self.record_errors
        );
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

/// 64-bit FNV-1a over 32-bit words (each word fed as 4 bytes, little end first).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Folds one word in.
    pub fn word(&mut self, w: u32) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// What a run did.
#[derive(Clone, Copy, Debug, Default)]
pub struct Summary {
    /// Fingerprint of every step's state and report.
    pub hash: u64,
    /// Steps that hit a stop.
    pub impacts: u32,
    /// Impacts after which the ball stayed on the stop.
    pub stuck: u32,
    /// Newton iterations summed over all steps.
    pub iterations: u32,
    /// Most Newton iterations in one step.
    pub max_iterations: u32,
    /// Steps that returned an error (state kept, run continued).
    pub errors: u32,
    /// Steps taken at the work cap (`Outcome::Capped`).
    pub capped: u32,
    /// Steps that restarted the model (`Outcome::Restarted`).
    pub restarts: u32,
    /// Most work units in one step.
    pub max_work: u32,
    /// Longest run of error steps (errors, capped or restarting steps) in a row.
    pub longest_error_run: u32,
}

impl Summary {
    /// Steps that did not converge normally: errors, capped and restarting steps.
    pub fn error_steps(&self) -> u32 {
        self.errors + self.capped + self.restarts
    }
}

/// Hooks around each step (the firmware measures the stack there; the host does nothing).
pub trait Probe {
    /// Just before `Sim::step`.
    fn before_step(&mut self) {}
    /// Just after it.
    fn after_step(&mut self) {}
}

/// Does nothing.
pub struct NoProbe;
impl Probe for NoProbe {}

/// Short name of an error (no float formatting: keeps the model's flash figure honest).
pub fn error_name(e: &Error) -> &'static str {
    match e {
        Error::InvalidParameter { field, .. } => field,
        Error::NonFiniteInput => "NonFiniteInput",
        Error::NoConvergence { .. } => "NoConvergence",
        Error::NonFiniteState => "NonFiniteState",
        Error::Singular => "Singular",
        Error::WorkCap => "WorkCap",
        _ => "other",
    }
}

struct F(f32);
impl fmt::Display for F {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:e} ({:08x})", self.0, self.0.to_bits())
    }
}

/// Runs the scene for [`STEPS`] steps (a stress scene: its own steps and input) from the
/// model's current state, printing to `out`. The text is identical on the host and on the
/// target.
pub fn run<M: Sim, W: Write, P: Probe>(
    m: &mut M,
    setup: &Setup,
    out: &mut W,
    probe: &mut P,
) -> Summary {
    let h = m.h();
    let steps = setup.steps();
    let _ = writeln!(
        out,
        "scene {} h={} steps={} A={:e} f={:e}",
        M::name(),
        F(h),
        steps,
        setup.amplitude(),
        M::frequency()
    );
    if let Some(st) = setup.stress {
        let _ = writeln!(out, "stress {}", st.name);
    }
    let _ = writeln!(out, "static tip={}", F(m.static_tip()));
    {
        use absorber_core::work as w;
        let _ = writeln!(
            out,
            "work cap={} refresh={} residual={} solve={} fallback={}",
            m.work_cap(),
            w::REFRESH,
            w::RESIDUAL,
            w::SOLVE,
            w::FALLBACK
        );
    }
    let mut hash = Fnv::default();
    let mut s = Summary::default();
    if let Some(rate) = setup.stress.and_then(|st| st.spin) {
        if let Err(e) = m.spin_start(rate) {
            let _ = writeln!(out, "spun start failed: {}", error_name(&e));
        }
    }
    let mut rng = stress::Rng::default();
    let mut run = 0u32;
    // Impact steps printed on the current line (16 per line).
    let mut on_line = 0u32;
    for k in 1..=steps {
        let accel = match setup.stress {
            Some(st) => st.accel(k, h, M::frequency(), &mut rng),
            None => base_accel(k, h, M::frequency()),
        };
        m.environment(accel);
        probe.before_step();
        let r = m.step(accel);
        probe.after_step();
        let normal = match r {
            Ok(rep) => {
                s.iterations += rep.iterations;
                s.max_iterations = s.max_iterations.max(rep.iterations);
                s.max_work = s.max_work.max(u32::from(rep.work));
                hash.word(rep.iterations);
                hash.word(rep.increment.to_bits());
                hash.word(u32::from(rep.work));
                hash.word(rep.outcome as u32);
                if let Some(i) = rep.impact {
                    s.impacts += 1;
                    s.stuck += u32::from(i.stuck);
                    for w in [i.time, i.relative_speed, i.impulse, i.energy_loss] {
                        hash.word(w.to_bits());
                    }
                    hash.word(u32::from(i.stuck));
                    // Which steps hit a stop, 16 per line (the report looks up the worst step).
                    if on_line == 0 {
                        let _ = write!(out, "impact steps:");
                    }
                    let _ = write!(out, " {k}");
                    on_line += 1;
                    if on_line == 16 {
                        let _ = writeln!(out);
                        on_line = 0;
                    }
                }
                match rep.outcome {
                    Outcome::Converged => true,
                    Outcome::Capped => {
                        s.capped += 1;
                        false
                    }
                    Outcome::Restarted => {
                        s.restarts += 1;
                        false
                    }
                }
            }
            Err(e) => {
                s.errors += 1;
                hash.word(0xdead_0000 | s.errors);
                if s.errors <= 20 {
                    let _ = writeln!(out, "step {k}: error {} (state kept)", error_name(&e));
                }
                false
            }
        };
        run = if normal { 0 } else { run + 1 };
        s.longest_error_run = s.longest_error_run.max(run);
        m.state_words(&mut |w| hash.word(w));
        // Every whole second of simulated time (k h crosses j seconds).
        if (k * STEP_MS) / 1000 != ((k - 1) * STEP_MS) / 1000 {
            if on_line != 0 {
                let _ = writeln!(out);
                on_line = 0;
            }
            let _ = writeln!(out, "k={k} tip={} ball={}", F(m.tip()), F(m.ball()));
            m.second(out, &mut |w| hash.word(w));
        }
    }
    if on_line != 0 {
        let _ = writeln!(out);
    }
    s.hash = hash.0;
    let _ = writeln!(
        out,
        "impacts={} stuck={} iterations={} max_iterations={} errors={}",
        s.impacts, s.stuck, s.iterations, s.max_iterations, s.errors
    );
    let _ = writeln!(
        out,
        "capped={} restarts={} error_steps={} longest_error_run={} max_work={}",
        s.capped,
        s.restarts,
        s.error_steps(),
        s.longest_error_run,
        s.max_work
    );
    let _ = writeln!(out, "state_hash=0x{:016x}", s.hash);
    s
}

/// The `main` of a firmware bin that runs the scene type `$m` ([`Sim`]): on the target the
/// cortex-m-rt entry with the model in a static (`target::target_main`), on the host
/// [`host_main`], which prints the reference the target must reproduce bit for bit.
#[macro_export]
macro_rules! firmware_main {
    ($m:ty) => {
        #[cfg(target_os = "none")]
        #[cortex_m_rt::entry]
        fn main() -> ! {
            static mut MODEL: core::mem::MaybeUninit<$m> = core::mem::MaybeUninit::uninit();
            $crate::target::target_main::<$m>(MODEL)
        }

        #[cfg(not(target_os = "none"))]
        fn main() {
            $crate::host_main::<$m>()
        }
    };
}

/// Host side: runs the scene (`stress=<name>` on the command line: a stress scene) and prints
/// the reference (the firmware must print the same).
#[cfg(not(target_os = "none"))]
pub fn host_main<M: Sim>() {
    use std::io::Write as _;
    struct Out(String);
    impl Write for Out {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            self.0.push_str(s);
            Ok(())
        }
    }
    let mut setup = Setup::default();
    for a in std::env::args().skip(1) {
        if setup.arg(&a).is_err() {
            eprintln!("unknown stress scene in `{a}`");
            std::process::exit(4);
        }
    }
    let mut out = Out(String::new());
    let mut slot = Box::new(MaybeUninit::<M>::uninit());
    let code = match M::init_in(&mut slot, &setup) {
        Ok(m) => {
            run(m, &setup, &mut out, &mut NoProbe);
            0
        }
        Err(e) => {
            let _ = writeln!(out, "init failed: {}", error_name(&e));
            3
        }
    };
    let _ = std::io::stdout().write_all(out.0.as_bytes());
    std::process::exit(code);
}

pub mod cost;
pub mod estimator;
pub mod monitor_loop;
pub mod stress;
#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
#[rustfmt::skip]
pub mod estimator_gain;

#[cfg(target_os = "none")]
pub mod target;
