//! What the results say: refused input named, failed points and physical failures in words,
//! measured excitation, the steady window and the time column of short runs, a locked ball, the
//! README's sample output.

use absorber_sim::excitation::Excitation;
use std::path::{Path, PathBuf};

mod common;
use common::{bin, dir, manifest, names, run, visible};

fn refused(args: &[&str], needle: &str) {
    let o = run(args);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(
        e.contains(needle),
        "{args:?} gave `{e}`, which does not name `{needle}`"
    );
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(o.stdout.is_empty());
}

#[test]
fn meaningless_input_is_refused_naming_the_field() {
    let d = dir("refused");
    let ds = d.to_str().unwrap();
    let r = |extra: &[&str], needle: &str| {
        let mut a = vec!["run", "--no-plots", "--out", ds];
        a.extend_from_slice(extra);
        refused(&a, needle);
    };
    // At and above the Nyquist limit 1/(2h) = 166.7 Hz, and exactly 1/h.
    r(&["--frequency", "1e6"], "`excitation.frequency`");
    r(&["--frequency", "333.3333333333333"], "Nyquist");
    r(&["--frequency", "166.67"], "Nyquist");
    r(&["--duration", "0.001"], "shorter than one step");
    r(&["--duration", "-1"], "`duration`");
    r(&["--duration", "1e300"], "`duration`");
    r(&["--duration", "1e6"], "`--every`");
    r(&["--duration", "20", "--transient", "30"], "`--transient`");
    r(&["--transient", "-1"], "`--transient`");
    r(&["--duration", "20", "--transient", "20"], "leaves 0 steps");
    r(
        &["--amplitude", "1", "--frequency", "20"],
        "`excitation.amplitude`",
    );
    for (toml, key) in [
        ("[integrator]\ntolerance = 0.05\n", "integrator.tolerance"),
        ("gravity = 1e300\n", "gravity"),
        ("[beam]\ninertia = 1e-300\n", "beam.inertia"),
        ("[beam]\nlength = 100.0\n", "beam.length"),
        ("[beam]\nlength = 1e-300\n", "beam.length"),
        ("[tip]\nmass = 1e300\n", "tip.mass"),
        ("[outputs]\ntransient = 70.0\n", "outputs.transient"),
    ] {
        let p = d.join("s.toml");
        std::fs::write(&p, toml).unwrap();
        r(&["--scene", p.to_str().unwrap()], key);
    }
    refused(&["sweep", "--freqs", "4,500", "--out", ds], "`--freqs`");
    refused(&["sweep", "--last", "60", "--out", ds], "`--last`");
    refused(
        &["sweep", "--last", "0.01", "--out", ds],
        "at least 10 steps",
    );
    refused(
        &["fatigue", "--amplitudes", "1", "--freqs", "20", "--out", ds],
        "`--amplitudes`",
    );
    // Nothing was written by any of them.
    assert!(
        visible(&d).iter().all(|n| n == "s.toml"),
        "{:?}",
        visible(&d)
    );
}

#[test]
fn a_poorly_resolved_frequency_is_warned_about() {
    let d = dir("resolution");
    let ds = d.to_str().unwrap();
    let args = |f: &'static str| {
        [
            "run",
            "--frequency",
            f,
            "--duration",
            "0.03",
            "--no-plots",
            "--out",
            ds,
        ]
    };
    let o = run(&args("20"));
    assert!(o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("warning") && e.contains("steps per period"),
        "{e}"
    );
    let o = run(&args("4.13"));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
}

#[test]
fn failed_points_have_no_numbers() {
    use absorber_sim::sweep::SweepPoint;
    let ok = SweepPoint {
        frequency: 4.0,
        tip_amplitude: 0.01,
        tip_mean: -0.016,
        ball_max_deg: 60.0,
        ball_amplitude_deg: 50.0,
        impacts: 3,
        flight_fraction: 0.1,
        max_iterations: 5,
        error: None,
    };
    let bad = SweepPoint {
        frequency: 4.1,
        error: Some("step 7 (t = 0.021 s) failed: the solver did not converge".into()),
        ..ok.clone()
    };
    let locked = SweepPoint {
        tip_amplitude: 0.03,
        ..ok.clone()
    };
    let csv = absorber_sim::sweep::csv(&[ok, bad], &[locked.clone(), locked], 20.0);
    assert!(
        csv.starts_with(
            "# host-sim sweep: every column over the steady window, steady: t ≥ 20 s to the end"
        ),
        "{csv}"
    );
    let rows: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
    assert!(rows[0].starts_with("frequency,status,"));
    assert!(rows[1].starts_with("4,ok,1.000000e-2,"));
    assert!(rows[1].ends_with(",3.000000e-2,"), "{}", rows[1]);
    assert_eq!(
        rows[2],
        "4.1,failed,,,,,,,,3.000000e-2,step 7 (t = 0.021 s) failed: the solver did not converge"
    );
    // Every row has as many fields as the header names.
    let n = absorber_sim::sweep::csv_columns().len();
    assert!(rows.iter().all(|r| r.split(',').count() == n), "{csv}");
}

#[test]
fn physical_failures_say_what_happened_in_words() {
    let s = absorber_sim::scene::Scene::paper();
    let m = absorber_sim::scene::physical_failure(
        absorber_core::Error::NoConvergence {
            iterations: 100,
            increment: 0.5,
        },
        &s,
    );
    assert!(
        m.contains("did not converge") && m.contains("--step"),
        "{m}"
    );
    let m = absorber_sim::scene::physical_failure(absorber_core::Error::Singular, &s);
    assert!(
        m.contains("likely cause") && !m.contains("state kept"),
        "{m}"
    );
    let m = absorber_sim::scene::physical_failure(absorber_core::Error::NonFiniteState, &s);
    assert!(m.contains("diverged"), "{m}");
    // A magnitude the static solve could not handle is refused before it, by key and range
    // (it used to end in "static equilibrium ... `beam.*`").
    let p = std::env::temp_dir().join(format!("host-sim-out-{}-tiny.toml", std::process::id()));
    std::fs::write(&p, "[beam]\nmass = 1e-300\n").unwrap();
    let o = run(&["static", "--scene", p.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("`beam.mass`") && e.contains("1e-300") && e.contains("allowed"),
        "{e}"
    );
    assert!(!e.contains("state kept"), "{e}");
}

#[test]
fn a_spike_between_grid_points_is_kept_by_averaging_and_warned_about() {
    // A 1 ms triangular spike of 100 m/s² peak centred between grid points (h = 3 ms),
    // sampled at 0.1 ms: its velocity change is 0.05 m/s.
    let h = 0.003;
    let mut text = String::from("\u{feff}t,accel\n");
    for k in 0..=3000 {
        let t = k as f64 * 1e-4;
        let a = (100.0 * (1.0 - (t - 0.1515).abs() / 0.0005)).max(0.0);
        text.push_str(&format!("{t},{a}\n"));
    }
    let (e, warnings) = Excitation::from_csv_checked(&text, h, Some(90)).unwrap();
    // The record reduced to the grid (before the baseline correction): trapezoid over the grid
    // = what the solver integrates, the spike's full 0.05 m/s.
    let accel = e.recorded().unwrap().to_vec();
    let dv: f64 = accel.windows(2).map(|w| 0.5 * h * (w[0] + w[1])).sum();
    assert!((dv - 0.05).abs() < 1e-9, "velocity change {dv}");
    assert!(accel.iter().any(|&a| a > 1.0));
    assert!(
        warnings.iter().any(|w| w.contains("faster than the step")),
        "{warnings:?}"
    );
    // A smooth record of a base that starts and ends at rest (y = sin⁴(πt/T), T = 0.3 s: the
    // baseline correction leaves it) gives no warning, and the BOM is accepted.
    let mut text = String::from("\u{feff}t,accel\n");
    let w = std::f64::consts::PI / 0.3;
    for k in 0..=300 {
        let t = k as f64 * 1e-3;
        let (s, c) = (w * t).sin_cos();
        text.push_str(&format!(
            "{t},{}\n",
            w * w * (12.0 * s * s * c * c - 4.0 * s.powi(4))
        ));
    }
    let (_, warnings) = Excitation::from_csv_checked(&text, h, Some(90)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[test]
fn readme_shows_what_paper_prints() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let start = readme.find("## What the first command prints").unwrap();
    let block = &readme[start..];
    let a = block.find("```\n").unwrap() + 4;
    let b = a + block[a..].find("```").unwrap();
    let shown = &block[a..b];
    let o = run(&["paper"]);
    assert!(o.status.success());
    assert_eq!(String::from_utf8_lossy(&o.stdout), shown);
}

/// A scene whose runs fail mid-way at 4.13 Hz (the ball reaches the stops and three Newton
/// iterations no longer suffice for an impact step's solves) but not at 3.9 Hz.
fn failing_scene(d: &Path) -> PathBuf {
    let p = d.join("budget.toml");
    std::fs::write(&p, "name = \"budget\"\n[integrator]\nmax_iterations = 3\n").unwrap();
    p
}

#[test]
fn a_sweep_with_a_failed_point_marks_it_and_exits_3() {
    let d = dir("sweep-failed");
    let scene = failing_scene(&d);
    let o = bin()
        .args([
            "sweep",
            "--duration",
            "10",
            "--last",
            "5",
            "--freqs",
            "3.9,4.13",
        ])
        .arg("--scene")
        .arg(&scene)
        .arg("--out")
        .arg(&d)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.contains("4.130")).unwrap();
    assert!(line.contains("FAILED") && line.contains("step"), "{line}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("1 of 2 sweep runs failed"));
    let csv = std::fs::read_to_string(d.join("sweep.csv")).unwrap();
    assert!(csv.contains("\n3.9,ok,"), "{csv}");
    // No numbers of its own; the locked ball's run at 4.13 Hz did not fail: its column stays.
    let row = csv.lines().find(|l| l.starts_with("4.13,")).unwrap();
    let f: Vec<&str> = row.split(',').collect();
    assert_eq!(
        f[..9],
        ["4.13", "failed", "", "", "", "", "", "", ""],
        "{row}"
    );
    assert!(
        f[9].parse::<f64>().unwrap() > 0.0 && f[10].starts_with("step "),
        "{row}"
    );
    assert!(csv.contains("t ≥ 4.999 s to the end"), "{csv}");
    let m = manifest(&d, "sweep");
    assert_eq!(m["status"], "points-failed");
    assert_eq!(names(&m), ["sweep.csv", "sweep.png"]);
}

#[test]
fn a_fatigue_study_with_a_failed_point_marks_it_and_exits_3() {
    let d = dir("fatigue-failed");
    let scene = failing_scene(&d);
    let o = bin()
        .args([
            "fatigue",
            "--duration",
            "10",
            "--freqs",
            "3.9,4.13",
            "--no-plots",
        ])
        .arg("--scene")
        .arg(&scene)
        .arg("--out")
        .arg(&d)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.contains("4.130")).unwrap();
    // Only the frequency and the amplitude before FAILED: no damage rate of a failed run.
    let (before, _) = line.split_once("FAILED").unwrap();
    assert_eq!(before.split_whitespace().count(), 2, "{line}");
    let csv = std::fs::read_to_string(d.join("fatigue.csv")).unwrap();
    let row = csv.lines().find(|l| l.starts_with("4.13,")).unwrap();
    assert!(row.starts_with("4.13,0.0005,failed,,,,,,,,,,,,,"), "{row}");
    assert_eq!(manifest(&d, "fatigue")["status"], "points-failed");
}

#[test]
fn a_short_run_gets_a_real_steady_state_window() {
    // 20 s with the default 20 s transient: the second half, not a window of one step.
    let d = dir("short");
    let o = run(&[
        "run",
        "--duration",
        "20",
        "--no-plots",
        "--json",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let s = &v["summary"];
    assert!(
        (s["steady_from"].as_f64().unwrap() - 10.0).abs() < 0.01,
        "{s}"
    );
    assert!(s["tip_amplitude_steady"].as_f64().unwrap() > 1e-3, "{s}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("second half"));
}

/// The time column is k·h at step k, impacts or not. (A step with a stop impact used not to
/// advance `Model::time`: a 5 s run with 6 impacts ended at 4.983 s, and per-hour rates and
/// time windows shifted. The core now sets the step count after the stop events.)
#[test]
fn the_time_column_advances_one_step_per_step_with_impacts() {
    let d = dir("time");
    let o = run(&[
        "run",
        "--duration",
        "5",
        "--no-plots",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let csv = std::fs::read_to_string(d.join("paper.csv")).unwrap();
    let rows: Vec<&str> = csv
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .collect();
    let impacts = rows
        .iter()
        .filter(|l| l.split(',').nth(15) == Some("1"))
        .count();
    assert!(impacts > 0);
    for (k, l) in rows.iter().enumerate() {
        let t: f64 = l.split(',').next().unwrap().parse().unwrap();
        assert!((t - k as f64 * 0.003).abs() < 1e-9, "row {k}: t = {t}");
    }
}

/// A locked ball has no angle of its own: `run` says it is locked in the housing (before: a
/// "ball angle θ max 8.1°" line that was the tip mass's slope), the JSON has no ball angle
/// and the CSV's ball columns are NaN while `tip_angle`, which the ball turns with, is there;
/// the free ball keeps its line.
#[test]
fn a_locked_ball_is_reported_as_locked_not_as_an_angle() {
    let d = dir("locked-ball");
    let ds = d.to_str().unwrap();
    let args = [
        "run",
        "--kind",
        "locked",
        "--duration",
        "4",
        "--no-plots",
        "--out",
        ds,
    ];
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("ball                       locked in the housing"),
        "{text}"
    );
    assert!(!text.contains("ball angle θ"), "{text}");
    let mut json_args = args.to_vec();
    json_args.push("--json");
    let o = run(&json_args);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let s = &v["summary"];
    assert_eq!(s["ball"], "locked");
    assert!(s["ball_angle_max_deg"].is_null(), "{s}");
    let csv = std::fs::read_to_string(d.join("paper.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    for row in lines {
        let f: Vec<&str> = row.split(',').collect();
        for c in ["ball_angle", "ball_rel_angle", "ball_rate", "ball_spin"] {
            assert_eq!(f[col(c)], "NaN", "{c} in {row}");
        }
        let psi: f64 = f[col("tip_angle")].parse().unwrap();
        assert!(psi.is_finite() && psi != 0.0, "{row}");
    }
    let o = run(&["run", "--duration", "4", "--no-plots", "--out", ds]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("ball angle θ               max "), "{text}");
    let _ = std::fs::remove_dir_all(&d);
}
