//! Identification of the first pole (f₁, ζ₁) from a measured response record: a free decay or
//! an ambient (broadband-excited) response, of acceleration, velocity or displacement (all show
//! the same pole).
//!
//! **Method** (chosen for a lightly damped, well separated mode, ζ ~ 0.1–1 %):
//!
//! 1. The mode: the highest peak of the Hann-windowed, zero-padded amplitude spectrum in the
//!    search band (default 0.1 Hz … Nyquist/2; `band` to choose a mode).
//! 2. Zero-phase band-pass around it, `[0.5, 1.5] f_p` with raised-cosine edges 0.2 f_p wide
//!    (an FFT filter on the zero-padded record: no phase shift, no decay-rate bias for a pole
//!    whose half-power band ζ f_p is far inside the passband).
//! 3. Ambient records only: **random decrement** — the average of the segments that start
//!    where the band-passed signal crosses its standard deviation upwards. For a linear system
//!    under broadband load it is proportional to the free decay from that level (Vandiver et
//!    al. 1982), so step 4 applies to it.
//! 4. **Fit of a damped sinusoid** `y = e^{−ζω t} (a cos ω_d t + b sin ω_d t)`,
//!    `ω_d = ω √(1 − ζ²)`, by nonlinear least squares (variable projection: a, b linear; f, ζ
//!    by Gauss–Newton with Levenberg damping), started from the spectral peak and the Hilbert
//!    envelope's log-decrement. The window skips the filter's edge transients (5 periods at each
//!    end) and stops where the envelope falls below 2 % of its start (below that the noise
//!    dominates). A fit of the whole waveform uses every sample's phase and amplitude: its
//!    variance is lower than a log-decrement's or a half-power reading's, and the standard
//!    errors come with it.
//!
//! **Uncertainty** (1σ): the fit's standard errors, `s² (JᵀJ)⁻¹` with the residual variance
//! `s²`, inflated by `f_s / (2B)` (the band-passed noise is correlated over 1/(2B); B = the
//! passband width), combined in quadrature with half the difference between the fits of the
//! first and the second half of the window, which catches what the model leaves out:
//! amplitude-dependent frequency and damping, a neighbouring mode, drift. Ambient: the standard
//! error of the mean of the random decrements of 8 blocks of the record (the scatter of the
//! random excitation, which dominates there: ζ from random decrement scatters by ±20 % at
//! ~1000 triggers).

use crate::{csvio, lm};
use anyhow::{bail, Context, Result};
use rustfft::{num_complex::Complex, FftPlanner};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::Path;

/// What kind of record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RecordKind {
    /// A free decay (after a release, a tap, or the end of an excitation).
    Decay,
    /// A response to broadband (ambient, wind, traffic) excitation: random decrement first.
    Ambient,
}

/// The identified pole with its uncertainty (1σ).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct Identified {
    /// Undamped natural frequency f₁ = ω/2π \[Hz\].
    pub f1: f64,
    /// Its standard uncertainty \[Hz\].
    pub f1_uncertainty: f64,
    /// Damping ratio ζ₁ \[-\].
    pub zeta: f64,
    /// Its standard uncertainty \[-\].
    pub zeta_uncertainty: f64,
    /// Record kind the method assumed.
    pub record: RecordKind,
    /// Column identified.
    pub column: String,
    /// Fit window \[s\] (decay: in the record; ambient: of the random-decrement signature).
    pub window: (f64, f64),
    /// Random-decrement triggers (ambient), 0 for a decay.
    pub triggers: usize,
    /// RMS of the fit residual over RMS of the fitted signal \[-\].
    pub residual_ratio: f64,
    /// `usable`, or `unusable` with the [`Identified::reasons`] (the quality gate,
    /// [`Identified::check`]); `calibrate --from-identified` refuses an unusable result.
    #[serde(default)]
    pub verdict: Verdict,
    /// Why the result is unusable (empty when usable).
    #[serde(default)]
    pub reasons: Vec<String>,
    /// Each quality figure beside its expected range and a grade ([`Identified::quality`]).
    #[serde(default)]
    pub quality: Vec<Quality>,
}

/// A grade of one quality figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Grade {
    /// In the range a good record gives.
    Ok,
    /// Usable, but outside that range: treat the number with care.
    Poor,
    /// Beyond what a usable result allows.
    Failed,
}

impl Grade {
    /// `ok`, `poor` or `FAILED`, as printed.
    pub fn word(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::Poor => "poor",
            Self::Failed => "FAILED",
        }
    }

    /// `Ok` up to `ok`, `Poor` up to `usable`, `Failed` beyond (or NaN).
    pub fn of(value: f64, ok: f64, usable: f64) -> Self {
        if value <= ok {
            Self::Ok
        } else if value <= usable {
            Self::Poor
        } else {
            Self::Failed
        }
    }
}

/// One quality figure: its value, the range expected of a good record, and the grade.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct Quality {
    /// What is measured.
    pub figure: String,
    /// Its value (in `unit`).
    pub value: f64,
    /// Unit of `value`.
    pub unit: String,
    /// The range a good record gives, and the limit of a usable one.
    pub expected: String,
    /// The grade.
    pub grade: Grade,
}

/// Fit residual of a clear mode: 0.002–0.06 of the signal RMS (see [`MAX_RESIDUAL`]).
pub const OK_RESIDUAL: f64 = 0.06;
/// Relative 1σ uncertainty of f₁ of a good record: a few per mille.
pub const OK_F1_UNCERTAINTY: f64 = 0.005;
/// Relative 1σ uncertainty of ζ of a good record: random decrement scatters by ±20 % at about
/// 1000 triggers, a clean decay by far less.
pub const OK_ZETA_UNCERTAINTY: f64 = 0.25;

/// The quality gate's verdict on an identified pole.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Every check of [`Identified::check`] passed (also what a file written before the gate
    /// reads as; `calibrate` checks its numbers again).
    #[default]
    Usable,
    /// At least one check failed: the numbers are not a pole of the record.
    Unusable,
}

/// Largest fit residual (RMS of the residual over RMS of the fitted signal) of a usable result.
/// A damped sinusoid fitted to a lightly damped mode leaves the noise of its band: 0.002–0.06 on
/// records with a clear mode (the tests' and the project's records); a fifth of the signal left
/// unexplained (a signal-to-noise ratio below 14 dB in the passband) means the "mode" is noise
/// or several modes, and white noise gives 0.3–1.
pub const MAX_RESIDUAL: f64 = 0.2;

/// Largest relative 1σ uncertainty of f₁ in a usable result: a measured pole is known to a few
/// per mille; ±5 % is no longer a frequency to calibrate a model to.
pub const MAX_F1_UNCERTAINTY: f64 = 0.05;

/// Bounds of ζ the fit is held in ([`fit_decay`]); a result on one of them is the bound, not a
/// measurement (a growing oscillation ends on the lower one).
const ZETA_BOUNDS: (f64, f64) = (1e-6, 0.5);

/// Largest record `identify` reads \[samples\]: the fit holds the record and its zero-padded
/// spectra in memory, about 100 bytes per sample at this size (0.4 GB); a free decay needs a few
/// hundred periods of the mode and an ambient record a few thousand, i.e. far fewer samples at
/// any useful sampling rate: decimate or cut a longer record.
pub const MAX_SAMPLES: usize = 1 << 22;

impl Identified {
    /// The quality gate: the reasons this result is not a pole of the record (empty: usable).
    /// `band` is the search band \[Hz\].
    pub fn check(&self, band: Option<(f64, f64)>) -> Vec<String> {
        let mut why = Vec::new();
        if !(self.f1.is_finite() && self.f1 > 0.0 && self.zeta.is_finite()) {
            why.push(format!(
                "f1 = {} Hz, zeta = {} are not finite",
                self.f1, self.zeta
            ));
            return why;
        }
        if !(self.f1_uncertainty.is_finite() && self.zeta_uncertainty.is_finite()) {
            why.push(format!(
                "an uncertainty is not finite (f1 ± {} Hz, zeta ± {}): the record does not determine the pole",
                self.f1_uncertainty, self.zeta_uncertainty
            ));
        }
        if self.residual_ratio.is_nan() || self.residual_ratio > MAX_RESIDUAL {
            why.push(format!(
                "the fit leaves {:.3} of the signal RMS unexplained (at most {MAX_RESIDUAL}): no single decaying mode in the record",
                self.residual_ratio
            ));
        }
        if let Some((lo, hi)) = band {
            if !(lo..=hi).contains(&self.f1) {
                why.push(format!(
                    "f1 = {:.6} Hz lies outside the band {lo} … {hi} Hz asked for",
                    self.f1
                ));
            }
        }
        if self.zeta <= 2.0 * ZETA_BOUNDS.0 {
            why.push(format!(
                "zeta = {:.2e} sits on the fit's lower bound {:.0e}: the oscillation does not decay (negative damping, or a steady response)",
                self.zeta, ZETA_BOUNDS.0
            ));
        } else if self.zeta >= 0.98 * ZETA_BOUNDS.1 {
            why.push(format!(
                "zeta = {:.3} sits on the fit's upper bound {}: no lightly damped mode",
                self.zeta, ZETA_BOUNDS.1
            ));
        }
        if self.f1_uncertainty > MAX_F1_UNCERTAINTY * self.f1 {
            why.push(format!(
                "f1 is uncertain by {:.1} % (at most {:.0} %)",
                100.0 * self.f1_uncertainty / self.f1,
                100.0 * MAX_F1_UNCERTAINTY
            ));
        }
        if self.zeta_uncertainty >= self.zeta {
            why.push(format!(
                "zeta = {:.3} % ± {:.3} %: the record does not tell the damping from zero",
                100.0 * self.zeta,
                100.0 * self.zeta_uncertainty
            ));
        }
        why
    }

    /// The quality figures, each beside its expected range and a grade: the fit residual, the
    /// relative uncertainties of f₁ and of ζ.
    pub fn quality(&self) -> Vec<Quality> {
        let rel_f = self.f1_uncertainty / self.f1;
        let rel_z = self.zeta_uncertainty / self.zeta;
        let nan_failed = |g: Grade, v: f64| if v.is_finite() { g } else { Grade::Failed };
        vec![
            Quality {
                figure: "fit residual".into(),
                value: self.residual_ratio,
                unit: "of the signal RMS".into(),
                expected: format!("≤ {OK_RESIDUAL} (a clear mode); usable ≤ {MAX_RESIDUAL}"),
                grade: nan_failed(
                    Grade::of(self.residual_ratio, OK_RESIDUAL, MAX_RESIDUAL),
                    self.residual_ratio,
                ),
            },
            Quality {
                figure: "f1 uncertainty".into(),
                value: 100.0 * rel_f,
                unit: "% (1σ)".into(),
                expected: format!(
                    "≤ {} %; usable ≤ {} %",
                    100.0 * OK_F1_UNCERTAINTY,
                    100.0 * MAX_F1_UNCERTAINTY
                ),
                grade: nan_failed(
                    Grade::of(rel_f, OK_F1_UNCERTAINTY, MAX_F1_UNCERTAINTY),
                    rel_f,
                ),
            },
            Quality {
                figure: "zeta uncertainty".into(),
                value: 100.0 * rel_z,
                unit: "% of zeta (1σ)".into(),
                expected: format!(
                    "≤ {} % of zeta; usable < 100 %",
                    100.0 * OK_ZETA_UNCERTAINTY
                ),
                grade: if rel_z.is_finite() && rel_z < 1.0 {
                    Grade::of(rel_z, OK_ZETA_UNCERTAINTY, 1.0)
                } else {
                    Grade::Failed
                },
            },
        ]
    }

    /// Applies [`Identified::check`]: sets the verdict, the reasons and the quality figures.
    pub fn gate(mut self, band: Option<(f64, f64)>) -> Self {
        self.quality = self.quality();
        self.reasons = self.check(band);
        self.verdict = if self.reasons.is_empty() {
            Verdict::Usable
        } else {
            Verdict::Unusable
        };
        self
    }
}

/// A record: uniform time step and the chosen column.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Time step \[s\].
    pub dt: f64,
    /// Start time \[s\].
    pub t0: f64,
    /// Samples.
    pub x: Vec<f64>,
}

/// Reads column `column` and time column `time` of a CSV (comment lines `#`, then a header row
/// of names, then numbers), line by line (the file is never held whole). Errors name the file,
/// line and column; a record longer than [`MAX_SAMPLES`] is refused when its row is reached.
pub fn read_csv(path: &Path, time: &str, column: &str) -> Result<Record> {
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot read `{}`", path.display()))?;
    parse(file, time, column).with_context(|| format!("`{}`", path.display()))
}

/// As [`read_csv`], from text.
pub fn parse_csv(text: &str, time: &str, column: &str) -> Result<Record> {
    parse(text.as_bytes(), time, column)
}

fn parse(source: impl std::io::Read, time: &str, column: &str) -> Result<Record> {
    // The separator from the first content line (comma, semicolon, tab or spaces, as the
    // excitation record's): the lines up to it are read ahead, the rest streams.
    use std::io::{BufRead, Read};
    let mut source = std::io::BufReader::new(source);
    let mut head = Vec::new();
    loop {
        let start = head.len();
        if source.read_until(b'\n', &mut head)? == 0 {
            break;
        }
        let line = String::from_utf8_lossy(&head[start..]);
        let line = line.trim_start_matches('\u{feff}').trim();
        if !line.is_empty() && !line.starts_with('#') {
            break;
        }
    }
    let separator = csvio::detect_separator(&String::from_utf8_lossy(&head));
    let mut rows = csvio::Rows::new(head.as_slice().chain(source), separator);
    let Some(header) = rows.next_row()? else {
        bail!("no header row (expected column names, e.g. `t,{column}`)");
    };
    let names: Vec<String> = header.cells().iter().map(|c| c.to_string()).collect();
    let find = |name: &str, what: &str| {
        names.iter().position(|n| *n == name).ok_or_else(|| {
            anyhow::anyhow!(
                "invalid value for `{what}`: no column `{name}` (columns: {})",
                names.join(", ")
            )
        })
    };
    let (it, ix) = (find(time, "--time-column")?, find(column, "--column")?);
    let (mut t, mut x) = (Vec::new(), Vec::new());
    while let Some(row) = rows.next_row()? {
        if x.len() == MAX_SAMPLES {
            bail!(
                "line {}: the record is longer than {MAX_SAMPLES} samples, the most `identify` reads (it holds the record and its spectra in memory); decimate it or cut it to the decay",
                row.line()
            );
        }
        t.push(row.number(it, time)?);
        x.push(row.number(ix, column)?);
    }
    if x.len() < 64 {
        bail!("too short: {} samples (at least 64)", x.len());
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        bail!("invalid time column `{time}`: not increasing");
    }
    for (k, w) in t.windows(2).enumerate() {
        if ((w[1] - w[0]) / dt - 1.0).abs() > 1e-3 {
            bail!(
                "invalid time column `{time}`: not uniformly sampled (step {:.6e} s after row {}, mean {dt:.6e} s); resample the record",
                w[1] - w[0],
                k + 1
            );
        }
    }
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
        bail!(
            "invalid value for `--column`: `{column}` is constant ({lo}): no response to identify"
        );
    }
    Ok(Record { dt, t0: t[0], x })
}

fn fft(x: &mut [Complex<f64>], inverse: bool) {
    let mut planner = FftPlanner::new();
    let plan = if inverse {
        planner.plan_fft_inverse(x.len())
    } else {
        planner.plan_fft_forward(x.len())
    };
    plan.process(x);
}

/// Peak of the Hann-windowed amplitude spectrum (zero-padded 8×) within `band` \[Hz\].
pub fn spectral_peak(x: &[f64], dt: f64, band: (f64, f64)) -> Result<f64> {
    let n = x.len();
    // Zero-padded 8× for a fine grid on short records; long ones are fine enough at 2×.
    let m = (8 * n).min((2 * n).max(1 << 21)).next_power_of_two();
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = (0..m)
        .map(|k| {
            if k < n {
                let w = 0.5 - 0.5 * (TAU * k as f64 / (n - 1) as f64).cos();
                Complex::new((x[k] - mean) * w, 0.0)
            } else {
                Complex::new(0.0, 0.0)
            }
        })
        .collect();
    fft(&mut buf, false);
    let df = 1.0 / (m as f64 * dt);
    let (lo, hi) = (
        (band.0 / df).ceil().max(1.0) as usize,
        ((band.1 / df).floor() as usize).min(m / 2 - 1),
    );
    if lo + 2 >= hi {
        bail!(
            "invalid value for `--band`: {:?} Hz holds no spectral line of this record",
            band
        );
    }
    let (k, _) = (lo..=hi)
        .map(|k| (k, buf[k].norm()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((lo, 0.0));
    // Parabolic interpolation of the log amplitude (Gaussian-like Hann main lobe).
    let (a, b, c) = (
        buf[k - 1].norm().max(1e-300).ln(),
        buf[k].norm().max(1e-300).ln(),
        buf[k + 1].norm().max(1e-300).ln(),
    );
    let den = a - 2.0 * b + c;
    let d = if den.abs() > 0.0 {
        (0.5 * (a - c) / den).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    Ok((k as f64 + d) * df)
}

/// Zero-phase band-pass `[0.5, 1.5] f_p`, raised-cosine edges 0.2 f_p; returns the filtered
/// signal and the passband width \[Hz\].
pub fn band_pass(x: &[f64], dt: f64, fp: f64) -> (Vec<f64>, f64) {
    let n = x.len();
    let m = (2 * n).next_power_of_two();
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = (0..m)
        .map(|k| Complex::new(if k < n { x[k] - mean } else { 0.0 }, 0.0))
        .collect();
    fft(&mut buf, false);
    let df = 1.0 / (m as f64 * dt);
    let (lo, hi, edge) = (0.5 * fp, 1.5 * fp, 0.2 * fp);
    let gain = |f: f64| -> f64 {
        let f = f.abs();
        if f < lo - edge / 2.0 || f > hi + edge / 2.0 {
            0.0
        } else if f < lo + edge / 2.0 {
            0.5 - 0.5 * (std::f64::consts::PI * (f - lo + edge / 2.0) / edge).cos()
        } else if f > hi - edge / 2.0 {
            0.5 + 0.5 * (std::f64::consts::PI * (f - hi + edge / 2.0) / edge).cos()
        } else {
            1.0
        }
    };
    for (k, v) in buf.iter_mut().enumerate() {
        let f = if k <= m / 2 {
            k as f64
        } else {
            k as f64 - m as f64
        } * df;
        *v *= gain(f);
    }
    fft(&mut buf, true);
    ((0..n).map(|k| buf[k].re / m as f64).collect(), hi - lo)
}

/// Hilbert envelope |x + i H(x)|.
pub fn envelope(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    let m = (2 * n).next_power_of_two();
    let mut buf: Vec<Complex<f64>> = (0..m)
        .map(|k| Complex::new(if k < n { x[k] } else { 0.0 }, 0.0))
        .collect();
    fft(&mut buf, false);
    for (k, v) in buf.iter_mut().enumerate() {
        if k > 0 && k < m / 2 {
            *v *= 2.0;
        } else if k > m / 2 {
            *v = Complex::new(0.0, 0.0);
        }
    }
    fft(&mut buf, true);
    (0..n).map(|k| buf[k].norm() / m as f64).collect()
}

/// A damped sinusoid fitted to `y` (sampled at `dt` from t = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecayFit {
    /// Natural frequency \[Hz\].
    pub f: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Standard errors of f, ζ (unscaled fit covariance).
    pub sigma: (f64, f64),
    /// RMS residual / RMS signal.
    pub residual_ratio: f64,
}

/// Basis and linear coefficients for (f, ζ); returns the residual vector.
fn project(y: &[f64], dt: f64, f: f64, zeta: f64) -> (Vec<f64>, [f64; 2]) {
    let w = TAU * f;
    let wd = w * (1.0 - zeta * zeta).max(0.0).sqrt();
    let (mut s11, mut s12, mut s22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let basis = |k: usize| {
        let t = k as f64 * dt;
        let e = (-zeta * w * t).exp();
        (e * (wd * t).cos(), e * (wd * t).sin())
    };
    for (k, yk) in y.iter().enumerate() {
        let (c, s) = basis(k);
        s11 += c * c;
        s12 += c * s;
        s22 += s * s;
        b1 += c * yk;
        b2 += s * yk;
    }
    let det = s11 * s22 - s12 * s12;
    let (a, b) = if det.abs() > 0.0 {
        ((s22 * b1 - s12 * b2) / det, (s11 * b2 - s12 * b1) / det)
    } else {
        (0.0, 0.0)
    };
    let r = y
        .iter()
        .enumerate()
        .map(|(k, yk)| {
            let (c, s) = basis(k);
            yk - a * c - b * s
        })
        .collect();
    (r, [a, b])
}

/// Fits a damped sinusoid to `y` from the start values (f₀, ζ₀): variable projection,
/// Gauss–Newton with Levenberg damping on (f, ζ); standard errors from the full 4-parameter
/// Jacobian.
pub fn fit_decay(y: &[f64], dt: f64, f0: f64, zeta0: f64) -> Result<DecayFit> {
    let sse = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    /// The fit's problem in x = (f, ζ): the residual after projecting out (a, b).
    struct Decay<'a> {
        y: &'a [f64],
        dt: f64,
    }
    impl lm::Problem<2> for Decay<'_> {
        fn residuals(&mut self, x: &[f64; 2]) -> Result<Vec<f64>> {
            Ok(project(self.y, self.dt, x[0], x[1]).0)
        }
        fn difference_step(&self, x: &[f64; 2], j: usize) -> f64 {
            if j == 0 {
                x[0] * 1e-7
            } else {
                x[1].max(1e-4) * 1e-5
            }
        }
        fn project(&self, x: &mut [f64; 2]) {
            x[1] = x[1].clamp(ZETA_BOUNDS.0, ZETA_BOUNDS.1);
        }
        fn small_step(&self, x: &[f64; 2], dx: &[f64; 2]) -> bool {
            (dx[0] / x[0]).abs() < 1e-12 && dx[1].abs() < 1e-10
        }
    }
    let settings = lm::Settings {
        max_iterations: 200,
        tries: 20,
        shrink: 5.0,
        damping_floor: 0.0,
        accept_equal: true,
        min_gain: f64::NEG_INFINITY,
        min_residual: 0.0,
    };
    let start = [f0, zeta0.clamp(1e-5, 0.3)];
    let fit = lm::minimize(&mut Decay { y, dt }, start, &settings)?;
    let ([f, z], r) = (fit.x, fit.residuals);
    if !(f.is_finite() && z.is_finite() && f > 0.0) {
        bail!("the damped-sinusoid fit did not converge");
    }
    // Covariance of (f, ζ, a, b) from the Jacobian of the model y = e(a cos + b sin).
    let (_, [a, b]) = project(y, dt, f, z);
    let model = |f: f64, z: f64, a: f64, b: f64, k: usize| {
        let w = TAU * f;
        let wd = w * (1.0 - z * z).sqrt();
        let t = k as f64 * dt;
        (-z * w * t).exp() * (a * (wd * t).cos() + b * (wd * t).sin())
    };
    let n = y.len();
    let mut jt = nalgebra::DMatrix::<f64>::zeros(4, n);
    let (hf, hz) = (f * 1e-7, z.max(1e-4) * 1e-5);
    let ha = (a.abs() + b.abs()).max(1e-300) * 1e-7;
    for k in 0..n {
        let m0 = model(f, z, a, b, k);
        jt[(0, k)] = (model(f + hf, z, a, b, k) - m0) / hf;
        jt[(1, k)] = (model(f, z + hz, a, b, k) - m0) / hz;
        jt[(2, k)] = (model(f, z, a + ha, b, k) - m0) / ha;
        jt[(3, k)] = (model(f, z, a, b + ha, k) - m0) / ha;
    }
    let s2 = sse(&r) / (n as f64 - 4.0).max(1.0);
    let cov = (&jt * jt.transpose())
        .try_inverse()
        .map(|c| c * s2)
        .unwrap_or_else(|| nalgebra::DMatrix::from_element(4, 4, f64::INFINITY));
    let signal = y.iter().map(|v| v * v).sum::<f64>();
    Ok(DecayFit {
        f,
        zeta: z,
        sigma: (cov[(0, 0)].max(0.0).sqrt(), cov[(1, 1)].max(0.0).sqrt()),
        residual_ratio: (sse(&r) / signal.max(1e-300)).sqrt(),
    })
}

/// Start values and window of a band-passed decay `y`: log-decrement of the Hilbert envelope.
fn decay_window(y: &[f64], dt: f64, fp: f64) -> Result<(usize, usize, f64)> {
    let n = y.len();
    let skip = ((5.0 / fp) / dt).ceil() as usize;
    if 2 * skip + 16 >= n {
        bail!(
            "record too short for the mode at {fp:.4} Hz: {:.2} s, at least 10 periods plus the fit needed",
            n as f64 * dt
        );
    }
    let env = envelope(y);
    let start = skip
        + env[skip..n / 2]
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, _)| i)
            .unwrap_or(0);
    let peak = env[start];
    let mut end = n - skip;
    if let Some(k) = env[start..n - skip].iter().position(|e| *e < 0.02 * peak) {
        end = start + k;
    }
    if end < start + ((3.0 / fp) / dt) as usize {
        bail!("no decay found at {fp:.4} Hz (the envelope does not decay over 3 periods); for a response to ambient excitation use `--record ambient`");
    }
    // ln envelope slope = −ζ ω.
    let (mut sx, mut sy, mut sxx, mut sxy, mut m) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (k, e) in env[start..end].iter().enumerate() {
        let (t, l) = (k as f64 * dt, e.max(1e-300).ln());
        sx += t;
        sy += l;
        sxx += t * t;
        sxy += t * l;
        m += 1.0;
    }
    let slope = (m * sxy - sx * sy) / (m * sxx - sx * sx);
    let zeta0 = (-slope / (TAU * fp)).clamp(1e-5, 0.3);
    Ok((start, end, zeta0))
}

/// Random-decrement signature of the band-passed `y`: average of segments of `len` samples
/// starting at the up-crossings of the level σ_y; returns it and the number of triggers.
pub fn random_decrement(y: &[f64], len: usize) -> Result<(Vec<f64>, usize)> {
    let n = y.len();
    let sigma = (y.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let mut sum = vec![0.0; len];
    let mut count = 0;
    for k in 1..n.saturating_sub(len) {
        if y[k - 1] < sigma && y[k] >= sigma {
            for (s, v) in sum.iter_mut().zip(&y[k..k + len]) {
                *s += v;
            }
            count += 1;
        }
    }
    if count < 10 {
        bail!("too few random-decrement triggers ({count}, at least 10): the record is too short for an ambient identification");
    }
    Ok((sum.into_iter().map(|s| s / count as f64).collect(), count))
}

/// Identifies f₁, ζ₁ of a record (module docs), with the quality gate's verdict
/// ([`Identified::check`]). `band`: where to look for the mode \[Hz\].
pub fn identify(
    rec: &Record,
    kind: RecordKind,
    band: Option<(f64, f64)>,
    column: &str,
) -> Result<Identified> {
    let id = fit_pole(rec, kind, band, column)?;
    Ok(id.gate(Some(band.unwrap_or((0.1, 0.25 / rec.dt)))))
}

fn fit_pole(
    rec: &Record,
    kind: RecordKind,
    band: Option<(f64, f64)>,
    column: &str,
) -> Result<Identified> {
    let dt = rec.dt;
    let nyquist = 0.5 / dt;
    let band = band.unwrap_or((0.1, 0.5 * nyquist));
    if !(band.0.is_finite() && band.1.is_finite() && 0.0 < band.0 && band.0 < band.1) {
        bail!("invalid value for `--band`: {band:?} (must be two increasing positive frequencies)");
    }
    if band.1 > nyquist {
        bail!(
            "invalid value for `--band`: {} … {} Hz reaches above the record's Nyquist frequency {nyquist} Hz",
            band.0,
            band.1
        );
    }
    let fp = spectral_peak(&rec.x, dt, band)?;
    let (y, width) = band_pass(&rec.x, dt, fp);
    // Correlation of band-passed noise: about f_s / (2B) samples per independent one.
    let inflate = (1.0 / dt / (2.0 * width)).max(1.0).sqrt();
    match kind {
        RecordKind::Decay => {
            let (start, end, zeta0) = decay_window(&y, dt, fp)?;
            let w = &y[start..end];
            let all = fit_decay(w, dt, fp, zeta0)?;
            let half = w.len() / 2;
            let first = fit_decay(&w[..half], dt, all.f, all.zeta)?;
            let second = fit_decay(&w[half..], dt, all.f, all.zeta)?;
            Ok(Identified {
                f1: all.f,
                f1_uncertainty: (all.sigma.0 * inflate).hypot(0.5 * (first.f - second.f)),
                zeta: all.zeta,
                zeta_uncertainty: (all.sigma.1 * inflate).hypot(0.5 * (first.zeta - second.zeta)),
                record: kind,
                column: column.into(),
                window: (rec.t0 + start as f64 * dt, rec.t0 + end as f64 * dt),
                triggers: 0,
                residual_ratio: all.residual_ratio,
                verdict: Verdict::Unusable,
                reasons: Vec::new(),
                quality: Vec::new(),
            })
        }
        RecordKind::Ambient => {
            // Segments of 30 periods (ζ ≥ 0.1 %: the signature decays by ≥ 17 % over them) or a
            // twentieth of the record.
            let len = ((30.0 / fp / dt) as usize).min(y.len() / 20);
            if len < ((3.0 / fp) / dt) as usize {
                bail!("record too short for an ambient identification at {fp:.4} Hz (at least 60 periods needed)");
            }
            let (rd, triggers) = random_decrement(&y, len)?;
            let env = envelope(&rd);
            let zeta0 = {
                let (e0, e1) = (env[0].max(1e-300), env[len * 3 / 4].max(1e-300));
                ((e0 / e1).ln() / (TAU * fp * (len * 3 / 4) as f64 * dt)).clamp(1e-4, 0.3)
            };
            let all = fit_decay(&rd, dt, fp, zeta0)?;
            // Scatter of the estimate: random decrements of K blocks of the record; the
            // standard error of their mean, s/√K (K = 8, or fewer for a short record).
            let mut blocks = Vec::new();
            for k in (2..=8).rev() {
                let size = y.len() / k;
                let fits: Result<Vec<DecayFit>> = (0..k)
                    .map(|i| {
                        let (r, _) = random_decrement(&y[i * size..(i + 1) * size], len)?;
                        fit_decay(&r, dt, all.f, all.zeta)
                    })
                    .collect();
                if let Ok(f) = fits {
                    blocks = f;
                    break;
                }
            }
            let sem = |v: &dyn Fn(&DecayFit) -> f64| -> f64 {
                let k = blocks.len() as f64;
                if k < 2.0 {
                    return f64::INFINITY;
                }
                let mean = blocks.iter().map(v).sum::<f64>() / k;
                (blocks.iter().map(|b| (v(b) - mean).powi(2)).sum::<f64>() / (k - 1.0) / k).sqrt()
            };
            Ok(Identified {
                f1: all.f,
                f1_uncertainty: (all.sigma.0 * inflate).hypot(sem(&|b| b.f)),
                zeta: all.zeta,
                zeta_uncertainty: (all.sigma.1 * inflate).hypot(sem(&|b| b.zeta)),
                record: kind,
                column: column.into(),
                window: (0.0, len as f64 * dt),
                triggers,
                residual_ratio: all.residual_ratio,
                verdict: Verdict::Unusable,
                reasons: Vec::new(),
                quality: Vec::new(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::ChaCha8Rng;
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;

    /// The seed of the tests' noise (ChaCha8).
    const SEED: u64 = 12345;

    /// An exact damped sinusoid (f = 1.1 Hz, ζ = 0.4 %) with 5 % white noise: recovered to the
    /// fit's own uncertainty (f within 0.05 %, ζ within 10 %; analytic reference).
    #[test]
    fn damped_sinusoid_with_noise_is_recovered() {
        let (f, z, dt) = (1.1, 0.004, 0.01);
        let w = TAU * f;
        let wd = w * (1.0f64 - z * z).sqrt();
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let mut noise = || rng.random_range(-1.0..=1.0);
        let x: Vec<f64> = (0..12000)
            .map(|k| {
                let t = k as f64 * dt;
                (-z * w * t).exp() * (wd * t + 0.3).cos() + 0.05 * noise()
            })
            .collect();
        let rec = Record { dt, t0: 0.0, x };
        let id = identify(&rec, RecordKind::Decay, None, "x").unwrap();
        assert!((id.f1 / f - 1.0).abs() < 5e-4, "{id:?}");
        assert!((id.zeta / z - 1.0).abs() < 0.1, "{id:?}");
        assert!(id.f1_uncertainty > 0.0 && id.zeta_uncertainty > 0.0);
    }

    /// Ambient record: a 1 Hz, ζ = 1 % oscillator under white-noise force (2000 s at 50 Hz,
    /// semi-implicit Euler with 10 substeps, whose own frequency and damping errors are below
    /// 0.1 %), its acceleration identified by random decrement. Budgets: f within 0.5 %; both
    /// f and ζ within 3σ of the uncertainty the tool states (its contract), plus 0.1 %. ζ itself
    /// is only as good as random decrement on 2000 s of record: measured +0.8 % at [`SEED`]
    /// (f −0.08 %; the stated 1σ of ζ is 10.7 %, and other streams have given +4 % and +20 %),
    /// which the stated uncertainty must cover; the 10 % ζ budget is for free decays
    /// (tests/calibration.rs: −0.3 %).
    #[test]
    fn ambient_response_is_identified_by_random_decrement() {
        let (f, z, dt, sub) = (1.0, 0.01, 0.02, 10);
        let w = TAU * f;
        let h = dt / sub as f64;
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let (mut x, mut v) = (0.0, 0.0);
        let mut acc = Vec::with_capacity(100_000);
        for _ in 0..100_000 {
            // A standard normal force for this sample.
            let n: f64 = rng.sample(StandardNormal);
            for _ in 0..sub {
                v += h * (n - 2.0 * z * w * v - w * w * x);
                x += h * v;
            }
            acc.push(n - 2.0 * z * w * v - w * w * x);
        }
        let rec = Record {
            dt,
            t0: 0.0,
            x: acc,
        };
        let id = identify(&rec, RecordKind::Ambient, Some((0.5, 2.0)), "acc").unwrap();
        eprintln!(
            "ambient: f {:+.3} %, zeta {:+.1} % (stated 1 sigma {:.1} %)",
            100.0 * (id.f1 / f - 1.0),
            100.0 * (id.zeta / z - 1.0),
            100.0 * id.zeta_uncertainty / z
        );
        assert!(id.triggers > 500, "{id:?}");
        assert!((id.f1 / f - 1.0).abs() < 5e-3, "{id:?}");
        assert!(
            (id.f1 - f).abs() < 3.0 * id.f1_uncertainty + 1e-3 * f,
            "{id:?}"
        );
        assert!(
            (id.zeta - z).abs() < 3.0 * id.zeta_uncertainty + 1e-3 * z,
            "{id:?}"
        );
    }

    /// Bad CSV input is an error naming the column or line, never a panic.
    #[test]
    fn bad_csv_names_the_problem() {
        let e = parse_csv("t,a\n0,1\n", "t", "b").unwrap_err().to_string();
        assert!(
            e.contains("`--column`") && e.contains("columns: t, a"),
            "{e}"
        );
        let mut text = String::from("t,a\n");
        for k in 0..100 {
            text.push_str(&format!(
                "{},{}\n",
                k as f64 * 0.01,
                if k == 50 { "x" } else { "1" }
            ));
        }
        let e = format!("{:#}", parse_csv(&text, "t", "a").unwrap_err());
        assert!(e.contains("line 52") && e.contains("not a number"), "{e}");
    }
}
