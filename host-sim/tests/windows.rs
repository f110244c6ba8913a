//! One steady window: `paper` (as `run`) and `sweep` at the same frequency report the same
//! steady figures, to the last digit, and every column of a sweep row is over that window.

use std::process::Command;

fn json(args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

#[test]
fn paper_and_sweep_share_the_steady_window() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    // 44 s: the default transient 20 s (at most half the run) leaves a 24 s steady window.
    let p = json(&["paper", "--duration", "44", "--json"]);
    let p = &p["run"];
    let s = json(&[
        "sweep",
        "--freqs",
        "4.13",
        "--duration",
        "44",
        "--out",
        out,
        "--no-plots",
        "--json",
    ]);
    assert_eq!(s["steady_from"], 20.0);
    assert_eq!(p["steady_from"], 20.0);
    assert_eq!(s["steady"], "steady: t ≥ 20 s to the end");
    let q = &s["points"][0];
    // The same simulation over the same window: equal to the last digit.
    assert_eq!(q["tip_amplitude"], p["tip_amplitude_steady"]);
    assert_eq!(q["ball_amplitude_deg"], p["ball_angle_steady_deg"]);
    let c = &p["contact"];
    assert_eq!(q["flight_fraction"], c["flight_fraction_steady"]);
    // Impacts over the window, not the run: the paper's steady impact rate times the window.
    let span = p["duration"].as_f64().unwrap() - 20.0;
    let steady_impacts = p["impact_rate_steady"].as_f64().unwrap() * span;
    assert_eq!(q["impacts"].as_f64().unwrap(), steady_impacts.round());
    assert!(
        p["impacts"].as_u64().unwrap() > q["impacts"].as_u64().unwrap(),
        "the run's impacts {} include the transient's, the window's {} not",
        p["impacts"],
        q["impacts"]
    );
    // The locked ball (run also without plots): `paper`'s locked run over the same window,
    // to the last digit, in the JSON and (to its printed digits) in the CSV's column.
    let p_locked = &json(&["paper", "--duration", "44", "--json"])["locked"];
    let locked = &s["locked"][0]["tip_amplitude"];
    assert_eq!(locked, &p_locked["tip_amplitude_steady"]);
    // The CSV header says which window.
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("t ≥ 20 s"), "{csv}");
    let mut rows = csv.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = rows.next().unwrap().split(',').collect();
    let row: Vec<&str> = rows.next().unwrap().split(',').collect();
    let i = head
        .iter()
        .position(|h| *h == "locked_tip_amplitude")
        .unwrap();
    assert_eq!(row[i], format!("{:.6e}", locked.as_f64().unwrap()));
}

/// `fatigue` uses the same window: its header, table and manifest state it, its free-ball
/// impacts and flight fraction are the sweep's over that window (the same model), and the
/// locked ball's figures are those of its steady harmonic response: tip RMS·√2 = the sweep's
/// steady half peak-to-peak (a sine's, 0.5 %), S_eq = the largest range (one range per cycle,
/// no ring-up from rest in the count, 1 %).
#[test]
fn fatigue_counts_damage_over_the_steady_window() {
    let dir = tempfile::tempdir().unwrap();
    let (f_out, s_out) = (dir.path().join("f"), dir.path().join("s"));
    let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "fatigue",
            "--freqs",
            "4.13",
            "--duration",
            "44",
            "--no-plots",
        ])
        .arg("--out")
        .arg(&f_out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("steady: t ≥ 20 s to the end"), "{text}");
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(f_out.join("fatigue.manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(manifest["result"]["steady_from"], 20.0, "{manifest}");
    let csv = std::fs::read_to_string(f_out.join("fatigue.csv")).unwrap();
    assert!(
        csv.contains("# steady: every column over t ≥ 20 s"),
        "{csv}"
    );
    let head: Vec<&str> = csv
        .lines()
        .find(|l| l.starts_with("frequency,"))
        .unwrap()
        .split(',')
        .collect();
    let row: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
    let col = |name: &str| -> f64 {
        let i = head.iter().position(|h| *h == name).unwrap();
        row[i].parse().unwrap()
    };
    let s = json(&[
        "sweep",
        "--freqs",
        "4.13",
        "--duration",
        "44",
        "--out",
        s_out.to_str().unwrap(),
        "--json",
    ]);
    let q = &s["points"][0];
    assert_eq!(col("free_impacts"), q["impacts"].as_f64().unwrap());
    assert!(col("free_impacts") > 0.0);
    let ff = q["flight_fraction"].as_f64().unwrap();
    assert!((col("free_flight_fraction") - ff).abs() <= 1e-4, "{ff}");
    let locked = s["locked"][0]["tip_amplitude"].as_f64().unwrap() * 1e3;
    let rms = col("locked_tip_rms");
    assert!(
        (rms * 2f64.sqrt() / locked - 1.0).abs() < 5e-3,
        "locked tip RMS {rms} mm · √2 against the steady amplitude {locked} mm"
    );
    let (seq, max) = (col("locked_s_eq"), col("locked_max_range"));
    assert!(
        seq / max > 0.99 && seq <= max,
        "S_eq {seq} MPa, max range {max} MPa"
    );
}
