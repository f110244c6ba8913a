//! Signal processing for identification: spectra, band-pass, envelope, damped-sinusoid fits,
//! random decrement.

use super::ZETA_BOUNDS;
use crate::lm;
use anyhow::{bail, Result};
use rustfft::{num_complex::Complex, FftPlanner};
use std::f64::consts::TAU;

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
pub(super) fn decay_window(y: &[f64], dt: f64, fp: f64) -> Result<(usize, usize, f64)> {
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
