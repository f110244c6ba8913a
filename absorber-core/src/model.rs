//! The model: state, assembly of the equations of motion, Newton solves and the fixed step.

use crate::ancf::Element;
use crate::beam::Beam;
use crate::dual::Plain;
use crate::error::Error;
use crate::linalg;
use crate::params::{ImpactModel, NewtonKind, Params};
use crate::scalar::{is_positive, lit, to_f64, Real};
use crate::scene::{BallKind, Scene};
use crate::tip::{self, BallMode, Chain, LocalState, TipInertia, D5, LOCAL};
use core::marker::PhantomData;
use nalgebra::{SMatrix, SVector};

/// Whether the free ball rests on a stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Ball off the stops (or no stops / no free ball).
    Off,
    /// Ball resting on the stop at `+φ_max` (`Positive`) or `−φ_max` (`Negative`).
    OnStop(Side),
}

/// Which stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Relative angle θ − ψ = +φ_max.
    Positive,
    /// Relative angle θ − ψ = −φ_max.
    Negative,
}

impl Side {
    /// +1 or −1.
    pub fn sign<T: Real>(self) -> T {
        match self {
            Side::Positive => T::one(),
            Side::Negative => -T::one(),
        }
    }
}

/// The full dynamic state: everything needed to continue a run. `D` = number of unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State<T, const D: usize> {
    /// Displacements of the free nodal coordinates from the straight reference \[m, -\], then
    /// the ball's spin angle φ \[rad\] (free-ball scenes; paper eq. 28).
    pub q: SVector<T, D>,
    /// Velocities relative to the base.
    pub v: SVector<T, D>,
    /// Accelerations relative to the base.
    pub a: SVector<T, D>,
    /// Time since the start \[s\], `steps · h` (not a running sum: in `f32` adding 3 ms to an
    /// hour drifts by tens of seconds).
    pub time: T,
    /// Whole steps taken since the start.
    pub steps: u64,
    /// Base acceleration ÿ_b of the last step (the input at `time`) \[m/s²\].
    pub base_accel: T,
    /// Stop contact.
    pub contact: Contact,
}

/// A stop impact that happened during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impact<T> {
    /// Time of the impact \[s\].
    pub time: T,
    /// Which stop.
    pub side: Side,
    /// Relative angular speed θ̇ − ψ̇ before the impact \[rad/s\].
    pub relative_speed: T,
    /// Contact impulse on the ball along the track, Λ/ρ \[N·s\].
    pub impulse: T,
    /// Kinetic energy dissipated, ½(1−e²)Ġ²/(∇G M⁻¹ ∇Gᵀ) \[J\].
    pub energy_loss: T,
    /// The ball stayed on the stop (plastic, compressive contact).
    pub stuck: bool,
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport<T> {
    /// Newton iterations used, summed over the sub-solves of the step.
    pub iterations: u32,
    /// Largest final scaled position increment of the Newton solves \[-\].
    pub increment: T,
    /// Stop impact within the step, if any.
    pub impact: Option<Impact<T>>,
}

/// The factored Newton matrix kept by modified Newton, with what it was built for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CachedJacobian<T, const D: usize> {
    lu: linalg::Lu<T, D>,
    c_q: T,
    contact: Contact,
}

/// Result of one Newton solve.
struct Solved<T, const D: usize> {
    x: SVector<T, D>,
    iterations: u32,
    increment: T,
}

/// The start error when the beam end tilts beyond a stop at static equilibrium (both solvers).
pub const END_BEYOND_STOP: Error = Error::InvalidParameter {
    field: "ball.stop_angle",
    reason: "the beam end tilts beyond the stop at static equilibrium (a start with the ball resting on a stop is not supported)",
};

/// The start error when the initial ball angle lies beyond a stop (both solvers).
pub const START_BEYOND_STOP: Error = Error::InvalidParameter {
    field: "ball.initial_angle",
    reason: "puts the ball beyond a stop relative to the tilted housing",
};

/// What a Newton solve solves: `r(q₀ + c_q x, v₀ + c_v x, a₀ + c_m x) = 0` for `x`, at
/// effective gravity `g_eff`, in a contact state, the free ball optionally pinned plumb; `c_pos`
/// converts `x` to a position for the convergence test.
struct Problem<'a, T, const D: usize> {
    q0: &'a SVector<T, D>,
    v0: &'a SVector<T, D>,
    a0: &'a SVector<T, D>,
    ch: &'a Chain<T>,
    c_pos: T,
    g_eff: T,
    contact: Contact,
    plumb: bool,
}

/// Trust radius of a Newton correction, in units of the beam length for positions and in
/// radians for slopes and angles: a correction beyond it is damped ([`Model::damping`]), never
/// below it. A linearization about a state with a large (transient) axial force can be nearly
/// singular in bending, and its raw correction would leave the physical range.
pub const MAX_STEP: f64 = 0.05;

/// Most damping factors tried per Newton iteration (λ = 1, ½, …, 1/2048), each one residual and one
/// back-substitution: the work per iteration stays bounded.
pub const DAMPING_TRIALS: u32 = 12;

/// The reduced model of scene `S` with `N` elements and `D = 4N + S::EXTRA_DOFS` unknowns.
#[derive(Clone, Debug)]
pub struct Model<T, S, const N: usize, const D: usize> {
    pub(crate) params: Params<T>,
    pub(crate) beam: Beam<T>,
    pub(crate) inertia: TipInertia<T>,
    pub(crate) state: State<T, D>,
    /// Static equilibrium (zero relative velocity) the run started from.
    pub(crate) equilibrium: SVector<T, D>,
    /// Scale of each unknown for the convergence test: beam length for positions, 1 otherwise.
    pub(crate) scale: SVector<T, D>,
    /// Modified Newton's factored matrix (not part of the state: a cache).
    pub(crate) jacobian: Option<CachedJacobian<T, D>>,
    _scene: PhantomData<S>,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Model<T, S, N, D> {
    const CHECK: () = {
        assert!(N >= 1, "a beam needs at least one element");
        assert!(
            D == 4 * N + S::EXTRA_DOFS,
            "D must equal 4N + the scene's extra unknowns"
        );
    };

    /// Builds the model, solves the static equilibrium under gravity by load stepping and starts
    /// from it at rest relative to the base (ball at `ball.initial_angle`), with the base
    /// acceleration `base_accel` \[m/s²\] as the input at t = 0.
    pub fn at_rest(params: Params<T>, base_accel: T) -> Result<Self, Error> {
        let mut m = Self::new(params)?;
        m.solve_static()?;
        m.restart(base_accel)?;
        Ok(m)
    }

    /// Builds the model in the undeformed reference configuration, at rest, without solving
    /// the static equilibrium (see [`Model::at_rest`]).
    pub fn new(params: Params<T>) -> Result<Self, Error> {
        #[allow(clippy::let_unit_value)]
        let () = Self::CHECK;
        params.validate(S::HAS_TIP, !matches!(S::BALL, BallKind::None))?;
        let n: T = lit(N as f64);
        let b = &params.beam;
        let element = Element {
            length: b.length / n,
            axial_rigidity: b.modulus * b.area,
            bending_rigidity: b.modulus * b.inertia,
            mass_per_length: b.mass / b.length,
        };
        let beam = Beam {
            element,
            mass: element.mass_matrix(),
            stiffness: element.bending_stiffness(),
            damping: params.damping.stiffness_proportional,
        };
        let mut scale = SVector::<T, D>::from_element(T::one());
        for node in 0..N {
            for c in 0..2 {
                if let Some(s) = scale.get_mut(4 * node + c) {
                    *s = b.length;
                }
            }
        }
        let z = SVector::<T, D>::zeros();
        Ok(Self {
            inertia: TipInertia::new(&params, S::HAS_TIP, S::BALL),
            params,
            beam,
            state: State {
                q: z,
                v: z,
                a: z,
                time: T::zero(),
                steps: 0,
                base_accel: T::zero(),
                contact: Contact::Off,
            },
            equilibrium: z,
            scale,
            jacobian: None,
            _scene: PhantomData,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &Params<T> {
        &self.params
    }

    /// The current state.
    pub fn state(&self) -> &State<T, D> {
        &self.state
    }

    /// The static equilibrium the model started from.
    pub fn equilibrium(&self) -> &SVector<T, D> {
        &self.equilibrium
    }

    /// Index of the end node's first coordinate.
    const END: usize = 4 * N - 4;
    /// Index of the ball spin φ (free ball only).
    const SPIN: usize = 4 * N;

    pub(crate) fn local(q: &SVector<T, D>, v: &SVector<T, D>, a: &SVector<T, D>) -> LocalState<T> {
        let mut x = LocalState {
            q: [T::zero(); LOCAL],
            v: [T::zero(); LOCAL],
            a: [T::zero(); LOCAL],
        };
        let n = if S::EXTRA_DOFS == 1 { LOCAL } else { 4 };
        for k in 0..n {
            let g = Self::END + k;
            if let (Some(qq), Some(vv), Some(aa), Some(dq), Some(dv), Some(da)) = (
                q.get(g),
                v.get(g),
                a.get(g),
                x.q.get_mut(k),
                x.v.get_mut(k),
                x.a.get_mut(k),
            ) {
                *dq = *qq;
                *dv = *vv;
                *da = *aa;
            }
        }
        x
    }

    fn ball_mode(contact: Contact, stop: T) -> BallMode<T> {
        match (S::BALL, contact) {
            (BallKind::None, _) => BallMode::Absent,
            (BallKind::Locked, _) => BallMode::Held(T::zero()),
            (BallKind::Free, Contact::Off) => BallMode::Free,
            (BallKind::Free, Contact::OnStop(side)) => BallMode::Held(side.sign::<T>() * stop),
        }
    }

    /// Residual `r(q, v, a)` of the equations of motion and its Jacobian along the chain `ch`;
    /// also the generalized contact force on the ball along θ. `plumb` pins a free ball plumb
    /// (static solve).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn assemble(
        &self,
        q: &SVector<T, D>,
        v: &SVector<T, D>,
        a: &SVector<T, D>,
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        plumb: bool,
    ) -> (SVector<T, D>, SMatrix<T, D, D>, T) {
        let mut jac = SMatrix::<T, D, D>::zeros();
        let (r, force) = self.residual_into(q, v, a, g_eff, ch, contact, plumb, Some(&mut jac));
        (r, jac, force)
    }

    /// Residual of the equations of motion, its Jacobian along `ch` added into `jac` when given
    /// (the tip terms then run in dual numbers; without it, in plain values), and the
    /// generalized contact force on the ball along θ.
    #[allow(clippy::too_many_arguments)]
    fn residual_into(
        &self,
        q: &SVector<T, D>,
        v: &SVector<T, D>,
        a: &SVector<T, D>,
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        plumb: bool,
        mut jac: Option<&mut SMatrix<T, D, D>>,
    ) -> (SVector<T, D>, T) {
        let mut r = SVector::<T, D>::zeros();
        self.beam
            .assemble(N, q, v, a, g_eff, ch, &mut r, jac.as_deref_mut());
        let mut contact_force = T::zero();
        if S::HAS_TIP {
            let x = Self::local(q, v, a);
            let mode = match Self::ball_mode(contact, self.params.ball.stop_angle) {
                BallMode::Free if plumb => BallMode::Plumb,
                m => m,
            };
            let n = if S::EXTRA_DOFS == 1 { LOCAL } else { 4 };
            let unknown = S::EXTRA_DOFS == 1;
            match jac {
                Some(jac) => {
                    let (rows, lambda) =
                        tip::residual::<T, D5<T>>(&self.inertia, &x, ch, g_eff, mode, unknown);
                    contact_force = lambda;
                    for (i, row) in rows.iter().enumerate().take(n) {
                        if let Some(dst) = r.get_mut(Self::END + i) {
                            *dst += row.re;
                        }
                        for (j, d) in row.du.iter().enumerate().take(n) {
                            if let Some(dst) = jac.get_mut((Self::END + i, Self::END + j)) {
                                *dst += *d;
                            }
                        }
                    }
                }
                None => {
                    let (rows, lambda) =
                        tip::residual::<T, Plain<T>>(&self.inertia, &x, ch, g_eff, mode, unknown);
                    contact_force = lambda;
                    for (i, row) in rows.iter().enumerate().take(n) {
                        if let Some(dst) = r.get_mut(Self::END + i) {
                            *dst += row.0;
                        }
                    }
                }
            }
        }
        (r, contact_force)
    }

    /// Newton–Raphson on `x` with `q = q₀ + c_q x`, `v = v₀ + c_v x`, `a = a₀ + c_m x`, from the
    /// guess `x`. Convergence: `max_i |c_pos Δx_i| / scale_i ≤ tolerance`. Optionally with a
    /// free ball pinned plumb (static solve), and with a slot for modified Newton's factored
    /// matrix (`None`: full Newton).
    #[allow(clippy::too_many_arguments)]
    fn newton(
        &self,
        q0: &SVector<T, D>,
        v0: &SVector<T, D>,
        a0: &SVector<T, D>,
        mut x: SVector<T, D>,
        ch: &Chain<T>,
        c_pos: T,
        g_eff: T,
        contact: Contact,
        plumb: bool,
        mut cache: Option<&mut Option<CachedJacobian<T, D>>>,
    ) -> Result<Solved<T, D>, Error> {
        let max = self.params.integrator.max_iterations;
        let tol = self.params.integrator.tolerance;
        let mut increment = T::zero();
        // Modified Newton: rebuild when the cached matrix was made for another step length or
        // contact, or when its correction would contract by less than half (not taken).
        let mut rebuild = false;
        let mut previous = T::zero();
        let problem = Problem {
            q0,
            v0,
            a0,
            ch,
            c_pos,
            g_eff,
            contact,
            plumb,
        };
        for it in 1..=max {
            let q = q0 + x * ch.c_q;
            let v = v0 + x * ch.c_v;
            let a = a0 + x * ch.c_m;
            let reuse = match cache.as_deref() {
                Some(Some(c)) => !rebuild && c.c_q == ch.c_q && c.contact == contact,
                _ => false,
            };
            let step = if reuse {
                let (r, _) = self.residual_into(&q, &v, &a, g_eff, ch, contact, plumb, None);
                if !r.iter().all(|z| z.is_finite()) {
                    return Err(Error::NonFiniteState);
                }
                // Borrow the factors: copying them would cost a D×D memcpy per iteration.
                // A reused matrix must contract the correction by half, else the correction is
                // not taken and the matrix is rebuilt here (taking it first could carry the
                // iterate where even fresh matrices no longer converge).
                let limit = if it > 1 {
                    Some(previous * lit::<T>(0.5))
                } else {
                    None
                };
                match cache.as_deref() {
                    Some(Some(c)) => match self.correction(&problem, &x, r, &c.lu, limit)? {
                        Ok(step) => step,
                        Err(norm) => {
                            increment = norm;
                            rebuild = true;
                            continue;
                        }
                    },
                    _ => return Err(Error::Singular),
                }
            } else {
                let (r, jac, _) = self.assemble(&q, &v, &a, g_eff, ch, contact, plumb);
                if !r.iter().all(|z| z.is_finite()) || !jac.iter().all(|z| z.is_finite()) {
                    return Err(Error::NonFiniteState);
                }
                let lu = linalg::factor(jac).ok_or(Error::Singular)?;
                let step = self
                    .correction(&problem, &x, r, &lu, None)?
                    .map_err(|_| Error::Singular)?;
                if let Some(slot) = cache.as_deref_mut() {
                    *slot = Some(CachedJacobian {
                        lu,
                        c_q: ch.c_q,
                        contact,
                    });
                }
                rebuild = false;
                step
            };
            let (dx, lambda);
            (dx, increment, lambda) = step;
            x += dx * lambda;
            if increment <= tol {
                return Ok(Solved {
                    x,
                    iterations: it,
                    increment,
                });
            }
            previous = increment;
        }
        // A step solve (it has the modified-Newton slot, or is a Newmark solve: c_m = 1 and
        // c_q > 0) may accept its budget; static and consistent-acceleration solves never do.
        let step_solve = ch.c_m == T::one() && is_positive(ch.c_q) && !plumb;
        if self.params.integrator.accept_after_budget && step_solve {
            return Ok(Solved {
                x,
                iterations: max,
                increment,
            });
        }
        Err(Error::NoConvergence {
            iterations: max,
            increment: to_f64(increment),
        })
    }

    /// `max_i |c_pos d_i| / scale_i`: a position increment in scaled units.
    fn scaled_norm(&self, d: &SVector<T, D>, c_pos: T) -> T {
        let mut n = T::zero();
        for (di, s) in d.iter().zip(self.scale.iter()) {
            let e = (*di * c_pos).abs() / *s;
            if e > n {
                n = e;
            }
        }
        n
    }

    /// The Newton correction `dx = −J⁻¹ r` from the factors `lu`, its scaled norm, and its
    /// damping factor λ (1 within the trust radius, else [`Model::damping`]); `Err(norm)`
    /// (nothing damped) when the norm exceeds `reject_above`.
    #[allow(clippy::type_complexity)]
    fn correction(
        &self,
        p: &Problem<'_, T, D>,
        x: &SVector<T, D>,
        r: SVector<T, D>,
        lu: &linalg::Lu<T, D>,
        reject_above: Option<T>,
    ) -> Result<Result<(SVector<T, D>, T, T), T>, Error> {
        let dx = lu.solve(-r).ok_or(Error::Singular)?;
        if !dx.iter().all(|z| z.is_finite()) {
            return Err(Error::Singular);
        }
        let norm = self.scaled_norm(&dx, p.c_pos);
        if reject_above.is_some_and(|limit| norm > limit) {
            return Ok(Err(norm));
        }
        let lambda = if norm > lit(MAX_STEP) {
            self.damping(p, x, &dx, norm, lu)
        } else {
            T::one()
        };
        Ok(Ok((dx, norm, lambda)))
    }

    /// Damping factor λ of a Newton correction `dx` larger than the trust radius `MAX_STEP`:
    /// Deuflhard's affine-invariant natural monotonicity test (Deuflhard 2004, *Newton Methods
    /// for Nonlinear Problems*, §3.3): accept λ when the simplified correction at `x + λ dx`,
    /// `−J⁻¹ r(x + λ dx)` with the same factors, is smaller than `(1 − λ/4)` times `dx` (in the
    /// scaled norm); otherwise halve λ. After [`DAMPING_TRIALS`] trials, or when λ‖dx‖ reaches
    /// the trust radius [`MAX_STEP`], it takes λ = MAX_STEP/‖dx‖ (the plain trust-region cap).
    ///
    /// Why: the plain cap alone limits the whole correction by its largest scaled entry. In a
    /// violent step (3.4 g at resonance, ball spinning at 85 rad/s) that entry is the ball's
    /// spin φ, whose linearized response to the beam's correction is ≈ 35 times larger; the beam
    /// then converged by 5 % per iteration while the spin's target ran away, and Newton failed
    /// after 100 iterations where the undamped correction converges in 6 (docs/stability.md).
    ///
    /// Not inlined: it runs only on violent steps, and inlined it would grow the stack frame
    /// and the code of every Newton iteration.
    #[inline(never)]
    fn damping(
        &self,
        p: &Problem<'_, T, D>,
        x: &SVector<T, D>,
        dx: &SVector<T, D>,
        norm: T,
        lu: &linalg::Lu<T, D>,
    ) -> T {
        let floor = lit::<T>(MAX_STEP) / norm;
        let (one, quarter) = (T::one(), lit::<T>(0.25));
        let mut lambda = one;
        for _ in 0..DAMPING_TRIALS {
            if lambda <= floor {
                break;
            }
            let xt = x + dx * lambda;
            let (r, _) = self.residual_into(
                &(p.q0 + xt * p.ch.c_q),
                &(p.v0 + xt * p.ch.c_v),
                &(p.a0 + xt * p.ch.c_m),
                p.g_eff,
                p.ch,
                p.contact,
                p.plumb,
                None,
            );
            if r.iter().all(|z| z.is_finite()) {
                if let Some(bar) = lu.solve(-r) {
                    let nb = self.scaled_norm(&bar, p.c_pos);
                    if nb <= (one - lambda * quarter) * norm {
                        return lambda;
                    }
                }
            }
            lambda *= lit::<T>(0.5);
        }
        floor
    }

    /// Static equilibrium under gravity (zero base acceleration), a free ball hanging plumb
    /// below the beam end, by load stepping: gravity in steps of at most a quarter, halved after
    /// a failed solve (down to 1/1024), doubled again after a success. Returns the Newton
    /// iterations used. Sets the state to the equilibrium, at rest, and remembers it as the
    /// reference of the potentials. On error the model is unchanged.
    pub fn solve_static(&mut self) -> Result<u32, Error> {
        let z = SVector::<T, D>::zeros();
        let ch = Chain {
            c_q: T::one(),
            c_v: T::zero(),
            c_m: T::zero(),
        };
        let (quarter, smallest) = (lit::<T>(0.25), lit::<T>(1.0 / 1024.0));
        let (mut q, mut done, mut step) = (z, T::zero(), quarter);
        let mut iterations = 0;
        while done < T::one() {
            let target = (done + step).min(T::one());
            let g = self.params.gravity * target;
            match self.newton(&z, &z, &z, q, &ch, T::one(), g, Contact::Off, true, None) {
                Ok(s) => {
                    q = s.x;
                    iterations += s.iterations;
                    done = target;
                    step = (step + step).min(quarter);
                }
                Err(e) => {
                    step *= lit::<T>(0.5);
                    if step < smallest {
                        return Err(Self::static_failure(e, self.params.integrator.tolerance));
                    }
                }
            }
        }
        self.equilibrium = q;
        self.state = State {
            q,
            v: z,
            a: z,
            time: T::zero(),
            steps: 0,
            base_accel: T::zero(),
            contact: Contact::Off,
        };
        Ok(iterations)
    }

    /// The error of a static solve that failed at every load step: when Newton ended within a
    /// few hundred tolerances of convergence it stagnates at the rounding floor of the stiffness
    /// (condition ∝ N⁴: f32 stalls at 1.2e-4 with 64 elements), which is a tolerance this
    /// precision cannot meet, not a hard load step.
    fn static_failure(e: Error, tolerance: T) -> Error {
        match e {
            Error::NoConvergence { increment, .. } if increment < 300.0 * to_f64(tolerance) => {
                Error::InvalidParameter {
                    field: "integrator.tolerance",
                    reason: "is below the rounding floor of this precision with this many elements (the static solve stagnates): raise it, use fewer elements or f64",
                }
            }
            e => e,
        }
    }

    /// Restarts the run at time 0 from the static equilibrium, at rest relative to the base, the
    /// ball at `ball.initial_angle` from the vertical, with input `base_accel` at t = 0; computes
    /// the consistent initial acceleration.
    pub fn restart(&mut self, base_accel: T) -> Result<(), Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        let mut s = State {
            q: self.equilibrium,
            v: SVector::zeros(),
            a: SVector::zeros(),
            time: T::zero(),
            steps: 0,
            base_accel,
            contact: Contact::Off,
        };
        if S::EXTRA_DOFS == 1 {
            if S::STOPS && self.relative_angle(&s).abs() >= self.params.ball.stop_angle {
                return Err(END_BEYOND_STOP);
            }
            // θ(0) = θ_eq + initial angle, i.e. φ decreases by ρ/r_b times the angle.
            let k = self.inertia.orbit_per_spin;
            if let Some(spin) = s.q.get_mut(Self::SPIN) {
                *spin -= self.params.ball.initial_angle / k;
            }
            if S::STOPS && self.relative_angle(&s).abs() >= self.params.ball.stop_angle {
                return Err(START_BEYOND_STOP);
            }
        }
        s.a = self.consistent_acceleration(&s)?.x;
        self.state = s;
        Ok(())
    }

    /// Replaces the state (e.g. restored from storage). The caller vouches for consistency.
    pub fn set_state(&mut self, state: State<T, D>) {
        self.state = state;
    }

    /// Starts from the configuration `q` with velocities `v` (relative to the base) at time 0,
    /// with input `base_accel`; computes the consistent acceleration. The ball is off the stops.
    /// On error the state is unchanged.
    pub fn set_configuration(
        &mut self,
        q: SVector<T, D>,
        v: SVector<T, D>,
        base_accel: T,
    ) -> Result<(), Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        if !q.iter().chain(v.iter()).all(|z| z.is_finite()) {
            return Err(Error::NonFiniteState);
        }
        let mut s = State {
            q,
            v,
            a: SVector::zeros(),
            time: T::zero(),
            steps: 0,
            base_accel,
            contact: Contact::Off,
        };
        if S::STOPS && self.relative_angle(&s).abs() >= self.params.ball.stop_angle {
            return Err(Error::InvalidParameter {
                field: "q",
                reason: "puts the ball beyond a stop",
            });
        }
        s.a = self.consistent_acceleration(&s)?.x;
        self.state = s;
        Ok(())
    }

    fn effective_gravity(&self, base_accel: T) -> T {
        self.params.gravity + base_accel
    }

    /// Solves `r(q, v, a) = 0` for the acceleration at fixed q, v (linear in a: 2 iterations).
    fn consistent_acceleration(&self, s: &State<T, D>) -> Result<Solved<T, D>, Error> {
        let ch = Chain {
            c_q: T::zero(),
            c_v: T::zero(),
            c_m: T::one(),
        };
        let i = &self.params.integrator;
        let c_pos = i.beta * i.step * i.step;
        self.newton(
            &s.q,
            &s.v,
            &SVector::zeros(),
            s.a,
            &ch,
            c_pos,
            self.effective_gravity(s.base_accel),
            s.contact,
            false,
            None,
        )
    }

    /// One Newmark step of length `h` from `s` to the input `base_accel` at its end, with
    /// modified Newton's matrix slot `cache`.
    fn newmark(
        &self,
        s: &State<T, D>,
        h: T,
        base_accel: T,
        cache: &mut Option<CachedJacobian<T, D>>,
    ) -> Result<(State<T, D>, Solved<T, D>), Error> {
        let i = &self.params.integrator;
        let half = lit::<T>(0.5);
        let q_pred = s.q + s.v * h + s.a * (h * h * (half - i.beta));
        let v_pred = s.v + s.a * (h * (T::one() - i.gamma));
        let ch = Chain {
            c_q: i.beta * h * h,
            c_v: i.gamma * h,
            c_m: T::one(),
        };
        let slot = match i.newton {
            NewtonKind::Full => None,
            NewtonKind::Modified => Some(cache),
        };
        let g_eff = self.effective_gravity(base_accel);
        let z = SVector::zeros();
        let solved = self.newton(
            &q_pred, &v_pred, &z, s.a, &ch, ch.c_q, g_eff, s.contact, false, slot,
        )?;
        let a = solved.x;
        let mut next = State {
            q: q_pred + a * ch.c_q,
            v: v_pred + a * ch.c_v,
            a,
            time: s.time + h,
            steps: s.steps,
            base_accel,
            contact: s.contact,
        };
        if let Contact::OnStop(side) = next.contact {
            self.hold_on_stop(&mut next, side);
        }
        Ok((next, solved))
    }

    /// Projects a ball resting on a stop onto α = side·α_max: φ = ψ − (ρ/r_b) α, φ̇ = ψ̇, φ̈ = ψ̈.
    fn hold_on_stop(&self, s: &mut State<T, D>, side: Side) {
        let (psi, rate, acc) = tip::psi_all(&Self::local(&s.q, &s.v, &s.a));
        let lock = side.sign::<T>() * self.params.ball.stop_angle;
        let k = self.inertia.orbit_per_spin;
        if let (Some(q), Some(v), Some(a)) = (
            s.q.get_mut(Self::SPIN),
            s.v.get_mut(Self::SPIN),
            s.a.get_mut(Self::SPIN),
        ) {
            *q = psi - lock / k;
            *v = rate;
            *a = acc;
        }
    }

    /// Relative ball angle α = θ − ψ = (r_b/ρ)(ψ − φ) of a state (0 without a free ball) \[rad\].
    pub(crate) fn relative_angle(&self, s: &State<T, D>) -> T {
        if S::EXTRA_DOFS != 1 {
            return T::zero();
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _) = tip::psi_and_rate(&x);
        self.inertia.orbit_per_spin * (psi - x.q[4])
    }

    /// Advances the model by one step `h` to the new input `base_accel` = ÿ_b(t + h) \[m/s²\]
    /// (the acceleration of the base, measured, positive up).
    ///
    /// On error the state is left exactly as it was.
    pub fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error> {
        if !base_accel.is_finite() {
            return Err(Error::NonFiniteInput);
        }
        let mut cache = self.jacobian.take();
        let result = self.advance(base_accel, &mut cache);
        self.jacobian = cache;
        let (next, report) = result?;
        self.state = next;
        Ok(report)
    }

    /// The step proper: the next state and the report, or an error (nothing is changed).
    fn advance(
        &self,
        base_accel: T,
        cache: &mut Option<CachedJacobian<T, D>>,
    ) -> Result<(State<T, D>, StepReport<T>), Error> {
        let h = self.params.integrator.step;
        let start = self.state;
        let (mut next, solved) = self.newmark(&start, h, base_accel, cache)?;
        next.steps = start.steps.saturating_add(1);
        let mut report = StepReport {
            iterations: solved.iterations,
            increment: solved.increment,
            impact: None,
        };

        if S::STOPS && S::EXTRA_DOFS == 1 {
            match next.contact {
                Contact::Off => {
                    let stop = self.params.ball.stop_angle;
                    let alpha1 = self.relative_angle(&next);
                    if alpha1.abs() > stop {
                        next = self.step_with_impact(
                            &start,
                            &next,
                            h,
                            base_accel,
                            &mut report,
                            cache,
                        )?;
                    }
                }
                Contact::OnStop(side) => {
                    // Release when the stop would have to pull the ball.
                    let force = self.contact_force(&next);
                    if side.sign::<T>() * force > T::zero() {
                        next.contact = Contact::Off;
                    }
                }
            }
        }
        if !(next
            .q
            .iter()
            .chain(next.v.iter())
            .chain(next.a.iter())
            .all(|z| z.is_finite()))
        {
            return Err(Error::NonFiniteState);
        }
        next.time = lit::<T>(next.steps as f64) * h;
        Ok((next, report))
    }

    /// Generalized contact force the stop puts on the ball along θ in a held state.
    fn contact_force(&self, s: &State<T, D>) -> T {
        let z = T::zero();
        let ch = Chain {
            c_q: z,
            c_v: z,
            c_m: z,
        };
        let g = self.effective_gravity(s.base_accel);
        self.residual_into(&s.q, &s.v, &s.a, g, &ch, s.contact, false, None)
            .1
    }

    /// Splits a step that crossed a stop: Newmark to the crossing (located by linear
    /// interpolation of α), impact, consistent acceleration, Newmark to the end of the step.
    fn step_with_impact(
        &self,
        start: &State<T, D>,
        trial: &State<T, D>,
        h: T,
        base_accel: T,
        report: &mut StepReport<T>,
        cache: &mut Option<CachedJacobian<T, D>>,
    ) -> Result<State<T, D>, Error> {
        let alpha1 = self.relative_angle(trial);
        let stop = self.params.ball.stop_angle;
        let side = if alpha1 > T::zero() {
            Side::Positive
        } else {
            Side::Negative
        };
        let target = side.sign::<T>() * stop;
        let tau = self.crossing_fraction(start, trial, h, target);
        let h1 = tau * h;
        let accel_mid = start.base_accel + (base_accel - start.base_accel) * tau;
        let mut mid = if h1 > h * lit(1e-6) {
            let (m, s) = self.newmark(start, h1, accel_mid, cache)?;
            report.iterations += s.iterations;
            report.increment = report.increment.max(s.increment);
            m
        } else {
            *start
        };
        let impact = self.impact(&mut mid, side)?;
        let acc = self.consistent_acceleration(&mid)?;
        report.iterations += acc.iterations;
        mid.a = acc.x;
        let rest = h - h1;
        let mut end = if rest > h * lit(1e-6) {
            let (e, s) = self.newmark(&mid, rest, base_accel, cache)?;
            report.iterations += s.iterations;
            report.increment = report.increment.max(s.increment);
            e
        } else {
            mid
        };
        // A second crossing within the same (remaining) step: the ball came straight back
        // onto the stop; end the step with it resting there (plastic).
        if end.contact == Contact::Off && self.relative_angle(&end).abs() > stop {
            let side2 = if self.relative_angle(&end) > T::zero() {
                Side::Positive
            } else {
                Side::Negative
            };
            self.hold_on_stop(&mut end, side2);
            end.contact = Contact::OnStop(side2);
            let acc = self.consistent_acceleration(&end)?;
            end.a = acc.x;
            if side2.sign::<T>() * self.contact_force(&end) > T::zero() {
                end.contact = Contact::Off;
            }
        }
        report.impact = Some(impact);
        Ok(end)
    }

    /// Relative ball angle rate α̇ = (r_b/ρ)(ψ̇ − φ̇) \[rad/s\].
    pub(crate) fn relative_rate(&self, s: &State<T, D>) -> T {
        if S::EXTRA_DOFS != 1 {
            return T::zero();
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let (_, rate) = tip::psi_and_rate(&x);
        self.inertia.orbit_per_spin * (rate - x.v[4])
    }

    /// Fraction τ ∈ \[0, 1\] of the step at which α reaches `target`: root of the cubic Hermite
    /// interpolant of α through both step ends with their rates (error O(h⁴); a linear
    /// interpolant, error O(h²), misplaces the ball by ~α̈h²/8, which the projection onto the
    /// stop then turns into a potential-energy error).
    fn crossing_fraction(&self, start: &State<T, D>, end: &State<T, D>, h: T, target: T) -> T {
        let (a0, a1) = (
            self.relative_angle(start) - target,
            self.relative_angle(end) - target,
        );
        let (d0, d1) = (self.relative_rate(start) * h, self.relative_rate(end) * h);
        let (two, three) = (lit::<T>(2.0), lit::<T>(3.0));
        let linear = a0 / (a0 - a1);
        let mut tau = if linear.is_finite() {
            linear.max(T::zero()).min(T::one())
        } else {
            T::zero()
        };
        for _ in 0..6 {
            let (t2, t3) = (tau * tau, tau * tau * tau);
            let p = (two * t3 - three * t2 + T::one()) * a0
                + (t3 - two * t2 + tau) * d0
                + (three * t2 - two * t3) * a1
                + (t3 - t2) * d1;
            let dp = (lit::<T>(6.0) * t2 - lit::<T>(6.0) * tau) * (a0 - a1)
                + (three * t2 - lit::<T>(4.0) * tau + T::one()) * d0
                + (three * t2 - two * tau) * d1;
            if !is_positive(dp.abs()) {
                break;
            }
            let next = tau - p / dp;
            if !next.is_finite() {
                break;
            }
            tau = next.max(T::zero()).min(T::one());
        }
        tau
    }

    /// The mass matrix M(q) of a state.
    pub(crate) fn mass_matrix(&self, s: &State<T, D>, contact: Contact) -> SMatrix<T, D, D> {
        let z = T::zero();
        let ch = Chain {
            c_q: z,
            c_v: z,
            c_m: T::one(),
        };
        self.assemble(
            &s.q,
            &s.v,
            &s.a,
            self.effective_gravity(s.base_accel),
            &ch,
            contact,
            false,
        )
        .1
    }

    /// Stop impact (MODEL.md, MODEL-DERIVATION §6): projects the ball onto the stop, applies the
    /// generalized impulse `Λ = −(1+e) Ġ⁻ / (∇G M⁻¹ ∇Gᵀ)` along `∇G = ∂(θ − ψ)/∂q`,
    /// `q̇⁺ = q̇⁻ + M⁻¹ ∇Gᵀ Λ`, and decides whether the ball stays on the stop.
    pub(crate) fn impact(&self, s: &mut State<T, D>, side: Side) -> Result<Impact<T>, Error> {
        let ball = &self.params.ball;
        let lock = side.sign::<T>() * ball.stop_angle;
        let x = Self::local(&s.q, &s.v, &s.a);
        let (psi, _) = tip::psi_and_rate(&x);
        if let Some(spin) = s.q.get_mut(Self::SPIN) {
            *spin = psi - lock / self.inertia.orbit_per_spin;
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let grad_local = tip::gap_gradient(&self.inertia, &x);
        let mut grad = SVector::<T, D>::zeros();
        for (k, gk) in grad_local.iter().enumerate() {
            if let Some(g) = grad.get_mut(Self::END + k) {
                *g = *gk;
            }
        }
        let speed = grad.dot(&s.v);
        let mut impact = Impact {
            time: s.time,
            side,
            relative_speed: speed,
            impulse: T::zero(),
            energy_loss: T::zero(),
            stuck: false,
        };
        let plastic = speed.abs() < ball.stick_speed;
        if side.sign::<T>() * speed > T::zero() {
            let e = if plastic { T::zero() } else { ball.restitution };
            let m = if ball.impact_model == ImpactModel::OverStep {
                let i = &self.params.integrator;
                let h = i.step;
                let ch = Chain {
                    c_q: i.beta * h * h,
                    c_v: i.gamma * h,
                    c_m: T::one(),
                };
                self.assemble(
                    &s.q,
                    &s.v,
                    &s.a,
                    self.effective_gravity(s.base_accel),
                    &ch,
                    Contact::Off,
                    false,
                )
                .1
            } else {
                self.mass_matrix(s, Contact::Off)
            };
            let y = linalg::solve(m, grad).ok_or(Error::Singular)?;
            let w = grad.dot(&y);
            if !is_positive(w) {
                return Err(Error::Singular);
            }
            let lambda = -(T::one() + e) * speed / w;
            s.v += y * lambda;
            // Λ is conjugate to α (N·m·s); the contact point moves at ρ α̇ along the track.
            impact.impulse = lambda / ball.path_radius();
            impact.energy_loss = lit::<T>(0.5) * (T::one() - e * e) * speed * speed / w;
        }
        s.contact = Contact::Off;
        if plastic {
            // Stay on the stop if the contact force is compressive.
            let mut held = *s;
            held.contact = Contact::OnStop(side);
            self.hold_on_stop(&mut held, side);
            let acc = self.consistent_acceleration(&held)?;
            held.a = acc.x;
            if side.sign::<T>() * self.contact_force(&held) <= T::zero() {
                *s = held;
                impact.stuck = true;
            }
        }
        Ok(impact)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{FreeBall, LockedBall};

    /// The assembled Newton matrix is the exact derivative of the residual along the Newmark
    /// chain (central differences, relative 1e-6), at a deformed, fast-moving state, for every
    /// ball mode.
    fn check_jacobian<S: Scene, const N: usize, const D: usize>(contact: Contact) {
        let m = Model::<f64, S, N, D>::new(Params::default()).expect("valid");
        let mut q = SVector::<f64, D>::zeros();
        let mut v = SVector::<f64, D>::zeros();
        let mut a = SVector::<f64, D>::zeros();
        for i in 0..D {
            let f = (i as f64 + 1.0) * 0.37;
            q[i] = 0.01 * f.sin();
            v[i] = 0.5 * (1.3 * f).cos();
            a[i] = 20.0 * (0.7 * f).sin();
        }
        if S::EXTRA_DOFS == 1 {
            q[4 * N] = -2.5;
            v[4 * N] = -40.0;
        }
        let ch = Chain {
            c_q: 0.36 * 9e-6,
            c_v: 0.7 * 3e-3,
            c_m: 1.0,
        };
        let (_, jac, _) = m.assemble(&q, &v, &a, 9.0, &ch, contact, false);
        for j in 0..D {
            let h = 1e-3;
            let mut e = SVector::<f64, D>::zeros();
            e[j] = h;
            let rp = m
                .assemble(
                    &(q + e * ch.c_q),
                    &(v + e * ch.c_v),
                    &(a + e),
                    9.0,
                    &ch,
                    contact,
                    false,
                )
                .0;
            let rm = m
                .assemble(
                    &(q - e * ch.c_q),
                    &(v - e * ch.c_v),
                    &(a - e),
                    9.0,
                    &ch,
                    contact,
                    false,
                )
                .0;
            let fd = (rp - rm) / (2.0 * h);
            for i in 0..D {
                assert!(
                    (fd[i] - jac[(i, j)]).abs() <= 1e-6 * jac.amax(),
                    "J[{i},{j}] = {} but finite differences give {}",
                    jac[(i, j)],
                    fd[i]
                );
            }
        }
    }

    /// The impact operator alone, on a state exactly at the stop: the relative speed reverses
    /// to −e times its value for both impulse metrics, and with the instantaneous metric the
    /// kinetic energy changes by exactly −½(1 − e²) Ġ² / (∇G M⁻¹ ∇Gᵀ) (zero for e = 1),
    /// to rounding (1e-12 of the kinetic energy).
    #[test]
    fn impact_operator_reverses_relative_speed_and_obeys_the_restitution_energy_law() {
        for model in [ImpactModel::Instantaneous, ImpactModel::OverStep] {
            for e in [1.0, 0.5, 0.0] {
                let mut p = Params::<f64>::default();
                p.ball.restitution = e;
                p.ball.impact_model = model;
                let mut m = Model::<f64, FreeBall, 3, 13>::at_rest(p, 0.0).expect("valid");
                let mut s = m.state;
                for i in 0..12 {
                    s.v[i] = 0.05 * ((i as f64) * 1.7).sin();
                }
                // Put the ball on the + stop moving outward at 4 rad/s relative to the housing.
                m.hold_on_stop(&mut s, Side::Positive);
                let k = m.inertia.orbit_per_spin;
                let (_, psi_rate) =
                    tip::psi_and_rate(&Model::<f64, FreeBall, 3, 13>::local(&s.q, &s.v, &s.a));
                s.v[12] = psi_rate - 4.0 / k;
                m.state = s;
                let before = m.relative_rate(&s);
                let t0 = m.energies(0.0, 0.0);
                let mut after = s;
                let imp = m.impact(&mut after, Side::Positive).expect("impact");
                m.state = after;
                let t1 = m.energies(0.0, 0.0);
                let kinetic =
                    |x: &crate::Energies<f64>| x.beam_kinetic + x.tip_kinetic + x.ball_kinetic;
                assert!((before - 4.0).abs() < 1e-9);
                assert!(
                    (m.relative_rate(&after) + e * before).abs() < 1e-9,
                    "{model:?} e={e}"
                );
                assert!(
                    (t1.total() - t0.total() - (kinetic(&t1) - kinetic(&t0))).abs() < 1e-15,
                    "positions unchanged"
                );
                if model == ImpactModel::Instantaneous {
                    let d = kinetic(&t1) - kinetic(&t0);
                    assert!(
                        (d + imp.energy_loss).abs() < 1e-12 * kinetic(&t0),
                        "e={e}: {d} vs {}",
                        imp.energy_loss
                    );
                }
            }
        }
    }

    #[test]
    fn newton_matrix_is_exact_derivative_of_residual() {
        check_jacobian::<FreeBall, 2, 9>(Contact::Off);
        check_jacobian::<FreeBall, 2, 9>(Contact::OnStop(Side::Positive));
        check_jacobian::<LockedBall, 2, 8>(Contact::Off);
    }
}
