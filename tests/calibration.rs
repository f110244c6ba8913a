//! Calibration of the reduced beam: a calibrated 3-element core model against the
//! converged full solver, the full solver with the same calibration against the core, the
//! identification of a pole from a synthetic noisy decay made by the full solver, and the
//! uncalibrated model bit for bit as before.

use absorber_core::{Calibration, FreeBallModel, LockedBall, LockedBallModel, Model, Params};
use absorber_full::sim::Simulator;
use absorber_full::{FullSolver, SceneKind};
use absorber_sim::calibrate::{fit, reference};
use absorber_sim::identify::{identify, Record, RecordKind};
use absorber_sim::scene::{Kind, Scene};

fn locked_scene() -> Scene {
    let mut s = Scene::paper();
    s.file.kind = Kind::Locked;
    s
}

/// The calibration `host-sim calibrate` fits for N = 3 against the full solver with N = 16.
fn calibration_n3() -> Calibration<f64> {
    let s = locked_scene();
    let (r, free) = reference(&s, 16).expect("reference");
    fit(&s, 3, &r, free).expect("fit").calibration
}

/// Calibrated core, N = 3, against the full solver, N = 16, uncalibrated (the converged model:
/// N = 12 and 16 agree in f₁ to 2e-6, docs/accuracy.md). Budgets (the calibration's targets): f₁ and f₂ of
/// the locked-ball beam within 0.05 %, static tip sag within 0.1 %; the free-ball beam mode is
/// fitted too and held to the f₁ budget. The fit itself reaches 5e-7 (printed); the budgets
/// leave room for a different but equally good optimum, not for a worse model. Uncalibrated,
/// N = 3 is +0.92 % in f₁, +2.4 % in f₂ and −0.79 % in sag.
#[test]
fn calibrated_n3_matches_full_solver_n16_f1_f2_within_0_05_percent_sag_within_0_1_percent() {
    let p = Params::<f64> {
        calibration: calibration_n3(),
        ..Default::default()
    };
    let core = LockedBallModel::<f64, 3, 12>::at_rest(p, 0.0).expect("core");
    let f = core.natural_frequencies().expect("modes");
    let sag = core.static_tip_deflection();
    let full =
        FullSolver::at_rest(Params::default(), SceneKind::LockedBall, 16, 0.0).expect("full");
    let fr = full.frequencies().expect("full modes");
    let sag_r = full.tip_deflection();
    let free = FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).expect("free core");
    let ff = free.natural_frequencies().expect("free modes");
    let full_free =
        FullSolver::at_rest(Params::default(), SceneKind::FreeBall, 16, 0.0).expect("full free");
    let ffr = full_free.frequencies().expect("full free modes");
    let e = |a: f64, b: f64| a / b - 1.0;
    let (e1, e2, es, ef) = (
        e(f[0], fr[0]),
        e(f[1], fr[1]),
        e(sag, sag_r),
        e(ff[1], ffr[1]),
    );
    println!(
        "calibrated N=3 vs full N=16: f1 {:+.2e}, f2 {:+.2e}, free-ball beam mode {:+.2e}, sag {:+.2e} ({:?})",
        e1, e2, ef, es, p.calibration
    );
    assert!(e1.abs() < 5e-4, "f1 {e1:e}");
    assert!(e2.abs() < 5e-4, "f2 {e2:e}");
    assert!(ef.abs() < 5e-4, "free-ball beam mode {ef:e}");
    assert!(es.abs() < 1e-3, "sag {es:e}");
}

/// One source of truth: the full solver applies the calibration to the same element
/// (`Element::of_beam`, `blended_mass_matrix`), so the calibrated full solver and the calibrated
/// core, both N = 3, agree as the uncalibrated ones do (tests/full_vs_core.rs): frequencies and
/// sag to 1e-9 relative (eigenvalue rounding), and the tip over 5 s of the locked resonance to
/// `tol·L / 100` = 3.65e-8 m (the same budget as the uncalibrated test, and why).
#[test]
fn calibrated_full_solver_agrees_with_calibrated_core() {
    let p = Params::<f64> {
        calibration: calibration_n3(),
        ..Default::default()
    };
    let mut core = Model::<f64, LockedBall, 3, 12>::at_rest(p, 0.0).expect("core");
    let mut full = FullSolver::at_rest(p, SceneKind::LockedBall, 3, 0.0).expect("full");
    let (fc, ff) = (
        core.natural_frequencies().expect("core modes"),
        full.frequencies().expect("full modes"),
    );
    for k in 0..2 {
        assert!(
            (fc[k] / ff[k] - 1.0).abs() < 1e-9,
            "mode {k}: {} vs {}",
            fc[k],
            ff[k]
        );
    }
    let (sc, sf) = (core.static_tip_deflection(), full.tip_deflection());
    assert!((sc / sf - 1.0).abs() < 1e-9, "sag {sc} vs {sf}");
    let h = p.integrator.step;
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let mut worst: f64 = 0.0;
    for k in 1..=(5.0 / h).round() as usize {
        let u = -0.5e-3 * w * w * (w * k as f64 * h).sin();
        core.step(u).expect("core step");
        full.step(u).expect("full step");
        worst = worst.max((core.tip_deflection() - full.tip_deflection()).abs());
    }
    println!("calibrated N=3, core vs full, 5 s at 4.13 Hz: max |Δy_tip| = {worst:.3e} m");
    assert!(
        worst <= 0.01 * p.integrator.tolerance * p.beam.length,
        "{worst:e}"
    );
}

/// Identification from a synthetic free decay of the full solver (N = 8, locked ball): a 0.2 s
/// half-sine base pulse, then 25 s of free decay at h = 1 ms with the trapezoidal rule
/// (γ = ½, β = ¼: no numerical damping; its period error (ωh)²/12 = 6e-5) and structural
/// damping ζ = 0.3 % at f₁ (`C = c K_t`, c = 2ζ/ω₁). The record is the absolute tip
/// acceleration plus white noise of 5 % of its peak. Reference: f₁ from the full solver's
/// `frequencies()`; ζ₁ = c ω₁ / 2, which is exact for a mode whose stiffness is all bending
/// and ~1 % high here (gravity and the axial prestress carry a little of the stiffness but not
/// of the damping). Budgets (identification's targets): f₁ within 0.2 %, ζ within 10 %; the stated
/// uncertainties must cover the error (3σ).
#[test]
fn identification_recovers_f1_within_0_2_percent_and_zeta_within_10_percent_from_full_solver_decay()
{
    let mut p = Params::<f64>::default();
    let n = 8;
    let f1 = FullSolver::at_rest(p, SceneKind::LockedBall, n, 0.0)
        .expect("full")
        .frequencies()
        .expect("modes")[0];
    let zeta = 0.003;
    let h = 0.001;
    p.integrator.gamma = 0.5;
    p.integrator.beta = 0.25;
    p.integrator.step = h;
    p.integrator.tolerance = 1e-9;
    p.damping = absorber_core::Damping::from_ratio(zeta, f1);
    let mut full = FullSolver::at_rest(p, SceneKind::LockedBall, n, 0.0).expect("full");
    let (pulse, amp) = (0.2, 2.0); // s, m/s²
    let steps = (25.0 / h) as usize;
    let mut accel = Vec::with_capacity(steps);
    let mut prev_v = 0.0;
    for k in 1..=steps {
        let t = k as f64 * h;
        let u = if t < pulse {
            amp * (std::f64::consts::PI * t / pulse).sin()
        } else {
            0.0
        };
        full.step(u).expect("step");
        // Absolute tip acceleration: the rate of the relative velocity plus the base's.
        let v = full.observe().tip_velocity;
        accel.push((v - prev_v) / h + u);
        prev_v = v;
    }
    // Deterministic white noise (xorshift), uniform with RMS 5 % of the peak / √3.
    let peak = accel.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    for x in accel.iter_mut() {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        *x += 0.05 * peak * ((seed as f64 / u64::MAX as f64) * 2.0 - 1.0);
    }
    let rec = Record {
        dt: h,
        t0: h,
        x: accel,
    };
    let id = identify(&rec, RecordKind::Decay, None, "tip_acceleration").expect("identify");
    let (ef, ez) = (id.f1 / f1 - 1.0, id.zeta / zeta - 1.0);
    println!(
        "identified f1 = {:.5} ± {:.5} Hz (model {f1:.5}, error {:+.3} %), zeta = {:.5} ± {:.5} (set {zeta}, error {:+.1} %)",
        id.f1,
        id.f1_uncertainty,
        100.0 * ef,
        id.zeta,
        id.zeta_uncertainty,
        100.0 * ez
    );
    assert!(ef.abs() < 2e-3, "f1 error {ef:e}");
    assert!(ez.abs() < 0.1, "zeta error {ez:e}");
    assert!((id.f1 - f1).abs() < 3.0 * id.f1_uncertainty + 1e-4 * f1);
}

fn fnv(h: &mut u64, x: u64) {
    for b in x.to_le_bytes() {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// FNV-1a of every step's iterations and q, v, a bits over 3000 steps of the paper's base
/// motion: free ball in `f32`, locked ball in `f64`, both N = 3, default parameters but the
/// ball held on its track (`ball.flight = false`, the model the hashes were recorded with; the
/// ball leaves the track after 3.3 s in this run with flight on).
fn run_hashes(steps: usize) -> (u64, u64) {
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let accel = |k: usize| -0.5e-3 * w * w * (w * k as f64 * 0.003).sin();
    let mut h32 = 0xcbf2_9ce4_8422_2325u64;
    let mut rolling = Params::default();
    rolling.ball.flight = false;
    let mut m: FreeBallModel<f32, 3, 13> = FreeBallModel::at_rest(rolling, 0.0).expect("free");
    for k in 1..=steps {
        let r = m.step(accel(k) as f32).expect("step");
        fnv(&mut h32, u64::from(r.iterations));
        let s = m.state();
        for x in s.q.iter().chain(s.v.iter()).chain(s.a.iter()) {
            fnv(&mut h32, u64::from(x.to_bits()));
        }
    }
    let mut h64 = 0xcbf2_9ce4_8422_2325u64;
    let mut m: LockedBallModel<f64, 3, 12> =
        LockedBallModel::at_rest(Params::default(), 0.0).expect("locked");
    for k in 1..=steps {
        let r = m.step(accel(k)).expect("step");
        fnv(&mut h64, u64::from(r.iterations));
        let s = m.state();
        for x in s.q.iter().chain(s.v.iter()).chain(s.a.iter()) {
            fnv(&mut h64, x.to_bits());
        }
    }
    (h32, h64)
}

/// Without a calibration the model is bit for bit the one without the calibration code: the
/// pinned hashes are those of the same runs on a core without it, carried forward only through
/// changes of the model's law, never of the calibration (each re-pinning is in the history of
/// this test, with the change of law that moved it: the stops' impulse metric, the beam's
/// accelerations at a stop crossing, the start from rest; docs/model.md).
#[test]
fn uncalibrated_run_is_bit_identical_to_before_calibration() {
    assert!(Params::<f64>::default().calibration.is_identity());
    assert_eq!(
        run_hashes(3000),
        (0x238d_c5ef_e5cd_5313, 0xe1b6_710a_e8f4_349e)
    );
}

/// Bad calibration factors are errors naming the field, never a panic or a silent NaN.
#[test]
fn bad_calibration_is_an_error_naming_the_field() {
    for (field, c) in [
        (
            "calibration.bending_stiffness",
            Calibration {
                bending_stiffness: f64::NAN,
                ..Calibration::default()
            },
        ),
        (
            "calibration.bending_stiffness",
            Calibration {
                bending_stiffness: 3.0,
                ..Calibration::default()
            },
        ),
        (
            "calibration.axial_stiffness",
            Calibration {
                axial_stiffness: 0.0,
                ..Calibration::default()
            },
        ),
        (
            "calibration.mass_lumping",
            Calibration {
                mass_lumping: -0.1,
                ..Calibration::default()
            },
        ),
    ] {
        let p = Params::<f64> {
            calibration: c,
            ..Default::default()
        };
        match LockedBallModel::<f64, 3, 12>::at_rest(p, 0.0) {
            Err(absorber_core::Error::InvalidParameter { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {:?}", other.map(|_| ())),
        }
    }
}
