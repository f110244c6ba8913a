//! The embedded core behind the [`Simulator`] trait, with the scene kind, the number of elements
//! and the scalar chosen at run time (the core fixes them at compile time: a macro instantiates
//! every supported combination).

use crate::scene::{Kind, Precision};
use absorber_core::{
    BallParams, BeamOnly, BeamParams, Calibration, Damping, Energies, Error, FreeBall,
    FreeBallNoStops, Integrator, LockedBall, Model, Params, Real, Scene, StepReport, TipMass,
    TipParams,
};
use absorber_full::sim::{Observation, Simulator};

/// A core model of any scene, size and scalar.
pub struct CoreSim<T: Real, S: Scene, const N: usize, const D: usize> {
    model: Model<T, S, N, D>,
    /// Static tip deflection \[m\] (kept apart: a model booted by [`Start::BootConverged`]
    /// has no equilibrium of its own).
    static_tip: f64,
}

/// How [`build_from`] starts a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// `Model::at_rest` with the given parameters.
    AtRest,
    /// As `AtRest`, except with a fixed Newton budget (`accept_after_budget`): the static and
    /// consistent-acceleration solves of `at_rest` obey `max_iterations` too but never accept
    /// the budget, so a budget of 1–3 fails there. Such a model boots with the converged solver
    /// (as firmware would, once) and continues from that state with the budget; its
    /// `equilibrium()` (energies, `natural_frequencies`) is then not set.
    BootConverged,
}

fn f64_of<T: Real>(x: T) -> f64 {
    absorber_core::scalar::to_f64(x)
}

fn energies_f64<T: Real>(e: Energies<T>) -> Energies<f64> {
    Energies {
        beam_strain: f64_of(e.beam_strain),
        beam_kinetic: f64_of(e.beam_kinetic),
        beam_potential: f64_of(e.beam_potential),
        tip_kinetic: f64_of(e.tip_kinetic),
        tip_potential: f64_of(e.tip_potential),
        ball_kinetic: f64_of(e.ball_kinetic),
        ball_potential: f64_of(e.ball_potential),
    }
}

impl<T: Real + Send, S: Scene + Send, const N: usize, const D: usize> Simulator
    for CoreSim<T, S, N, D>
{
    fn step(&mut self, base_accel: f64) -> Result<StepReport<f64>, Error> {
        let r = self.model.step(absorber_core::scalar::lit(base_accel))?;
        Ok(r.to_f64())
    }

    fn observe(&self) -> Observation {
        let m = &self.model;
        let (psi, psi_dot) = m.tip_angle();
        let (th, thd) = m
            .ball_angle()
            .map(|(a, b)| (f64_of(a), f64_of(b)))
            .unwrap_or((f64::NAN, f64::NAN));
        let (al, ald) = m
            .ball_relative_angle()
            .map(|(a, b)| (f64_of(a), f64_of(b)))
            .unwrap_or((f64::NAN, f64::NAN));
        Observation {
            time: f64_of(m.time()),
            tip_deflection: f64_of(m.tip_deflection()),
            tip_velocity: f64_of(m.tip_velocity()),
            tip_acceleration: m.state().a.get(4 * N - 3).map_or(f64::NAN, |&a| f64_of(a)),
            tip_angle: f64_of(psi),
            tip_rate: f64_of(psi_dot),
            ball_angle: th,
            ball_rate: thd,
            ball_relative_angle: al,
            ball_relative_rate: ald,
        }
    }

    fn in_flight(&self) -> bool {
        self.model.in_flight()
    }

    fn contact_forces(&self) -> Option<(f64, f64)> {
        self.model
            .contact_forces()
            .map(|c| (f64_of(c.normal), f64_of(c.tangential)))
    }

    fn energies(&self, base_velocity: f64, base_displacement: f64) -> Energies<f64> {
        let lit = absorber_core::scalar::lit::<T>;
        energies_f64(
            self.model
                .energies(lit(base_velocity), lit(base_displacement)),
        )
    }

    fn natural_frequencies(&self) -> Result<Vec<f64>, Error> {
        Ok(self
            .model
            .natural_frequencies()?
            .iter()
            .map(|&f| f64_of(f))
            .collect())
    }

    fn static_tip_deflection(&self) -> f64 {
        self.static_tip
    }

    fn solver_name(&self) -> &'static str {
        "core"
    }

    fn set_ball_rate(&mut self, rate: f64) -> Result<(), Error> {
        set_orbit_rate(&mut self.model, rate)
    }
}

/// At the start of a run (the housing at rest): the rolling ball's orbit rate θ̇ set to `rate`
/// \[rad/s\], i.e. its spin rate `φ̇ = −(ρ/r_b) θ̇` (the last unknown), with the consistent
/// acceleration (`Model::set_configuration`). No effect on a scene without a free ball's spin.
pub fn set_orbit_rate<T: Real, S: Scene, const N: usize, const D: usize>(
    model: &mut Model<T, S, N, D>,
    rate: f64,
) -> Result<(), Error> {
    if S::EXTRA_DOFS != 1 {
        return Ok(());
    }
    let s = *model.state();
    let b = &model.params().ball;
    let mut v = s.v;
    if let Some(spin) = v.get_mut(D - 1) {
        *spin = absorber_core::scalar::lit::<T>(-rate) * b.path_radius() / b.radius;
    }
    model.set_configuration(s.q, v, s.base_accel)
}

/// The arm's parameters in precision `T` (each value rounded to nearest).
pub fn cast_arm<T: absorber_core::Real>(
    a: &absorber_core::ArmParams<f64>,
) -> absorber_core::ArmParams<T> {
    let lit = absorber_core::scalar::lit::<T>;
    absorber_core::ArmParams {
        root_diameter: lit(a.root_diameter),
        tip_diameter: lit(a.tip_diameter),
        wall: lit(a.wall),
        density: lit(a.density),
        point_masses: a.point_masses.map(|m| absorber_core::PointMass {
            position: lit(m.position),
            mass: lit(m.mass),
        }),
    }
}

/// The parameters rounded to `f32`.
pub fn params_f32(p: &Params<f64>) -> Params<f32> {
    let b = &p.ball;
    Params {
        beam: BeamParams {
            length: p.beam.length as f32,
            mass: p.beam.mass as f32,
            area: p.beam.area as f32,
            modulus: p.beam.modulus as f32,
            inertia: p.beam.inertia as f32,
        },
        tip: TipParams {
            mass: p.tip.mass as f32,
            inertia: p.tip.inertia as f32,
            offset: p.tip.offset as f32,
        },
        ball: BallParams {
            mass: b.mass as f32,
            inertia: b.inertia as f32,
            radius: b.radius as f32,
            track_radius: b.track_radius as f32,
            stop_angle: b.stop_angle as f32,
            restitution: b.restitution as f32,
            stick_speed: b.stick_speed as f32,
            initial_angle: b.initial_angle as f32,
            impact_model: b.impact_model,
            stop_contact_time: b.stop_contact_time as f32,
            flight: b.flight,
            landing_restitution: b.landing_restitution as f32,
            min_bounce_time: b.min_bounce_time as f32,
            lift_height: b.lift_height as f32,
        },
        // Every field spelled out: a new field of the core fails to compile here instead of
        // silently keeping its f32 default (generalized-α once did).
        integrator: Integrator {
            gamma: p.integrator.gamma as f32,
            beta: p.integrator.beta as f32,
            alpha_m: p.integrator.alpha_m as f32,
            alpha_f: p.integrator.alpha_f as f32,
            step: p.integrator.step as f32,
            tolerance: p.integrator.tolerance as f32,
            max_iterations: p.integrator.max_iterations,
            newton: p.integrator.newton,
            accept_after_budget: p.integrator.accept_after_budget,
            events: p.integrator.events,
            max_work: p.integrator.max_work,
            at_cap: p.integrator.at_cap,
        },
        damping: Damping {
            stiffness_proportional: p.damping.stiffness_proportional as f32,
        },
        gravity: p.gravity as f32,
        calibration: Calibration {
            bending_stiffness: p.calibration.bending_stiffness as f32,
            axial_stiffness: p.calibration.axial_stiffness as f32,
            mass_lumping: p.calibration.mass_lumping as f32,
            bending_gradient: p.calibration.bending_gradient as f32,
        },
    }
}

fn boxed<T: Real + Send, S: Scene + Send, const N: usize, const D: usize>(
    params: Params<T>,
    base_accel0: T,
    start: Start,
) -> Result<Box<dyn Simulator>, Error> {
    if start == Start::AtRest || !params.integrator.accept_after_budget {
        let model = Model::<T, S, N, D>::at_rest(params, base_accel0)?;
        let static_tip = f64_of(model.static_tip_deflection());
        return Ok(Box::new(CoreSim { model, static_tip }));
    }
    let mut boot = params;
    boot.integrator.max_iterations = Params::<T>::default().integrator.max_iterations;
    boot.integrator.accept_after_budget = false;
    let first = Model::<T, S, N, D>::at_rest(boot, base_accel0)?;
    let mut model = Model::<T, S, N, D>::new(params)?;
    model.set_state(*first.state());
    Ok(Box::new(CoreSim {
        model,
        static_tip: f64_of(first.static_tip_deflection()),
    }))
}

/// The one way to pick the number of beam elements N at compile time: `match`es the run-time
/// `$n` over the listed element counts and calls `$f::<generics…, N, D>(args…)` with
/// D = 4 N + `$extra` (the core's unknowns: 4 per element, plus 1 for a free ball);
/// `$other` for any other count. Used by every command and study that builds core models.
///
/// `with_elements!(n, [1, 3, 8], 1, boxed [f64, FreeBall] (params, a0), Err(...))`
#[macro_export]
macro_rules! with_elements {
    (@call $f:ident [$($g:ty),*] $k:tt $extra:tt ($($arg:expr),*)) => {
        $f::<$($g,)* $k, { 4 * $k + $extra }>($($arg),*)
    };
    ($n:expr, [$($k:tt),*], $extra:tt, $f:ident $gen:tt $args:tt, $other:expr) => {
        match $n {
            $( $k => $crate::with_elements!(@call $f $gen $k $extra $args), )*
            _ => $other,
        }
    };
}

macro_rules! by_elements {
    ($t:ty, $s:ty, $extra:tt, $n:expr, $p:expr, $a:expr, $st:expr) => {
        $crate::with_elements!(
            $n,
            [1, 2, 3, 4, 6, 8, 16],
            $extra,
            boxed[$t, $s]($p, $a, $st),
            Err(Error::InvalidParameter {
                field: "elements",
                reason: "supported: 1, 2, 3, 4, 6, 8, 16",
            })
        )
    };
}

macro_rules! by_kind {
    ($t:ty, $kind:expr, $n:expr, $p:expr, $a:expr, $st:expr) => {
        match $kind {
            Kind::Beam => by_elements!($t, BeamOnly, 0, $n, $p, $a, $st),
            Kind::Tip => by_elements!($t, TipMass, 0, $n, $p, $a, $st),
            Kind::Locked => by_elements!($t, LockedBall, 0, $n, $p, $a, $st),
            Kind::Free => by_elements!($t, FreeBall, 1, $n, $p, $a, $st),
            Kind::FreeNostops => by_elements!($t, FreeBallNoStops, 1, $n, $p, $a, $st),
        }
    };
}

/// Builds the core model of `kind` with `elements` elements in `precision`, at rest in its
/// static equilibrium, with the base acceleration `base_accel0` at t = 0.
pub fn build(
    kind: Kind,
    elements: usize,
    precision: Precision,
    params: &Params<f64>,
    base_accel0: f64,
) -> Result<Box<dyn Simulator>, Error> {
    build_from(
        kind,
        elements,
        precision,
        params,
        base_accel0,
        Start::AtRest,
    )
}

/// As [`build`], started as `start` says.
pub fn build_from(
    kind: Kind,
    elements: usize,
    precision: Precision,
    params: &Params<f64>,
    base_accel0: f64,
    start: Start,
) -> Result<Box<dyn Simulator>, Error> {
    match precision {
        Precision::F64 => by_kind!(f64, kind, elements, *params, base_accel0, start),
        Precision::F32 => by_kind!(
            f32,
            kind,
            elements,
            params_f32(params),
            base_accel0 as f32,
            start
        ),
    }
}
