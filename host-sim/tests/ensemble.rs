//! Ensembles of the chaotic free ball (`absorber_sim::ensemble`): seeded and reproducible, one
//! member is the plain run byte for byte; and the rows of event steps tell the truth about the
//! track.

use absorber_sim::ensemble::{spread_of, Ensemble};
use absorber_sim::run::{scene_excitation, simulate};
use absorber_sim::scene::{Scene, Solver};
use absorber_sim::simulate::{run_ensemble_in_memory, run_in_memory};
use host_sim::cli::SceneArgs;
use std::process::Command;

fn scene(args: SceneArgs) -> Scene {
    args.load().expect("scene")
}

fn paper(frequency: f64, duration: f64) -> Scene {
    scene(SceneArgs {
        frequency: Some(frequency),
        duration: Some(duration),
        ..Default::default()
    })
}

/// The same seed gives the same statistics whatever the thread count (the members are seeded
/// by their index, not by their order of execution); another seed gives others; every
/// statistic carries K; the members differ (the run is chaotic: 0.1° and 0.01 rad/s change
/// the steady amplitude); one member is the plain run's summary.
#[test]
fn seeded_ensembles_are_reproducible_and_one_member_is_the_plain_run() {
    let s = paper(4.10, 20.0);
    let e = Ensemble::new(4, 7).expect("ensemble");
    let on = |threads: usize, e: Ensemble| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| run_ensemble_in_memory(&s, Some(10.0), None, e))
            .expect("run")
            .1
    };
    let a = on(1, e);
    let b = on(2, e);
    assert_eq!(a, b);
    let tip = spread_of(&a["tip_amplitude_steady"]).expect("a spread");
    println!("tip amplitude over 4 members: {tip:?}");
    assert_eq!(tip.k, 4);
    assert!(tip.min < tip.max && tip.min <= tip.mean && tip.mean <= tip.max);
    assert!(tip.sd > 0.0);
    assert_eq!(a["steady_from"], 10.0);
    let other = on(2, Ensemble::new(4, 8).expect("ensemble"));
    assert_ne!(a, other);
    // One member: the plain run's summary, unchanged.
    let plain = run_in_memory(&s, Some(10.0), None).expect("run").1;
    let one = run_ensemble_in_memory(&s, Some(10.0), None, Ensemble::single())
        .expect("run")
        .1;
    assert_eq!(plain, one);
}

fn host_sim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim")
}

/// `run --ensemble 1` writes the CSV and prints the JSON of a plain `run`, byte for byte (but
/// the wall time); `--ensemble 3` prints every statistic as {mean, sd, min, max, k}.
#[test]
fn ensemble_of_one_is_the_plain_run_byte_for_byte() {
    let base = std::env::temp_dir().join(format!("host-sim-ensemble-{}", std::process::id()));
    let run = |name: &str, extra: &[&str]| {
        let d = base.join(name);
        let _ = std::fs::remove_dir_all(&d);
        let mut args = vec![
            "run",
            "--duration",
            "4",
            "--transient",
            "2",
            "--no-plots",
            "--json",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", d.to_str().expect("path")]);
        let o = host_sim(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        v["wall_time"] = serde_json::Value::Null;
        v["csv"] = serde_json::Value::Null;
        (v, std::fs::read(d.join("paper.csv")).expect("csv"))
    };
    let (plain, plain_csv) = run("plain", &[]);
    let (one, one_csv) = run("one", &["--ensemble", "1", "--seed", "5"]);
    assert_eq!(plain, one);
    assert!(plain_csv == one_csv, "the CSVs differ");
    let (three, three_csv) = run("three", &["--ensemble", "3"]);
    assert!(plain_csv == three_csv, "member 0 writes the CSV");
    let s = &three["summary"];
    for key in ["tip_amplitude_steady", "impacts", "tip_rms_steady"] {
        let v = &s[key];
        for f in ["mean", "sd", "min", "max", "k"] {
            assert!(v.get(f).is_some(), "{key}: {v}");
        }
        assert_eq!(v["k"], 3, "{key}");
    }
    assert_eq!(three["ensemble"]["k"], 3);
    assert_eq!(three["ensemble"]["members"][0]["initial_rate"], 0.0);
    let o = host_sim(&["run", "--ensemble", "0", "--duration", "1"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--ensemble"));
    let _ = std::fs::remove_dir_all(&base);
}

/// A row that says the ball is on the track (`contact = 1`) never has the track pulling it
/// (N < 0): at the end of a step with a stop impact or a landing the ball takes off when the
/// track would pull. The reference is the contact law itself (a track only pushes). Table 1 at
/// 4.10 Hz, 60 s, core and full solver: this run used to have 97 of 20,001 rows with
/// `contact = 1` and N down to −0.15 m_b g, all at event steps.
#[test]
fn no_row_on_the_track_has_the_track_pulling() {
    for solver in [Solver::Core, Solver::Full] {
        let mut s = paper(4.10, 60.0);
        s.file.solver = solver;
        let exc = scene_excitation(&s).expect("excitation");
        let p = s.params().expect("params");
        let weight = p.ball.mass * p.gravity;
        let (mut rows, mut pulled, mut events, mut worst) = (0u32, 0u32, 0u32, 0.0f64);
        simulate(
            &s,
            &exc,
            s.steps(),
            |r| {
                rows += 1;
                let e = r.events;
                events += u32::from(e.separations + e.landings + e.impacts > 0);
                if r.contact == 1.0 && r.normal_force < 0.0 {
                    pulled += 1;
                    worst = worst.min(r.normal_force / weight);
                }
            },
            |_| {},
        )
        .expect("run");
        println!(
            "{solver:?}: {rows} rows, {events} event steps, {pulled} on the track with N < 0 \
             (min {worst:.3} m_b g)"
        );
        assert!(events > 100, "{events}");
        assert_eq!(pulled, 0, "min N {worst} m_b g");
    }
}

/// The built-in physics scene loads (generalized-α, a steel arm's damping, the calibrated
/// 3-element f32 model), and `paper` says in one line that the paper's integrator damps by an
/// amount that depends on h: (γ − ½) ω h / 2 = 0.2 · 2π · 4.13 Hz · 3 ms / 2 = 0.78 % of
/// critical at the excitation frequency; the physics scene's integrator needs no such line.
#[test]
fn physics_scene_is_built_in_and_paper_names_its_step_dependent_damping() {
    let p = Scene::load("physics").expect("physics");
    assert_eq!(p.file.integrator.rho_inf, Some(0.8));
    assert_eq!(p.file.elements, 3);
    assert!(p.file.damping.ratio.is_some_and(|r| r > 0.0));
    assert!(!p.file.calibration.is_identity());
    assert!(host_sim::commands::step_damping_line(&p).is_none());
    let line = host_sim::commands::step_damping_line(&Scene::paper()).expect("a line");
    assert!(line.contains("0.78 %"), "{line}");
}
