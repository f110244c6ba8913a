//! The `host-sim` command line: `paper`, `static`, `modes`, `run`, `sweep`, `tune`.

use crate::figures::run_plots;
use crate::run::{half_range, run_rows, write_csv, Row};
use crate::scene::{ExcitationType, Kind, Plot, Precision, Scene, Solver};
use crate::sweep::{sweep, PAPER_FREQUENCIES};
use crate::tune::tune;
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Free pendulum vibration absorber on a flexible cantilever (Gumus & Ertas): run scenes,
/// sweep the excitation frequency, compute static deflection and modes, tune the track radius.
///
/// Without a command: `paper` (a short summary of the paper's scene at 4.13 Hz).
/// Units are SI throughout (m, s, kg, rad; frequencies in Hz).
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about)]
pub struct Cli {
    /// What to do (default: paper).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Short summary of a scene (default the paper's, 4.13 Hz, 60 s): static deflection,
    /// frequencies, tip and ball amplitudes, energy flow from the beam to the ball.
    Paper(PaperArgs),
    /// Static tip deflection under gravity [m].
    Static(InfoArgs),
    /// Natural frequencies about the static equilibrium [Hz].
    Modes(ModesArgs),
    /// Time history of a scene: CSV and PNG plots (paper Figs. 8–23).
    ///
    /// Writes `<out>/<name>.csv`, one row per step (every n-th with --every), SI units, angles
    /// in rad, documented in the file's `#` header: t [s]; base_y = y_b [m]; tip_y = y_b +
    /// deflection, the absolute height of the beam end [m]; tip_deflection, relative to the
    /// base, static sag included [m]; tip_angle ψ [rad]; ball_angle θ from the downward
    /// vertical [rad]; ball_rel_angle θ − ψ [rad]; beam_strain, beam_kinetic, beam_potential,
    /// tip_kinetic, tip_potential, ball_kinetic, ball_potential [J] (kinetic with absolute
    /// velocities, i.e. with the base velocity; potentials as changes from the static state,
    /// with the base displacement); iterations (Newton, per step); impact (1 if the ball hit a
    /// stop); then base_accel [m/s²], tip_velocity [m/s], tip_rate, ball_rate, ball_rel_rate
    /// [rad/s], ball_spin φ [rad], ball_spin_rate [rad/s]. Base velocity and displacement are
    /// closed form for a harmonic excitation and integrated (zero mean) for a CSV one.
    ///
    /// Plots `<out>/<name>_{time,fft,phase,energy}.png`: time histories, FFT of tip and ball
    /// after the transient, phase planes (y–ẏ, θ–θ̇, φ–φ̇, θ–ψ), energy curves.
    Run(RunArgs),
    /// Frequency response (paper Fig. 10): one run per frequency in parallel, steady-state
    /// amplitudes of the tip [m] and the ball [deg] over the last part; CSV and PNG.
    Sweep(SweepArgs),
    /// Track radius R that puts the ball at half the beam's first frequency (coupled
    /// linearized model), by bisection.
    Tune(TuneArgs),
    /// Numerical stability matrix (stiff and extreme cases, bad input, f32/f64 drift);
    /// writes docs/stability.md.
    Stability(crate::stability::StabilityArgs),
    /// Fatigue damage rate at the clamp vs frequency, free vs locked ball (root stress,
    /// rainflow, AASHTO S–N, Miner): CSV and PNG.
    Fatigue(crate::fatigue::FatigueArgs),
    /// Writes docs/accuracy.md: error of embedded configurations (elements, step, precision,
    /// Newton budget) against a converged full-solver reference, and their run time.
    Accuracy(crate::accuracy::AccuracyArgs),
    /// Writes docs/validation.md: every quantitative claim of the paper beside this model's
    /// numbers (3 elements and a converged mesh), with verdicts, reasons and figures.
    Validation(ValidationArgs),
}

/// `validation` options.
#[derive(Args, Debug, Clone)]
pub struct ValidationArgs {
    /// Output document.
    #[arg(long, default_value = "docs/validation.md")]
    pub out: std::path::PathBuf,
    /// Directory of its figures (the document links them as `img/...`).
    #[arg(long, default_value = "docs/img")]
    pub img: std::path::PathBuf,
    /// Elements of the converged mesh.
    #[arg(long, default_value_t = 16)]
    pub converged: usize,
}

/// Scene selection and overrides shared by all commands.
#[derive(Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// `paper` (built in) or a scene TOML file.
    #[arg(long, short, default_value = "paper")]
    pub scene: String,
    /// Solver (overrides the scene).
    #[arg(long, value_enum)]
    pub solver: Option<Solver>,
    /// Bodies (overrides the scene).
    #[arg(long, value_enum)]
    pub kind: Option<Kind>,
    /// Beam elements: core 1, 2, 3, 4, 6, 8 or 16; full any (overrides the scene).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Scalar (overrides the scene).
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
    /// Harmonic excitation frequency [Hz] (overrides the scene).
    #[arg(long)]
    pub frequency: Option<f64>,
    /// Harmonic base amplitude [m] (overrides the scene; paper 0.5e-3).
    #[arg(long)]
    pub amplitude: Option<f64>,
    /// Simulated time [s] (overrides the scene).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Time step h [s] (overrides the scene).
    #[arg(long)]
    pub step: Option<f64>,
}

impl SceneArgs {
    /// Loads the scene and applies the overrides.
    pub fn load(&self) -> Result<Scene> {
        let mut s = Scene::load(&self.scene)?;
        let f = &mut s.file;
        if let Some(v) = self.solver {
            f.solver = v;
        }
        if let Some(v) = self.kind {
            f.kind = v;
        }
        if let Some(v) = self.elements {
            f.elements = v;
        }
        if let Some(v) = self.precision {
            f.precision = v;
        }
        if self.frequency.is_some() || self.amplitude.is_some() {
            if f.excitation.kind != ExcitationType::Harmonic {
                f.excitation.kind = ExcitationType::Harmonic;
                f.excitation.file = None;
            }
            f.excitation.frequency = self.frequency.or(f.excitation.frequency);
            f.excitation.amplitude = self.amplitude.or(f.excitation.amplitude);
        }
        if let Some(v) = self.duration {
            f.duration = v;
        }
        if let Some(v) = self.step {
            f.integrator.step = v;
        }
        s.validate()?;
        Ok(s)
    }
}

/// `static`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    json: bool,
}

/// `modes`.
#[derive(Args, Debug)]
pub struct ModesArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// How many of the lowest frequencies to print.
    #[arg(long, default_value_t = 4)]
    count: usize,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    json: bool,
}

/// `run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output directory (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Plots to draw (default: the scene's `outputs.plots`).
    #[arg(long, value_enum, value_delimiter = ',')]
    plots: Option<Vec<Plot>>,
    /// Write the CSV only.
    #[arg(long)]
    no_plots: bool,
    /// Write every n-th step to the CSV (default: the scene's `outputs.every`).
    #[arg(long)]
    every: Option<usize>,
    /// Transient left out of the FFT and the amplitudes [s] (default: `outputs.transient`).
    #[arg(long)]
    transient: Option<f64>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// `sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Excitation frequencies [Hz] (default: the paper's 14, 3.50 … 4.70).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    freqs: Option<Vec<f64>>,
    /// Steady-state window at the end of each run [s].
    #[arg(long, default_value_t = 20.0)]
    last: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output directory (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Skip the PNG.
    #[arg(long)]
    no_plots: bool,
    /// Print the result as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// `tune`.
#[derive(Args, Debug)]
pub struct TuneArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Target ball / beam frequency ratio.
    #[arg(long, default_value_t = 0.5)]
    ratio: f64,
    /// Write the scene with the tuned R (and name "tuned") to this TOML file.
    #[arg(long)]
    write: Option<PathBuf>,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    json: bool,
}

/// `paper`.
#[derive(Args, Debug, Default)]
pub struct PaperArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Machine-readable output (JSON on stdout).
    #[arg(long)]
    json: bool,
}

/// Runs the parsed command line.
pub fn main(cli: Cli) -> Result<()> {
    match cli.command.unwrap_or(Command::Paper(PaperArgs {
        scene: SceneArgs {
            scene: "paper".into(),
            ..Default::default()
        },
        json: false,
    })) {
        Command::Paper(a) => paper(&a),
        Command::Static(a) => static_cmd(&a),
        Command::Modes(a) => modes(&a),
        Command::Run(a) => run(&a),
        Command::Sweep(a) => sweep_cmd(&a),
        Command::Tune(a) => tune_cmd(&a),
        Command::Stability(a) => crate::stability::command(&a),
        Command::Fatigue(a) => crate::fatigue::run(&a),
        Command::Accuracy(a) => crate::accuracy::run(&a),
        Command::Validation(a) => {
            let t0 = std::time::Instant::now();
            crate::validation::write(&a.out, &a.img, a.converged, &|stage| {
                eprintln!("validation: {stage}…")
            })?;
            eprintln!(
                "validation: wrote {} in {:.1} s",
                a.out.display(),
                t0.elapsed().as_secs_f64()
            );
            Ok(())
        }
    }
}

fn describe(s: &Scene) -> String {
    let f = &s.file;
    let exc = match f.excitation.kind {
        ExcitationType::Harmonic => format!(
            "base {:.3} mm at {} Hz",
            f.excitation.amplitude_or_paper() * 1e3,
            f.excitation.frequency_or_paper()
        ),
        ExcitationType::Csv => format!(
            "base acceleration from {}",
            f.excitation
                .file
                .as_deref()
                .map(Path::display)
                .map(|d| d.to_string())
                .unwrap_or_default()
        ),
    };
    format!(
        "scene {}: {}, {} elements, {}, {} solver; {}; {} s with h = {} s",
        f.name,
        f.kind.name(),
        f.elements,
        match f.precision {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        },
        f.solver.name(),
        exc,
        f.duration,
        f.integrator.step
    )
}

fn static_cmd(a: &InfoArgs) -> Result<()> {
    let s = a.scene.load()?;
    let sim = crate::run::build_simulator(&s, 0.0)?;
    let d = sim.static_tip_deflection();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "kind": s.file.kind.name(), "elements": s.file.elements, "solver": sim.solver_name(), "static_tip_deflection": d })
        );
    } else {
        println!("{}", describe(&s));
        println!("static tip deflection: {d:.6e} m ({:.3} mm)", d * 1e3);
    }
    Ok(())
}

fn modes(a: &ModesArgs) -> Result<()> {
    let s = a.scene.load()?;
    let sim = crate::run::build_simulator(&s, 0.0)?;
    let f = sim
        .natural_frequencies()
        .map_err(|e| crate::scene::map_core_error(e, &s))?;
    let f: Vec<f64> = f.into_iter().take(a.count).collect();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "kind": s.file.kind.name(), "elements": s.file.elements, "solver": sim.solver_name(), "frequencies": f })
        );
    } else {
        println!("{}", describe(&s));
        for (i, x) in f.iter().enumerate() {
            println!("mode {}: {x:.4} Hz", i + 1);
        }
        if s.file.kind.free_ball() {
            let p = s.params()?;
            println!(
                "(ball on a fixed housing: {:.4} Hz)",
                p.ball.fixed_housing_frequency(p.gravity)
            );
        }
    }
    Ok(())
}

fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// Summary numbers of a run.
fn summary(rows: &[Row], transient: f64) -> serde_json::Value {
    let end = rows.last().map(|r| r.t).unwrap_or(0.0);
    let strain0 = rows.first().map(|r| r.energies.beam_strain).unwrap_or(0.0);
    // A transient as long as the run would leave nothing: then use the second half.
    let from = if transient < end {
        transient
    } else {
        end / 2.0
    };
    let max_abs = |f: &dyn Fn(&Row) -> f64, a: f64, b: f64| {
        rows.iter()
            .filter(|r| r.t >= a && r.t <= b)
            .map(f)
            .filter(|x| x.is_finite())
            .fold(f64::NAN, |m, x| m.max(x.abs()))
    };
    let mean = |f: &dyn Fn(&Row) -> f64, a: f64, b: f64| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r.t >= a && r.t <= b)
            .map(f)
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let static_d = rows.first().map(|r| r.tip_deflection).unwrap_or(f64::NAN);
    let beam = |r: &Row| {
        r.energies.beam_strain - strain0 + r.energies.beam_kinetic + r.energies.beam_potential
    };
    let ball = |r: &Row| r.energies.ball_kinetic + r.energies.ball_potential;
    let w = 10.0f64.min(end / 2.0);
    json!({
        "duration": end,
        "steady_from": from,
        "static_tip_deflection": static_d,
        "tip_amplitude_max": max_abs(&|r: &Row| r.tip_deflection - static_d, 0.0, end),
        "tip_amplitude_steady": half_range(rows, from, |r| r.tip_deflection),
        "ball_angle_max_deg": max_abs(&|r: &Row| r.ball_angle.to_degrees(), 0.0, end),
        "ball_angle_steady_deg": half_range(rows, from, |r| r.ball_angle.to_degrees()),
        "impacts": rows.iter().filter(|r| r.impact).count(),
        "max_iterations": rows.iter().map(|r| r.iterations).max().unwrap_or(0),
        "energy_window": w,
        "beam_energy_first": mean(&beam, 0.0, w),
        "beam_energy_last": mean(&beam, end - w, end),
        "ball_energy_first": mean(&ball, 0.0, w),
        "ball_energy_last": mean(&ball, end - w, end),
    })
}

fn num(v: &serde_json::Value, k: &str) -> f64 {
    v.get(k).and_then(|x| x.as_f64()).unwrap_or(f64::NAN)
}

fn print_summary(s: &serde_json::Value) {
    let w = num(s, "energy_window");
    println!(
        "static tip deflection      {:.3} mm",
        1e3 * num(s, "static_tip_deflection")
    );
    println!(
        "tip amplitude              max {:.3} mm; steady (t ≥ {:.1} s, half peak-to-peak) {:.3} mm",
        1e3 * num(s, "tip_amplitude_max"),
        num(s, "steady_from"),
        1e3 * num(s, "tip_amplitude_steady")
    );
    println!(
        "ball angle θ               max {:.1}°; steady {:.1}°; {} stop impacts",
        num(s, "ball_angle_max_deg"),
        num(s, "ball_angle_steady_deg"),
        s.get("impacts").and_then(|x| x.as_u64()).unwrap_or(0)
    );
    println!(
        "mean energy [mJ]           beam {:.3} (first {w:.1} s) → {:.3} (last {w:.1} s); ball {:.3} → {:.3}",
        1e3 * num(s, "beam_energy_first"),
        1e3 * num(s, "beam_energy_last"),
        1e3 * num(s, "ball_energy_first"),
        1e3 * num(s, "ball_energy_last")
    );
}

fn paper(a: &PaperArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = a.scene.load()?;
    let transient = s.file.outputs.transient.min(s.file.duration / 2.0);
    let sim = crate::run::build_simulator(&s, 0.0)?;
    let freqs = sim
        .natural_frequencies()
        .map_err(|e| crate::scene::map_core_error(e, &s))?;
    let pb = progress_bar(s.steps() as u64, "free ball");
    let rows = run_rows(&s, |k| pb.set_position(k as u64))?;
    pb.finish_and_clear();
    let free = summary(&rows, transient);
    let mut locked = None;
    if s.file.kind.free_ball() {
        let mut l = s.clone();
        l.file.kind = Kind::Locked;
        let pb = progress_bar(l.steps() as u64, "locked ball");
        let rows = run_rows(&l, |k| pb.set_position(k as u64))?;
        pb.finish_and_clear();
        locked = Some(summary(&rows, transient));
    }
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "frequencies": freqs.iter().take(3).collect::<Vec<_>>(), "run": free, "locked": locked, "wall_time": wall })
        );
        return Ok(());
    }
    println!("{}", describe(&s));
    let f: Vec<String> = freqs.iter().take(3).map(|x| format!("{x:.3}")).collect();
    println!("lowest frequencies         {} Hz", f.join(", "));
    print_summary(&free);
    if let Some(l) = &locked {
        println!(
            "locked ball (passive)      tip amplitude max {:.3} mm, steady {:.3} mm",
            1e3 * num(l, "tip_amplitude_max"),
            1e3 * num(l, "tip_amplitude_steady")
        );
    }
    println!("wall time                  {wall:.2} s");
    Ok(())
}

fn run(a: &RunArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = a.scene.load()?;
    let f = &s.file;
    let dir = a.out.clone().unwrap_or_else(|| f.outputs.directory.clone());
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create output directory `{}`", dir.display()))?;
    let transient = a.transient.unwrap_or(f.outputs.transient);
    let every = a.every.unwrap_or(f.outputs.every);
    if every == 0 {
        anyhow::bail!("invalid value for `--every`: 0 (must be at least 1)");
    }
    let pb = progress_bar(s.steps() as u64, "run");
    let rows = run_rows(&s, |k| pb.set_position(k as u64))?;
    pb.finish_and_clear();
    let stem = f.name.replace(['/', '\\', ' '], "_");
    let csv = dir.join(format!("{stem}.csv"));
    write_csv(&csv, &rows, every)?;
    let plots = if a.no_plots {
        Vec::new()
    } else {
        a.plots.clone().unwrap_or_else(|| f.outputs.plots.clone())
    };
    let title = describe(&s);
    let pngs = run_plots(&dir, &stem, &title, &rows, &plots, transient)?;
    let sum = summary(&rows, transient);
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": f.name, "csv": csv, "plots": pngs, "summary": sum, "wall_time": wall })
        );
    } else {
        println!("{title}");
        print_summary(&sum);
        println!("wrote {}", csv.display());
        for p in &pngs {
            println!("wrote {}", p.display());
        }
        println!("wall time {wall:.2} s");
    }
    Ok(())
}

fn sweep_cmd(a: &SweepArgs) -> Result<()> {
    let s = a.scene.load()?;
    let freqs = a
        .freqs
        .clone()
        .unwrap_or_else(|| PAPER_FREQUENCIES.to_vec());
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create output directory `{}`", dir.display()))?;
    if !a.last.is_finite() || a.last <= 0.0 {
        anyhow::bail!("invalid value for `--last`: {} (must be positive)", a.last);
    }
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(64 << 20);
    if let Some(j) = a.jobs {
        pool = pool.num_threads(j.max(1));
    }
    let pool = pool.build()?;
    let pb = progress_bar(
        (freqs.len() * s.steps()) as u64,
        &format!("sweep ({} threads)", pool.current_num_threads()),
    );
    let t0 = Instant::now();
    let points = pool.install(|| sweep(&s, &freqs, a.last, &|n| pb.inc(n)))?;
    pb.finish_and_clear();
    let wall = t0.elapsed().as_secs_f64();
    let csv_path = dir.join("sweep.csv");
    std::fs::write(&csv_path, crate::sweep::csv(&points))
        .with_context(|| format!("cannot write `{}`", csv_path.display()))?;
    let mut png = None;
    if !a.no_plots {
        use crate::plot::{render, Panel, Series};
        let path = dir.join("sweep.png");
        let ok: Vec<_> = points.iter().collect();
        render(
            &path,
            &format!(
                "Frequency response: scene {}, {}, base {} mm; last {} s of {} s",
                s.file.name,
                s.file.kind.name(),
                s.file.excitation.amplitude_or_paper() * 1e3,
                a.last,
                s.file.duration,
            ),
            &[
                Panel::new(
                    "Beam tip",
                    "excitation frequency [Hz]",
                    "Y (half peak-to-peak) [m]",
                    vec![Series::marked(
                        "",
                        ok.iter().map(|p| (p.frequency, p.tip_amplitude)).collect(),
                    )],
                ),
                Panel::new(
                    "Ball",
                    "excitation frequency [Hz]",
                    "θ [deg]",
                    vec![
                        Series::marked(
                            "max |θ|",
                            ok.iter().map(|p| (p.frequency, p.ball_max_deg)).collect(),
                        ),
                        Series::marked(
                            "half peak-to-peak",
                            ok.iter()
                                .map(|p| (p.frequency, p.ball_amplitude_deg))
                                .collect(),
                        ),
                    ],
                ),
            ],
            2,
            1,
            (1100, 900),
        )?;
        png = Some(path);
    }
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "duration": s.file.duration, "last": a.last, "points": points, "csv": csv_path, "plot": png, "wall_time": wall })
        );
    } else {
        println!("{}", describe(&s));
        println!("  f [Hz]   tip Y [mm]   ball max|θ| [deg]   ball θ half p-p [deg]   impacts");
        for p in &points {
            println!(
                "  {:6.3}   {:10.4}   {:17.2}   {:21.2}   {:7}{}",
                p.frequency,
                p.tip_amplitude * 1e3,
                p.ball_max_deg,
                p.ball_amplitude_deg,
                p.impacts,
                p.error
                    .as_deref()
                    .map(|e| format!("   FAILED: {e}"))
                    .unwrap_or_default()
            );
        }
        println!("wrote {}", csv_path.display());
        if let Some(p) = &png {
            println!("wrote {}", p.display());
        }
        println!(
            "wall time {wall:.2} s ({} runs on {} threads)",
            points.len(),
            pool.current_num_threads()
        );
    }
    Ok(())
}

fn tune_cmd(a: &TuneArgs) -> Result<()> {
    let s = a.scene.load()?;
    let t = tune(&s, a.ratio)?;
    if let Some(path) = &a.write {
        let mut out = s.clone();
        out.file.name = "tuned".into();
        out.file.ball.track_radius = (t.track_radius * 1e9).round() / 1e9;
        let text = format!(
            "# Paper scene with the track radius tuned by `host-sim tune` so that the ball's frequency is\n\
             # {} x the beam's first frequency in the coupled linearized model ({:.4} Hz / {:.4} Hz).\n{}",
            a.ratio,
            t.ball_frequency,
            t.beam_frequency,
            out.to_toml()?
        );
        std::fs::write(path, text).with_context(|| format!("cannot write `{}`", path.display()))?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&t)?);
    } else {
        println!("{}", describe(&s));
        println!(
            "tuned track radius R       {:.6} mm (ρ = R − r_b = {:.6} mm)",
            t.track_radius * 1e3,
            t.path_radius * 1e3
        );
        println!(
            "coupled model              ball {:.4} Hz, beam {:.4} Hz, ratio {:.6}",
            t.ball_frequency, t.beam_frequency, t.ratio
        );
        println!(
            "ball on a fixed housing    {:.4} Hz;  locked-ball first frequency {:.4} Hz",
            t.fixed_housing_frequency, t.locked_frequency
        );
        if let Some(p) = &a.write {
            println!("wrote {}", p.display());
        }
    }
    Ok(())
}
