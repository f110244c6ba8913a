//! `host-sim fatigue`: fatigue damage rate at the clamp vs base frequency (and amplitude), with
//! the free ball and with the ball locked (the paper's passive case), from the core's on-device
//! monitor (`absorber_core::monitor`): root stress → streaming rainflow → Miner's rule on an
//! AASHTO S–N curve. One run per (frequency, amplitude, scene), in parallel (rayon).
//!
//! Every figure of a row is over the steady window, t ≥ `outputs.transient` to the end (the
//! window `paper`, `run` and `sweep` call steady): the monitor starts at the window's first
//! sample, so damage (residue counted as half cycles), S_eq, ranges, cycles, impacts, flight
//! fraction and the tip RMS all cover the same samples. Damage rate = that damage per hour of
//! the window. The start-up from rest is left out because it is not part of the service
//! loading: an arm under sustained excitation does not start from rest every hour, and the
//! start-up's ring-up (or the free ball's first large swings) would bias the hourly rate a
//! life estimate is extrapolated from. Runs that fail keep what they computed and say why.

use crate::ensemble::Ensemble;
use crate::excitation::Excitation;
use absorber_core::monitor::{Monitor, MonitorConfig, NoTwin};
use absorber_core::{FreeBall, LockedBall, Model, Params, Scene as CoreScene};
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;

/// One run's fatigue figures.
#[derive(Clone, Debug, Serialize)]
pub struct RunFatigue {
    /// Miner damage per hour [1/h].
    pub damage_rate: f64,
    /// Equivalent stress range S_eq [Pa].
    pub equivalent_range: f64,
    /// Largest rainflow range [Pa].
    pub max_range: f64,
    /// Cycles counted.
    pub cycles: f64,
    /// Static root stress [Pa].
    pub static_stress: f64,
    /// RMS tip deflection about static over the steady window [m].
    pub tip_rms: f64,
    /// Stop impacts.
    pub impacts: u32,
    /// Fraction of the samples with the ball in flight \[-\].
    pub flight_fraction: f64,
    /// Residue overflows (0 = exact counting).
    pub overflows: u64,
    /// Length of the steady window the figures cover [s].
    pub time: f64,
    /// Why the run stopped early.
    pub error: Option<String>,
}

/// Free and locked at one excitation.
#[derive(Clone, Debug, Serialize)]
pub struct FatiguePoint {
    /// Frequency [Hz].
    pub frequency: f64,
    /// Base amplitude [m].
    pub amplitude: f64,
    /// Start of the steady window [s]: every figure is over t ≥ this to the end of the run.
    pub steady_from: f64,
    /// Free ball.
    pub free: RunFatigue,
    /// Locked ball.
    pub locked: RunFatigue,
}

impl RunFatigue {
    fn failed(e: String) -> Self {
        Self {
            damage_rate: f64::NAN,
            equivalent_range: f64::NAN,
            max_range: f64::NAN,
            cycles: 0.0,
            static_stress: f64::NAN,
            tip_rms: f64::NAN,
            impacts: 0,
            flight_fraction: f64::NAN,
            overflows: 0,
            time: 0.0,
            error: Some(e),
        }
    }
}

impl FatiguePoint {
    /// A run of this point failed (its figures are not reported).
    pub fn failed(&self) -> bool {
        self.free.error.is_some() || self.locked.error.is_some()
    }
}

fn run_one<S: CoreScene, const N: usize, const D: usize>(
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: Window,
    rate: f64,
) -> RunFatigue {
    let fail = RunFatigue::failed;
    let mut model = match Model::<f64, S, N, D>::at_rest(*params, exc.at(0).accel) {
        Ok(m) => m,
        Err(e) => return fail(e.to_string()),
    };
    if rate != 0.0 {
        if let Err(e) = crate::core_sim::set_orbit_rate(&mut model, rate) {
            return fail(e.to_string());
        }
    }
    let failure = |k: usize, t: f64, e| {
        format!(
            "step {k} (t = {t:.3} s): {}",
            crate::scene::physical_failure(e, &crate::scene::Scene::paper())
        )
    };
    // The transient: the model alone, nothing monitored. The impacts of the step that ends on
    // the window's first sample are the window's (as `sweep` counts them).
    let mut first_impacts = 0;
    for k in 1..=steps.from {
        match model.step(exc.at(k).accel) {
            Ok(r) if k == steps.from => first_impacts = u32::from(r.events.impacts),
            Ok(_) => {}
            Err(e) => return fail(failure(k, model.time(), e)),
        }
    }
    // The steady window: the monitor's first sample is the state at its start.
    let mut mon: Monitor<f64, NoTwin> = match Monitor::new(config, &model) {
        Ok(m) => m,
        Err(e) => return fail(e.to_string()),
    };
    let tip = |m: &Model<f64, S, N, D>| m.tip_deflection() - m.static_tip_deflection();
    let (mut sum2, mut n) = (tip(&model).powi(2), 1.0);
    let mut error = None;
    for k in steps.from + 1..=steps.end {
        let a = exc.at(k).accel;
        let r = model.step(a).and_then(|r| mon.record(&model, &r, a));
        if let Err(e) = r {
            error = Some(failure(k, model.time(), e));
            break;
        }
        sum2 += tip(&model).powi(2);
        n += 1.0;
    }
    let f = mon.fatigue();
    RunFatigue {
        damage_rate: mon.damage_rate_per_hour(),
        equivalent_range: f.equivalent_range,
        max_range: f.max_range,
        cycles: f.cycles,
        static_stress: mon.static_root_stress(),
        tip_rms: (sum2 / n).sqrt(),
        impacts: mon.impacts().total() + first_impacts,
        flight_fraction: mon.flight_fraction(),
        overflows: mon.rainflow().overflows(),
        time: mon.elapsed(),
        error,
    }
}

/// The steps of a run: the steady window is steps `from + 1 ..= end` (its first sample the
/// state after step `from`).
#[derive(Clone, Copy, Debug)]
struct Window {
    from: usize,
    end: usize,
}

fn pair<const N: usize, const D: usize>(
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: Window,
    rate: f64,
) -> (RunFatigue, RunFatigue) {
    // D counts the free ball's unknown; the locked scene has one fewer.
    (
        run_one::<FreeBall, N, D>(params, config, exc, steps, rate),
        locked_of::<N>(params, config, exc, steps),
    )
}

fn locked_of<const N: usize>(
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: Window,
) -> RunFatigue {
    crate::with_elements!(
        N,
        [3, 8, 16],
        0,
        run_one[LockedBall](params, config, exc, steps, 0.0),
        unreachable_count(N)
    )
}

fn unreachable_count(n: usize) -> RunFatigue {
    RunFatigue::failed(format!("fatigue supports 3, 8 or 16 elements (got {n})"))
}

fn run_pair(
    elements: usize,
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: Window,
    rate: f64,
) -> Result<(RunFatigue, RunFatigue)> {
    Ok(crate::with_elements!(
        elements,
        [3, 8, 16],
        1,
        pair[](params, config, exc, steps, rate),
        bail!("invalid value for `elements`: {elements} (fatigue supports 3, 8 or 16)")
    ))
}

/// Computes the fatigue points (free and locked) for every frequency × amplitude.
pub fn fatigue_points(
    params: &Params<f64>,
    elements: usize,
    config: MonitorConfig<f64>,
    frequencies: &[f64],
    amplitudes: &[f64],
    duration: f64,
    steady_from: f64,
) -> Result<Vec<FatiguePoint>> {
    let members = fatigue_members(
        params,
        elements,
        config,
        frequencies,
        amplitudes,
        duration,
        steady_from,
        Ensemble::single(),
    )?;
    Ok(members.into_iter().flatten().collect())
}

/// The fatigue points of every member of an ensemble ([`crate::ensemble`]: the ball's initial
/// angle and rate perturbed, the locked ball at the perturbed angle): per frequency ×
/// amplitude, the K members' points (member 0 first), all runs in parallel. Every figure is
/// over the steady window t ≥ `steady_from` to `duration` (at least one step of it).
#[allow(clippy::too_many_arguments)]
pub fn fatigue_members(
    params: &Params<f64>,
    elements: usize,
    config: MonitorConfig<f64>,
    frequencies: &[f64],
    amplitudes: &[f64],
    duration: f64,
    steady_from: f64,
    e: Ensemble,
) -> Result<Vec<Vec<FatiguePoint>>> {
    for &x in frequencies.iter().chain(amplitudes) {
        if !x.is_finite() || x <= 0.0 {
            bail!("invalid frequency or amplitude {x} (must be finite and positive)");
        }
    }
    let h = params.integrator.step;
    let end = (duration / h).round() as usize;
    if !steady_from.is_finite() || steady_from < 0.0 {
        bail!("invalid steady-window start {steady_from} s (must be finite and not negative)");
    }
    // The first sample with t ≥ steady_from (to rounding).
    let from = (steady_from / h - 1e-9).ceil() as usize;
    if from >= end {
        bail!("the steady window t ≥ {steady_from} s is empty in a {duration} s run");
    }
    let steps = Window { from, end };
    let jobs: Vec<(f64, f64, usize)> = amplitudes
        .iter()
        .flat_map(|&a| frequencies.iter().map(move |&f| (f, a)))
        .flat_map(|(f, a)| (0..e.k).map(move |m| (f, a, m)))
        .collect();
    let points = jobs
        .par_iter()
        .map(|&(f, a, m)| {
            let exc = Excitation::harmonic(a, f, h);
            let (angle, rate) = crate::ensemble::perturbation(e.seed, m);
            let mut p = *params;
            p.ball.initial_angle += angle.to_radians();
            let (free, locked) = run_pair(elements, &p, config, &exc, steps, rate)?;
            Ok(FatiguePoint {
                frequency: f,
                amplitude: a,
                steady_from,
                free,
                locked,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(points.chunks(e.k).map(<[FatiguePoint]>::to_vec).collect())
}

/// CSV of an ensemble's points: [`csv`] of every run with the member first (0: the scene
/// itself).
pub fn csv_members(
    points: &[Vec<FatiguePoint>],
    e: Ensemble,
    category: &str,
    moment: &str,
) -> String {
    let flat: Vec<FatiguePoint> = points.iter().flatten().cloned().collect();
    let members = points.iter().flat_map(|m| 0..m.len());
    let text = csv(&flat, category, moment);
    let mut out = format!(
        "# ensemble of {} runs per point, seed {} (member 0: the scene itself)\n",
        e.k, e.seed
    );
    let mut lines = text.lines();
    for line in lines.by_ref() {
        if line.starts_with('#') {
            out.push_str(line);
            out.push('\n');
        } else {
            out.push_str("member,");
            out.push_str(line);
            out.push('\n');
            break;
        }
    }
    for (line, m) in lines.zip(members) {
        out.push_str(&format!("{m},{line}\n"));
    }
    out
}

/// CSV of the points.
pub fn csv(points: &[FatiguePoint], category: &str, moment: &str) -> String {
    let steady_from = points.first().map_or(f64::NAN, |p| p.steady_from);
    let mut s = format!(
        "# host-sim fatigue: root-stress damage rate, AASHTO category {category} (m = 3, CAFT cutoff), moment estimate {moment}\n\
         # steady: every column over t ≥ {steady_from} s to the end of the run (the window paper, run and sweep call steady; the start-up from rest is not service loading)\n\
         # damage_rate [1/h] = Miner damage over the window (residue as half cycles) per hour of it; s_eq, max_range, static_stress [MPa]; tip_rms [mm]; impacts and flight fraction over the window\n\
         # status: ok, or failed (then no numbers; error says why)\n\
         frequency,amplitude,status,free_damage_rate,locked_damage_rate,free_s_eq,locked_s_eq,free_max_range,locked_max_range,static_stress,free_tip_rms,locked_tip_rms,free_impacts,free_flight_fraction,free_overflows,locked_overflows,error\n"
    );
    for p in points {
        let err = [&p.free.error, &p.locked.error]
            .iter()
            .filter_map(|e| e.as_deref())
            .collect::<Vec<_>>()
            .join("; ")
            .replace([',', '\n'], ";");
        if p.failed() {
            // No numbers for a failed point: what a failed run computed is not its result.
            s.push_str(&format!(
                "{},{},failed,,,,,,,,,,,,,,{err}\n",
                p.frequency, p.amplitude
            ));
            continue;
        }
        s.push_str(&format!(
            "{},{},ok,{:.6e},{:.6e},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{:.4},{},{},\n",
            p.frequency,
            p.amplitude,
            p.free.damage_rate,
            p.locked.damage_rate,
            p.free.equivalent_range / 1e6,
            p.locked.equivalent_range / 1e6,
            p.free.max_range / 1e6,
            p.locked.max_range / 1e6,
            p.free.static_stress / 1e6,
            p.free.tip_rms * 1e3,
            p.locked.tip_rms * 1e3,
            p.free.impacts,
            p.free.flight_fraction,
            p.free.overflows,
            p.locked.overflows,
        ));
    }
    s
}

/// The damage rate of the scene's model beside its calibrated twin and a converged mesh, per
/// frequency: `model` = the scene's N elements as given, `calibrated` = N elements
/// with the calibration fitted to the full solver, `converged` = the core with M elements,
/// uncalibrated.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The scene's model.
    pub model: FatiguePoint,
    /// Calibrated.
    pub calibrated: FatiguePoint,
    /// Converged mesh.
    pub converged: FatiguePoint,
}

impl Comparison {
    /// The free ball of the converged run reached the stops: its motion is chaotic, and damage
    /// rates of different models are then statistics of different trajectories.
    pub fn free_chaotic(&self) -> bool {
        self.converged.free.impacts > 0 || self.calibrated.free.impacts > 0
    }

    /// Any run failed.
    pub fn failed(&self) -> bool {
        self.model.failed() || self.calibrated.failed() || self.converged.failed()
    }
}

/// Ratio `a / b` of two damage rates (NaN when b is 0 or either is not finite).
pub fn ratio(a: f64, b: f64) -> f64 {
    if a.is_finite() && b.is_finite() && b > 0.0 {
        a / b
    } else {
        f64::NAN
    }
}

/// CSV of a comparison (damage rates per hour and their ratios to the converged mesh).
pub fn comparison_csv(rows: &[Comparison], n: usize, m: usize) -> String {
    let steady_from = rows.first().map_or(f64::NAN, |c| c.converged.steady_from);
    let mut s = format!(
        "# host-sim fatigue --calibrate-against {m}: damage rate [1/h] of the {n}-element model as given, calibrated ({n} elements, fitted to the full solver with {m}), and the core with {m} elements\n\
         # steady: every damage rate over t ≥ {steady_from} s to the end of the run\n\
         # ratio_* = damage rate / the {m}-element one; free_chaotic = 1 when the free ball reached the stops (then its damage rate is a statistic of a chaotic run)\n\
         frequency,amplitude,status,locked_model,locked_calibrated,locked_converged,locked_ratio_model,locked_ratio_calibrated,free_model,free_calibrated,free_converged,free_ratio_model,free_ratio_calibrated,free_chaotic\n"
    );
    for c in rows {
        let (f, a) = (c.converged.frequency, c.converged.amplitude);
        if c.failed() {
            s.push_str(&format!("{f},{a},failed,,,,,,,,,,,\n"));
            continue;
        }
        let (lm, lc, lr) = (
            c.model.locked.damage_rate,
            c.calibrated.locked.damage_rate,
            c.converged.locked.damage_rate,
        );
        let (fm, fc, fr) = (
            c.model.free.damage_rate,
            c.calibrated.free.damage_rate,
            c.converged.free.damage_rate,
        );
        s.push_str(&format!(
            "{f},{a},ok,{lm:.6e},{lc:.6e},{lr:.6e},{:.4},{:.4},{fm:.6e},{fc:.6e},{fr:.6e},{:.4},{:.4},{}\n",
            ratio(lm, lr),
            ratio(lc, lr),
            ratio(fm, fr),
            ratio(fc, fr),
            u8::from(c.free_chaotic())
        ));
    }
    s
}
