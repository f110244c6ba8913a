//! Bad input to the host tools: every loader and constructor rejects non-finite, negative, zero
//! or inconsistent values with an error naming the field; the binary prints one line and exits
//! non-zero, never a backtrace. (Complements `tests/cli.rs`.)

use absorber_core::{Error, Params};
use absorber_full::{FullSolver, SceneKind};
use absorber_sim::excitation::Excitation;
use absorber_sim::scene::Scene;
use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn err_of(text: &str) -> String {
    match Scene::from_toml(text) {
        Ok(_) => panic!("accepted: `{text}`"),
        Err(e) => format!("{e:#}"),
    }
}

/// Every numeric key of a scene file, with non-finite, negative and zero values (where zero is
/// invalid): an error naming the key, on one line.
#[test]
fn every_scene_key_rejects_bad_numbers_by_name() {
    let keys: &[(&str, &str, bool)] = &[
        // (section, key, zero is invalid)
        ("beam", "length", true),
        ("beam", "mass", true),
        ("beam", "area", true),
        ("beam", "modulus", true),
        ("beam", "inertia", true),
        ("tip", "mass", true),
        ("tip", "inertia", true),
        ("tip", "offset", false),
        ("ball", "mass", true),
        ("ball", "inertia", false),
        ("ball", "radius", true),
        ("ball", "track_radius", true),
        ("ball", "stop_angle_deg", true),
        ("ball", "restitution", false),
        ("ball", "stick_speed", false),
        ("ball", "lift_height", false),
        ("integrator", "gamma", true),
        ("integrator", "beta", true),
        ("integrator", "step", true),
        ("integrator", "tolerance", true),
        ("damping", "stiffness_proportional", false),
        ("excitation", "frequency", true),
        ("excitation", "amplitude", false),
    ];
    for &(section, key, zero_bad) in keys {
        let mut values = vec!["nan", "inf", "-inf", "-1.0"];
        if zero_bad {
            values.push("0.0");
        }
        for v in values {
            let text = format!("[{section}]\n{key} = {v}\n");
            let e = err_of(&text);
            let name = format!("{section}.{key}");
            assert!(
                e.contains(&name),
                "`{text}` gave `{e}`, which does not name `{name}`"
            );
            assert!(!e.contains('\n'), "{e}");
        }
    }
    for (text, key) in [
        ("gravity = nan\n", "gravity"),
        ("gravity = inf\n", "gravity"),
        ("duration = nan\n", "duration"),
        ("duration = -1.0\n", "duration"),
        ("duration = inf\n", "duration"),
        ("elements = 0\n", "elements"),
        ("elements = -3\n", "elements"),
        (
            "[ball]\ninitial_angle_deg = nan\n",
            "ball.initial_angle_deg",
        ),
        (
            "[ball]\ninitial_angle_deg = 70.0\n",
            "ball.initial_angle_deg",
        ),
        (
            "[integrator]\nmax_iterations = -1\n",
            "integrator.max_iterations",
        ),
        ("[damping]\nratio = nan\nfrequency = 4.0\n", "damping.ratio"),
        (
            "[damping]\nratio = 0.01\nfrequency = 0.0\n",
            "damping.frequency",
        ),
        (
            "[damping]\nratio = 0.01\nfrequency = nan\n",
            "damping.frequency",
        ),
        ("[outputs]\ntransient = -1.0\n", "outputs.transient"),
        ("[outputs]\ntransient = nan\n", "outputs.transient"),
        ("[outputs]\nevery = 0\n", "outputs.every"),
        // Above the path radius of the ball's centre (Table 1: 32 mm) no flight could count.
        ("[ball]\nlift_height = 0.05\n", "ball.lift_height"),
    ] {
        let e = err_of(text);
        assert!(
            e.contains(key),
            "`{text}` gave `{e}`, which does not name `{key}`"
        );
        assert!(!e.contains('\n'), "{e}");
    }
}

/// `ball.lift_height` names its allowed range, below and above it.
#[test]
fn lift_height_names_its_range() {
    for v in ["-1e-6", "0.05", "nan"] {
        let e = err_of(&format!("[ball]\nlift_height = {v}\n"));
        assert!(
            e.contains("ball.lift_height") && e.contains("0 <= lift_height < R - r_b"),
            "{e}"
        );
    }
    assert!(Scene::from_toml("[ball]\nlift_height = 1e-5\n").is_ok());
}

/// Inconsistent combinations are named too.
#[test]
fn inconsistent_scene_values_are_named() {
    for (text, key) in [
        ("[ball]\nradius = 0.05\n", "ball.track_radius"),
        ("[ball]\nstop_angle_deg = 180.0\n", "ball.stop_angle_deg"),
        ("[integrator]\ngamma = 0.9\nbeta = 0.3\n", "integrator.beta"),
        ("[integrator]\ngamma = 1.5\n", "integrator.gamma"),
        ("[integrator]\nrho_inf = 0.8\n", "integrator.rho_inf"),
        (
            "[integrator]\nscheme = \"generalized-alpha\"\n",
            "integrator.rho_inf",
        ),
        (
            "[integrator]\nscheme = \"generalized-alpha\"\nrho_inf = 1.2\n",
            "integrator.rho_inf",
        ),
        (
            "[integrator]\nscheme = \"generalized-alpha\"\nrho_inf = 0.8\ngamma = 0.6\n",
            "integrator.gamma",
        ),
        (
            "[excitation]\ntype = \"csv\"\nfile = \"a.csv\"\nfrequency = 3.0\n",
            "excitation.frequency",
        ),
        ("[excitation]\ntype = \"csv\"\n", "excitation.file"),
        ("[excitation]\nfile = \"a.csv\"\n", "excitation.file"),
        (
            "[damping]\nstiffness_proportional = 0.001\nratio = 0.01\nfrequency = 4.0\n",
            "damping.ratio",
        ),
        (
            "solver = \"full\"\nprecision = \"f32\"\nduration = 0.01\n",
            "f64",
        ),
    ] {
        match Scene::from_toml(text) {
            Err(e) => {
                let e = format!("{e:#}");
                assert!(
                    e.contains(key),
                    "`{text}` gave `{e}`, which does not name `{key}`"
                );
                assert!(!e.contains('\n'), "{e}");
            }
            Ok(scene) => {
                // Some checks happen when the solver is built.
                let e = absorber_sim::run::build_simulator(&scene, 0.0)
                    .err()
                    .map(|e| format!("{e:#}"))
                    .unwrap_or_else(|| panic!("`{text}` accepted"));
                assert!(e.contains(key), "`{text}` gave `{e}`");
            }
        }
    }
}

/// The full solver's constructor validates like the core and names the field.
#[test]
fn full_solver_rejects_bad_parameters_by_name() {
    let field = |e: Error| match e {
        Error::InvalidParameter { field, .. } => field,
        other => panic!("expected InvalidParameter, got {other:?}"),
    };
    for (change, name) in [
        (
            (|p: &mut Params<f64>| p.beam.length = f64::NAN) as fn(&mut Params<f64>),
            "beam.length",
        ),
        (|p| p.beam.modulus = -1.0, "beam.modulus"),
        (|p| p.tip.mass = 0.0, "tip.mass"),
        (|p| p.ball.radius = f64::INFINITY, "ball.radius"),
        (|p| p.ball.track_radius = 0.001, "ball.track_radius"),
        (|p| p.integrator.step = 0.0, "integrator.step"),
        (|p| p.gravity = f64::NAN, "gravity"),
    ] {
        let mut p = Params::default();
        change(&mut p);
        let e = FullSolver::new(p, SceneKind::FreeBall, 3).unwrap_err();
        assert_eq!(field(e), name);
    }
    assert!(FullSolver::new(Params::default(), SceneKind::FreeBall, 0).is_err());
}

/// The full solver's step rejects a non-finite input and keeps its state.
#[test]
fn full_solver_step_rejects_non_finite_input_and_keeps_the_state() {
    let mut s = FullSolver::at_rest(Params::default(), SceneKind::FreeBall, 2, 0.0).unwrap();
    for k in 0..20 {
        s.step(0.3 * (k as f64 * 0.2).sin()).unwrap();
    }
    let before = s.state().clone();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(s.step(bad), Err(Error::NonFiniteInput));
        assert_eq!(*s.state(), before);
    }
    // A violent sample: an error (no convergence) or a finite step, never a panic or NaN.
    match s.step(1e9) {
        Ok(_) => assert!(s.state().q.iter().all(|x| x.is_finite())),
        Err(_) => assert_eq!(*s.state(), before),
    }
    s.step(0.0).unwrap();
}

/// Malformed CSV excitations: clear errors (more in `tests/cli.rs`).
#[test]
fn malformed_csv_is_a_clear_error() {
    let h = 1e-3;
    for (text, what) in [
        ("", "at least 2"),
        ("# only a comment\n", "at least 2"),
        ("t,accel\n", "at least 2"),
        ("0,nan\n0.001,0\n", "not finite"),
        ("nan,0\n0.001,0\n", "not finite"),
        ("0,0\n0.001,1e400\n", "not finite"),
        ("0,0\n-0.001,0\n", "does not increase"),
        ("0,0,0\n0.001,0,0\n", "2 columns"),
        ("0,0\n0.001,0\nx,y\n", "line 3"),
        ("0;0\n0.001;abc\n", "line 2"),
    ] {
        let e = format!(
            "{:#}",
            Excitation::from_csv_text(text, h, None).expect_err(text)
        );
        assert!(e.contains(what), "`{text}` gave `{e}`");
        assert!(!e.contains('\n'), "{e}");
    }
    // Bytes that are not UTF-8.
    let p = tmp("binary.csv");
    std::fs::write(&p, [0xff, 0xfe, 0x00, 0x41]).unwrap();
    assert!(Excitation::from_csv(&p, h, None).is_err());
}

fn one_line_failure(args: &[&str], extra: Option<&std::path::Path>, needle: &str) {
    let mut cmd = bin();
    cmd.args(args);
    if let Some(p) = extra {
        cmd.arg(p);
    }
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(
        err.starts_with("error: ") && err.trim_end().lines().count() == 1,
        "{args:?}: {err}"
    );
    assert!(
        !err.contains("panic") && !err.contains("backtrace") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    assert!(err.contains(needle), "{args:?}: `{err}` lacks `{needle}`");
}

/// The binary: malformed scene or CSV files give one line on stderr and exit code 1.
#[test]
fn binary_reports_malformed_files_on_one_line() {
    let cases: &[(&str, &str, &str)] = &[
        ("syntax.toml", "[beam\nlength = 1\n", "line"),
        ("type.toml", "[beam]\nlength = \"long\"\n", "beam.length"),
        ("nan.toml", "[beam]\nlength = nan\n", "beam.length"),
        ("neg.toml", "[tip]\ninertia = -1e-5\n", "tip.inertia"),
        ("unknown.toml", "[ball]\ncolour = 1\n", "colour"),
        ("zero.toml", "[integrator]\nstep = 0.0\n", "integrator.step"),
        ("binary.toml", "\u{0}\u{1}\u{2}", "line"),
    ];
    for (name, text, needle) in cases {
        let p = tmp(name);
        std::fs::write(&p, text).unwrap();
        one_line_failure(&["static", "--scene"], Some(&p), needle);
    }
    // A scene whose CSV is malformed, and one that is not UTF-8.
    let csv = tmp("bad.csv");
    std::fs::write(&csv, "t,accel\n0,0\n0.001,oops\n").unwrap();
    let scene = tmp("csv-scene.toml");
    std::fs::write(
        &scene,
        format!(
            "duration = 0.002\n[integrator]\nstep = 0.001\n[excitation]\ntype = \"csv\"\nfile = \"{}\"\n",
            csv.display()
        ),
    )
    .unwrap();
    one_line_failure(&["run", "--no-plots", "--scene"], Some(&scene), "line 3");
    let nan_csv = tmp("nan.csv");
    std::fs::write(&nan_csv, "0,0\n0.001,NaN\n0.002,0\n").unwrap();
    std::fs::write(
        &scene,
        format!(
            "duration = 0.002\n[integrator]\nstep = 0.001\n[excitation]\ntype = \"csv\"\nfile = \"{}\"\n",
            nan_csv.display()
        ),
    )
    .unwrap();
    one_line_failure(
        &["run", "--no-plots", "--scene"],
        Some(&scene),
        "not finite",
    );
    let bin_scene = tmp("latin1.toml");
    std::fs::write(&bin_scene, [b'n', b'a', b'm', b'e', b'=', 0xe9, b'\n']).unwrap();
    let out = bin()
        .args(["static", "--scene"])
        .arg(&bin_scene)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: ") && err.trim_end().lines().count() == 1,
        "{err}"
    );
    // Overrides on the command line.
    one_line_failure(
        &["run", "--no-plots", "--step", "nan"],
        None,
        "integrator.step",
    );
    one_line_failure(
        &["run", "--no-plots", "--step=-0.001"],
        None,
        "integrator.step",
    );
    one_line_failure(
        &[
            "run",
            "--no-plots",
            "--amplitude",
            "inf",
            "--duration",
            "0.01",
        ],
        None,
        "excitation.amplitude",
    );
    one_line_failure(
        &[
            "run",
            "--no-plots",
            "--frequency",
            "0",
            "--duration",
            "0.01",
        ],
        None,
        "excitation.frequency",
    );
}

/// `host-sim <args>` in `dir`: exit code and stderr.
fn refused_in(dir: &std::path::Path, args: &[&str]) -> (i32, String) {
    let o = bin().args(args).current_dir(dir).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Cases of the bad-input matrix (scripts/error-matrix.py) that were accepted with no answer
/// or refused without naming the option, its value or what is allowed: each is now refused
/// before any work, on one error line that holds every listed word.
#[test]
fn options_are_refused_with_name_value_and_range() {
    let dir = tmp("matrix");
    std::fs::create_dir_all(&dir).unwrap();
    let arm = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/mast-arm.toml"
    ))
    .unwrap();
    let scene = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let missing_value = scene("missing-value.toml", "[beam]\nlength =\n");
    let long_beam = scene("long-beam.toml", "[beam]\nlength = 1e300\n");
    let stiff = scene("stiff.toml", "[beam]\nmodulus = 1e300\n");
    let big_ball = scene("big-ball.toml", "[ball]\nradius = 1e300\n");
    let narrow_stops = scene("narrow-stops.toml", "[ball]\nstop_angle_deg = 1e-300\n");
    let thick_wall = scene(
        "thick-wall.toml",
        &arm.replacen("wall = 0.00455", "wall = 0.5", 1),
    );
    let no_density = scene(
        "no-density.toml",
        &arm.replacen("density = 7850.0", "density = 0.0", 1),
    );
    let cases: Vec<(Vec<&str>, i32, Vec<&str>)> = vec![
        (
            vec!["modes", "--count", "0"],
            1,
            vec!["`--count`", "0", "at least 1"],
        ),
        (
            vec!["estimate", "--lab", "--tip-force", "1e300"],
            1,
            vec!["`--tip-force`", "1e300", "0 < force ≤"],
        ),
        (
            vec!["estimate", "--frequency", "4"],
            1,
            vec!["`--frequency`", "4", "only with `--lab`"],
        ),
        (
            vec!["identify", "--csv", "none.csv", "--band", "1"],
            1,
            vec!["`--band`", "1", "two frequencies"],
        ),
        (
            vec!["static", "--scene", &missing_value],
            1,
            vec!["`beam.length`", "no value", "allowed: a number"],
        ),
        (
            vec!["static", "--scene", &long_beam],
            1,
            vec!["`beam.length`", "1e300", "allowed: "],
        ),
        (
            vec!["static", "--scene", &stiff],
            1,
            vec!["`beam.modulus`", "1e300", "allowed: "],
        ),
        (
            vec!["static", "--scene", &big_ball],
            1,
            vec![
                "`ball.track_radius`",
                "`ball.radius` = 1e300",
                "must exceed",
            ],
        ),
        (
            vec!["static", "--scene", &narrow_stops],
            1,
            vec![
                "`ball.initial_angle_deg`",
                "`ball.stop_angle_deg` = 1e-300",
                "inside the stops",
            ],
        ),
        (
            vec!["modes", "--scene", &thick_wall],
            1,
            vec![
                "`arm.wall`: 0.5",
                "`arm.root_diameter` = 0.33",
                "must be less than half",
            ],
        ),
        (
            vec!["modes", "--scene", &no_density],
            1,
            vec!["`arm.density`: 0", "must be finite and positive"],
        ),
        (
            vec!["bogus"],
            2,
            vec![
                "unknown command `bogus`",
                "allowed: paper, static, modes, run",
            ],
        ),
        (
            // The studies that write docs/ are the developer tool `absorber-studies`.
            vec!["stability"],
            2,
            vec![
                "unknown command `stability`",
                "sweep, tune, fatigue, calibrate",
            ],
        ),
    ];
    for (args, code, words) in cases {
        let (rc, err) = refused_in(&dir, &args);
        assert_eq!(rc, code, "{args:?}: {err}");
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(errors.len(), 1, "{args:?}: {err}");
        for w in words {
            assert!(
                errors[0].contains(w),
                "{args:?}: `{}` lacks `{w}`",
                errors[0]
            );
        }
    }
}

/// `identify` reads a record separated by semicolons, tabs or spaces as the excitation record
/// is read: the same f₁ and ζ to the last digit as from the comma-separated file.
#[test]
fn identify_reads_other_separators() {
    let dir = tmp("separators");
    std::fs::create_dir_all(&dir).unwrap();
    let decay: String = std::iter::once("t,tip_acceleration\n".to_string())
        .chain((0..4000).map(|i| {
            let t = i as f64 * 0.002;
            format!("{t},{}\n", (-0.08 * t).exp() * (25.8 * t).sin())
        }))
        .collect();
    let mut outputs = Vec::new();
    for (name, sep) in [
        ("comma", ","),
        ("semicolon", ";"),
        ("tab", "\t"),
        ("space", "  "),
    ] {
        let p = dir.join(format!("{name}.csv"));
        std::fs::write(
            &p,
            format!("\u{feff}# a comment\n{}", decay.replace(',', sep)),
        )
        .unwrap();
        let o = bin()
            .args(["identify", "--json", "--csv", p.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        // 25.8 rad/s = 4.1062 Hz; ζ = 0.08 / 25.8 = 0.0031.
        let f1 = json["f1"].as_f64().unwrap();
        assert!(
            (f1 - 25.8 / std::f64::consts::TAU).abs() < 1e-3,
            "{name}: f1 {f1}"
        );
        outputs.push(o.stdout);
    }
    assert!(outputs.windows(2).all(|w| w[0] == w[1]));
}

/// A failed run into the directory of a good one keeps the good one's files and, in its
/// manifest, the good one's result to the last digit (read back and written again: the
/// default JSON float parser could land one unit in the last place off).
#[test]
fn a_failed_run_keeps_the_previous_result_exactly() {
    let dir = tmp("previous");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let good = bin()
        .args(["run", "--duration", "0.2", "--no-plots", "--out", out])
        .output()
        .unwrap();
    assert!(
        good.status.success(),
        "{}",
        String::from_utf8_lossy(&good.stderr)
    );
    let manifest = std::path::Path::new(out).join("paper.manifest.json");
    let read = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap()
    };
    let first = read();
    let csv = std::fs::read(std::path::Path::new(out).join("paper.csv")).unwrap();
    // A run that fails after it opened the directory: its CSV exceeds a 100 KiB file-size
    // limit (`ulimit -f`).
    let mut cmd = bin();
    cmd.args(["run", "--duration", "20", "--every", "1", "--out", out]);
    // SAFETY: setrlimit is async-signal-safe; the closure touches nothing else.
    unsafe {
        use std::os::unix::process::CommandExt;
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 100 * 1024,
                rlim_max: 100 * 1024,
            };
            libc::setrlimit(libc::RLIMIT_FSIZE, &limit);
            Ok(())
        });
    }
    let bad = cmd.output().unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("paper.csv"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
    let second = read();
    assert_eq!(second["status"], "failed");
    assert_eq!(second["previous"]["result"], first["result"]);
    assert_eq!(
        std::fs::read(std::path::Path::new(out).join("paper.csv")).unwrap(),
        csv
    );
}
