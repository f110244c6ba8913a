//! A state that is not finite (restored from corrupted storage through `Model::set_state`) is
//! reported as such by the next step, `Error::NonFiniteState`, with the state kept as it was,
//! in both precisions; a run of such steps ends in the recovery restart at rest.

use absorber_core::scalar::{lit, to_f64};
use absorber_core::{Error, FreeBallModel, Model, Outcome, Params, Real};

fn nan_in_state<T: Real>(which: usize) {
    let mut m: FreeBallModel<T, 3, 13> = Model::at_rest(Params::default(), T::zero()).unwrap();
    let mut s = *m.state();
    match which {
        0 => s.q[4] = lit(f64::NAN),
        1 => s.v[0] = lit(f64::NAN),
        _ => s.a[12] = lit(f64::INFINITY),
    }
    m.set_state(s);
    let a = lit(0.1);
    let e = m.step(a).err();
    assert_eq!(e, Some(Error::NonFiniteState), "entry {which}");
    // Kept bit for bit (NaN != NaN: compare the bits).
    let bits = |x: &absorber_core::State<T, 13>| {
        x.q.iter()
            .chain(x.v.iter())
            .chain(x.a.iter())
            .map(|z| to_f64(*z).to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(m.state()), bits(&s));
    assert_eq!(m.step(a).err(), Some(Error::NonFiniteState));
    // The third failure in a row restarts the model at rest: finite again.
    let r = m.step(a).unwrap();
    assert_eq!(r.outcome, Outcome::Restarted);
    assert!(m.state().q.iter().all(|z| z.is_finite()));
}

#[test]
fn nan_in_the_state_is_a_non_finite_state_f64() {
    for which in 0..3 {
        nan_in_state::<f64>(which);
    }
}

#[test]
fn nan_in_the_state_is_a_non_finite_state_f32() {
    for which in 0..3 {
        nan_in_state::<f32>(which);
    }
}
