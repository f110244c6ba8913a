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

mod record;
mod signal;

pub use record::*;
pub use signal::*;

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

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
