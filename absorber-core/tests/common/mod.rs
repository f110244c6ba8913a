//! Shared helpers of the core's tests: signal analysis by independent, elementary means.
#![allow(dead_code)]

/// Times of upward zero crossings of `x(t) − mean`, by linear interpolation.
pub fn upward_crossings(t: &[f64], x: &[f64], mean: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for i in 1..x.len() {
        let (a, b) = (x[i - 1] - mean, x[i] - mean);
        if a < 0.0 && b >= 0.0 {
            out.push(t[i - 1] + (t[i] - t[i - 1]) * a / (a - b));
        }
    }
    out
}

/// Mean period from the first to the last upward crossing.
pub fn mean_period(crossings: &[f64]) -> f64 {
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// Local maxima of `x − mean` (peak values) with their times, parabolic refinement.
pub fn peaks(t: &[f64], x: &[f64], mean: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for i in 1..x.len() - 1 {
        if x[i] > x[i - 1] && x[i] >= x[i + 1] && x[i] > mean {
            let (a, b, c) = (x[i - 1], x[i], x[i + 1]);
            let d = a - 2.0 * b + c;
            let off = if d != 0.0 { 0.5 * (a - c) / d } else { 0.0 };
            let h = t[i] - t[i - 1];
            out.push((t[i] + off * h, b - 0.25 * (a - c) * off - mean));
        }
    }
    out
}

/// Natural frequencies of a uniform cantilever (Euler–Bernoulli): f_i = (β_i L)² / (2π L²) √(EI/μ).
pub fn cantilever_frequency(beta_l: f64, length: f64, ei: f64, mu: f64) -> f64 {
    beta_l * beta_l / (2.0 * std::f64::consts::PI * length * length) * (ei / mu).sqrt()
}

/// Roots β_i L of 1 + cos x cosh x = 0 (first two), from the literature: 1.875104069, 4.694091133.
pub const CANTILEVER_BETA_L: [f64; 2] = [1.875_104_068_711_961, 4.694_091_132_974_175];

/// Newmark's exact per-step amplitude ratio ρ and phase Ω̄ for an undamped oscillator with
/// Ω = ω h (Hughes, *The Finite Element Method*, §9.1): the characteristic equation is
/// (1 + βΩ²) λ² − (2 − (γ + ½ − 2β) Ω²) λ + (1 + (β − γ + ½) Ω²) = 0.
pub fn newmark_amplification(omega_h: f64, gamma: f64, beta: f64) -> (f64, f64) {
    let o2 = omega_h * omega_h;
    let den = 1.0 + beta * o2;
    let a2 = (1.0 + (beta - gamma + 0.5) * o2) / den;
    let a1 = (2.0 - (gamma + 0.5 - 2.0 * beta) * o2) / den / 2.0;
    let rho = a2.sqrt();
    (rho, (a1 / rho).acos())
}
