//! Host time of one step of the embedded core: scene × elements × precision.
//!
//! Each benchmark warms the model up for 2 s of simulated time under a 0.5 mm base excitation
//! at 3.70 Hz (steady, no stop impacts), then times single steps continuing the same run.
//! `free-4.13Hz` runs at 4.13 Hz from 5 s on, where the ball hits the stops (impact steps
//! included in the average).

use absorber_core::{BeamOnly, FreeBall, LockedBall, Model, Params, Real, Scene};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

fn excitation<T: Real>(freq: f64, k: u64) -> T {
    let w = 2.0 * std::f64::consts::PI * freq;
    let t = k as f64 * 0.003;
    nalgebra::convert(-0.5e-3 * w * w * (w * t).sin())
}

fn bench_scene<T: Real, S: Scene, const N: usize, const D: usize>(
    c: &mut Criterion,
    precision: &str,
    freq: f64,
    warm: f64,
) {
    let mut model =
        Model::<T, S, N, D>::at_rest(Params::default(), T::zero()).expect("paper scene");
    let mut k = 0u64;
    while (k as f64) * 0.003 < warm {
        k += 1;
        model.step(excitation(freq, k)).expect("warm-up");
    }
    let name = if freq == 3.70 {
        S::NAME.to_string()
    } else {
        format!("{}-{freq}Hz", S::NAME)
    };
    c.bench_with_input(
        BenchmarkId::new(format!("core_step/{name}/{precision}"), N),
        &N,
        |b, _| {
            b.iter(|| {
                k += 1;
                // A failed step would keep the state; the benchmark then measures failures, so
                // count them in the result instead of hiding them.
                black_box(
                    model
                        .step(excitation(freq, k))
                        .map(|r| r.iterations)
                        .unwrap_or(u32::MAX),
                )
            })
        },
    );
}

fn core_step(c: &mut Criterion) {
    bench_scene::<f32, FreeBall, 3, 13>(c, "f32", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 3, 13>(c, "f64", 3.70, 2.0);
    bench_scene::<f32, FreeBall, 3, 13>(c, "f32", 4.13, 5.0);
    bench_scene::<f64, FreeBall, 3, 13>(c, "f64", 4.13, 5.0);
    bench_scene::<f32, LockedBall, 3, 12>(c, "f32", 3.70, 2.0);
    bench_scene::<f64, LockedBall, 3, 12>(c, "f64", 3.70, 2.0);
    bench_scene::<f32, BeamOnly, 3, 12>(c, "f32", 3.70, 2.0);
    bench_scene::<f64, BeamOnly, 3, 12>(c, "f64", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 1, 5>(c, "f64", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 2, 9>(c, "f64", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 4, 17>(c, "f64", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 6, 25>(c, "f64", 3.70, 2.0);
    bench_scene::<f64, FreeBall, 8, 33>(c, "f64", 3.70, 2.0);
    // f32 across N (the firmware's scalar), and the locked and beam scenes at N = 6.
    bench_scene::<f32, FreeBall, 1, 5>(c, "f32", 3.70, 2.0);
    bench_scene::<f32, FreeBall, 2, 9>(c, "f32", 3.70, 2.0);
    bench_scene::<f32, FreeBall, 4, 17>(c, "f32", 3.70, 2.0);
    bench_scene::<f32, FreeBall, 6, 25>(c, "f32", 3.70, 2.0);
    bench_scene::<f32, LockedBall, 6, 24>(c, "f32", 3.70, 2.0);
    bench_scene::<f32, BeamOnly, 6, 24>(c, "f32", 3.70, 2.0);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = core_step
}
criterion_main!(benches);
