//! Host time of the monitor per sample: `Monitor::record` after a model step (the step itself
//! is not timed), for f32/f64 and with/without the locked-ball twin (the twin's time is mostly
//! its own model step); and the rainflow counter + Miner alone on a stress-like signal.
//!
//! Timing uses `iter_custom` around each call (the model step between calls is excluded), so
//! each figure includes ~20 ns of `Instant` overhead.

use absorber_core::monitor::{
    DetailCategory, Miner, Monitor, MonitorConfig, NoTwin, Rainflow, ThresholdRule, Twin,
};
use absorber_core::{FreeBall, LockedBallModel, Model, Params, Real};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::{Duration, Instant};

fn excitation<T: Real>(freq: f64, k: u64) -> T {
    let w = 2.0 * std::f64::consts::PI * freq;
    let t = k as f64 * 0.003;
    nalgebra::convert(-0.5e-3 * w * w * (w * t).sin())
}

fn bench_record<T: Real, Tw: Twin<T>>(c: &mut Criterion, name: &str, twin: Tw) {
    let p = Params::<T>::default();
    let mut model = Model::<T, FreeBall, 3, 13>::at_rest(p, T::zero()).expect("paper scene");
    let cfg = MonitorConfig::paper(&p).expect("config");
    let mut mon: Monitor<T, Tw> = Monitor::with_twin(cfg, &model, twin).expect("monitor");
    let mut k = 0u64;
    // Warm up 2 s at 3.70 Hz so the window and residue are populated.
    while k < 667 {
        k += 1;
        let a = excitation(3.70, k);
        let r = model.step(a).expect("warm-up");
        mon.record(&model, &r, a).expect("record");
    }
    c.bench_function(&format!("monitor_record/{name}"), |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                k += 1;
                let a = excitation(3.70, k);
                let Ok(r) = model.step(a) else { continue };
                let t0 = Instant::now();
                black_box(mon.record(&model, &r, a).ok());
                total += t0.elapsed();
            }
            total
        })
    });
    c.bench_function(&format!("monitor_read/{name}"), |b| {
        b.iter(|| black_box((mon.fatigue(), mon.indicators())))
    });
}

fn bench_rainflow(c: &mut Criterion) {
    let mut rf = Rainflow::<f32, 128>::new(0.0).expect("rainflow");
    let mut miner =
        Miner::<f32>::new(DetailCategory::EPrime.curve(ThresholdRule::Cutoff)).expect("curve");
    let mut k = 0u64;
    c.bench_function("rainflow_miner_push/f32", |b| {
        b.iter(|| {
            k += 1;
            let t = k as f32 * 0.003;
            let x = 60e6 + 20e6 * (25.9 * t).sin() * (1.0 + 0.3 * (1.6 * t).sin());
            black_box(rf.push(x, &mut |cy| miner.add(&cy)).ok())
        })
    });
}

fn monitor(c: &mut Criterion) {
    bench_record::<f32, NoTwin>(c, "f32", NoTwin);
    bench_record::<f64, NoTwin>(c, "f64", NoTwin);
    let twin = LockedBallModel::<f32, 3, 12>::at_rest(Params::default(), 0.0).expect("twin");
    bench_record::<f32, _>(c, "f32+locked-twin", twin);
    bench_rainflow(c);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(Duration::from_secs(2)).warm_up_time(Duration::from_millis(500));
    targets = monitor
}
criterion_main!(benches);
