//! Frequency-response sweep (paper Fig. 10): one run per excitation frequency, in parallel,
//! every figure over the steady window (t ≥ the transient to the end, as `run`), or the last part.

use crate::ensemble::Ensemble;
use crate::excitation::Excitation;
use crate::run::simulate;
use crate::scene::{ExcitationType, Scene};
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;

/// The paper's excitation frequencies \[Hz\] (§5.1).
pub const PAPER_FREQUENCIES: [f64; 14] = [
    3.50, 3.70, 3.80, 3.85, 3.90, 3.95, 4.00, 4.05, 4.10, 4.13, 4.25, 4.40, 4.50, 4.70,
];

/// Steady-state response at one frequency.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepPoint {
    /// Excitation frequency \[Hz\].
    pub frequency: f64,
    /// Half peak-to-peak of the tip deflection over the window \[m\].
    pub tip_amplitude: f64,
    /// Mean tip deflection over the window \[m\].
    pub tip_mean: f64,
    /// Largest |θ| over the window \[deg\].
    pub ball_max_deg: f64,
    /// Half peak-to-peak of θ over the window \[deg\].
    pub ball_amplitude_deg: f64,
    /// Stop impacts over the window.
    pub impacts: u32,
    /// Fraction of the window with the ball in flight \[-\] (0 without a free ball).
    pub flight_fraction: f64,
    /// Largest Newton iteration count of a step over the window.
    pub max_iterations: u32,
    /// Why the run failed (then the figures above cover only what was computed and are not
    /// reported by the commands).
    pub error: Option<String>,
}

/// Runs the sweep. `from`: the steady window's start \[s\] (every figure of a point is over
/// t ≥ `from` to the end; [`crate::simulate::response::window`] gives the default, the window of
/// `run` and `paper`); `progress(steps)` is called (from worker threads) with step increments.
pub fn sweep(
    scene: &Scene,
    frequencies: &[f64],
    from: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<SweepPoint>> {
    let members = sweep_members(scene, frequencies, from, Ensemble::single(), progress)?;
    Ok(members.into_iter().flatten().collect())
}

/// The sweep of every member of an ensemble ([`crate::ensemble`]): per frequency, the K
/// members' points (member 0 first), all runs in parallel.
pub fn sweep_members(
    scene: &Scene,
    frequencies: &[f64],
    from: f64,
    e: Ensemble,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Vec<SweepPoint>>> {
    if scene.file.excitation.kind != ExcitationType::Harmonic {
        bail!("sweep needs a harmonic excitation (the scene has type = \"csv\")");
    }
    for &f in frequencies {
        if !f.is_finite() || f <= 0.0 {
            bail!("invalid sweep frequency {f} (must be finite and positive)");
        }
    }
    crate::ensemble::check_scene(scene, e)?;
    // Build once up front so that a bad scene fails before the threads start.
    crate::run::build_simulator(scene, 0.0)?;
    let jobs: Vec<(f64, usize)> = frequencies
        .iter()
        .flat_map(|&f| (0..e.k).map(move |m| (f, m)))
        .collect();
    let points: Vec<SweepPoint> = jobs
        .par_iter()
        .map(|&(f, m)| {
            point(
                &crate::ensemble::member_scene(scene, e.seed, m),
                f,
                from,
                progress,
            )
        })
        .collect();
    Ok(points.chunks(e.k).map(<[SweepPoint]>::to_vec).collect())
}

/// One run of the sweep at `f` \[Hz\].
fn point(scene: &Scene, f: f64, from: f64, progress: &(dyn Fn(u64) + Sync)) -> SweepPoint {
    let amplitude = scene.file.excitation.amplitude_or_paper();
    let steps = scene.steps();
    let h = scene.file.integrator.step;
    // The window of `run::RunStats`: the same slack at its start.
    let eps = 1e-9 * (steps as f64 * h).max(1.0);
    let exc = Excitation::harmonic(amplitude, f, h);
    let (mut lo, mut hi, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    let (mut blo, mut bhi, mut bmax) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    let (mut impacts, mut max_it) = (0u32, 0u32);
    let mut flying = 0usize;
    let mut last_k = 0usize;
    let result = simulate(
        scene,
        &exc,
        steps,
        |r| {
            if r.t >= from - eps {
                impacts += u32::from(r.events.impacts);
                max_it = max_it.max(r.iterations);
                lo = lo.min(r.tip_deflection);
                hi = hi.max(r.tip_deflection);
                sum += r.tip_deflection;
                n += 1;
                flying += usize::from(r.contact == 0.0);
                if r.ball_angle.is_finite() {
                    let d = r.ball_angle.to_degrees();
                    blo = blo.min(d);
                    bhi = bhi.max(d);
                    bmax = bmax.max(d.abs());
                }
            }
        },
        |k| {
            progress((k - last_k) as u64);
            last_k = k;
        },
    );
    let half = |lo: f64, hi: f64| if lo <= hi { 0.5 * (hi - lo) } else { f64::NAN };
    SweepPoint {
        frequency: f,
        tip_amplitude: half(lo, hi),
        tip_mean: if n > 0 { sum / n as f64 } else { f64::NAN },
        ball_max_deg: if blo <= bhi { bmax } else { f64::NAN },
        ball_amplitude_deg: half(blo, bhi),
        impacts,
        flight_fraction: if n > 0 {
            flying as f64 / n as f64
        } else {
            f64::NAN
        },
        max_iterations: max_it,
        error: result.err().map(|e| format!("{e:#}")),
    }
}

/// An ensemble's point as JSON: [`crate::ensemble::aggregate`] of its members' points (the
/// frequency kept), with `error` the first failed member's (then the point is failed) and
/// `failed_members` their number.
pub fn aggregate_point(members: &[SweepPoint]) -> serde_json::Value {
    let values: Vec<serde_json::Value> = members
        .iter()
        .map(|p| serde_json::to_value(p).unwrap_or_default())
        .collect();
    let mut v = crate::ensemble::aggregate(&values, &["frequency"]);
    let failed: Vec<(usize, &String)> = members
        .iter()
        .enumerate()
        .filter_map(|(m, p)| p.error.as_ref().map(|e| (m, e)))
        .collect();
    if let Some(o) = v.as_object_mut() {
        o.insert(
            "error".into(),
            failed.first().map_or(serde_json::Value::Null, |(m, e)| {
                format!("member {m}: {e}").into()
            }),
        );
        if members.len() > 1 {
            o.insert("failed_members".into(), failed.len().into());
        }
    }
    v
}

impl SweepPoint {
    /// The run failed (its amplitudes are not reported).
    pub fn failed(&self) -> bool {
        self.error.is_some()
    }
}

/// CSV of a sweep. A failed point has status `failed`, no numbers and the error;
/// `locked`: the same frequencies with the ball locked (empty: not run, no free ball), whose
/// tip amplitude is the `locked_tip_amplitude` column.
pub fn csv(points: &[SweepPoint], locked: &[SweepPoint], steady_from: f64) -> String {
    let mut s = csv_head(steady_from);
    for (i, p) in points.iter().enumerate() {
        s.push_str(&csv_row(p, locked.get(i)));
    }
    s
}

/// CSV of an ensemble's sweep: one row per run, the member first (0: the scene itself), then
/// the columns of [`csv`] (the locked ball's column is the same in every member's row: a
/// locked ball has no initial angle to perturb).
pub fn csv_members(
    points: &[Vec<SweepPoint>],
    locked: &[SweepPoint],
    e: Ensemble,
    steady_from: f64,
) -> String {
    let mut s = format!(
        "# ensemble of {} runs per frequency, seed {} (member 0: the scene itself)\n",
        e.k, e.seed
    );
    for line in csv_head(steady_from).lines() {
        if line.starts_with('#') {
            s.push_str(line);
        } else {
            s.push_str("member,");
            s.push_str(line);
        }
        s.push('\n');
    }
    for (i, members) in points.iter().enumerate() {
        for (m, p) in members.iter().enumerate() {
            s.push_str(&format!("{m},{}", csv_row(p, locked.get(i))));
        }
    }
    s
}

/// The header of [`csv`].
fn csv_head(steady_from: f64) -> String {
    format!(
        "# host-sim sweep: every column over the steady window, {} of each run\n{CSV_HEADER}",
        crate::run::steady_label(steady_from)
    )
}

const CSV_HEADER: &str = "# frequency [Hz]; status: ok, or failed (then no numbers; error says why); tip_amplitude: half peak-to-peak tip deflection [m]; tip_mean [m];\n\
         # ball_max_deg: max |theta| [deg]; ball_amplitude_deg: half peak-to-peak theta [deg] (NaN unless the ball is free); impacts;\n\
         # flight_fraction: share of the window with the ball in flight [-]; max_iterations;\n\
         # locked_tip_amplitude: tip_amplitude with the ball locked (the passive absorber) [m], empty without a free ball or when that run failed; error\n\
         frequency,status,tip_amplitude,tip_mean,ball_max_deg,ball_amplitude_deg,impacts,flight_fraction,max_iterations,locked_tip_amplitude,error\n";

/// Names of the sweep CSV's columns, in order (the last line of its header).
pub fn csv_columns() -> Vec<&'static str> {
    CSV_HEADER
        .lines()
        .last()
        .map(|l| l.split(',').collect())
        .unwrap_or_default()
}

/// One point's CSV row (with its newline), with the locked ball's at the same frequency.
fn csv_row(p: &SweepPoint, locked: Option<&SweepPoint>) -> String {
    let locked_error = locked.and_then(|l| l.error.as_ref());
    let locked_y = match locked {
        Some(l) if l.error.is_none() => format!("{:.6e}", l.tip_amplitude),
        _ => String::new(),
    };
    let error = match (&p.error, locked_error) {
        (Some(e), _) => e.clone(),
        (None, Some(e)) => format!("locked ball: {e}"),
        (None, None) => String::new(),
    }
    .replace([',', '\n'], ";");
    if p.error.is_some() {
        return format!("{},failed,,,,,,,,{locked_y},{error}\n", p.frequency);
    }
    format!(
        "{},ok,{:.6e},{:.6e},{:.4},{:.4},{},{:.4},{},{locked_y},{error}\n",
        p.frequency,
        p.tip_amplitude,
        p.tip_mean,
        p.ball_max_deg,
        p.ball_amplitude_deg,
        p.impacts,
        p.flight_fraction,
        p.max_iterations,
    )
}
