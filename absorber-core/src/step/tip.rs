//! Tip mass welded to the beam end, and the ball rolling in its track (docs/derivation.md §§2–5).
//!
//! The tip body and the ball depend on the beam only through the end node A: its position
//! `r_A`, and its slope `(a₃, a₄)`, whose angle is the tip rotation `ψ = atan2(a₄, a₃)`
//! (paper eq. 25). With the track centred at A (docs/derivation.md, "Conventions") and `u_t = (0, d)`, Lagrange's
//! equations in the physical coordinates `p = (x_A, y_A, ψ, θ)` read (`g` = effective gravity,
//! `m = m_t + m_b`, `J_ψ = J_t + m_t d² + J_b R_tr²/r_b²`, `J_θ = (m_b + J_b/r_b²) ρ²`,
//! `J_ψθ = −J_b R_tr ρ / r_b²`, `R_tr = ρ + r_b`):
//!
//! ```text
//! E_x = m ẍ_A + m_t d (cψ ψ̈ − sψ ψ̇²) + m_b ρ (cθ θ̈ − sθ θ̇²)
//! E_y = m (ÿ_A + g) + m_t d (sψ ψ̈ + cψ ψ̇²) + m_b ρ (sθ θ̈ + cθ θ̇²)
//! E_ψ = m_t d (cψ ẍ_A + sψ (ÿ_A + g)) + J_ψ ψ̈ + J_ψθ θ̈
//! E_θ = m_b ρ (cθ ẍ_A + sθ (ÿ_A + g)) + J_θ θ̈ + J_ψθ ψ̈
//! ```
//!
//! `E_p` is the generalized inertia-plus-weight force the bodies put on the beam end. With
//! `ψ̇ = j·ȧ`, `j = (−a₄, a₃)/s²`, `ψ̈ = j·ä − 2ψ̇ (a₃ȧ₃ + a₄ȧ₄)/s²`, `s² = a₃² + a₄²`, the map
//! to the end-node coordinates is the chain rule `r = Pᵀ E_p`: rows `(E_x, E_y, j₃ E_ψ, j₄ E_ψ)`.
//!
//! **Ball unknown.** As in the paper's partition (eq. 28), the free ball's unknown is its spin
//! angle φ, not the orbit angle θ. Rolling without slip integrates to
//! `θ = (R_tr ψ − r_b φ) / ρ` (docs/derivation.md §3), so `E_θ` enters the ψ rows with weight
//! `R_tr/ρ` and the φ row is `E_φ = −(r_b/ρ) E_θ`. The relative angle is
//! `α = θ − ψ = (r_b/ρ)(ψ − φ)`. Using the paper's independent coordinates lets the full
//! solver (`host-sim`) integrate exactly the same discrete equations. A locked ball (or one
//! resting on a stop) has `θ = ψ + α_lock`, so its `E_θ` adds to `E_ψ`.
//!
//! Everything is evaluated in [`Dual`] arithmetic seeded with the Newmark chain coefficients,
//! so one pass gives the residual and its exact Jacobian `c_m ∂r/∂ä + c_v ∂r/∂ȧ + c_q ∂r/∂q`.

use crate::params::Params;
use crate::scalar::{lit, Real};
use crate::scene::BallKind;
use crate::step::dual::{Dual, Number, Plain};
use crate::step::scheme::Chain;

/// Local coordinates: end-node displacement (x, y), slope displacement (x, y), ball spin φ.
pub const LOCAL: usize = 5;
/// Dual number over the local coordinates.
pub type D5<T> = Dual<T, LOCAL>;

/// How the ball moves in the current evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BallMode<T> {
    /// No ball in the scene.
    Absent,
    /// Ball fixed in the housing at relative angle `φ_lock` (locked scene, or resting on a stop).
    Held(T),
    /// Ball free: its spin φ is an unknown.
    Free,
    /// Ball in flight: gone from the housing (the tip rows use the tip body's inertia alone)
    /// and its spin φ torque-free, row 4 = φ̈ (`step::flight`).
    Flying,
    /// Static solve of a free ball: φ is an unknown pinned by row 4 to the plumb position
    /// θ = 0 (an equilibrium for any gravity, the only stable one for g > 0; with g = 0 the
    /// ball's own equation would be singular).
    Plumb,
}

/// Constant inertia data of the tip body and ball, precomputed from [`Params`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipInertia<T> {
    /// m_t + m_b \[kg\].
    pub total_mass: T,
    /// m_t d \[kg·m\].
    pub tip_moment: T,
    /// J_ψ \[kg·m²\].
    pub j_psi: T,
    /// m_b ρ \[kg·m\].
    pub ball_moment: T,
    /// J_θ \[kg·m²\].
    pub j_theta: T,
    /// J_ψθ \[kg·m²\].
    pub j_psi_theta: T,
    /// R_tr / ρ: ∂θ/∂ψ at fixed spin.
    pub orbit_per_tilt: T,
    /// r_b / ρ: −∂θ/∂φ.
    pub orbit_per_spin: T,
}

impl<T: Real> TipInertia<T> {
    /// Inertia data for a scene with (`has_tip`, `ball`).
    pub fn new(p: &Params<T>, has_tip: bool, ball: BallKind) -> Self {
        let zero = T::zero();
        let (mt, jt, d) = if has_tip {
            (p.tip.mass, p.tip.inertia, p.tip.offset)
        } else {
            (zero, zero, zero)
        };
        let mut s = Self {
            total_mass: mt,
            tip_moment: mt * d,
            j_psi: jt + mt * d * d,
            ball_moment: zero,
            j_theta: zero,
            j_psi_theta: zero,
            orbit_per_tilt: zero,
            orbit_per_spin: zero,
        };
        if !matches!(ball, BallKind::None) {
            let b = &p.ball;
            let rho = b.path_radius();
            let r_tr = rho + b.radius;
            let jr = b.inertia / (b.radius * b.radius);
            s.total_mass += b.mass;
            s.j_psi += jr * r_tr * r_tr;
            s.ball_moment = b.mass * rho;
            s.j_theta = (b.mass + jr) * rho * rho;
            s.j_psi_theta = -jr * r_tr * rho;
            s.orbit_per_tilt = r_tr / rho;
            s.orbit_per_spin = b.radius / rho;
        }
        s
    }
}

/// Kinematics of the local coordinates (displacements, velocities, accelerations).
#[derive(Clone, Copy, Debug)]
pub struct LocalState<T> {
    /// Positions (displacements from the reference; θ absolute).
    pub q: [T; LOCAL],
    /// Velocities.
    pub v: [T; LOCAL],
    /// Accelerations.
    pub a: [T; LOCAL],
}

/// Tip rotation kinematics: ψ, ψ̇, ψ̈, its gradient j and (cos ψ, sin ψ) = (a₃, a₄)/|a|
/// (no trigonometric call).
struct Psi<A> {
    psi: A,
    rate: A,
    accel: A,
    jx: A,
    jy: A,
    cos: A,
    sin: A,
}

fn psi_kinematics<T: Real, A: Number<T>>(x: &LocalState<T>, ch: &Chain<T>) -> Psi<A> {
    let var = |k: usize| -> (A, A, A) {
        let (q, v, a) = (
            x.q.get(k).copied().unwrap_or(T::zero()),
            x.v.get(k).copied().unwrap_or(T::zero()),
            x.a.get(k).copied().unwrap_or(T::zero()),
        );
        (
            A::variable(q, k, ch.c_q),
            A::variable(v, k, ch.c_v),
            A::variable(a, k, ch.c_m),
        )
    };
    let (u3, v3, a3dd) = var(2);
    let (a4, v4, a4dd) = var(3);
    let a3 = u3.add_re(T::one()); // slope x = 1 + displacement
    let s2 = a3 * a3 + a4 * a4;
    let len = s2.sqrt();
    let jx = -a4 / s2;
    let jy = a3 / s2;
    let rate = jx * v3 + jy * v4;
    let gamma = (rate * (a3 * v3 + a4 * v4) / s2).scale(lit(-2.0));
    let accel = jx * a3dd + jy * a4dd + gamma;
    Psi {
        psi: a4.atan2(a3),
        rate,
        accel,
        jx,
        jy,
        cos: a3 / len,
        sin: a4 / len,
    }
}

/// Tip rotation ψ and rate ψ̇ (plain values) from the local state.
pub fn psi_and_rate<T: Real>(x: &LocalState<T>) -> (T, T) {
    let (psi, rate, _) = psi_all(x);
    (psi, rate)
}

/// Tip rotation ψ, rate and acceleration (plain values).
pub fn psi_all<T: Real>(x: &LocalState<T>) -> (T, T, T) {
    let p = tip_rotation(x);
    (p.psi, p.rate, p.accel)
}

/// Tip rotation in plain values: ψ = atan2(a₄, 1 + a₃) \[rad\], ψ̇ \[rad/s\], ψ̈ \[rad/s²\], and
/// (cos ψ, sin ψ) = a/|a| from the end slope a = (1 + a₃, a₄) without trigonometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipRotation<T> {
    /// ψ \[rad\].
    pub psi: T,
    /// ψ̇ \[rad/s\].
    pub rate: T,
    /// ψ̈ \[rad/s²\].
    pub accel: T,
    /// cos ψ.
    pub cos: T,
    /// sin ψ.
    pub sin: T,
}

/// The tip rotation of a local state (the formulas of the equations of motion, in plain values).
pub fn tip_rotation<T: Real>(x: &LocalState<T>) -> TipRotation<T> {
    let z = T::zero();
    let p: Psi<Plain<T>> = psi_kinematics(
        x,
        &Chain {
            c_q: z,
            c_v: z,
            c_m: z,
        },
    );
    TipRotation {
        psi: p.psi.0,
        rate: p.rate.0,
        accel: p.accel.0,
        cos: p.cos.0,
        sin: p.sin.0,
    }
}

/// Orbit angle θ and its rate from the local state of a free ball (spin φ at index 4).
pub fn orbit_angle<T: Real>(inertia: &TipInertia<T>, x: &LocalState<T>) -> (T, T) {
    let (psi, rate) = psi_and_rate(x);
    (
        inertia.orbit_per_tilt * psi - inertia.orbit_per_spin * x.q[4],
        inertia.orbit_per_tilt * rate - inertia.orbit_per_spin * x.v[4],
    )
}

/// Gradient of the relative ball angle `G = θ − ψ = (r_b/ρ)(ψ − φ)` with respect to the local
/// coordinates.
pub fn gap_gradient<T: Real>(inertia: &TipInertia<T>, x: &LocalState<T>) -> [T; LOCAL] {
    let a3 = T::one() + x.q[2];
    let a4 = x.q[3];
    let s2 = a3 * a3 + a4 * a4;
    let k = inertia.orbit_per_spin;
    [T::zero(), T::zero(), -k * a4 / s2, k * a3 / s2, -k]
}

/// Residual rows of the tip body and ball on the local coordinates, with their Jacobian when
/// `A` is a `Dual` (plain values with `Plain`).
///
/// Returns the five rows (value = generalized force, for duals `du[k]` = Jacobian entry along
/// local direction k) and the value of `E_θ` (the generalized contact force the housing or stop
/// exerts on the ball along θ; zero without a ball). Row 4 is `E_φ` for a free ball, the
/// acceleration constraint `φ̈ − ψ̈` for a ball held on a stop (held: `φ = ψ − α_lock ρ/r_b`),
/// θ itself for a ball pinned plumb (static solve), and zero otherwise.
pub fn residual<T: Real, A: Number<T>>(
    inertia: &TipInertia<T>,
    x: &LocalState<T>,
    ch: &Chain<T>,
    g_eff: T,
    mode: BallMode<T>,
    free_theta_is_unknown: bool,
) -> ([A; LOCAL], T) {
    let ps: Psi<A> = psi_kinematics(x, ch);
    let xdd = A::variable(x.a[0], 0, ch.c_m);
    let ydd_g = A::variable(x.a[1], 1, ch.c_m).add_re(g_eff);
    let (s_psi, c_psi) = (ps.sin, ps.cos);
    let rate2 = ps.rate * ps.rate;

    let mut e_x = xdd.scale(inertia.total_mass)
        + (c_psi * ps.accel - s_psi * rate2).scale(inertia.tip_moment);
    let mut e_y = ydd_g.scale(inertia.total_mass)
        + (s_psi * ps.accel + c_psi * rate2).scale(inertia.tip_moment);
    let mut e_psi =
        (c_psi * xdd + s_psi * ydd_g).scale(inertia.tip_moment) + ps.accel.scale(inertia.j_psi);
    let mut row4 = A::constant(T::zero());
    let mut contact = T::zero();

    if mode == BallMode::Flying {
        row4 = A::variable(x.a[4], 4, ch.c_m);
    }
    let theta = match mode {
        BallMode::Absent | BallMode::Flying => None,
        BallMode::Held(lock) => Some((ps.psi.add_re(lock), ps.rate, ps.accel)),
        BallMode::Free | BallMode::Plumb => {
            // θ = (R_tr ψ − r_b φ)/ρ, and likewise for its rates (linear in ψ and φ).
            let (kt, ks) = (inertia.orbit_per_tilt, inertia.orbit_per_spin);
            let orbit = |p: A, f: A| p.scale(kt) - f.scale(ks);
            Some((
                orbit(ps.psi, A::variable(x.q[4], 4, ch.c_q)),
                orbit(ps.rate, A::variable(x.v[4], 4, ch.c_v)),
                orbit(ps.accel, A::variable(x.a[4], 4, ch.c_m)),
            ))
        }
    };
    if let Some((th, th_d, th_dd)) = theta {
        let (s_th, c_th) = th.sin_cos();
        let th_d2 = th_d * th_d;
        e_x = e_x + (c_th * th_dd - s_th * th_d2).scale(inertia.ball_moment);
        e_y = e_y + (s_th * th_dd + c_th * th_d2).scale(inertia.ball_moment);
        e_psi = e_psi + th_dd.scale(inertia.j_psi_theta);
        let e_theta = (c_th * xdd + s_th * ydd_g).scale(inertia.ball_moment)
            + th_dd.scale(inertia.j_theta)
            + ps.accel.scale(inertia.j_psi_theta);
        contact = e_theta.re();
        match mode {
            BallMode::Free => {
                e_psi = e_psi + e_theta.scale(inertia.orbit_per_tilt);
                row4 = e_theta.scale(-inertia.orbit_per_spin);
            }
            BallMode::Plumb => {
                e_psi = e_psi + e_theta.scale(inertia.orbit_per_tilt);
                row4 = th;
            }
            _ => {
                e_psi = e_psi + e_theta;
                if free_theta_is_unknown {
                    // Ball held on a stop: φ stays an unknown, tied to ψ at acceleration level.
                    row4 = A::variable(x.a[4], 4, ch.c_m) - ps.accel;
                }
            }
        }
    }
    ([e_x, e_y, ps.jx * e_psi, ps.jy * e_psi, row4], contact)
}
