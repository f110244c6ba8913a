//! S–N curves (AASHTO detail categories) and Miner's-rule damage.
//!
//! **S–N curve** (AASHTO LRFD Bridge Design Specifications, Art. 6.6.1.2.5, Eq. 6.6.1.2.5-2;
//! the same curves are used by the AASHTO *LRFD Specifications for Structural Supports for
//! Highway Signs, Luminaires, and Traffic Signals*, §11.9): a stress range S survives
//! `N = A · S^(−m)` cycles, m = 3. It is stored through the stress range at 2·10⁶ cycles,
//! `S₂ = (A / 2·10⁶)^(1/m)`, so that `N = 2·10⁶ · (S₂ / S)^m` stays well scaled in `f32`.
//!
//! **Threshold.** Below the constant-amplitude fatigue threshold (CAFT, (ΔF)_TH) a constant
//! amplitude history has infinite life (AASHTO's infinite-life check, Fatigue I). How cycles
//! below it count under *variable* amplitude is a choice ([`ThresholdRule`]); the default
//! [`ThresholdRule::Cutoff`] gives zero damage to every cycle whose range is ≤ CAFT. All three
//! rules are tracked at once (the sums are kept separately), so the choice can be changed when
//! reading.
//!
//! **Miner's rule** `D = Σ nᵢ / Nᵢ` with n = 1 for a full and ½ for a half cycle, and the
//! equivalent constant-amplitude range `S_eq = (Σ nᵢ Sᵢ^m / Σ nᵢ)^(1/m)` over all counted cycles
//! (AASHTO's effective stress range). Sums use compensated (Neumaier) summation, so millions of
//! tiny increments do not vanish against a large total in `f32`.
//!
//! **Presets** ([`DetailCategory`]): AASHTO LRFD Table 6.6.1.2.5-1 (detail category constant A,
//! ×10⁸ ksi³) and Table 6.6.1.2.5-3 (constant-amplitude fatigue thresholds, ksi), converted with
//! 1 ksi = 6.894 757 MPa:
//!
//! | category | A \[10⁸ ksi³\] | CAFT \[ksi\] | A \[10¹¹ MPa³\] | S₂ at 2·10⁶ \[MPa\] | CAFT \[MPa\] |
//! |---|---|---|---|---|---|
//! | A  | 250 | 24  | 81.9 | 160.0 | 165.5 |
//! | B  | 120 | 16  | 39.3 | 125.3 | 110.3 |
//! | B′ | 61  | 12  | 20.0 | 100.0 | 82.7 |
//! | C  | 44  | 10  | 14.4 | 89.7  | 68.9 |
//! | C′ | 44  | 12  | 14.4 | 89.7  | 82.7 |
//! | D  | 22  | 7   | 7.21 | 71.2  | 48.3 |
//! | E  | 11  | 4.5 | 3.61 | 56.5  | 31.0 |
//! | E′ | 3.9 | 2.6 | 1.28 | 40.0  | 17.9 |
//!
//! (The SI edition lists A = 82.0, 39.3, 20.0, 14.4, 14.4, 7.21, 3.61, 1.28 ×10¹¹ MPa³ and
//! thresholds 165, 110, 82.7, 69.0, 82.7, 48.3, 31.0, 17.9 MPa: the same values, rounded.)

use crate::error::Error;
use crate::monitor::rainflow::{Cycle, Rainflow};
use crate::scalar::{is_positive, lit, Real};

/// Cycles at which [`SnCurve::reference_range`] is given.
pub const REFERENCE_CYCLES: f64 = 2.0e6;
/// 1 ksi in Pa.
pub const KSI: f64 = 6.894_757_293_168_361e6;

/// AASHTO detail categories (LRFD Table 6.6.1.2.5-1/-3), m = 3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DetailCategory {
    /// Category A (plain rolled or cleaned base metal).
    A,
    /// Category B.
    B,
    /// Category B′.
    BPrime,
    /// Category C.
    C,
    /// Category C′.
    CPrime,
    /// Category D.
    D,
    /// Category E.
    E,
    /// Category E′ (e.g. fillet-welded socket connections of mast arms, the default here).
    EPrime,
}

impl DetailCategory {
    /// All categories, best first.
    pub const ALL: [DetailCategory; 8] = [
        Self::A,
        Self::B,
        Self::BPrime,
        Self::C,
        Self::CPrime,
        Self::D,
        Self::E,
        Self::EPrime,
    ];

    /// Detail category constant A \[ksi³\] (Table 6.6.1.2.5-1).
    pub fn constant_ksi3(self) -> f64 {
        1e8 * match self {
            Self::A => 250.0,
            Self::B => 120.0,
            Self::BPrime => 61.0,
            Self::C | Self::CPrime => 44.0,
            Self::D => 22.0,
            Self::E => 11.0,
            Self::EPrime => 3.9,
        }
    }

    /// Constant-amplitude fatigue threshold (ΔF)_TH \[ksi\] (Table 6.6.1.2.5-3).
    pub fn threshold_ksi(self) -> f64 {
        match self {
            Self::A => 24.0,
            Self::B => 16.0,
            Self::BPrime | Self::CPrime => 12.0,
            Self::C => 10.0,
            Self::D => 7.0,
            Self::E => 4.5,
            Self::EPrime => 2.6,
        }
    }

    /// Name as printed in the specifications.
    pub fn name(self) -> &'static str {
        match self {
            Self::A => "A",
            Self::B => "B",
            Self::BPrime => "B'",
            Self::C => "C",
            Self::CPrime => "C'",
            Self::D => "D",
            Self::E => "E",
            Self::EPrime => "E'",
        }
    }

    /// The stress range at [`REFERENCE_CYCLES`] \[ksi\]: `∛(A / 2·10⁶)`, the value of
    /// `libm::cbrt` (correctly rounded) as a constant: a firmware building the curve then links
    /// no `f64` cube root (about 2 KB; the test `reference_ranges_are_the_cube_roots` checks
    /// every category bit for bit).
    pub fn reference_range_ksi(self) -> f64 {
        f64::from_bits(match self {
            Self::A => 0x4037_353b_d439_3a75,
            Self::B => 0x4032_2bd4_26d7_058f,
            Self::BPrime => 0x402d_011d_afce_3df7,
            Self::C | Self::CPrime => 0x402a_0307_38a1_ae3b,
            Self::D => 0x4024_a546_3163_ec8d,
            Self::E => 0x4020_62ec_c69a_f055,
            Self::EPrime => 0x4017_3210_3834_040e,
        })
    }

    /// The S–N curve in Pa with the given threshold rule.
    pub fn curve<T: Real>(self, rule: ThresholdRule) -> SnCurve<T> {
        let s2_ksi = self.reference_range_ksi();
        SnCurve {
            slope: lit(3.0),
            reference_range: lit(s2_ksi * KSI),
            threshold: lit(self.threshold_ksi() * KSI),
            rule,
        }
    }
}

/// How cycles below the constant-amplitude fatigue threshold count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThresholdRule {
    /// Every cycle with range ≤ CAFT does no damage (the constant-amplitude reading of the
    /// threshold; optimistic for variable amplitude). Default.
    Cutoff,
    /// No threshold: the straight S–N line continues below CAFT (conservative; AASHTO's
    /// finite-life Fatigue II resistance has no threshold).
    Extended,
    /// No damage while no cycle has exceeded CAFT; once one has, every cycle counts on the
    /// extended line (the variable-amplitude reading behind AASHTO's infinite-life check).
    AllOnceExceeded,
}

/// `N = 2·10⁶ (S₂ / S)^m` above the threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnCurve<T> {
    /// Slope m (AASHTO: 3).
    pub slope: T,
    /// Stress range S₂ that survives 2·10⁶ cycles \[Pa\]; `A = 2·10⁶ S₂^m`.
    pub reference_range: T,
    /// Constant-amplitude fatigue threshold \[Pa\].
    pub threshold: T,
    /// Treatment of cycles below the threshold.
    pub rule: ThresholdRule,
}

impl<T: Real> SnCurve<T> {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), Error> {
        let finite_pos = |x: T| is_positive(x) && x.is_finite();
        if !finite_pos(self.slope) {
            return Err(Error::InvalidParameter {
                field: "monitor.curve.slope",
                reason: "must be finite and positive",
            });
        }
        if !finite_pos(self.reference_range) {
            return Err(Error::InvalidParameter {
                field: "monitor.curve.reference_range",
                reason: "must be finite and positive",
            });
        }
        if !self.threshold.is_finite() || self.threshold < T::zero() {
            return Err(Error::InvalidParameter {
                field: "monitor.curve.threshold",
                reason: "must be finite and not negative",
            });
        }
        Ok(())
    }

    /// Damage of one full cycle of range `range` on the straight line, `(S/S₂)^m / 2·10⁶`.
    pub fn damage_per_cycle(&self, range: T) -> T {
        self.normalized(range) / lit::<T>(REFERENCE_CYCLES)
    }

    /// `(S / S₂)^m`.
    fn normalized(&self, range: T) -> T {
        (range / self.reference_range).powf(self.slope)
    }

    /// Cycles to failure at constant range `range` (∞ at or below CAFT unless the rule is
    /// [`ThresholdRule::Extended`]).
    pub fn cycles_to_failure(&self, range: T) -> T {
        if self.rule != ThresholdRule::Extended && range <= self.threshold {
            return T::max_value().unwrap_or(T::one() / T::zero());
        }
        lit::<T>(REFERENCE_CYCLES) / self.normalized(range)
    }
}

/// Compensated (Neumaier) sum.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sum<T> {
    sum: T,
    carry: T,
}

impl<T: Real> Sum<T> {
    fn zero() -> Self {
        Self {
            sum: T::zero(),
            carry: T::zero(),
        }
    }
    fn add(&mut self, x: T) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.carry += (self.sum - t) + x;
        } else {
            self.carry += (x - t) + self.sum;
        }
        self.sum = t;
    }
    fn value(&self) -> T {
        self.sum + self.carry
    }
}

/// Miner's-rule accumulator over rainflow cycles. `Copy`: take a copy, add the residue to it
/// ([`Miner::with_residue`]) and read damage at any time without touching the running state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Miner<T> {
    curve: SnCurve<T>,
    half_cycles: u64,
    /// Σ n (S/S₂)^m over all cycles.
    all: Sum<T>,
    /// Σ n (S/S₂)^m over cycles above the threshold.
    above: Sum<T>,
    max_range: T,
}

/// Fatigue figures at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FatigueSummary<T> {
    /// Miner damage D \[-\] with the curve's threshold rule.
    pub damage: T,
    /// Equivalent constant-amplitude stress range S_eq \[Pa\] over all counted cycles.
    pub equivalent_range: T,
    /// Cycles counted Σn (half cycles count ½).
    pub cycles: T,
    /// Largest range counted \[Pa\].
    pub max_range: T,
}

impl<T: Real> Miner<T> {
    /// Empty accumulator for `curve`.
    pub fn new(curve: SnCurve<T>) -> Result<Self, Error> {
        curve.validate()?;
        Ok(Self {
            curve,
            half_cycles: 0,
            all: Sum::zero(),
            above: Sum::zero(),
            max_range: T::zero(),
        })
    }

    /// The S–N curve.
    pub fn curve(&self) -> &SnCurve<T> {
        &self.curve
    }

    /// Adds one cycle (non-finite ranges are ignored).
    pub fn add(&mut self, cycle: &Cycle<T>) {
        if !cycle.range.is_finite() {
            return;
        }
        let w = cycle.count() * self.curve.normalized(cycle.range);
        self.half_cycles += cycle.halves();
        self.all.add(w);
        if cycle.range > self.curve.threshold {
            self.above.add(w);
        }
        if cycle.range > self.max_range {
            self.max_range = cycle.range;
        }
    }

    /// A copy with the current residue of `rainflow` added as half cycles (see
    /// [`Rainflow::residue`]): the damage "if the history ended now". O(CAP).
    pub fn with_residue<const CAP: usize>(&self, rainflow: &Rainflow<T, CAP>) -> Self {
        let mut m = *self;
        rainflow.residue(&mut |c| m.add(&c));
        m
    }

    /// Miner damage D with the curve's threshold rule.
    pub fn damage(&self) -> T {
        self.damage_with(self.curve.rule)
    }

    /// Miner damage D with another threshold rule.
    pub fn damage_with(&self, rule: ThresholdRule) -> T {
        let s = match rule {
            ThresholdRule::Cutoff => self.above.value(),
            ThresholdRule::Extended => self.all.value(),
            ThresholdRule::AllOnceExceeded => {
                if self.max_range > self.curve.threshold {
                    self.all.value()
                } else {
                    T::zero()
                }
            }
        };
        s / lit::<T>(REFERENCE_CYCLES)
    }

    /// Cycles counted Σn.
    pub fn cycles(&self) -> T {
        lit::<T>(self.half_cycles as f64) * lit::<T>(0.5)
    }

    /// Equivalent range `S_eq = S₂ (Σ n (S/S₂)^m / Σ n)^(1/m)` \[Pa\] (0 before any cycle).
    pub fn equivalent_range(&self) -> T {
        let n = self.cycles();
        if !is_positive(n) {
            return T::zero();
        }
        self.curve.reference_range * (self.all.value() / n).powf(T::one() / self.curve.slope)
    }

    /// Largest range counted \[Pa\].
    pub fn max_range(&self) -> T {
        self.max_range
    }

    /// All figures.
    pub fn summary(&self) -> FatigueSummary<T> {
        FatigueSummary {
            damage: self.damage(),
            equivalent_range: self.equivalent_range(),
            cycles: self.cycles(),
            max_range: self.max_range,
        }
    }
}

/// The monitor's fatigue pipeline on a stress history that comes from elsewhere — the root
/// stress of the estimator ([`crate::estimator`]) — one sample at a time: rainflow counting
/// ([`Rainflow`], ASTM E1049 four-point) and Miner's rule on the S–N curve of a detail category
/// (AASHTO LRFD-LTS §11.9). The host's twin experiment and the firmware count with it alike.
/// Memory: `CAP` stress points, fixed at compile time.
#[derive(Clone, Debug)]
pub struct StressDamage<T, const CAP: usize> {
    rainflow: Rainflow<T, CAP>,
    miner: Miner<T>,
}

impl<T: Real, const CAP: usize> StressDamage<T, CAP> {
    /// Empty, on the S–N curve of `category` (both threshold rules are reported).
    pub fn new(category: DetailCategory) -> Result<Self, Error> {
        Ok(Self {
            rainflow: Rainflow::new(T::zero())?,
            miner: Miner::new(category.curve(ThresholdRule::Cutoff))?,
        })
    }

    /// Adds one stress sample \[Pa\]; every cycle it closes is counted and handed to
    /// `on_cycle`. A non-finite sample is an error and counts nothing.
    pub fn push(&mut self, stress: T, on_cycle: &mut impl FnMut(&Cycle<T>)) -> Result<(), Error> {
        let miner = &mut self.miner;
        self.rainflow.push(stress, &mut |c| {
            miner.add(&c);
            on_cycle(&c);
        })
    }

    /// Miner damage so far, the open residue counted as half cycles: `(extended, cutoff)` —
    /// the S–N line continued below the constant-amplitude fatigue threshold, and cycles below
    /// it doing no damage.
    pub fn damage(&self) -> (T, T) {
        let m = self.miner.with_residue(&self.rainflow);
        (
            m.damage_with(ThresholdRule::Extended),
            m.damage_with(ThresholdRule::Cutoff),
        )
    }

    /// The rainflow counter (its residue: the cycles not closed yet).
    pub fn rainflow(&self) -> &Rainflow<T, CAP> {
        &self.rainflow
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants of [`DetailCategory::reference_range_ksi`] are the cube roots the curve
    /// took before, bit for bit.
    #[test]
    fn reference_ranges_are_the_cube_roots() {
        for c in DetailCategory::ALL {
            let cbrt = libm::cbrt(c.constant_ksi3() / REFERENCE_CYCLES);
            assert_eq!(
                c.reference_range_ksi().to_bits(),
                cbrt.to_bits(),
                "{}",
                c.name()
            );
        }
    }
}
