//! Arbitrary bytes → parameter perturbations + a base-acceleration sequence → the core model.
//! Never a panic; an accepted state is finite; a failed step keeps the state bit for bit.
#![no_main]
use absorber_core::{FreeBallModel, Model, Params};
use libfuzzer_sys::fuzz_target;

fn take_f32(data: &mut &[u8]) -> Option<f32> {
    let (head, rest) = data.split_first_chunk::<4>()?;
    *data = rest;
    Some(f32::from_le_bytes(*head))
}

/// Model steps taken over the whole fuzzing run.
static STEPS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fuzz_target!(|bytes: &[u8]| {
    let mut data = bytes;
    let mut p = Params::<f32>::default();
    // First byte: which fields to perturb (bit mask); then one factor per set bit.
    let Some((&mask, rest)) = data.split_first() else {
        return;
    };
    data = rest;
    let factor = |d: &mut &[u8]| take_f32(d).map(|x| x.abs().clamp(1e-3, 1e3)).unwrap_or(1.0);
    if mask & 1 != 0 {
        p.beam.modulus *= factor(&mut data);
    }
    if mask & 2 != 0 {
        p.beam.inertia *= factor(&mut data);
    }
    if mask & 4 != 0 {
        let f = factor(&mut data);
        p.beam.length *= f;
        p.beam.mass *= f;
    }
    if mask & 8 != 0 {
        p.ball.mass *= factor(&mut data);
    }
    if mask & 16 != 0 {
        p.ball.restitution = (factor(&mut data) - 1.0e-3).min(1.0);
    }
    if mask & 32 != 0 {
        p.gravity *= factor(&mut data) - 1e-3;
    }
    if mask & 64 != 0 {
        p.integrator.step *= factor(&mut data).min(10.0);
    }
    if mask & 128 != 0 {
        p.tip.mass *= factor(&mut data);
    }
    // The firmware's per-step work cap: every step's work is bounded (without it one violent
    // input runs up to 50,000 units a step, ~20 ms here), so 10⁷ steps fit a campaign.
    p.integrator.max_work = absorber_core::work::DEADLINE;
    let Ok(mut m) = FreeBallModel::<f32, 3, 13>::at_rest(p, 0.0) else {
        return;
    };
    let mut steps = 0;
    while let Some(a) = take_f32(&mut data) {
        steps += 1;
        if steps > 400 {
            break;
        }
        // Progress on stderr every 10⁶ steps over the whole fuzzing run (how far it got).
        let total = STEPS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if total % 1_000_000 == 0 {
            eprintln!("fuzz step: {total} model steps");
        }
        let before = *m.state();
        match m.step(a) {
            Ok(_) => {
                let s = m.state();
                assert!(s
                    .q
                    .iter()
                    .chain(s.v.iter())
                    .chain(s.a.iter())
                    .all(|x| x.is_finite()));
            }
            Err(_) => assert_eq!(*m.state(), before),
        }
    }
    let _: Option<Model<f32, absorber_core::FreeBall, 3, 13>> = None;
});
