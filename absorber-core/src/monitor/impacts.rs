//! Fixed-size log of the last `K` stop impacts, with counters.
//!
//! Each entry is the core's [`Impact`] as reported by [`crate::StepReport::impact`]: time \[s\],
//! side, relative speed θ̇ − ψ̇ before the impact \[rad/s\], impulse on the ball along the track
//! \[N·s\], dissipated energy \[J\], and whether the ball stayed on the stop. When the log is full
//! the oldest entry is dropped (a ring); the counters keep counting.
//!
//! A step can hold several impacts ([`crate::EventCounts::impacts`]; a coarse step with the ball
//! between the stops in flight, or a bounce off a stop and back): the report keeps the last one's
//! record, so [`ImpactLog::record_step`] logs that one and counts the others in
//! [`ImpactLog::total`] and [`ImpactLog::unlogged`].

use crate::scalar::Real;
use crate::state::{Impact, Side, StepReport};
use heapless::Deque;

/// The last `K` impacts and counters since the start.
#[derive(Clone, Debug)]
pub struct ImpactLog<T, const K: usize> {
    log: Deque<Impact<T>, K>,
    total: u32,
    positive: u32,
    negative: u32,
    stuck: u32,
    unlogged: u32,
    max_speed: T,
    energy_loss: T,
}

impl<T: Real, const K: usize> Default for ImpactLog<T, K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const K: usize> ImpactLog<T, K> {
    /// Empty log.
    pub fn new() -> Self {
        Self {
            log: Deque::new(),
            total: 0,
            positive: 0,
            negative: 0,
            stuck: 0,
            unlogged: 0,
            max_speed: T::zero(),
            energy_loss: T::zero(),
        }
    }

    /// Records one impact (O(1); drops the oldest entry when full).
    pub fn record(&mut self, impact: &Impact<T>) {
        if self.log.is_full() {
            let _ = self.log.pop_front();
        }
        let _ = self.log.push_back(*impact);
        self.total = self.total.saturating_add(1);
        match impact.side {
            Side::Positive => self.positive = self.positive.saturating_add(1),
            Side::Negative => self.negative = self.negative.saturating_add(1),
        }
        if impact.stuck {
            self.stuck = self.stuck.saturating_add(1);
        }
        if impact.relative_speed.abs() > self.max_speed {
            self.max_speed = impact.relative_speed.abs();
        }
        if impact.energy_loss.is_finite() {
            self.energy_loss += impact.energy_loss;
        }
    }

    /// Records every stop impact of a step: the one the report keeps (the step's last, in the
    /// log and the per-side counters) and the earlier ones it only counted (in
    /// [`Self::total`] and [`Self::unlogged`]; `events.impacts` counts them all).
    pub fn record_step(&mut self, report: &StepReport<T>) {
        let counted = u32::from(report.events.impacts);
        let logged = match &report.impact {
            Some(impact) => {
                self.record(impact);
                1
            }
            None => 0,
        };
        let others = counted.saturating_sub(logged);
        self.total = self.total.saturating_add(others);
        self.unlogged = self.unlogged.saturating_add(others);
    }

    /// The logged impacts, oldest first (at most `K`).
    pub fn iter(&self) -> impl Iterator<Item = &Impact<T>> {
        self.log.iter()
    }

    /// The most recent impact.
    pub fn last(&self) -> Option<&Impact<T>> {
        self.log.back()
    }

    /// Impacts since the start.
    pub fn total(&self) -> u32 {
        self.total
    }

    /// Impacts counted without a record: the earlier impacts of steps that held several (their
    /// side and speed are not kept; [`Self::per_side`] counts the recorded ones).
    pub fn unlogged(&self) -> u32 {
        self.unlogged
    }

    /// Impacts on the `+φ_max` and the `−φ_max` stop (the recorded ones: `total − unlogged`).
    pub fn per_side(&self) -> (u32, u32) {
        (self.positive, self.negative)
    }

    /// Impacts after which the ball stayed on the stop.
    pub fn stuck(&self) -> u32 {
        self.stuck
    }

    /// Largest |relative speed| before an impact \[rad/s\].
    pub fn max_relative_speed(&self) -> T {
        self.max_speed
    }

    /// Kinetic energy dissipated by all impacts \[J\].
    pub fn energy_loss(&self) -> T {
        self.energy_loss
    }
}
