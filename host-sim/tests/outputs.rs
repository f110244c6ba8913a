//! Outputs that cannot tear or lie: the manifest, a failed, killed or concurrent run, an
//! unusable directory, a failed write; and bounded plot buffers on long runs.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod common;
use common::{bin, dir, manifest, names, run, visible};

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
