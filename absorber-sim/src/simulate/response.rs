//! The frequency response (`sweep`): one streamed run per frequency in parallel, and the
//! locked ball's response beside a free ball's.

use super::{check_excitations, pool};
use crate::ensemble::Ensemble;
use crate::scene::Scene;
use crate::sweep::{aggregate_point, sweep, sweep_members, SweepPoint, PAPER_FREQUENCIES};
use anyhow::{bail, Result};
use serde_json::Value;

/// The steady window's start \[s\]: `last` seconds before the end of each run, or (`None`) the
/// start `run` and `paper` use ([`super::time::steady_start`]: `outputs.transient`, or the run's
/// second half when the default 20 s would leave less; [`crate::run::steady_label`]).
pub fn window(s: &Scene, last: Option<f64>) -> Result<f64> {
    match last {
        Some(l) => Ok(s.steps() as f64 * s.file.integrator.step - l),
        None => super::time::steady_start(None, s),
    }
}

/// What `sweep` checks before it computes: a harmonic scene, the frequencies (default: the
/// paper's) against the step, and the window `last`; returns the frequencies.
pub fn check(s: &Scene, freqs: Option<&[f64]>, from: f64) -> Result<Vec<f64>> {
    let freqs = freqs.map_or_else(|| PAPER_FREQUENCIES.to_vec(), <[f64]>::to_vec);
    if s.file.excitation.kind != crate::scene::ExcitationType::Harmonic {
        bail!("sweep needs a harmonic excitation (the scene has type = \"csv\")");
    }
    let h = s.file.integrator.step;
    check_excitations(
        &freqs,
        &[s.file.excitation.amplitude_or_paper()],
        h,
        &crate::output::option("freqs"),
        &crate::output::option("amplitude"),
    )?;
    let duration = s.steps() as f64 * h;
    let last = duration - from;
    if !last.is_finite() || last < 10.0 * h || last >= duration {
        bail!(
            "invalid value for `{opt}`: {last} (the steady-state window must hold at least 10 steps, \
             {} s, and be shorter than the run, {duration} s; without `{opt}` it is the run after \
             `outputs.transient` = {} s)",
            10.0 * h,
            s.file.outputs.transient,
            opt = crate::output::option("last"),
        );
    }
    Ok(freqs)
}

/// The scene with its ball locked (the passive absorber `sweep` compares with), for a scene
/// whose ball is free; `None` otherwise.
pub fn locked_scene(s: &Scene) -> Option<Scene> {
    s.file.kind.free_ball().then(|| {
        let mut l = s.clone();
        l.file.kind = crate::scene::Kind::Locked;
        l
    })
}

/// The locked ball's points at `freqs` (none without a free ball), on the current pool.
pub fn locked_points(
    locked: Option<&Scene>,
    freqs: &[f64],
    from: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<SweepPoint>> {
    match locked {
        Some(l) => sweep(l, freqs, from, progress),
        None => Ok(Vec::new()),
    }
}

/// `sweep` in memory (the Python package's `sweep`): the same checks and the same parallel runs
/// on `jobs` threads (default and at most: the cores and the frequencies), one point per
/// frequency (failed points carry their error), and the locked ball's points as the command
/// prints them (empty without a free ball).
pub fn sweep_in_memory(
    s: &Scene,
    freqs: Option<&[f64]>,
    last: Option<f64>,
    jobs: Option<usize>,
) -> Result<(Vec<SweepPoint>, Vec<SweepPoint>)> {
    let from = window(s, last)?;
    let freqs = check(s, freqs, from)?;
    let pool = pool(jobs, freqs.len())?;
    let locked = locked_scene(s);
    pool.install(|| {
        Ok((
            sweep(s, &freqs, from, &|_| {})?,
            locked_points(locked.as_ref(), &freqs, from, &|_| {})?,
        ))
    })
}

/// An ensemble's sweep in memory (the Python package's `sweep(..., ensemble=K)`): per frequency
/// the aggregated point ([`crate::sweep::aggregate_point`]), and the locked ball's points (one
/// run per frequency: a locked ball has no initial angle to perturb; empty without a free
/// ball).
pub fn sweep_ensemble_in_memory(
    s: &Scene,
    freqs: Option<&[f64]>,
    last: Option<f64>,
    jobs: Option<usize>,
    e: Ensemble,
) -> Result<(Vec<Value>, Vec<SweepPoint>)> {
    let from = window(s, last)?;
    let freqs = check(s, freqs, from)?;
    let pool = pool(jobs, freqs.len() * e.k)?;
    let l = locked_scene(s);
    let (members, locked) = pool.install(|| -> Result<_> {
        Ok((
            sweep_members(s, &freqs, from, e, &|_| {})?,
            locked_points(l.as_ref(), &freqs, from, &|_| {})?,
        ))
    })?;
    Ok((members.iter().map(|m| aggregate_point(m)).collect(), locked))
}
