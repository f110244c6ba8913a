use super::*;
use crate::estimate::BaselineLoad;

fn find<'a>(
    r: &'a LabReport,
    estimator: &str,
    model: &str,
    sensors: &[&str],
    truth: &str,
) -> &'a EstimatorReport {
    r.estimators
        .iter()
        .find(|e| {
            e.estimator == estimator && e.model == model && e.sensors == sensors && e.truth == truth
        })
        .unwrap_or_else(|| panic!("no {estimator} {model} {sensors:?} {truth}"))
}

/// The lab scene (free ball with flight in the truth: full solver, 16 elements, f64), a
/// 0.05 N tip force at 3.70 Hz (off the 2:1 tuning) and at the absorber's working point
/// (4.05, 4.10, 4.13 Hz), 60 s, seeded sensors: the extended Kalman filter with the ball
/// in its model meets the targets — tip accelerometer with the ball-angle sensor: dynamic
/// stress RMS error ≤ 10 %, Miner damage ratio 0.8–1.25 (measured 1.8–5.0 %, 0.96–1.01);
/// tip accelerometer alone ≤ 20 % (measured 3.6–4.6 %, 0.96–1.00) — where the
/// constant-gain filter it replaces, the ball left out, is off by more than 100 % at the
/// working point (measured 131–312 %). The control (ball locked in truth and filter: the
/// model right) stays within 10 % (measured 0.5–2.2 %). Measured: members 0–5.
///
/// The free ball is chaotic at the working point, and which side it swings to in each
/// episode is a coin toss the filter's model makes too (doc of [`LabEnsemble`]): there the
/// targets are judged in every member of a seeded ensemble of 4 realizations (sensor seeds
/// and 10⁻¹² rad of initial angle), not in one run. Off tuning the ball stays off the stops
/// and one run is the ensemble.
#[test]
fn ekf_with_the_ball_meets_the_lab_targets_on_and_off_tuning() {
    for f in [3.70, 4.05, 4.10, 4.13] {
        let mut scene = Scene::paper();
        scene.file.excitation.frequency = Some(f);
        let members = if f < 4.0 { 1 } else { 4 };
        let ens = lab_ensemble(&scene, 60.0, 0.05, BaselineLoad::default(), members).expect("lab");
        for r in &ens.reports {
            // Open loop: off tuning the ball's motion enters the stress at second order
            // (a locked ball within 2 %, measured 0.4 %); on tuning the free ball takes
            // energy out of the beam (locked RMS more than 1.5× the free one, measured
            // 2.3×).
            if f < 4.0 {
                assert!(r.exclusion_error_pct < 2.0, "{}", r.exclusion_error_pct);
                assert!((r.exclusion_damage_ratio - 1.0).abs() < 0.05, "{r:?}");
            } else if f > 4.1 {
                assert!(r.impacts > 0, "the ball reaches the stops");
                assert!(
                    r.locked_stress_rms_mpa > 1.5 * r.free_stress_rms_mpa,
                    "{} vs {}",
                    r.locked_stress_rms_mpa,
                    r.free_stress_rms_mpa
                );
            }
            let both = find(r, "ekf", "free-ball", &["tip_accel", "ball_angle"], "free");
            let tip = find(r, "ekf", "free-ball", &["tip_accel"], "free");
            let control = find(r, "ekf", "locked-ball", &["tip_accel"], "locked");
            for (e, limit) in [(both, 10.0), (tip, 20.0), (control, 10.0)] {
                assert_eq!(e.failed, 0, "{f} Hz: {e:?}");
                assert!(e.stress_rms_error_pct <= limit, "{f} Hz: {e:?}");
                assert!((0.8..=1.25).contains(&e.damage_ratio), "{f} Hz: {e:?}");
            }
            // The constant-gain baseline's verdict (its load check): never `ok` on a
            // wrong number, `ok` where it is right (the locked ball: 0.4–4.5 %).
            let before = find(r, "constant-gain", "locked-ball", &["tip_accel"], "free");
            let before_locked = find(r, "constant-gain", "locked-ball", &["tip_accel"], "locked");
            assert_eq!(before_locked.verdict, "ok", "{f} Hz: {before_locked:?}");
            if f > 4.0 {
                assert!(before.stress_rms_error_pct > 100.0, "{f} Hz: {before:?}");
                assert_eq!(before.verdict, "failed", "{f} Hz: {before:?}");
                // The tip accelerometer alone near the ball's events: its stress is right
                // in every member (above); its mean NIS and verdict are draws (0.6–3.1
                // over members 0–5, 2.5 ± 0.4 at 4.05 Hz; `ok` to `failed`: the episodes'
                // onsets and the ball's side). One run's NIS within 0.5–2 and not
                // `failed` was asserted here and held for one draw only: the ensemble's
                // figures are reported (`docs/monitoring.md`), not claimed consistent.
                assert!(tip.nis.is_finite() && tip.nis > 0.0, "{f} Hz: {tip:?}");
            } else {
                assert_eq!(before.verdict, "ok", "{f} Hz: {before:?}");
                // Off tuning the model is right: a consistent filter's mean NIS, 0.5–2
                // (measured 0.97–0.98; 0.19 with the broadband calibration, 0.49 without
                // the load model's scale λ).
                for e in [both, tip, control] {
                    assert!((0.5..=2.0).contains(&e.nis), "{f} Hz: {e:?}");
                }
            }
        }
        // The ensemble's entries: every member counted, its spread the members'.
        let tip = ens
            .find("ekf", "free-ball", &["tip_accel"], "free")
            .expect("tip accelerometer");
        assert_eq!(tip.member_verdicts.iter().sum::<usize>(), members as usize);
        assert!(tip.stress_rms_error_pct.max <= 20.0, "{f} Hz: {tip:?}");
        assert!(
            tip.nis.min <= tip.nis.mean && tip.nis.mean <= tip.nis.max,
            "{f} Hz: {tip:?}"
        );
    }
}
