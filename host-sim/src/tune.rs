//! Tuning the track radius R so that the ball's frequency is a given fraction (½) of the beam's
//! first frequency, both taken from the coupled linearized free-ball model
//! (`natural_frequencies()`), by bisection on R.

use crate::scene::{Kind, Precision, Scene};
use anyhow::{anyhow, bail, Result};
use serde::Serialize;

/// Result of the tuning.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tuned {
    /// Track radius R \[m\].
    pub track_radius: f64,
    /// Ball path radius ρ = R − r_b \[m\].
    pub path_radius: f64,
    /// Ball mode of the coupled model \[Hz\].
    pub ball_frequency: f64,
    /// Beam mode of the coupled model \[Hz\].
    pub beam_frequency: f64,
    /// ball / beam.
    pub ratio: f64,
    /// The ball on a fixed housing with this R \[Hz\] (for comparison).
    pub fixed_housing_frequency: f64,
    /// First frequency with the ball locked (the paper's 4.13 Hz) \[Hz\].
    pub locked_frequency: f64,
    /// Bisection steps.
    pub iterations: u32,
}

/// (ball, beam) frequencies of the coupled free-ball model with track radius `r`.
pub fn coupled_frequencies(scene: &Scene, r: f64) -> Result<(f64, f64)> {
    let mut p = scene.params()?;
    p.ball.track_radius = r;
    let sim = crate::core_sim::build(
        Kind::FreeNostops,
        scene.file.elements,
        Precision::F64,
        &p,
        0.0,
    )
    .map_err(|e| crate::scene::map_core_error(e, scene))?;
    let f = sim.natural_frequencies().map_err(|e| anyhow!("{e}"))?;
    match f.as_slice() {
        [a, b, ..] => Ok((*a, *b)),
        _ => bail!("model has fewer than two modes"),
    }
}

/// Finds R with ball frequency = `ratio` × beam frequency (relative tolerance 1e-9 on R).
pub fn tune(scene: &Scene, ratio: f64) -> Result<Tuned> {
    if !(ratio > 0.05 && ratio < 0.9) {
        bail!("invalid ratio {ratio} (must lie in (0.05, 0.9))");
    }
    let p = scene.params()?;
    if p.gravity <= 0.0 {
        bail!("tuning needs gravity > 0 (the ball's restoring force)");
    }
    let b = p.ball;
    let locked = crate::core_sim::build(Kind::Locked, scene.file.elements, Precision::F64, &p, 0.0)
        .map_err(|e| crate::scene::map_core_error(e, scene))?;
    let f_beam = *locked
        .natural_frequencies()
        .map_err(|e| anyhow!("{e}"))?
        .first()
        .unwrap_or(&f64::NAN);
    // Fixed-housing ball: f = √(g m / ((m + J/r²) ρ)) / 2π → ρ(f).
    let m_eff = b.mass + b.inertia / (b.radius * b.radius);
    let rho_of = |f: f64| p.gravity * b.mass / (m_eff * (std::f64::consts::TAU * f).powi(2));
    // The ball mode is the lowest and the beam mode the second between these limits.
    let (mut lo, mut hi) = (
        b.radius + rho_of(0.8 * f_beam),
        b.radius + rho_of(0.2 * f_beam),
    );
    let g = |r: f64| -> Result<f64> {
        let (ball, beam) = coupled_frequencies(scene, r)?;
        Ok(ball / beam - ratio)
    };
    let (glo, ghi) = (g(lo)?, g(hi)?);
    if glo.signum() == ghi.signum() {
        bail!("cannot bracket the tuned radius between {lo:.5} m and {hi:.5} m");
    }
    let mut iterations = 0;
    while (hi - lo) > 1e-10 * hi && iterations < 100 {
        let mid = 0.5 * (lo + hi);
        if g(mid)?.signum() == glo.signum() {
            lo = mid;
        } else {
            hi = mid;
        }
        iterations += 1;
    }
    let r = 0.5 * (lo + hi);
    let (ball, beam) = coupled_frequencies(scene, r)?;
    let mut bb = b;
    bb.track_radius = r;
    Ok(Tuned {
        track_radius: r,
        path_radius: r - b.radius,
        ball_frequency: ball,
        beam_frequency: beam,
        ratio: ball / beam,
        fixed_housing_frequency: bb.fixed_housing_frequency(p.gravity),
        locked_frequency: f_beam,
        iterations,
    })
}
