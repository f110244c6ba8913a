//! Amplitude spectra (rustfft) for the FFT figures.

use rustfft::{num_complex::Complex, FftPlanner};

/// A single-sided amplitude spectrum.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Frequencies \[Hz\], k / (n dt), k = 0 … n/2.
    pub frequency: Vec<f64>,
    /// Amplitude of each bin, scaled so that a sine of amplitude A on a bin reads A.
    pub amplitude: Vec<f64>,
}

/// Spectrum of `x` sampled every `dt` seconds: mean removed, Hann window, single sided,
/// amplitude scaled by the window's coherent gain (a sine of amplitude A reads ≈ A).
pub fn spectrum(x: &[f64], dt: f64) -> Spectrum {
    let n = x.len();
    if n < 2 || dt <= 0.0 {
        return Spectrum {
            frequency: Vec::new(),
            amplitude: Vec::new(),
        };
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let window = |i: usize| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos();
    let gain: f64 = (0..n).map(window).sum::<f64>();
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            Complex::new(
                if v.is_finite() {
                    (v - mean) * window(i)
                } else {
                    0.0
                },
                0.0,
            )
        })
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let half = n / 2;
    let frequency = (0..=half).map(|k| k as f64 / (n as f64 * dt)).collect();
    let amplitude = (0..=half)
        .map(|k| {
            let s = if k == 0 || (n.is_multiple_of(2) && k == half) {
                1.0
            } else {
                2.0
            };
            s * buf[k].norm() / gain
        })
        .collect();
    Spectrum {
        frequency,
        amplitude,
    }
}

impl Spectrum {
    /// Frequency of the largest peak (above `min_hz`), refined by a parabola through the log
    /// amplitudes of the three bins around it (exact for a Gaussian, close for Hann) \[Hz\].
    pub fn peak(&self, min_hz: f64) -> Option<(f64, f64)> {
        let (k, &a) = self
            .amplitude
            .iter()
            .enumerate()
            .filter(|(k, _)| self.frequency[*k] >= min_hz)
            .max_by(|x, y| x.1.total_cmp(y.1))?;
        let df = self.frequency.get(1).copied().unwrap_or(0.0);
        if k == 0 || k + 1 >= self.amplitude.len() || a <= 0.0 {
            return Some((self.frequency[k], a));
        }
        let (l, c, r) = (
            self.amplitude[k - 1].max(1e-300).ln(),
            a.ln(),
            self.amplitude[k + 1].max(1e-300).ln(),
        );
        let den = l - 2.0 * c + r;
        let d = if den.abs() > 0.0 {
            0.5 * (l - r) / den
        } else {
            0.0
        };
        Some((self.frequency[k] + d.clamp(-0.5, 0.5) * df, a))
    }
}
