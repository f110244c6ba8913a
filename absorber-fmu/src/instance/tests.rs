use super::*;
use crate::config::{Config, Kind};
use absorber_core::monitor::DetailCategory;
use std::sync::{Arc, Mutex};

type Messages = Arc<Mutex<Vec<(Status, String)>>>;

struct Capture(Messages);
impl Log for Capture {
    fn log(&self, status: Status, _: &str, message: &str) {
        if let Ok(mut v) = self.0.lock() {
            v.push((status, message.to_string()));
        }
    }
}

fn instance(kind: Kind, single: bool) -> (Instance, Messages) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let c = Config {
        name: "t".into(),
        kind,
        elements: 3,
        single,
        detail: DetailCategory::EPrime,
        stop_time: 1.0,
        params: Params::default(),
    };
    (
        Instance::new("t", c, false, Box::new(Capture(log.clone()))),
        log,
    )
}

fn started(kind: Kind, single: bool) -> Instance {
    let (mut i, _) = instance(kind, single);
    assert_eq!(i.enter_initialization(0.0), Status::Ok);
    assert_eq!(i.exit_initialization(), Status::Ok);
    i
}

fn tip(i: &mut Instance) -> f64 {
    let mut v = [0.0];
    assert_eq!(i.get_f64(&[10], &mut v), Status::Ok);
    v[0]
}

/// The instance steps the core exactly: 500 steps of the paper's free ball (f32 and f64)
/// under a sampled harmonic base acceleration give the plain `Model::step` run's tip
/// deflection bit for bit (the loaded scene with a zero tip load adds exact zeros).
#[test]
fn instance_steps_equal_the_core_bit_for_bit() {
    use absorber_core::FreeBallModel;
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let accel = |k: usize| -0.5e-3 * w * w * (w * k as f64 * 0.003).sin();
    let mut i = started(Kind::Free, false);
    let mut m = FreeBallModel::<f64, 3, 13>::at_rest(Params::default(), 0.0).expect("model");
    let mut i32_ = started(Kind::Free, true);
    let p32 = sim::cast_params::<f32>(&Params::default());
    let mut m32 = FreeBallModel::<f32, 3, 13>::at_rest(p32, 0.0).expect("model");
    for k in 1..=500 {
        let a = accel(k);
        for inst in [&mut i, &mut i32_] {
            assert_eq!(inst.set_f64(&[1], &[a]), Status::Ok);
            let t = inst.time();
            assert_eq!(inst.do_step(t, 0.003).0, Status::Ok);
        }
        m.step(a).expect("step");
        m32.step(a as f32).expect("step");
        assert_eq!(
            tip(&mut i).to_bits(),
            m.tip_deflection().to_bits(),
            "step {k}"
        );
        assert_eq!(
            tip(&mut i32_).to_bits(),
            f64::from(m32.tip_deflection()).to_bits()
        );
    }
}

/// A tip load switches the model to the loaded scene in mid-run without a jump: 200 steps
/// without, 300 with a tip load give the core's loaded model fed the same loads bit for bit.
#[test]
fn tip_load_continues_the_plain_run_bit_for_bit() {
    use absorber_core::{FreeBall, Loaded, Loads, Model};
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let accel = |k: usize| -0.5e-3 * w * w * (w * k as f64 * 0.003).sin();
    let load = |k: usize| {
        if k > 200 {
            0.05 * (0.7 * k as f64 * 0.003).sin()
        } else {
            0.0
        }
    };
    let mut i = started(Kind::Free, false);
    let mut m =
        Model::<f64, Loaded<FreeBall>, 3, 13>::at_rest(Params::default(), 0.0).expect("model");
    for k in 1..=500 {
        i.set_f64(&[1, 2], &[accel(k), load(k)]);
        let t = i.time();
        assert_eq!(i.do_step(t, 0.003).0, Status::Ok);
        m.step_with_loads(accel(k), &Loads::uniform(load(k), 0.0))
            .expect("step");
        assert_eq!(
            tip(&mut i).to_bits(),
            m.tip_deflection().to_bits(),
            "step {k}"
        );
    }
}

/// A communication step that is not k·h is refused with `Discard` and a message, and
/// nothing happens; 3h runs three steps.
#[test]
fn wrong_communication_steps_are_refused() {
    let (mut i, log) = instance(Kind::Locked, false);
    i.enter_initialization(0.0);
    i.exit_initialization();
    assert_eq!(i.do_step(0.0, 0.004).0, Status::Discard);
    assert_eq!(i.time(), 0.0);
    let last = log.lock().map(|v| v.last().cloned()).ok().flatten();
    assert!(last.is_some_and(|(s, m)| s == Status::Discard && m.contains("h = 0.003")));
    assert_eq!(i.do_step(0.0, 0.009).0, Status::Ok);
    assert!((i.time() - 0.009).abs() < 1e-15);
    assert_eq!(i.do_step(0.0, 0.003).0, Status::Discard, "wrong start time");
}

/// A bad parameter fails initialization with the field's name and value in the log.
#[test]
fn bad_parameters_are_named() {
    let (mut i, log) = instance(Kind::Free, false);
    assert_eq!(i.set_f64(&[103], &[-1.0]), Status::Ok);
    i.enter_initialization(0.0);
    assert_eq!(i.exit_initialization(), Status::Error);
    let msgs = log.lock().map(|v| v.clone()).unwrap_or_default();
    assert!(
        msgs.iter().any(|(_, m)| m.contains("`beam.modulus` = -1")),
        "{msgs:?}"
    );
    let (mut i, log) = instance(Kind::Free, false);
    i.enter_initialization(0.0);
    i.exit_initialization();
    i.set_f64(&[1], &[f64::NAN]);
    assert_eq!(i.do_step(0.0, 0.003).0, Status::Error);
    let msgs = log.lock().map(|v| v.clone()).unwrap_or_default();
    assert!(msgs.iter().any(|(_, m)| m.contains("`base_acceleration`")));
}

/// A state taken, serialized and read back continues bit for bit, in this instance and
/// in another one of the same FMU.
#[test]
fn serialized_state_continues_bit_for_bit() {
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let accel = |k: usize| -2e-3 * w * w * (w * k as f64 * 0.003).sin();
    let mut a = started(Kind::Free, true);
    for k in 1..=300 {
        a.set_f64(&[1], &[accel(k)]);
        let t = a.time();
        a.do_step(t, 0.003);
    }
    let s = a.snapshot();
    let mut bytes = vec![0u8; a.serialized_size(&s)];
    assert_eq!(a.serialize(&s, &mut bytes), Status::Ok);
    let run = |i: &mut Instance| -> Vec<u64> {
        (301..=900)
            .map(|k| {
                i.set_f64(&[1], &[accel(k)]);
                let t = i.time();
                i.do_step(t, 0.003);
                let mut v = [0.0; 3];
                i.get_f64(&[10, 12, 16], &mut v);
                v.iter().fold(0u64, |h, x| h.rotate_left(7) ^ x.to_bits())
            })
            .collect()
    };
    let first = run(&mut a);
    let (mut b, _) = instance(Kind::Free, true);
    let back = b.deserialize(&bytes).expect("deserializes");
    b.restore(&back);
    assert_eq!(run(&mut b), first);
    let back = a.deserialize(&bytes).expect("deserializes");
    a.restore(&back);
    assert_eq!(run(&mut a), first);
    bytes[0] ^= 1;
    assert!(a.deserialize(&bytes).is_err());
}
