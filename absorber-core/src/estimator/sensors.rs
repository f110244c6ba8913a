//! What the monitor measures: a sensor set of any subset of a tip accelerometer, a ball-angle
//! sensor in the housing and a root strain gauge, each with its noise, bias, range and rate.
//!
//! | kind | measures | unit |
//! | --- | --- | --- |
//! | [`SensorKind::TipAccel`] | absolute vertical acceleration of the beam end, `ä_tip + ÿ_b` | m/s² |
//! | [`SensorKind::BallAngle`] | ball angle relative to the housing, `α = θ − ψ` (on the track, or the flying ball's polar angle about the track's centre) | rad |
//! | [`SensorKind::RootStrain`] | bending strain at the top fibre at the clamp, `ε = σ / E` (the estimator's recovered root stress) | – |
//!
//! A reading is **clipped** when its magnitude reaches the sensor's range (a saturated part
//! reads its rail): it is never used, only counted ([`crate::estimator::health`]). A reading
//! that is not finite is counted as invalid and not used either.

use crate::error::Error;
use crate::scalar::{is_positive, Real};

/// Which quantity a sensor measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorKind {
    /// Tip accelerometer, vertical axis \[m/s²\].
    TipAccel,
    /// Ball angle relative to the housing (e.g. a magnetic angle encoder) \[rad\].
    BallAngle,
    /// Strain gauge at the clamp, top fibre \[–\].
    RootStrain,
}

/// Number of sensor kinds.
pub const KINDS: usize = 3;

impl SensorKind {
    /// All kinds, in slot order.
    pub const ALL: [SensorKind; KINDS] = [
        SensorKind::TipAccel,
        SensorKind::BallAngle,
        SensorKind::RootStrain,
    ];

    /// The slot of the kind in a [`SensorSet`] and in [`Readings`].
    pub const fn index(self) -> usize {
        match self {
            SensorKind::TipAccel => 0,
            SensorKind::BallAngle => 1,
            SensorKind::RootStrain => 2,
        }
    }

    /// The id used in scenes and reports.
    pub const fn id(self) -> &'static str {
        match self {
            SensorKind::TipAccel => "tip_accel",
            SensorKind::BallAngle => "ball_angle",
            SensorKind::RootStrain => "root_strain",
        }
    }
}

/// One sensor as the filter sees it (SI units of its quantity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor<T> {
    /// Standard deviation of the white noise of one sample (for a MEMS accelerometer
    /// `noise density · √bandwidth`; for an encoder, add its resolution step over √12).
    pub noise: T,
    /// Standard deviation of the bias at the start, after the installation's zero
    /// calibration ([`crate::estimator::Ekf::calibrate_zero`]); zero: no bias state.
    pub bias_sd: T,
    /// Standard deviation of the bias's random-walk increment per model step (drift).
    pub bias_walk: T,
    /// Readings with `|y| ≥ range` are clipped (the part's full scale).
    pub range: T,
    /// A reading arrives every `every` model steps (the sensor's rate is `1 / (every · h)`).
    pub every: u32,
    /// The reduced model's own error on this measurement, as a fraction of the RMS of its
    /// predicted dynamic value (`docs/monitoring.md`, "Noise model"): it adds
    /// `(model_error · rms)²` to the noise variance.
    pub model_error: T,
}

impl<T: Real> Sensor<T> {
    /// A sensor with `noise`, range `range` and a reading every step, no bias, no model error.
    pub fn new(noise: T, range: T) -> Self {
        Self {
            noise,
            bias_sd: T::zero(),
            bias_walk: T::zero(),
            range,
            every: 1,
            model_error: T::zero(),
        }
    }

    fn check(&self, field: &'static str) -> Result<(), Error> {
        let ok = is_positive(self.noise)
            && self.noise.is_finite()
            && self.bias_sd >= T::zero()
            && self.bias_sd.is_finite()
            && self.bias_walk >= T::zero()
            && self.bias_walk.is_finite()
            && is_positive(self.range)
            && self.model_error >= T::zero()
            && self.model_error.is_finite()
            && self.every >= 1;
        if ok {
            Ok(())
        } else {
            Err(Error::InvalidParameter {
                field,
                reason: "noise and range must be positive, bias and model error finite and not negative, every >= 1",
            })
        }
    }
}

/// The sensors a monitor has: any subset, at least one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorSet<T> {
    /// By [`SensorKind::index`].
    pub slots: [Option<Sensor<T>>; KINDS],
}

impl<T: Real> SensorSet<T> {
    /// No sensor (add some with [`SensorSet::with`]).
    pub fn empty() -> Self {
        Self {
            slots: [None; KINDS],
        }
    }

    /// The set with `sensor` of `kind` added (replacing one of the same kind).
    pub fn with(mut self, kind: SensorKind, sensor: Sensor<T>) -> Self {
        if let Some(s) = self.slots.get_mut(kind.index()) {
            *s = Some(sensor);
        }
        self
    }

    /// The sensor of `kind`, if present.
    pub fn get(&self, kind: SensorKind) -> Option<&Sensor<T>> {
        self.slots.get(kind.index()).and_then(Option::as_ref)
    }

    /// Validates every sensor (the error names it) and that there is at least one.
    pub fn check(&self) -> Result<(), Error> {
        const FIELDS: [&str; KINDS] = [
            "sensors.tip_accel",
            "sensors.ball_angle",
            "sensors.root_strain",
        ];
        let mut any = false;
        for (s, field) in self.slots.iter().zip(FIELDS) {
            if let Some(s) = s {
                s.check(field)?;
                any = true;
            }
        }
        if any {
            Ok(())
        } else {
            Err(Error::InvalidParameter {
                field: "sensors",
                reason: "the estimator needs at least one sensor",
            })
        }
    }
}

/// The readings of one sample: `Some` for each sensor that delivered one at this step.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Readings<T> {
    /// By [`SensorKind::index`].
    pub values: [Option<T>; KINDS],
}

impl<T: Real> Readings<T> {
    /// No reading.
    pub fn none() -> Self {
        Self {
            values: [None; KINDS],
        }
    }

    /// The readings with `value` from the sensor of `kind`.
    pub fn with(mut self, kind: SensorKind, value: T) -> Self {
        if let Some(v) = self.values.get_mut(kind.index()) {
            *v = Some(value);
        }
        self
    }

    /// The reading of `kind`, if any.
    pub fn get(&self, kind: SensorKind) -> Option<T> {
        self.values.get(kind.index()).copied().flatten()
    }
}

/// What became of one sensor's reading in a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ReadingUse {
    /// No reading at this step (sensor absent, or between its samples).
    #[default]
    None,
    /// Used for the correction.
    Used,
    /// Used with its weight bounded: the innovation was beyond the filter's gate.
    Capped,
    /// At or beyond the range: detected, not used.
    Clipped,
    /// Not finite: not used.
    Invalid,
    /// Not used because the model cannot linearize it here (the ball angle while the model's
    /// ball flies: its flight state is outside the filter's error subspace).
    Skipped,
}
