//! The health verdict of the estimate: `Ok`, `Degraded` or `Failed`, from the innovations,
//! the clipped and invalid readings and the range of the estimate, over a sliding window.
//!
//! Per window of `window` samples (a ring of `BLOCKS` blocks, so the memory is fixed):
//! - **clipped or invalid readings**: any one makes the estimate `Degraded` (a saturated part
//!   reads its rail: the sample is not used, and what happened meanwhile is only predicted);
//!   when they are more than `failed_clip` of a sensor's readings, or a sensor delivered none
//!   that could be used while the window expected some, the estimate is `Failed` for that
//!   sensor's information (with no other sensor left, `Failed`);
//! - **innovations**: the mean normalized innovation squared per scalar measurement (NIS),
//!   1 for a consistent filter; above `degraded_nis` the model does not explain the
//!   measurements (a force or a motion it lacks), `Degraded`; above `failed_nis`, `Failed`;
//! - **range**: a root stress beyond `stress_limit` (e.g. the yield stress: the model is
//!   elastic), or a sample the estimator had to refuse (a failed step), `Failed`.
//!
//! The verdict of a sample is that of the window ending with it.

use crate::scalar::{lit, Real};

/// How far the estimate can be trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum Verdict {
    /// Consistent innovations, every reading in range.
    #[default]
    Ok,
    /// Some readings clipped or invalid, or innovations above what the filter predicts.
    Degraded,
    /// Most readings of a sensor lost, innovations far above prediction, or the estimate out
    /// of range.
    Failed,
}

impl Verdict {
    /// `ok`, `degraded` or `failed`.
    pub const fn name(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Degraded => "degraded",
            Verdict::Failed => "failed",
        }
    }
}

/// Thresholds of the verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HealthConfig<T> {
    /// Samples per window.
    pub window: u32,
    /// Mean NIS per measurement above which the estimate is `Degraded`.
    pub degraded_nis: T,
    /// Mean NIS per measurement above which it is `Failed`.
    pub failed_nis: T,
    /// Fraction of a sensor's readings in the window clipped or invalid above which the
    /// estimate is `Failed`.
    pub failed_clip: T,
    /// |root stress − static| above which the estimate is `Failed` \[Pa\].
    pub stress_limit: T,
}

impl<T: Real> HealthConfig<T> {
    /// Defaults: a window of `window` samples; NIS 4 (degraded) and 25 (failed) — a
    /// consistent filter's mean over a few hundred samples stays within 1 ± 0.3 even with
    /// correlated innovations, a model that misses the ball or a mode gives 10–1000 —, 5 % of
    /// a sensor's readings clipped (failed), and a stress limit of 250 MPa (structural steel's
    /// yield stress: beyond it the elastic model says nothing).
    pub fn new(window: u32) -> Self {
        Self {
            window,
            degraded_nis: lit(4.0),
            failed_nis: lit(25.0),
            failed_clip: lit(0.05),
            stress_limit: lit(250e6),
        }
    }
}

/// Blocks of the sliding window.
pub const BLOCKS: usize = 8;

/// Counters of one block of samples.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct Block<T> {
    samples: u32,
    /// Sum of NIS over the scalar measurements used, and their number.
    nis: T,
    used: u32,
    /// Per sensor: readings expected (delivered at all), clipped or invalid.
    expected: [u32; super::sensors::KINDS],
    lost: [u32; super::sensors::KINDS],
    /// Samples refused, or with the stress out of range.
    failures: u32,
}

/// The sliding-window health tracker.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Health<T> {
    config: HealthConfig<T>,
    blocks: [Block<T>; BLOCKS],
    current: usize,
    block_len: u32,
    verdict: Verdict,
}

impl<T: Real> Health<T> {
    /// A tracker with `config` (window rounded up to whole blocks).
    pub fn new(config: HealthConfig<T>) -> Self {
        let block_len = config.window.div_ceil(BLOCKS as u32).max(1);
        Self {
            config,
            blocks: [Block {
                samples: 0,
                nis: T::zero(),
                used: 0,
                expected: [0; super::sensors::KINDS],
                lost: [0; super::sensors::KINDS],
                failures: 0,
            }; BLOCKS],
            current: 0,
            block_len,
            verdict: Verdict::Ok,
        }
    }

    /// The thresholds.
    pub fn config(&self) -> &HealthConfig<T> {
        &self.config
    }

    /// The verdict of the window ending with the last sample.
    pub fn verdict(&self) -> Verdict {
        self.verdict
    }

    /// Records one sample: per sensor whether a reading was expected and whether it was lost
    /// (clipped or invalid), the NIS of each used scalar measurement summed and their number,
    /// and whether the sample failed (refused, or the stress out of range). Returns the new
    /// verdict.
    pub fn record(
        &mut self,
        expected: [bool; super::sensors::KINDS],
        lost: [bool; super::sensors::KINDS],
        nis_sum: T,
        used: u32,
        failed: bool,
    ) -> Verdict {
        if self
            .blocks
            .get(self.current)
            .is_some_and(|b| b.samples >= self.block_len)
        {
            self.current = (self.current + 1) % BLOCKS;
            if let Some(b) = self.blocks.get_mut(self.current) {
                *b = Block {
                    samples: 0,
                    nis: T::zero(),
                    used: 0,
                    expected: [0; super::sensors::KINDS],
                    lost: [0; super::sensors::KINDS],
                    failures: 0,
                };
            }
        }
        if let Some(b) = self.blocks.get_mut(self.current) {
            b.samples += 1;
            b.nis += nis_sum;
            b.used += used;
            for ((e, l), (ex, lo)) in b
                .expected
                .iter_mut()
                .zip(b.lost.iter_mut())
                .zip(expected.iter().zip(lost.iter()))
            {
                *e += u32::from(*ex);
                *l += u32::from(*lo && *ex);
            }
            b.failures += u32::from(failed);
        }
        self.verdict = self.evaluate();
        self.verdict
    }

    /// Mean NIS per scalar measurement over the window (NaN-free: 0 without measurements).
    pub fn mean_nis(&self) -> T {
        let (sum, n) = self
            .blocks
            .iter()
            .fold((T::zero(), 0u32), |(s, n), b| (s + b.nis, n + b.used));
        if n == 0 {
            T::zero()
        } else {
            sum / T::from_count(u64::from(n))
        }
    }

    fn evaluate(&self) -> Verdict {
        let c = &self.config;
        let failures: u32 = self.blocks.iter().map(|b| b.failures).sum();
        if failures > 0 {
            return Verdict::Failed;
        }
        let mut verdict = Verdict::Ok;
        let mut usable = 0;
        for k in 0..super::sensors::KINDS {
            let (mut expected, mut lost) = (0u32, 0u32);
            for b in &self.blocks {
                expected += b.expected.get(k).copied().unwrap_or(0);
                lost += b.lost.get(k).copied().unwrap_or(0);
            }
            if expected == 0 {
                continue;
            }
            if lost < expected {
                usable += 1;
            }
            if lost > 0 {
                verdict = verdict.max(Verdict::Degraded);
                let frac = T::from_count(u64::from(lost)) / T::from_count(u64::from(expected));
                if frac > c.failed_clip {
                    verdict = Verdict::Failed;
                }
            }
        }
        let expected_any = self
            .blocks
            .iter()
            .any(|b| b.expected.iter().any(|e| *e > 0));
        if expected_any && usable == 0 {
            return Verdict::Failed;
        }
        let nis = self.mean_nis();
        if nis > c.failed_nis {
            verdict = Verdict::Failed;
        } else if nis > c.degraded_nis {
            verdict = verdict.max(Verdict::Degraded);
        }
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Consistent innovations and no lost reading: `Ok`; one clipped reading: `Degraded` for a
    /// window, then `Ok` again; 10 % clipped: `Failed`; a NIS of 10: `Degraded`, 40: `Failed`.
    #[test]
    fn verdicts_follow_clipping_and_innovations() {
        let mut h = Health::new(HealthConfig::<f64>::new(80));
        let yes = [true, false, false];
        let none = [false; 3];
        for _ in 0..200 {
            assert_eq!(h.record(yes, none, 1.0, 1, false), Verdict::Ok);
        }
        assert_eq!(h.record(yes, yes, 0.0, 0, false), Verdict::Degraded);
        for _ in 0..70 {
            assert_eq!(h.record(yes, none, 1.0, 1, false), Verdict::Degraded);
        }
        for _ in 0..20 {
            h.record(yes, none, 1.0, 1, false);
        }
        assert_eq!(h.verdict(), Verdict::Ok);
        for k in 0..100 {
            h.record(yes, if k % 10 == 0 { yes } else { none }, 1.0, 1, false);
        }
        assert_eq!(h.verdict(), Verdict::Failed);
        let mut h = Health::new(HealthConfig::<f64>::new(80));
        for _ in 0..100 {
            h.record(yes, none, 10.0, 1, false);
        }
        assert_eq!(h.verdict(), Verdict::Degraded);
        for _ in 0..100 {
            h.record(yes, none, 40.0, 1, false);
        }
        assert_eq!(h.verdict(), Verdict::Failed);
        // Every reading of the only sensor lost: failed.
        let mut h = Health::new(HealthConfig::<f64>::new(80));
        assert_eq!(h.record(yes, yes, 0.0, 0, false), Verdict::Failed);
    }
}
