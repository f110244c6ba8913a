//! What the time integrator does to one linear mode: its numerical damping ratio and spectral
//! radius (the integrator's own dissipation, to be set beside the structure's).
//!
//! For the undamped mode `q̈ + ω²q = 0`, one step of Newmark's method or of the generalized-α
//! scheme (`absorber-core/src/step/newmark`) maps `(q, q̇, a)` linearly to the next: the amplification
//! matrix `A(Ω)`, `Ω = ωh`. Its complex pair `λ = exp(Ω̄(−ζ̄ ± i√(1 − ζ̄²)))` gives the
//! numerical damping ratio `ζ̄ = −Re ln λ / |ln λ|` (Hilber, Hughes & Taylor 1977; Chung &
//! Hulbert 1993, eqs. 27–29), and its largest modulus is the spectral radius. Closed forms to
//! check against: Newmark `ζ̄ → (γ − ½)Ω/2` for `Ω → 0`; the trapezoidal rule `ζ̄ = 0`;
//! generalized-α spectral radius `→ ρ∞` for `Ω → ∞`.

use absorber_core::shared::AlphaRecursion;
use absorber_core::Integrator;
use nalgebra::Matrix3;

/// The amplification matrix of one step for `q̈ + ω²q = 0` with `Ω = ωh` (state `(q, hq̇,
/// h²a)`, `a` the scheme's acceleration variable).
fn amplification(i: &Integrator<f64>, omega_h: f64) -> Matrix3<f64> {
    let w2 = omega_h * omega_h;
    let (g, b) = (i.gamma, i.beta);
    // The core's recursion constants (Newmark: a = q̈).
    let r = AlphaRecursion::of(i).unwrap_or(AlphaRecursion {
        from_accel: 0.0,
        from_pseudo: 0.0,
        ratio: 1.0,
    });
    let mut m = Matrix3::zeros();
    for j in 0..3 {
        let mut e = [0.0; 3];
        e[j] = 1.0;
        let [x, v, pa] = e;
        // a' = (α_f q̈ − α_m a)/(1 − α_m) + κ q̈', q̈ = −Ω² x (h = 1), q̈' = −Ω² x'.
        let known = r.from_accel * (-w2 * x) + r.from_pseudo * pa;
        let x_pred = x + v + (0.5 - b) * pa + b * known;
        let x1 = x_pred / (1.0 + w2 * b * r.ratio);
        let pa1 = known + r.ratio * (-w2 * x1);
        let v1 = v + (1.0 - g) * pa + g * pa1;
        m[(0, j)] = x1;
        m[(1, j)] = v1;
        m[(2, j)] = pa1;
    }
    m
}

/// Numerical damping ratio ζ̄ of the integrator for a mode of `frequency_hz` at step `h`
/// \[-\]; `None` when the step does not resolve the mode (no complex pair: ωh beyond the
/// bifurcation of the scheme).
pub fn numerical_damping(i: &Integrator<f64>, frequency_hz: f64) -> Option<f64> {
    let omega_h = 2.0 * std::f64::consts::PI * frequency_hz * i.step;
    let ev = amplification(i, omega_h).complex_eigenvalues();
    let pair = ev
        .iter()
        .copied()
        .max_by(|a, b| a.im.abs().total_cmp(&b.im.abs()))?;
    if pair.im.abs() < 1e-300 {
        return None;
    }
    let l = pair.ln();
    Some(-l.re / l.norm())
}

/// Spectral radius of the integrator (largest |λ|) for a mode of `frequency_hz` at step `h`.
pub fn spectral_radius(i: &Integrator<f64>, frequency_hz: f64) -> f64 {
    let omega_h = 2.0 * std::f64::consts::PI * frequency_hz * i.step;
    amplification(i, omega_h)
        .complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use absorber_core::Params;

    fn newmark(gamma: f64, beta: f64) -> Integrator<f64> {
        Integrator {
            gamma,
            beta,
            ..Params::<f64>::default().integrator
        }
    }

    /// Newmark: ζ̄ → (γ − ½)Ω/2 for small Ω (Hughes, *The Finite Element Method*, §9.3), within
    /// 1 % at Ω = 0.01; the trapezoidal rule conserves: ζ̄ = 0 to rounding.
    #[test]
    fn newmark_damping_matches_the_small_step_limit() {
        let i = newmark(0.7, 0.36);
        let f = 0.01 / (2.0 * std::f64::consts::PI * i.step);
        let z = numerical_damping(&i, f).unwrap();
        let limit = 0.2 * 0.01 / 2.0;
        assert!((z / limit - 1.0).abs() < 0.01, "{z} vs {limit}");
        let t = newmark(0.5, 0.25);
        for f in [1.0, 4.13, 50.0] {
            assert!(numerical_damping(&t, f).unwrap().abs() < 1e-12);
        }
    }

    /// Generalized-α: the spectral radius tends to ρ∞ for unresolved modes (Chung & Hulbert 1993,
    /// eq. 25) and the resolved first mode is damped far less than by the paper's Newmark.
    #[test]
    fn generalized_alpha_spectral_radius_tends_to_rho_inf() {
        for rho in [0.0, 0.5, 0.8, 0.95] {
            let i = Params::<f64>::default().integrator.generalized_alpha(rho);
            let r = spectral_radius(&i, 1e7);
            assert!((r - rho).abs() < 1e-3, "rho_inf {rho}: {r}");
        }
        let i = Params::<f64>::default().integrator.generalized_alpha(0.8);
        let z = numerical_damping(&i, 4.13).unwrap();
        assert!(z > 0.0 && z < 1e-5, "{z}");
    }
}
