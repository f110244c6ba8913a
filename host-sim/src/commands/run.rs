//! `paper` and `run`: one scene in time, streamed (fixed memory whatever the duration).

use super::{describe, load, progress_bar};
use crate::cli::{PaperArgs, RunArgs};
use crate::excitation::Excitation;
use crate::figures::{run_plots, PlotData};
use crate::output::{command_line, with_output, OutputDir, Status};
use crate::run::{scene_excitation, simulate_with, RunStats, CSV_HEADER};
use crate::scene::{Kind, Scene};
use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::time::Instant;

/// Largest number of CSV rows of one run (about 350 bytes each); use `--every` beyond.
pub const MAX_CSV_ROWS: u64 = 20_000_000;

/// Start of the steady-state window: `--transient` (checked: 0 ≤ it, and it leaves at least
/// [`MIN_STEADY_STEPS`] steps of the run), else the scene's `outputs.transient` (the same
/// check, except that the built-in default 20 s on a run shorter than 40 s falls back to the
/// run's second half, with a note). A window shorter than one excitation period is warned about.
fn steady_start(cli: Option<f64>, s: &Scene) -> Result<f64> {
    let h = s.file.integrator.step;
    let end = s.steps() as f64 * h;
    let check = |t: f64, key: &str| -> Result<f64> {
        if !t.is_finite() || t < 0.0 {
            bail!("invalid value for `{key}`: {t} (must be finite and not negative)");
        }
        let left = ((end - t) / h).round();
        if left < MIN_STEADY_STEPS as f64 {
            bail!(
                "invalid value for `{key}`: {t} s leaves {} steps of the run ({end} s) for the steady \
                 state; allowed: 0 ≤ transient ≤ {} s (at least {MIN_STEADY_STEPS} steps after it)",
                left.max(0.0),
                end - MIN_STEADY_STEPS as f64 * h
            );
        }
        if s.file.excitation.kind == crate::scene::ExcitationType::Harmonic {
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
        return check(t, "--transient");
    }
    let t = s.file.outputs.transient;
    let default = crate::scene::OutputsSection::default().transient;
    if t == default && t > end / 2.0 {
        eprintln!(
            "note: the default transient ({default} s) would leave less than half of the run ({end} s); \
             the steady-state figures use its second half (t ≥ {} s); set --transient to choose",
            end / 2.0
        );
        return Ok(end / 2.0);
    }
    check(t, "outputs.transient")
}

/// Fewest steps a steady-state window may hold.
pub const MIN_STEADY_STEPS: usize = 10;

fn num(v: &Value, k: &str) -> f64 {
    v.get(k).and_then(|x| x.as_f64()).unwrap_or(f64::NAN)
}

/// The summary lines of `paper` and `run`.
pub fn summary_lines(s: &Value) -> Vec<String> {
    let w = num(s, "energy_window");
    let mut lines = vec![
        format!(
            "static tip deflection      {:.3} mm",
            1e3 * num(s, "static_tip_deflection")
        ),
        format!(
            "tip amplitude              max {:.3} mm; steady (t ≥ {} s, half peak-to-peak) {:.3} mm",
            1e3 * num(s, "tip_amplitude_max"),
            num(s, "steady_from"),
            1e3 * num(s, "tip_amplitude_steady")
        ),
        format!(
            "ball angle θ               max {:.1}°; steady {:.1}°; {} stop impacts",
            num(s, "ball_angle_max_deg"),
            num(s, "ball_angle_steady_deg"),
            s.get("impacts").and_then(|x| x.as_u64()).unwrap_or(0)
        ),
        format!(
            "mean energy [mJ]           beam {:.3} (first {w:.1} s) → {:.3} (last {w:.1} s); ball {:.3} → {:.3}",
            1e3 * num(s, "beam_energy_first"),
            1e3 * num(s, "beam_energy_last"),
            1e3 * num(s, "ball_energy_first"),
            1e3 * num(s, "ball_energy_last")
        ),
    ];
    if let Some(c) = s.get("contact").filter(|c| c.is_object()) {
        let count = |k: &str| c.get(k).and_then(|x| x.as_u64()).unwrap_or(0);
        if count("separations") > 0 {
            lines.push(format!(
                "ball in flight             {:.1} % of the time ({:.1} % for t ≥ {} s): {} separations, {} landings ({} bounces)",
                100.0 * num(c, "flight_fraction"),
                100.0 * num(c, "flight_fraction_steady"),
                num(s, "steady_from"),
                count("separations"),
                count("landings"),
                count("bounces"),
            ));
            lines.push(format!(
                "landing on the track       {} of {} rolling landings need more friction than μ = {} (peak |P_t|/P_n {:.2})",
                count("landings_slipping"),
                count("landings") - count("bounces"),
                num(c, "friction"),
                num(c, "landing_friction_max"),
            ));
        }
        if count("separations") == 0 {
            lines.push(format!(
            "track contact              N < 0 (the track pulls: a real ball would leave it) {:.1} % of the time ({:.1} % for t ≥ {} s), min N = {:.2} m_b g",
            100.0 * num(c, "track_pulls_fraction"),
            100.0 * num(c, "track_pulls_fraction_steady"),
            num(s, "steady_from"),
            num(c, "normal_force_min_over_weight"),
        ));
        }
        lines.push(format!(
            "rolling without slip       needs more friction than μ = {} {:.1} % of the time ({:.1} % for t ≥ {} s; peak |F_t|/N {:.3e})",
            num(c, "friction"),
            100.0 * num(c, "slip_fraction"),
            100.0 * num(c, "slip_fraction_steady"),
            num(s, "steady_from"),
            num(c, "required_friction_max")
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
    mut each: impl FnMut(&crate::run::Row) -> Result<()>,
) -> Result<Value> {
    let steps = s.steps();
    let p = s.params()?;
    let ball = s.file.kind.free_ball().then_some((
        p.ball.mass * p.gravity,
        p.ball.stop_angle,
        s.file.ball.friction,
    ));
    let mut stats =
        RunStats::new(steps as f64 * s.file.integrator.step, steady_from).with_ball(ball);
    let pb = progress_bar(steps as u64, what);
    let r = simulate_with(
        s,
        exc,
        steps,
        |row| {
            stats.push(row);
            each(row)
        },
        |k| pb.set_position(k as u64),
    );
    pb.finish_and_clear();
    r?;
    Ok(stats.json())
}

pub fn paper(a: &PaperArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let from = steady_start(None, &s)?;
    let sim = crate::run::build_simulator(&s, 0.0)?;
    let freqs = sim
        .natural_frequencies()
        .map_err(|e| crate::scene::map_core_error(e, &s))?;
    let exc = scene_excitation(&s)?;
    let free = stream(&s, &exc, from, "free ball", |_| Ok(()))?;
    let mut locked = None;
    if s.file.kind.free_ball() {
        let mut l = s.clone();
        l.file.kind = Kind::Locked;
        locked = Some(stream(&l, &exc, from, "locked ball", |_| Ok(()))?);
    }
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "frequencies": freqs.iter().take(3).collect::<Vec<_>>(), "run": free, "locked": locked, "wall_time": wall })
        );
        return Ok(());
    }
    for line in paper_lines(&s, &freqs, &free, locked.as_ref()) {
        println!("{line}");
    }
    eprintln!("wall time                  {wall:.2} s");
    Ok(())
}

/// What `paper` prints on stdout (the README shows it; a test keeps them equal).
pub fn paper_lines(s: &Scene, freqs: &[f64], free: &Value, locked: Option<&Value>) -> Vec<String> {
    let mut out = vec![describe(s)];
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
        bail!("invalid value for `--every`: 0 (must be at least 1)");
    }
    let steps = s.steps();
    let rows = steps as u64 / every as u64 + 1;
    if rows > MAX_CSV_ROWS {
        bail!(
            "invalid value for `--every` (or `outputs.every`): {every} writes {rows} CSV rows for {steps} \
             steps; allowed: at most {MAX_CSV_ROWS} rows (use --every {} or more)",
            (steps as u64).div_ceil(MAX_CSV_ROWS - 1)
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
) -> Result<(Vec<crate::run::Row>, Value)> {
    let (exc, from, every) = plan(s, transient, every)?;
    let mut rows = Vec::new();
    rows.try_reserve(s.steps() / every + 1).map_err(|_| {
        anyhow::anyhow!(
            "a run of {} rows does not fit in memory here",
            s.steps() / every + 1
        )
    })?;
    let mut k = 0u64;
    let sum = stream(s, &exc, from, "run", |r| {
        if k.is_multiple_of(every as u64) {
            rows.push(*r);
        }
        k += 1;
        Ok(())
    })?;
    Ok((rows, sum))
}

pub fn run(a: &RunArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let f = &s.file;
    let (exc, from, every) = plan(&s, a.transient, a.every)?;
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
        let sum = stream(&s, &exc, from, "run", |r| {
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
        })?;
        let csv = out.finish(csv)?;
        let pngs = match &data {
            Some(d) => run_plots(out, &stem, &title, d, &plots)?,
            None => Vec::new(),
        };
        Ok(((sum.clone(), csv, pngs), Status::Complete, sum))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": f.name, "csv": csv, "plots": pngs, "summary": sum, "wall_time": wall })
        );
    } else {
        println!("{title}");
        for line in summary_lines(&sum) {
            println!("{line}");
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
