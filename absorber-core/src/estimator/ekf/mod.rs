//! The extended Kalman filter whose prediction is the model's own step and whose Jacobian is
//! that step's exact sensitivity, in the error subspace of the model's lowest modes.
//!
//! **Filter state.** The step from `n` to `n + 1` depends on the state only through the
//! Newmark predictor `p_n = (q*, v*, b)` (module doc of `newmark`: `q* = q + h v +
//! h²(½ − β) ā + βh² b`, `v* = v + h(1 − γ) ā + γh b`, `b = f_a q̈ + f_p ā`, zero for Newmark),
//! the tip load `P_{n+1}` of the step and the sensor biases. Its error lives in the span of
//! the `M` lowest modes `Φ` ([`super::basis`]): `δq* = Φ η_q`, `δv* = Φ η_v`, `δb = Φ η_b`
//! (generalized-α only), so the filter's covariance is `X × X` with `X = 2M + 6` (Newmark) or
//! `3M + 6` (generalized-α): the modal errors, the load, its rate and its running mean, and
//! three bias slots.
//!
//! **Sensitivity.** The step solves `r(q* + c_q x, v* + c_v x, x) = 0` for `x = q̈_{n+1}`;
//! differentiating, `J δx = −(R_q δq* + R_v δv* + R_P δP)` with `J = R_a + c_v R_v + c_q R_q`
//! the Newton matrix the step has already factored, `R_q = ∂r/∂q` and `R_v = ∂r/∂v` assembled
//! at the step's end by the same code as `J` (the tip rows in dual numbers: exact), and
//! `R_P = −e` (the tip force enters the end node's vertical row). One back-substitution per
//! direction: `2M + 1` per sample. With `x`, the new state is linear in the predictor:
//! `q' = q* + c_q x`, `v' = v* + c_v x`, `ā' = b + κ x`, and so is the next predictor.
//! Projected onto the modes (`Π = Φᵀ M`) this is the filter's transition matrix `F`.
//!
//! **Measurements** of sample `n + 1` depend on `p_n`: the tip acceleration through `x`, the
//! ball angle through `q'`, the root strain through `(q', v', x)`. The correction `δ` (in the
//! filter's coordinates at `n`) moves the model's state at `n + 1` by the same linear map, so
//! positions change by `Φ δη_q + c_q δx`: the stiff axial coordinates take `c_q δx ≈ −Φ δη_q`
//! along themselves, exactly as the implicit step would, and the correction never pumps them.
//!
//! **Events.** A stop impact reverses the ball's relative rate (`−e`): the covariance of that
//! direction is reflected and widened by the uncertainty of the restitution and of the impact
//! time; while the model's ball rests on a stop or flies, its relative angle is not in the
//! filter's subspace (held, or a flight state), so the ball-angle reading is not used and the
//! ball's correction is dropped; at a landing or a release the ball's covariance restarts from
//! [`EkfConfig::ball_restart_sd`] (`docs/monitoring.md`, "Events").
//!
//! **Load model.** The tip load is a stationary process ([`load_model`]): first-order
//! Gauss–Markov, `P_{k+1} = φ P_k + w`, `φ = exp(−h/τ)`, or critically damped second order:
//! its slow part, which accelerations cannot see, decays to zero instead of drifting (a random
//! walk, φ = 1, makes it an unobservable marginally stable state, and its estimate drifts;
//! Lourens et al. 2012, Naets et al. 2015). A dummy measurement holds the load's running mean
//! at zero ([`EkfConfig::load_mean_time`]).

mod build;
mod config;
mod correct;
mod predict;
#[cfg(test)]
mod tests;

use super::basis::ModalBasis;
use super::health::{Health, Verdict};
use super::sensors::{ReadingUse, Readings, SensorKind, KINDS};
use crate::error::Error;
use crate::loads::Loads;
use crate::model::Model;
use crate::monitor::stress::root_reaction_moment;
use crate::scalar::{is_positive, Real};
use crate::scene::Scene;
use crate::state::{Contact, StepReport};
use crate::step::linalg::BandMatrix;
pub use config::{load_model, EkfConfig};
use nalgebra::{SMatrix, SVector};

/// Slots after the modal errors: the load, its rate and its running mean, then one bias per
/// sensor kind.
pub const AUGMENTED: usize = 3 + KINDS;

/// What the filter says after a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate<T> {
    /// Recovered root stress at the top fibre, tension positive \[Pa\].
    pub root_stress: T,
    /// Its standard deviation \[Pa\].
    pub root_stress_sd: T,
    /// Tip deflection relative to the base \[m\].
    pub tip_deflection: T,
    /// Estimated tip load, positive up \[N\], and its standard deviation.
    pub load: T,
    /// Standard deviation of the load \[N\].
    pub load_sd: T,
    /// Ball angle relative to the housing \[rad\] (0 without a free ball).
    pub ball_angle: T,
    /// Per sensor: innovation (measured − predicted) and its predicted variance.
    pub innovation: [T; KINDS],
    /// Per sensor: the innovation's predicted variance.
    pub innovation_var: [T; KINDS],
    /// Per sensor: what became of its reading.
    pub used: [ReadingUse; KINDS],
    /// Per sensor: the model error in use, relative to the RMS of its predicted value.
    pub model_error: [T; KINDS],
    /// Sum of the NIS of the readings used, and how many.
    pub nis_sum: T,
    /// Scalar measurements used.
    pub nis_count: u32,
    /// The window's verdict.
    pub verdict: Verdict,
    /// The model step's report.
    pub report: StepReport<T>,
}

/// Constants of the predictor recursion (module doc): `δq*' = δq* + h δv* + qb δb + qx δx`,
/// `δv*' = δv* + vb δb + vx δx`, `δb' = bb δb + bx δx`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Recursion<T> {
    h: T,
    c_q: T,
    c_v: T,
    kappa: T,
    qb: T,
    qx: T,
    vb: T,
    vx: T,
    bb: T,
    bx: T,
    /// 3 for generalized-α (the predictor carries `b`), 2 for Newmark.
    blocks: usize,
}

/// The fixed data of a filter, checked ([`Ekf::new`]).
struct Parts<T: Real, const D: usize, const M: usize, const X: usize> {
    rec: Recursion<T>,
    basis: ModalBasis<T, D, M>,
    scale: SVector<T, X>,
    ud_d: SVector<T, X>,
    load_map: [[T; 2]; 2],
    load_noise: [[T; 2]; 2],
}

/// Noise columns of the time update (load, one per mode, one per bias, two for the ball's
/// events): at most `NOISE` (so `M ≤ 6`).
const NOISE: usize = 12;

/// The extended Kalman filter of a model of scene `S` (`N` elements, `D` unknowns) in the
/// error subspace of its `M` lowest modes, `X` = `2M + 6` (Newmark) or `3M + 6`
/// (generalized-α) filter coordinates. It does not own the model: [`Ekf::update`] steps the
/// model given to it (the one it was built for), so model and filter can live in separate
/// caller storage, like [`crate::monitor::Monitor`].
///
/// **Numerics.** The covariance is kept factored, `P = U D Uᵀ` (`U` unit upper triangular,
/// `D` diagonal): Bierman's scalar measurement update and Thornton's modified weighted
/// Gram–Schmidt time update (Bierman 1977, *Factorization Methods for Discrete Sequential
/// Estimation*), which keep `P` symmetric positive semi-definite in `f32` where the plain
/// and Joseph forms lose it (an accelerometer reading collapses a variance by 10⁷ and more).
/// The coordinates are scaled to accelerations: `ω² η_q`, `ω η_v`, `η_b` (modal), the load
/// in N, the biases in their units.
#[derive(Clone, Debug)]
pub struct Ekf<T: Real, S: Scene, const N: usize, const D: usize, const M: usize, const X: usize> {
    config: EkfConfig<T, M>,
    basis: ModalBasis<T, D, M>,
    rec: Recursion<T>,
    /// Physical coordinate = `scale` × filter coordinate.
    scale: SVector<T, X>,
    /// `P = U D Uᵀ` in the scaled coordinates.
    ud_u: SMatrix<T, X, X>,
    ud_d: SVector<T, X>,
    load: T,
    load_rate: T,
    /// The load's running mean (module doc of [`EkfConfig::load_mean_time`]) and its weight
    /// per step, `μ = h / T`.
    load_mean: T,
    mean_weight: T,
    /// The load model's transition over a step, `(P, Ṗ) ← A (P, Ṗ)`.
    load_map: [[T; 2]; 2],
    /// Its process noise as two columns `L` with `Q = L Lᵀ` (physical units).
    load_noise: [[T; 2]; 2],
    bias: [T; KINDS],
    /// Running mean square of each predicted dynamic measurement.
    rms2: [T; KINDS],
    /// Per sensor, away from and near events: the model error's variance measured online
    /// (exponential mean of the excess) and the mean's accumulated weight (its bias
    /// correction).
    adapt: [[(T, T); 2]; KINDS],
    adapt_weight: T,
    rms_weight: T,
    /// Modal stress recovery: `σ += w_q·(q − q_eq) + w_v·v + w_a·q̈`.
    recover: [SVector<T, D>; 3],
    static_stress: T,
    modulus: T,
    samples: u64,
    /// The model's contact after the previous sample (a release from a stop is an event).
    last_contact: Contact,
    /// Samples since the last ball event (saturating).
    since_event: u32,
    health: Health<T>,
    /// The modes completed consistently at the current state (`Π B = I`): the stiff
    /// (axial, high) coordinates that follow a modal displacement quasi-statically there.
    consistent: SMatrix<T, D, M>,
    /// The residual static mode of the load, completed likewise (`Π Ψ = 0`).
    residual: SVector<T, D>,
    /// The directions through the step of the last sample, `δx` as columns: `2M + 1` of
    /// them (`η_q`, `η_v`, load; the remaining columns unused), physical coordinates.
    dx: SMatrix<T, D, X>,
    /// Their modal projections `Π δx`.
    xi: SMatrix<T, M, X>,
    /// Scratch of the time update, by rows: `F U` (its columns of positive weight only) and
    /// the noise columns.
    w1: [[T; X]; X],
    w2: [[T; NOISE]; X],
    scratch: BandMatrix<T, D>,
    /// The beam's part of `R_v` (`c K₄ ⊗ I₂` per element: constant), built once by
    /// [`Ekf::finish`] (not in the filter's value expression: a second band there was built
    /// on the boot stack); each sample adds the tip rows to a copy.
    damping: Option<BandMatrix<T, D>>,
    _scene: core::marker::PhantomData<S>,
}

impl<T: Real, S: Scene, const N: usize, const D: usize, const M: usize, const X: usize>
    Ekf<T, S, N, D, M, X>
{
    const CHECK: () = {
        assert!(M >= 1 && M + 6 <= NOISE, "1 to 6 modes");
        assert!(
            X == 2 * M + AUGMENTED || X == 3 * M + AUGMENTED,
            "X must be 2M + 6 (Newmark) or 3M + 6 (generalized-α)"
        );
    };

    /// Row of the end node's vertical coordinate.
    const TIP: usize = 4 * N - 3;

    /// The load's slot (after the modal errors) and the first bias slot: compile-time
    /// constants of `X` (`X = blocks·M + AUGMENTED`, checked by `new`), so every index built on
    /// them is in range by construction.
    const LD: usize = X - AUGMENTED;

    const OFF: usize = X - KINDS;

    /// Row of the ball's spin (free ball only).
    const SPIN: usize = 4 * N;

    /// The filter for `model` (at its start state: the static equilibrium, at rest) with
    /// `config`. The scene must hold loads ([`crate::scene::Loaded`], [`crate::scene::Arm`]);
    /// `X` must match the model's integrator (`3M + 6` for generalized-α).
    pub fn new(model: &Model<T, S, N, D>, config: EkfConfig<T, M>) -> Result<Self, Error> {
        let parts = Self::parts(model, &config)?;
        let mut ekf = Self::fresh(model, config, parts);
        ekf.finish(model);
        Ok(ekf)
    }

    /// [`Ekf::new`] into caller storage (a `static`, or a field of a larger value built in
    /// place): only the small fixed data (the modal basis, the recursion's constants) is built
    /// on the stack, the filter is written in place. On error `slot` holds nothing usable.
    pub fn new_in<'a>(
        slot: &'a mut core::mem::MaybeUninit<Self>,
        model: &Model<T, S, N, D>,
        config: EkfConfig<T, M>,
    ) -> Result<&'a mut Self, Error> {
        let parts = Self::parts(model, &config)?;
        let ekf = slot.write(Self::fresh(model, config, parts));
        ekf.finish(model);
        Ok(ekf)
    }

    /// The modal basis.
    pub fn basis(&self) -> &ModalBasis<T, D, M> {
        &self.basis
    }

    /// The filter's covariance `U D Uᵀ` in its scaled coordinates (`ω² η_q`, `ω η_v`,
    /// `η_b`, load, biases).
    pub fn covariance(&self) -> SMatrix<T, X, X> {
        let mut ud = self.ud_u;
        for (j, d) in self.ud_d.iter().enumerate() {
            for i in 0..X {
                ud[(i, j)] *= *d;
            }
        }
        ud * self.ud_u.transpose()
    }

    /// The estimated tip load of the last step \[N\].
    pub fn load(&self) -> T {
        self.load
    }

    /// The estimated bias of each sensor kind (by [`SensorKind::index`]).
    pub fn biases(&self) -> [T; KINDS] {
        self.bias
    }

    /// The current verdict.
    pub fn verdict(&self) -> Verdict {
        self.health.verdict()
    }

    /// The health tracker (its mean NIS over the window).
    pub fn health(&self) -> &Health<T> {
        &self.health
    }

    /// The recovered root stress of the model's static equilibrium \[Pa\].
    pub fn static_stress(&self) -> T {
        self.static_stress
    }

    /// The recovered root stress of the model's current state \[Pa\].
    pub fn root_stress(&self, model: &Model<T, S, N, D>) -> T {
        let s = model.state();
        let raw = self
            .config
            .section
            .stress_of_moment(root_reaction_moment(model));
        let dq = s.q - model.equilibrium();
        raw + self.recover[0].dot(&dq) + self.recover[1].dot(&s.v) + self.recover[2].dot(&s.a)
    }

    /// The installation's zero calibration: with the arm at rest in the model's start state,
    /// `readings` (e.g. the mean over the first second) set the biases of the sensors that
    /// have a bias state (`bias_sd > 0`) to measured minus predicted.
    pub fn calibrate_zero(
        &mut self,
        model: &Model<T, S, N, D>,
        readings: &Readings<T>,
    ) -> Result<(), Error> {
        for kind in SensorKind::ALL {
            let (Some(s), Some(y)) = (self.config.sensors.get(kind), readings.get(kind)) else {
                continue;
            };
            if !y.is_finite() {
                return Err(Error::NonFiniteInput);
            }
            if is_positive(s.bias_sd) {
                let predicted = self.predicted(model, kind);
                if let Some(b) = self.bias.get_mut(kind.index()) {
                    *b = y - predicted;
                }
            }
        }
        Ok(())
    }

    /// One sample: the model steps to the base acceleration `base_accel` \[m/s²\] under the
    /// predicted tip load, then the readings that arrived correct it. On error (non-finite
    /// base acceleration, failed step, a correction that leaves the physical range) the model
    /// and the filter keep their state, and the sample counts as failed in the verdict and
    /// toward the model's restart rule ([`Model::step`], "Recovery"): the
    /// [`crate::RESTART_AFTER`]-th failed sample in a row restarts the model at rest and the
    /// load estimate at zero, so that a state the filter cannot correct is not kept for ever.
    pub fn update(
        &mut self,
        model: &mut Model<T, S, N, D>,
        base_accel: T,
        readings: &Readings<T>,
    ) -> Result<Estimate<T>, Error> {
        let before = (*model.state(), model.recovery());
        let loads = Loads {
            tip_force: self.load_map[0][0] * self.load + self.load_map[0][1] * self.load_rate,
            line_load: [T::zero(); N],
        };
        // A failed step keeps the model's state and counts itself; a refused correction takes
        // the step back and counts.
        let result = model
            .step_with_loads(base_accel, &loads)
            .and_then(|report| {
                self.correct(model, readings, report).inspect_err(|_| {
                    if model.refuse_step(before, base_accel) {
                        self.load = T::zero();
                        self.load_rate = T::zero();
                    }
                })
            });
        if result.is_err() {
            self.health
                .record([false; KINDS], [false; KINDS], T::zero(), 0, true);
        }
        result
    }
}
