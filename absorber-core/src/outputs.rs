//! What firmware reads back after a step.

use crate::model::Model;
use crate::scalar::Real;
use crate::scene::{BallKind, Scene};
use crate::tip;

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
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
        match S::BALL {
            BallKind::None => None,
            BallKind::Locked => Some(self.tip_angle()),
            BallKind::Free => Some(self.orbit_of(&self.state)),
        }
    }

    /// Ball angle relative to the housing α = θ − ψ \[rad\] and its rate; `None` without a ball.
    pub fn ball_relative_angle(&self) -> Option<(T, T)> {
        let (th, thd) = self.ball_angle()?;
        let (psi, psid) = self.tip_angle();
        Some((th - psi, thd - psid))
    }

    /// Time since the start \[s\].
    pub fn time(&self) -> T {
        self.state.time
    }

    /// Vertical momentum relative to the base \[kg·m/s\]: `∫ μ ẏ dx` of the beam (per element
    /// `−Q_f(g = 1) · u̇`, eq. 17) plus `m_t Ḃ_y + m_b Ḋ_y` of the tip mass and ball. In the
    /// frame moving with the base the only energy source is the inertial force −m ÿ_b, whose
    /// power is `−ÿ_b p_y`: integrating it gives the work the base has done, the bound every
    /// run's energy must respect.
    pub fn vertical_momentum(&self) -> T {
        let unit = self.beam.element.gravity_force(T::one());
        let mut p = T::zero();
        for k in 0..N {
            p -= unit.dot(&crate::beam::gather(&self.state.v, k));
        }
        if S::HAS_TIP {
            let y_rate = self.tip_velocity();
            let (psi, psi_rate) = self.tip_angle();
            p += self.params.tip.mass * (y_rate + self.params.tip.offset * psi_rate * psi.sin());
            if let Some((theta, theta_rate)) = self.ball_angle() {
                let rho = self.params.ball.path_radius();
                p += self.params.ball.mass * (y_rate + rho * theta_rate * theta.sin());
            }
        }
        p
    }

    /// Static tip deflection of the equilibrium the run started from \[m\].
    pub fn static_tip_deflection(&self) -> T {
        self.equilibrium
            .get(4 * N - 3)
            .copied()
            .unwrap_or(T::zero())
    }
}
