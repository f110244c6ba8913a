//! What firmware reads back after a step.

use crate::model::Model;

use crate::scalar::Real;
use crate::scene::{BallKind, Scene};
use crate::state::{Contact, State};
use crate::step::tip;

/// The force the track puts on the ball centre, in the track's frame (free-ball scenes).
///
/// With A the beam end (the track's centre), θ the orbit angle from the downward vertical, the
/// inward normal `n = (−sin θ, cos θ)` (from the ball centre towards A) and the tangent
/// `t = (cos θ, sin θ)`, Newton's law for the ball centre `C = A + ρ(sin θ, −cos θ)` in the frame
/// translating with the base (effective gravity `g + ÿ_b`) gives
/// `N = m_b [−ẍ_A sin θ + (ÿ_A + g + ÿ_b) cos θ + ρ θ̇²]` and
/// `F_t = m_b [ẍ_A cos θ + (ÿ_A + g + ÿ_b) sin θ + ρ θ̈]` (docs/model.md, "Contact forces").
/// A bilateral track can pull (`N < 0`); a real one cannot: the ball would leave it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactForces<T> {
    /// Normal force N along n \[N\] (positive: the track pushes the ball towards A).
    pub normal: T,
    /// Tangential force F_t along t \[N\]: friction (rolling without slip needs it), plus the
    /// stop's reaction while the ball rests on a stop.
    pub tangential: T,
}

impl<T: Real> ContactForces<T> {
    /// The friction coefficient rolling needs, `|F_t| / N`; `None` when the track does not
    /// push (`N ≤ 0`: no friction can hold the ball).
    pub fn required_friction(&self) -> Option<T> {
        (self.normal > T::zero()).then(|| self.tangential.abs() / self.normal)
    }
}

/// The angles of one state, each evaluated once: ψ and ψ̇ of the end slope, cos ψ and sin ψ
/// taken from the slope vector itself, `(a₃, a₄)/|a|` (no trigonometric call; the model's
/// step does the same), and the ball's orbit angle θ and θ̇ (`None` without a ball; = ψ for a
/// locked ball). Every output that needs one of them goes through [`Model::angles_of`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Angles<T> {
    /// ψ \[rad\] (`atan2` of the end slope).
    pub psi: T,
    /// ψ̇ \[rad/s\].
    pub psi_rate: T,
    /// cos ψ.
    pub cos_psi: T,
    /// sin ψ.
    pub sin_psi: T,
    /// θ \[rad\] and θ̇ \[rad/s\]; `None` without a ball.
    pub theta: Option<(T, T)>,
    /// θ is ψ (locked ball): its cos and sin are those of ψ.
    theta_is_psi: bool,
}

impl<T: Real> Angles<T> {
    /// (sin θ, cos θ): one `sin_cos`, or none for a locked ball (θ = ψ); `None` without a ball.
    pub fn theta_sin_cos(&self) -> Option<(T, T)> {
        let (theta, _) = self.theta?;
        Some(if self.theta_is_psi {
            (self.sin_psi, self.cos_psi)
        } else {
            theta.fast_sin_cos()
        })
    }

    /// Ball angle relative to the housing α = θ − ψ and its rate; `None` without a ball.
    pub fn ball_relative(&self) -> Option<(T, T)> {
        let (th, thd) = self.theta?;
        Some((th - self.psi, thd - self.psi_rate))
    }
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
    /// The angles of a state (see [`Angles`]): one `atan2` for ψ, and one more (inside
    /// [`tip::orbit_angle`]) for the orbit angle of a free ball.
    pub(crate) fn angles_of(&self, s: &State<T, D>) -> Angles<T> {
        let x = Self::local(&s.q, &s.v, &s.a);
        let rot = tip::tip_rotation(&x);
        let (psi, psi_rate, cos_psi, sin_psi) = (rot.psi, rot.rate, rot.cos, rot.sin);
        let theta = match S::BALL {
            BallKind::None => None,
            BallKind::Locked => Some((psi, psi_rate)),
            BallKind::Free if s.contact == Contact::InFlight => {
                // The flying ball's polar angle about A, on the branch of ψ.
                let (alpha, rate) = self.sys.flight_relative_angle(s);
                Some((psi + alpha, psi_rate + rate))
            }
            BallKind::Free => Some(tip::orbit_angle(&self.sys.inertia, &x)),
        };
        Angles {
            psi,
            psi_rate,
            cos_psi,
            sin_psi,
            theta,
            theta_is_psi: matches!(S::BALL, BallKind::Locked),
        }
    }

    /// Vertical deflection of the beam end A relative to the base (includes the static sag) \[m\].
    pub fn tip_deflection(&self) -> T {
        self.state.q.get(4 * N - 3).copied().unwrap_or(T::zero())
    }

    /// Vertical velocity of the beam end relative to the base \[m/s\].
    pub fn tip_velocity(&self) -> T {
        self.state.v.get(4 * N - 3).copied().unwrap_or(T::zero())
    }

    /// Horizontal displacement of the beam end from its unloaded position \[m\].
    pub fn tip_axial_displacement(&self) -> T {
        self.state.q.get(4 * N - 4).copied().unwrap_or(T::zero())
    }

    /// Tip rotation ψ (angle of the end slope) \[rad\] and its rate \[rad/s\].
    pub fn tip_angle(&self) -> (T, T) {
        tip::psi_and_rate(&Self::local(&self.state.q, &self.state.v, &self.state.a))
    }

    /// Ball angle θ from the downward vertical \[rad\] and its rate \[rad/s\]; `None` without a
    /// ball. A locked ball moves with the housing (θ = ψ).
    pub fn ball_angle(&self) -> Option<(T, T)> {
        if matches!(S::BALL, BallKind::None) {
            return None; // (a constant: no angle is computed)
        }
        self.angles_of(&self.state).theta
    }

    /// Ball angle relative to the housing α = θ − ψ \[rad\] and its rate; `None` without a ball.
    pub fn ball_relative_angle(&self) -> Option<(T, T)> {
        if matches!(S::BALL, BallKind::None) {
            return None;
        }
        self.angles_of(&self.state).ball_relative()
    }

    /// The track's force on the ball ([`ContactForces`]; zero while it flies); `None`
    /// without a free ball.
    pub fn contact_forces(&self) -> Option<ContactForces<T>> {
        if !matches!(S::BALL, BallKind::Free) || S::EXTRA_DOFS != 1 {
            return None;
        }
        let (normal, tangential) = self.sys.track_forces(&self.state);
        Some(ContactForces { normal, tangential })
    }

    /// The ball flies inside the housing (`flight`).
    pub fn in_flight(&self) -> bool {
        self.state.contact == Contact::InFlight
    }

    /// The ball's centre and its velocity in the frame translating with the base (x along the
    /// undeformed beam from the clamp, y up) \[m, m/s\]; `None` without a free ball.
    pub fn ball_centre(&self) -> Option<([T; 2], [T; 2])> {
        if !matches!(S::BALL, BallKind::Free) || S::EXTRA_DOFS != 1 {
            return None;
        }
        Some(self.sys.ball_centre(&self.state))
    }

    /// Time since the start \[s\].
    pub fn time(&self) -> T {
        self.state.time
    }

    /// Vertical momentum relative to the base \[kg·m/s\]: `∫ μ ẏ dx` of the beam (per element
    /// `−Q_f(g = 1) · u̇`, eq. 17, heads included on an arm) plus `m_t Ḃ_y + m_b Ḋ_y` of the tip mass and ball. In the
    /// frame moving with the base the only energy source is the inertial force −m ÿ_b, whose
    /// power is `−ÿ_b p_y`: integrating it gives the work the base has done, the bound every
    /// run's energy must respect.
    pub fn vertical_momentum(&self) -> T {
        let mut p = T::zero();
        for k in 0..N {
            // On an arm, the element's own section and heads (as the energies).
            let (_, unit) = self.element_and_unit_weight(k);
            p -= unit.dot(&crate::step::beam::gather(&self.state.v, k));
        }
        if S::HAS_TIP {
            let y_rate = self.tip_velocity();
            let ang = self.angles_of(&self.state);
            p += self.sys.params.tip.mass
                * (y_rate + self.sys.params.tip.offset * ang.psi_rate * ang.sin_psi);
            if self.state.contact == Contact::InFlight {
                p += self.sys.params.ball.mass * self.state.flight.velocity[1];
            } else if let (Some((_, theta_rate)), Some((sin_theta, _))) =
                (ang.theta, ang.theta_sin_cos())
            {
                let rho = self.sys.params.ball.path_radius();
                p += self.sys.params.ball.mass * (y_rate + rho * theta_rate * sin_theta);
            }
        }
        p
    }

    /// Static tip deflection of the equilibrium the run started from \[m\].
    pub fn static_tip_deflection(&self) -> T {
        self.sys
            .equilibrium
            .get(4 * N - 3)
            .copied()
            .unwrap_or(T::zero())
    }
}
