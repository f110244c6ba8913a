//! Running indicators over a fixed window: RMS and peak tip deflection about the static value,
//! RMS ball angle relative to the housing, mean beam and ball energies, and the absorber
//! effectiveness against a locked-ball twin.
//!
//! The window holds the last `W` **blocks** of `block` samples each (a ring in a
//! [`heapless::Vec`]: filled by `push`, then overwritten oldest first through `get_mut`, so no
//! access can panic and the storage starts uninitialized). A block stores the mean square and
//! the peak of each signal over its samples, so RMS and peak over the window are exact for the
//! `W · block` samples it covers while the memory is `W` blocks. Per sample the work is O(1);
//! reading the indicators scans the `W` blocks (O(W)), so read them at a low rate (e.g. once
//! per second).
//!
//! - `tip_rms = √(mean (y − y_static)²)`, `tip_peak = max |y − y_static|` \[m\]
//!   (y = tip deflection relative to the base, y_static = static deflection of the run);
//! - `ball_rms = √(mean α²)` \[rad\], α = θ − ψ;
//! - `beam_energy`: beam strain energy above the static one + beam kinetic + beam gravity
//!   potential; `ball_energy`: ball kinetic (translation + spin) + gravity potential \[J\], both in
//!   the frame moving with the base ([`crate::Model::energies`] with zero base velocity);
//! - `effectiveness = tip_rms(free) / tip_rms(locked twin)`: below 1 the free ball reduces the
//!   tip motion compared with the same mass locked (the paper's passive case), above 1 it makes
//!   it worse.

use crate::scalar::{lit, Real};
use heapless::Vec;

/// Aggregates of one block of samples. `X` is the twin's share (`()` without a twin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block<T, X> {
    /// Samples in the block.
    pub samples: u16,
    /// Σ (y − y_static)² \[m²\].
    pub tip_sq: T,
    /// max |y − y_static| \[m\].
    pub tip_peak: T,
    /// Σ α² \[rad²\].
    pub ball_sq: T,
    /// Σ beam energy \[J\].
    pub beam_energy: T,
    /// Σ ball energy \[J\].
    pub ball_energy: T,
    /// Twin: Σ (y_twin − y_twin,static)² \[m²\], or `()`.
    pub twin_sq: X,
}

/// One sample of the signals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<T, X> {
    /// Tip deflection about the static value \[m\].
    pub tip: T,
    /// Ball angle relative to the housing \[rad\] (0 without a ball).
    pub ball: T,
    /// Beam energy \[J\].
    pub beam_energy: T,
    /// Ball energy \[J\].
    pub ball_energy: T,
    /// Twin's tip deflection about its static value \[m\], or `()`.
    pub twin: X,
}

/// A twin's per-sample share of the window: `()` (nothing) or a scalar.
pub trait TwinValue<T>: Copy {
    /// Zero.
    fn zero() -> Self;
    /// Adds the square of `sample` to `acc`.
    fn accumulate(acc: &mut Self, sample: Self);
    /// The accumulated value, if there is a twin.
    fn value(self) -> Option<T>;
}

impl<T> TwinValue<T> for () {
    fn zero() -> Self {}
    fn accumulate(_: &mut Self, _: Self) {}
    fn value(self) -> Option<T> {
        None
    }
}

/// A twin's tip deflection (newtype so that `()` and scalars cannot overlap).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinTip<T>(pub T);

impl<T: Real> TwinValue<T> for TwinTip<T> {
    fn zero() -> Self {
        TwinTip(T::zero())
    }
    fn accumulate(acc: &mut Self, sample: Self) {
        acc.0 += sample.0 * sample.0;
    }
    fn value(self) -> Option<T> {
        Some(self.0)
    }
}

/// The indicators over the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndicatorValues<T> {
    /// Samples covered.
    pub samples: u32,
    /// RMS tip deflection about the static value \[m\].
    pub tip_rms: T,
    /// Peak |tip deflection − static| \[m\].
    pub tip_peak: T,
    /// RMS ball angle relative to the housing \[rad\].
    pub ball_rms: T,
    /// Mean beam energy \[J\].
    pub beam_energy: T,
    /// Mean ball energy \[J\].
    pub ball_energy: T,
    /// RMS tip deflection of the locked-ball twin \[m\] (with a twin).
    pub twin_tip_rms: Option<T>,
    /// `tip_rms / twin_tip_rms` \[-\] (with a twin; `None` if the twin is at rest).
    pub effectiveness: Option<T>,
}

/// Window of `W` blocks.
#[derive(Clone, Debug)]
pub struct Indicators<T, X, const W: usize> {
    block_len: u16,
    current: Block<T, X>,
    /// Ring of completed blocks, filled by `push`; once full, `window[next]` is the oldest.
    window: Vec<Block<T, X>, W>,
    next: usize,
}

impl<T: Real, X: TwinValue<T>> Block<T, X> {
    fn zero() -> Self {
        let z = T::zero();
        Self {
            samples: 0,
            tip_sq: z,
            tip_peak: z,
            ball_sq: z,
            beam_energy: z,
            ball_energy: z,
            twin_sq: X::zero(),
        }
    }
}

impl<T: Real, X: TwinValue<T>, const W: usize> Indicators<T, X, W> {
    /// Window of `W` blocks of `block_len` ≥ 1 samples. Inlined: built straight into its
    /// destination (a monitor built in place, `crate::monitor::Monitor::new_in`).
    #[inline(always)]
    pub fn new(block_len: u16) -> Self {
        Self {
            block_len: block_len.max(1),
            current: Block::zero(),
            window: Vec::new(),
            next: 0,
        }
    }

    /// Samples per block.
    pub fn block_len(&self) -> u16 {
        self.block_len
    }

    /// Adds one sample (O(1)).
    pub fn push(&mut self, s: Sample<T, X>) {
        let b = &mut self.current;
        b.samples += 1;
        b.tip_sq += s.tip * s.tip;
        if s.tip.abs() > b.tip_peak {
            b.tip_peak = s.tip.abs();
        }
        b.ball_sq += s.ball * s.ball;
        b.beam_energy += s.beam_energy;
        b.ball_energy += s.ball_energy;
        X::accumulate(&mut b.twin_sq, s.twin);
        if b.samples >= self.block_len {
            self.store(self.current);
            self.current = Block::zero();
        }
    }

    /// Appends a completed block, or once the window is full writes it over the oldest one
    /// (O(1); `push` and `get_mut` cannot panic).
    fn store(&mut self, block: Block<T, X>) {
        if let Err(block) = self.window.push(block) {
            if let Some(slot) = self.window.get_mut(self.next) {
                *slot = block;
            }
            self.next += 1;
            if self.next >= W {
                self.next = 0;
            }
        }
    }

    /// The indicators over the completed blocks in the window (O(W)).
    pub fn values(&self) -> IndicatorValues<T> {
        let z = T::zero();
        let (mut n, mut tip, mut peak, mut ball, mut be, mut bb) = (0u32, z, z, z, z, z);
        let mut twin = X::zero();
        let mut twin_sum = z;
        // Storage order, not time order (sums do not care).
        for b in self.window.as_slice() {
            n += u32::from(b.samples);
            tip += b.tip_sq;
            if b.tip_peak > peak {
                peak = b.tip_peak;
            }
            ball += b.ball_sq;
            be += b.beam_energy;
            bb += b.ball_energy;
            twin = b.twin_sq;
            if let Some(v) = twin.value() {
                twin_sum += v;
            }
        }
        let count: T = lit(f64::from(n.max(1)));
        let tip_rms = (tip / count).sqrt();
        let twin_tip_rms = twin.value().map(|_| (twin_sum / count).sqrt());
        IndicatorValues {
            samples: n,
            tip_rms,
            tip_peak: peak,
            ball_rms: (ball / count).sqrt(),
            beam_energy: be / count,
            ball_energy: bb / count,
            twin_tip_rms,
            effectiveness: twin_tip_rms.and_then(|t| {
                let r = tip_rms / t;
                if r.is_finite() {
                    Some(r)
                } else {
                    None
                }
            }),
        }
    }
}
