//! One scene in time, streamed (fixed memory whatever the duration): what `run` and `paper`
//! check before they compute, the run itself with its summary, the members of an ensemble.

use super::{pool, progress_bar};
use crate::ensemble::Ensemble;
use crate::excitation::Excitation;
use crate::run::{scene_excitation, secs, simulate_with, RunStats};
use crate::scene::{Kind, Scene};
use anyhow::{anyhow, bail, Result};
use indicatif::ProgressBar;
use serde_json::Value;

/// Largest number of CSV rows of one run (about 350 bytes each); use `--every` beyond.
pub const MAX_CSV_ROWS: u64 = 20_000_000;

/// Start of the steady-state window: `--transient` (checked: 0 ≤ it, and it leaves at least
/// [`MIN_STEADY_STEPS`] steps of the run), else the scene's `outputs.transient` (the same
/// check, except that the built-in default 20 s on a run shorter than 40 s falls back to the
/// run's second half, with a note). A window shorter than one excitation period is warned about.
pub fn steady_start(cli: Option<f64>, s: &Scene) -> Result<f64> {
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
        return check(t, &crate::output::option("transient"));
    }
    let t = s.file.outputs.transient;
    let default = crate::scene::OutputsSection::default().transient;
    if t == default && t > end / 2.0 {
        eprintln!(
            "note: the default transient ({default} s) would leave less than half of the run ({} s); \
             the steady-state figures use its second half (t ≥ {} s); set {} to choose",
            secs(end),
            secs(end / 2.0),
            crate::output::option("transient")
        );
        return Ok(end / 2.0);
    }
    check(t, "outputs.transient")
}

/// Fewest steps a steady-state window may hold.
pub const MIN_STEADY_STEPS: usize = 10;

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

/// Runs a scene, feeding every row to `each` (fixed memory); returns the summary.
pub fn stream(
    s: &Scene,
    exc: &Excitation,
    steady_from: f64,
    what: &str,
    each: impl FnMut(&crate::run::Row) -> Result<()>,
) -> Result<Value> {
    let pb = progress_bar(s.steps() as u64, what);
    let r = stream_with(s, exc, steady_from, &pb, each);
    pb.finish_and_clear();
    r
}

/// [`stream`] advancing a progress bar that may be shared (by the members of an ensemble).
pub fn stream_with(
    s: &Scene,
    exc: &Excitation,
    steady_from: f64,
    pb: &ProgressBar,
    mut each: impl FnMut(&crate::run::Row) -> Result<()>,
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
pub fn other_members(
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
            let member = crate::ensemble::member_scene(s, e.seed, m);
            stream_with(&member, exc, steady_from, pb, |_| Ok(())).map_err(|err| {
                let (a, r) = crate::ensemble::perturbation(e.seed, m);
                anyhow!(
                    "ensemble member {m} (initial angle {:+.4}°, rate {r:+.5} rad/s): {err:#}",
                    a
                )
            })
        })
        .collect()
}

/// Member 0's summary and the others', aggregated ([`crate::ensemble::aggregate`]); the plain
/// summary for one member.
pub fn ensemble_summary(first: Value, others: Vec<Value>) -> Value {
    if others.is_empty() {
        return first;
    }
    let mut all = vec![first];
    all.extend(others);
    crate::ensemble::aggregate(&all, &SHARED_KEYS)
}

/// What `run` checks before it computes: the excitation (a CSV record is read here), the
/// start of the steady-state window and the CSV row interval.
pub fn plan(
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
            crate::output::option("every")
        );
    }
    let steps = s.steps();
    let rows = steps as u64 / every as u64 + 1;
    if rows > MAX_CSV_ROWS {
        bail!(
            "invalid value for `{opt}` (or `outputs.every`): {every} writes {rows} CSV rows for {steps} \
             steps; allowed: at most {MAX_CSV_ROWS} rows (use {opt} {} or more)",
            (steps as u64).div_ceil(MAX_CSV_ROWS - 1),
            opt = crate::output::option("every"),
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
    rows_in_memory(s, &exc, from, every)
}

/// The rows of `run_in_memory` for a planned run ([`plan`]: checked once, its notes printed
/// once).
fn rows_in_memory(
    s: &Scene,
    exc: &Excitation,
    from: f64,
    every: usize,
) -> Result<(Vec<crate::run::Row>, Value)> {
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
) -> Result<(Vec<crate::run::Row>, Value)> {
    crate::ensemble::check_scene(s, e)?;
    let (exc, from, every) = plan(s, transient, every)?;
    let (rows, first) = rows_in_memory(s, &exc, from, every)?;
    let pb = ProgressBar::hidden();
    let others = pool(None, e.k)?.install(|| other_members(s, &exc, from, e, &pb))?;
    Ok((rows, ensemble_summary(first, others)))
}
