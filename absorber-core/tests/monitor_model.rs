//! The monitor on the model: fixed memory, impact log, effectiveness against a locked twin.

use absorber_core::monitor::indicators::Block;
use absorber_core::monitor::{Monitor, MonitorConfig, NoTwin};
use absorber_core::Impact;
use absorber_core::{FreeBallModel, LockedBallModel, Params};
use std::mem::size_of;

fn accel(f: f64, k: usize) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    -0.5e-3 * w * w * (w * k as f64 * 0.003).sin()
}

/// Memory is a compile-time constant: the residue (CAP scalars), the impact ring (K records),
/// the window (W blocks) and a fixed set of scalars and counters (≤ 512 bytes); the twin adds
/// its model and one scalar per block, `NoTwin` adds nothing.
#[test]
fn monitor_memory_is_a_compile_time_constant() {
    type Plain = Monitor<f32>; // CAP = 128, K = 16, W = 256
    type Twinned = Monitor<f32, LockedBallModel<f32, 3, 12>>;
    let parts =
        128 * size_of::<f32>() + 16 * size_of::<Impact<f32>>() + 256 * size_of::<Block<f32, ()>>();
    let plain = size_of::<Plain>();
    let twinned = size_of::<Twinned>();
    println!(
        "Monitor<f32> (CAP 128, K 16, W 256): {plain} bytes (residue {} + impacts {} + window {} + rest {}); \
         with locked twin: {twinned} bytes (model {} bytes); Monitor<f64>: {} bytes",
        128 * 4,
        16 * size_of::<Impact<f32>>(),
        256 * size_of::<Block<f32, ()>>(),
        plain - parts,
        size_of::<LockedBallModel<f32, 3, 12>>(),
        size_of::<Monitor<f64>>(),
    );
    assert!(
        plain >= parts && plain <= parts + 512,
        "{plain} vs {parts} + 512"
    );
    assert_eq!(size_of::<NoTwin>(), 0);
    assert_eq!(
        twinned - plain,
        size_of::<LockedBallModel<f32, 3, 12>>() + 256 * 4,
        "the twin costs its model and one f32 per block"
    );
    assert!(plain < 8 * 1024);
}

/// At 4.13 Hz the ball reaches the stops: every impact is counted, per side, and the log keeps
/// the last K in time order. The fatigue figures are finite and grow monotonically.
#[test]
fn impacts_are_logged_and_counted_per_side() {
    let p = Params::<f64>::default();
    let mut model = FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).unwrap();
    let mut mon: Monitor<f64, NoTwin, 64, 8, 128> =
        Monitor::new(MonitorConfig::paper(&p).unwrap(), &model).unwrap();
    let (mut impacts, mut last_d) = (0u32, 0.0);
    for k in 1..=10_000 {
        let a = accel(4.13, k);
        let r = model.step(a).unwrap();
        impacts += u32::from(r.impact.is_some());
        mon.record(&model, &r, a).unwrap();
        if k % 1000 == 0 {
            let d = mon.fatigue_closed().damage;
            assert!(d >= last_d && d.is_finite());
            last_d = d;
        }
    }
    let log = mon.impacts();
    let (pos, neg) = log.per_side();
    println!(
        "30 s at 4.13 Hz: {impacts} impacts ({pos} +, {neg} −), stress now {:.2} MPa (static {:.2}), \
         D = {:.3e}, S_eq = {:.2} MPa, residue {} points, overflows {}",
        mon.root_stress() / 1e6,
        mon.static_root_stress() / 1e6,
        mon.fatigue().damage,
        mon.fatigue().equivalent_range / 1e6,
        mon.rainflow().residue_len(),
        mon.rainflow().overflows()
    );
    assert!(impacts > 8, "the paper scene hits the stops at 4.13 Hz");
    assert_eq!(log.total(), impacts);
    assert_eq!(pos + neg, impacts);
    assert_eq!(log.iter().count(), 8);
    let times: Vec<f64> = log.iter().map(|i| i.time).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(log.last().map(|i| i.time), times.last().copied());
}

/// A step can hold several events of a kind (at 3 ms the free ball at 4.10 Hz takes off, lands
/// and hits the stops more than once in some steps): the monitor counts every one the step
/// reports (`StepReport::events`), not one per step. Over 60 s of Table 1 at 4.10 Hz the
/// monitor's totals equal the sums of the step reports' counts, and the run has steps with
/// two events of a kind (else the check would not test anything).
#[test]
fn every_event_of_a_step_is_counted() {
    let p = Params::<f64>::default();
    let mut model = FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).unwrap();
    let mut mon: Monitor<f64, NoTwin, 64, 8, 128> =
        Monitor::new(MonitorConfig::paper(&p).unwrap(), &model).unwrap();
    let (mut sums, mut multiple) = ([0u32; 4], 0u32);
    for k in 1..=20_000 {
        let a = accel(4.10, k);
        let r = model.step(a).unwrap();
        let e = &r.events;
        let counts = [e.impacts, e.separations, e.landings, e.bounces];
        for (s, c) in sums.iter_mut().zip(counts) {
            *s += u32::from(c);
        }
        multiple += u32::from(counts.iter().any(|&c| c > 1));
        mon.record(&model, &r, a).unwrap();
    }
    let log = mon.impacts();
    let f = mon.flight();
    println!(
        "60 s at 4.10 Hz: {} impacts ({} without a record), {} separations, {} landings, {} \
         bounces; {multiple} steps with two events of a kind",
        sums[0],
        log.unlogged(),
        sums[1],
        sums[2],
        sums[3]
    );
    assert!(multiple > 0, "no step with several events of a kind");
    assert_eq!(log.total(), sums[0]);
    let (pos, neg) = log.per_side();
    assert_eq!(pos + neg + log.unlogged(), sums[0]);
    assert_eq!(
        [f.separations, f.landings, f.bounces],
        [sums[1], sums[2], sums[3]]
    );
}

/// Effectiveness = RMS tip (free) / RMS tip (locked twin). The twin run inside the monitor equals
/// a separate locked model on the same input (same window RMS to rounding), and the figure is
/// finite and positive at 3.70 Hz.
#[test]
fn effectiveness_compares_with_the_locked_twin() {
    let p = Params::<f64>::default();
    let mut model = FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).unwrap();
    let twin = LockedBallModel::<f64, 3, 12>::at_rest(p, 0.0).unwrap();
    let mut alone = twin.clone();
    let mut mon: Monitor<f64, LockedBallModel<f64, 3, 12>, 64, 16, 250> =
        Monitor::with_twin(MonitorConfig::paper(&p).unwrap(), &model, twin).unwrap();
    let mut sq = Vec::new();
    for k in 1..=6000 {
        let a = accel(3.70, k);
        let r = model.step(a).unwrap();
        mon.record(&model, &r, a).unwrap();
        alone.step(a).unwrap();
        let y = alone.tip_deflection() - alone.static_tip_deflection();
        sq.push(y * y);
    }
    let v = mon.indicators();
    assert_eq!(v.samples, 2000, "W · block = 250 · 8 samples");
    let reference = (sq[sq.len() - 2000..].iter().sum::<f64>() / 2000.0).sqrt();
    let twin_rms = v.twin_tip_rms.unwrap();
    assert!((twin_rms - reference).abs() <= 1e-12 * reference);
    let e = v.effectiveness.unwrap();
    println!(
        "3.70 Hz, last 6 s: tip RMS {:.3} mm, peak {:.3} mm, locked {:.3} mm, effectiveness {e:.3}, \
         ball RMS {:.2}°, beam {:.3e} J, ball {:.3e} J",
        v.tip_rms * 1e3,
        v.tip_peak * 1e3,
        twin_rms * 1e3,
        v.ball_rms.to_degrees(),
        v.beam_energy,
        v.ball_energy
    );
    assert!(e.is_finite() && e > 0.0);
    assert!(v.tip_peak >= v.tip_rms * std::f64::consts::SQRT_2 * 0.9);
    assert_eq!(mon.twin_failures(), 0);
}

/// Built in place (`Monitor::new_in`, a firmware's `static`), the monitor is the one `new`
/// builds: the same stress, fatigue and window indicators, bit for bit, over 3000 samples of
/// the paper's run at 4.13 Hz (impacts included).
#[test]
fn monitor_built_in_place_equals_the_one_built_by_value() {
    let p = Params::<f32>::default();
    let mut model = FreeBallModel::<f32, 3, 13>::at_rest(p, 0.0).unwrap();
    let config = MonitorConfig::paper(&p).unwrap();
    let mut by_value: Monitor<f32> = Monitor::new(config, &model).unwrap();
    let mut slot = Box::new(std::mem::MaybeUninit::<Monitor<f32>>::uninit());
    let in_place = Monitor::new_in(&mut slot, config, &model).unwrap();
    for k in 1..=3000 {
        let a = accel(4.13, k) as f32;
        let r = model.step(a).unwrap();
        assert_eq!(
            by_value.record(&model, &r, a).unwrap().to_bits(),
            in_place.record(&model, &r, a).unwrap().to_bits()
        );
    }
    assert_eq!(by_value.fatigue(), in_place.fatigue());
    assert_eq!(by_value.indicators(), in_place.indicators());
    assert_eq!(by_value.static_root_stress(), in_place.static_root_stress());
    assert_eq!(by_value.impacts().total(), in_place.impacts().total());
    let bad = MonitorConfig {
        gate: -1.0,
        ..config
    };
    let mut slot = Box::new(std::mem::MaybeUninit::<Monitor<f32>>::uninit());
    assert!(Monitor::new_in(&mut slot, bad, &model).is_err());
}
