//! Fixed-size log of the last `K` stop impacts, with counters.
//!
//! Each entry is the core's [`Impact`] as reported by [`crate::StepReport::impact`]: time \[s\],
//! side, relative speed θ̇ − ψ̇ before the impact \[rad/s\], impulse on the ball along the track
//! \[N·s\], dissipated energy \[J\], and whether the ball stayed on the stop. When the log is full
//! the oldest entry is dropped (a ring); the counters keep counting.

use crate::model::{Impact, Side};
use crate::scalar::Real;
use heapless::Deque;

/// The last `K` impacts and counters since the start.
#[derive(Clone, Debug)]
pub struct ImpactLog<T, const K: usize> {
    log: Deque<Impact<T>, K>,
    total: u32,
    positive: u32,
    negative: u32,
    stuck: u32,
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

    /// Impacts on the `+φ_max` and the `−φ_max` stop.
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
