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
/// Quantities of the time-history envelopes.
const K: usize = 12;

fn fields(r: &Row) -> [f64; K] {
    let e = &r.energies;
    [
        r.tip_deflection,
        r.base_y,
        r.ball_angle.to_degrees(),
        r.ball_rel_angle.to_degrees(),
        r.tip_angle.to_degrees(),
        e.beam_strain,
        e.beam_kinetic,
        e.beam_potential,
        e.tip_kinetic,
        e.tip_potential,
        e.ball_kinetic,
        e.ball_potential,
    ]
}

#[derive(Clone, Debug)]
struct Bucket {
    t0: f64,
    t1: f64,
    lo: [f64; K],
    hi: [f64; K],
    n: usize,
}

impl Bucket {
    fn merge(&mut self, o: &Bucket) {
        self.t1 = o.t1;
        for i in 0..K {
            self.lo[i] = self.lo[i].min(o.lo[i]);
            self.hi[i] = self.hi[i].max(o.hi[i]);
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
        }
    }

    /// Adds a row.
    pub fn push(&mut self, r: &Row) {
        self.has_ball |= r.ball_angle.is_finite();
        let v = fields(r);
        match self.buckets.last_mut() {
            Some(b) if b.n < self.per_bucket => b.merge(&Bucket {
                t0: r.t,
                t1: r.t,
                lo: v,
                hi: v,
                n: 1,
            }),
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
                self.buckets.push(Bucket {
                    t0: r.t,
                    t1: r.t,
                    lo: v,
                    hi: v,
                    n: 1,
                });
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
                .push_back((r.t, r.tip_deflection, r.ball_angle.to_degrees()));
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

    fn envelope(&self, label: &str, i: usize, scale: f64) -> Series {
        let mut pts = Vec::with_capacity(2 * self.buckets.len());
        for b in &self.buckets {
            if b.lo[i] <= b.hi[i] {
                let t = 0.5 * (b.t0 + b.t1);
                pts.push((t, scale * b.lo[i]));
                if b.hi[i] > b.lo[i] {
                    pts.push((t, scale * b.hi[i]));
                }
            }
        }
        Series::line(label, pts)
    }

    fn phase(&self, f: impl Fn(&Row) -> (f64, f64)) -> Series {
        Series::line("", self.thin.iter().map(f).collect())
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
                let mut p = vec![Panel::new(
                    "Beam tip",
                    "t [s]",
                    "y [m]",
                    vec![
                        data.envelope("deflection (relative)", 0, 1.0),
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
                    "amplitude [m]",
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
                let mut p = vec![Panel::new(
                    "Beam tip y – ẏ",
                    "y [m]",
                    "ẏ [m/s]",
                    vec![data.phase(|r| (r.tip_deflection, r.tip_velocity))],
                )];
                if has_ball {
                    p.push(Panel::new(
                        "Ball θ – θ̇",
                        "θ [rad]",
                        "θ̇ [rad/s]",
                        vec![data.phase(|r| (r.ball_angle, r.ball_rate))],
                    ));
                    p.push(Panel::new(
                        "Ball spin φ – φ̇",
                        "φ [rad]",
                        "φ̇ [rad/s]",
                        vec![data.phase(|r| (r.ball_spin, r.ball_spin_rate))],
                    ));
                    p.push(Panel::new(
                        "Ball θ – tip mass ψ",
                        "ψ [rad]",
                        "θ [rad]",
                        vec![data.phase(|r| (r.tip_angle, r.ball_angle))],
                    ));
                    ("phase", p, (2, 2), (1200, 1000))
                } else {
                    p.push(Panel::new(
                        "Tip mass ψ – ψ̇",
                        "ψ [rad]",
                        "ψ̇ [rad/s]",
                        vec![data.phase(|r| (r.tip_angle, r.tip_rate))],
                    ));
                    ("phase", p, (1, 2), (1200, 550))
                }
            }
            Plot::Energy => {
                let mj = 1e3;
                let mut p = vec![
                    Panel::new(
                        "Beam energies",
                        "t [s]",
                        "E [mJ = N·mm]",
                        vec![
                            data.envelope("strain", 5, mj),
                            data.envelope("kinetic", 6, mj),
                            data.envelope("potential Δ", 7, mj),
                        ],
                    ),
                    Panel::new(
                        "Tip mass energies",
                        "t [s]",
                        "E [mJ]",
                        vec![
                            data.envelope("kinetic", 8, mj),
                            data.envelope("potential Δ", 9, mj),
                        ],
                    ),
                ];
                if has_ball {
                    p.push(Panel::new(
                        "Ball energies",
                        "t [s]",
                        "E [mJ]",
                        vec![
                            data.envelope("kinetic", 10, mj),
                            data.envelope("potential Δ", 11, mj),
                        ],
                    ));
                    p.push(Panel::new(
                        "Kinetic energy: beam vs ball",
                        "t [s]",
                        "E [mJ]",
                        vec![data.envelope("beam", 6, mj), data.envelope("ball", 10, mj)],
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
