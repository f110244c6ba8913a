//! Host time of one frequency-response sweep on the embedded core: the paper's 14 frequencies
//! (3.50–4.70 Hz) × 10 s each, free ball, N = 3, `f32`, h = 3 ms (`absorber_sim::sweep::sweep`,
//! parallel over the frequencies with rayon; the machine's cores are shared).

use absorber_sim::scene::Scene;
use absorber_sim::sweep::{sweep, PAPER_FREQUENCIES};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn sweep_bench(c: &mut Criterion) {
    let mut scene = Scene::paper();
    scene.file.duration = 10.0;
    c.bench_function("sweep/core/14x10s", |b| {
        b.iter(|| black_box(sweep(&scene, &PAPER_FREQUENCIES, 5.0, &|_| {}).expect("sweep")))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(10)).warm_up_time(std::time::Duration::from_millis(500));
    targets = sweep_bench
}
criterion_main!(benches);
