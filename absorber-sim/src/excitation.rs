//! Base excitation: harmonic, or measured acceleration from a CSV file.
//!
//! Everything is on the step grid t_k = k h. The solver's input is the base acceleration
//! ÿ_b(t_k) \[m/s²\]; velocity ẏ_b and displacement y_b (for the absolute tip position and the
//! energies) are closed form for the harmonic case.
//!
//! A measured (CSV) acceleration record is processed as strong-motion records are (Boore &
//! Bommer 2005, "Processing of strong-motion accelerograms"), so that the base starts and ends
//! at rest and the energies are measured from rest:
//!
//! 1. reduced to the step grid by its average over each step's cell (nothing between grid
//!    points is lost);
//! 2. its mean removed, zero pads of 1.5·n/f_c (n = 2, the filter's order) added at both ends,
//!    and high-passed by a zero-phase (forward and backward) 2nd-order Butterworth filter with
//!    corner f_c (`excitation.highpass`, default [`HIGHPASS_CORNER`] = 0.1 Hz): gain
//!    1/(1 + (f_c/f)⁴), ½ at f_c, 0.9999 at 1 Hz, no phase shift;
//! 3. integrated from rest (ẏ_b = y_b = 0 at t = 0) by the trapezoidal rule, and a linear
//!    baseline c₀ + c₁ t subtracted from the acceleration (a quadratic from the velocity) that
//!    brings velocity and displacement back to zero at the record's end.
//!
//! The solver is driven by the processed acceleration, so relative motion, base motion and
//! energies belong to one consistent record.

use crate::csvio;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// The base motion on the step grid.
#[derive(Clone, Debug, PartialEq)]
pub enum Excitation {
    /// y_b = A sin(Ω t), ÿ_b = −A Ω² sin(Ω t), Ω = 2π f.
    Harmonic {
        /// Amplitude A \[m\].
        amplitude: f64,
        /// Frequency f \[Hz\].
        frequency: f64,
        /// Step h \[s\].
        step: f64,
    },
    /// Measured acceleration reduced to the step h (average over each step's cell).
    Sampled {
        /// Step h \[s\].
        step: f64,
        /// ÿ_b(t_k).
        accel: Vec<f64>,
        /// ẏ_b(t_k) (trapezoidal integral of the processed ÿ_b from rest).
        velocity: Vec<f64>,
        /// y_b(t_k) (trapezoidal integral of ẏ_b from rest).
        displacement: Vec<f64>,
        /// The record reduced to the grid before the baseline correction \[m/s²\].
        recorded: Vec<f64>,
    },
}

/// Base state at one grid point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Base {
    /// Acceleration \[m/s²\].
    pub accel: f64,
    /// Velocity \[m/s\].
    pub velocity: f64,
    /// Displacement \[m\].
    pub displacement: f64,
}

impl Excitation {
    /// Harmonic excitation.
    pub fn harmonic(amplitude: f64, frequency: f64, step: f64) -> Self {
        Self::Harmonic {
            amplitude,
            frequency,
            step,
        }
    }

    /// Base state at grid point `k` (t = k h). A sampled excitation holds its last value.
    pub fn at(&self, k: usize) -> Base {
        match self {
            Self::Harmonic {
                amplitude,
                frequency,
                step,
            } => {
                let w = std::f64::consts::TAU * frequency;
                let (s, c) = (w * k as f64 * step).sin_cos();
                Base {
                    accel: -amplitude * w * w * s,
                    velocity: amplitude * w * c,
                    displacement: amplitude * s,
                }
            }
            Self::Sampled {
                accel,
                velocity,
                displacement,
                ..
            } => {
                let i = k.min(accel.len().saturating_sub(1));
                Base {
                    accel: accel.get(i).copied().unwrap_or(0.0),
                    velocity: velocity.get(i).copied().unwrap_or(0.0),
                    displacement: displacement.get(i).copied().unwrap_or(0.0),
                }
            }
        }
    }

    /// A CSV record reduced to the step grid before its baseline correction (`None`: harmonic).
    pub fn recorded(&self) -> Option<&[f64]> {
        match self {
            Self::Harmonic { .. } => None,
            Self::Sampled { recorded, .. } => Some(recorded),
        }
    }

    /// Number of grid points available (`None`: unbounded).
    pub fn samples(&self) -> Option<usize> {
        match self {
            Self::Harmonic { .. } => None,
            Self::Sampled { accel, .. } => Some(accel.len()),
        }
    }

    /// Reads a CSV of `t, accel` and reduces it to the grid t_k = k h, k = 0 … `steps`
    /// (`steps = None`: as far as the file reaches). See [`Excitation::from_csv_text`]; its
    /// warnings are printed on stderr.
    pub fn from_csv(path: &Path, step: f64, steps: Option<usize>) -> Result<Self> {
        Self::from_csv_with(path, step, steps, None)
    }

    /// As [`Excitation::from_csv`], with the high-pass corner `corner` \[Hz\] (`None`: the
    /// default [`HIGHPASS_CORNER`]).
    pub fn from_csv_with(
        path: &Path,
        step: f64,
        steps: Option<usize>,
        corner: Option<f64>,
    ) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read excitation CSV `{}`", path.display()))?;
        let (e, warnings) = Self::from_csv_corner(&text, step, steps, corner)
            .with_context(|| format!("excitation CSV `{}`", path.display()))?;
        for w in warnings {
            eprintln!("warning: excitation CSV `{}`: {w}", path.display());
        }
        Ok(e)
    }

    /// As [`Excitation::from_csv_checked`], without the warnings.
    pub fn from_csv_text(text: &str, step: f64, steps: Option<usize>) -> Result<Self> {
        Self::from_csv_checked(text, step, steps).map(|(e, _)| e)
    }

    /// Parses CSV text ([`crate::csvio`]): two columns `t [s], accel [m/s²]`, separated by a
    /// comma (or, when the first line has none, a semicolon, a tab or spaces); a UTF-8
    /// byte-order mark, lines starting with `#` and an optional header line are skipped. Times must be finite and strictly increasing and start at or
    /// before 0; the grid must not extend past the last sample; the samples must be no coarser
    /// than 10 h apart; |accel| at most [`crate::scene::MAX_ACCEL`].
    ///
    /// The record (linear between its samples) is reduced to the step grid by its average over
    /// each step's cell [t_k − h/2, t_k + h/2] (the initial value at k = 0), so that nothing
    /// between grid points is dropped: the velocity change over the record is kept exactly, and
    /// the trapezoidal integral of the reduced record is its exact integral. It is then
    /// baseline-corrected as the module's documentation says, with the default corner
    /// [`HIGHPASS_CORNER`]. Returns warnings: when the record holds content the step cannot
    /// resolve (more than 10 % of its RMS differs from the reduced signal), and when the
    /// correction changes the peak acceleration by more than 10 %.
    pub fn from_csv_checked(
        text: &str,
        step: f64,
        steps: Option<usize>,
    ) -> Result<(Self, Vec<String>)> {
        Self::from_csv_corner(text, step, steps, None)
    }

    /// As [`Excitation::from_csv_checked`] with the high-pass corner `corner` \[Hz\] (`None`:
    /// [`HIGHPASS_CORNER`]); refused unless 0 < corner < 1/(4h).
    pub fn from_csv_corner(
        text: &str,
        step: f64,
        steps: Option<usize>,
        corner: Option<f64>,
    ) -> Result<(Self, Vec<String>)> {
        if let Some(c) = corner {
            if !(c.is_finite() && c > 0.0 && c < 0.25 / step) {
                bail!(
                    "`excitation.highpass` = {c} Hz: the high-pass corner must lie in (0, {}) Hz \
                     (a quarter of the step's sampling rate 1/h)",
                    0.25 / step
                );
            }
        }
        let mut t = Vec::new();
        let mut a = Vec::new();
        let mut rows = csvio::Rows::new(text.as_bytes(), csvio::detect_separator(text));
        let mut first = true;
        while let Some(row) = rows.next_row()? {
            let n = row.line();
            if std::mem::take(&mut first) && row.numbers().is_none() {
                continue; // header
            }
            if row.cells().len() != 2 {
                bail!(
                    "line {n}: expected 2 columns (t, accel), found {}",
                    row.cells().len()
                );
            }
            let (ti, ai) = (row.number(0, "t")?, row.number(1, "accel")?);
            if ai.abs() > crate::scene::MAX_ACCEL {
                bail!(
                    "line {n}: acceleration {ai} m/s² is beyond what the model represents (allowed: \
                     |accel| ≤ {} m/s², about 100 g)",
                    crate::scene::MAX_ACCEL
                );
            }
            if let Some(&prev) = t.last() {
                if ti <= prev {
                    bail!("line {n}: time {ti} does not increase (previous {prev})");
                }
                if ti - prev > 10.0 * step * (1.0 + 1e-9) {
                    bail!(
                        "line {n}: sample interval {:.6} s is coarser than 10 steps ({:.6} s)",
                        ti - prev,
                        10.0 * step
                    );
                }
            }
            t.push(ti);
            a.push(ai);
        }
        if t.len() < 2 {
            bail!("needs at least 2 samples, found {}", t.len());
        }
        if t[0] > 1e-12 {
            bail!("first sample at t = {} s; must start at t = 0", t[0]);
        }
        let last = *t.last().unwrap_or(&0.0);
        let available = ((last / step) * (1.0 + 1e-12)).floor() as usize;
        let n = match steps {
            Some(s) if s > available => {
                bail!(
                    "covers {last} s but the run needs {} s ({s} steps of {step} s)",
                    s as f64 * step
                )
            }
            Some(s) => s,
            None => available,
        };
        let rec = Record::new(&t, &a);
        let mut accel = Vec::with_capacity(available + 1);
        for k in 0..=available {
            let tk = k as f64 * step;
            accel.push(if k == 0 {
                rec.value(0.0)
            } else {
                let lo = (tk - 0.5 * step).max(t[0]);
                let hi = (tk + 0.5 * step).min(last);
                (rec.integral(hi) - rec.integral(lo)) / (hi - lo)
            });
        }
        let reduced = accel.clone();
        let corner = corner.unwrap_or(HIGHPASS_CORNER);
        let (velocity, displacement) = process(&mut accel, step, corner);
        let mut warnings = Vec::new();
        let (peak_raw, peak) = (max_abs(&reduced), max_abs(&accel));
        if peak_raw > 0.0 && (peak - peak_raw).abs() > 0.1 * peak_raw {
            warnings.push(format!(
                "the baseline correction changes the peak acceleration from {peak_raw:.4e} to \
                 {peak:.4e} m/s² (the record's content near or below the {corner} Hz corner \
                 is removed; a record holding long-period motion needs a lower \
                 `excitation.highpass`)"
            ));
        }
        let (mut accel, mut velocity, mut displacement) = (accel, velocity, displacement);
        accel.truncate(n + 1);
        velocity.truncate(n + 1);
        displacement.truncate(n + 1);
        let accel_reduced = &reduced[..=n];
        // Bandwidth: how much of the record (over the run) the reduced signal misses.
        let end = n as f64 * step;
        let (mut sum, mut sum2, mut res2, mut m) = (0.0, 0.0, 0.0, 0usize);
        for (&ti, &ai) in t.iter().zip(&a) {
            if ti < 0.0 || ti > end {
                continue;
            }
            let x = ti / step;
            let k = (x.floor() as usize).min(n.saturating_sub(1));
            let w = (x - k as f64).clamp(0.0, 1.0);
            let r = accel_reduced[k] + w * (accel_reduced[(k + 1).min(n)] - accel_reduced[k]);
            sum += ai;
            sum2 += ai * ai;
            res2 += (ai - r) * (ai - r);
            m += 1;
        }
        if m > 1 {
            let mean = sum / m as f64;
            let var = (sum2 / m as f64 - mean * mean).max(0.0);
            let lost = (res2 / m as f64).sqrt();
            if var > 0.0 && lost > 0.1 * var.sqrt() {
                warnings.push(format!(
                    "the record has content faster than the step h = {step} s resolves (Nyquist {:.1} Hz): \
                     {:.0} % of its RMS is averaged out over each step (the velocity change is kept); \
                     use a smaller step to follow it",
                    0.5 / step,
                    100.0 * lost / var.sqrt()
                ));
            }
        }
        Ok((
            Self::Sampled {
                step,
                accel,
                velocity,
                displacement,
                recorded: accel_reduced.to_vec(),
            },
            warnings,
        ))
    }
}

/// Default high-pass corner of a measured record's baseline correction \[Hz\]: a tenth of the
/// lowest first frequency of the scenes here (1.03 Hz, the mast arm), the corner
/// strong-motion processing commonly uses for records of this length.
pub const HIGHPASS_CORNER: f64 = 0.1;

/// The strong-motion processing of the module's documentation, steps 2 and 3, on the grid
/// acceleration `accel` (processed in place; step `h`, corner `corner` \[Hz\]). Returns
/// (ẏ_b, y_b), both zero at the first and the last grid point.
fn process(accel: &mut [f64], h: f64, corner: f64) -> (Vec<f64>, Vec<f64>) {
    let n = accel.len();
    if n < 2 {
        accel.iter_mut().for_each(|a| *a = 0.0);
        return (vec![0.0; n], vec![0.0; n]);
    }
    let mean = trapezoid_mean(accel);
    // Pads of 1.5·n/f_c with n = 2 (Converse & Brady's rule as Boore & Bommer state it): the
    // filter's response to the record's ends dies out inside them.
    let pad = (3.0 / corner / h).ceil() as usize;
    let mut x = vec![0.0; n + 2 * pad];
    for (xi, &a) in x[pad..pad + n].iter_mut().zip(accel.iter()) {
        *xi = a - mean;
    }
    let filter = HighPass::butterworth2(corner, h);
    filter.run(&mut x);
    x.reverse();
    filter.run(&mut x);
    x.reverse();
    accel.copy_from_slice(&x[pad..pad + n]);
    // Integrated from rest; then the linear baseline that ends at rest.
    let (mut v, mut y) = integrate(accel, h);
    let t: Vec<f64> = (0..n).map(|k| k as f64 * h).collect();
    let (v0, y0) = integrate(&vec![1.0; n], h);
    let (v1, y1) = integrate(&t, h);
    let e = n - 1;
    let det = v0[e] * y1[e] - v1[e] * y0[e];
    if det.abs() > 0.0 {
        let c0 = -(v[e] * y1[e] - v1[e] * y[e]) / det;
        let c1 = -(v0[e] * y[e] - v[e] * y0[e]) / det;
        for k in 0..n {
            accel[k] += c0 + c1 * t[k];
            v[k] += c0 * v0[k] + c1 * v1[k];
            y[k] += c0 * y0[k] + c1 * y1[k];
        }
    }
    (v, y)
}

/// Trapezoidal integrals from rest: (∫a, ∫∫a).
fn integrate(a: &[f64], h: f64) -> (Vec<f64>, Vec<f64>) {
    let n = a.len();
    let (mut v, mut y) = (vec![0.0; n], vec![0.0; n]);
    for k in 1..n {
        v[k] = v[k - 1] + 0.5 * h * (a[k - 1] + a[k]);
        y[k] = y[k - 1] + 0.5 * h * (v[k - 1] + v[k]);
    }
    (v, y)
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, a| m.max(a.abs()))
}

/// A 2nd-order high-pass biquad (bilinear transform with the corner pre-warped).
struct HighPass {
    b: [f64; 3],
    a: [f64; 2],
}

impl HighPass {
    /// Butterworth (Q = 1/√2), corner `fc` \[Hz\], sample interval `h` \[s\].
    fn butterworth2(fc: f64, h: f64) -> Self {
        let k = (std::f64::consts::PI * fc * h).tan();
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        Self {
            b: [norm, -2.0 * norm, norm],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
        }
    }

    /// Filters `x` in place from its first sample (transposed direct form II, from rest).
    fn run(&self, x: &mut [f64]) {
        let (mut z1, mut z2) = (0.0, 0.0);
        for xi in x.iter_mut() {
            let u = *xi;
            let y = self.b[0] * u + z1;
            z1 = self.b[1] * u - self.a[0] * y + z2;
            z2 = self.b[2] * u - self.a[1] * y;
            *xi = y;
        }
    }
}

/// A record, linear between its samples, with its running integral.
struct Record<'a> {
    t: &'a [f64],
    a: &'a [f64],
    f: Vec<f64>,
}

impl<'a> Record<'a> {
    fn new(t: &'a [f64], a: &'a [f64]) -> Self {
        let mut f = vec![0.0; t.len()];
        for i in 1..t.len() {
            f[i] = f[i - 1] + 0.5 * (a[i - 1] + a[i]) * (t[i] - t[i - 1]);
        }
        Self { t, a, f }
    }

    /// Segment containing x (clamped to the record).
    fn seg(&self, x: f64) -> usize {
        let i = self.t.partition_point(|&ti| ti <= x);
        i.clamp(1, self.t.len() - 1) - 1
    }

    fn value(&self, x: f64) -> f64 {
        let j = self.seg(x);
        let (t0, t1) = (self.t[j], self.t[j + 1]);
        let w = ((x - t0) / (t1 - t0)).clamp(0.0, 1.0);
        self.a[j] + w * (self.a[j + 1] - self.a[j])
    }

    /// ∫ from the first sample to x.
    fn integral(&self, x: f64) -> f64 {
        let j = self.seg(x);
        let x = x.clamp(self.t[0], *self.t.last().unwrap_or(&x));
        self.f[j] + 0.5 * (x - self.t[j]) * (self.a[j] + self.value(x))
    }
}

/// Mean over the record by the trapezoidal rule (exact for whole periods of a sine).
fn trapezoid_mean(x: &[f64]) -> f64 {
    match x {
        [] => 0.0,
        [a] => *a,
        [first, .., last] => (x.iter().sum::<f64>() - 0.5 * (first + last)) / (x.len() - 1) as f64,
    }
}

/// The excitation of a scene, on its step grid, for `steps` steps.
pub fn of_scene(scene: &crate::scene::Scene, steps: usize) -> Result<Excitation> {
    use crate::scene::ExcitationType;
    let f = &scene.file;
    let h = f.integrator.step;
    match f.excitation.kind {
        ExcitationType::Harmonic if f.excitation.highpass.is_some() => {
            bail!("`excitation.highpass` is only for type = \"csv\" (a measured record)")
        }
        ExcitationType::Harmonic => Ok(Excitation::harmonic(
            f.excitation.amplitude_or_paper(),
            f.excitation.frequency_or_paper(),
            h,
        )),
        ExcitationType::Csv => {
            let file = f
                .excitation
                .file
                .as_ref()
                .context("missing `excitation.file`")?;
            let path = if file.is_absolute() {
                file.clone()
            } else {
                scene.base_dir.join(file)
            };
            Excitation::from_csv_with(&path, h, Some(steps), f.excitation.highpass)
        }
    }
}
