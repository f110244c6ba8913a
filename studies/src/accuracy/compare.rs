//! Comparing a candidate's trajectory with the reference: error statistics and paired host
//! timings.

use super::{embedded, Config, TestScene, Trajectory, GRID};
use anyhow::Result;
use serde::Serialize;
use std::time::Instant;

/// Errors of a candidate against the reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Errors {
    /// Window of the pointwise errors \[s\] (the whole comparison, or up to the reference's
    /// first impact for chaotic scenes).
    pub window: f64,
    /// RMS and max tip error over [0, min(5 s, window)] \[m\].
    pub tip_rms_5: f64,
    /// Max tip error, first 5 s \[m\].
    pub tip_max_5: f64,
    /// RMS tip error over the window \[m\].
    pub tip_rms: f64,
    /// Max tip error over the window \[m\].
    pub tip_max: f64,
    /// Max ball angle error over the first 5 s (or the window) \[rad\] (NaN: locked).
    pub ball_max_5: f64,
    /// Max ball angle error over the window \[rad\].
    pub ball_max: f64,
    /// Steady-state tip amplitude (half peak-to-peak over the last 20 s) \[m\].
    pub amplitude: f64,
    /// First time the tip error exceeds 10 % of the reference's peak dynamic deflection \[s\]
    /// (None: never).
    pub separation: Option<f64>,
    /// RMS dynamic tip deflection (about its mean) over [10 s, end] \[m\].
    pub dyn_rms: f64,
    /// Impacts per second.
    pub impacts_per_s: f64,
    /// RMS of θ over [10 s, end] \[rad\].
    pub ball_rms: f64,
}

/// Whole-run statistics of one trajectory.
pub fn statistics(t: &Trajectory, last: f64) -> (f64, f64, f64, f64) {
    let n = t.tip.len();
    let from_ss = ((t.duration() - last).max(0.0) / GRID).round() as usize;
    let from10 = ((10.0f64).min(t.duration() * 0.5) / GRID).round() as usize;
    let ss = &t.tip[from_ss.min(n)..];
    let (lo, hi) = ss
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let amplitude = if lo <= hi { 0.5 * (hi - lo) } else { f64::NAN };
    let w = &t.tip[from10.min(n)..];
    let mean = w.iter().sum::<f64>() / w.len().max(1) as f64;
    let dyn_rms =
        (w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / w.len().max(1) as f64).sqrt();
    let b = &t.ball[from10.min(n)..];
    let ball_rms = if b.iter().all(|x| x.is_finite()) {
        (b.iter().map(|x| x * x).sum::<f64>() / b.len().max(1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let ips = t.impacts.len() as f64 / t.duration().max(GRID);
    (amplitude, dyn_rms, ball_rms, ips)
}

/// Peak dynamic deflection of the reference, max |tip − static| \[m\].
pub fn peak_dynamic(r: &Trajectory) -> f64 {
    r.tip
        .iter()
        .map(|x| (x - r.static_tip).abs())
        .fold(0.0, f64::max)
}

/// Compares `c` with the reference `r` (same grid). `window`: end of the pointwise comparison.
pub fn compare(c: &Trajectory, r: &Trajectory, window: f64, last: f64) -> Errors {
    let n = c.tip.len().min(r.tip.len());
    let jw = ((window / GRID).round() as usize + 1).min(n);
    let j5 = ((5.0f64.min(window) / GRID).round() as usize + 1).min(n);
    let err = |j: usize| (c.tip[j] - r.tip[j]).abs();
    let berr = |j: usize| (c.ball[j] - r.ball[j]).abs();
    let rms = |m: usize| ((0..m).map(|j| err(j).powi(2)).sum::<f64>() / m.max(1) as f64).sqrt();
    let max = |m: usize, f: &dyn Fn(usize) -> f64| (0..m).map(f).fold(0.0, f64::max);
    let ball_locked = r.ball.first().is_none_or(|x| !x.is_finite());
    let scale = peak_dynamic(r);
    let separation = (0..n).find(|&j| err(j) > 0.1 * scale).map(Trajectory::time);
    let (amplitude, dyn_rms, ball_rms, impacts_per_s) = statistics(c, last);
    // A run that stopped early has no error bound: infinite.
    let short = c.tip.len() < r.tip.len();
    let inf_if = |x: f64| if short { f64::INFINITY } else { x };
    Errors {
        window,
        tip_rms_5: rms(j5),
        tip_max_5: max(j5, &err),
        tip_rms: inf_if(rms(jw)),
        tip_max: inf_if(max(jw, &err)),
        ball_max_5: if ball_locked {
            f64::NAN
        } else {
            max(j5, &berr)
        },
        ball_max: if ball_locked {
            f64::NAN
        } else {
            inf_if(max(jw, &berr))
        },
        amplitude: inf_if(amplitude),
        separation,
        dyn_rms,
        impacts_per_s,
        ball_rms,
    }
}

/// Host time of `cfg` relative to `reference` on `scene`: the median of `repeats` ratios of
/// runs taken in interleaved pairs (so that drifts of a shared machine cancel), which of the
/// two runs first alternating from pair to pair (a warm cache favours the second) \[-\].
pub fn paired_ratio(
    cfg: &Config,
    reference: &Config,
    scene: &TestScene,
    seconds: f64,
    repeats: usize,
) -> Result<f64> {
    let mut v = Vec::new();
    for k in 0..repeats.max(1) {
        let (r, c) = if k % 2 == 0 {
            let r = time_per_second(reference, scene, seconds, 1)?;
            (r, time_per_second(cfg, scene, seconds, 1)?)
        } else {
            let c = time_per_second(cfg, scene, seconds, 1)?;
            (time_per_second(reference, scene, seconds, 1)?, c)
        };
        v.push(c / r);
    }
    v.sort_by(f64::total_cmp);
    Ok(v[v.len() / 2])
}

/// Median host time per simulated second of `cfg` on `scene` (`seconds` simulated per
/// repetition, `repeats` repetitions) \[s/s\].
pub fn time_per_second(
    cfg: &Config,
    scene: &TestScene,
    seconds: f64,
    repeats: usize,
) -> Result<f64> {
    let mut v = Vec::new();
    for _ in 0..repeats.max(1) {
        let mut s = embedded(cfg, scene)?;
        let steps = (seconds / cfg.step).round() as usize;
        let start = Instant::now();
        for k in 1..=steps {
            if s.step(scene.input.accel(k as f64 * cfg.step)).is_err() {
                break;
            }
        }
        v.push(start.elapsed().as_secs_f64() / seconds);
    }
    v.sort_by(f64::total_cmp);
    Ok(v[v.len() / 2])
}
