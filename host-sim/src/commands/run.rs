//! `paper` and `run`: one scene in time, streamed (fixed memory whatever the duration).

use super::{describe, load, pool, progress_bar};
use crate::cli::{PaperArgs, RunArgs};
use absorber_sim::ensemble::Ensemble;
use absorber_sim::excitation::Excitation;
use absorber_sim::figures::{run_plots, PlotData};
use absorber_sim::output::{command_line, with_output, OutputDir, Status};
use absorber_sim::run::{scene_excitation, secs, simulate_with, RunStats, CSV_HEADER};
use absorber_sim::scene::{Kind, Scene};
use anyhow::{anyhow, bail, Result};
use indicatif::ProgressBar;
use serde_json::{json, Value};
use std::time::Instant;

/// Largest number of CSV rows of one run (about 350 bytes each); use `--every` beyond.
pub const MAX_CSV_ROWS: u64 = 20_000_000;

/// Start of the steady-state window: `--transient` (checked: 0 ≤ it, and it leaves at least
/// [`MIN_STEADY_STEPS`] steps of the run), else the scene's `outputs.transient` (the same
/// check, except that the built-in default 20 s on a run shorter than 40 s falls back to the
/// run's second half, with a note). A window shorter than one excitation period is warned about.
pub(crate) fn steady_start(cli: Option<f64>, s: &Scene) -> Result<f64> {
    let h = s.file.integrator.step;
    let end = s.steps() as f64 * h;
    let check = |t: f64, key: &str| -> Result<f64> {
        if !t.is_finite() || t < 0.0 {
            bail!("invalid value for `{key}`: {t} (must be finite and not negative)");
        }
        let left = ((end - t) / h).round();
        if left < MIN_STEADY_STEPS as f64 {
            bail!(
                "invalid value for `{key}`: {t} s leaves {} steps of the run ({} s) for the steady \
                 state; allowed: 0 ≤ transient ≤ {} s (at least {MIN_STEADY_STEPS} steps after it)",
                left.max(0.0),
                secs(end),
                secs(end - MIN_STEADY_STEPS as f64 * h)
            );
        }
        if s.file.excitation.kind == absorber_sim::scene::ExcitationType::Harmonic {
            let period = 1.0 / s.file.excitation.frequency_or_paper();
            if end - t < period {
                eprintln!(
                    "warning: the steady-state window after `{key}` = {t} s is {:.4} s, shorter than one \
                     excitation period ({period:.4} s): its amplitudes are not steady-state amplitudes",
                    end - t
                );
            }
        }
        Ok(t)
    };
    if let Some(t) = cli {
        return check(t, &absorber_sim::output::option("transient"));
    }
    let t = s.file.outputs.transient;
    let default = absorber_sim::scene::OutputsSection::default().transient;
    if t == default && t > end / 2.0 {
        eprintln!(
            "note: the default transient ({default} s) would leave less than half of the run ({} s); \
             the steady-state figures use its second half (t ≥ {} s); set {} to choose",
            secs(end),
            secs(end / 2.0),
            absorber_sim::output::option("transient")
        );
        return Ok(end / 2.0);
    }
    check(t, "outputs.transient")
}

/// Fewest steps a steady-state window may hold.
pub const MIN_STEADY_STEPS: usize = 10;

/// The number under `k` (a [`absorber_sim::ensemble::Spread`]'s mean in an ensemble's summary).
fn num(v: &Value, k: &str) -> f64 {
    v.get(k).map_or(f64::NAN, absorber_sim::ensemble::value)
}

/// The statistic under `k` scaled by `scale` with `prec` decimals (`mean ± sd (min–max)` in
/// an ensemble's summary).
fn stat(v: &Value, k: &str, scale: f64, prec: usize) -> String {
    absorber_sim::ensemble::text(v.get(k).unwrap_or(&Value::Null), scale, prec)
}

/// The count under `k` (`mean ± sd (min–max)` in an ensemble's summary).
fn count(v: &Value, k: &str) -> String {
    absorber_sim::ensemble::count_text(v.get(k).unwrap_or(&Value::Null))
}

/// A friction ratio: plain below 1000 (`4.73`), else in exponent form (`1.162e4`, where a
/// near-zero normal force makes it large).
fn ratio(x: f64) -> String {
    if x.abs() < 1e3 {
        format!("{x:.2}")
    } else {
        format!("{x:.3e}")
    }
}

/// The stop impacts of the steady window (what `sweep`'s impacts column counts): their number
/// from the steady rate of a single run, the rate's statistics in an ensemble's summary.
fn steady_impacts(s: &Value) -> String {
    let from = num(s, "steady_from");
    match s.get("impact_rate_steady").and_then(Value::as_f64) {
        Some(rate) => format!("{:.0} for t ≥ {from} s", rate * (num(s, "duration") - from)),
        None => format!(
            "{}/s for t ≥ {from} s",
            stat(s, "impact_rate_steady", 1.0, 2)
        ),
    }
}

/// The keys of a run's summary that are settings shared by the members of an ensemble, not
/// statistics.
pub const SHARED_KEYS: [&str; 6] = [
    "ball",
    "duration",
    "steady_from",
    "energy_window",
    "friction",
    "flight_resolution",
];

/// The summary lines of `paper` and `run` (an ensemble's statistics as `mean ± sd (min–max)`).
pub fn summary_lines(s: &Value) -> Vec<String> {
    let w = num(s, "energy_window");
    let mut lines = vec![
        format!(
            "static tip deflection      {} mm",
            stat(s, "static_tip_deflection", 1e3, 3)
        ),
        format!(
            "tip amplitude              max {} mm; steady (t ≥ {} s, half peak-to-peak) {} mm",
            stat(s, "tip_amplitude_max", 1e3, 3),
            num(s, "steady_from"),
            stat(s, "tip_amplitude_steady", 1e3, 3)
        ),
        match s.get("ball").and_then(Value::as_str) {
            Some("locked") => "ball                       locked in the housing: it turns with the tip mass (no angle, stop impacts or flight of its own)".to_string(),
            Some("none") => "ball                       none in this scene".to_string(),
            _ => format!(
                "ball angle θ               max {}°; steady {}°; {} stop impacts in the run, {}",
                stat(s, "ball_angle_max_deg", 1.0, 1),
                stat(s, "ball_angle_steady_deg", 1.0, 1),
                count(s, "impacts"),
                steady_impacts(s)
            ),
        },
        format!(
            "mean energy [mJ]           beam {} (first {w:.1} s) → {} (last {w:.1} s); ball {} → {}",
            stat(s, "beam_energy_first", 1e3, 3),
            stat(s, "beam_energy_last", 1e3, 3),
            stat(s, "ball_energy_first", 1e3, 3),
            stat(s, "ball_energy_last", 1e3, 3)
        ),
    ];
    if let Some(c) = s.get("contact").filter(|c| c.is_object()) {
        let separations = num(c, "separations");
        if separations > 0.0 {
            lines.push(format!(
                "ball in flight             {} % of the time ({} % for t ≥ {} s): {} separations, {} landings ({} bounces; counts of short hops depend on h: docs/chaos.md)",
                stat(c, "flight_fraction", 100.0, 1),
                stat(c, "flight_fraction_steady", 100.0, 1),
                num(s, "steady_from"),
                count(c, "separations"),
                count(c, "landings"),
                count(c, "bounces"),
            ));
            let rolling = match (
                c.get("landings").and_then(Value::as_u64),
                c.get("bounces").and_then(Value::as_u64),
            ) {
                (Some(l), Some(b)) => (l - b.min(l)).to_string(),
                _ => format!("{:.1}", num(c, "landings") - num(c, "bounces")),
            };
            lines.push(format!(
                "landing on the track       {} of {rolling} rolling landings need more friction than μ = {} (peak |P_t|/P_n {})",
                count(c, "landings_slipping"),
                num(c, "friction"),
                stat(c, "landing_friction_max", 1.0, 2),
            ));
        }
        if separations == 0.0 || separations.is_nan() {
            lines.push(format!(
            "track contact              N < 0 (the track pulls: a real ball would leave it) {} % of the time ({} % for t ≥ {} s), min N = {} m_b g",
            stat(c, "track_pulls_fraction", 100.0, 1),
            stat(c, "track_pulls_fraction_steady", 100.0, 1),
            num(s, "steady_from"),
            stat(c, "normal_force_min_over_weight", 1.0, 2),
        ));
        }
        let peak = match absorber_sim::ensemble::spread_of(
            c.get("required_friction_max").unwrap_or(&Value::Null),
        ) {
            Some(p) => format!("{} ({}–{})", ratio(p.mean), ratio(p.min), ratio(p.max)),
            None => ratio(num(c, "required_friction_max")),
        };
        lines.push(format!(
            "rolling without slip       needs more friction than μ = {} {} % of the time ({} % for t ≥ {} s; peak |F_t|/N {peak})",
            num(c, "friction"),
            stat(c, "slip_fraction", 100.0, 1),
            stat(c, "slip_fraction_steady", 100.0, 1),
            num(s, "steady_from"),
        ));
    }
    lines
}

/// Runs a scene, feeding every row to `each` (fixed memory); returns the summary.
fn stream(
    s: &Scene,
    exc: &Excitation,
    steady_from: f64,
    what: &str,
    each: impl FnMut(&absorber_sim::run::Row) -> Result<()>,
) -> Result<Value> {
    let pb = progress_bar(s.steps() as u64, what);
    let r = stream_with(s, exc, steady_from, &pb, each);
    pb.finish_and_clear();
    r
}

/// [`stream`] advancing a progress bar that may be shared (by the members of an ensemble).
fn stream_with(
    s: &Scene,
    exc: &Excitation,
    steady_from: f64,
    pb: &ProgressBar,
    mut each: impl FnMut(&absorber_sim::run::Row) -> Result<()>,
) -> Result<Value> {
    let steps = s.steps();
    let p = s.params()?;
    let ball = s.file.kind.free_ball().then_some((
        p.ball.mass * p.gravity,
        p.ball.stop_angle,
        s.file.ball.friction,
    ));
    let mut stats = RunStats::new(steps as f64 * s.file.integrator.step, steady_from)
        .with_ball(ball)
        .with_flight_resolution(s.file.outputs.flight_resolution);
    let mut done = 0usize;
    simulate_with(
        s,
        exc,
        steps,
        |row| {
            stats.push(row);
            each(row)
        },
        |k| {
            pb.inc(k.saturating_sub(done) as u64);
            done = k;
        },
    )?;
    let mut summary = stats.json();
    summary["ball"] = ball_state(s.file.kind).into();
    Ok(summary)
}

/// What the summary's `ball` says: `free` (the ball's angle and stop impacts are figures of
/// its own), `locked` (held in the housing: it turns with the tip mass and has no angle, stop
/// impact or flight of its own) or `none`.
pub fn ball_state(kind: Kind) -> &'static str {
    if kind.free_ball() {
        "free"
    } else if kind.has_ball() {
        "locked"
    } else {
        "none"
    }
}

/// The summaries of members `1..K` of an ensemble (member 0, the scene itself, is run by the
/// caller), in parallel, each failure naming its member.
fn other_members(
    s: &Scene,
    exc: &Excitation,
    steady_from: f64,
    e: Ensemble,
    pb: &ProgressBar,
) -> Result<Vec<Value>> {
    use rayon::prelude::*;
    (1..e.k)
        .into_par_iter()
        .map(|m| {
            let member = absorber_sim::ensemble::member_scene(s, e.seed, m);
            stream_with(&member, exc, steady_from, pb, |_| Ok(())).map_err(|err| {
                let (a, r) = absorber_sim::ensemble::perturbation(e.seed, m);
                anyhow!(
                    "ensemble member {m} (initial angle {:+.4}°, rate {r:+.5} rad/s): {err:#}",
                    a
                )
            })
        })
        .collect()
}

/// Member 0's summary and the others', aggregated ([`absorber_sim::ensemble::aggregate`]); the plain
/// summary for one member.
fn ensemble_summary(first: Value, others: Vec<Value>) -> Value {
    if others.is_empty() {
        return first;
    }
    let mut all = vec![first];
    all.extend(others);
    absorber_sim::ensemble::aggregate(&all, &SHARED_KEYS)
}

pub fn paper(a: &PaperArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let from = steady_start(None, &s)?;
    let sim = absorber_sim::run::build_simulator(&s, 0.0)?;
    let freqs = sim
        .natural_frequencies()
        .map_err(|e| absorber_sim::scene::map_core_error(e, &s))?;
    let exc = scene_excitation(&s)?;
    let free = stream(&s, &exc, from, "free ball", |_| Ok(()))?;
    let mut locked = None;
    if s.file.kind.free_ball() {
        let mut l = s.clone();
        l.file.kind = Kind::Locked;
        locked = Some(stream(&l, &exc, from, "locked ball", |_| Ok(()))?);
    }
    // Beside the paper's integrator (its damping depends on h), the physics scene: the same
    // absorber with a steel arm's damping and an integrator whose damping does not.
    let physics = if step_damping_line(&s).is_some() && s.file.kind.free_ball() {
        let p = Scene::physics()?;
        let exc = scene_excitation(&p)?;
        let from = steady_start(None, &p)?;
        Some((
            p.clone(),
            stream(&p, &exc, from, "physics scene", |_| Ok(()))?,
        ))
    } else {
        None
    };
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "frequencies": freqs.iter().take(3).collect::<Vec<_>>(), "run": free, "locked": locked, "physics": physics.as_ref().map(|p| &p.1), "wall_time": wall })
        );
        return Ok(());
    }
    for line in paper_lines(&s, &freqs, &free, locked.as_ref()) {
        println!("{line}");
    }
    if let Some((p, summary)) = &physics {
        println!("{}", physics_line(p, summary));
    }
    eprintln!("wall time                  {wall:.2} s");
    Ok(())
}

/// What `paper` prints on stdout (the README shows it; a test keeps them equal).
pub fn paper_lines(s: &Scene, freqs: &[f64], free: &Value, locked: Option<&Value>) -> Vec<String> {
    let mut out = vec![describe(s)];
    if let Some(line) = step_damping_line(s) {
        out.push(line);
    }
    let f: Vec<String> = freqs.iter().take(3).map(|x| format!("{x:.3}")).collect();
    out.push(format!("lowest frequencies         {} Hz", f.join(", ")));
    out.extend(summary_lines(free));
    if let Some(l) = locked {
        out.push(format!(
            "locked ball (passive)      tip amplitude max {:.3} mm, steady {:.3} mm",
            1e3 * num(l, "tip_amplitude_max"),
            1e3 * num(l, "tip_amplitude_steady")
        ));
    }
    out
}

/// The physics scene's summary in one line, printed by `paper` beside a scene whose
/// integrator's damping depends on h: what the same absorber does with a steel arm's damping
/// and generalized-α (docs/chaos.md measures how these figures converge).
pub fn physics_line(p: &Scene, summary: &Value) -> String {
    let f = &p.file;
    let c = summary.get("contact").unwrap_or(&Value::Null);
    format!(
        "physics scene              `--scene physics` ({} % structural damping, generalized-α, {} calibrated elements {}, h = {} s, {} s at {} Hz): steady tip amplitude {} mm, tip RMS {} mm, {} stop impacts/s, ball in flight {} % (t ≥ {} s)",
        100.0 * f.damping.ratio.unwrap_or(0.0),
        f.elements,
        match f.precision {
            absorber_sim::scene::Precision::F32 => "f32",
            absorber_sim::scene::Precision::F64 => "f64",
        },
        f.integrator.step,
        f.duration,
        f.excitation.frequency_or_paper(),
        stat(summary, "tip_amplitude_steady", 1e3, 3),
        stat(summary, "tip_rms_steady", 1e3, 3),
        stat(summary, "impact_rate_steady", 1.0, 2),
        stat(c, "flight_fraction_steady", 100.0, 1),
        num(summary, "steady_from"),
    )
}

/// For Newmark with γ > ½ (the paper's integrator): one line saying that its damping is
/// numerical and depends on h. For small ωh the scheme damps a mode of angular frequency ω by
/// ξ ≈ (γ − ½) ω h / 2 of critical (Hughes, *The Finite Element Method*, §9.3); it is given at
/// the excitation frequency, where the response is.
pub fn step_damping_line(s: &Scene) -> Option<String> {
    let i = &s.file.integrator;
    if i.rho_inf.is_some() || i.gamma <= 0.5 {
        return None;
    }
    let f = s.file.excitation.frequency_or_paper();
    let xi = (i.gamma - 0.5) * std::f64::consts::TAU * f * i.step / 2.0;
    Some(format!(
        "integrator damping         numerical, depends on h: Newmark γ = {} damps {:.2} % of critical at {f} Hz with h = {} s (∝ h; `--scene physics`: generalized-α and a steel arm's damping)",
        i.gamma,
        100.0 * xi,
        i.step
    ))
}

/// What `run` checks before it computes: the excitation (a CSV record is read here), the
/// start of the steady-state window and the CSV row interval.
fn plan(
    s: &Scene,
    transient: Option<f64>,
    every: Option<usize>,
) -> Result<(Excitation, f64, usize)> {
    // The excitation (a CSV record) is read and checked before anything else.
    let exc = scene_excitation(s)?;
    let from = steady_start(transient, s)?;
    let every = every.unwrap_or(s.file.outputs.every);
    if every == 0 {
        bail!(
            "invalid value for `{}`: 0 (must be at least 1)",
            absorber_sim::output::option("every")
        );
    }
    let steps = s.steps();
    let rows = steps as u64 / every as u64 + 1;
    if rows > MAX_CSV_ROWS {
        bail!(
            "invalid value for `{opt}` (or `outputs.every`): {every} writes {rows} CSV rows for {steps} \
             steps; allowed: at most {MAX_CSV_ROWS} rows (use {opt} {} or more)",
            (steps as u64).div_ceil(MAX_CSV_ROWS - 1),
            opt = absorber_sim::output::option("every"),
        );
    }
    Ok((exc, from, every))
}

/// `run` in memory instead of files (the Python package's `run`): the rows the CSV would hold
/// (every `every`-th step, default `outputs.every`) and the summary `run --json` prints, from
/// the same checks and the same streamed computation as the command.
pub fn run_in_memory(
    s: &Scene,
    transient: Option<f64>,
    every: Option<usize>,
) -> Result<(Vec<absorber_sim::run::Row>, Value)> {
    let (exc, from, every) = plan(s, transient, every)?;
    rows_in_memory(s, &exc, from, every)
}

/// The rows of `run_in_memory` for a planned run ([`plan`]: checked once, its notes printed
/// once).
fn rows_in_memory(
    s: &Scene,
    exc: &Excitation,
    from: f64,
    every: usize,
) -> Result<(Vec<absorber_sim::run::Row>, Value)> {
    let mut rows = Vec::new();
    rows.try_reserve(s.steps() / every + 1).map_err(|_| {
        anyhow::anyhow!(
            "a run of {} rows does not fit in memory here",
            s.steps() / every + 1
        )
    })?;
    let mut k = 0u64;
    let sum = stream(s, exc, from, "run", |r| {
        if k.is_multiple_of(every as u64) {
            rows.push(*r);
        }
        k += 1;
        Ok(())
    })?;
    Ok((rows, sum))
}

/// The summary of `run --json` for `s`, without rows or files (the studies' runs).
pub fn summary_in_memory(s: &Scene, transient: Option<f64>) -> Result<Value> {
    let (exc, from, _) = plan(s, transient, None)?;
    stream_with(s, &exc, from, &ProgressBar::hidden(), |_| Ok(()))
}

/// An ensemble's summary in memory (the Python package's `run(..., ensemble=K)`): the same
/// checks as `run`, member 0's rows, and the statistics over the K members.
pub fn run_ensemble_in_memory(
    s: &Scene,
    transient: Option<f64>,
    every: Option<usize>,
    e: Ensemble,
) -> Result<(Vec<absorber_sim::run::Row>, Value)> {
    absorber_sim::ensemble::check_scene(s, e)?;
    let (exc, from, every) = plan(s, transient, every)?;
    let (rows, first) = rows_in_memory(s, &exc, from, every)?;
    let pb = ProgressBar::hidden();
    let others = pool(None, e.k)?.install(|| other_members(s, &exc, from, e, &pb))?;
    Ok((rows, ensemble_summary(first, others)))
}

pub fn run(a: &RunArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let f = &s.file;
    let ens = a.ensemble.ensemble()?;
    absorber_sim::ensemble::check_scene(&s, ens)?;
    let (exc, from, every) = plan(&s, a.transient, a.every)?;
    let workers = pool(None, ens.k)?;
    let plots = if a.no_plots {
        Vec::new()
    } else {
        a.plots.clone().unwrap_or_else(|| f.outputs.plots.clone())
    };
    let dir = a.out.clone().unwrap_or_else(|| f.outputs.directory.clone());
    let stem = f.name.replace(['/', '\\', ' '], "_");
    let stem = if stem.is_empty() || stem.starts_with('.') {
        format!("run{stem}")
    } else {
        stem
    };
    let out = OutputDir::open(&dir, Some(&stem), &command_line())?;
    let title = describe(&s);
    let ((sum, csv, pngs), _files) = with_output(out, |out| {
        let mut csv = out.stream(&format!("{stem}.csv"))?;
        csv.line(CSV_HEADER)?;
        let mut data = (!plots.is_empty()).then(|| PlotData::new(from));
        let mut k = 0u64;
        let what = if ens.is_ensemble() {
            format!("run (ensemble of {})", ens.k)
        } else {
            "run".to_string()
        };
        let pb = progress_bar((ens.k * s.steps()) as u64, &what);
        // Member 0 (the scene itself) writes the CSV and the plots; the others, in parallel
        // beside it, give their summaries.
        let (first, others) = workers.install(|| {
            rayon::join(
                || {
                    stream_with(&s, &exc, from, &pb, |r| {
                        if let Some(d) = data.as_mut() {
                            d.push(r);
                        }
                        let write = k.is_multiple_of(every as u64);
                        k += 1;
                        if write {
                            csv.line(&r.csv())
                        } else {
                            Ok(())
                        }
                    })
                },
                || other_members(&s, &exc, from, ens, &pb),
            )
        });
        pb.finish_and_clear();
        let sum = ensemble_summary(first?, others?);
        let csv = out.finish(csv)?;
        let pngs = match &data {
            Some(d) => run_plots(out, &stem, &title, d, &plots)?,
            None => Vec::new(),
        };
        Ok(((sum.clone(), csv, pngs), Status::Complete, sum))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        let mut out = json!({ "scene": f.name, "csv": csv, "plots": pngs, "summary": sum, "wall_time": wall });
        if ens.is_ensemble() {
            out["ensemble"] = ens.json();
        }
        println!("{out}");
    } else {
        println!("{title}");
        if ens.is_ensemble() {
            println!("{}", ensemble_line(ens));
        }
        for line in summary_lines(&sum) {
            println!("{line}");
        }
        if ens.is_ensemble() {
            println!("(CSV and plots: member 0, the scene itself)");
        }
        println!("wrote {}", csv.display());
        for p in &pngs {
            println!("wrote {}", p.display());
        }
        println!(
            "wrote {}",
            dir.join(format!("{stem}.manifest.json")).display()
        );
        println!("wall time {wall:.2} s");
    }
    Ok(())
}

/// The line that introduces an ensemble's statistics.
pub fn ensemble_line(e: Ensemble) -> String {
    format!(
        "ensemble of {} runs (seed {}; initial ball angle ± {}°, rate ± {} rad/s): mean ± sd (min–max)",
        e.k,
        e.seed,
        absorber_sim::ensemble::ANGLE_SPREAD_DEG,
        absorber_sim::ensemble::RATE_SPREAD
    )
}
