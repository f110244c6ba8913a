//! `restart` recovers from any state a failed run can reach. Under ±5 g of random base
//! acceleration (uniform, seeded, 10⁶ samples of 3 ms, f32 — the case that once drove the model
//! to a tip rotated −96° from which nothing converged), the driver restarts the model after a
//! failed sample. Asserted: after every restart the model steps again at once (the next sample
//! succeeds, or at most `BOUND` samples fail), and the run as a whole keeps going. The reference
//! is the model's own contract (errors as values, a restart at the static equilibrium), no
//! tolerance.

use absorber_core::{EventLocation, FreeBallModel, Params};

const BOUND: u32 = 3;
const BUDGET: u32 = 6;

/// Runs 10⁶ samples; returns (failed samples, restarts, most failures in a row after a restart).
fn run(max_iterations: u32, flight: bool) -> (u32, u32, u32) {
    run_with(max_iterations, flight, EventLocation::Crossing)
}

/// [`run`] with the events at `events`.
fn run_with(max_iterations: u32, flight: bool, events: EventLocation) -> (u32, u32, u32) {
    let mut p = Params::<f32>::default();
    p.integrator.max_iterations = max_iterations;
    p.ball.flight = flight;
    p.integrator.events = events;
    let mut m = FreeBallModel::<f32, 3, 13>::at_rest(p, 0.0).expect("start");
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        // xorshift64*: uniform in [−5 g, 5 g].
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        let u = (seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
        (2.0 * u - 1.0) * 5.0 * 9.81
    };
    let (mut failures, mut restarts, mut after_restart, mut worst_after) = (0u32, 0u32, 0u32, 0u32);
    let mut pending = false;
    for _ in 0..1_000_000 {
        let a = next();
        match m.step(a) {
            Ok(_) => {
                pending = false;
                after_restart = 0;
            }
            Err(_) => {
                failures += 1;
                if pending {
                    after_restart += 1;
                    worst_after = worst_after.max(after_restart);
                }
                m.restart(a).expect("restart from the static equilibrium");
                restarts += 1;
                pending = true;
            }
        }
    }
    println!("{events:?}, flight {flight}, max_iterations {max_iterations}: {failures} failed samples, {restarts} restarts, at most {worst_after} failures in a row after a restart");
    (failures, restarts, worst_after)
}

#[test]
fn restart_recovers_from_every_failure_under_five_g_random_input() {
    // The default budget runs the whole record with the ball held on its track (it used to reach
    // a state nothing converged from).
    let (failures, _, _) = run(100, false);
    assert_eq!(failures, 0, "{failures} of 10⁶ samples failed");
    // With flight (the ball in the air 71 % of the time at ±5 g, 20 times the paper's peak
    // input) a bounce every other step can pump the housing's stiff end-rotation mode until a
    // step does not converge in f32: measured 4 of 10⁶ samples. Budget 10, and each is
    // followed by a restart that steps again at once.
    let (failures, _, worst_after) = run(100, true);
    assert!(
        failures <= 10,
        "{failures} of 10⁶ samples failed with flight"
    );
    assert_eq!(worst_after, 0, "a failure right after a restart");
    // A budget of 6 iterations fails 0.7 % of the samples (measured 7,072): every failure is
    // followed by a restart, and the model steps again at once (measured: the next sample
    // succeeded every time; bound 3).
    let (failures, restarts, worst_after) = run(BUDGET, false);
    assert!(
        restarts > 10,
        "the tight budget must exercise restart ({failures} failures)"
    );
    assert!(
        worst_after <= BOUND,
        "{worst_after} failures in a row after a restart"
    );
}

/// The same with every event at the end of its step (`EventLocation::StepEnd`, no sub-steps,
/// no consistent acceleration after an event): with flight no more failed samples than the
/// crossing's budget, each followed by a restart that steps again at once.
#[test]
fn step_end_events_survive_five_g_random_input() {
    let (failures, _, worst_after) = run_with(100, true, EventLocation::StepEnd);
    assert!(failures <= 10, "{failures} of 10⁶ samples failed");
    assert_eq!(worst_after, 0, "a failure right after a restart");
}
