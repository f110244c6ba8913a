//! Outputs that cannot tear or lie, bounded runs, refused input, visible failures, measured
//! excitation, the README's sample output.

use absorber_sim::excitation::Excitation;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-out-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> std::process::Output {
    bin().args(args).output().unwrap()
}

fn manifest(d: &Path, name: &str) -> serde_json::Value {
    let t = std::fs::read_to_string(d.join(format!("{name}.manifest.json"))).unwrap();
    serde_json::from_str(&t).unwrap()
}

fn names(v: &serde_json::Value) -> Vec<String> {
    v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap().to_string())
        .collect()
}

/// Visible (non-hidden) files of a directory, sorted.
fn visible(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !n.starts_with('.'))
        .collect();
    v.sort();
    v
}

fn partials(d: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(absorber_sim::output::PARTIAL_PREFIX)
        })
        .collect()
}

#[test]
fn manifest_lists_the_run_and_a_rerun_with_fewer_plots_removes_stale_ones() {
    let d = dir("stale");
    let ds = d.to_str().unwrap();
    let o = run(&["run", "--duration", "1", "--plots", "time,fft", "--out", ds]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = manifest(&d, "paper");
    assert_eq!(m["status"], "complete");
    assert_eq!(names(&m), ["paper.csv", "paper_time.png", "paper_fft.png"]);
    for f in m["files"].as_array().unwrap() {
        let p = d.join(f["name"].as_str().unwrap());
        assert_eq!(
            std::fs::metadata(&p).unwrap().len(),
            f["bytes"].as_u64().unwrap()
        );
    }
    let o = run(&["run", "--duration", "1", "--plots", "time", "--out", ds]);
    assert!(o.status.success());
    let m = manifest(&d, "paper");
    assert_eq!(names(&m), ["paper.csv", "paper_time.png"]);
    assert_eq!(m["removed_stale"][0], "paper_fft.png");
    assert_eq!(
        visible(&d),
        ["paper.csv", "paper.manifest.json", "paper_time.png"]
    );
    assert!(partials(&d).is_empty());
    // The CSV is complete: header, then one row per step (1 s / 3 ms = 333 steps + t = 0).
    let csv = std::fs::read_to_string(d.join("paper.csv")).unwrap();
    let rows = csv.lines().filter(|l| !l.starts_with('#')).count();
    assert_eq!(rows, 1 + 334);
}

#[test]
fn a_failed_run_keeps_the_previous_result_and_says_it_failed() {
    let d = dir("failed");
    let ds = d.to_str().unwrap();
    let o = run(&["run", "--duration", "1", "--no-plots", "--out", ds]);
    assert!(o.status.success());
    let before = std::fs::read(d.join("paper.csv")).unwrap();
    // Fails at the start of the computation (the static solve cannot meet its budget).
    let scene = d.join("bad.toml");
    std::fs::write(
        &scene,
        "name = \"paper\"\n[integrator]\nmax_iterations = 1\n",
    )
    .unwrap();
    let o = run(&[
        "run",
        "--scene",
        scene.to_str().unwrap(),
        "--duration",
        "1",
        "--no-plots",
        "--out",
        ds,
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(std::fs::read(d.join("paper.csv")).unwrap(), before);
    let m = manifest(&d, "paper");
    assert_eq!(m["status"], "failed");
    assert!(names(&m).is_empty());
    assert_eq!(m["previous"]["status"], "complete");
    assert_eq!(names(&m["previous"]), ["paper.csv"]);
    assert!(partials(&d).is_empty());
}

/// Starts a long run into `d` and waits until it streams its CSV (a partial file with data).
/// The caller kills and waits for it.
#[allow(clippy::zombie_processes)]
fn start_long_run(d: &Path) -> std::process::Child {
    let child = bin()
        .args([
            "run",
            "--duration",
            "3000",
            "--every",
            "1",
            "--no-plots",
            "--out",
        ])
        .arg(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    loop {
        if partials(d).iter().any(|p| {
            std::fs::metadata(p)
                .map(|m| m.len() > 100_000)
                .unwrap_or(false)
        }) {
            return child;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn a_killed_run_destroys_nothing_and_leaves_nothing_that_looks_complete() {
    let d = dir("killed");
    let ds = d.to_str().unwrap();
    let o = run(&["run", "--duration", "1", "--no-plots", "--out", ds]);
    assert!(o.status.success());
    let csv = std::fs::read(d.join("paper.csv")).unwrap();
    let man = std::fs::read(d.join("paper.manifest.json")).unwrap();
    let mut child = start_long_run(&d);
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert_eq!(std::fs::read(d.join("paper.csv")).unwrap(), csv);
    assert_eq!(std::fs::read(d.join("paper.manifest.json")).unwrap(), man);
    assert_eq!(visible(&d), ["paper.csv", "paper.manifest.json"]);
    assert!(
        !partials(&d).is_empty(),
        "the killed run's partial file is hidden"
    );
    // The next command into the directory removes the leftovers.
    let o = run(&["run", "--duration", "1", "--no-plots", "--out", ds]);
    assert!(o.status.success());
    assert!(partials(&d).is_empty());
}

#[test]
fn concurrent_runs_into_one_directory_take_turns() {
    let d = dir("lock");
    let mut first = start_long_run(&d);
    // The second command waits for the lock (and says so) until the first one ends.
    let mut second = bin()
        .args(["run", "--duration", "1", "--no-plots", "--out"])
        .arg(&d)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(second.stderr.take().unwrap());
    let mut msg = String::new();
    while !msg.contains("waiting") {
        let mut line = String::new();
        if std::io::BufRead::read_line(&mut err, &mut line).unwrap() == 0 {
            break;
        }
        msg.push_str(&line);
    }
    assert!(
        msg.contains("waiting") && msg.contains(".host-sim.lock"),
        "{msg}"
    );
    assert!(!d.join("paper.csv").exists());
    first.kill().unwrap();
    first.wait().unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    // The second one ran after the first ended: a complete result, no torn file.
    assert!(second.wait().unwrap().success());
    assert_eq!(manifest(&d, "paper")["status"], "complete");
    let csv = std::fs::read_to_string(d.join("paper.csv")).unwrap();
    assert_eq!(csv.lines().filter(|l| !l.starts_with('#')).count(), 1 + 334);
}

#[test]
fn an_unusable_output_directory_is_an_error_before_any_computation() {
    let d = dir("unwritable");
    let file = d.join("a-file");
    std::fs::write(&file, "x").unwrap();
    let out = file.join("sub");
    // 10⁵ s would take minutes if it were computed first.
    let o = bin()
        .args([
            "run",
            "--duration",
            "1e5",
            "--every",
            "100",
            "--no-plots",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("output directory") && e.contains("a-file"),
        "{e}"
    );
}

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
fn plot_buffers_stay_bounded_on_long_runs() {
    use absorber_sim::figures::PlotData;
    use absorber_sim::run::{Row, RunStats};
    let mut data = PlotData::new(10.0);
    let mut stats = RunStats::new(3e4, 10.0);
    let row0 = Row {
        t: 0.0,
        base_y: 0.0,
        tip_y: 0.0,
        tip_deflection: 0.0,
        tip_angle: 0.0,
        ball_angle: 0.0,
        ball_rel_angle: 0.0,
        energies: absorber_sim::absorber_core::Energies {
            beam_strain: 0.0,
            beam_kinetic: 0.0,
            beam_potential: 0.0,
            tip_kinetic: 0.0,
            tip_potential: 0.0,
            ball_kinetic: 0.0,
            ball_potential: 0.0,
        },
        iterations: 1,
        impact: false,
        base_accel: 0.0,
        tip_velocity: 0.0,
        tip_rate: 0.0,
        ball_rate: 0.0,
        ball_rel_rate: 0.0,
        ball_spin: 0.0,
        ball_spin_rate: 0.0,
        normal_force: f64::NAN,
        tangential_force: f64::NAN,
        contact: f64::NAN,
        tip_acceleration: 0.0,
        separated: false,
        landing: None,
        events: Default::default(),
    };
    let n = 3_000_000usize;
    for k in 0..=n {
        let t = k as f64 * 0.01;
        let r = Row {
            t,
            tip_deflection: (t * 26.0).sin() + if k == n / 2 { 10.0 } else { 0.0 },
            ..row0
        };
        data.push(&r);
        stats.push(&r);
    }
    let (len, buckets, thin) = data.sizes();
    assert!(len <= absorber_sim::figures::MAX_FFT, "{len}");
    assert!(buckets <= 10_000 && thin <= 20_000, "{buckets} {thin}");
    // The min/max envelope keeps the single spike that uniform thinning would drop.
    assert!(data.envelope_max(0) > 9.0, "{}", data.envelope_max(0));
    assert!(stats.json()["tip_amplitude_max"].as_f64().unwrap() > 9.0);
}

/// A write that fails (here: the file size limit, as a full disk would) names the file, keeps
/// the previous result and leaves nothing that looks complete. The tool ignores SIGXFSZ itself
/// (the shell does not trap it here): before, `ulimit -f` killed it with no message.
#[cfg(unix)]
#[test]
fn a_failed_write_names_the_file_and_keeps_the_previous_result() {
    let d = dir("efbig");
    let ds = d.to_str().unwrap();
    let o = run(&["run", "--duration", "1", "--no-plots", "--out", ds]);
    assert!(o.status.success());
    let csv = std::fs::read(d.join("paper.csv")).unwrap();
    // 200 blocks of 512 bytes: the CSV of a 20 s run (about 2.3 MB) does not fit.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -f 200; exec '{}' run --duration 20 --no-plots --out '{ds}'",
            env!("CARGO_BIN_EXE_host-sim")
        ))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("cannot write") && e.contains("paper.csv"), "{e}");
    assert_eq!(std::fs::read(d.join("paper.csv")).unwrap(), csv);
    assert_eq!(manifest(&d, "paper")["status"], "failed");
    assert_eq!(visible(&d), ["paper.csv", "paper.manifest.json"]);
    assert!(partials(&d).is_empty());
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
