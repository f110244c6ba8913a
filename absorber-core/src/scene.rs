//! Scenes compose at compile time: what a scene does not have costs neither code nor unknowns.
//!
//! A scene is a zero-sized marker type. Its associated constants are known to the compiler, so
//! every `if S::HAS_BALL { … }` in the model is folded away: the beam-only scene's binary holds
//! no tip or ball code, and only [`FreeBall`] scenes have an extra unknown (the ball spin φ).
//!
//! The number of unknowns `D` is checked at compile time: a free ball has `4N + 1`.
//!
//! ```
//! use absorber_core::{FreeBallModel, LockedBallModel, Params};
//! assert!(FreeBallModel::<f64, 3, 13>::new(Params::default()).is_ok());
//! assert!(LockedBallModel::<f64, 3, 12>::new(Params::default()).is_ok());
//! ```
//!
//! ```compile_fail
//! use absorber_core::{FreeBallModel, Params};
//! // 12 unknowns cannot hold a free ball on 3 elements (4·3 + 1 = 13): rejected at build time.
//! let _ = FreeBallModel::<f64, 3, 12>::new(Params::default());
//! ```
//!
//! ```compile_fail
//! use absorber_core::{BeamModel, Params};
//! // A beam needs at least one element.
//! let _ = BeamModel::<f64, 0, 0>::new(Params::default());
//! ```

use crate::loads::{ArmData, Loads, SceneData};
use crate::scalar::Real;
use core::marker::PhantomData;

/// How the ball is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BallKind {
    /// No ball.
    None,
    /// Ball fixed in the housing at the bottom of the track (θ = ψ; the paper's passive case).
    Locked,
    /// Ball rolling freely in the track (one extra unknown, the orbit angle θ).
    Free,
}

/// A scene: which bodies the model contains.
pub trait Scene: Copy + Default + 'static {
    /// The tip mass is welded to the beam end.
    const HAS_TIP: bool;
    /// The ball.
    const BALL: BallKind;
    /// The ±stop angle is enforced (free ball only).
    const STOPS: bool;
    /// The free ball may leave the track (`flight`; at run time also
    /// `ball.flight`). A scene without it compiles the flight code out.
    const FLIGHT: bool = false;
    /// The perfectly elastic ball's rules are compiled in (`ball.restitution` 1 with events at
    /// their crossings: energy-exact impulses, every flight event split at its crossing;
    /// `docs/model.md`, "Elastic bounces at the paper's step"). A scene without them
    /// ([`Lean`]) links none of that code and rejects, at construction, the parameters that
    /// would take it: restitution 1 with [`EventLocation::Crossing`](crate::EventLocation).
    /// Every other run is the same, bit for bit.
    const ELASTIC_RULES: bool = true;
    /// Events at their crossings are compiled in ([`EventLocation::Crossing`](crate::EventLocation):
    /// the step redone to the crossing, the event, the rest). A scene without them
    /// ([`AtStepEnd`]) puts every event at the end of its step and rejects, at construction,
    /// parameters with events at their crossings. Every other run is the same, bit for bit.
    const EVENTS_AT_CROSSING: bool = true;
    /// The generalized-α scheme is compiled in (`integrator.alpha_m`, `alpha_f` not zero:
    /// [`crate::Integrator::generalized_alpha`]). A scene without it ([`Lean`]) is Newmark's
    /// method only and rejects other parameters at construction; its Newmark runs are the same,
    /// bit for bit.
    const GENERALIZED_ALPHA: bool = true;
    /// Unknowns the scene adds after the 4N beam coordinates.
    const EXTRA_DOFS: usize = if matches!(Self::BALL, BallKind::Free) {
        1
    } else {
        0
    };
    /// Short name for reports.
    const NAME: &'static str;
    /// What the model stores beyond the paper's scene ([`crate::loads::SceneData`]): `()` for
    /// the paper's scenes (nothing: their RAM, flash and results are unchanged), the loads for
    /// [`Loaded`], loads and per-element sections for [`Arm`].
    type Data<T: Real, const N: usize>: SceneData<T, N>;
}

/// The cantilever alone.
#[derive(Clone, Copy, Debug, Default)]
pub struct BeamOnly;
impl Scene for BeamOnly {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = false;
    const BALL: BallKind = BallKind::None;
    const STOPS: bool = false;
    const NAME: &'static str = "beam";
}

/// Cantilever + rigid tip mass (no ball).
#[derive(Clone, Copy, Debug, Default)]
pub struct TipMass;
impl Scene for TipMass {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = true;
    const BALL: BallKind = BallKind::None;
    const STOPS: bool = false;
    const NAME: &'static str = "tip";
}

/// Cantilever + tip mass + ball locked in its housing (the paper's passive absorber).
#[derive(Clone, Copy, Debug, Default)]
pub struct LockedBall;
impl Scene for LockedBall {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = true;
    const BALL: BallKind = BallKind::Locked;
    const STOPS: bool = false;
    const NAME: &'static str = "locked";
}

/// Cantilever + tip mass + free ball with the ±stops (the paper's active absorber).
#[derive(Clone, Copy, Debug, Default)]
pub struct FreeBall;
impl Scene for FreeBall {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = true;
    const BALL: BallKind = BallKind::Free;
    const STOPS: bool = true;
    const FLIGHT: bool = true;
    const NAME: &'static str = "free";
}

/// Free ball with stops held on its track by any force (the paper's bilateral track: no
/// flight). Bit-identical to [`FreeBall`] with `ball.flight = false`.
#[derive(Clone, Copy, Debug, Default)]
pub struct FreeBallNoFlight;
impl Scene for FreeBallNoFlight {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = true;
    const BALL: BallKind = BallKind::Free;
    const STOPS: bool = true;
    const NAME: &'static str = "free-noflight";
}

/// Free ball without stops (the track is a full circle).
#[derive(Clone, Copy, Debug, Default)]
pub struct FreeBallNoStops;
impl Scene for FreeBallNoStops {
    type Data<T: Real, const N: usize> = ();
    const HAS_TIP: bool = true;
    const BALL: BallKind = BallKind::Free;
    const STOPS: bool = false;
    const FLIGHT: bool = true;
    const NAME: &'static str = "free-nostops";
}

/// Scene `S` with external loads on the beam ([`crate::loads::Loads`], fed per sample by
/// [`crate::Model::step_with_loads`]): the same bodies and unknowns as `S`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Loaded<S>(PhantomData<S>);
impl<S: Scene> Scene for Loaded<S> {
    const HAS_TIP: bool = S::HAS_TIP;
    const BALL: BallKind = S::BALL;
    const STOPS: bool = S::STOPS;
    const FLIGHT: bool = S::FLIGHT;
    const ELASTIC_RULES: bool = S::ELASTIC_RULES;
    const EVENTS_AT_CROSSING: bool = S::EVENTS_AT_CROSSING;
    const GENERALIZED_ALPHA: bool = S::GENERALIZED_ALPHA;
    const NAME: &'static str = S::NAME;
    type Data<T: Real, const N: usize> = Loads<T, N>;
}

/// Scene `S` on a real arm: external loads and per-element sections (a tapered tube with
/// point masses, [`crate::loads::ArmParams`], set by [`crate::Model::with_arm`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Arm<S>(PhantomData<S>);
impl<S: Scene> Scene for Arm<S> {
    const HAS_TIP: bool = S::HAS_TIP;
    const BALL: BallKind = S::BALL;
    const STOPS: bool = S::STOPS;
    const FLIGHT: bool = S::FLIGHT;
    const ELASTIC_RULES: bool = S::ELASTIC_RULES;
    const EVENTS_AT_CROSSING: bool = S::EVENTS_AT_CROSSING;
    const GENERALIZED_ALPHA: bool = S::GENERALIZED_ALPHA;
    const NAME: &'static str = S::NAME;
    type Data<T: Real, const N: usize> = ArmData<T, N>;
}

/// Scene `S` with only what a firmware's configuration takes compiled in: the same bodies,
/// unknowns and arithmetic, without the code of run-time options its parameters never choose
/// (those parameters are rejected at construction instead): the perfectly elastic ball's rules
/// ([`Scene::ELASTIC_RULES`]) and the generalized-α scheme ([`Scene::GENERALIZED_ALPHA`]). Every run it accepts is bit for bit the run of `S`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Lean<S>(PhantomData<S>);
impl<S: Scene> Scene for Lean<S> {
    const HAS_TIP: bool = S::HAS_TIP;
    const BALL: BallKind = S::BALL;
    const STOPS: bool = S::STOPS;
    const FLIGHT: bool = S::FLIGHT;
    const ELASTIC_RULES: bool = false;
    const EVENTS_AT_CROSSING: bool = S::EVENTS_AT_CROSSING;
    const GENERALIZED_ALPHA: bool = false;
    const NAME: &'static str = S::NAME;
    type Data<T: Real, const N: usize> = S::Data<T, N>;
}

/// [`Lean`] with every event at the end of its step ([`Scene::EVENTS_AT_CROSSING`] off): the
/// code of events at their crossings is left out too (the firmware's scenes, which run with
/// [`EventLocation::StepEnd`](crate::EventLocation); the pole monitor's own scene keeps it for
/// the simulated pole its sensor reads). Every run it accepts is bit for bit the run of `S`.
#[derive(Clone, Copy, Debug, Default)]
pub struct AtStepEnd<S>(PhantomData<S>);
impl<S: Scene> Scene for AtStepEnd<S> {
    const HAS_TIP: bool = S::HAS_TIP;
    const BALL: BallKind = S::BALL;
    const STOPS: bool = S::STOPS;
    const FLIGHT: bool = S::FLIGHT;
    const ELASTIC_RULES: bool = false;
    const EVENTS_AT_CROSSING: bool = false;
    const GENERALIZED_ALPHA: bool = false;
    const NAME: &'static str = S::NAME;
    type Data<T: Real, const N: usize> = S::Data<T, N>;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EventLocation, Model, Params};

    /// The paper's free ball at ten times its amplitude, perfectly elastic (`e = e_n = 1`),
    /// events at the step end: `AtStepEnd<FreeBall>` (and `Lean<FreeBall>`) run it exactly as
    /// `FreeBall` does, every state bit for bit, with impacts and flights in the run.
    #[test]
    fn lean_scenes_run_the_same_steps_bit_for_bit() {
        let mut p = Params::<f32>::default();
        p.integrator.events = EventLocation::StepEnd;
        p.ball.restitution = 1.0;
        p.ball.landing_restitution = 1.0;
        let mut full = Model::<f32, FreeBall, 3, 13>::at_rest(p, 0.0).unwrap();
        let mut end = Model::<f32, AtStepEnd<FreeBall>, 3, 13>::at_rest(p, 0.0).unwrap();
        let mut lean = Model::<f32, Lean<FreeBall>, 3, 13>::at_rest(p, 0.0).unwrap();
        let omega = 2.0 * core::f32::consts::PI * 4.13;
        let mut events = 0u32;
        for k in 1..=1500u32 {
            let t = k as f32 * p.integrator.step;
            let ya = -5.0e-3 * omega * omega * libm::sinf(omega * t);
            let r = full.step(ya);
            assert_eq!(r, end.step(ya));
            assert_eq!(r, lean.step(ya));
            if let Ok(r) = r {
                events += u32::from(r.events.impacts) + u32::from(r.impact.is_some());
            }
            for m in [end.state(), lean.state()] {
                let s = full.state();
                for (a, b) in
                    s.q.iter()
                        .chain(s.v.iter())
                        .zip(m.q.iter().chain(m.v.iter()))
                {
                    assert_eq!(a.to_bits(), b.to_bits(), "step {k}");
                }
                assert_eq!(s.contact, m.contact);
            }
        }
        assert!(events > 0, "the run has no impact");
    }

    /// A scene without a run-time option rejects the parameters that would take it.
    #[test]
    fn lean_scenes_reject_what_they_leave_out() {
        let p = Params::<f32>::default();
        assert_eq!(p.integrator.events, EventLocation::Crossing);
        assert!(Model::<f32, AtStepEnd<FreeBall>, 3, 13>::new(p).is_err());
        assert!(Model::<f32, Lean<FreeBall>, 3, 13>::new(p).is_ok());
        let mut elastic = p;
        elastic.ball.restitution = 1.0;
        assert!(Model::<f32, FreeBall, 3, 13>::new(elastic).is_ok());
        assert!(Model::<f32, Lean<FreeBall>, 3, 13>::new(elastic).is_err());
        let mut alpha = p;
        alpha.integrator = alpha.integrator.generalized_alpha(0.8);
        assert!(Model::<f32, FreeBall, 3, 13>::new(alpha).is_ok());
        assert!(Model::<f32, Lean<FreeBall>, 3, 13>::new(alpha).is_err());
    }
}
