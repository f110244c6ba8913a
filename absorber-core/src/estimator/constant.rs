//! The constant-gain estimator (the baseline the extended Kalman filter replaces): the root
//! stress of an arm from a tip accelerometer.
//!
//! **Design: the nonlinear model as predictor, a constant (steady-state) Kalman gain.** Each
//! sample the model takes one step ([`crate::Model::step_with_loads`]) under the base
//! acceleration and the *estimated* tip load; the innovation `ν = y − (ä_tip + ÿ_b + b̂)`
//! (measured minus predicted absolute tip acceleration, with the estimated sensor bias b̂)
//! then corrects the state, the load and the bias by a constant gain: `x⁺ = x⁻ + K ν`. The
//! host's design leaves the positions uncorrected (`Gain::q = 0`): a correction of the vertical
//! slopes at a deflected state changes the axial strain to first order, which the gain
//! linearized at the static state does not know, and it drove the loop unstable at large swings
//! (`absorber_sim::estimate::design`); velocities and accelerations carry the correction into the
//! positions through the integrator. The gain is the steady-state Kalman gain of the model linearized about its
//! static state — the discrete step map itself, `x_k = F x_{k−1} + G P_k` with the state
//! `x = (q, q̇, q̈, a)` of the Newmark / generalized-α recursion — augmented with the unknown
//! tip load P (first-order Gauss–Markov, `P_k = φ P_{k−1} + η`, increment variance `q_P` per
//! sample: a random walk that forgets over a time constant τ) and the sensor bias (random
//! walk, `q_b`), and computed on the host (`absorber_sim::estimate::design`), where the Riccati
//! equation is iterated to convergence in `f64`.
//!
//! Why this and not an extended Kalman filter: the arm's response is linear to within its
//! static sag (the gain computed about the static state stays valid, the nonlinear predictor
//! keeps the geometric and gravity terms exact), and the per-sample cost is one model step plus
//! `4D + 2` multiply-adds. An EKF would propagate a `(4D + 2)²` covariance each sample — for
//! `D = 12` some 10⁵ flops, several times the model step on a Cortex-M4F — for a gain that,
//! in this almost linear regime, converges to this one.
//!
//! **Outputs** ([`Estimate`]): the model's state (tip deflection), the root moment and stress
//! ([`crate::monitor::stress`], clamp reaction) with the steady-state standard deviation of
//! the stress from the Riccati solution, the estimated load and bias. The *mean and static*
//! stress are not observable from accelerations (a constant load gives no acceleration): the
//! estimate carries the model's static state under gravity, and a steady load is seen only as
//! far as the random-walk load model lets its slow part through (see `docs/monitoring.md`).
//!
//! Bounded work: one model step and a fixed number of operations; errors are values and leave
//! the estimator's state unchanged.

use crate::error::Error;
use crate::loads::{Loads, MAX_LOAD};
use crate::model::Model;
use crate::monitor::stress::{root_reaction_moment, RootSection};
use crate::scalar::{is_positive, lit, Real};
use crate::scene::Scene;
use crate::state::{State, StepReport};
use nalgebra::SVector;

/// The constant gain of an [`Estimator`] and the steady-state uncertainty it implies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gain<T, const D: usize> {
    /// Gain on the positions q \[m or 1 per m/s²\].
    pub q: SVector<T, D>,
    /// Gain on the velocities.
    pub v: SVector<T, D>,
    /// Gain on the accelerations.
    pub a: SVector<T, D>,
    /// Gain on the generalized-α variable (zero for Newmark).
    pub pseudo_accel: SVector<T, D>,
    /// Gain on the tip load \[N per m/s²\].
    pub load: T,
    /// Decay of the tip load per sample, `φ = exp(−h/τ)` \[-\]: the load model is a
    /// first-order Gauss–Markov process `P_k = φ P_{k−1} + η_k` (a pure random walk, φ = 1,
    /// would make the steady load undetectable from accelerations and the Riccati equation
    /// without a steady state).
    pub load_decay: T,
    /// Gain on the sensor bias \[-\].
    pub bias: T,
    /// Steady-state standard deviation of the root stress estimate \[Pa\].
    pub stress_sd: T,
    /// Steady-state standard deviation of the load estimate \[N\].
    pub load_sd: T,
    /// Steady-state standard deviation of the innovation, `√(h P⁻ hᵀ + r)` \[m/s²\]: what
    /// the innovations of a model that explained the measurement to the sensor's noise would
    /// scatter by. A reduced model's own error keeps their RMS at a few times this even where
    /// its estimate is good; a rise above what the site shows when the estimate is known good
    /// says the model misses a force (`docs/monitoring.md`).
    pub innovation_sd: T,
}

impl<T: Real, const D: usize> Gain<T, D> {
    /// Converts the gain (designed in `f64`) to another scalar.
    pub fn cast<U: Real>(&self) -> Gain<U, D> {
        let c = |x: T| -> U { lit(crate::scalar::to_f64(x)) };
        Gain {
            q: self.q.map(c),
            v: self.v.map(c),
            a: self.a.map(c),
            pseudo_accel: self.pseudo_accel.map(c),
            load: c(self.load),
            load_decay: c(self.load_decay),
            bias: c(self.bias),
            stress_sd: c(self.stress_sd),
            load_sd: c(self.load_sd),
            innovation_sd: c(self.innovation_sd),
        }
    }

    fn check(&self) -> Result<(), Error> {
        let vectors = [&self.q, &self.v, &self.a, &self.pseudo_accel];
        let finite = vectors
            .iter()
            .all(|x| x.as_slice().iter().all(|z| z.is_finite()))
            && [
                self.load,
                self.load_decay,
                self.bias,
                self.stress_sd,
                self.load_sd,
                self.innovation_sd,
            ]
            .iter()
            .all(|z| z.is_finite());
        if !finite {
            return Err(Error::InvalidParameter {
                field: "estimator.gain",
                reason: "must be finite",
            });
        }
        if self.load_decay < T::zero() || self.load_decay > T::one() {
            return Err(Error::InvalidParameter {
                field: "estimator.gain.load_decay",
                reason: "must lie in [0, 1] (a growing load model is unstable)",
            });
        }
        Ok(())
    }
}

/// What the estimator says after a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate<T> {
    /// Tip deflection relative to the base \[m\].
    pub tip_deflection: T,
    /// Root bending moment, sagging positive \[N·m\].
    pub root_moment: T,
    /// Root stress at the top fibre, tension positive \[Pa\].
    pub root_stress: T,
    /// Its standard deviation (steady state of the filter) \[Pa\].
    pub root_stress_sd: T,
    /// Estimated vertical tip load, positive up \[N\].
    pub load: T,
    /// Its standard deviation \[N\].
    pub load_sd: T,
    /// Estimated sensor bias \[m/s²\].
    pub bias: T,
    /// Innovation: measured minus predicted tip acceleration \[m/s²\].
    pub innovation: T,
    /// The innovation's steady-state standard deviation ([`Gain::innovation_sd`]) \[m/s²\].
    pub innovation_sd: T,
    /// The sample was beyond the sensor's range: predicted only, not corrected.
    pub clipped: bool,
    /// The model step's report.
    pub report: StepReport<T>,
}

/// The error of a sensor range that is not finite and positive ([`Estimator::new_in`]).
const RANGE: Error = Error::InvalidParameter {
    field: "estimator.range",
    reason: "must be finite and positive",
};

/// The estimator: a model of a scene with loads ([`crate::scene::Loaded`] or
/// [`crate::scene::Arm`]) and a constant gain (module doc).
#[derive(Clone, Debug)]
pub struct Estimator<T: Real, S: Scene, const N: usize, const D: usize> {
    model: Model<T, S, N, D>,
    gain: Gain<T, D>,
    section: RootSection<T>,
    load: T,
    bias: T,
    /// Largest |measured acceleration| the sensor reads \[m/s²\] (its range).
    range: T,
    max_load: T,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Estimator<T, S, N, D> {
    /// Row of the end node's vertical coordinate.
    const TIP: usize = 4 * N - 3;

    /// The estimator of `model` (at its start state) with `gain`, the root `section`, and a
    /// sensor of range ±`range` \[m/s²\]. The scene must have loads.
    pub fn new(
        mut model: Model<T, S, N, D>,
        gain: Gain<T, D>,
        section: RootSection<T>,
        range: T,
    ) -> Result<Self, Error> {
        gain.check()?;
        if !is_positive(range) || !range.is_finite() {
            return Err(Error::InvalidParameter {
                field: "estimator.range",
                reason: "must be finite and positive",
            });
        }
        model.set_loads(&Loads::zero())?;
        Ok(Self {
            model,
            gain,
            section,
            load: T::zero(),
            bias: T::zero(),
            range,
            max_load: lit(MAX_LOAD),
        })
    }

    /// [`Estimator::new`] into caller storage, with no estimator and no model passing through
    /// the stack (a firmware keeps it in a `static`, `docs/embedded.md`, boot RAM): the
    /// undeformed model of `params` is written in place, then `start` brings it to the start
    /// state the model given to `new` would have (e.g. [`Model::set_arm`],
    /// [`Model::solve_static`], [`Model::restart`]). On error `slot` holds nothing usable: use
    /// only the returned reference.
    pub fn new_in(
        slot: &mut core::mem::MaybeUninit<Self>,
        params: crate::Params<T>,
        start: impl FnOnce(&mut Model<T, S, N, D>) -> Result<(), Error>,
        gain: Gain<T, D>,
        section: RootSection<T>,
        range: T,
    ) -> Result<&mut Self, Error> {
        gain.check()?;
        if !is_positive(range) || !range.is_finite() {
            return Err(RANGE);
        }
        Model::<T, S, N, D>::check_params(&params)?;
        let e = slot.write(Self {
            model: Model::fresh(params),
            gain,
            section,
            load: T::zero(),
            bias: T::zero(),
            range,
            max_load: lit(MAX_LOAD),
        });
        start(&mut e.model)?;
        e.model.set_loads(&Loads::zero())?;
        Ok(e)
    }

    /// The model (its state is the state estimate).
    pub fn model(&self) -> &Model<T, S, N, D> {
        &self.model
    }

    /// The gain.
    pub fn gain(&self) -> &Gain<T, D> {
        &self.gain
    }

    /// The estimated tip load \[N\].
    pub fn load(&self) -> T {
        self.load
    }

    /// The estimated sensor bias \[m/s²\].
    pub fn bias(&self) -> T {
        self.bias
    }

    /// Root stress of the current state estimate \[Pa\].
    pub fn root_stress(&self) -> T {
        self.section
            .stress_of_moment(root_reaction_moment(&self.model))
    }

    /// Absolute vertical tip acceleration the model predicts plus the estimated bias \[m/s²\].
    pub fn predicted_measurement(&self, base_accel: T) -> T {
        let a = self.model.state().a.get(Self::TIP).copied();
        a.unwrap_or(T::zero()) + base_accel + self.bias
    }

    /// Sets the bias estimate to the measured minus the predicted tip acceleration of the
    /// current state (`tip_accel − ä_tip − ÿ_b`): the zero-g calibration at installation, with
    /// the arm at rest. Without it the bias state learns the offset over its own time constant
    /// (the gain's `bias`), and an offset of many noise σ drives the load estimate meanwhile.
    pub fn initialize_bias(&mut self, base_accel: T, tip_accel: T) -> Result<(), Error> {
        if !tip_accel.is_finite() || !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        self.bias = T::zero();
        self.bias = tip_accel - self.predicted_measurement(base_accel);
        Ok(())
    }

    /// One sample: the base acceleration `base_accel` and the measured vertical tip
    /// acceleration `tip_accel` \[m/s²\], both at the end of the step. Errors (non-finite
    /// input, failed step, a correction that would leave the physical range) leave the
    /// estimator unchanged, but count as failed steps of the model's recovery rule
    /// ([`Model::step`], "Recovery"): the [`crate::RESTART_AFTER`]-th in a row restarts the
    /// model at rest (and a refused correction there also the load estimate at zero), so that
    /// the next sample's innovation re-seeds the state from the measurement.
    pub fn update(&mut self, base_accel: T, tip_accel: T) -> Result<Estimate<T>, Error> {
        if !tip_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        let before = (*self.model.state(), self.load, self.bias);
        let recovery = self.model.recovery();
        let prior = self.gain.load_decay * self.load;
        let loads = Loads {
            tip_force: prior,
            line_load: [T::zero(); N],
        };
        let report = self.model.step_with_loads(base_accel, &loads)?;
        let clipped = tip_accel.abs() >= self.range;
        let innovation = if clipped {
            T::zero()
        } else {
            tip_accel - self.predicted_measurement(base_accel)
        };
        let mut s: State<T, D> = *self.model.state();
        let g = &self.gain;
        s.q += g.q * innovation;
        s.v += g.v * innovation;
        s.a += g.a * innovation;
        s.pseudo_accel += g.pseudo_accel * innovation;
        let load = prior + g.load * innovation;
        let bias = self.bias + g.bias * innovation;
        let finite =
            s.q.iter()
                .chain(s.v.iter())
                .chain(s.a.iter())
                .all(|z| z.is_finite());
        if !finite || !load.is_finite() || load.abs() > self.max_load || !bias.is_finite() {
            if self.model.refuse_step((before.0, recovery), base_accel) {
                self.load = T::zero();
            }
            let _ = self.model.set_loads(&Loads {
                tip_force: self.load,
                line_load: [T::zero(); N],
            });
            return Err(Error::NonFiniteState);
        }
        self.model.correct_state(s);
        self.load = load;
        self.bias = bias;
        let moment = root_reaction_moment(&self.model);
        Ok(Estimate {
            tip_deflection: self.model.tip_deflection(),
            root_moment: moment,
            root_stress: self.section.stress_of_moment(moment),
            root_stress_sd: self.gain.stress_sd,
            load,
            load_sd: self.gain.load_sd,
            bias,
            innovation,
            innovation_sd: self.gain.innovation_sd,
            clipped,
            report,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loads::{ArmParams, PointMass, MAX_POINT_MASSES};
    use crate::scene::{Arm, BeamOnly, FreeBall, Loaded};
    use crate::Params;

    fn arm_params() -> (Params<f64>, ArmParams<f64>) {
        let mut p = Params::<f64>::default();
        p.beam.length = 6.0;
        let arm = ArmParams {
            root_diameter: 0.2,
            tip_diameter: 0.1,
            wall: 0.004,
            density: 7850.0,
            point_masses: [PointMass {
                position: 6.0,
                mass: 0.0,
            }; MAX_POINT_MASSES],
        };
        (p, arm)
    }

    fn arm_model() -> Model<f64, Arm<BeamOnly>, 2, 8> {
        let (p, arm) = arm_params();
        Model::arm_at_rest(p, &arm, 0.0).expect("arm")
    }

    fn gain(load_decay: f64) -> Gain<f64, 8> {
        Gain {
            q: SVector::zeros(),
            v: SVector::zeros(),
            a: SVector::zeros(),
            pseudo_accel: SVector::zeros(),
            load: 0.0,
            load_decay,
            bias: 0.0,
            stress_sd: 0.0,
            load_sd: 0.0,
            innovation_sd: 0.0,
        }
    }

    fn section() -> RootSection<f64> {
        RootSection {
            bending_rigidity: 1.0,
            stress_per_curvature: 1.0,
            extreme_fibre: 0.1,
        }
    }

    /// Errors are values naming the field, and a rejected sample leaves the estimator as it
    /// was: a bad gain, a scene without loads, a NaN measurement.
    #[test]
    fn estimator_errors_are_values_and_keep_the_state() {
        let bad = Estimator::new(arm_model(), gain(1.5), section(), 20.0).err();
        assert!(matches!(
            bad,
            Some(Error::InvalidParameter {
                field: "estimator.gain.load_decay",
                ..
            })
        ));
        let paper = Model::<f64, FreeBall, 2, 9>::at_rest(Params::default(), 0.0).expect("model");
        let g9 = Gain {
            q: SVector::<f64, 9>::zeros(),
            v: SVector::zeros(),
            a: SVector::zeros(),
            pseudo_accel: SVector::zeros(),
            load: 0.0,
            load_decay: 1.0,
            bias: 0.0,
            stress_sd: 0.0,
            load_sd: 0.0,
            innovation_sd: 0.0,
        };
        assert!(matches!(
            Estimator::new(paper, g9, section(), 20.0).err(),
            Some(Error::InvalidParameter { field: "loads", .. })
        ));
        let mut e = Estimator::new(arm_model(), gain(0.9), section(), 20.0).expect("valid");
        e.update(0.0, 0.01).expect("sample");
        let before = (*e.model().state(), e.load(), e.bias());
        assert_eq!(e.update(0.0, f64::NAN).err(), Some(Error::NonFiniteInput));
        assert_eq!((*e.model().state(), e.load(), e.bias()), before);
    }

    /// Built in place, the estimator is the one `new` builds: the same start, and the same
    /// states bit for bit over 50 corrected samples; its errors name the same fields.
    #[test]
    fn estimator_built_in_place_equals_the_one_built_by_value() {
        let (p, arm) = arm_params();
        let mut g = gain(0.95);
        g.v = SVector::from_element(1e-3);
        g.load = 0.5;
        g.bias = 1e-2;
        let mut by_value = Estimator::new(arm_model(), g, section(), 20.0).expect("valid");
        let start = |m: &mut Model<f64, Arm<BeamOnly>, 2, 8>| {
            m.set_arm(&arm)?;
            m.solve_static()?;
            m.restart(0.0)
        };
        let mut slot = core::mem::MaybeUninit::uninit();
        let in_place = Estimator::new_in(&mut slot, p, start, g, section(), 20.0).expect("valid");
        assert_eq!(in_place.model().state(), by_value.model().state());
        for k in 0..50 {
            let y = 0.3 * (0.2 * f64::from(k)).sin();
            let a = by_value.update(0.1, y).expect("sample");
            let b = in_place.update(0.1, y).expect("sample");
            assert_eq!(a, b);
            assert_eq!(in_place.model().state(), by_value.model().state());
        }
        let mut slot = core::mem::MaybeUninit::uninit();
        let bad = Estimator::new_in(&mut slot, p, start, g, section(), f64::NAN).err();
        assert!(matches!(
            bad,
            Some(Error::InvalidParameter {
                field: "estimator.range",
                ..
            })
        ));
        let mut slot = core::mem::MaybeUninit::<Estimator<f64, Loaded<BeamOnly>, 2, 8>>::uninit();
        let no_sections = Estimator::new_in(&mut slot, p, |m| m.set_arm(&arm), g, section(), 20.0);
        assert!(matches!(
            no_sections.err(),
            Some(Error::InvalidParameter { field: "arm", .. })
        ));
    }

    /// Refused corrections count as failed steps of the model's recovery rule: the first two
    /// leave the estimator as it was, the third restarts it at rest (the load estimate at
    /// zero, the clock at three samples), and the next sample is an ordinary one. Before,
    /// each refusal reset the rule's count and one bad sample could be refused for ever.
    #[test]
    fn refused_corrections_restart_the_estimator_after_three_in_a_row() {
        let mut g = gain(1.0);
        g.load = 1.0e6; // an innovation of 5 m/s² asks for a 5 MN load: refused
        let mut e = Estimator::new(arm_model(), g, section(), 20.0).expect("valid");
        let start = *e.model().state();
        for _ in 0..2 {
            assert_eq!(e.update(0.0, 5.0).err(), Some(Error::NonFiniteState));
            assert_eq!(e.model().state(), &start);
        }
        assert_eq!(e.update(0.0, 5.0).err(), Some(Error::NonFiniteState));
        assert_eq!(e.model().restarts(), 1);
        assert_eq!(e.load(), 0.0);
        let s = *e.model().state();
        assert_eq!((s.q, s.steps), (start.q, 3));
        assert!(s.v.iter().all(|v| *v == 0.0));
        let y = e.predicted_measurement(0.0);
        let next = e.update(0.0, y).expect("an ordinary sample");
        assert_eq!(next.report.outcome, crate::Outcome::Converged);
        assert_eq!(e.model().state().steps, 4);
    }

    /// With a zero gain the estimator is the model: its state after a sample is a plain step's.
    #[test]
    fn zero_gain_estimator_is_the_model() {
        let mut e = Estimator::new(arm_model(), gain(1.0), section(), 20.0).expect("valid");
        let mut m = arm_model();
        for _ in 0..50 {
            e.update(0.1, 0.3).expect("sample");
            m.step_with_loads(0.1, &Loads::zero()).expect("step");
        }
        assert_eq!(e.model().state(), m.state());
    }
}
