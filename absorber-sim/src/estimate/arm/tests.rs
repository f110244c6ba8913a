use super::*;

fn scene(name: &str) -> Scene {
    Scene::load(&format!("{}/../scenes/{name}", env!("CARGO_MANIFEST_DIR"))).expect("scene")
}

fn find<'a>(r: &'a TwinReport, estimator: &str, sensors: &[&str]) -> &'a EstimatorReport {
    r.estimators
        .iter()
        .find(|e| e.estimator == estimator && e.sensors == sensors)
        .unwrap_or_else(|| panic!("no {estimator} {sensors:?}"))
}

/// The mast arm's N = 3 model calibrated on f₁ and f₂ of the truth (full solver, 16
/// elements): both to 1e-8 (the fit's own tolerance, 1e-9, plus the eigen-solve), and what
/// was not fitted follows: f₃ within 0.5 % of the truth's (measured +0.24 %; −1.9 % with
/// the E·I factor alone) and the second mode's root stress per tip acceleration within 1 %
/// of the 16-element core arm's (stress factor measured 0.998; 0.980 with the factor
/// alone). Why the gradient and not the mass blend: lumping lowers f₂/f₁ (measured
/// 4.496 → 4.429 at μ = 0.1), and the f₁-only model's 4.496 is already below the truth's
/// 4.578.
#[test]
fn the_arm_model_calibrated_on_f1_and_f2_gets_f3_and_the_second_mode_stress() {
    let a = ArmScene::of(&scene("mast-arm.toml")).expect("arm");
    let mut pt = a.params;
    pt.integrator.tolerance = TRUTH_TOLERANCE;
    let f = absorber_full::FullSolver::arm_at_rest(
        pt,
        absorber_full::SceneKind::BeamOnly,
        TRUTH_ELEMENTS,
        &a.arm,
        0.0,
    )
    .expect("truth")
    .frequencies()
    .expect("modes");
    let c = calibrate_arm(&a.params, &a.arm, (f[0], f[1])).expect("calibration");
    assert!(
        c.bending_gradient > 0.0 && c.bending_gradient < 0.5,
        "{c:?}"
    );
    let mut p = a.params;
    p.calibration = c;
    let model = ArmModel::<f64>::arm_at_rest(p, &a.arm, 0.0).expect("model");
    let g = model.natural_frequencies().expect("modes");
    for i in 0..2 {
        assert!(
            (g[i] / f[i] - 1.0).abs() < 1e-8,
            "f{}: {} vs {}",
            i + 1,
            g[i],
            f[i]
        );
    }
    assert!((g[2] / f[2] - 1.0).abs() < 5e-3, "f3: {} vs {}", g[2], f[2]);
    let section = root_section(&a.params, &a.arm).expect("section");
    let reference = ArmReference::arm_at_rest(a.params, &a.arm, 0.0).expect("reference");
    let theirs = filter::modal_stress_ratios(&reference, &section).expect("ratios");
    let ours = filter::modal_stress_ratios(&model, &section).expect("ratios");
    let second = theirs.0[1] / ours.0[1];
    assert!(
        (second - 1.0).abs() < 0.01,
        "second-mode stress factor {second}"
    );
    let mut only_b = a.params;
    only_b.calibration.bending_stiffness = calibrate_bending(&a.params, &a.arm, f[0]).expect("f1");
    let (b1, b2) = reduced_pair(&only_b, &a.arm).expect("pair");
    let mut lumped = only_b;
    lumped.calibration.mass_lumping = 0.1;
    let (l1, l2) = reduced_pair(&lumped, &a.arm).expect("pair");
    assert!(
        b2 / b1 < f[1] / f[0] && l2 / l1 < b2 / b1,
        "{b1} {b2} {l1} {l2}"
    );
}

/// The mast arm under first-mode wind (10 min: gusts, trucks, three vortex-shedding
/// episodes at f1), truth = full solver (16 elements, f64): the extended Kalman filter on
/// the tip accelerometer has a Miner damage ratio within 0.9–1.1 (measured 0.997: the
/// first mode's stress factor 0.967 corrects the model's stress recovery, which the
/// constant-gain filter lacks) and a stress RMS error ≤ 5 % (measured 2.5 %). The model is
/// right here: the mean NIS of a consistent filter, 0.5–2 (measured 0.52, with the strain
/// gauge 0.84; ε matched on 16 pooled draws of the calibration load — on one draw the
/// tip accelerometer's NIS is 0.27–0.59 over seeds 1–8). The constant-gain baseline is
/// pinned as measured with the model calibrated on f1 and f2 (3.8 %, 1.103; with f1 alone
/// 3.1 %, 1.076; before the end sign was modelled 5.0 %, 0.867).
#[test]
fn ekf_removes_the_first_mode_damage_bias() {
    let (r, s) = twin(
        &scene("mast-arm.toml"),
        600.0,
        constant::BaselineLoad::default(),
    )
    .expect("twin");
    assert_eq!(s.time.len(), 60_000);
    let tip = find(&r, "ekf", &["tip_accel"]);
    assert_eq!(tip.failed, 0);
    assert!((0.9..=1.1).contains(&tip.damage_ratio), "{tip:?}");
    assert!(tip.stress_rms_error_pct <= 5.0, "{tip:?}");
    assert!((0.5..=2.0).contains(&tip.nis), "{tip:?}");
    let both = find(&r, "ekf", &["tip_accel", "root_strain"]);
    assert!((0.9..=1.1).contains(&both.damage_ratio), "{both:?}");
    assert!((0.5..=2.0).contains(&both.nis), "{both:?}");
    let before = find(&r, "constant-gain", &["tip_accel"]);
    assert!((before.damage_ratio - 1.103).abs() < 0.005, "{before:?}");
    assert!(
        (before.stress_rms_error_pct - 3.8).abs() < 0.1,
        "{before:?}"
    );
}

/// Second-mode vortex lock-in (4.70 Hz at 19.6 m/s, three episodes): with a ±8 g
/// accelerometer (no clipping) the filter meets ≤ 15 % and a damage ratio of 0.8–1.25
/// (measured 2.0 %, 0.998; with the strain gauge 0.7 %, 0.993) with a consistent NIS
/// (0.5–2, measured 0.96) — with the model calibrated on f1 and f2; calibrated on f1 alone
/// its second mode sat 1.8 % low, beside the forcing, and the filter was 20.9 % off with a
/// damage ratio of 0.630. With the shipped ±2 g part, which clips 28 % of the readings,
/// the clipped readings are detected and the verdict is never `ok` — the constant-gain
/// baseline's included (86.7 % off: `failed`).
#[test]
fn second_mode_lock_in_is_estimated_and_clipping_is_flagged() {
    let (r, _) = twin(
        &scene("mast-arm-second-mode.toml"),
        600.0,
        constant::BaselineLoad::default(),
    )
    .expect("twin");
    let tip = find(&r, "ekf", &["tip_accel"]);
    assert!(tip.stress_rms_error_pct <= 15.0, "{tip:?}");
    assert!((0.8..=1.25).contains(&tip.damage_ratio), "{tip:?}");
    assert!((0.5..=2.0).contains(&tip.nis), "{tip:?}");
    assert_eq!(tip.clipped, [0, 0, 0]);
    let (r, _) = twin(
        &scene("mast-arm-second-mode-2g.toml"),
        600.0,
        constant::BaselineLoad::default(),
    )
    .expect("twin");
    assert_ne!(r.verdict, "ok");
    assert!(r.clipped_pct > 20.0, "{}", r.clipped_pct);
    for e in r
        .estimators
        .iter()
        .filter(|e| e.sensors.contains(&"tip_accel"))
    {
        assert_ne!(e.verdict, "ok", "{e:?}");
        assert!(e.clipped[0] > 0, "{e:?}");
    }
}

/// Measurement, not a check (`cargo test --release -p absorber-sim --lib
/// calibration_draw_spread -- --ignored --nocapture`, a few minutes): the model error ε
/// matched on one draw of the calibration load against K pooled draws, and the tip
/// accelerometer's mean NIS on the 10 min study with it — the spread over draws that
/// docs/monitoring.md ("One draw is not enough") quotes and `ARM_CALIBRATION_DRAWS` rests on.
#[test]
#[ignore = "measurement (prints the spread of ε over calibration draws; minutes)"]
fn calibration_draw_spread() {
    for name in ["mast-arm.toml", "mast-arm-second-mode.toml"] {
        let a = ArmScene::of(&scene(name)).expect("arm");
        let params = a.params;
        let h = params.integrator.step;
        let steps = (600.0 / h).round() as usize;
        let (truth, f_truth) =
            truth(&a, steps, &|t| a.loads.sample(t, TRUTH_ELEMENTS)).expect("truth");
        let section = root_section(&params, &a.arm).expect("section");
        let mut pc = params;
        pc.calibration = calibrate_arm(&params, &a.arm, f_truth).expect("calibration");
        pc.integrator.tolerance = super::super::ESTIMATOR_TOLERANCE;
        let window = (1.0 / h).round() as u32;
        let m = filter::measure(&truth, &a.specs, h, 1).expect("readings");
        let mut sets: Vec<(String, Vec<u64>)> =
            vec![("one draw, 0x5EED".into(), vec![filter::CALIBRATION_SEED])];
        for k in 1..=8u64 {
            sets.push((format!("one draw, seed {k}"), vec![k]));
        }
        for k in [4u64, 8, 16] {
            let from = filter::CALIBRATION_SEED;
            sets.push((format!("K = {k} from 0x5EED"), (from..from + k).collect()));
            // Disjoint sets of seeds from 1 (as quoted in the docs: 4, 3 and 2 sets).
            for j in 0..(16 / k + 1).min(4) {
                let first = 1 + j * k;
                sets.push((
                    format!("K = {k} from {first}"),
                    (first..first + k).collect(),
                ));
            }
        }
        for (label, seeds) in sets {
            let s = setup(&a, &pc, &section, window, &seeds).expect("setup");
            let tip = run_filter(&pc, &a, &s, &section, &m, &[SensorKind::TipAccel], &truth)
                .expect("filter");
            println!(
                "{name}, {label}: ε {:.4}, tip accelerometer NIS {:.3}, {:.2} %, damage {:.3}",
                s.model_error,
                tip.report.nis,
                tip.report.stress_rms_error_pct,
                tip.report.damage_ratio
            );
        }
    }
}
