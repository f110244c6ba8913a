//! The extended Kalman filter whose prediction is the model's own step and whose Jacobian is
//! that step's exact sensitivity, in the error subspace of the model's lowest modes.
//!
//! **Filter state.** The step from `n` to `n + 1` depends on the state only through the
//! Newmark predictor `p_n = (q*, v*, b)` (module doc of [`crate::step::newmark`]: `q* = q + h v +
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

use super::basis::ModalBasis;
use super::health::{Health, HealthConfig, Verdict};
use super::sensors::{ReadingUse, Readings, SensorKind, SensorSet, KINDS};
use super::ud::{bierman_f, column, quadratic, quadratic_f, row_of, set_column, thornton};
use crate::error::Error;
use crate::loads::{Loads, MAX_LOAD};
use crate::model::Model;
use crate::monitor::stress::{root_reaction_moment, static_root_moment, RootSection};
use crate::scalar::{is_positive, lit, Real};
use crate::scene::{BallKind, Scene};
use crate::state::{Contact, StepReport};
use crate::step::ancf::TangentBlocks;
use crate::step::linalg::BandMatrix;
use crate::step::scheme::Chain;
use crate::step::system::Problem;
use crate::step::tip;
use nalgebra::{SMatrix, SVector};

/// Slots after the modal errors: the load, its rate and its running mean, then one bias per
/// sensor kind.
pub const AUGMENTED: usize = 3 + KINDS;

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
    /// error ([`super::sensors::Sensor::model_error`]) \[s\].
    pub rms_time: T,
    /// The verdict's thresholds.
    pub health: HealthConfig<T>,
    /// Huber's bound: innovations beyond `gate` predicted sd correct as if they were
    /// `gate` sd (0: none).
    pub gate: T,
    /// The reduced model's error around the ball's events, as `model_error` of every sensor
    /// ([`super::sensors::Sensor::model_error`]): added while the model's ball is held on a
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

    /// The recovery vectors, the static stress and `R_v`'s constant part, from the built
    /// filter. Out of line (measured: 96 B less boot stack than inlined into the construction).
    #[inline(never)]
    fn finish(&mut self, model: &Model<T, S, N, D>) {
        self.recover = self.recovery(model);
        let velocity = Chain {
            c_q: T::zero(),
            c_v: T::one(),
            c_m: T::zero(),
        };
        let damping = self.damping.insert(BandMatrix::zeros());
        model
            .sys
            .beam_jacobian(model.equilibrium(), &velocity, damping);
        // The recovery's terms vanish at the equilibrium.
        self.static_stress = self
            .config
            .section
            .stress_of_moment(static_root_moment(model));
    }

    /// What [`Ekf::new`] checks, and the filter's fixed data: the recursion's constants, the
    /// modal basis, the scaling, the initial variances and the load model.
    #[allow(clippy::type_complexity)]
    fn parts(
        model: &Model<T, S, N, D>,
        config: &EkfConfig<T, M>,
    ) -> Result<Parts<T, D, M, X>, Error> {
        #[allow(clippy::let_unit_value)]
        let () = Self::CHECK;
        config.sensors.check()?;
        if model.loads().is_none() {
            return Err(Error::InvalidParameter {
                field: "loads",
                reason: "the estimator's model must hold loads (scene Loaded or Arm)",
            });
        }
        let positive = |x: T| is_positive(x) && x.is_finite();
        if !positive(config.load_sd) || !positive(config.load_corner) {
            return Err(Error::InvalidParameter {
                field: "estimator.load",
                reason:
                    "the load's standard deviation and corner frequency must be finite and positive",
            });
        }
        let finite_nonneg = |x: &T| x.is_finite() && *x >= T::zero();
        if !config.stress_factors.iter().all(|f| positive(*f))
            || !finite_nonneg(&config.initial_accel)
            || !finite_nonneg(&config.modal_noise)
            || !finite_nonneg(&config.impact_sd)
            || !config.ball_restart_sd.iter().all(finite_nonneg)
            || !positive(config.rms_time)
            || !finite_nonneg(&config.gate)
            || !finite_nonneg(&config.event_error)
            || !finite_nonneg(&config.adapt_time)
            || !finite_nonneg(&config.load_mean_time)
            || !finite_nonneg(&config.load_mean_sd)
        {
            return Err(Error::InvalidParameter {
                field: "estimator",
                reason: "stress factors and the RMS time must be positive, the standard deviations finite and not negative",
            });
        }
        if config.sensors.get(SensorKind::BallAngle).is_some() && !matches!(S::BALL, BallKind::Free)
        {
            return Err(Error::InvalidParameter {
                field: "sensors.ball_angle",
                reason: "needs a model with the free ball",
            });
        }
        let p = model.params();
        let i = &p.integrator;
        let h = i.step;
        let ch = model.sys.newmark_chain(h);
        let (fa, fp, kappa, blocks) = match model.sys.alpha() {
            Some(g) => (g.from_accel, g.from_pseudo, g.ratio, 3),
            None => (T::zero(), T::zero(), T::one(), 2),
        };
        if X != blocks * M + AUGMENTED {
            return Err(Error::InvalidParameter {
                field: "estimator.X",
                reason: "X must be 2M + 6 for Newmark, 3M + 6 for generalized-α",
            });
        }
        let half = lit::<T>(0.5);
        let h2 = h * h;
        let rec = Recursion {
            h,
            c_q: ch.c_q,
            c_v: ch.c_v,
            kappa,
            qb: h2 * (half - i.beta) + i.beta * h2 * fp,
            qx: ch.c_q
                + h * ch.c_v
                + h2 * (half - i.beta) * kappa
                + i.beta * h2 * (fa + fp * kappa),
            vb: h * (T::one() - i.gamma) + i.gamma * h * fp,
            vx: ch.c_v + h * (T::one() - i.gamma) * kappa + i.gamma * h * (fa + fp * kappa),
            bb: fp,
            bx: fa + fp * kappa,
            blocks,
        };
        let basis = ModalBasis::of(model)?;
        let (ld, off) = (blocks * M, blocks * M + 3);
        let mut scale = SVector::<T, X>::from_element(T::one());
        for (k, w) in basis.omega.iter().enumerate() {
            scale[k] = T::one() / (*w * *w);
            scale[M + k] = T::one() / *w;
        }
        let wc = config.load_corner;
        scale[ld + 1] = wc;
        let (load_map, load_noise) = load_model(config.load_sd, wc, h, config.load_order);
        let mut ud_d = SVector::<T, X>::zeros();
        let a0 = config.initial_accel;
        for k in 0..2 * M {
            ud_d[k] = a0 * a0;
        }
        // The load's stationary variance (scaled: P and Ṗ/ω_c both have σ): the prior of a
        // monitor that starts at any time.
        ud_d[ld] = config.load_sd * config.load_sd;
        if config.load_order >= 2 {
            ud_d[ld + 1] = config.load_sd * config.load_sd;
        }
        ud_d[ld + 2] = config.load_mean_sd * config.load_mean_sd;
        for (k, s) in config.sensors.slots.iter().enumerate() {
            if let Some(s) = s {
                ud_d[off + k] = s.bias_sd * s.bias_sd;
            }
        }
        Ok(Parts {
            rec,
            basis,
            scale,
            ud_d,
            load_map,
            load_noise,
        })
    }

    /// The filter at the model's start from its checked fixed data ([`Ekf::parts`]): a plain
    /// value expression, inlined so that it is written straight into its destination.
    #[inline(always)]
    fn fresh(model: &Model<T, S, N, D>, config: EkfConfig<T, M>, parts: Parts<T, D, M, X>) -> Self {
        let Parts {
            rec,
            basis,
            scale,
            ud_d,
            load_map,
            load_noise,
        } = parts;
        let h = rec.h;
        Self {
            config,
            consistent: basis.shapes,
            residual: basis.residual,
            basis,
            rec,
            scale,
            ud_u: SMatrix::identity(),
            ud_d,
            load: T::zero(),
            load_rate: T::zero(),
            load_mean: T::zero(),
            mean_weight: if is_positive(config.load_mean_time) {
                (h / config.load_mean_time).min(T::one())
            } else {
                T::zero()
            },
            load_map,
            load_noise,
            bias: [T::zero(); KINDS],
            rms2: [T::zero(); KINDS],
            rms_weight: (h / config.rms_time).min(T::one()),
            adapt: [[(T::zero(), T::zero()); 2]; KINDS],
            adapt_weight: if is_positive(config.adapt_time) {
                (h / config.adapt_time).min(T::one())
            } else {
                T::zero()
            },
            recover: [SVector::zeros(); 3],
            static_stress: T::zero(),
            modulus: model.params().beam.modulus,
            samples: 0,
            last_contact: Contact::Off,
            since_event: u32::MAX,
            health: Health::new(config.health),
            dx: SMatrix::zeros(),
            xi: SMatrix::zeros(),
            w1: [[T::zero(); X]; X],
            w2: [[T::zero(); NOISE]; X],
            scratch: BandMatrix::zeros(),
            damping: None,
            _scene: core::marker::PhantomData,
        }
    }

    /// The modal stress recovery vectors (module doc of [`EkfConfig::stress_factors`]):
    /// `w = Σ_i (f_i − 1) (g·φ_i) Π_i` for the stress gradients `g` at the static state.
    fn recovery(&self, model: &Model<T, S, N, D>) -> [SVector<T, D>; 3] {
        let g = self.stress_gradients(model, model.equilibrium(), model.params().gravity);
        let mut w = [SVector::<T, D>::zeros(); 3];
        for (i, f) in self.config.stress_factors.iter().enumerate() {
            let phi = self.basis.shape(i);
            let pi: SVector<T, D> = self.basis.projection.row(i).transpose();
            for (wk, gk) in w.iter_mut().zip(g.iter()) {
                *wk += pi * ((*f - T::one()) * gk.dot(&phi));
            }
        }
        w
    }

    /// Gradients of the model's root stress (clamp reaction, [`crate::monitor::stress`]) with
    /// respect to q, v and q̈ at the configuration `q` (element 0's axial tangent there)
    /// \[Pa per unit\].
    fn stress_gradients(
        &self,
        model: &Model<T, S, N, D>,
        q: &SVector<T, D>,
        g_eff: T,
    ) -> [SVector<T, D>; 3] {
        let (b, _) = model.sys.element_and_force(0, g_eff);
        let u = crate::step::beam::gather(q, 0);
        let mut block = [[T::zero(); 8]; 8];
        let zero4 = [[T::zero(); 4]; 4];
        let (_, tangent) = b
            .quadrature
            .tangent_block_with(&u, &zero4, T::one(), &mut block);
        self.stress_gradients_of(model, g_eff, &tangent)
    }

    /// [`Ekf::stress_gradients`] from element 0's axial tangent blocks at that configuration
    /// (the `∂r/∂q` assembly's, [`crate::step::system::System::jacobian`]).
    fn stress_gradients_of(
        &self,
        model: &Model<T, S, N, D>,
        g_eff: T,
        tangent: &TangentBlocks<T>,
    ) -> [SVector<T, D>; 3] {
        const ROW: usize = 3;
        let (b, _) = model.sys.element_and_force(0, g_eff);
        // Row 3 of K_l (the root node's vertical row), columns 4..8, as
        // `AxialQuadrature::tangent_block` writes it with a zero linear part and unit scale:
        // `0 + 1 · xy`, `0 + 1 · yy` of blocks (1, 2) and (1, 3).
        let (zero, one) = (T::zero(), T::one());
        let kl = |j: usize| -> T {
            match tangent.get(1).and_then(|r| r.get(j / 2)) {
                Some([_, xy, yy]) => zero + one * if j.is_multiple_of(2) { *xy } else { *yy },
                None => zero,
            }
        };
        // σ = −M c/I with M = −R₃: dσ = (c/I) dR₃.
        let f = self.config.section.stress_of_moment(-T::one());
        let mut g = [SVector::<T, D>::zeros(); 3];
        for j in 4..8 {
            let (m, k) = (b.mass[(ROW, j)], b.stiffness[(ROW, j)]);
            let [gq, gv, ga] = &mut g;
            if let (Some(gq), Some(gv), Some(ga)) =
                (gq.get_mut(j - 4), gv.get_mut(j - 4), ga.get_mut(j - 4))
            {
                *gq = f * (k + kl(j));
                *gv = f * k * b.damping;
                *ga = f * m;
            }
        }
        g
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

    /// The model's prediction of a sensor's reading (without its bias) in its current state.
    fn predicted(&self, model: &Model<T, S, N, D>, kind: SensorKind) -> T {
        let s = model.state();
        match kind {
            SensorKind::TipAccel => s.a.get(Self::TIP).copied().unwrap_or(T::zero()) + s.base_accel,
            SensorKind::BallAngle => model.ball_relative_angle().map_or(T::zero(), |(a, _)| a),
            SensorKind::RootStrain => self.root_stress(model) / self.modulus,
        }
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

    /// The linearization, the correction and the covariance's propagation of a sample whose
    /// model step succeeded. On error nothing of the filter has changed (the caller restores
    /// the model).
    fn correct(
        &mut self,
        model: &mut Model<T, S, N, D>,
        readings: &Readings<T>,
        report: StepReport<T>,
    ) -> Result<Estimate<T>, Error> {
        let (ld, off) = (Self::LD, Self::OFF);
        let root_tangent = self.directions(model)?;
        let contact = model.state().contact;
        // The ball's relative angle is in the filter's subspace only while it rolls off the
        // stops (held on a stop it is fixed; flying, it is the flight state's).
        let ball_free = matches!(S::BALL, BallKind::Free) && contact == Contact::Off;
        // A landing, a separation, or a release from a stop (which the report does not name).
        let released = matches!(self.last_contact, Contact::OnStop(_)) && contact == Contact::Off;
        let ball_event = report.impact.is_some()
            || report.landing.is_some()
            || report.separation.is_some()
            || released;
        let since_event = if ball_event {
            0
        } else {
            self.since_event.saturating_add(1)
        };
        let near_event = matches!(S::BALL, BallKind::Free)
            && (!ball_free || since_event < self.config.event_window);
        let rows = self.measurement_rows(model, &root_tangent);
        // The measurement updates, on copies of the factors (committed at the end).
        let (mut u, mut d) = (self.ud_u, self.ud_d);
        let mut delta = SVector::<T, X>::zeros();
        let mut est_innov = [T::zero(); KINDS];
        let mut est_var = [T::zero(); KINDS];
        let mut used = [ReadingUse::None; KINDS];
        let mut expected = [false; KINDS];
        let mut lost = [false; KINDS];
        let (mut nis_sum, mut nis_count) = (T::zero(), 0u32);
        let k_sample = self.samples.saturating_add(1);
        let mut rms2 = self.rms2;
        let mut adapt = self.adapt;
        let slot = usize::from(near_event);
        let mut model_error_ratio = [T::zero(); KINDS];
        for kind in SensorKind::ALL {
            let k = kind.index();
            let Some(sensor) = self.config.sensors.get(kind).copied() else {
                continue;
            };
            let predicted = self.predicted(model, kind);
            // Running mean square of the predicted dynamic value (the model error's scale).
            let dynamic = match kind {
                SensorKind::RootStrain => predicted - self.static_stress / self.modulus,
                _ => predicted,
            };
            if let Some(r) = rms2.get_mut(k) {
                *r += self.rms_weight * (dynamic * dynamic - *r);
            }
            let Some(y) = readings.get(kind) else {
                continue;
            };
            if sensor.every > 1 && !k_sample.is_multiple_of(u64::from(sensor.every)) {
                continue;
            }
            let (Some(row), Some(use_k), Some(x), Some(l)) = (
                rows.get(k),
                used.get_mut(k),
                expected.get_mut(k),
                lost.get_mut(k),
            ) else {
                continue;
            };
            *x = true;
            if !y.is_finite() {
                *use_k = ReadingUse::Invalid;
                *l = true;
                continue;
            }
            if y.abs() >= sensor.range {
                *use_k = ReadingUse::Clipped;
                *l = true;
                continue;
            }
            if kind == SensorKind::BallAngle && !ball_free {
                *use_k = ReadingUse::Skipped;
                continue;
            }
            let bias = self.bias.get(k).copied().unwrap_or(T::zero());
            // Linearized: the predicted reading moves with the corrections made so far.
            let innovation = y - predicted - bias - row.dot(&delta);
            let scale2 = rms2.get(k).copied().unwrap_or(T::zero());
            let mut floor2 = sensor.model_error * sensor.model_error;
            if near_event {
                floor2 += self.config.event_error * self.config.event_error;
            }
            let (mean, weight) = adapt
                .get(k)
                .and_then(|a| a.get(slot))
                .copied()
                .unwrap_or((T::zero(), T::zero()));
            let measured = if is_positive(weight) {
                mean / weight
            } else {
                T::zero()
            };
            let model2 = (floor2 * scale2).max(measured);
            if let Some(x) = model_error_ratio.get_mut(k) {
                *x = if is_positive(scale2) {
                    (model2 / scale2).sqrt()
                } else {
                    T::zero()
                };
            }
            let noise2 = sensor.noise * sensor.noise;
            let r = noise2 + model2;
            // Huber's bound on the correction (a robust Kalman update, Masreliez & Martin
            // 1977): an innovation beyond `gate` of its predicted sd — an event the model put
            // elsewhere in time (a landing, an impact), not Gaussian noise — is used with the
            // noise variance that brings it to `gate` sd exactly.
            // `Uᵀ h`, once for the predicted variance and the update.
            let f = u.tr_mul(row);
            let hph = quadratic_f(&f, &d);
            let s0 = hph + r;
            let nis = innovation * innovation / s0;
            let gate = self.config.gate;
            if is_positive(self.adapt_weight) {
                // The excess of this innovation over the prediction without model error,
                // winsorized at the gate.
                let mut nu2 = innovation * innovation;
                if is_positive(gate) && nu2 > gate * gate * s0 {
                    nu2 = gate * gate * s0;
                }
                let w = self.adapt_weight;
                if let Some(a) = adapt.get_mut(k).and_then(|a| a.get_mut(slot)) {
                    a.0 += w * (nu2 - hph - noise2 - a.0);
                    a.1 += w * (T::one() - a.1);
                }
            }
            let mut r_used = r;
            *use_k = ReadingUse::Used;
            if is_positive(gate) && nis > gate * gate {
                r_used = innovation * innovation / (gate * gate) - (s0 - r);
                *use_k = ReadingUse::Capped;
            }
            let (gain, _) = bierman_f(&mut u, &mut d, f, r_used).ok_or(Error::NonFiniteState)?;
            delta += gain * innovation;
            nis_sum += nis;
            nis_count += 1;
            if let (Some(iv), Some(vv)) = (est_innov.get_mut(k), est_var.get_mut(k)) {
                *iv = innovation;
                *vv = s0;
            }
        }
        // The dummy measurement that the load's running mean is zero.
        let mean_sd = self.config.load_mean_sd;
        if is_positive(self.mean_weight) && is_positive(mean_sd) {
            let mean_prior = (T::one() - self.mean_weight) * self.load_mean
                + self.mean_weight
                    * (self.load_map[0][0] * self.load + self.load_map[0][1] * self.load_rate);
            let innovation = -mean_prior - delta[ld + 2];
            // The row is the unit vector of the slot: `Uᵀ h` is U's row.
            let f = row_of(&u, ld + 2);
            let (gain, _) =
                bierman_f(&mut u, &mut d, f, mean_sd * mean_sd).ok_or(Error::NonFiniteState)?;
            delta += gain * innovation;
        }
        // The correction in physical coordinates, onto the model's state at n + 1.
        let physical = delta.component_mul(&self.scale);
        let [[a11, a12], [a21, a22]] = self.load_map;
        let load = a11 * self.load + a12 * self.load_rate + physical[ld];
        let load_rate = a21 * self.load + a22 * self.load_rate + physical[ld + 1];
        let load_mean = (T::one() - self.mean_weight) * self.load_mean
            + self.mean_weight * (a11 * self.load + a12 * self.load_rate)
            + physical[ld + 2];
        if !load.is_finite() || !load_rate.is_finite() || load.abs() > lit(MAX_LOAD) {
            return Err(Error::NonFiniteState);
        }
        self.apply(model, &physical, ball_free)?;
        // Committed from here on.
        self.ud_u = u;
        self.ud_d = d;
        self.rms2 = rms2;
        self.adapt = adapt;
        self.load = load;
        self.load_rate = load_rate;
        self.load_mean = load_mean;
        for (k, b) in self.bias.iter_mut().enumerate() {
            *b += physical[off + k];
        }
        self.last_contact = contact;
        self.since_event = since_event;
        // The stress's variance: its row over the posterior at n (the state at n + 1 is a
        // linear function of it).
        let mut row = rows
            .get(SensorKind::RootStrain.index())
            .copied()
            .unwrap_or(SVector::zeros())
            * self.modulus;
        row[off + SensorKind::RootStrain.index()] = T::zero();
        let stress_var = quadratic(&self.ud_u, &self.ud_d, &row);
        let load_sd = quadratic_f(&row_of(&self.ud_u, ld), &self.ud_d)
            .max(T::zero())
            .sqrt();
        // Propagation to the next sample's prior.
        self.propagate(model, ball_free, ball_event, &report);
        self.samples = k_sample;
        let stress = self.root_stress(model);
        let failed = (stress - self.static_stress).abs() > self.config.health.stress_limit;
        let verdict = self
            .health
            .record(expected, lost, nis_sum, nis_count, failed);
        let ball_angle = model.ball_relative_angle().map_or(T::zero(), |(a, _)| a);
        Ok(Estimate {
            root_stress: stress,
            root_stress_sd: stress_var.max(T::zero()).sqrt(),
            tip_deflection: model.tip_deflection(),
            load: self.load,
            load_sd,
            ball_angle,
            innovation: est_innov,
            innovation_var: est_var,
            used,
            model_error: model_error_ratio,
            nis_sum,
            nis_count,
            verdict,
            report,
        })
    }

    /// The directions of the filter's subspace through the last step: `δx` for each modal
    /// position and velocity error of the predictor and for the load, from the Newton matrix
    /// (factored again at the step's end if the step ended with other factors: an event) and
    /// `R_q`, `R_v` assembled at the step's end. Returns the root element's axial tangent
    /// blocks of the `R_q` assembly (the stress row's, [`Ekf::measurement_rows`]).
    fn directions(&mut self, model: &mut Model<T, S, N, D>) -> Result<TangentBlocks<T>, Error> {
        let s = *model.state();
        let g_eff = model.sys.effective_gravity(s.base_accel);
        let rec = self.rec;
        if !model.work.has_factors(rec.c_q, s.contact) {
            // An event step ended with another matrix (a sub-step's, or another contact's):
            // factor the step's own at its end.
            let p = Problem {
                q0: &s.q,
                v0: &s.v,
                a0: &s.a,
                ch: Chain {
                    c_q: rec.c_q,
                    c_v: rec.c_v,
                    c_m: T::one(),
                },
                c_pos: rec.c_q,
                g_eff,
                contact: s.contact,
                plumb: false,
            };
            let mut r = SVector::<T, D>::zeros();
            model
                .sys
                .refresh_at(&p, [&s.q, &s.v, &s.a], &mut model.work, &mut r)?;
        }
        let unit = |c_q: T, c_v: T| Chain {
            c_q,
            c_v,
            c_m: T::zero(),
        };
        // R_q Φ_i → directions 0..M; R_v Φ_i → M..2M (right-hand sides, negated); the load
        // moves the predictor's positions by the residual static mode Ψ (module doc), so its
        // right-hand side is e_tip − R_q Ψ.
        let mut y: SVector<T, D>;
        let mut load_rhs = SVector::<T, D>::zeros();
        let mut root = [[[T::zero(); 3]; 4]; 4];
        for (block, ch) in [
            (0usize, unit(T::one(), T::zero())),
            (M, unit(T::zero(), T::one())),
        ] {
            let qva = [&s.q, &s.v, &s.a];
            if block == 0 {
                if let Some(t) = model
                    .sys
                    .jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch)
                {
                    root = t;
                }
            } else if let Some(damping) = &self.damping {
                // R_v: the beam's constant part, then the tip rows at the step's end.
                self.scratch = *damping;
                model
                    .sys
                    .add_tip_jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch);
            } else {
                model
                    .sys
                    .jacobian(qva, g_eff, &ch, s.contact, &mut self.scratch);
            }
            // The products on the band (the same sums as the dense product, in the same order,
            // without the terms outside the band, which are exact zeros).
            // R_q Ψ in the same pass as R_q Φ.
            let mut rphi = SMatrix::<T, D, M>::zeros();
            if block == 0 {
                self.scratch.mul_mat_vec(
                    &self.consistent,
                    &self.residual,
                    &mut rphi,
                    &mut load_rhs,
                );
            } else {
                self.scratch.mul_mat(&self.consistent, &mut rphi);
            }
            for i in 0..M {
                y = -column(&rphi, i);
                model.work.solve(&mut y)?;
                set_column(&mut self.dx, block + i, &y);
            }
        }
        // The load: R_P = −e_tip, so J δx = e_tip − R_q Ψ.
        y = -load_rhs;
        if let Some(x) = y.get_mut(Self::TIP) {
            *x += T::one();
        }
        model.work.solve(&mut y)?;
        set_column(&mut self.dx, 2 * M, &y);
        // Only the directions' columns (the others are zero and unused).
        for c in 0..=2 * M {
            let xi = self.basis.projection * column(&self.dx, c);
            set_column(&mut self.xi, c, &xi);
        }
        // The stiff completion for the next step: the out-of-span part of the positions the
        // step gives each direction, `(I − ΦΠ)(b + c_q δx)` (the implicit step moves the stiff
        // coordinates onto their quasi-static response: `c_q J⁻¹ R_q ≈ I` on them, a
        // contraction toward the completion consistent with the current state).
        for i in 0..M {
            let b = column(&self.consistent, i) + column(&self.dx, i) * self.rec.c_q;
            let out = b - self.basis.shapes * (self.basis.projection * b);
            set_column(
                &mut self.consistent,
                i,
                &(column(&self.basis.shapes, i) + out),
            );
        }
        let b = self.residual + column(&self.dx, 2 * M) * self.rec.c_q;
        self.residual = b - self.basis.shapes * (self.basis.projection * b);
        Ok(root)
    }

    /// The rows `H` of each sensor's reading over the filter's scaled coordinates at `n`
    /// (zero rows for absent sensors; the root-strain row, times the modulus and without its
    /// bias, is the stress row), with the root element's axial tangent at the step's end as
    /// [`Ekf::directions`] returns it.
    fn measurement_rows(
        &self,
        model: &Model<T, S, N, D>,
        root_tangent: &TangentBlocks<T>,
    ) -> [SVector<T, X>; KINDS] {
        let rec = self.rec;
        let (ld, off) = (Self::LD, Self::OFF);
        let mut rows = [SVector::<T, X>::zeros(); KINDS];
        let s = model.state();
        // Filter coordinate c → (direction, mode whose shape is in δq* (c < M) or δv*).
        let direction = |c: usize| -> Option<usize> {
            if c < 2 * M {
                Some(c)
            } else if c == ld {
                Some(2 * M)
            } else {
                None
            }
        };
        // Tip acceleration: δx_tip.
        if let Some(row) = rows.get_mut(SensorKind::TipAccel.index()) {
            for c in 0..=ld {
                if let Some(j) = direction(c) {
                    row[c] = self.dx[(Self::TIP, j)];
                }
            }
            row[off + SensorKind::TipAccel.index()] = T::one();
        }
        // Ball angle: ∇α · δq', δq' = δq* + c_q δx (only read with the sensor).
        if matches!(S::BALL, BallKind::Free)
            && self.config.sensors.get(SensorKind::BallAngle).is_some()
        {
            let x = Model::<T, S, N, D>::local(&s.q, &s.v, &s.a);
            let grad = tip::gap_gradient(&model.sys.inertia, &x);
            let end = 4 * N - 4;
            let dot = |c: usize, m: &SMatrix<T, D, X>| -> T {
                grad.iter()
                    .enumerate()
                    .map(|(k, g)| *g * m[(end + k, c)])
                    .fold(T::zero(), |a, b| a + b)
            };
            let phi_dot = |i: usize| -> T {
                grad.iter()
                    .enumerate()
                    .map(|(k, g)| *g * self.consistent[(end + k, i)])
                    .fold(T::zero(), |a, b| a + b)
            };
            if let Some(row) = rows.get_mut(SensorKind::BallAngle.index()) {
                for c in 0..=ld {
                    if let Some(j) = direction(c) {
                        let mut v = rec.c_q * dot(j, &self.dx);
                        if c < M {
                            v += phi_dot(c);
                        } else if c == ld {
                            v += grad
                                .iter()
                                .enumerate()
                                .map(|(k, g)| *g * self.residual[end + k])
                                .fold(T::zero(), |a, b| a + b);
                        }
                        row[c] = v;
                    }
                }
                row[off + SensorKind::BallAngle.index()] = T::one();
            }
        }
        // Root strain (and stress): (g_q·δq' + g_v·δv' + g_a·δx) / E.
        let g_eff = model.sys.effective_gravity(s.base_accel);
        let mut g = self.stress_gradients_of(model, g_eff, root_tangent);
        for (gk, wk) in g.iter_mut().zip(self.recover.iter()) {
            *gk += *wk;
        }
        let inv_e = T::one() / self.modulus;
        if let Some(row) = rows.get_mut(SensorKind::RootStrain.index()) {
            for c in 0..=ld {
                if let Some(j) = direction(c) {
                    let dx = self.dx.column(j);
                    let mut v = rec.c_q * g[0].dot(&dx) + rec.c_v * g[1].dot(&dx) + g[2].dot(&dx);
                    if c < M {
                        v += g[0].dot(&self.consistent.column(c));
                    } else if c < 2 * M {
                        v += g[1].dot(&self.consistent.column(c - M));
                    } else if c == ld {
                        v += g[0].dot(&self.residual);
                    }
                    row[c] = v * inv_e;
                }
            }
            row[off + SensorKind::RootStrain.index()] = T::one();
        }
        // To the scaled coordinates.
        for row in rows.iter_mut() {
            *row = row.component_mul(&self.scale);
        }
        rows
    }

    /// Moves the model's state at `n + 1` by the correction `delta` (physical coordinates of
    /// the filter at `n`; module doc), keeps a held ball on its stop and a flying ball's
    /// spin, and keeps the ball inside the stops.
    fn apply(
        &self,
        model: &mut Model<T, S, N, D>,
        delta: &SVector<T, X>,
        ball_free: bool,
    ) -> Result<(), Error> {
        let rec = self.rec;
        let mut dx = SVector::<T, D>::zeros();
        let mut s = *model.state();
        for i in 0..M {
            let phi = self.consistent.column(i);
            s.q.axpy(delta[i], &phi, T::one());
            s.v.axpy(delta[M + i], &phi, T::one());
            if rec.blocks == 3 {
                s.pseudo_accel.axpy(delta[2 * M + i], &phi, T::one());
            }
            dx.axpy(delta[i], &self.dx.column(i), T::one());
            dx.axpy(delta[M + i], &self.dx.column(M + i), T::one());
        }
        dx.axpy(delta[Self::LD], &self.dx.column(2 * M), T::one());
        s.q.axpy(delta[Self::LD], &self.residual, T::one());
        // Positions take the whole linear correction: `c_q δx` moves the stiff (axial and
        // high) coordinates to where the step puts them for the corrected predictor
        // (quasi-statically). Velocities and accelerations take its modal part only: the
        // stiff part of `c_v δx` and `δx` is the integrator's jump of a stiff mode started off
        // its equilibrium, which the filter's subspace does not hold (it treats the stiff
        // coordinates as slaved), and which would ring into the next predictor.
        s.q.axpy(rec.c_q, &dx, T::one());
        let modal = self.consistent * (self.basis.projection * dx);
        s.v.axpy(rec.c_v, &modal, T::one());
        s.a += modal;
        if rec.blocks == 3 {
            s.pseudo_accel.axpy(rec.kappa, &modal, T::one());
        } else {
            s.pseudo_accel = s.a;
        }
        if let (BallKind::Free, Contact::OnStop(side)) = (S::BALL, s.contact) {
            // Held: the ball stays on the stop, whatever the housing's correction.
            model.sys.hold_on_stop(&mut s, side);
        } else if matches!(S::BALL, BallKind::Free) && !ball_free {
            // Flying (or beyond the stops): the spin is not the filter's; keep the model's.
            let m0 = model.state();
            for (x, x0) in [
                (&mut s.q, &m0.q),
                (&mut s.v, &m0.v),
                (&mut s.a, &m0.a),
                (&mut s.pseudo_accel, &m0.pseudo_accel),
            ] {
                if let (Some(a), Some(b)) = (x.get_mut(Self::SPIN), x0.get(Self::SPIN)) {
                    *a = *b;
                }
            }
        }
        let finite = |x: &SVector<T, D>| x.iter().all(|z| z.is_finite());
        if !(finite(&s.q) && finite(&s.v) && finite(&s.a) && finite(&s.pseudo_accel)) {
            return Err(Error::NonFiniteState);
        }
        if S::STOPS && ball_free {
            // Keep the corrected ball inside the stops (the model's crossing test needs the
            // start of a step on the track's side).
            let stop = model.params().ball.stop_angle * lit::<T>(0.9999);
            let alpha = model.sys.relative_angle(&s);
            if alpha.abs() > stop {
                let k = model.sys.inertia.orbit_per_spin;
                let target = if alpha > T::zero() { stop } else { -stop };
                if let Some(spin) = s.q.get_mut(Self::SPIN) {
                    *spin += (alpha - target) / k;
                }
            }
        }
        model.set_state(s);
        Ok(())
    }

    /// The time update `P ← F P Fᵀ + Q` on the factors (Thornton), with the events'
    /// treatment of the ball folded into `F` and `Q`.
    fn propagate(
        &mut self,
        model: &Model<T, S, N, D>,
        ball_free: bool,
        ball_event: bool,
        report: &StepReport<T>,
    ) {
        let rec = self.rec;
        let (ld, off) = (Self::LD, Self::OFF);
        // F in physical coordinates, then scaled: F̃ = T⁻¹ F T.
        let mut f = SMatrix::<T, X, X>::zeros();
        for c in 0..=2 * M {
            let col = if c < 2 * M { c } else { ld };
            for i in 0..M {
                let xi = self.xi[(i, c)];
                f[(i, col)] = rec.qx * xi;
                f[(M + i, col)] = rec.vx * xi;
                if rec.blocks == 3 {
                    f[(2 * M + i, col)] = rec.bx * xi;
                }
            }
        }
        for i in 0..M {
            f[(i, i)] += T::one();
            f[(i, M + i)] += rec.h;
            f[(M + i, M + i)] += T::one();
            if rec.blocks == 3 {
                f[(i, 2 * M + i)] = rec.qb;
                f[(M + i, 2 * M + i)] = rec.vb;
                f[(2 * M + i, 2 * M + i)] = rec.bb;
            }
        }
        for (i, row) in self.load_map.iter().enumerate() {
            for (j, a) in row.iter().enumerate() {
                f[(ld + i, ld + j)] = *a;
            }
        }
        let mu = self.mean_weight;
        f[(ld + 2, ld)] = mu * self.load_map[0][0];
        f[(ld + 2, ld + 1)] = mu * self.load_map[0][1];
        f[(ld + 2, ld + 2)] = T::one() - mu;
        for k in 0..KINDS {
            f[(off + k, off + k)] = T::one();
        }
        // Only F's nonzero entries (a zero stays zero; its sign is never read: F's entries
        // enter below only as nonzero factors).
        for (j, col) in f.as_mut_slice().chunks_exact_mut(X).enumerate() {
            let sj = self.scale[j];
            for (x, si) in col.iter_mut().zip(self.scale.iter()) {
                if *x != T::zero() {
                    *x *= sj / *si;
                }
            }
        }
        // Noise columns (scaled) and their variances: the first `n` columns of `w2`, the others
        // zero (Thornton's windows read them).
        self.w2 = [[T::zero(); NOISE]; X];
        let mut q = [T::zero(); NOISE];
        let mut n = 0;
        let mut push = |col: SVector<T, X>, var: T, w2: &mut [[T; NOISE]; X]| {
            if let (Some(qn), true) = (q.get_mut(n), is_positive(var)) {
                *qn = var;
                for (row, c) in w2.iter_mut().zip(col.iter()) {
                    if let Some(x) = row.get_mut(n) {
                        *x = *c;
                    }
                }
                n += 1;
            }
        };
        let unit = |k: usize| {
            let mut e = SVector::<T, X>::zeros();
            e[k] = T::one();
            e
        };
        for c in 0..2 {
            let mut col = SVector::<T, X>::zeros();
            col[ld] = self.load_noise[0][c];
            col[ld + 1] = self.load_noise[1][c] / self.scale[ld + 1];
            col[ld + 2] = mu * self.load_noise[0][c];
            push(col, T::one(), &mut self.w2);
        }
        let half = lit::<T>(0.5);
        for i in 0..M {
            let mut col = SVector::<T, X>::zeros();
            col[i] = half * rec.h * rec.h / self.scale[i];
            col[M + i] = rec.h / self.scale[M + i];
            push(
                col,
                self.config.modal_noise * self.config.modal_noise,
                &mut self.w2,
            );
        }
        for (k, s) in self.config.sensors.slots.iter().enumerate() {
            if let Some(s) = s {
                push(unit(off + k), s.bias_walk * s.bias_walk, &mut self.w2);
            }
        }
        if matches!(S::BALL, BallKind::Free) {
            if let Some((a, u)) = self.ball_direction(model) {
                let (uq, uv) = (embed::<T, M, X>(&u, 0), embed::<T, M, X>(&u, M));
                // Rank-one maps I − c u aᵀ on the block of rows `at..at + M` (the positions' or
                // the velocities'), applied to F (scaled: ũ = T⁻¹u, ã = T a): `u` and `a` are
                // zero elsewhere, so only that block's entries of `Fᵀã` have nonzero terms
                // (summed in row order, as the full product sums them) and only its rows move.
                let scale = &self.scale;
                let mut map = |at: usize, c: T| {
                    let s = scale.as_slice().get(at..at + M).unwrap_or(&[]);
                    for col in f.as_mut_slice().chunks_exact_mut(X) {
                        let Some(col) = col.get_mut(at..at + M) else {
                            continue;
                        };
                        // (Fᵀã)_j over the block, then f −= ũ (Fᵀã)_j c.
                        let mut bj = T::zero();
                        for ((x, ak), sk) in col.iter().zip(a.iter()).zip(s.iter()) {
                            bj += *ak * *sk * *x;
                        }
                        for ((x, uk), sk) in col.iter_mut().zip(u.iter()).zip(s.iter()) {
                            *x -= *uk / *sk * bj * c;
                        }
                    }
                };
                if let Some(imp) = &report.impact {
                    // The relative rate's error reverses like the rate: v ← v − (1 + e) u (a·v),
                    // and the rebound speed's uncertainty is added.
                    let e = model.params().ball.restitution;
                    map(M, T::one() + e);
                    let sd = self.config.impact_sd * imp.relative_speed.abs();
                    push(uv.component_div(&self.scale), sd * sd, &mut self.w2);
                }
                if !ball_free {
                    // Held or flying: the relative angle is the model's; its error leaves the
                    // subspace.
                    map(0, T::one());
                    map(M, T::one());
                } else if ball_event && report.impact.is_none() {
                    // Landed or released: the relative angle and rate restart with their prior.
                    map(0, T::one());
                    map(M, T::one());
                    let [sa, sr] = self.config.ball_restart_sd;
                    push(uq.component_div(&self.scale), sa * sa, &mut self.w2);
                    push(uv.component_div(&self.scale), sr * sr, &mut self.w2);
                }
            }
        }
        // W₁ = F U by rows, only its columns of positive weight (the others add nothing to
        // U D Uᵀ): U's rows restricted to those columns, then each row of F U as the sum of
        // the rows of U that F's nonzero entries of that row pick, in order (F is sparse: 2M + 1
        // entries in a modal row, at most three in the load's and one in a bias's), over whole
        // rows (U is unit upper triangular: a row's entries left of its diagonal, and the
        // columns beyond the kept ones, are exact zeros and change no sum).
        let mut d1 = [T::zero(); X];
        let mut ur = [[T::zero(); X]; X];
        let mut n1 = 0;
        let columns = self.ud_u.as_slice().chunks_exact(X);
        for (uk, dk) in columns.zip(self.ud_d.iter()) {
            if !is_positive(*dk) {
                continue;
            }
            let Some(slot) = d1.get_mut(n1) else { break };
            *slot = *dk;
            for (row, x) in ur.iter_mut().zip(uk.iter()) {
                if let Some(y) = row.get_mut(n1) {
                    *y = *x;
                }
            }
            n1 += 1;
        }
        // F's nonzero entries of row i lie in columns `lo..=hi`: the modal rows' in the modal
        // columns and the load's, the load's block's in that block, a bias's on the diagonal
        // (the entries outside are never written, and the ball's maps move only modal rows,
        // by multiples of modal rows). F is read in place, column-major.
        let fs = f.as_slice();
        for (i, row) in self.w1.iter_mut().enumerate() {
            let (lo, hi) = if i < ld {
                (0, ld)
            } else if i < off {
                (ld, off - 1)
            } else {
                (i, i)
            };
            let mut acc = [T::zero(); X];
            for k in lo..=hi {
                let (Some(fik), Some(uk)) = (fs.get(k * X + i), ur.get(k)) else {
                    continue;
                };
                if *fik != T::zero() {
                    for (x, y) in acc.iter_mut().zip(uk.iter()) {
                        *x += *fik * *y;
                    }
                }
            }
            *row = acc;
        }
        thornton(
            &mut self.w1,
            &d1,
            n1,
            &mut self.w2,
            &q,
            n,
            &mut self.ud_u,
            &mut self.ud_d,
        );
    }

    /// The ball's relative angle as a direction of the modal coordinates, `a_i = ∇α·φ_i`,
    /// and the smallest modal change with `a·u = 1`, `u = a / |a|²`.
    fn ball_direction(&self, model: &Model<T, S, N, D>) -> Option<(SVector<T, M>, SVector<T, M>)> {
        let s = model.state();
        let x = Model::<T, S, N, D>::local(&s.q, &s.v, &s.a);
        let grad = tip::gap_gradient(&model.sys.inertia, &x);
        let end = 4 * N - 4;
        let mut a = SVector::<T, M>::zeros();
        for (i, ai) in a.iter_mut().enumerate() {
            *ai = grad
                .iter()
                .enumerate()
                .map(|(k, g)| *g * self.consistent[(end + k, i)])
                .fold(T::zero(), |u, v| u + v);
        }
        let aa = a.dot(&a);
        is_positive(aa).then(|| (a, a / aa))
    }
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

/// An `M`-vector placed at `offset` of an `X`-vector.
fn embed<T: Real, const M: usize, const X: usize>(
    v: &SVector<T, M>,
    offset: usize,
) -> SVector<T, X> {
    let mut e = SVector::<T, X>::zeros();
    for (i, x) in v.iter().enumerate() {
        if let Some(y) = e.get_mut(offset + i) {
            *y = *x;
        }
    }
    e
}

#[cfg(test)]
mod tests;
