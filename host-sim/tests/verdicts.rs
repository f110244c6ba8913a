//! What a reader sees without the source: every quality figure of `estimate` and `identify`
//! printed with its range and a word, the grade that the JSON carries the same, no bare NaN,
//! and the tables' counts and comparison curves over the windows they state.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn run(args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("host-sim");
    assert!(
        o.status.success(),
        "host-sim {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The worst word of a list of quality figures, `none` skipped (the rule stated in the table's
/// legend), computed here from the words alone.
fn worst(q: &[Value]) -> &'static str {
    let words: Vec<&str> = q.iter().filter_map(|f| f["word"].as_str()).collect();
    if words.contains(&"failed") {
        "failed"
    } else if words.contains(&"poor") {
        "poor"
    } else {
        "ok"
    }
}

/// The twin of the mast arm: the JSON's grades are the worst words of each estimator's figures,
/// the headline grade is the filter's with all the scene's sensors, and the text prints the
/// same words, a dash instead of NaN, and both the grade and the health check in its verdict.
#[test]
fn estimate_grades_each_figure_and_the_json_says_the_same() {
    let args = [
        "estimate",
        "--scene",
        "scenes/mast-arm.toml",
        "--duration",
        "60",
    ];
    let v: Value =
        serde_json::from_slice(&run(&[&args[..], &["--json"]].concat()).stdout).expect("json");
    let est = v["estimators"].as_array().expect("estimators");
    assert!(est.len() >= 3, "{v}");
    for e in est {
        let q = e["quality"].as_array().expect("quality");
        assert_eq!(q.len(), 5, "{e}");
        assert_eq!(e["grade"], worst(q), "{e}");
    }
    let all = est
        .iter()
        .filter(|e| e["estimator"] == "ekf")
        .max_by_key(|e| e["sensors"].as_array().map_or(0, Vec::len))
        .expect("ekf");
    assert_eq!(
        all["sensors"],
        serde_json::json!(["tip_accel", "root_strain"])
    );
    assert_eq!(v["grade"], all["grade"], "{v}");

    let out = text(&run(&args));
    assert!(!out.contains("NaN"), "{out}");
    // The strain gauge alone has no accelerometer innovation; the constant gain no covariance.
    assert!(
        out.contains("innovation RMS / sd –, none: no tip accelerometer"),
        "{out}"
    );
    assert!(
        out.contains("NIS –, none: a constant gain has no covariance"),
        "{out}"
    );
    assert!(out.contains("within ±2 sd"), "{out}");
    let verdict = out
        .lines()
        .find(|l| l.starts_with("verdict (filter with all sensors"))
        .expect("verdict line");
    let grade = all["grade"].as_str().unwrap();
    let health = all["verdict"].as_str().unwrap();
    assert!(
        verdict.contains(&format!("grade against the truth {grade}"))
            && verdict.contains(&format!("health {health}")),
        "{verdict}"
    );
}

/// `identify` names the record kind as the option spells it and says which figure limits a
/// usable result: the ambient record's damping (graded poor), none for the decay.
#[test]
fn identify_says_which_figure_limits_the_result() {
    let decay = text(&run(&["identify", "--csv", "examples/decay.csv"]));
    assert!(decay.contains("(decay record)"), "{decay}");
    assert!(
        decay.contains("verdict: usable (every figure ok)"),
        "{decay}"
    );
    let ambient = text(&run(&[
        "identify",
        "--csv",
        "examples/ambient.csv",
        "--record",
        "ambient",
    ]));
    assert!(ambient.contains("(ambient record)"), "{ambient}");
    assert!(
        ambient.contains("verdict: usable, with care: zeta uncertainty poor"),
        "{ambient}"
    );
}

/// The value after `key` in a summary line, as a number.
fn after(line: &str, key: &str) -> f64 {
    let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
    let word: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    word.parse().unwrap_or_else(|_| panic!("{key} in {line}"))
}

/// `paper` and `sweep` at the paper's 4.13 Hz count the same steady stop impacts, and the
/// sweep's locked-ball column is `paper`'s locked ball (two code paths: the summary's locked
/// run and the sweep's own locked runs).
#[test]
fn paper_and_sweep_count_the_same_window_and_agree_on_the_locked_ball() {
    let paper = text(&run(&["paper"]));
    let angle = paper
        .lines()
        .find(|l| l.starts_with("ball angle θ"))
        .expect("ball line");
    let steady = after(angle, "stop impacts in the run,");
    let locked = paper
        .lines()
        .find(|l| l.starts_with("locked ball (passive)"))
        .expect("locked line");
    let locked_steady = after(locked, "steady");

    let dir = tempfile::tempdir().expect("tempdir");
    let sweep = text(&run(&[
        "sweep",
        "--freqs",
        "4.13",
        "--out",
        dir.path().to_str().unwrap(),
    ]));
    assert!(sweep.contains("locked: tip Y [mm]"), "{sweep}");
    let row: Vec<f64> = sweep
        .lines()
        .find(|l| l.trim_start().starts_with("4.130"))
        .expect("row")
        .split_whitespace()
        .map(|w| w.parse().expect("number"))
        .collect();
    // f, tip Y, max |θ|, θ half p-p, impacts, flight %, locked tip Y.
    assert_eq!(row.len(), 7, "{row:?}");
    assert_eq!(row[4], steady, "{angle}\n{sweep}");
    assert!((row[6] - locked_steady).abs() <= 5e-4, "{locked}\n{sweep}");
}

/// `tune` on an arm prints the ball it would need in mm, as its JSON gives it in m, and
/// refuses `--write` (before: ignored without a word).
#[test]
fn tune_on_an_arm_prints_mm_and_refuses_write() {
    let arm = ["tune", "--scene", "scenes/mast-arm.toml"];
    let v: Value =
        serde_json::from_slice(&run(&[&arm[..], &["--json"]].concat()).stdout).expect("json");
    let r = v["track_radius"].as_f64().expect("track_radius");
    let out = text(&run(&arm));
    let line = out
        .lines()
        .find(|l| l.starts_with("ball at 0.5 × f1"))
        .expect("ball line");
    assert_eq!(after(line, "R ="), (r * 1e3).round(), "{line}");
    let dir = tempfile::tempdir().expect("tempdir");
    let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(arm)
        .arg("--write")
        .arg(dir.path().join("t.toml"))
        .current_dir(repo())
        .output()
        .expect("host-sim");
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("`--write`"));
    assert!(!dir.path().join("t.toml").exists());
}
