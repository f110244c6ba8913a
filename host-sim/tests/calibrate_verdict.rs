//! `calibrate` prints its fit residual beside the expected range and a grade (ok / poor /
//! FAILED, as `identify` grades its figures), in the table, the JSON and the written scene.

use absorber_sim::calibrate::{residual_quality, MAX_RESIDUAL, MAX_RESIDUAL_AT_CAP, OK_RESIDUAL};
use absorber_sim::identify::Grade;
use std::process::Command;

/// The grade's edges: a 2-element model reaches 6.5e-4 against a converged reference (ok), a
/// residual of a few per mille is poor, one beyond 1 % (or 1e-3 when the fit stopped at its
/// iteration cap) FAILED, a NaN FAILED.
#[test]
fn residual_grades_follow_the_expected_range() {
    assert_eq!(OK_RESIDUAL, 1e-3);
    assert_eq!(residual_quality(6.5e-4, false).grade, Grade::Ok);
    assert_eq!(residual_quality(4e-7, true).grade, Grade::Ok);
    assert_eq!(residual_quality(5e-3, false).grade, Grade::Poor);
    assert_eq!(residual_quality(5e-3, true).grade, Grade::Failed);
    assert_eq!(residual_quality(2e-3, true).grade, Grade::Failed);
    // At the cap a usable fit is a good one: no `poor` band.
    assert_eq!(residual_quality(MAX_RESIDUAL_AT_CAP, true).grade, Grade::Ok);
    assert_eq!(
        residual_quality(2.0 * MAX_RESIDUAL, false).grade,
        Grade::Failed
    );
    assert_eq!(residual_quality(f64::NAN, false).grade, Grade::Failed);
    let q = residual_quality(5e-3, false);
    assert_eq!(q.expected, "≤ 1e-3; usable ≤ 1e-2");
}

/// The locked scene with 3 elements against the 16-element full solver fits to about 5e-7:
/// printed, in the JSON and in the scene header as `ok`, the JSON value the largest of the
/// fit's relative errors.
#[test]
fn calibrate_reports_its_residual_with_a_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal.toml");
    let locked = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/locked.toml");
    let run = |json: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_host-sim"));
        c.args(["calibrate", "--scene", locked, "--elements", "3", "--out"])
            .arg(&out);
        if json {
            c.arg("--json");
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let v: serde_json::Value = serde_json::from_str(&run(true)).unwrap();
    let q = &v["quality"][0];
    assert_eq!(q["figure"], "worst residual");
    assert_eq!(q["grade"], "ok");
    assert_eq!(q["expected"], "≤ 1e-3; usable ≤ 1e-2");
    let worst = v["errors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    assert_eq!(q["value"].as_f64().unwrap(), worst);
    assert!(worst > 0.0 && worst < 1e-5, "{worst}");
    let text = run(false);
    let line = text
        .lines()
        .find(|l| l.starts_with("worst residual"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.ends_with("(expected ≤ 1e-3; usable ≤ 1e-2): ok"),
        "{line}"
    );
    let scene = std::fs::read_to_string(&out).unwrap();
    assert!(
        scene.contains("(expected ≤ 1e-3; usable ≤ 1e-2): ok"),
        "{scene}"
    );
}
