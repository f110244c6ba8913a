//! Statistics of one run's rows and the figures' smoothing: maxima and means over a window,
//! the ball's beat period and spectral peaks, the sweep's onset, block amplitudes and running
//! means.

use absorber_sim::fft;
use absorber_sim::run::Row;
use absorber_sim::sweep::SweepPoint;

/// Largest value of `x` over rows with `from ≤ t < to`.
pub(super) fn max_in(rows: &[Row], from: f64, to: f64, x: impl Fn(&Row) -> f64) -> f64 {
    rows.iter()
        .filter(|r| r.t >= from && r.t < to)
        .map(x)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Mean of `x` over rows with `from ≤ t < to`.
pub(super) fn mean_in(rows: &[Row], from: f64, to: f64, x: impl Fn(&Row) -> f64) -> f64 {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.t >= from && r.t < to)
        .map(x)
        .collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Beating of the ball angle after `from` seconds: the period of its envelope (mean time
/// between the envelope's upward crossings of its mean), from the peaks of |α|.
pub(super) fn beat_period(rows: &[Row], from: f64) -> Option<f64> {
    let a: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.t >= from)
        .map(|r| (r.t, r.ball_rel_angle.abs()))
        .collect();
    let peaks: Vec<(f64, f64)> = a
        .windows(3)
        .filter(|w| w[1].1 > w[0].1 && w[1].1 >= w[2].1)
        .map(|w| w[1])
        .collect();
    if peaks.len() < 8 {
        return None;
    }
    let mean = peaks.iter().map(|p| p.1).sum::<f64>() / peaks.len() as f64;
    let ups: Vec<f64> = peaks
        .windows(2)
        .filter(|w| w[0].1 < mean && w[1].1 >= mean)
        .map(|w| w[1].0)
        .collect();
    (ups.len() >= 3).then(|| (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64)
}

/// The two strongest spectral peaks of the ball angle between 1.5 and 3 Hz after `from`.
pub(super) fn ball_peaks(rows: &[Row], from: f64, h: f64) -> (f64, f64) {
    let x: Vec<f64> = rows
        .iter()
        .filter(|r| r.t >= from)
        .map(|r| r.ball_rel_angle)
        .collect();
    let s = fft::spectrum(&x, h);
    let mut bins: Vec<(f64, f64)> = s
        .frequency
        .iter()
        .zip(&s.amplitude)
        .map(|(f, a)| (*f, *a))
        .filter(|(f, _)| (1.5..3.0).contains(f))
        .collect();
    bins.sort_by(|a, b| b.1.total_cmp(&a.1));
    let first = bins.first().map_or(f64::NAN, |b| b.0);
    // The second peak: the strongest bin at least 0.1 Hz away from the first.
    let second = bins
        .iter()
        .find(|b| (b.0 - first).abs() > 0.1)
        .map_or(f64::NAN, |b| b.0);
    (first.max(second), first.min(second))
}

/// Lowest sweep frequency at which the ball's steady amplitude exceeds 10°.
pub(super) fn onset(points: &[SweepPoint]) -> Option<f64> {
    points
        .iter()
        .find(|p| p.ball_amplitude_deg > 10.0)
        .map(|p| p.frequency)
}

/// Half peak-to-peak tip deflection \[mm\] over consecutive blocks of `block` seconds, at each
/// block's middle: three oscillations at 4 Hz drawn over each other are one band, their
/// amplitudes three curves.
pub(super) fn amplitude_blocks(rows: &[Row], block: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let Some(first) = rows.first() else {
        return out;
    };
    let (mut t0, mut lo, mut hi) = (first.t, f64::INFINITY, f64::NEG_INFINITY);
    for r in rows {
        if r.t >= t0 + block {
            out.push((t0 + 0.5 * block, 0.5 * (hi - lo) * 1e3));
            (t0, lo, hi) = (t0 + block, f64::INFINITY, f64::NEG_INFINITY);
        }
        lo = lo.min(r.tip_deflection);
        hi = hi.max(r.tip_deflection);
    }
    out
}

/// Centred running mean of `pts` (times ascending) over `window` seconds; applied twice it is a
/// triangular kernel of width 2·`window` (the energies' ripple at twice the excitation
/// frequency gone, the beam → ball exchange over seconds kept), as the run's energy plot.
pub(super) fn running_mean(pts: &[(f64, f64)], window: f64) -> Vec<(f64, f64)> {
    let mut cs = vec![0.0; pts.len() + 1];
    for (k, p) in pts.iter().enumerate() {
        cs[k + 1] = cs[k] + p.1;
    }
    pts.iter()
        .map(|&(t, _)| {
            let lo = pts.partition_point(|p| p.0 < t - 0.5 * window);
            let hi = pts.partition_point(|p| p.0 <= t + 0.5 * window);
            let n = hi - lo;
            (
                t,
                if n > 0 {
                    (cs[hi] - cs[lo]) / n as f64
                } else {
                    f64::NAN
                },
            )
        })
        .collect()
}
