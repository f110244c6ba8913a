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
    // The CSV header says which window.
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("t ≥ 20 s"), "{csv}");
}
