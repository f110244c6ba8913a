use super::*;

/// Every field name the checks of this file can report has its value in
/// [`Params::value_of`] (the names are read from the checks' source, so a new check with a
/// name missing from the table fails here).
#[test]
fn every_checked_field_has_its_value() {
    let src = include_str!("mod.rs");
    let checks = &src[..src
        .find("impl<T: Real> Params<T> {\n    /// The value of")
        .unwrap()];
    let p = Params::<f64>::default();
    let mut names = 0;
    for (i, _) in checks.match_indices('"') {
        let rest = &checks[i + 1..];
        let Some(end) = rest.find('"') else { break };
        let name = &rest[..end];
        let before = checks[..i].trim_end();
        let is_field = before.ends_with("field:") || rest[end + 1..].starts_with(')');
        if is_field && name.contains('.') || name == "gravity" {
            assert!(
                p.value_of(name).is_some(),
                "`{name}` has no value in `value_of`"
            );
            names += 1;
        }
    }
    assert!(names >= 33, "{names} names found");
    assert_eq!(p.value_of("elements"), None);
}

/// A rejected parameter's value is the one that was set, NaN and counts included.
#[test]
fn value_of_a_rejected_field_is_the_value_set() {
    type Set = fn(&mut Params<f32>);
    let cases: [(Set, f32); 6] = [
        (|p| p.beam.modulus = -2.5e9, -2.5e9),
        (
            |p| {
                p.ball.radius = 0.02;
                p.ball.track_radius = 0.01;
            },
            0.01,
        ),
        (|p| p.ball.initial_angle = 3.0, 3.0),
        (|p| p.integrator.tolerance = 1e-9, 1e-9),
        (|p| p.integrator.max_iterations = 0, 0.0),
        (|p| p.gravity = f32::NAN, f32::NAN),
    ];
    for (set, value) in cases {
        let mut p = Params::<f32>::default();
        set(&mut p);
        let Err(Error::InvalidParameter { field, .. }) = p.validate(true, true) else {
            panic!("accepted: {value}");
        };
        let v = p.value_of(field).unwrap();
        assert!(v == value || v.is_nan() && value.is_nan(), "{field}: {v}");
    }
}
