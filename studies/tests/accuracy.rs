//! Error budgets of the default embedded configuration (N = 3, h = 3 ms, `f32`, full Newton to
//! 1e-5) against the full solver on a converged mesh (`docs/accuracy.md`).
//!
//! The test reference is the report's reference made cheaper to fit CI: full solver, N = 8,
//! `f64`, Newton to 1e-10, damping-matched integrator, but h = 1 ms instead of 0.5 ms (5 s of
//! it costs a few seconds). Budgets are in % of the reference's peak dynamic tip deflection
//! (max |tip − static| over the window) and were set as: the value measured with `f32`, plus
//! the spread between `f32` and `f64` runs of the same configuration, plus the difference
//! between this reference and the report's (h = 1 ms vs 0.5 ms, N = 8 vs 16), rounded up
//! (numbers beside each budget). A change that moves the embedded model further from the
//! converged model by more than that fails. `cargo test --test accuracy -- --nocapture`
//! prints the measured values.

use absorber_studies::accuracy::{
    compare, embedded_f1, full_f1, peak_dynamic, reference_config, run_embedded, run_full, scenes,
    Config, Errors, TestScene, Trajectory,
};

fn scene(name: &str) -> TestScene {
    scenes()
        .into_iter()
        .find(|s| s.name == name)
        .expect("scene")
}

/// Reference and the default configuration in f32 and f64 over `window` s.
fn measure(name: &str, window: f64) -> (Trajectory, Errors, Errors) {
    let s = scene(name);
    let r = run_full(&reference_config(8, 0.001), &s, window).expect("reference");
    assert!(r.error.is_none(), "reference failed: {:?}", r.error);
    let c32 = run_embedded(&Config::DEFAULT, &s, window).expect("f32");
    let c64 = run_embedded(&Config::DEFAULT.with(|c| c.f32 = false), &s, window).expect("f64");
    assert!(c32.error.is_none() && c64.error.is_none());
    let e32 = compare(&c32, &r, window, window);
    let e64 = compare(&c64, &r, window, window);
    let p = peak_dynamic(&r);
    println!(
        "{name}, {window} s: peak dynamic {:.3} mm; f32: RMS {:.3} %, max {:.3} %, θ max {:.3} mrad; \
         f64: RMS {:.3} %, max {:.3} %, θ max {:.3} mrad",
        p * 1e3,
        100.0 * e32.tip_rms / p,
        100.0 * e32.tip_max / p,
        e32.ball_max * 1e3,
        100.0 * e64.tip_rms / p,
        100.0 * e64.tip_max / p,
        e64.ball_max * 1e3,
    );
    (r, e32, e64)
}

fn within(what: &str, value: f64, budget: f64) {
    assert!(
        value <= budget,
        "{what}: {value:.3} exceeds the budget {budget:.3}"
    );
}

/// First natural frequency of the locked scene (the beam mode): N = 3 is 0.92 % stiffer than
/// the N = 16 mesh (membrane locking of the cable element and the coarse mesh; docs/model.md).
/// Budget 0.95 %: measured 0.917 % (f64) / 0.91 % (f32) against N = 16.
#[test]
fn default_first_frequency_error() {
    let f_ref = full_f1(16).expect("full");
    let f32_ = embedded_f1(&Config::DEFAULT).expect("f32");
    let f64_ = embedded_f1(&Config::DEFAULT.with(|c| c.f32 = false)).expect("f64");
    let e32 = 100.0 * (f32_ / f_ref - 1.0);
    let e64 = 100.0 * (f64_ / f_ref - 1.0);
    println!(
        "f1: ref {f_ref:.5} Hz, f32 {f32_:.5} Hz ({e32:+.3} %), f64 {f64_:.5} Hz ({e64:+.3} %)"
    );
    within("f1 error f32 [%]", e32.abs(), 0.95);
    within("f1 error f64 [%]", e64.abs(), 0.95);
}

/// Locked ball at 4.13 Hz, first 5 s: the excitation sits between the converged f₁ (4.109 Hz)
/// and N = 3's (4.147 Hz), inside the half-power band (±0.032 Hz at ζ = 0.78 %), so the N = 3
/// frequency error dominates the tip error.
#[test]
fn default_locked_4_13_first_5_s() {
    let (r, e32, e64) = measure("locked-4.13", 5.0);
    let p = peak_dynamic(&r);
    // The report's numbers (docs/accuracy.md) are the same quantities against the h = 0.5 ms
    // reference and in % of the 60 s peak, hence smaller percentages.
    within("RMS tip error f32 [%]", 100.0 * e32.tip_rms / p, RMS_LOCKED);
    within("RMS tip error f64 [%]", 100.0 * e64.tip_rms / p, RMS_LOCKED);
    within("max tip error f32 [%]", 100.0 * e32.tip_max / p, MAX_LOCKED);
    within("max tip error f64 [%]", 100.0 * e64.tip_max / p, MAX_LOCKED);
}

/// Free ball at 3.70 Hz (no impacts: the only free-ball scene where pointwise errors mean
/// something over the whole run), first 5 s: tip and ball angle.
#[test]
fn default_free_3_70_first_5_s() {
    let (r, e32, e64) = measure("free-3.70", 5.0);
    let p = peak_dynamic(&r);
    within(
        "RMS tip error f32 [%]",
        100.0 * e32.tip_rms / p,
        RMS_FREE_370,
    );
    within(
        "RMS tip error f64 [%]",
        100.0 * e64.tip_rms / p,
        RMS_FREE_370,
    );
    within(
        "max tip error f32 [%]",
        100.0 * e32.tip_max / p,
        MAX_FREE_370,
    );
    within(
        "max tip error f64 [%]",
        100.0 * e64.tip_max / p,
        MAX_FREE_370,
    );
    within("max θ error f32 [mrad]", 1e3 * e32.ball_max, BALL_FREE_370);
    within("max θ error f64 [mrad]", 1e3 * e64.ball_max, BALL_FREE_370);
}

/// Paper scene (free ball, 4.13 Hz) up to 2.9 s, before the ball first reaches a stop (at
/// 3.0 s; after it the motion is chaotic and pointwise errors say nothing).
#[test]
fn default_free_4_13_before_the_first_impact() {
    let (r, e32, e64) = measure("free-4.13", 2.9);
    assert!(
        r.impacts.is_empty(),
        "the reference hit a stop before 2.9 s"
    );
    let p = peak_dynamic(&r);
    within(
        "RMS tip error f32 [%]",
        100.0 * e32.tip_rms / p,
        RMS_FREE_413,
    );
    within(
        "RMS tip error f64 [%]",
        100.0 * e64.tip_rms / p,
        RMS_FREE_413,
    );
    within(
        "max tip error f32 [%]",
        100.0 * e32.tip_max / p,
        MAX_FREE_413,
    );
    within(
        "max tip error f64 [%]",
        100.0 * e64.tip_max / p,
        MAX_FREE_413,
    );
    within("max θ error f32 [mrad]", 1e3 * e32.ball_max, BALL_FREE_413);
    within("max θ error f64 [mrad]", 1e3 * e64.ball_max, BALL_FREE_413);
}

/// Locked ball under the band-limited noise (1–10 Hz, 1 m/s² RMS), first 5 s.
#[test]
fn default_locked_noise_first_5_s() {
    let (r, e32, e64) = measure("locked-noise", 5.0);
    let p = peak_dynamic(&r);
    within("RMS tip error f32 [%]", 100.0 * e32.tip_rms / p, RMS_NOISE);
    within("RMS tip error f64 [%]", 100.0 * e64.tip_rms / p, RMS_NOISE);
    within("max tip error f32 [%]", 100.0 * e32.tip_max / p, MAX_NOISE);
    within("max tip error f64 [%]", 100.0 * e64.tip_max / p, MAX_NOISE);
}

// Budgets (see the module doc for the rule). Each: measured f32 value (this test, 5 s or until
// the first impact) + |f32 − f64| + the test reference's own step error (h = 1 ms vs 0.25 ms on
// the report's convergence table: 32 µm max on the locked scene = 0.15 % of its 5 s peak,
// 12 µm = 0.3 % and 1.4 mrad on the free ball at 3.70 Hz), rounded up.
/// Locked 4.13 Hz, RMS tip error, 5 s: 15.50 % + 0.01 + 0.15 → 16 %.
const RMS_LOCKED: f64 = 16.0;
/// Locked 4.13 Hz, max tip error, 5 s: 42.34 % + 0.01 + 0.15 → 43 %.
const MAX_LOCKED: f64 = 43.0;
/// Free 3.70 Hz, RMS tip error, 5 s: 12.74 % + 0.01 + 0.3 → 13.5 % (3.3 % of it is the static
/// sag of N = 3, 0.13 mm less than the converged mesh's).
const RMS_FREE_370: f64 = 13.5;
/// Free 3.70 Hz, max tip error, 5 s: 28.34 % + 0.01 + 0.3 → 29 %.
const MAX_FREE_370: f64 = 29.0;
/// Free 3.70 Hz, max ball angle error, 5 s: 4.38 mrad + 0.00 + 1.4 → 6 mrad.
const BALL_FREE_370: f64 = 6.0;
/// Free 4.13 Hz before the first impact (2.9 s), RMS tip: 10.32 % + 0.01 + 0.3 → 11 %.
const RMS_FREE_413: f64 = 11.0;
/// Same, max tip: 27.65 % + 0.01 + 0.3 → 28.5 %.
const MAX_FREE_413: f64 = 28.5;
/// Same, max ball angle: 87.0 mrad + 0.02 + 1.4 (as at 3.70 Hz) → 90 mrad (the ball's
/// instability grows the 1° start to the stops, so small phase errors show up large here).
const BALL_FREE_413: f64 = 90.0;
/// Locked noise, RMS tip, 5 s: 9.09 % + 0.01 + 0.15 on this noise draw (ChaCha8, seed 4);
/// 11.93 % on another draw of the same spectrum (the 5 s error moves by draw, not by the
/// model): 12.5 % holds both.
const RMS_NOISE: f64 = 12.5;
/// Locked noise, max tip, 5 s: 28.59 % + 0.01 + 0.15 on this draw, 29.10 % on the other → 30 %.
const MAX_NOISE: f64 = 30.0;
