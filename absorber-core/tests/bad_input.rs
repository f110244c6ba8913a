//! Bad input is an error naming the field; a bad step input leaves the state as it was.

use absorber_core::{BeamModel, Error, FreeBallModel, LockedBallModel, Model, Params};

fn field_of(e: Error) -> &'static str {
    match e {
        Error::InvalidParameter { field, .. } => field,
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

fn rejects(change: impl Fn(&mut Params<f64>), field: &str) {
    let mut p = Params::<f64>::default();
    change(&mut p);
    let e = FreeBallModel::<f64, 3, 13>::new(p)
        .err()
        .unwrap_or_else(|| panic!("{field} accepted"));
    assert_eq!(field_of(e), field);
    assert!(
        e.to_string().contains(field),
        "message names the field: {e}"
    );
}

#[test]
fn every_bad_parameter_is_rejected_with_its_name() {
    rejects(|p| p.beam.length = 0.0, "beam.length");
    rejects(|p| p.beam.mass = -1.0, "beam.mass");
    rejects(|p| p.beam.area = f64::NAN, "beam.area");
    rejects(|p| p.beam.modulus = f64::INFINITY, "beam.modulus");
    rejects(|p| p.beam.inertia = 0.0, "beam.inertia");
    rejects(|p| p.tip.mass = 0.0, "tip.mass");
    rejects(|p| p.tip.inertia = -1e-5, "tip.inertia");
    rejects(|p| p.tip.offset = f64::NAN, "tip.offset");
    rejects(|p| p.ball.mass = 0.0, "ball.mass");
    rejects(|p| p.ball.inertia = -1.0, "ball.inertia");
    rejects(|p| p.ball.radius = 0.0, "ball.radius");
    rejects(|p| p.ball.track_radius = 0.005, "ball.track_radius");
    rejects(|p| p.ball.stop_angle = 4.0, "ball.stop_angle");
    rejects(|p| p.ball.restitution = 1.5, "ball.restitution");
    rejects(|p| p.ball.stick_speed = -0.1, "ball.stick_speed");
    rejects(|p| p.ball.initial_angle = 2.0, "ball.initial_angle");
    rejects(|p| p.integrator.gamma = 0.4, "integrator.gamma");
    // Generalized-α (Chung & Hulbert's stability conditions).
    rejects(|p| p.integrator.alpha_f = 0.6, "integrator.alpha_f");
    rejects(|p| p.integrator.alpha_f = f64::NAN, "integrator.alpha_f");
    rejects(|p| p.integrator.alpha_m = 0.1, "integrator.alpha_m");
    rejects(
        |p| p.integrator = p.integrator.generalized_alpha(1.5),
        "integrator.alpha_f",
    );
    rejects(
        |p| {
            p.integrator = p.integrator.generalized_alpha(0.8);
            p.integrator.gamma = 0.55;
        },
        "integrator.gamma",
    );
    rejects(|p| p.integrator.beta = 0.2, "integrator.beta");
    rejects(|p| p.integrator.step = 0.0, "integrator.step");
    rejects(
        |p| p.integrator.tolerance = f64::NAN,
        "integrator.tolerance",
    );
    rejects(
        |p| p.integrator.max_iterations = 0,
        "integrator.max_iterations",
    );
    rejects(
        |p| p.damping.stiffness_proportional = -1.0,
        "damping.stiffness_proportional",
    );
    rejects(|p| p.gravity = f64::NAN, "gravity");
}

/// A beam-only model neither needs nor checks the tip and ball parameters.
#[test]
fn a_scene_validates_only_what_it_contains() {
    let mut p = Params::<f64>::default();
    p.tip.mass = -1.0;
    p.ball.radius = f64::NAN;
    assert!(BeamModel::<f64, 3, 12>::new(p).is_ok());
    assert_eq!(
        field_of(LockedBallModel::<f64, 3, 12>::new(p).unwrap_err()),
        "tip.mass"
    );
}

/// The default parameters are the paper's Table 1, and f32 accepts γ = 0.7, β = 0.36 (on the
/// stability boundary β = (γ + ½)²/4 after rounding).
#[test]
fn table_1_defaults_are_valid_in_both_precisions() {
    let p = Params::<f64>::default();
    assert_eq!(
        (p.beam.length, p.beam.mass, p.beam.area, p.beam.modulus),
        (0.365, 0.116, 4.06e-5, 200e9)
    );
    assert_eq!(
        (p.tip.mass, p.tip.inertia, p.tip.offset),
        (0.1154, 1.871e-5, 0.0204)
    );
    assert_eq!(
        (
            p.ball.mass,
            p.ball.inertia,
            p.ball.radius,
            p.ball.track_radius
        ),
        (0.014, 3.15e-7, 0.0075, 0.0395)
    );
    assert_eq!(
        (p.integrator.gamma, p.integrator.beta, p.integrator.step),
        (0.7, 0.36, 0.003)
    );
    assert!(FreeBallModel::<f32, 3, 13>::new(Params::default()).is_ok());
}

/// A non-finite base acceleration is rejected and the state is bit-for-bit unchanged; the next
/// good sample continues as if the bad one never came.
#[test]
fn non_finite_input_is_rejected_and_the_state_kept() {
    let mut m: FreeBallModel<f32, 3, 13> = Model::at_rest(Params::default(), 0.0).unwrap();
    let mut twin = m.clone();
    for k in 0..100 {
        m.step(0.3 * (k as f32 * 0.1).sin()).unwrap();
        twin.step(0.3 * (k as f32 * 0.1).sin()).unwrap();
    }
    let before = *m.state();
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(m.step(bad), Err(Error::NonFiniteInput));
        assert_eq!(*m.state(), before);
    }
    m.step(0.5).unwrap();
    twin.step(0.5).unwrap();
    assert_eq!(m.state(), twin.state());
}

/// A step that cannot converge within the iteration budget (1 iteration, a violent input)
/// returns `NoConvergence` and leaves the state exactly as it was.
#[test]
fn failed_step_returns_an_error_and_keeps_the_state() {
    let good: FreeBallModel<f64, 3, 13> = Model::at_rest(Params::default(), 0.0).unwrap();
    let mut p = Params::<f64>::default();
    p.integrator.max_iterations = 1;
    let mut m: FreeBallModel<f64, 3, 13> = Model::new(p).unwrap();
    m.set_state(*good.state());
    let before = *m.state();
    let e = m.step(5000.0).unwrap_err();
    assert!(
        matches!(e, Error::NoConvergence { iterations: 1, .. }),
        "{e:?}"
    );
    assert_eq!(*m.state(), before);
}

/// A work cap above `work::UNLIMITED` is refused by name. Before, the C API took
/// `max_work` = 2,041,904,906 with `max_iterations` = 554,223,915 (a fuzz input, 10⁻⁹ of the
/// beam's length): one step ran for minutes.
#[test]
fn work_cap_above_unlimited_is_refused_by_name() {
    let mut p = Params::<f64>::default();
    p.integrator.max_work = absorber_core::work::UNLIMITED;
    assert!(FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).is_ok());
    p.integrator.max_work = 2_041_904_906;
    p.integrator.max_iterations = 554_223_915;
    match FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0) {
        Err(Error::InvalidParameter { field, .. }) => assert_eq!(field, "integrator.max_work"),
        other => panic!("{other:?}"),
    }
}
