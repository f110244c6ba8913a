//! The equations of motion of a scene: residual `r(q, q̇, q̈)` and Newton matrix, assembled from
//! the beam ([`crate::step::beam`]) and the tip body and ball ([`crate::step::tip`]).
//!
//! [`System`] holds everything that stays fixed during a run (parameters, the beam's
//! precomputed element data, the tip inertia, the static equilibrium, the unknowns' scales);
//! the step path borrows it immutably next to the Newton workspace
//! ([`crate::step::newton::Workspace`]) and the state.

use crate::error::Error;
use crate::loads::SceneData;
use crate::params::Params;
use crate::scalar::{lit, Real};
use crate::scene::{BallKind, Scene};
use crate::state::{Contact, State};
use crate::step::ancf::TangentBlocks;
use crate::step::beam::Beam;
use crate::step::convergence::MAX_STEP;
use crate::step::dual::Plain;
use crate::step::linalg::{BandMatrix, PIVOT_RATIO};
use crate::step::scheme::Chain;
use crate::step::tip::{self, BallMode, LocalState, TipInertia, D5, LOCAL};
use core::marker::PhantomData;
use nalgebra::{SMatrix, SVector};

/// What stays fixed during a run of scene `S` with `N` elements and `D` unknowns.
#[derive(Clone, Debug)]
pub struct System<T: Real, S: Scene, const N: usize, const D: usize> {
    pub(crate) params: Params<T>,
    pub(crate) beam: Beam<T>,
    pub(crate) inertia: TipInertia<T>,
    /// The tip body without the ball (the housing while the ball flies).
    pub(crate) flight_inertia: TipInertia<T>,
    /// Static equilibrium (zero relative velocity) the run started from.
    pub(crate) equilibrium: SVector<T, D>,
    /// Scale of each unknown for the convergence test: beam length for positions, 1 otherwise.
    pub(crate) scale: SVector<T, D>,
    /// [`PIVOT_RATIO`] and [`MAX_STEP`] in the scalar (converted once, not per step).
    pub(crate) pivot_ratio: T,
    pub(crate) max_step: T,
    /// What a reused matrix's estimated remaining error must be below:
    /// `max(SETTLE · tolerance, 8ε)` ([`crate::step::convergence::SETTLE`]; not below the rounding floor
    /// of the precision, which `f32` reaches first: 9.5e-7).
    pub(crate) settle: T,
    /// [`crate::step::convergence::SLOW`] in the scalar.
    pub(crate) slow: T,
    /// The generalized-α recursion's constants (`None`: Newmark).
    pub(crate) alpha: Option<crate::step::scheme::AlphaRecursion<T>>,
    /// What the scene adds: loads, per-element sections (`()` for the paper's scenes).
    pub(crate) data: S::Data<T, N>,
    /// Where a restart puts the model (computed with the static equilibrium).
    pub(crate) rest: Rest<T, D>,
    _scene: PhantomData<S>,
}

/// The state a restart puts the model in, precomputed off the step path: the configuration
/// (static equilibrium, the ball at its initial angle), at rest, whose consistent acceleration
/// is affine in the input, `a(ÿ_b) = a₀ + ÿ_b a₁` (at zero velocity the residual is linear in
/// the acceleration and in the effective gravity `g + ÿ_b`), so that a restart costs a few
/// vector operations, within any step's work.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rest<T, const D: usize> {
    pub q: SVector<T, D>,
    pub a0: SVector<T, D>,
    pub a1: SVector<T, D>,
    /// The map was computed (a start that is not possible has none: no restart then).
    pub ready: bool,
}

/// What a Newton solve solves: `r(q₀ + c_q x, v₀ + c_v x, a₀ + c_m x) = 0` for `x`, at
/// effective gravity `g_eff`, in a contact state, the free ball optionally pinned plumb; `c_pos`
/// converts `x` to a position for the convergence test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Problem<'a, T, const D: usize> {
    pub q0: &'a SVector<T, D>,
    pub v0: &'a SVector<T, D>,
    pub a0: &'a SVector<T, D>,
    pub ch: Chain<T>,
    pub c_pos: T,
    pub g_eff: T,
    pub contact: Contact,
    pub plumb: bool,
}

impl<T: Real, const D: usize> Problem<'_, T, D> {
    /// `(q, v, a)` at the unknown `x`.
    #[inline]
    pub fn at(&self, x: &SVector<T, D>, out: &mut [SVector<T, D>; 3]) {
        let [q, v, a] = out;
        fn sl<T, const D: usize>(x: &SVector<T, D>) -> core::slice::Iter<'_, T> {
            x.as_slice().iter()
        }
        let outs = q.as_mut_slice().iter_mut();
        let outs = outs
            .zip(v.as_mut_slice().iter_mut())
            .zip(a.as_mut_slice().iter_mut());
        let ins = sl(x).zip(sl(self.q0).zip(sl(self.v0)).zip(sl(self.a0)));
        for (((qi, vi), ai), (xi, ((q0, v0), a0))) in outs.zip(ins) {
            *qi = *q0 + *xi * self.ch.c_q;
            *vi = *v0 + *xi * self.ch.c_v;
            *ai = *a0 + *xi * self.ch.c_m;
        }
    }
}

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// Index of the end node's first coordinate.
    pub(crate) const END: usize = 4 * N - 4;
    /// Index of the ball spin φ (free ball only).
    pub(crate) const SPIN: usize = 4 * N;

    /// Precomputes the fixed data from validated parameters.
    pub(crate) fn new(params: Params<T>) -> Self {
        let b = &params.beam;
        // The calibration's factors are folded in here, once (the step never sees them).
        let element = crate::step::ancf::Element::of_beam(b, &params.calibration, N);
        let mut scale = SVector::<T, D>::from_element(T::one());
        for node in 0..N {
            for c in 0..2 {
                if let Some(s) = scale.get_mut(4 * node + c) {
                    *s = b.length;
                }
            }
        }
        let beam = Beam::with_lumping(
            element,
            params.damping.stiffness_proportional,
            params.calibration.mass_lumping,
        );
        Self {
            inertia: TipInertia::new(&params, S::HAS_TIP, S::BALL),
            flight_inertia: TipInertia::new(&params, S::HAS_TIP, BallKind::None),
            data: SceneData::uniform(&beam),
            beam,
            params,
            equilibrium: SVector::zeros(),
            scale,
            pivot_ratio: lit(PIVOT_RATIO),
            max_step: lit(MAX_STEP),
            settle: {
                let want = lit::<T>(crate::step::convergence::SETTLE) * params.integrator.tolerance;
                let floor = T::default_epsilon() * lit(8.0);
                if want > floor {
                    want
                } else {
                    floor
                }
            },
            slow: lit(crate::step::convergence::SLOW),
            alpha: crate::step::scheme::AlphaRecursion::of(&params.integrator),
            rest: Rest {
                q: SVector::zeros(),
                a0: SVector::zeros(),
                a1: SVector::zeros(),
                ready: false,
            },
            _scene: PhantomData,
        }
    }

    /// The tip's five local coordinates (end node, spin) of a global state.
    pub(crate) fn local(q: &SVector<T, D>, v: &SVector<T, D>, a: &SVector<T, D>) -> LocalState<T> {
        let mut x = LocalState {
            q: [T::zero(); LOCAL],
            v: [T::zero(); LOCAL],
            a: [T::zero(); LOCAL],
        };
        let n = if S::EXTRA_DOFS == 1 { LOCAL } else { 4 };
        let end = Self::END;
        for (src, dst) in [(q, &mut x.q), (v, &mut x.v), (a, &mut x.a)] {
            if let Some(s) = src.as_slice().get(end..end + n) {
                for (d, v) in dst.iter_mut().zip(s.iter()) {
                    *d = *v;
                }
            }
        }
        x
    }

    fn ball_mode(&self, contact: Contact, plumb: bool) -> BallMode<T> {
        match (S::BALL, contact) {
            (BallKind::None, _) => BallMode::Absent,
            (BallKind::Locked, _) => BallMode::Held(T::zero()),
            (BallKind::Free, Contact::Off) if plumb => BallMode::Plumb,
            (BallKind::Free, Contact::Off | Contact::Beyond) => BallMode::Free,
            (BallKind::Free, Contact::OnStop(side)) => {
                BallMode::Held(side.sign::<T>() * self.params.ball.stop_angle)
            }
            (BallKind::Free, Contact::InFlight) => BallMode::Flying,
        }
    }

    /// The inertia of the tip rows in `mode` (the tip body alone while the ball flies).
    #[inline]
    fn inertia_of(&self, mode: BallMode<T>) -> &TipInertia<T> {
        if S::FLIGHT && mode == BallMode::Flying {
            &self.flight_inertia
        } else {
            &self.inertia
        }
    }

    /// The ball may leave the track in this run (scene type and `ball.flight`).
    #[inline]
    pub(crate) fn flies(&self) -> bool {
        S::FLIGHT && self.params.ball.flight
    }

    /// Residual of the equations of motion at `(q, v, a)` into `r` (overwritten); returns the
    /// generalized contact force on the ball along θ. Not inlined: the work bound counts its
    /// calls (`docs/embedded.md`).
    #[inline(never)]
    pub(crate) fn residual(
        &self,
        qva: [&SVector<T, D>; 3],
        g_eff: T,
        contact: Contact,
        plumb: bool,
        r: &mut SVector<T, D>,
    ) -> T {
        let [q, v, a] = qva;
        r.fill(T::zero());
        if self.data.loads().is_none() && self.data.sections().is_none() {
            self.beam.residual(N, (q, v, a), g_eff, r);
        } else {
            for k in 0..N {
                let (b, applied) = self.element_and_force(k, g_eff);
                b.element_residual(k, (q, v, a), &applied, r);
            }
            self.subtract_tip_force(r);
        }
        if !S::HAS_TIP {
            return T::zero();
        }
        let x = Self::local(q, v, a);
        let mode = self.ball_mode(contact, plumb);
        let zero = T::zero();
        let ch = Chain {
            c_q: zero,
            c_v: zero,
            c_m: zero,
        };
        let (rows, force) = tip::residual::<T, Plain<T>>(
            self.inertia_of(mode),
            &x,
            &ch,
            g_eff,
            mode,
            S::EXTRA_DOFS == 1,
        );
        if let Some(dst) = r.as_mut_slice().get_mut(Self::END..) {
            for (d, row) in dst.iter_mut().zip(rows.iter()) {
                *d += row.0;
            }
        }
        force
    }

    /// Residual into `r` and the Newton matrix `c_m ∂r/∂a + c_v ∂r/∂v + c_q ∂r/∂q` into `jac`
    /// (both overwritten); returns the generalized contact force on the ball along θ. The tip
    /// rows run in dual numbers (exact derivatives). Not inlined: the refresh and the rare
    /// pivoting fallback share one copy (LTO once inlined it into both, with 17 KB more flash
    /// and 1 KB more stack, after an unrelated change elsewhere in the firmware).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(crate) fn residual_and_jacobian(
        &self,
        qva: [&SVector<T, D>; 3],
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        plumb: bool,
        r: &mut SVector<T, D>,
        jac: &mut BandMatrix<T, D>,
    ) -> T {
        let [q, v, a] = qva;
        r.fill(T::zero());
        jac.clear();
        if self.data.loads().is_none() && self.data.sections().is_none() {
            self.beam
                .residual_and_jacobian(N, (q, v, a), g_eff, ch, r, jac);
        } else {
            for k in 0..N {
                let (b, applied) = self.element_and_force(k, g_eff);
                b.element_residual_and_jacobian(k, (q, v, a), &applied, ch, r, jac);
            }
            self.subtract_tip_force(r);
        }
        self.add_tip_rows(qva, g_eff, ch, contact, plumb, r, jac)
    }

    /// The tip rows of [`System::residual_and_jacobian`]: their residual added into `r`, their
    /// Newton matrix (dual numbers) into `jac`; returns the contact force (zero without a tip).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_tip_rows(
        &self,
        [q, v, a]: [&SVector<T, D>; 3],
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        plumb: bool,
        r: &mut SVector<T, D>,
        jac: &mut BandMatrix<T, D>,
    ) -> T {
        if !S::HAS_TIP {
            return T::zero();
        }
        let x = Self::local(q, v, a);
        let mode = self.ball_mode(contact, plumb);
        let (rows, force) = tip::residual::<T, D5<T>>(
            self.inertia_of(mode),
            &x,
            ch,
            g_eff,
            mode,
            S::EXTRA_DOFS == 1,
        );
        let n = if S::EXTRA_DOFS == 1 { LOCAL } else { 4 };
        for (i, row) in rows.iter().enumerate().take(n) {
            if let Some(dst) = r.get_mut(Self::END + i) {
                *dst += row.re;
            }
            for (j, d) in row.du.iter().enumerate().take(n) {
                jac.add(Self::END + i, Self::END + j, *d);
            }
        }
        force
    }

    /// The Newton matrix `c_m ∂r/∂a + c_v ∂r/∂v + c_q ∂r/∂q` into `jac` (overwritten), the
    /// same numbers as [`System::residual_and_jacobian`] without the residual: the
    /// estimator's `∂r/∂q` and `∂r/∂v` at a step's end. With `c_q = 0` the beam's axial
    /// tangent is not evaluated ([`Beam::add_element_jacobian`]); otherwise the root
    /// element's tangent blocks are returned (the root stress's gradient needs them).
    #[inline(never)]
    pub(crate) fn jacobian(
        &self,
        qva: [&SVector<T, D>; 3],
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        jac: &mut BandMatrix<T, D>,
    ) -> Option<TangentBlocks<T>> {
        let root = self.beam_jacobian(qva[0], ch, jac);
        self.add_tip_jacobian(qva, g_eff, ch, contact, jac);
        root
    }

    /// The beam's part of [`System::jacobian`] (`jac` overwritten): with `c_q = 0` it does not
    /// depend on the state (the estimator keeps its `∂r/∂v`).
    pub(crate) fn beam_jacobian(
        &self,
        q: &SVector<T, D>,
        ch: &Chain<T>,
        jac: &mut BandMatrix<T, D>,
    ) -> Option<TangentBlocks<T>> {
        jac.clear();
        let mut root = None;
        for k in 0..N {
            let b = self
                .data
                .sections()
                .and_then(|s| s.get(k))
                .map_or(&self.beam, |s| &s.beam);
            let tangent = b.add_element_jacobian(k, q, ch, jac);
            if k == 0 {
                root = tangent;
            }
        }
        root
    }

    /// The tip rows' part of [`System::jacobian`], added into `jac` after the beam's.
    pub(crate) fn add_tip_jacobian(
        &self,
        qva: [&SVector<T, D>; 3],
        g_eff: T,
        ch: &Chain<T>,
        contact: Contact,
        jac: &mut BandMatrix<T, D>,
    ) {
        let mut r = SVector::<T, D>::zeros();
        self.add_tip_rows(qva, g_eff, ch, contact, false, &mut r, jac);
    }

    /// Element `k`'s matrices and applied force (weight, point masses' weight, line load) of a
    /// scene with loads or sections ([`crate::loads`]).
    #[inline]
    pub(crate) fn element_and_force(
        &self,
        k: usize,
        g_eff: T,
    ) -> (&Beam<T>, crate::step::ancf::ElementVector<T>) {
        let (b, mut applied) = match self.data.sections().and_then(|s| s.get(k)) {
            Some(sec) => (&sec.beam, sec.weight(g_eff)),
            None => (&self.beam, self.beam.element.gravity_force(g_eff)),
        };
        if let Some(w) = self.data.loads().and_then(|l| l.line_load.get(k)) {
            applied += b.element.line_load_force(*w);
        }
        (b, applied)
    }

    /// `r₂` of the end node: `r −= P` for the tip force P (positive up).
    #[inline]
    fn subtract_tip_force(&self, r: &mut SVector<T, D>) {
        if let (Some(l), Some(x)) = (self.data.loads(), r.get_mut(Self::END + 1)) {
            *x -= l.tip_force;
        }
    }

    /// Residual, Newton matrix and contact force by value (off the step path: modes, tests).
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
        let mut r = SVector::zeros();
        let mut jac = BandMatrix::zeros();
        let f = self.residual_and_jacobian([q, v, a], g_eff, ch, contact, plumb, &mut r, &mut jac);
        (r, jac.to_dense(), f)
    }

    /// Effective gravity `g + ÿ_b` \[m/s²\] (the frame translating with the base).
    #[inline]
    pub(crate) fn effective_gravity(&self, base_accel: T) -> T {
        self.params.gravity + base_accel
    }

    /// `max_i |c_pos d_i| / scale_i`: a position increment in scaled units.
    pub(crate) fn scaled_norm(&self, d: &SVector<T, D>, c_pos: T) -> T {
        let mut n = T::zero();
        for (di, s) in d.as_slice().iter().zip(self.scale.as_slice().iter()) {
            let e = (*di * c_pos).abs() / *s;
            if e > n {
                n = e;
            }
        }
        n
    }

    /// Generalized contact force the stop (or housing) puts on the ball along θ in a state.
    pub(crate) fn contact_force(&self, s: &State<T, D>) -> T {
        let mut r = SVector::zeros();
        let g = self.effective_gravity(s.base_accel);
        self.residual([&s.q, &s.v, &s.a], g, s.contact, false, &mut r)
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

    /// Relative ball angle rate α̇ = (r_b/ρ)(ψ̇ − φ̇) \[rad/s\].
    pub(crate) fn relative_rate(&self, s: &State<T, D>) -> T {
        if S::EXTRA_DOFS != 1 {
            return T::zero();
        }
        let x = Self::local(&s.q, &s.v, &s.a);
        let (_, rate) = tip::psi_and_rate(&x);
        self.inertia.orbit_per_spin * (rate - x.v[4])
    }

    /// The state is finite (checked on the slices: nalgebra's strided iterator costs ~40
    /// instructions an entry on the M4).
    pub(crate) fn is_finite(s: &State<T, D>) -> Result<(), Error> {
        let all = |x: &SVector<T, D>| x.as_slice().iter().all(|z| z.is_finite());
        if all(&s.q) && all(&s.v) && all(&s.a) {
            Ok(())
        } else {
            Err(Error::NonFiniteState)
        }
    }
}
