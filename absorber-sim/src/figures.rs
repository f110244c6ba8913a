//! The paper's figures from a run: time histories, FFT, phase planes, energy curves.

use crate::fft::spectrum;
use crate::output::OutputDir;
use crate::plot::{render, Panel, Series};
use crate::run::Row;
use crate::scene::Plot;
use anyhow::Result;
use std::collections::VecDeque;
use std::path::PathBuf;

/// Largest number of rows kept for the phase planes (longer runs are thinned uniformly).
const MAX_POINTS: usize = 20_000;
/// Largest number of min/max buckets of the time histories.
const MAX_BUCKETS: usize = 10_000;
/// Largest number of samples in the FFT (the last ones after the transient).
pub const MAX_FFT: usize = 1 << 20;
/// Quantities of the time-history envelopes and running means.
const K: usize = 15;
/// Window of the energies' running means \[s\]: several periods of the beam (≥ 1 Hz here), short
/// against the beam → ball exchange (seconds).
pub const ENERGY_MEAN_WINDOW: f64 = 2.0;

/// The plotted quantities of a row: lengths in mm, angles in degrees, energies in mJ; the beam's
/// strain energy as its change from the first row (`strain0` \[J\]), and the totals from rest.
fn fields(r: &Row, strain0: f64) -> [f64; K] {
    let e = &r.energies;
    let strain = e.beam_strain - strain0;
    let mj = 1e3;
    [
        1e3 * r.tip_deflection,
        1e3 * r.base_y,
        r.ball_angle.to_degrees(),
        r.ball_rel_angle.to_degrees(),
        r.tip_angle.to_degrees(),
        mj * strain,
        mj * e.beam_kinetic,
        mj * e.beam_potential,
        mj * e.tip_kinetic,
        mj * e.tip_potential,
        mj * e.ball_kinetic,
        mj * e.ball_potential,
        mj * (strain + e.beam_kinetic + e.beam_potential),
        mj * (e.tip_kinetic + e.tip_potential),
        mj * (e.ball_kinetic + e.ball_potential),
    ]
}

#[derive(Clone, Debug)]
struct Bucket {
    t0: f64,
    t1: f64,
    lo: [f64; K],
    hi: [f64; K],
    sum: [f64; K],
    n: usize,
}

impl Bucket {
    fn of(t: f64, v: [f64; K]) -> Self {
        Self {
            t0: t,
            t1: t,
            lo: v,
            hi: v,
            sum: v,
            n: 1,
        }
    }

    fn merge(&mut self, o: &Bucket) {
        self.t1 = o.t1;
        for i in 0..K {
            self.lo[i] = self.lo[i].min(o.lo[i]);
            self.hi[i] = self.hi[i].max(o.hi[i]);
            self.sum[i] += o.sum[i];
        }
        self.n += o.n;
    }
}

/// What the plots of a run need, gathered row by row in bounded memory: min/max envelopes of
/// the time histories (at most [`MAX_BUCKETS`] buckets), a uniformly thinned set of rows for
/// the phase planes (at most [`MAX_POINTS`]), the last [`MAX_FFT`] samples after the transient.
#[derive(Clone, Debug)]
pub struct PlotData {
    transient: f64,
    buckets: Vec<Bucket>,
    per_bucket: usize,
    thin: Vec<Row>,
    stride: usize,
    seen: usize,
    fft: VecDeque<(f64, f64, f64)>,
    has_ball: bool,
    /// The first row's beam strain energy \[J\] (the energies are plotted from it).
    strain0: Option<f64>,
    /// The first row's tip deflection, the static one \[mm\] (the tip is plotted about it).
    tip0: Option<f64>,
}

impl PlotData {
    /// Empty; the FFT takes the rows with t ≥ `transient`.
    pub fn new(transient: f64) -> Self {
        Self {
            transient,
            buckets: Vec::new(),
            per_bucket: 1,
            thin: Vec::new(),
            stride: 1,
            seen: 0,
            fft: VecDeque::new(),
            has_ball: false,
            strain0: None,
            tip0: None,
        }
    }

    /// Adds a row.
    pub fn push(&mut self, r: &Row) {
        self.has_ball |= r.ball_angle.is_finite();
        let strain0 = *self.strain0.get_or_insert(r.energies.beam_strain);
        self.tip0.get_or_insert(1e3 * r.tip_deflection);
        let v = fields(r, strain0);
        match self.buckets.last_mut() {
            Some(b) if b.n < self.per_bucket => b.merge(&Bucket::of(r.t, v)),
            _ => {
                if self.buckets.len() == MAX_BUCKETS {
                    let old = std::mem::take(&mut self.buckets);
                    for pair in old.chunks(2) {
                        let mut b = pair[0].clone();
                        if let Some(o) = pair.get(1) {
                            b.merge(o);
                        }
                        self.buckets.push(b);
                    }
                    self.per_bucket *= 2;
                }
                self.buckets.push(Bucket::of(r.t, v));
            }
        }
        if self.seen.is_multiple_of(self.stride) {
            if self.thin.len() == MAX_POINTS {
                let mut i = 0;
                self.thin.retain(|_| {
                    i += 1;
                    (i - 1) % 2 == 0
                });
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.thin.push(*r);
            }
        }
        self.seen += 1;
        if r.t >= self.transient {
            if self.fft.len() == MAX_FFT {
                self.fft.pop_front();
            }
            self.fft
                .push_back((r.t, 1e3 * r.tip_deflection, r.ball_angle.to_degrees()));
        }
    }

    /// Sizes of the buffers: FFT samples, envelope buckets, thinned rows (all bounded).
    pub fn sizes(&self) -> (usize, usize, usize) {
        (self.fft.len(), self.buckets.len(), self.thin.len())
    }

    /// Largest value of envelope quantity `i` (0: tip deflection) over the run.
    pub fn envelope_max(&self, i: usize) -> f64 {
        self.buckets
            .iter()
            .map(|b| b.hi[i])
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Running mean of quantity `i` over `window` seconds, applied twice (centred; a triangular
    /// kernel of width 2·`window`: a single boxcar leaves a ripple at twice the excitation
    /// frequency unless the window holds whole periods; twice, its side lobes are squared);
    /// from the buckets' sums, one point per bucket.
    fn running_mean(&self, label: &str, i: usize, window: f64) -> Series {
        let b = &self.buckets;
        // Prefix sums of (sum, n) over the buckets.
        let mut cs = vec![(0.0, 0usize); b.len() + 1];
        for (k, x) in b.iter().enumerate() {
            cs[k + 1] = (cs[k].0 + x.sum[i], cs[k].1 + x.n);
        }
        let mid: Vec<f64> = b.iter().map(|x| 0.5 * (x.t0 + x.t1)).collect();
        let pts = (0..b.len())
            .map(|k| {
                let lo = mid.partition_point(|&t| t < mid[k] - 0.5 * window);
                let hi = mid.partition_point(|&t| t <= mid[k] + 0.5 * window);
                let (s, n) = (cs[hi].0 - cs[lo].0, cs[hi].1 - cs[lo].1);
                (mid[k], if n > 0 { s / n as f64 } else { f64::NAN })
            })
            .collect::<Vec<(f64, f64)>>();
        // The second pass, over the first pass's points (equal weights: equal buckets).
        let mut c2 = vec![0.0; pts.len() + 1];
        for (k, p) in pts.iter().enumerate() {
            c2[k + 1] = c2[k] + p.1;
        }
        // Only where the kernel (half-width `window`) lies inside the run: a truncated one
        // near the start averages the ring-up into t = 0 and shows energy at rest.
        let (first, last) = match (b.first(), b.last()) {
            (Some(f), Some(l)) => (f.t0, l.t1),
            _ => (0.0, 0.0),
        };
        let pts = (0..pts.len())
            .filter(|&k| mid[k] >= first + window && mid[k] <= last - window)
            .map(|k| {
                let lo = mid.partition_point(|&t| t < mid[k] - 0.5 * window);
                let hi = mid.partition_point(|&t| t <= mid[k] + 0.5 * window);
                (mid[k], (c2[hi] - c2[lo]) / (hi - lo).max(1) as f64)
            })
            .collect();
        Series::line(label, pts).width(2)
    }

    fn envelope(&self, label: &str, i: usize, scale: f64) -> Series {
        self.envelope_about(label, i, scale, 0.0)
    }

    /// The min/max envelope of quantity `i`, scaled, less `offset` (after scaling).
    fn envelope_about(&self, label: &str, i: usize, scale: f64, offset: f64) -> Series {
        let mut pts = Vec::with_capacity(2 * self.buckets.len());
        for b in &self.buckets {
            if b.lo[i] <= b.hi[i] {
                let t = 0.5 * (b.t0 + b.t1);
                pts.push((t, scale * b.lo[i] - offset));
                if b.hi[i] > b.lo[i] {
                    pts.push((t, scale * b.hi[i] - offset));
                }
            }
        }
        Series::line(label, pts)
    }

    /// A phase plane: the transient (t < the transient, grey) and the steady state (t ≥ it,
    /// in colour) apart.
    fn phase(&self, f: impl Fn(&Row) -> (f64, f64)) -> Vec<Series> {
        let t = self.transient;
        let pick = |steady: bool| -> Vec<(f64, f64)> {
            self.thin
                .iter()
                .filter(|r| (r.t >= t) == steady)
                .map(&f)
                .collect()
        };
        vec![
            Series::line(&format!("transient, t < {t} s"), pick(false)).colored(crate::plot::GREY),
            Series::line(&format!("steady, t ≥ {t} s"), pick(true)).colored(0),
        ]
    }

    /// FFT amplitude of the tip deflection (`ball = false`) or the ball angle in degrees, up to
    /// `max_hz`; and the time span it covers.
    pub fn fft(&self, ball: bool, max_hz: f64) -> (Vec<(f64, f64)>, f64, f64) {
        let n = self.fft.len();
        if n < 4 {
            return (Vec::new(), f64::NAN, f64::NAN);
        }
        let (t0, t1) = (self.fft[0].0, self.fft[n - 1].0);
        let dt = (t1 - t0) / (n - 1) as f64;
        let x: Vec<f64> = self
            .fft
            .iter()
            .map(|s| if ball { s.2 } else { s.1 })
            .collect();
        let s = spectrum(&x, dt);
        let pts = s
            .frequency
            .iter()
            .zip(&s.amplitude)
            .filter(|(f, _)| **f <= max_hz)
            .map(|(f, a)| (*f, *a))
            .collect();
        (pts, t0, t1)
    }
}

/// FFT of `x` over rows with t ≥ `from`, up to `max_hz`.
pub fn fft_points(
    rows: &[Row],
    from: f64,
    max_hz: f64,
    x: impl Fn(&Row) -> f64,
) -> Vec<(f64, f64)> {
    let tail: Vec<&Row> = rows.iter().filter(|r| r.t >= from).collect();
    if tail.len() < 4 {
        return Vec::new();
    }
    let dt = (tail[tail.len() - 1].t - tail[0].t) / (tail.len() - 1) as f64;
    let s = spectrum(&tail.iter().map(|r| x(r)).collect::<Vec<_>>(), dt);
    s.frequency
        .iter()
        .zip(&s.amplitude)
        .filter(|(f, _)| **f <= max_hz)
        .map(|(f, a)| (*f, *a))
        .collect()
}

/// Writes the requested plots of a run into `dir` as `<stem>_<plot>.png` (staged; committed
/// with the run); returns the paths.
pub fn run_plots(
    dir: &mut OutputDir,
    stem: &str,
    title: &str,
    data: &PlotData,
    plots: &[Plot],
) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let has_ball = data.has_ball;
    let transient = data.transient;
    for plot in plots {
        let (name, panels, rows_cols, size) = match plot {
            Plot::Time => {
                // About the static sag, so that the base's motion and the tip's share a scale
                // (a 0.2 mm decay under a −16 mm sag was a flat line).
                let tip0 = data.tip0.unwrap_or(0.0);
                let mut p = vec![Panel::new(
                    "Beam tip",
                    "t [s]",
                    "y [mm]",
                    vec![
                        data.envelope_about(
                            &format!("tip deflection (relative to the base) − static {tip0:.3} mm"),
                            0,
                            1.0,
                            tip0,
                        ),
                        data.envelope("base y_b", 1, 1.0),
                    ],
                )];
                if has_ball {
                    p.push(Panel::new(
                        "Ball",
                        "t [s]",
                        "angle [deg]",
                        vec![
                            data.envelope("θ (from vertical)", 2, 1.0),
                            data.envelope("θ − ψ (in housing)", 3, 1.0),
                        ],
                    ));
                } else {
                    p.push(Panel::new(
                        "Tip mass",
                        "t [s]",
                        "ψ [deg]",
                        vec![data.envelope("", 4, 1.0)],
                    ));
                }
                ("time", p, (2, 1), (1200, 800))
            }
            Plot::Fft => {
                let (tip, t0, t1) = data.fft(false, 10.0);
                let t = format!("t = {t0:.1} … {t1:.1} s, after the transient {transient} s");
                let mut p = vec![Panel::new(
                    &format!("FFT of the beam tip deflection ({t})"),
                    "f [Hz]",
                    "amplitude [mm]",
                    vec![Series::line("", tip)],
                )];
                if has_ball {
                    p.push(Panel::new(
                        &format!("FFT of the ball angle θ ({t})"),
                        "f [Hz]",
                        "amplitude [deg]",
                        vec![Series::line("", data.fft(true, 10.0).0)],
                    ));
                }
                ("fft", p, (p_len(has_ball), 1), (1200, 800))
            }
            Plot::Phase => {
                let d = f64::to_degrees;
                let mut p = vec![Panel::new(
                    "Beam tip y – ẏ",
                    "y [mm]",
                    "ẏ [mm/s]",
                    data.phase(|r| (1e3 * r.tip_deflection, 1e3 * r.tip_velocity)),
                )];
                if has_ball {
                    p.push(Panel::new(
                        "Ball θ – θ̇",
                        "θ [deg]",
                        "θ̇ [deg/s]",
                        data.phase(|r| (d(r.ball_angle), d(r.ball_rate))),
                    ));
                    p.push(Panel::new(
                        "Ball spin φ – φ̇",
                        "φ [deg]",
                        "φ̇ [deg/s]",
                        data.phase(|r| (d(r.ball_spin), d(r.ball_spin_rate))),
                    ));
                    p.push(Panel::new(
                        "Ball θ – tip mass ψ",
                        "ψ [deg]",
                        "θ [deg]",
                        data.phase(|r| (d(r.tip_angle), d(r.ball_angle))),
                    ));
                    ("phase", p, (2, 2), (1200, 1000))
                } else {
                    p.push(Panel::new(
                        "Tip mass ψ – ψ̇",
                        "ψ [deg]",
                        "ψ̇ [deg/s]",
                        data.phase(|r| (d(r.tip_angle), d(r.tip_rate))),
                    ));
                    ("phase", p, (1, 2), (1200, 550))
                }
            }
            Plot::Energy => {
                let w = ENERGY_MEAN_WINDOW;
                let m = |label: &str, i: usize| data.running_mean(label, i, w);
                let mut transfer = vec![m("beam", 12), m("tip mass", 13)];
                if has_ball {
                    transfer.push(m("ball", 14));
                }
                let mut p = vec![
                    Panel::new(
                        &format!(
                            "Energy from rest: beam → ball ({w} s running mean, applied twice)"
                        ),
                        "t [s]",
                        "E [mJ]",
                        transfer,
                    ),
                    Panel::new(
                        &format!("Beam ({w} s running mean, applied twice)"),
                        "t [s]",
                        "E [mJ]",
                        vec![m("strain Δ", 5), m("kinetic", 6), m("potential Δ", 7)],
                    ),
                    Panel::new(
                        &format!("Tip mass ({w} s running mean, applied twice)"),
                        "t [s]",
                        "E [mJ]",
                        vec![m("kinetic", 8), m("potential Δ", 9)],
                    ),
                ];
                if has_ball {
                    p.push(Panel::new(
                        &format!("Ball ({w} s running mean, applied twice)"),
                        "t [s]",
                        "E [mJ]",
                        vec![m("kinetic", 10), m("potential Δ", 11)],
                    ));
                }
                ("energy", p, (2, 2), (1200, 900))
            }
        };
        let path = dir.write_with(&format!("{stem}_{name}.png"), |p| {
            render(p, title, &panels, rows_cols.0, rows_cols.1, size)
        })?;
        out.push(path);
    }
    Ok(out)
}

fn p_len(has_ball: bool) -> usize {
    if has_ball {
        2
    } else {
        1
    }
}
