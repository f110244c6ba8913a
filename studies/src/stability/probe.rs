//! The probes: one interface over the core (every scalar and scene) and the full solver, and
//! the case's solver built from its description.

use super::*;

pub(super) fn magnitude<T: Real>(e: &absorber_core::Energies<T>) -> f64 {
    [
        e.beam_strain,
        e.beam_kinetic,
        e.beam_potential,
        e.tip_kinetic,
        e.tip_potential,
        e.ball_kinetic,
        e.ball_potential,
    ]
    .iter()
    .map(|&x| f64_of(x).abs())
    .sum()
}

/// The core model behind [`Probe`].
pub struct CoreProbe<T: Real, S: Scene, const N: usize, const D: usize>(pub Model<T, S, N, D>);

pub(super) fn f64_of<T: Real>(x: T) -> f64 {
    absorber_core::scalar::to_f64(x)
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Probe for CoreProbe<T, S, N, D> {
    fn step(&mut self, a: f64) -> Result<StepReport<f64>, Error> {
        let r = self.0.step(absorber_core::scalar::lit(a))?;
        Ok(r.to_f64())
    }
    fn step_loaded(&mut self, a: f64, tip: f64, line: &[f64]) -> Result<StepReport<f64>, Error> {
        let lit = absorber_core::scalar::lit::<T>;
        let mut loads = Loads::<T, N>::uniform(lit(tip), T::zero());
        for (d, w) in loads.line_load.iter_mut().zip(line) {
            *d = lit(*w);
        }
        let r = self.0.step_with_loads(lit(a), &loads)?;
        Ok(r.to_f64())
    }
    fn energy(&self) -> f64 {
        f64_of(self.0.energies(T::zero(), T::zero()).total())
    }
    fn momentum(&self) -> f64 {
        f64_of(self.0.vertical_momentum())
    }
    fn energy_magnitude(&self) -> f64 {
        magnitude(&self.0.energies(T::zero(), T::zero()))
    }
    fn accel_energy(&self) -> f64 {
        let mut m = self.0.clone();
        let mut s = *m.state();
        s.v = s.a;
        m.set_state(s);
        let e = m.energies(T::zero(), T::zero());
        f64_of(e.beam_kinetic) + f64_of(e.tip_kinetic) + f64_of(e.ball_kinetic)
    }
    fn epsilon(&self) -> f64 {
        f64_of(T::default_epsilon())
    }
    fn bits(&self) -> (Vec<u64>, bool) {
        let s = self.0.state();
        let mut v: Vec<f64> =
            s.q.iter()
                .chain(s.v.iter())
                .chain(s.a.iter())
                .map(|&x| f64_of(x))
                .collect();
        let finite = v.iter().all(|x| x.is_finite());
        v.push(f64_of(s.time));
        v.push(f64_of(s.base_accel));
        let mut b: Vec<u64> = v.iter().map(|x| x.to_bits()).collect();
        b.push(match s.contact {
            absorber_core::Contact::Off => 0,
            absorber_core::Contact::OnStop(absorber_core::Side::Positive) => 1,
            absorber_core::Contact::OnStop(absorber_core::Side::Negative) => 2,
            absorber_core::Contact::InFlight => 3,
            absorber_core::Contact::Beyond => 4,
        });
        (b, finite)
    }
    fn tip(&self) -> f64 {
        f64_of(self.0.tip_deflection())
    }
    fn static_tip(&self) -> f64 {
        f64_of(self.0.static_tip_deflection())
    }
    fn alpha(&self) -> f64 {
        self.0
            .ball_relative_angle()
            .map(|(a, _)| f64_of(a))
            .unwrap_or(f64::NAN)
    }
    fn balance(&self) -> Option<&dyn Balance> {
        Some(self)
    }
}

impl<T: Real, S: Scene, const N: usize, const D: usize> CoreProbe<T, S, N, D> {
    /// The model's kinetic energy `½ zᵀ M z` at velocities `z` (the current configuration).
    fn kinetic_of(&self, z: &[f64]) -> f64 {
        let mut m = self.0.clone();
        let mut s = *m.state();
        for (d, x) in s.v.iter_mut().zip(z) {
            *d = absorber_core::scalar::lit(*x);
        }
        m.set_state(s);
        let e = m.energies(T::zero(), T::zero());
        f64_of(e.beam_kinetic) + f64_of(e.tip_kinetic) + f64_of(e.ball_kinetic)
    }
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Balance for CoreProbe<T, S, N, D> {
    fn coordinates(&self) -> Vec<f64> {
        self.0.state().q.iter().map(|&x| f64_of(x)).collect()
    }
    fn filter_lag(&self) -> Vec<f64> {
        let s = self.0.state();
        if self.0.params().integrator.is_newmark() {
            return vec![0.0; D];
        }
        s.pseudo_accel
            .iter()
            .zip(s.a.iter())
            .map(|(&p, &a)| f64_of(p) - f64_of(a))
            .collect()
    }
    fn load_vector(&self, tip: f64, line: &[f64]) -> Vec<f64> {
        let mut f = vec![0.0; D];
        for (k, w) in line.iter().enumerate().take(N) {
            // The element's own length (an arm's section, or the uniform beam's).
            let element = match self.0.section(k) {
                Some(sec) => sec.beam.element,
                None => {
                    let p = self.0.params();
                    absorber_core::shared::Element::of_beam(&p.beam, &p.calibration, N)
                }
            };
            let q = element.line_load_force(absorber_core::scalar::lit::<T>(*w));
            for (i, x) in q.iter().enumerate() {
                if let Some(d) =
                    absorber_core::shared::global_index(k, i).and_then(|g| f.get_mut(g))
                {
                    *d += f64_of(*x);
                }
            }
        }
        if let Some(d) = f.get_mut(4 * N - 3) {
            *d += tip;
        }
        f
    }
    fn mass_inner(&self, x: &[f64], y: &[f64]) -> f64 {
        // Polarization, `xᵀ M y = (T(x + y) − T(x − y)) / 2`, with y scaled to x's size so
        // that f32 does not lose the small one in the sum.
        let norm = |z: &[f64]| z.iter().map(|a| a * a).sum::<f64>().sqrt();
        let (nx, ny) = (norm(x), norm(y));
        if nx == 0.0 || ny == 0.0 {
            return 0.0;
        }
        let c = nx / ny;
        let plus: Vec<f64> = x.iter().zip(y).map(|(a, b)| a + c * b).collect();
        let minus: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - c * b).collect();
        (self.kinetic_of(&plus) - self.kinetic_of(&minus)) / (2.0 * c)
    }
    fn pseudo_accel_energy(&self) -> f64 {
        let a: Vec<f64> = self
            .0
            .state()
            .pseudo_accel
            .iter()
            .map(|&x| f64_of(x))
            .collect();
        self.kinetic_of(&a)
    }
}

/// The full solver behind [`Probe`].
pub struct FullProbe {
    /// The solver.
    pub solver: FullSolver,
    /// Scene (for the momentum's bodies).
    pub bodies: Bodies,
    /// Its parameters.
    pub params: Params<f64>,
    /// The loads held since the last successful step (`None`: none yet).
    pub held: Option<(f64, Vec<f64>)>,
}

impl FullProbe {
    /// Vertical momentum relative to the base from the maximal coordinates: the solver's mass
    /// matrix applied to a rigid vertical translation `r` (`rᵀ M ż`: `∫ ρ a ẏ dx` of each
    /// element's own section and heads, plus `m_t Ṙ_t2 + m_b Ṙ_b2`).
    pub fn vertical_momentum(&self) -> f64 {
        let s = self.solver.state();
        let n = self.solver.elements();
        let mut lift = vec![0.0; s.v.len()];
        for k in 0..=n {
            lift[4 * k + 1] = 1.0;
        }
        let b0 = 4 * (n + 1);
        for i in [b0 + 1, b0 + 5] {
            if let Some(x) = lift.get_mut(i) {
                *x = 1.0;
            }
        }
        self.solver.mass_inner(&lift, &s.v)
    }
}

impl Probe for FullProbe {
    fn step(&mut self, a: f64) -> Result<StepReport<f64>, Error> {
        self.solver.step(a)
    }
    fn step_loaded(&mut self, a: f64, tip: f64, line: &[f64]) -> Result<StepReport<f64>, Error> {
        self.solver.set_loads(tip, line)?;
        let r = self.solver.step(a);
        match (&r, &self.held) {
            // A failed step keeps its state; the held loads go back too (as the core's
            // `step_with_loads`).
            (Err(_), Some((t, l))) => self.solver.set_loads(*t, l)?,
            (Err(_), None) => self.solver.set_loads(0.0, &vec![0.0; line.len()])?,
            (Ok(_), _) => self.held = Some((tip, line.to_vec())),
        }
        r
    }
    fn energy(&self) -> f64 {
        Simulator::energies(&self.solver, 0.0, 0.0).total()
    }
    fn momentum(&self) -> f64 {
        self.vertical_momentum()
    }
    fn energy_magnitude(&self) -> f64 {
        magnitude(&Simulator::energies(&self.solver, 0.0, 0.0))
    }
    fn accel_energy(&self) -> f64 {
        let a = &self.solver.state().a;
        0.5 * self.solver.mass_inner(a, a)
    }
    fn epsilon(&self) -> f64 {
        f64::EPSILON
    }
    fn bits(&self) -> (Vec<u64>, bool) {
        let s = self.solver.state();
        let finite = s.q.iter().chain(&s.v).chain(&s.a).all(|x| x.is_finite());
        let mut b: Vec<u64> =
            s.q.iter()
                .chain(&s.v)
                .chain(&s.a)
                .chain([s.time, s.base_accel, s.theta_ref].iter())
                .map(|x| x.to_bits())
                .collect();
        b.push(match s.contact {
            absorber_core::Contact::Off => 0,
            absorber_core::Contact::OnStop(absorber_core::Side::Positive) => 1,
            absorber_core::Contact::OnStop(absorber_core::Side::Negative) => 2,
            absorber_core::Contact::InFlight => 3,
            absorber_core::Contact::Beyond => 4,
        });
        (b, finite)
    }
    fn tip(&self) -> f64 {
        self.solver.observe().tip_deflection
    }
    fn static_tip(&self) -> f64 {
        Simulator::static_tip_deflection(&self.solver)
    }
    fn alpha(&self) -> f64 {
        match self.bodies {
            Bodies::Free => self.solver.observe().ball_relative_angle,
            Bodies::Locked | Bodies::Arm => f64::NAN,
        }
    }
    fn balance(&self) -> Option<&dyn Balance> {
        Some(self)
    }
}

/// In the maximal coordinates `z` (full/balance.rs: on an arm the clamp is the only
/// constraint, so the balance is the core's in the same free coordinates).
impl Balance for FullProbe {
    fn coordinates(&self) -> Vec<f64> {
        self.solver.state().q.clone()
    }
    fn filter_lag(&self) -> Vec<f64> {
        self.solver.filter_lag()
    }
    fn load_vector(&self, tip: f64, line: &[f64]) -> Vec<f64> {
        self.solver.load_vector(tip, line)
    }
    fn mass_inner(&self, x: &[f64], y: &[f64]) -> f64 {
        self.solver.mass_inner(x, y)
    }
    fn pseudo_accel_energy(&self) -> f64 {
        self.solver.pseudo_accel_energy()
    }
}

pub(super) fn boxed<T: Real + 'static, S: Scene + 'static, const N: usize, const D: usize>(
    p: Params<T>,
    a0: T,
) -> Result<Box<dyn Probe>, Error> {
    // Built on the heap directly would need unsafe; the model is moved once (large N: run in a
    // thread with a big stack, see [`run_case`]).
    Ok(Box::new(CoreProbe(Model::<T, S, N, D>::at_rest(p, a0)?)))
}

macro_rules! by_elements {
    ($t:ty, $s:ty, $x:tt, $n:expr, $p:expr, $a:expr) => {
        absorber_sim::with_elements!(
            $n,
            [1, 2, 3, 16, 64],
            $x,
            boxed[$t, $s]($p, $a),
            Err(Error::InvalidParameter {
                field: "elements",
                reason: "stability cases: 1, 2, 3, 16, 64",
            })
        )
    };
}

pub(super) fn locked<T: Real + 'static>(
    n: usize,
    p: Params<T>,
    a0: T,
) -> Result<Box<dyn Probe>, Error> {
    absorber_sim::with_elements!(
        n,
        [3],
        0,
        boxed[T, LockedBall](p, a0),
        Err(Error::InvalidParameter {
            field: "elements",
            reason: "locked stability cases: 3",
        })
    )
}

/// The core model of a bare arm (N = 3, the monitor's model) at rest.
pub(super) fn arm_core<T: Real + 'static>(
    n: usize,
    p: Params<T>,
    arm: &ArmParams<f64>,
    a0: T,
) -> Result<Box<dyn Probe>, Error> {
    if n != 3 {
        return Err(Error::InvalidParameter {
            field: "elements",
            reason: "arm stability cases: 3",
        });
    }
    let m = Model::<T, Arm<BeamOnly>, 3, 12>::arm_at_rest(
        p,
        &absorber_sim::core_sim::cast_arm(arm),
        a0,
    )?;
    Ok(Box::new(CoreProbe(m)))
}

/// The case's parameters in `f32`, with its Newton variant and budget rule.
pub(super) fn f32_params(case: &Case) -> Params<f32> {
    let p = absorber_sim::core_sim::params_f32(&case.params);
    Params {
        integrator: absorber_core::Integrator {
            newton: case.params.integrator.newton,
            accept_after_budget: case.params.integrator.accept_after_budget,
            ..p.integrator
        },
        ..p
    }
}

/// Builds the probe of a case at rest with input `a0` at t = 0.
pub fn build(case: &Case, a0: f64) -> Result<Box<dyn Probe>, Error> {
    let p = case.params;
    if case.bodies == Bodies::Arm {
        let arm = &case
            .arm
            .as_ref()
            .ok_or(Error::InvalidParameter {
                field: "arm",
                reason: "an arm case needs the arm and its loads",
            })?
            .arm;
        return match case.engine {
            Engine::CoreF64 => arm_core::<f64>(case.elements, p, arm, a0),
            Engine::CoreF32 => arm_core::<f32>(case.elements, f32_params(case), arm, a0 as f32),
            Engine::Full => Ok(Box::new(FullProbe {
                solver: FullSolver::arm_at_rest(p, SceneKind::BeamOnly, case.elements, arm, a0)?,
                bodies: case.bodies,
                params: p,
                held: None,
            })),
        };
    }
    match case.engine {
        Engine::CoreF64 => match case.bodies {
            Bodies::Free => by_elements!(f64, FreeBall, 1, case.elements, p, a0),
            Bodies::Locked => locked::<f64>(case.elements, p, a0),
            Bodies::Arm => unreachable_arm(),
        },
        Engine::CoreF32 => {
            let p = f32_params(case);
            let a0 = a0 as f32;
            match case.bodies {
                Bodies::Free => by_elements!(f32, FreeBall, 1, case.elements, p, a0),
                Bodies::Locked => locked::<f32>(case.elements, p, a0),
                Bodies::Arm => unreachable_arm(),
            }
        }
        Engine::Full => {
            let kind = match case.bodies {
                Bodies::Free => SceneKind::FreeBall,
                Bodies::Locked => SceneKind::LockedBall,
                Bodies::Arm => return unreachable_arm(),
            };
            Ok(Box::new(FullProbe {
                solver: FullSolver::at_rest(p, kind, case.elements, a0)?,
                bodies: case.bodies,
                params: p,
                held: None,
            }))
        }
    }
}

/// Arm cases return from [`build`] before the paper scenes' match.
pub(super) fn unreachable_arm() -> Result<Box<dyn Probe>, Error> {
    Err(Error::InvalidParameter {
        field: "arm",
        reason: "arm cases are built by their own branch",
    })
}
