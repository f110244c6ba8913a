//! The clock counts every step, impact steps included: after K steps the time is K·h exactly
//! (the state's `steps` times `h`), and the tip response of the paper's scene peaks at the
//! forcing frequency. (An impact step used to rebuild its state without counting the step: the
//! paper run's clock fell one step behind per impact, 0.47 s in 60 s, and its spectrum peaked
//! at 4.174 Hz instead of 4.142.)

use absorber_core::{FreeBallModel, Params};
use core::f64::consts::PI;

#[test]
fn time_is_steps_times_h_through_stop_impacts_and_the_tip_peaks_at_the_forcing_frequency() {
    let p = Params::<f64>::default();
    let h = p.integrator.step;
    let (amp, f) = (0.5e-3, 4.13);
    let omega = 2.0 * PI * f;
    let accel = |t: f64| -amp * omega * omega * (omega * t).sin();
    let mut m: FreeBallModel<f64, 3, 13> = FreeBallModel::at_rest(p, 0.0).expect("valid");
    let steps = 20_000u64; // 60 s
    let (mut impacts, mut samples) = (0, Vec::new());
    for k in 1..=steps {
        let r = m.step(accel(k as f64 * h)).expect("step");
        impacts += usize::from(r.impact.is_some());
        assert_eq!(m.state().steps, k);
        assert_eq!(m.time(), k as f64 * h, "step {k}");
        if m.time() >= 20.0 {
            samples.push((m.time(), m.tip_deflection()));
        }
    }
    assert!(impacts > 50, "the ball hits the stops ({impacts} impacts)");
    // Amplitude spectrum by direct DFT on a 0.002 Hz grid over 3.9–4.4 Hz.
    let mean = samples.iter().map(|s| s.1).sum::<f64>() / samples.len() as f64;
    let power = |fr: f64| {
        let (mut c, mut s) = (0.0, 0.0);
        for (t, y) in &samples {
            c += (y - mean) * (2.0 * PI * fr * t).cos();
            s += (y - mean) * (2.0 * PI * fr * t).sin();
        }
        c * c + s * s
    };
    let peak = (0..=250)
        .map(|i| 3.9 + 0.002 * f64::from(i))
        .max_by(|a, b| power(*a).total_cmp(&power(*b)))
        .expect("grid");
    // 40 s of record resolve 1/40 = 0.025 Hz: the peak lies within half a bin of the forcing.
    assert!((peak - f).abs() <= 0.0125, "peak at {peak} Hz");
}

/// Stop impacts put at the end of their step (`EventLocation::StepEnd`) come at the end of the
/// step that contains the crossing: the ball released from −62° (no excitation; trapezoidal,
/// h = 1 ms, so that it keeps the energy to reach the +65° stop) hits the stop first at the
/// crossing time `t_c` in the default mode, and at the end of the step containing `t_c` in
/// step-end mode (the two runs are identical until then).
#[test]
fn step_end_impacts_are_late_by_less_than_one_step() {
    use absorber_core::{EventLocation, FreeBall, Model};
    let first_impact = |events: EventLocation| {
        let mut p = Params::<f64>::default();
        p.integrator.events = events;
        p.integrator.gamma = 0.5;
        p.integrator.beta = 0.25;
        p.integrator.step = 1e-3;
        p.ball.initial_angle = -62f64.to_radians();
        p.ball.flight = false;
        let h = p.integrator.step;
        let mut m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("valid");
        for _ in 0..10_000 {
            if let Some(i) = m.step(0.0).expect("step").impact {
                return (i.time, m.time(), h);
            }
        }
        panic!("no impact in 10 s");
    };
    let (t_c, end_c, h) = first_impact(EventLocation::Crossing);
    let (t_e, end_e, _) = first_impact(EventLocation::StepEnd);
    println!("crossing at {t_c:.6} s (step ends {end_c:.6} s), step-end impact at {t_e:.6} s");
    assert!(
        t_c < end_c && end_c - t_c < h,
        "the crossing lies inside its step"
    );
    assert_eq!(end_e, end_c, "the same step");
    assert!(
        (t_e - end_e).abs() < 1e-12,
        "the step-end impact is at the step's end"
    );
    assert!(t_e - t_c > 0.0 && t_e - t_c < h);
}
