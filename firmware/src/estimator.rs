//! `fw-estimator`: the root-stress estimator of the mast arm (`absorber_core::estimator`,
//! `Arm<BeamOnly>`, N = 3, f32, the twin experiment's calibrated model and gain from
//! [`crate::estimator_gain`]) fed every sample a synthetic tip accelerometer reading: 1 m/s² at
//! the arm's 1.03 Hz plus a 20 mg bias, computed in `f32` with `libm` (the same on the host and
//! the target). `Sim::step` is one sample of the monitor: `Estimator::update` (the model step
//! with the estimated load, the innovation and the correction), then the estimated root stress
//! into the fatigue counter (`StressDamage`: rainflow and Miner on the arm's detail category).

use crate::estimator_gain as g;
use crate::{Setup, Sim};
use absorber_core::estimator::{Estimator, Gain};
use absorber_core::loads::{ArmParams, PointMass, MAX_POINT_MASSES};
use absorber_core::monitor::stress::RootSection;
use absorber_core::monitor::StressDamage;
use absorber_core::{Arm, BeamOnly, Error, Model, Params, StepReport};
use core::mem::MaybeUninit;
use nalgebra::SVector;

/// Stress points the fatigue counter keeps (the rainflow residue), fixed at compile time.
pub const RESIDUE: usize = 128;

/// The estimator and the fatigue counter fed by its root stress.
pub struct EstimatorSim {
    est: Estimator<f32, Arm<BeamOnly>, 3, 12>,
    damage: StressDamage<f32, RESIDUE>,
    k: u32,
}

/// The synthetic measurement at sample `k` \[m/s²\].
#[inline(never)]
pub fn tip_accel(k: u32, h: f32) -> f32 {
    let omega = 2.0 * core::f32::consts::PI * 1.03;
    libm::sinf(omega * k as f32 * h) + 0.196
}

fn params() -> Params<f32> {
    let mut p = Params::<f32>::default();
    let [length, mass, area, modulus, inertia] = g::BEAM;
    p.beam.length = length;
    p.beam.mass = mass;
    p.beam.area = area;
    p.beam.modulus = modulus;
    p.beam.inertia = inertia;
    let [gamma, beta, alpha_m, alpha_f, step, tolerance] = g::INTEGRATOR;
    p.integrator.gamma = gamma;
    p.integrator.beta = beta;
    p.integrator.alpha_m = alpha_m;
    p.integrator.alpha_f = alpha_f;
    p.integrator.step = step;
    p.integrator.tolerance = tolerance;
    // The free ball's deadline, not this run's hardest step (23 units) plus the reserve: with
    // 25 units the arm, rung by one 8 g sample, needs two refreshed iterations a step for tens
    // of steps and is capped for all of them (docs/embedded.md, "Firmware defaults").
    p.integrator.max_work = absorber_core::work::DEADLINE;
    let [c, factor, gravity] = g::DAMPING_CALIBRATION_GRAVITY;
    p.damping.stiffness_proportional = c;
    p.calibration.bending_stiffness = factor;
    p.calibration.bending_gradient = g::BENDING_GRADIENT;
    p.gravity = gravity;
    p
}

fn arm() -> ArmParams<f32> {
    let [root_diameter, tip_diameter, wall, density] = g::ARM;
    let mut point_masses = [PointMass {
        position: 0.0,
        mass: 0.0,
    }; MAX_POINT_MASSES];
    for (d, (position, mass)) in point_masses.iter_mut().zip(g::POINT_MASSES) {
        *d = PointMass { position, mass };
    }
    ArmParams {
        root_diameter,
        tip_diameter,
        wall,
        density,
        point_masses,
    }
}

fn section() -> RootSection<f32> {
    let [bending_rigidity, stress_per_curvature, extreme_fibre] = g::SECTION;
    RootSection {
        bending_rigidity,
        stress_per_curvature,
        extreme_fibre,
    }
}

fn gain() -> Gain<f32, 12> {
    let [load, load_decay, bias, stress_sd, load_sd, innovation_sd] = g::GAIN_SCALARS;
    Gain {
        q: SVector::from(g::GAIN_Q),
        v: SVector::from(g::GAIN_V),
        a: SVector::from(g::GAIN_A),
        pseudo_accel: SVector::from(g::GAIN_PA),
        load,
        load_decay,
        bias,
        stress_sd,
        load_sd,
        innovation_sd,
    }
}

impl Sim for EstimatorSim {
    fn name() -> &'static str {
        "mast-arm estimator"
    }

    fn init() -> Result<Self, Error> {
        let model = Model::arm_at_rest(params(), &arm(), 0.0)?;
        let mut est = Estimator::new(model, gain(), section(), g::RANGE)?;
        let h = est.model().params().integrator.step;
        est.initialize_bias(0.0, tip_accel(0, h))?;
        let damage = StressDamage::new(g::CATEGORY)?;
        Ok(Self { est, damage, k: 0 })
    }

    /// The estimator in place (`Estimator::new_in`: its model built in it, the arm's sections,
    /// the static solve and the start at rest), then the fatigue counter beside it: no model
    /// and no estimator pass through the stack (`docs/embedded.md`, boot RAM).
    fn init_in<'a>(slot: &'a mut MaybeUninit<Self>, setup: &Setup) -> Result<&'a mut Self, Error> {
        let _ = setup;
        let start = |m: &mut Model<f32, Arm<BeamOnly>, 3, 12>| {
            m.set_arm(&arm())?;
            m.solve_static()?;
            m.restart(0.0)
        };
        let est = Estimator::new_in(
            field!(slot, est),
            params(),
            start,
            gain(),
            section(),
            g::RANGE,
        )?;
        let h = est.model().params().integrator.step;
        est.initialize_bias(0.0, tip_accel(0, h))?;
        damage_in(field!(slot, damage))?;
        field!(slot, k).write(0u32);
        // SAFETY: every field was just initialized.
        Ok(unsafe { slot.assume_init_mut() })
    }

    #[inline(never)]
    fn step(&mut self, base_accel: f32) -> Result<StepReport<f32>, Error> {
        let k = self.k.wrapping_add(1);
        let y = tip_accel(k, self.h());
        let e = self.est.update(base_accel, y)?;
        self.damage.push(self.est.root_stress(), &mut |_| {})?;
        self.k = k;
        Ok(e.report)
    }

    fn h(&self) -> f32 {
        self.est.model().params().integrator.step
    }

    fn work_cap(&self) -> u32 {
        self.est.model().params().integrator.max_work
    }

    fn tip(&self) -> f32 {
        self.est.model().tip_deflection()
    }

    fn ball(&self) -> f32 {
        0.0
    }

    fn static_tip(&self) -> f32 {
        self.est.model().static_tip_deflection()
    }

    /// The model's state, then the load and bias estimates, the root stress and the Miner
    /// damage so far (extended and cutoff).
    fn state_words(&self, f: &mut dyn FnMut(u32)) {
        self.est.model().state_words(f);
        f(self.est.load().to_bits());
        f(self.est.bias().to_bits());
        f(self.est.root_stress().to_bits());
        let (extended, cutoff) = self.damage.damage();
        f(extended.to_bits());
        f(cutoff.to_bits());
    }
}

/// The fatigue counter written into `slot`, out of line: its value is built in this frame,
/// which is gone before the boot's deepest point (inlined into the construction, the
/// optimizer kept it under the static solve: boot RAM 4,896 -> 5,424 B once the S–N curve's
/// reference range became a constant).
#[inline(never)]
fn damage_in(slot: &mut MaybeUninit<StressDamage<f32, RESIDUE>>) -> Result<(), Error> {
    slot.write(StressDamage::new(g::CATEGORY)?);
    Ok(())
}
