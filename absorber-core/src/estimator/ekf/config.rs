//! The filter's configuration and the load's process model (a Gauss–Markov load of order 1
//! or 2, discretized over a step).

use crate::estimator::health::HealthConfig;
use crate::estimator::sensors::SensorSet;
use crate::monitor::stress::RootSection;
use crate::scalar::{is_positive, Real};

/// The filter's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EkfConfig<T, const M: usize> {
    /// The sensors.
    pub sensors: SensorSet<T>,
    /// Standard deviation of the tip load (its stationary prior) \[N\].
    pub load_sd: T,
    /// Corner frequency ω_c of the tip load's model \[rad/s\] (module doc, "Load model").
    pub load_corner: T,
    /// Order of the load's model: 1 (Gauss–Markov, `τ = 1/ω_c`) or 2 (critically damped).
    pub load_order: u8,
    /// Time constant of the load's running mean \[s\] (0: none), and the standard deviation
    /// of the dummy measurement that it is zero \[N\]: a steady load is what accelerations
    /// cannot see, and a filter left to estimate it learns it from couplings of the swinging
    /// arm's own nonlinearity and drifts; with it the load's mean over the time constant stays
    /// within its own sampling scatter (the dummy measurement of Naets, Cuadrado & Desmet
    /// 2015, here on the load).
    pub load_mean_time: T,
    /// See [`EkfConfig::load_mean_time`] \[N\].
    pub load_mean_sd: T,
    /// Root section (stress = −M c / I).
    pub section: RootSection<T>,
    /// Modal stress recovery: the root stress of mode `i` is multiplied by `stress_factors[i]`
    /// (the reference model's root stress per tip acceleration in that mode over the reduced
    /// model's; 1: none; `docs/monitoring.md`, "The first-mode damage bias").
    pub stress_factors: [T; M],
    /// Standard deviation of each mode's acceleration at the start, `ω² η` and `ω η̇` (the
    /// monitor starts at rest without knowing the motion) \[√kg·m/s²\] (modal units: mass-
    /// normalized modes).
    pub initial_accel: T,
    /// Standard deviation of a white modal acceleration noise per step (the reduced model's
    /// error in its dynamics; 0: none) \[√kg·m/s²\].
    pub modal_noise: T,
    /// Relative uncertainty of a stop impact's rebound speed (restitution and timing) \[–\].
    pub impact_sd: T,
    /// Standard deviation of the ball's relative angle \[rad\] and rate \[rad/s\] after a landing
    /// or a release from a stop.
    pub ball_restart_sd: [T; 2],
    /// Time constant of the running RMS of the predicted measurements that scales the model
    /// error ([`crate::estimator::Sensor::model_error`]) \[s\].
    pub rms_time: T,
    /// The verdict's thresholds.
    pub health: HealthConfig<T>,
    /// Huber's bound: innovations beyond `gate` predicted sd correct as if they were
    /// `gate` sd (0: none).
    pub gate: T,
    /// The reduced model's error around the ball's events, as `model_error` of every sensor
    /// ([`crate::estimator::Sensor::model_error`]): added while the model's ball is held on a
    /// stop or flies, and for `event_window` samples after an impact, a separation, a
    /// landing or a release (the full solver and the reduced model put them at other
    /// instants; `docs/monitoring.md`, "Noise model").
    pub event_error: T,
    /// Samples after a ball event during which `event_error` applies.
    pub event_window: u32,
    /// Time constant of the model error measured online \[s\] (0: none): the innovations'
    /// variance beyond the filter's own prediction, `E[ν²] − (h P hᵀ + r)`, averaged
    /// (exponentially, bias-corrected) apart away from and near the ball's events, becomes the
    /// model error's variance where it exceeds `model_error` and `event_error` (covariance
    /// matching, Mehra 1972; `docs/monitoring.md`, "Noise model"). Innovations beyond the
    /// gate enter it at the gate.
    pub adapt_time: T,
}

/// The load model over a step `h`: the transition `A = exp(F h)` and the process noise as two
/// columns `L` (`Q = L Lᵀ`, `Q = P∞ − A P∞ Aᵀ` for the stationary covariance `P∞`: the
/// discrete process is the continuous one sampled, exactly). Order 1: the Gauss–Markov
/// process `Ṗ = −ω P + w` (`τ = 1/ω`; the rate slot unused). Order 2: the critically damped
/// `P̈ = −ω² P − 2ω Ṗ + w`, `P∞ = diag(σ², ω² σ²)`.
pub fn load_model<T: Real>(sd: T, corner: T, h: T, order: u8) -> ([[T; 2]; 2], [[T; 2]; 2]) {
    let w = corner;
    if order < 2 {
        let phi = (-w * h).exp();
        let q = sd * (T::one() - phi * phi).max(T::zero()).sqrt();
        return (
            [[phi, T::zero()], [T::zero(), T::zero()]],
            [[q, T::zero()], [T::zero(), T::zero()]],
        );
    }
    let e = (-w * h).exp();
    let a = [
        [e * (T::one() + w * h), e * h],
        [-e * w * w * h, e * (T::one() - w * h)],
    ];
    let (p11, p22) = (sd * sd, w * w * sd * sd);
    let q11 = p11 - (a[0][0] * a[0][0] * p11 + a[0][1] * a[0][1] * p22);
    let q12 = -(a[0][0] * a[1][0] * p11 + a[0][1] * a[1][1] * p22);
    let q22 = p22 - (a[1][0] * a[1][0] * p11 + a[1][1] * a[1][1] * p22);
    let l11 = q11.max(T::zero()).sqrt();
    let l21 = if is_positive(l11) {
        q12 / l11
    } else {
        T::zero()
    };
    let l22 = (q22 - l21 * l21).max(T::zero()).sqrt();
    (a, [[l11, T::zero()], [l21, l22]])
}
