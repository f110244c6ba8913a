//! Newton iterations on the Newmark (or static, or acceleration) equations, with a factored
//! Newton matrix that is reused while it still contracts, and damping beyond a trust radius.
//!
//! **Reuse rule** (the same in the full solver, `absorber-full`). An iteration either
//! *refreshes* — assembles the residual and the exact Newton matrix at the current iterate and
//! factors it — or *reuses* the latest factors with a residual alone (no dual numbers, no axial
//! tangent: about a third of the work). A reused matrix must contract the correction by half:
//! if `‖dx_k‖ > ½ ‖dx_{k−1}‖` the correction is not taken and the next iteration refreshes at
//! the same iterate. Which factors may be reused ([`NewtonKind`]):
//! - `PerStep` (default): the first iteration of a step refreshes; every later iteration and
//!   every sub-solve of the same step (an impact's impulse, its consistent acceleration and the
//!   rest of the step) may reuse, whatever their Newmark coefficients — the guard catches a
//!   matrix that no longer fits. One factorization per step is the rule, not the exception.
//! - `Modified`: as `PerStep`, and a step may also start from the previous steps' factors when
//!   they were built for the same step length and contact — except a step that starts with the
//!   ball in flight, which refreshes at once. Its events (a landing, a stop hit in flight) are
//!   found at its end and a landing needs a matrix of its own; the kept factors, from the
//!   housing's earlier flight steps, contract too slowly there: on the paper's input the
//!   costliest landings spent three reused iterations, the third not taken, before the refresh
//!   they then needed anyway (62 work units; refreshing at once, no landing takes more than 44,
//!   and the paper run's mean falls from 26.7 to 25.8 units a step).
//!   Kept factors get at most [`KEPT_ITERATIONS`] iterations in a solve: one that is not
//!   converged by then refreshes at the next (below).
//! - `Full`: every iteration refreshes (the paper's Newton–Raphson; the reference).
//!
//! **Work cap.** Every expensive operation of a step is counted in work units ([`work`]):
//! an assembly with its factorization, a residual, a back-substitution, the pivoting fallback.
//! Each is charged before it runs, against [`crate::Integrator::max_work`] for the whole step —
//! every Newton solve of it (the Newmark solve, the sub-steps and consistent accelerations of
//! an event, the impulse metrics), every damping trial. A Newton solve that cannot afford its
//! next iteration stops with the iterate it has (the step is flagged [`crate::Outcome::Capped`];
//! [`crate::model`] says what follows); a damping trial that cannot be afforded takes the
//! trust-radius cap; an operation that cannot stop early (an impulse's solve, the fallback)
//! fails with [`Error::WorkCap`]. The Newmark solves of a step leave [`work::RESERVE`] units
//! to the events at its end. The work of a step is therefore at most `max_work` units,
//! whatever the input: `docs/embedded.md` turns that into an instruction bound per firmware.
//!
//! **State invariants.** Factors built during a step go to a scratch slot; the slot that
//! modified Newton keeps between steps is replaced only when the step succeeds
//! ([`Workspace::commit`]), so a rejected sample leaves every later step bit for bit as if it
//! had never been offered.

use crate::error::Error;
use crate::params::NewtonKind;
use crate::scalar::{is_positive, lit, to_f64, Real};
use crate::scene::Scene;
use crate::state::Contact;
use crate::step::convergence::{DAMPING_TRIALS, KEPT_ITERATIONS};
use crate::step::linalg::{self, BandMatrix};
use crate::step::system::{Problem, System};
use crate::work;
use nalgebra::{SMatrix, SVector};

/// What a factored matrix was built for.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key<T> {
    c_q: T,
    contact: Contact,
}

/// One factored Newton matrix: banded (the rule), or dense with row exchanges (the fallback
/// when a band pivot is too small).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Factors<T, const D: usize> {
    band: BandMatrix<T, D>,
    dense: SMatrix<T, D, D>,
    /// `None`: the band holds the factors; `Some`: the dense matrix, with these row exchanges.
    pivots: Option<[usize; D]>,
    key: Option<Key<T>>,
}

/// The Newton matrices of a model: not part of the state, but kept inside the model so that
/// `step` neither builds nor copies a matrix on the stack.
#[derive(Clone, Debug, PartialEq)]
pub struct Workspace<T, const D: usize> {
    slots: [Factors<T, D>; 2],
    /// The slot modified Newton keeps between steps.
    kept: usize,
    /// The slot the next iteration may reuse, if any.
    current: Option<usize>,
    /// Factors were built during this step (they go to slot `1 − kept`).
    built: bool,
    /// Off the step path (static solve, start of a run): factor dense with partial pivoting.
    /// The static stiffness has no mass to lean on, and pivoting keeps its rounding floor
    /// where `f32` needs it (N = 16, very short beams).
    pivot: bool,
    /// Work units charged in this step ([`work`]).
    used: u32,
    /// The cap of this step (`Integrator::max_work`; unlimited off the step path).
    cap: u32,
    /// A Newton solve of this step stopped at the cap.
    capped: bool,
    /// ... far from convergence: before any correction, or with a last correction above
    /// [`crate::state::RESTART_INCREMENT`] tolerances (or an event had to wait).
    far: bool,
    /// Band factorizations of this step that fell back to pivoting.
    fallbacks: u32,
    /// Units the current Newton solve leaves to the events at the step's end.
    reserve: u32,
}

impl<T: Real, const D: usize> Default for Workspace<T, D> {
    fn default() -> Self {
        let empty = Factors {
            band: BandMatrix::zeros(),
            dense: SMatrix::zeros(),
            pivots: None,
            key: None,
        };
        Self {
            slots: [empty, empty],
            kept: 0,
            current: None,
            built: false,
            pivot: false,
            used: 0,
            cap: work::UNLIMITED,
            capped: false,
            far: false,
            fallbacks: 0,
            reserve: 0,
        }
    }
}

impl<T: Real, const D: usize> Workspace<T, D> {
    /// Forgets every factorization (after a restart or a new state: nothing may be reused).
    pub(crate) fn clear(&mut self) {
        for s in self.slots.iter_mut() {
            s.key = None;
        }
        self.current = None;
        self.built = false;
    }

    /// Starts a step with the work cap `cap`: modified Newton may reuse the kept factors unless
    /// the step starts with the ball `in_flight` (module doc); the others start afresh.
    pub(crate) fn begin_step(&mut self, kind: NewtonKind, cap: u32, in_flight: bool) {
        self.built = false;
        self.pivot = false;
        self.used = 0;
        self.cap = cap;
        self.capped = false;
        self.far = false;
        self.fallbacks = 0;
        self.current = match kind {
            NewtonKind::Modified if !in_flight => Some(self.kept),
            NewtonKind::Modified | NewtonKind::PerStep | NewtonKind::Full => None,
        };
    }

    /// Starts a solve outside a step (static, initial acceleration): build fresh factors.
    pub(crate) fn begin_solve(&mut self) {
        self.built = false;
        self.current = None;
        self.pivot = true;
        self.used = 0;
        self.cap = work::UNLIMITED;
        self.capped = false;
        self.far = false;
    }

    /// Work units charged in this step so far.
    pub fn used(&self) -> u32 {
        self.used
    }

    /// Whether a Newton solve of this step stopped at the cap.
    pub fn capped(&self) -> bool {
        self.capped
    }

    /// Whether one stopped far from convergence (or an event had to wait for the next step).
    pub fn capped_far(&self) -> bool {
        self.far
    }

    /// The cap of a solve that stopped after its last correction `increment` (none if `taken`
    /// is false), with the tolerance `tol`. Kept out of line (rare): the Newton loop's frame
    /// does not grow.
    #[inline(never)]
    #[cold]
    fn stop_at_cap(&mut self, taken: bool, increment: T, tol: T) {
        self.capped = true;
        let near = increment <= tol * lit(crate::state::RESTART_INCREMENT);
        if !taken || !near {
            self.far = true;
        }
    }

    /// Flags the step as capped (an event it could not afford waits for the next step).
    pub(crate) fn flag_capped(&mut self) {
        self.capped = true;
        self.far = true;
    }

    /// Band factorizations of this step that fell back to pivoting.
    pub fn fallbacks(&self) -> u32 {
        self.fallbacks
    }

    /// Whether `units` more fit under the cap, keeping `reserve` units back.
    #[inline]
    pub(crate) fn affords(&self, units: u32, reserve: u32) -> bool {
        self.used + units + reserve <= self.cap
    }

    /// Charges `units` of work that the step does whatever the cap (its event tests), before its
    /// solves: they then have that much less.
    #[inline]
    pub(crate) fn charge_fixed(&mut self, units: u32) {
        self.used += units;
    }

    /// Charges `units` if they fit under the cap (with nothing held back); `false` otherwise.
    #[inline]
    pub(crate) fn charge(&mut self, units: u32) -> bool {
        if self.affords(units, 0) {
            self.used += units;
            true
        } else {
            false
        }
    }

    /// Charges `units` for an event's test if the cap affords them; otherwise the test is not
    /// made (the event code takes its cheaper branch) and the step is flagged capped.
    pub(crate) fn afford_event(&mut self, units: u32) -> bool {
        let ok = self.charge(units);
        if !ok {
            self.capped = true;
        }
        ok
    }

    /// Whether an event found at the end of the trial step can still afford being split at its
    /// crossing ([`work::SPLIT`]); else it acts at the end of the step.
    pub(crate) fn affords_split(&self) -> bool {
        self.affords(work::SPLIT, 0)
    }

    /// The step succeeded: modified Newton keeps the newest factors.
    pub(crate) fn commit(&mut self) {
        if self.built {
            self.kept = 1 - self.kept;
        }
        self.built = false;
    }

    fn scratch(&self) -> usize {
        1 - self.kept
    }

    /// Whether the latest factors may serve problem `p`.
    fn can_reuse(&self, p: &Problem<'_, T, D>) -> bool {
        let Some(slot) = self.current.and_then(|i| self.slots.get(i)) else {
            return false;
        };
        // Only for the same Newmark coefficient and contact: a matrix built for another
        // chain (a sub-step, an acceleration solve) can be far off in the stiff modes, and the
        // first correction of a solve has no previous one to be checked against.
        slot.key
            .is_some_and(|k| k.contact == p.contact && k.c_q == p.ch.c_q)
    }

    /// Solves `J dx = b` in place with the latest factors; charges [`work::SOLVE`] (an impulse's
    /// solve that the cap cannot afford fails with [`Error::WorkCap`]). Not inlined: the work
    /// bound counts its calls (`docs/embedded.md`).
    #[inline(never)]
    pub(crate) fn solve(&mut self, b: &mut SVector<T, D>) -> Result<(), Error> {
        if !self.charge(work::SOLVE) {
            return Err(Error::WorkCap);
        }
        let f = self
            .current
            .and_then(|i| self.slots.get(i))
            .ok_or(Error::Singular)?;
        let ok = match &f.pivots {
            None => f.band.solve(b),
            Some(p) => linalg::solve(&f.dense, p, b),
        };
        if f.key.is_some() && ok {
            Ok(())
        } else {
            Err(Error::Singular)
        }
    }

    /// Whether the current factors were built for Newmark coefficient `c_q` and `contact`.
    pub(crate) fn has_factors(&self, c_q: T, contact: Contact) -> bool {
        self.current
            .and_then(|i| self.slots.get(i))
            .and_then(|f| f.key)
            .is_some_and(|k| k.contact == contact && k.c_q == c_q)
    }
}

/// Result of one Newton solve.
pub(crate) struct Solved<T, const D: usize> {
    pub x: SVector<T, D>,
    pub iterations: u32,
    pub increment: T,
}

impl<T: Real, S: Scene, const N: usize, const D: usize> System<T, S, N, D> {
    /// Whether an event found at the end of the trial step acts there: events are put at the
    /// step end ([`crate::EventLocation::StepEnd`]), or the step's work cap cannot afford a split
    /// at the crossing ([`work::SPLIT`]).
    #[inline]
    pub(crate) fn event_at_end(&self, ws: &Workspace<T, D>) -> bool {
        self.events_at_step_end() || !ws.affords_split()
    }

    /// Assembles the residual and Newton matrix of `p` at `x` into the scratch slot, factors it
    /// (banded; partial pivoting when a pivot is too small) and makes it the current factors.
    /// Charges [`work::REFRESH`] (and [`work::FALLBACK`] for the fallback): fails with
    /// [`Error::WorkCap`] when the cap cannot afford them.
    pub(crate) fn refresh_at(
        &self,
        p: &Problem<'_, T, D>,
        qva: [&SVector<T, D>; 3],
        ws: &mut Workspace<T, D>,
        r: &mut SVector<T, D>,
    ) -> Result<(), Error> {
        if !ws.charge(work::REFRESH) {
            return Err(Error::WorkCap);
        }
        let i = ws.scratch();
        ws.current = Some(i);
        ws.built = true;
        let pivot = ws.pivot;
        let slot = ws.slots.get_mut(i).ok_or(Error::Singular)?;
        slot.key = None;
        self.assemble_problem(p, qva, r, &mut slot.band);
        let banded = !pivot && slot.band.factor(self.pivot_ratio);
        let pivots = if banded {
            None
        } else {
            if !pivot {
                // The elimination gave up and destroyed the band: assemble it again and pivot —
                // not under a work cap, whose bound counts banded factorizations only (the
                // dense LU's cost grows as D³): there the solve stops at the cap.
                if ws.cap < work::UNLIMITED || !ws.charge(work::FALLBACK) {
                    return Err(Error::WorkCap);
                }
                ws.fallbacks += 1;
            }
            let slot = ws.slots.get_mut(i).ok_or(Error::Singular)?;
            if !pivot {
                self.assemble_problem(p, qva, r, &mut slot.band);
            }
            Some(Self::pivot_fallback(slot)?)
        };
        let slot = ws.slots.get_mut(i).ok_or(Error::Singular)?;
        slot.pivots = pivots;
        slot.key = Some(Key {
            c_q: p.ch.c_q,
            contact: p.contact,
        });
        Ok(())
    }

    /// Residual of `p` at `qva` into `r` and its Newton matrix into `band`.
    #[inline(always)]
    fn assemble_problem(
        &self,
        p: &Problem<'_, T, D>,
        qva: [&SVector<T, D>; 3],
        r: &mut SVector<T, D>,
        band: &mut BandMatrix<T, D>,
    ) {
        self.residual_and_jacobian(qva, p.g_eff, &p.ch, p.contact, p.plumb, r, band);
    }

    /// Factors the assembled matrix dense with partial pivoting: off the step path, or (rare)
    /// when a band pivot was too small. Not inlined: it keeps the dense matrix's code off the
    /// ordinary path (and its frame off the assembly's call chain).
    #[inline(never)]
    #[cold]
    fn pivot_fallback(slot: &mut Factors<T, D>) -> Result<[usize; D], Error> {
        slot.band.write_dense(&mut slot.dense);
        linalg::factor_pivoted(&mut slot.dense).ok_or(Error::Singular)
    }

    /// Newton from the guess `x0` for problem `p`. Convergence:
    /// `max_i |c_pos Δx_i| / scale_i ≤ tolerance`. `kind` says whether factors may be reused
    /// (see the module doc). `step_solve`: a Newmark solve, which may accept its budget
    /// ([`crate::Integrator::accept_after_budget`]) and leaves [`work::RESERVE`] units of the
    /// step's cap to the events at its end. An iteration the cap cannot afford is not begun:
    /// the solve returns the iterate it has and the step is flagged (module doc).
    ///
    /// **Retry.** A Newmark solve with reused factors that ends at `max_iterations` (and is not
    /// accepted there by `accept_after_budget`) is solved again from the same guess with every
    /// iteration refreshed ([`NewtonKind::Full`]), its work charged to the same cap, in the
    /// same frame (a helper's frame would stack over the solve's: +360 B of static stack bound
    /// for the locked ball). Why: far from the solution (a guess thousands of m/s² off, as under
    /// a full-scale input that alternates every sample) the first correction leaves
    /// the trust radius, the damping takes the trust-radius cap, and the reused matrix's next
    /// correction points back along the same unknown: the iterate cycles between two points
    /// (an end-node slope moving ±[`MAX_STEP`] in turn) while the fresh corrections grow
    /// towards a singular matrix (from 6 to 10¹⁴ in the scaled norm over 90 iterations). A
    /// matrix refreshed at every iterate does not cycle: that solve converges in 9–11
    /// iterations. Only a solve that would fail takes this path; every other step is unchanged
    /// bit for bit. A retry stopped by the cap refuses the step as before.
    pub(crate) fn newton(
        &self,
        p: &Problem<'_, T, D>,
        x0: SVector<T, D>,
        ws: &mut Workspace<T, D>,
        mut kind: NewtonKind,
        step_solve: bool,
    ) -> Result<Solved<T, D>, Error> {
        let max = self.params.integrator.max_iterations;
        let tol = self.params.integrator.tolerance;
        ws.reserve = if step_solve { work::RESERVE } else { 0 };
        let half = lit::<T>(0.5);
        // The retry (module doc): a step solve with reused factors that fails is solved again
        // from the same guess with a fresh matrix at every iteration, in this frame (a helper's
        // would stack over it). `first`: the failed solve's error; `before`: the cap flag then.
        let mut first: Option<Error> = None;
        let mut before = false;
        'solve: loop {
            let mut x = x0;
            // Iterations of the failed solve, counted into the retry's.
            let spent = match first {
                Some(Error::NoConvergence { iterations, .. }) => iterations,
                _ => 0,
            };
            let mut increment = T::zero();
            let mut previous = T::zero();
            let mut refresh = false;
            let mut qva = [SVector::<T, D>::zeros(); 3];
            let mut dx = SVector::<T, D>::zeros();
            // The iterations done when the cap stopped the solve (`u32::MAX`: it did not).
            let mut stopped = u32::MAX;
            for it in 1..=max {
                let can = kind != NewtonKind::Full && ws.can_reuse(p);
                // Near the cap a refresh that cannot be afforded gives way to the factors in hand,
                // whose correction is then taken if it contracts at all.
                let fresh = !refresh && can;
                let forced = !fresh && can && !ws.affords(work::REFRESH + work::SOLVE, ws.reserve);
                let reuse = fresh || forced;
                let cost = if reuse { work::RESIDUAL } else { work::REFRESH };
                if !ws.affords(cost + work::SOLVE, ws.reserve) {
                    // The cap: the iterate so far stands, flagged.
                    ws.stop_at_cap(it > 1, increment, tol);
                    stopped = it - 1;
                    break;
                }
                p.at(&x, &mut qva);
                let [q, v, a] = &qva;
                if reuse {
                    ws.used += work::RESIDUAL;
                    self.residual([q, v, a], p.g_eff, p.contact, p.plumb, &mut dx);
                } else {
                    match self.refresh_at(p, [q, v, a], ws, &mut dx) {
                        // A matrix the banded LU refuses, under a work cap: the iterate so far.
                        Err(Error::WorkCap) => {
                            ws.stop_at_cap(false, increment, tol);
                            stopped = it - 1;
                            break;
                        }
                        r => r?,
                    }
                }
                if !dx.as_slice().iter().all(|z| z.is_finite()) {
                    return Err(Error::NonFiniteState);
                }
                dx.neg_mut();
                ws.solve(&mut dx)?;
                let norm = self.scaled_norm(&dx, p.c_pos);
                if forced && norm >= previous {
                    // The factors in hand do not contract and no others can be afforded: the cap.
                    ws.stop_at_cap(it > 1, previous, tol);
                    increment = previous;
                    stopped = it;
                    break;
                }
                // Not taken: the reused matrix no longer fits (it did not contract by half, or,
                // with factors kept from an earlier step (modified Newton) in the solve's first
                // iteration, where there is nothing to compare with, its correction leaves the
                // trust radius); refresh at the same iterate.
                if reuse
                    && !forced
                    && ((it > 1 && norm > previous * half)
                        || (it == 1 && !ws.built && norm > self.max_step))
                {
                    increment = norm;
                    refresh = true;
                    continue;
                }
                // Taken; but a matrix that contracts slowly (θ > SLOW) would cost more iterations
                // than a fresh one, which converges quadratically: refresh at the next iteration;
                // so do factors kept from an earlier step after `KEPT_ITERATIONS` iterations
                // (every iteration of this solve so far reused them: none was built).
                refresh = reuse
                    && it > 1
                    && (norm > previous * self.slow || (!ws.built && it >= KEPT_ITERATIONS));
                let lambda = if norm > self.max_step {
                    self.damping(p, &x, &dx, norm, ws)
                } else {
                    T::one()
                };
                x.axpy(lambda, &dx, T::one());
                increment = norm;
                // A fresh matrix's correction converges quadratically: what is left after it is far
                // below `tol`. A reused one's converges linearly with the observed contraction
                // θ = ‖dx_k‖/‖dx_{k−1}‖, and leaves ≈ θ/(1−θ)‖dx_k‖ (Hairer & Wanner, *Solving
                // ODEs II*, IV.8): demand that be below `tol`/100 too, so that the solution is as
                // close to the exact discrete one as full Newton's.
                let settled = !reuse || it == 1 || {
                    let theta = norm / previous;
                    theta * norm <= (T::one() - theta) * self.settle
                };
                if norm <= tol && settled {
                    if first.is_some() {
                        ws.capped = before;
                    }
                    return Ok(Solved {
                        x,
                        iterations: it.saturating_add(spent),
                        increment,
                    });
                }
                previous = norm;
            }
            if stopped != u32::MAX {
                if let Some(e) = first {
                    // The retry stopped at the cap: the step is refused as before, state kept.
                    ws.capped = before;
                    return Err(e);
                }
                return Ok(Solved {
                    x,
                    iterations: stopped,
                    increment,
                });
            }
            if self.params.integrator.accept_after_budget && step_solve {
                if first.is_some() {
                    ws.capped = before;
                }
                return Ok(Solved {
                    x,
                    iterations: max.saturating_add(spent),
                    increment,
                });
            }
            let e = Error::NoConvergence {
                iterations: max,
                increment: to_f64(increment),
            };
            if first.is_some() || !step_solve || kind == NewtonKind::Full {
                if first.is_some() {
                    ws.capped = before;
                }
                return Err(e);
            }
            first = Some(e);
            before = core::mem::replace(&mut ws.capped, false);
            kind = NewtonKind::Full;
            continue 'solve;
        }
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
    /// Each trial is a residual and a back-substitution charged to the step's work; a trial the
    /// cap (less the solve's reserve) cannot afford is not made, and the trust-radius cap is
    /// taken.
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
        ws: &mut Workspace<T, D>,
    ) -> T {
        let floor = self.max_step / norm;
        let (one, quarter) = (T::one(), lit::<T>(0.25));
        let mut lambda = one;
        let mut qva = [SVector::<T, D>::zeros(); 3];
        let mut bar = SVector::<T, D>::zeros();
        for _ in 0..DAMPING_TRIALS {
            if lambda <= floor || !ws.affords(work::RESIDUAL + work::SOLVE, ws.reserve) {
                break;
            }
            ws.used += work::RESIDUAL;
            // The trial point in `bar` (its residual overwrites it): no third vector here.
            bar.copy_from(x);
            bar.axpy(lambda, dx, one);
            p.at(&bar, &mut qva);
            let [q, v, a] = &qva;
            self.residual([q, v, a], p.g_eff, p.contact, p.plumb, &mut bar);
            if bar.as_slice().iter().all(|z| z.is_finite()) {
                bar.neg_mut();
                if ws.solve(&mut bar).is_ok() {
                    let nb = self.scaled_norm(&bar, p.c_pos);
                    if nb <= (one - lambda * quarter) * norm {
                        return lambda;
                    }
                }
            }
            lambda *= lit::<T>(0.5);
        }
        if is_positive(floor) {
            floor
        } else {
            one
        }
    }
}
