//! The command-line tool: scene parsing, CSV excitation, exit codes, run output, FFT, tuning.

use absorber_sim::excitation::Excitation;
use absorber_sim::fft::spectrum;
use absorber_sim::scene::Scene;
use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-tests-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn err_of(text: &str) -> String {
    format!("{:#}", Scene::from_toml(text).unwrap_err())
}

#[test]
fn empty_scene_is_the_paper() {
    assert_eq!(Scene::from_toml("").unwrap(), Scene::paper());
    let shipped =
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/paper.toml")).unwrap();
    let (mut a, b) = (shipped.file.clone(), Scene::paper().file);
    assert_eq!(a.damping.stiffness_proportional, Some(0.0));
    a.damping.stiffness_proportional = None;
    assert_eq!(a, b);
    assert_eq!(shipped.params().unwrap(), Scene::paper().params().unwrap());
}

#[test]
fn unknown_keys_are_named() {
    let e = err_of("[beam]\nlenght = 0.3\n");
    assert!(e.contains("lenght") && e.contains("beam"), "{e}");
    let e = err_of("colour = 1\n");
    assert!(e.contains("colour"), "{e}");
    let e = err_of("[excitation]\ntype = \"harmonic\"\nphase = 1\n");
    assert!(e.contains("phase"), "{e}");
    assert!(!e.contains('\n'));
}

#[test]
fn bad_values_are_named() {
    for (text, key) in [
        ("[beam]\nlength = -0.3\n", "beam.length"),
        ("[beam]\nmodulus = \"steel\"\n", "beam.modulus"),
        ("[ball]\ntrack_radius = 0.005\n", "ball.track_radius"),
        ("[ball]\nstop_angle_deg = 200.0\n", "ball.stop_angle_deg"),
        ("[ball]\nrestitution = 1.5\n", "ball.restitution"),
        ("[integrator]\ngamma = 0.3\n", "integrator.gamma"),
        (
            "[integrator]\nmax_iterations = 0\n",
            "integrator.max_iterations",
        ),
        ("[excitation]\nfrequency = -1.0\n", "excitation.frequency"),
        ("elements = 5\n", "elements"),
        ("kind = \"ball\"\n", "kind"),
        ("duration = 0.0\n", "duration"),
        ("[damping]\nratio = 0.01\n", "damping.frequency"),
    ] {
        let e = err_of(text);
        assert!(
            e.contains(key),
            "`{text}` gave `{e}`, which does not name `{key}`"
        );
        assert!(!e.contains('\n'), "{e}");
    }
    // A beam-only scene does not check ball parameters (the core ignores them).
    assert!(Scene::from_toml("kind = \"beam\"\n[ball]\ntrack_radius = 0.001\n").is_ok());
}

#[test]
fn csv_excitation_errors() {
    let h = 0.001;
    for (text, what) in [
        ("t,accel\n0,1\n", "at least 2"),
        ("0,1\n0.001,x\n", "line 2"),
        ("0,1\n0.001,2\n0.001,3\n", "does not increase"),
        ("0,1\n0.001\n", "2 columns"),
        ("0.5,1\n0.501,2\n", "start at t = 0"),
        ("0,1\n0.5,2\n", "coarser"),
        ("0,1\n0.001,inf\n", "not finite"),
    ] {
        let e = format!(
            "{:#}",
            Excitation::from_csv_text(text, h, None).unwrap_err()
        );
        assert!(e.contains(what), "`{text}` gave `{e}`");
    }
    let e = format!(
        "{:#}",
        Excitation::from_csv_text("0,0\n0.002,0\n0.004,0\n", h, Some(10)).unwrap_err()
    );
    assert!(e.contains("needs"), "{e}");
}

#[test]
fn csv_excitation_resamples() {
    // ÿ = −A Ω² sin Ωt over whole periods, sampled at 1 ms, reduced to the 0.5 ms grid (the
    // record before its baseline correction; the correction's own tests are in excitation.rs).
    let (a, w) = (1e-3, std::f64::consts::TAU * 2.0);
    let mut text = String::from("# measured\nt,accel\n");
    for k in 0..=2000 {
        let t = k as f64 * 1e-3;
        text.push_str(&format!("{t},{}\n", -a * w * w * (w * t).sin()));
    }
    let h = 5e-4;
    let e = Excitation::from_csv_text(&text, h, Some(4000)).unwrap();
    let rec = e.recorded().unwrap();
    assert_eq!(rec.len(), 4001);
    for k in [0, 1000, 3000, 3999] {
        let t = k as f64 * h;
        assert!((rec[k] + a * w * w * (w * t).sin()).abs() < 1e-3 * a * w * w);
    }
    // The base starts at rest.
    assert_eq!((e.at(0).velocity, e.at(0).displacement), (0.0, 0.0));
}

#[test]
fn fft_peak_of_a_sine() {
    let dt = 0.003;
    let n = 8000;
    let df = 1.0 / (n as f64 * dt);
    // On a bin: the amplitude is exact.
    let f0 = 98.0 * df;
    let x: Vec<f64> = (0..n)
        .map(|i| 0.7 * (std::f64::consts::TAU * f0 * i as f64 * dt).sin() + 0.2)
        .collect();
    let s = spectrum(&x, dt);
    let (f, amp) = s.peak(0.1).unwrap();
    assert!((f - f0).abs() < 1e-9, "{f} vs {f0}");
    assert!((amp - 0.7).abs() < 1e-6, "{amp}");
    // Between bins: the interpolated peak is within a few percent of a bin.
    let f1 = 2.065;
    let x: Vec<f64> = (0..n)
        .map(|i| (std::f64::consts::TAU * f1 * i as f64 * dt).sin())
        .collect();
    let (f, _) = spectrum(&x, dt).peak(0.1).unwrap();
    assert!((f - f1).abs() < 0.05 * df, "{f} vs {f1} (bin {df})");
}

#[test]
fn tune_puts_the_ball_at_half_the_beam_frequency() {
    let t = absorber_sim::tune::tune(&Scene::paper(), 0.5).unwrap();
    let (ball, beam) =
        absorber_sim::tune::coupled_frequencies(&Scene::paper(), t.track_radius).unwrap();
    assert!((ball / beam - 0.5).abs() < 0.5e-3, "ratio {}", ball / beam);
    assert!(
        t.track_radius > 0.0395,
        "a slower ball needs a larger radius: {}",
        t.track_radius
    );
    let shipped =
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/tuned.toml")).unwrap();
    let r = shipped.file.ball.track_radius;
    let (ball, beam) = absorber_sim::tune::coupled_frequencies(&shipped, r).unwrap();
    assert!(
        (ball / beam - 0.5).abs() < 0.5e-3,
        "shipped tuned.toml: ratio {}",
        ball / beam
    );
}

#[test]
fn exit_codes_and_one_line_errors() {
    let ok = bin().arg("--help").output().unwrap();
    assert!(ok.status.success());
    for args in [
        vec!["static", "--scene", "/nonexistent/scene.toml"],
        vec!["static", "--solver", "full", "--precision", "f32"],
        vec!["modes", "--elements", "5"],
        vec!["run", "--duration=-1"],
    ] {
        let out = bin().args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("error: ") && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("backtrace"),
            "{err}"
        );
    }
    let bad = tmp("bad.toml");
    std::fs::write(&bad, "[tip]\nmass = -1\n").unwrap();
    let out = bin()
        .args(["static", "--scene"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("tip.mass"));
    let csv = tmp("bad-accel.toml");
    std::fs::write(
        &csv,
        "[excitation]\ntype = \"csv\"\nfile = \"missing.csv\"\n",
    )
    .unwrap();
    let out = bin()
        .args(["run", "--no-plots", "--duration", "0.03", "--scene"])
        .arg(&csv)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.csv"));
    // Usage errors are clap's (exit code 2).
    let out = bin().args(["run", "--bogus"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn run_starts_at_the_static_deflection() {
    let out = bin().args(["static", "--json"]).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let d = v["static_tip_deflection"].as_f64().unwrap();
    assert!((d + 0.016).abs() < 0.001, "{d}");
    let dir = tmp("run");
    let out = bin()
        .args(["run", "--no-plots", "--duration", "0.3", "--json", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("paper.csv")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..7],
        &[
            "t",
            "base_y",
            "tip_y",
            "tip_deflection",
            "tip_angle",
            "ball_angle",
            "ball_rel_angle"
        ]
    );
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let first: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(first[col("t")], 0.0);
    assert!(
        (first[col("tip_deflection")] - d).abs() <= 1e-9 * d.abs(),
        "{} vs {d}",
        first[col("tip_deflection")]
    );
    assert_eq!(first[col("tip_y")], first[col("tip_deflection")]);
    assert_eq!(lines.count(), 100);
}

/// `calibrate` round trip: it writes a complete scene that `modes`, `static` and `run` take as
/// is, whose locked-ball f₁ and sag are the converged full solver's (N = 16: 4.108761 Hz,
/// −16.12983 mm; the fit reaches 5e-7, the budget is the calibration's 0.05 % / 0.1 %).
#[test]
fn calibrate_writes_a_scene_that_modes_static_and_run_accept() {
    let out = tmp("calibrated-n3.toml");
    let locked = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/locked.toml");
    let o = bin()
        .args(["calibrate", "--scene", locked, "--elements", "3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(text.contains("worst residual"), "{text}");
    let scene = Scene::load(out.to_str().unwrap()).unwrap();
    assert!(!scene.file.calibration.is_identity());
    let o = bin()
        .args(["modes", "--json", "--scene"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f1 = v["frequencies"][0].as_f64().unwrap();
    assert!((f1 / 4.108761 - 1.0).abs() < 5e-4, "{f1}");
    let o = bin()
        .args(["static", "--json", "--scene"])
        .arg(&out)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let sag = v["static_tip_deflection"].as_f64().unwrap();
    assert!((sag / -16.12983e-3 - 1.0).abs() < 1e-3, "{sag}");
    let dir = tmp("calibrated-run");
    let o = bin()
        .args(["run", "--no-plots", "--duration", "1", "--scene"])
        .arg(&out)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Bad factors are named.
    let bad = tmp("bad-calibration.toml");
    std::fs::write(&bad, "[calibration]\naxial_stiffness = 2.0\n").unwrap();
    let o = bin()
        .args(["static", "--scene"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("calibration.axial_stiffness"), "{e}");
}

/// `identify` → `calibrate --from-identified`: a damped sinusoid of 4.0 Hz, ζ = 1 % (exact
/// record, 2 % noise) is identified to 0.01 % in f and 2 % in ζ, and the calibrated scene puts
/// its locked-ball beam mode at the identified f₁ (to 1e-8, the fit's stopping rule) with the
/// integrator's 0.75 % at 4 Hz topped up by structural damping to the identified ζ.
#[test]
fn identify_then_calibrate_from_identified_hits_the_measured_pole() {
    let (f, z, dt) = (4.0, 0.01, 0.005);
    let w = std::f64::consts::TAU * f;
    let wd = w * (1.0f64 - z * z).sqrt();
    let mut csv = String::from("# synthetic decay\nt,tip_acceleration\n");
    let mut seed = 99u64;
    for k in 0..6000 {
        let t = k as f64 * dt;
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let noise = ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
        let x = (-z * w * t).exp() * (wd * t).cos() + 0.02 * noise;
        csv.push_str(&format!("{t},{x}\n"));
    }
    let rec = tmp("decay.csv");
    std::fs::write(&rec, csv).unwrap();
    let id = tmp("identified.toml");
    let o = bin()
        .args(["identify", "--csv"])
        .arg(&rec)
        .arg("--out")
        .arg(&id)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: toml::Value = toml::from_str(&std::fs::read_to_string(&id).unwrap()).unwrap();
    let (fi, zi) = (v["f1"].as_float().unwrap(), v["zeta"].as_float().unwrap());
    assert!((fi / f - 1.0).abs() < 1e-4, "{fi}");
    assert!((zi / z - 1.0).abs() < 0.02, "{zi}");
    let out = tmp("pole.toml");
    let locked = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/locked.toml");
    let o = bin()
        .args(["calibrate", "--scene", locked, "--from-identified"])
        .arg(&id)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = bin()
        .args(["modes", "--json", "--scene"])
        .arg(&out)
        .output()
        .unwrap();
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f1 = m["frequencies"][0].as_f64().unwrap();
    assert!((f1 / fi - 1.0).abs() < 1e-8, "{f1} vs {fi}");
    let scene = Scene::load(out.to_str().unwrap()).unwrap();
    let ratio = scene.file.damping.ratio.unwrap();
    assert!(ratio > 0.0 && ratio < zi, "{ratio}");
    assert!(text.contains("total"), "{text}");
    // A missing column is named.
    let o = bin()
        .args(["identify", "--column", "nope", "--csv"])
        .arg(&rec)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--column") && e.contains("tip_acceleration"),
        "{e}"
    );
}
