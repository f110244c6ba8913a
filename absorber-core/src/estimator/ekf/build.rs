//! Building the filter: the modal basis and the parts precomputed from the model, the first
//! state and covariance, the restart state and the stress gradients.

use super::config::{load_model, EkfConfig};
use super::{Ekf, Parts, Recursion, AUGMENTED, NOISE};
use crate::error::Error;
use crate::estimator::basis::ModalBasis;
use crate::estimator::health::Health;
use crate::estimator::sensors::{SensorKind, KINDS};
use crate::model::Model;
use crate::monitor::stress::static_root_moment;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::{BallKind, Scene};
use crate::state::Contact;
use crate::step::ancf::TangentBlocks;
use crate::step::linalg::BandMatrix;
use crate::step::scheme::Chain;
use nalgebra::{SMatrix, SVector};

impl<T: Real, S: Scene, const N: usize, const D: usize, const M: usize, const X: usize>
    Ekf<T, S, N, D, M, X>
{
    /// The recovery vectors, the static stress and `R_v`'s constant part, from the built
    /// filter. Out of line (measured: 96 B less boot stack than inlined into the construction).
    #[inline(never)]
    pub(super) fn finish(&mut self, model: &Model<T, S, N, D>) {
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
    pub(super) fn parts(
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
    pub(super) fn fresh(
        model: &Model<T, S, N, D>,
        config: EkfConfig<T, M>,
        parts: Parts<T, D, M, X>,
    ) -> Self {
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
    pub(super) fn recovery(&self, model: &Model<T, S, N, D>) -> [SVector<T, D>; 3] {
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
    /// (the `∂r/∂q` assembly's, `system::System::jacobian`).
    pub(super) fn stress_gradients_of(
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
}
