//! The command line's surface holds for odd input: negative numbers in any notation reach the
//! option's own check, the command line's overrides are applied before the scene is validated,
//! every error names the key users write, and `--jobs` is capped at the work there is.

use std::path::PathBuf;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-surface-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

/// Exit 1 with every word of `words` on stderr.
fn refused(o: &Output, words: &[&str]) {
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
}

/// Before: `--amplitude -1e-3` and `--freqs -1,4` were "unexpected argument '-1'" (exit 2).
#[test]
fn negative_numbers_reach_the_options_check() {
    let out = tmp("neg");
    let out = out.to_str().unwrap();
    refused(
        &run(&["run", "--amplitude", "-1e-3", "--no-plots", "--out", out]),
        &["`excitation.amplitude`", "-0.001", "not negative"],
    );
    refused(
        &run(&["sweep", "--freqs", "-1,4", "--no-plots", "--out", out]),
        &["`--freqs`", "-1", "positive"],
    );
    refused(
        &run(&["fatigue", "--amplitudes", "-2.5e-4", "--out", out]),
        &["-0.00025"],
    );
    // A missing value is still clap's usage error, not a value taken from the next option.
    let o = run(&["run", "--duration", "--amplitude", "1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("a value is required for '--duration"));
}

/// Before: a scene with `duration = 1e7` refused `--duration 1` (the scene was validated before
/// the override replaced the value).
#[test]
fn overrides_are_applied_before_the_scene_is_checked() {
    let scene = tmp("long.toml");
    std::fs::write(&scene, "duration = 1e7\n").unwrap();
    let out = tmp("long-out");
    let o = run(&[
        "run",
        "--scene",
        scene.to_str().unwrap(),
        "--duration",
        "0.03",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Without the override the scene's own value is checked, naming the file.
    let o = run(&["static", "--scene", "/nonexistent-dir/x.toml"]);
    refused(&o, &["x.toml"]);
}

/// Before: "arm.point_masses.position: ?" (no index, no value, not the key users write);
/// `validation --converged 0`: "invalid value for `elements`: ?".
#[test]
fn errors_name_the_key_users_write() {
    let arm = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/mast-arm.toml"
    ))
    .unwrap()
    .replace(
        "{ position = 11.0, mass = 30.0 }",
        "{ position = 21.0, mass = 30.0 }",
    );
    let scene = tmp("bad-head.toml");
    std::fs::write(&scene, arm).unwrap();
    refused(
        &run(&["static", "--scene", scene.to_str().unwrap()]),
        &["`arm.heads[1].position`", "21", "16.76"],
    );
    // Before: `max_iterations = 1` was blamed on `integrator.tolerance`.
    let scene = tmp("one-iteration.toml");
    std::fs::write(&scene, "[integrator]\nmax_iterations = 1\n").unwrap();
    refused(
        &run(&["static", "--scene", scene.to_str().unwrap()]),
        &["`integrator.max_iterations`", "too few"],
    );
}

/// Before: `sweep --jobs 1000000` started a thread per job (with a 64 MiB stack each): nothing
/// in 300 s and a load average above 600. Now two frequencies run on at most two threads.
#[test]
fn jobs_are_capped_at_the_points_and_the_cores() {
    let out = tmp("jobs");
    let o = run(&[
        "sweep",
        "--freqs",
        "4.0,4.1",
        "--duration",
        "0.6",
        "--last",
        "0.3",
        "--jobs",
        "1000000",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("--jobs 1000000 runs on"), "{e}");
    let threads: usize = e
        .split("runs on ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!((1..=2).contains(&threads), "{e}");
}

/// `estimate` bounds its work before allocating (before: `--duration 1e9` aborted with "memory
/// allocation of 800000000000 bytes failed", `--duration 0.01` printed "inf %", `--lab
/// --frequency 400` ran above the 166.7 Hz Nyquist limit and printed a 263,770 % error).
#[test]
fn estimate_has_runs_limits() {
    let arm = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/mast-arm.toml");
    refused(
        &run(&["estimate", "--scene", arm, "--duration", "1e9"]),
        &["`--duration`", "1000000000", "steps"],
    );
    refused(
        &run(&["estimate", "--lab", "--duration", "0.01"]),
        &["`--duration`", "0.01"],
    );
    refused(
        &run(&["estimate", "--lab", "--frequency", "400"]),
        &["`--frequency`", "Nyquist"],
    );
}
