//! The model with an on-device monitor recording after every step.

use crate::{firmware_params, spin_start, Setup, Sim, F};
use absorber_core::monitor::{Monitor, MonitorConfig, NoTwin};
use absorber_core::{Error, Model, Params, Scene, StepReport};
use core::fmt::Write;
use core::mem::MaybeUninit;

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
