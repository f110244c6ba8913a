//! Constraints between the beam end node, the tip mass and the ball in maximal coordinates.
//!
//! Local coordinates `w` (10): the end node's displacement `a = (a₁, a₂, a₃, a₄)` from the
//! straight reference (so `r_A = (L + a₁, a₂)`, `r_A′ = (1 + a₃, a₄)`), the tip mass
//! `(R_t1, R_t2, ψ)`, the ball `(φ, R_b1, R_b2)`; all in the frame translating with the base.
//! Constraints (paper eqs. 25–27, the rolling contact in its integrated holonomic form):
//!
//! ```text
//! c₁,₂ = r_A − R_t − A(ψ) u_t            (fixed joint, u_t = (0, d))
//! c₃   = ψ − atan2(a₄, 1 + a₃)           (fixed joint, tip rotation = end slope angle)
//! c₄   = |R_b − r_A| − ρ                 (ball centre on the circle of radius ρ about A)
//! c₅   = r_b φ − R_tr ψ + ρ θ            (no slip; θ = angle of R_b − r_A from −y)
//! c₆   = θ − ψ − α_lock                  (ball held: locked scene, or resting on a stop)
//! c₆′  = θ                               (static solve of a free ball: pinned plumb)
//! ```
//!
//! While the ball flies only the fixed joint c₁…c₃ is active:
//! the ball's `(φ, R_b1, R_b2)` are independent coordinates ([`Mode::Flying`]).
//!
//! For each one: value, gradient `∂c/∂w` and the quadratic term `ẇᵀ (∂²c/∂w²) ẇ`, so that
//! `Q_d = −(C_q q̇)_q q̇` (eq. 23; the constraints do not depend on time in the base frame).

/// Number of local coordinates.
pub const NW: usize = 10;
/// Local index of the tip mass centre x.
pub const RT1: usize = 4;
/// Tip mass centre y.
pub const RT2: usize = 5;
/// Tip rotation ψ.
pub const PSI: usize = 6;
/// Ball spin φ.
pub const PHI: usize = 7;
/// Ball centre x.
pub const RB1: usize = 8;
/// Ball centre y.
pub const RB2: usize = 9;
/// Most constraints at once.
pub const MC: usize = 6;
/// Most independent local coordinates at once (end node, and φ, R_b1, R_b2 in flight).
pub const NI: usize = 7;

/// Which local constraints are active.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Beam alone: no local constraint.
    Beam,
    /// Tip mass only: c₁…c₃.
    Tip,
    /// Free ball: c₁…c₅; φ is independent.
    Free,
    /// Ball in flight inside the housing: c₁…c₃ only (the rolling contact c₄, c₅ released);
    /// φ, R_b1, R_b2 are independent.
    Flying,
    /// Ball held at relative angle α_lock: c₁…c₆; φ is dependent.
    Held(f64),
    /// Static solve of a free ball: c₁…c₅ and c₆′ (θ = 0, plumb); φ is dependent. The plumb
    /// position is an equilibrium for any gravity (the only stable one for g > 0); with g = 0
    /// the free ball's own equation would be singular. Mirrors the core's `BallMode::Plumb`.
    Plumb,
}

impl Mode {
    /// Number of active constraints.
    pub fn m(self) -> usize {
        match self {
            Mode::Beam => 0,
            Mode::Tip | Mode::Flying => 3,
            Mode::Free => 5,
            Mode::Held(_) | Mode::Plumb => 6,
        }
    }

    /// Dependent local coordinates (one per active constraint, in this order).
    pub fn dependent(self) -> &'static [usize] {
        match self {
            Mode::Beam => &[],
            Mode::Tip | Mode::Flying => &[RT1, RT2, PSI],
            Mode::Free => &[RT1, RT2, PSI, RB1, RB2],
            Mode::Held(_) | Mode::Plumb => &[RT1, RT2, PSI, PHI, RB1, RB2],
        }
    }

    /// Independent local coordinates.
    pub fn independent(self) -> &'static [usize] {
        match self {
            Mode::Free => &[0, 1, 2, 3, PHI],
            Mode::Flying => &[0, 1, 2, 3, PHI, RB1, RB2],
            _ => &[0, 1, 2, 3],
        }
    }
}

/// Geometry and inertia of the tip body and ball.
#[derive(Clone, Copy, Debug)]
pub struct Bodies {
    /// Beam length L \[m\].
    pub length: f64,
    /// u_t2 = d \[m\].
    pub offset: f64,
    /// ρ = R − r_b \[m\].
    pub rho: f64,
    /// r_b \[m\].
    pub rb: f64,
    /// R_tr = ρ + r_b \[m\].
    pub rtr: f64,
    /// Diagonal of the (constant) mass matrix over the local coordinates.
    pub mass: [f64; NW],
    /// m_t, m_b \[kg\] (for the weights).
    pub weights: (f64, f64),
}

/// Values, gradients and quadratic velocity terms of the active constraints.
#[derive(Clone, Copy, Debug)]
pub struct Cons {
    /// c_k(w).
    pub val: [f64; MC],
    /// ∂c_k/∂w.
    pub grad: [[f64; NW]; MC],
    /// ẇᵀ ∂²c_k/∂w² ẇ.
    pub quad: [f64; MC],
}

impl Cons {
    /// No constraint.
    pub const ZERO: Self = Self {
        val: [0.0; MC],
        grad: [[0.0; NW]; MC],
        quad: [0.0; MC],
    };
}

/// `ẇᵀ ∇² atan2(Y, X) ẇ` for the direction vector (X, Y) and its rate.
fn atan2_quad(x: f64, y: f64, xd: f64, yd: f64) -> f64 {
    let r2 = x * x + y * y;
    (2.0 * x * y * (xd * xd - yd * yd) + 2.0 * (y * y - x * x) * xd * yd) / (r2 * r2)
}

/// θ = atan2(D_x, −D_y), unwrapped to the branch nearest `theta_ref`.
pub fn theta_of(dx: f64, dy: f64, theta_ref: f64) -> f64 {
    let raw = dx.atan2(-dy);
    let tau = 2.0 * core::f64::consts::PI;
    raw + tau * ((theta_ref - raw) / tau).round()
}

impl Bodies {
    /// Ball centre relative to A, `D = R_b − r_A`.
    pub fn ball_offset(&self, w: &[f64; NW]) -> (f64, f64) {
        (w[RB1] - self.length - w[0], w[RB2] - w[1])
    }

    /// The active constraints at `w` with velocities `wd`.
    pub fn constraints(&self, w: &[f64; NW], wd: &[f64; NW], mode: Mode, theta_ref: f64) -> Cons {
        let mut c = self.values(w, mode, theta_ref);
        c.quad = self.quad(w, wd, mode);
        c
    }

    /// Values and gradients of the active constraints at `w` (quadratic terms zero: those of
    /// [`Bodies::constraints`] at rest).
    pub fn values(&self, w: &[f64; NW], mode: Mode, theta_ref: f64) -> Cons {
        let mut c = Cons::ZERO;
        self.values_into(w, mode, theta_ref, &mut c);
        c
    }

    /// [`Bodies::values`] written into `c` (every entry).
    pub fn values_into(&self, w: &[f64; NW], mode: Mode, theta_ref: f64, c: &mut Cons) {
        *c = Cons::ZERO;
        if mode == Mode::Beam {
            return;
        }
        let d = self.offset;
        let (s, co) = w[PSI].sin_cos();
        // c1, c2: fixed joint position.
        c.val[0] = self.length + w[0] - w[RT1] + d * s;
        c.grad[0][0] = 1.0;
        c.grad[0][RT1] = -1.0;
        c.grad[0][PSI] = d * co;
        c.val[1] = w[1] - w[RT2] - d * co;
        c.grad[1][1] = 1.0;
        c.grad[1][RT2] = -1.0;
        c.grad[1][PSI] = d * s;
        // c3: ψ − atan2(a4, 1 + a3).
        let (x, y) = (1.0 + w[2], w[3]);
        let r2 = x * x + y * y;
        c.val[2] = w[PSI] - y.atan2(x);
        c.grad[2][PSI] = 1.0;
        c.grad[2][2] = y / r2;
        c.grad[2][3] = -x / r2;
        if matches!(mode, Mode::Tip | Mode::Flying) {
            return;
        }
        // Ball: D = R_b − r_A.
        let (dx, dy) = self.ball_offset(w);
        let dist2 = dx * dx + dy * dy;
        let dist = dist2.sqrt();
        let (nx, ny) = (dx / dist, dy / dist);
        c.val[3] = dist - self.rho;
        c.grad[3][RB1] = nx;
        c.grad[3][RB2] = ny;
        c.grad[3][0] = -nx;
        c.grad[3][1] = -ny;
        // θ = atan2(Y, X) with X = −D_y, Y = D_x.
        let theta = theta_of(dx, dy, theta_ref);
        let (tx, ty) = (-dy / dist2, dx / dist2); // ∂θ/∂D
        c.val[4] = self.rb * w[PHI] - self.rtr * w[PSI] + self.rho * theta;
        c.grad[4][PHI] = self.rb;
        c.grad[4][PSI] = -self.rtr;
        c.grad[4][RB1] = self.rho * tx;
        c.grad[4][RB2] = self.rho * ty;
        c.grad[4][0] = -self.rho * tx;
        c.grad[4][1] = -self.rho * ty;
        let held = match mode {
            Mode::Held(lock) => Some((lock, 1.0)),
            Mode::Plumb => Some((0.0, 0.0)),
            _ => None,
        };
        if let Some((lock, tilt)) = held {
            // c₆ = θ − ψ − α_lock (held), c₆′ = θ (plumb).
            c.val[5] = theta - tilt * w[PSI] - lock;
            c.grad[5][PSI] = -tilt;
            c.grad[5][RB1] = tx;
            c.grad[5][RB2] = ty;
            c.grad[5][0] = -tx;
            c.grad[5][1] = -ty;
        }
    }

    /// The quadratic velocity terms `ẇᵀ (∂²c/∂w²) ẇ` of the active constraints.
    pub fn quad(&self, w: &[f64; NW], wd: &[f64; NW], mode: Mode) -> [f64; MC] {
        let mut q = [0.0; MC];
        if mode == Mode::Beam {
            return q;
        }
        let d = self.offset;
        let (s, co) = w[PSI].sin_cos();
        let psid = wd[PSI];
        q[0] = -d * s * psid * psid;
        q[1] = d * co * psid * psid;
        let (x, y) = (1.0 + w[2], w[3]);
        q[2] = -atan2_quad(x, y, wd[2], wd[3]);
        if matches!(mode, Mode::Tip | Mode::Flying) {
            return q;
        }
        let (dx, dy) = self.ball_offset(w);
        let (dxd, dyd) = (wd[RB1] - wd[0], wd[RB2] - wd[1]);
        let dist2 = dx * dx + dy * dy;
        let dist = dist2.sqrt();
        let (nx, ny) = (dx / dist, dy / dist);
        let ndot = nx * dxd + ny * dyd;
        q[3] = (dxd * dxd + dyd * dyd - ndot * ndot) / dist;
        let tq = atan2_quad(-dy, dx, -dyd, dxd);
        q[4] = self.rho * tq;
        if matches!(mode, Mode::Held(_) | Mode::Plumb) {
            q[5] = tq;
        }
        q
    }

    /// Relative ball angle α = θ − ψ, its gradient over `w` and its rate.
    pub fn relative_angle(
        &self,
        w: &[f64; NW],
        wd: &[f64; NW],
        theta_ref: f64,
    ) -> (f64, [f64; NW], f64) {
        let (dx, dy) = self.ball_offset(w);
        let dist2 = dx * dx + dy * dy;
        let theta = theta_of(dx, dy, theta_ref);
        let (tx, ty) = (-dy / dist2, dx / dist2);
        let mut g = [0.0; NW];
        g[PSI] = -1.0;
        g[RB1] = tx;
        g[RB2] = ty;
        g[0] = -tx;
        g[1] = -ty;
        let rate: f64 = g.iter().zip(wd.iter()).map(|(a, b)| a * b).sum();
        (theta - w[PSI], g, rate)
    }

    /// Orbit angle θ and rate.
    pub fn orbit(&self, w: &[f64; NW], wd: &[f64; NW], theta_ref: f64) -> (f64, f64) {
        let (dx, dy) = self.ball_offset(w);
        let dist2 = dx * dx + dy * dy;
        let theta = theta_of(dx, dy, theta_ref);
        let (dxd, dyd) = (wd[RB1] - wd[0], wd[RB2] - wd[1]);
        (theta, (-dy * dxd + dx * dyd) / dist2)
    }

    /// Scale of a local coordinate for convergence tests.
    pub fn scale(&self, j: usize) -> f64 {
        match j {
            0 | 1 | RT1 | RT2 | RB1 | RB2 => self.length,
            _ => 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bodies() -> Bodies {
        Bodies {
            length: 0.365,
            offset: 0.0204,
            rho: 0.032,
            rb: 0.0075,
            rtr: 0.0395,
            mass: [
                0.0, 0.0, 0.0, 0.0, 0.1154, 0.1154, 1.871e-5, 3.15e-7, 0.014, 0.014,
            ],
            weights: (0.1154, 0.014),
        }
    }

    /// Gradients and quadratic terms are the derivatives of the values (central differences).
    #[test]
    fn gradients_and_quadratic_terms_match_finite_differences() {
        let b = bodies();
        let w = [
            0.01, -0.02, -0.03, -0.1, 0.37, -0.04, -0.09, 1.3, 0.38, -0.05,
        ];
        let wd = [0.1, -0.3, 0.2, 0.5, -0.1, 0.2, 0.7, -3.0, 0.4, -0.6];
        for mode in [Mode::Held(0.2), Mode::Plumb] {
            let c = b.constraints(&w, &wd, mode, 0.0);
            let h = 1e-6;
            for k in 0..mode.m() {
                for j in 0..NW {
                    let (mut wp, mut wm) = (w, w);
                    wp[j] += h;
                    wm[j] -= h;
                    let fd = (b.constraints(&wp, &wd, mode, 0.0).val[k]
                        - b.constraints(&wm, &wd, mode, 0.0).val[k])
                        / (2.0 * h);
                    assert!(
                        (fd - c.grad[k][j]).abs() < 1e-7,
                        "c{k} w{j}: {fd} vs {}",
                        c.grad[k][j]
                    );
                }
                // d/dt (grad · wd) along w + t wd = wdᵀ H wd.
                let (mut wp, mut wm) = (w, w);
                for j in 0..NW {
                    wp[j] += h * wd[j];
                    wm[j] -= h * wd[j];
                }
                let dot = |g: &[f64; NW]| g.iter().zip(wd.iter()).map(|(a, b)| a * b).sum::<f64>();
                let fd = (dot(&b.constraints(&wp, &wd, mode, 0.0).grad[k])
                    - dot(&b.constraints(&wm, &wd, mode, 0.0).grad[k]))
                    / (2.0 * h);
                assert!(
                    (fd - c.quad[k]).abs() < 1e-5 * (1.0 + fd.abs()),
                    "quad c{k}: {fd} vs {}",
                    c.quad[k]
                );
            }
        }
    }
}
