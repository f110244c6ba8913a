//! The quality gate of the fits: `identify` refuses a record that holds no decaying mode (white
//! noise, a constant, a growing oscillation, a band that misses the mode) and says why, the file
//! it writes carries the verdict, and `calibrate` refuses an unusable identification, a reference
//! that is not finer than the model and a fit that does not fit.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-fits-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Uniform numbers in [−1, 1] (a fixed LCG: the records are the same on every machine).
fn noise(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A record `t,tip_acceleration` of `n` samples at `dt`, written to `name`.
fn record(name: &str, dt: f64, n: usize, x: impl Fn(f64) -> f64, header: &str) -> PathBuf {
    let mut csv = format!("{header}t,tip_acceleration\n");
    for k in 0..n {
        let t = k as f64 * dt;
        csv.push_str(&format!("{t},{}\n", x(t)));
    }
    let p = tmp(name);
    std::fs::write(&p, csv).unwrap();
    p
}

/// A damped sinusoid at `f` [Hz] with damping ratio `z` (negative: growing) plus noise of
/// amplitude `a`.
fn decay(f: f64, z: f64, a: f64) -> impl Fn(f64) -> f64 {
    let w = TAU * f;
    let wd = w * (1.0 - z * z).sqrt();
    let table: Vec<f64> = {
        let mut u = noise(7);
        (0..200_000).map(|_| u()).collect()
    };
    move |t: f64| {
        let k = (t / 0.005).round() as usize % table.len();
        (-z * w * t).exp() * (wd * t).cos() + a * table[k]
    }
}

fn identify(rec: &Path, extra: &[&str]) -> Output {
    bin()
        .args(["identify", "--csv"])
        .arg(rec)
        .args(extra)
        .output()
        .unwrap()
}

fn refused(o: &Output, words: &[&str]) -> String {
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(
        o.status.code(),
        Some(1),
        "exit {:?}\nstdout {}\nstderr {e}",
        o.status,
        String::from_utf8_lossy(&o.stdout)
    );
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
    e
}

/// A clean 4.1 Hz decay (ζ = 0.5 %, 2 % noise) passes the gate; white noise, a constant, a
/// growing oscillation and a band that misses the mode do not, each with its reason.
#[test]
fn identify_refuses_records_without_a_decaying_mode() {
    let dt = 0.005;
    let good = record("good.csv", dt, 8000, decay(4.1, 0.005, 0.02), "");
    let o = identify(&good, &["--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["verdict"], "usable", "{v}");
    assert!((v["f1"].as_f64().unwrap() / 4.1 - 1.0).abs() < 1e-3, "{v}");

    // White noise: before the gate, f1 = 134.9 Hz, zeta = 0.349 with exit 0.
    let mut u = noise(3);
    let white: Vec<f64> = (0..8000).map(|_| u()).collect();
    let w = record(
        "white.csv",
        dt,
        8000,
        |t| white[(t / dt).round() as usize],
        "",
    );
    let e = refused(&identify(&w, &[]), &["no usable pole", "white.csv"]);
    assert!(e.contains("unexplained") || e.contains("bound"), "{e}");

    // A constant column: before, f1 = 250 Hz ± inf.
    let c = record("constant.csv", dt, 8000, |_| 1.5, "");
    refused(&identify(&c, &[]), &["`--column`", "constant"]);

    // Growing (zeta = −1 %): before, zeta = +0.000001 accepted downstream.
    let g = record("growing.csv", dt, 8000, decay(4.1, -0.01, 0.0), "");
    refused(&identify(&g, &[]), &["lower bound"]);

    // A band that misses the 4.1 Hz mode: before, 7.146 Hz from `--band 10,20`.
    let e = refused(&identify(&good, &["--band", "10,20"]), &["no usable pole"]);
    assert!(
        e.contains("outside the band") || e.contains("unexplained"),
        "{e}"
    );
    // A band above the Nyquist frequency (100 Hz) is an invalid option.
    refused(
        &identify(&good, &["--band", "50,150"]),
        &["`--band`", "Nyquist"],
    );
}

/// The file written for an unusable record carries the verdict, and `calibrate
/// --from-identified` refuses it; a byte-order mark before the header is not part of `t`.
#[test]
fn an_unusable_identification_is_written_as_such_and_refused_downstream() {
    let dt = 0.005;
    let g = record(
        "growing-bom.csv",
        dt,
        8000,
        decay(4.1, -0.01, 0.0),
        "\u{feff}",
    );
    let id = tmp("growing.toml");
    let o = bin()
        .args(["identify", "--csv"])
        .arg(&g)
        .arg("--out")
        .arg(&id)
        .output()
        .unwrap();
    refused(&o, &["lower bound"]);
    let text = std::fs::read_to_string(&id).unwrap();
    assert!(text.contains("verdict = \"unusable\""), "{text}");
    let out = tmp("never.toml");
    let locked = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/locked.toml");
    let o = bin()
        .args(["calibrate", "--scene", locked, "--from-identified"])
        .arg(&id)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    refused(&o, &["`--from-identified`", "unusable", "lower bound"]);
    assert!(!out.exists());
}

/// A reference no finer than the model is refused before any work (before the check, `--elements
/// 3 --reference-elements 1` stopped at the fit's cap with a 43.7 % residual and wrote a scene
/// with f1 = 4.999 Hz against the converged 4.109 Hz).
#[test]
fn calibrate_refuses_a_reference_not_finer_than_the_model() {
    let locked = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/locked.toml");
    for m in ["1", "3"] {
        let out = tmp(&format!("coarse{m}.toml"));
        let o = bin()
            .args(["calibrate", "--scene", locked, "--reference-elements", m])
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        refused(&o, &["`--reference-elements`", "must lie in 4 ..="]);
        assert!(!out.exists());
    }
}
