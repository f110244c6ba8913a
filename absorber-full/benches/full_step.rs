//! Host time of one step of the full solver (maximal coordinates, `f64`) against the number of
//! elements, N = 8 … 512: it should grow about linearly in N (constant mass matrix factored
//! once, block LU of the block-tridiagonal reduced Newton matrix once per step). Locked ball
//! (no stop events), paper integrator (h = 3 ms), 0.5 mm at 3.70 Hz, after 1 s of warm-up. The
//! cost slope is `log(t_512 / t_8) / log(64)` (docs/full-solver.md). The group
//! `full_step/locked-sparse-lu` times the same step with the kept sparse LU (faer), the
//! reference the block LU replaced, at N = 16 and 64.

use absorber_core::Params;
use absorber_full::{FullSolver, Linear, SceneKind};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

fn accel(k: u64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * 3.70;
    -0.5e-3 * w * w * (w * k as f64 * 0.003).sin()
}

fn full_step(c: &mut Criterion) {
    run(
        c,
        "full_step/locked",
        Linear::Block,
        &[8, 16, 32, 64, 128, 256, 512],
    );
    run(c, "full_step/locked-sparse-lu", Linear::Sparse, &[16, 64]);
}

fn run(c: &mut Criterion, group: &str, linear: Linear, sizes: &[usize]) {
    let mut g = c.benchmark_group(group);
    for &n in sizes {
        let mut s = FullSolver::at_rest(Params::default(), SceneKind::LockedBall, n, 0.0)
            .expect("paper scene");
        s.set_linear(linear).expect("factorization");
        let mut k = 0u64;
        while (k as f64) * 0.003 < 1.0 {
            k += 1;
            s.step(accel(k)).expect("warm-up");
        }
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                k += 1;
                black_box(s.step(accel(k)).map(|r| r.iterations).unwrap_or(u32::MAX))
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_millis(500));
    targets = full_step
}
criterion_main!(benches);
