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
    /// The free ball may leave the track ([`crate::flight`]; at run time also
    /// `ball.flight`). A scene without it compiles the flight code out.
    const FLIGHT: bool = false;
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
    const NAME: &'static str = S::NAME;
    type Data<T: Real, const N: usize> = ArmData<T, N>;
}
