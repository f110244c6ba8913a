//! `modes` and `static` on an arm scene describe the arm (the tapered tube with its heads), as
//! `tune` does, not the uniform `[beam]`: against Euler–Bernoulli closed forms of the same arm.

use std::process::Command;

fn json(args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("host-sim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

/// scenes/mast-arm.toml's arm: a steel tube tapering linearly from 330 to 134.5 mm, wall
/// 4.55 mm, 16.76 m, with heads of 30, 30, 30 and 10 kg at 7, 11, 15 and 16.76 m. Linear
/// Euler–Bernoulli by quadrature: the static deflection w(x) = ∫ M(s)(x − s)/EI(s) ds under
/// gravity (self weight and heads), and Rayleigh's quotient on that shape,
/// ω² = g Σ m w / Σ m w² (an upper bound, within about 1 % for a cantilever's first mode).
/// Returns (tip deflection [m], f1 [Hz]).
fn closed_form() -> (f64, f64) {
    let (l, e, rho, dr, dt, t, g) = (16.76, 200e9, 7850.0, 0.330, 0.1345, 0.00455, 9.81);
    let heads = [(7.0, 30.0), (11.0, 30.0), (15.0, 30.0), (16.76, 10.0)];
    let d = |x: f64| dr - (dr - dt) * x / l;
    let inertia = |x: f64| std::f64::consts::PI / 64.0 * (d(x).powi(4) - (d(x) - 2.0 * t).powi(4));
    let mu = |x: f64| rho * std::f64::consts::PI / 4.0 * (d(x).powi(2) - (d(x) - 2.0 * t).powi(2));
    let n = 2000;
    let h = l / n as f64;
    let mid = |i: usize| (i as f64 + 0.5) * h;
    // Bending moment at x from the load outboard of it.
    let moment = |x: f64| {
        let heads: f64 = heads
            .iter()
            .filter(|(a, _)| *a > x)
            .map(|(a, m)| m * g * (a - x))
            .sum();
        let k = 400;
        let hs = (l - x) / k as f64;
        let own: f64 = (0..k)
            .map(|j| {
                let s = (j as f64 + 0.5) * hs;
                mu(x + s) * g * s * hs
            })
            .sum();
        heads + own
    };
    // Curvature, slope and deflection from the clamp, midpoint rule.
    let mut w = vec![0.0; n + 1];
    let mut slope = 0.0;
    for i in 0..n {
        let kappa = moment(mid(i)) / (e * inertia(mid(i)));
        w[i + 1] = w[i] + h * (slope + 0.5 * h * kappa);
        slope += h * kappa;
    }
    let at = |x: f64| {
        let i = ((x / h) as usize).min(n - 1);
        let f = x / h - i as f64;
        w[i] + f * (w[i + 1] - w[i])
    };
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..n {
        let (m, y) = (mu(mid(i)) * h, 0.5 * (w[i] + w[i + 1]));
        num += m * y;
        den += m * y * y;
    }
    for (a, m) in heads {
        num += m * at(a);
        den += m * at(a) * at(a);
    }
    (w[n], (g * num / den).sqrt() / std::f64::consts::TAU)
}

#[test]
fn modes_and_static_on_the_mast_arm_describe_the_arm() {
    let (sag, f1) = closed_form();
    let m = json(&["modes", "--scene", "scenes/mast-arm.toml", "--json"]);
    let s = json(&["static", "--scene", "scenes/mast-arm.toml", "--json"]);
    let t = json(&["tune", "--scene", "scenes/mast-arm.toml", "--json"]);
    assert_eq!(m["arm"], true);
    let f = m["frequencies"][0].as_f64().unwrap();
    // The same arm `tune` reports (to the last digit: the same model).
    assert_eq!(f, t["arm_frequency"].as_f64().unwrap());
    // Within 1.5 % of Rayleigh's bound (the uniform beam gave 1.192 Hz, 16 % off).
    assert!(f < f1 && f > f1 * 0.985, "f1 {f} vs Rayleigh {f1}");
    // Static tip deflection within 1 % of linear Euler–Bernoulli (the uniform beam gave
    // −270 mm); the rest: 16 elements and the large-deflection geometry.
    let d = -s["static_tip_deflection"].as_f64().unwrap();
    assert!((d / sag - 1.0).abs() < 0.01, "sag {d} vs {sag}");
}
