//! A measured base acceleration processed as strong-motion records are: the base starts and
//! ends at rest, a record that already does is kept, and energies are measured from rest.

use absorber_sim::excitation::Excitation;
use std::f64::consts::{PI, TAU};

/// A 20 ms half-sine of `peak` m/s² at 0.5 s, 1 ms samples, `len` s: a velocity change of
/// 2·peak·0.02/π that, integrated as it stands, makes the base drift forever.
fn pulse(peak: f64, len: f64) -> String {
    let mut text = String::from("t,accel\n");
    for k in 0..=(len * 1e3).round() as usize {
        let t = k as f64 * 1e-3;
        let a = if (0.5..=0.52).contains(&t) {
            peak * (PI * (t - 0.5) / 0.02).sin()
        } else {
            0.0
        };
        text.push_str(&format!("{t},{a}\n"));
    }
    text
}

#[test]
fn a_pulse_leaves_the_base_at_rest_where_it_started() {
    let h = 0.0025;
    let n = 8000; // 20 s
    let e = Excitation::from_csv_text(&pulse(5.0, 20.5), h, Some(n)).unwrap();
    let dv = 2.0 * 5.0 * 0.02 / PI; // 63.7 mm/s
    let b0 = e.at(0);
    assert_eq!((b0.velocity, b0.displacement), (0.0, 0.0));
    // The whole record (20.5 s) ends at rest.
    let all = Excitation::from_csv_text(&pulse(5.0, 20.5), h, None).unwrap();
    let end = all.at(all.samples().unwrap() - 1);
    assert!(
        end.velocity.abs() < 1e-12 && end.displacement.abs() < 1e-12,
        "{end:?}"
    );
    // Never faster than the pulse made it.
    let vmax = (0..=n).map(|k| e.at(k).velocity.abs()).fold(0.0, f64::max);
    assert!(vmax < 1.01 * dv, "{vmax} vs {dv}");
    // Just after the pulse the base moves with (nearly) the pulse's velocity change: the
    // high-pass at 0.1 Hz takes it back over seconds, not during the 20 ms.
    let after = e.at((0.53 / h) as usize).velocity - e.at((0.49 / h) as usize).velocity;
    assert!((after / dv - 1.0).abs() < 0.02, "{after} vs {dv}");
    // Displacement bounded: at most the drift the pulse would make in 1/(2π f_c) = 1.6 s.
    let ymax = (0..=n)
        .map(|k| e.at(k).displacement.abs())
        .fold(0.0, f64::max);
    assert!(ymax < dv / (TAU * 0.1), "{ymax}");
}

/// A base motion that starts and ends at rest by itself (a 2 Hz burst under a sin² window,
/// 4 s) is kept: displacement, velocity and acceleration against the closed form, within 1 %
/// of their peaks (the 0.1 Hz high-pass passes 1.5–2.5 Hz with a gain above 0.9999).
#[test]
fn a_record_at_rest_at_both_ends_is_kept() {
    let (amp, w, span) = (1e-3, TAU * 2.0, 4.0);
    let p = PI / span;
    let y = |t: f64| amp * (w * t).sin() * (p * t).sin().powi(2);
    let v = |t: f64| {
        amp * (w * (w * t).cos() * (p * t).sin().powi(2) + (w * t).sin() * p * (2.0 * p * t).sin())
    };
    let a = |t: f64| {
        let (s, c) = ((w * t).sin(), (w * t).cos());
        let win = (p * t).sin().powi(2);
        amp * (-w * w * s * win
            + 2.0 * w * c * p * (2.0 * p * t).sin()
            + s * 2.0 * p * p * (2.0 * p * t).cos())
    };
    let mut text = String::from("# burst\nt,accel\n");
    for k in 0..=4000 {
        let t = k as f64 * 1e-3;
        text.push_str(&format!("{t},{}\n", a(t)));
    }
    let h = 5e-4;
    let e = Excitation::from_csv_text(&text, h, Some(8000)).unwrap();
    for k in (0..=8000).step_by(250) {
        let t = k as f64 * h;
        let b = e.at(k);
        assert!(
            (b.displacement - y(t)).abs() < 1e-2 * amp,
            "y({t}) = {}",
            b.displacement
        );
        assert!(
            (b.velocity - v(t)).abs() < 1e-2 * amp * w,
            "v({t}) = {}",
            b.velocity
        );
        assert!(
            (b.accel - a(t)).abs() < 1e-2 * amp * w * w,
            "a({t}) = {}",
            b.accel
        );
    }
}

/// The shipped pole (examples/pole.toml, 0.3 % damping) after the shipped tap (a 0.5 mm base
/// bump at 0.5 s): energies from rest are never negative (they were, when the integration
/// constants made the base's mean zero: it then sat below its start before and after), the
/// energy decays (the last 5 s hold less than the 5 s after the tap, and the end less than
/// 5 % of the peak), and the base ends where it started.
#[test]
fn energies_after_a_tap_are_positive_and_decay() {
    let scene = absorber_sim::scene::Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/pole.toml"
    ))
    .unwrap();
    let rows = absorber_sim::run::run_rows(&scene, |_| {}).unwrap();
    let total = |r: &absorber_sim::run::Row| r.energies.total();
    let e0 = total(&rows[0]);
    let e: Vec<(f64, f64)> = rows.iter().map(|r| (r.t, total(r) - e0)).collect();
    let peak = e.iter().map(|x| x.1).fold(0.0, f64::max);
    assert!(peak > 0.0);
    for &(t, x) in &e {
        assert!(x > -1e-6 * peak, "E({t}) = {x} (peak {peak})");
    }
    let mean = |lo: f64, hi: f64| {
        let w: Vec<f64> = e
            .iter()
            .filter(|x| x.0 >= lo && x.0 < hi)
            .map(|x| x.1)
            .collect();
        w.iter().sum::<f64>() / w.len() as f64
    };
    assert!(
        mean(15.0, 20.0) < mean(1.0, 6.0),
        "{} {}",
        mean(15.0, 20.0),
        mean(1.0, 6.0)
    );
    let last = rows.last().unwrap();
    assert!(total(last) - e0 < 0.05 * peak);
    assert!(last.base_y.abs() < 1e-7, "{}", last.base_y);
}
