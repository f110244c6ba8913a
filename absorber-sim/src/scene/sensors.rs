//! The monitor's sensors: `[[sensors]]` (and the older `[sensor]`), in their data sheets' units.

use super::finite_positive;
use anyhow::{bail, Result};
use rand::RngExt;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// One `[[sensors]]` entry: a sensor of the monitor, in its data sheet's units. The noise is
/// white with the standard deviation of one sample; the bias is a constant offset the
/// estimator does not know beyond its installation's zero calibration; a reading at or
/// beyond the range reads the rail (clipped).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SensorSpec {
    /// MEMS accelerometer at the tip, vertical axis.
    TipAccel {
        /// Noise density \[µg/√Hz\].
        noise_density_ug: f64,
        /// Bandwidth of its filter \[Hz\] (the noise is white up to it).
        bandwidth: f64,
        /// Constant bias \[mg\].
        #[serde(default)]
        bias_mg: f64,
        /// Full-scale range ± \[g\].
        range_g: f64,
        /// Output data rate \[Hz\] (a divisor of the model's step rate).
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
    /// Ball angle relative to the housing: a magnetic angle encoder in the housing's wall.
    BallAngle {
        /// Noise, standard deviation of one sample \[°\].
        noise_deg: f64,
        /// Resolution (quantization step) \[°\] (0: none).
        #[serde(default)]
        resolution_deg: f64,
        /// Constant offset \[°\].
        #[serde(default)]
        bias_deg: f64,
        /// Range ± \[°\].
        #[serde(default = "half_turn")]
        range_deg: f64,
        /// Output data rate \[Hz\].
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
    /// Foil strain gauge at the clamp, top fibre, along the arm.
    RootStrain {
        /// Noise, standard deviation of one sample \[µε\].
        noise_ue: f64,
        /// Constant offset \[µε\] (zero drift after installation).
        #[serde(default)]
        bias_ue: f64,
        /// Range ± \[µε\] (the bridge amplifier's full scale).
        range_ue: f64,
        /// Output data rate \[Hz\].
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
}

fn half_turn() -> f64 {
    180.0
}

impl SensorSpec {
    /// The kind.
    pub fn kind(&self) -> absorber_core::estimator::SensorKind {
        use absorber_core::estimator::SensorKind;
        match self {
            SensorSpec::TipAccel { .. } => SensorKind::TipAccel,
            SensorSpec::BallAngle { .. } => SensorKind::BallAngle,
            SensorSpec::RootStrain { .. } => SensorKind::RootStrain,
        }
    }

    /// Standard deviation of one sample's noise, with the quantization's `step/√12` \[SI\].
    pub fn noise_sd(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel {
                noise_density_ug,
                bandwidth,
                ..
            } => noise_density_ug * 1e-6 * G0 * bandwidth.sqrt(),
            SensorSpec::BallAngle {
                noise_deg,
                resolution_deg,
                ..
            } => (noise_deg.powi(2) + resolution_deg.powi(2) / 12.0)
                .sqrt()
                .to_radians(),
            SensorSpec::RootStrain { noise_ue, .. } => noise_ue * 1e-6,
        }
    }

    /// The bias \[SI\].
    pub fn bias(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { bias_mg, .. } => bias_mg * 1e-3 * G0,
            SensorSpec::BallAngle { bias_deg, .. } => bias_deg.to_radians(),
            SensorSpec::RootStrain { bias_ue, .. } => bias_ue * 1e-6,
        }
    }

    /// The range ± \[SI\].
    pub fn range(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { range_g, .. } => range_g * G0,
            SensorSpec::BallAngle { range_deg, .. } => range_deg.to_radians(),
            SensorSpec::RootStrain { range_ue, .. } => range_ue * 1e-6,
        }
    }

    /// The output data rate \[Hz\].
    pub fn rate(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { rate, .. }
            | SensorSpec::BallAngle { rate, .. }
            | SensorSpec::RootStrain { rate, .. } => rate,
        }
    }

    /// The seed of its noise.
    pub fn seed(&self) -> u64 {
        match *self {
            SensorSpec::TipAccel { seed, .. }
            | SensorSpec::BallAngle { seed, .. }
            | SensorSpec::RootStrain { seed, .. } => seed,
        }
    }

    /// Quantization step \[SI\] (0: none).
    pub fn resolution(&self) -> f64 {
        match *self {
            SensorSpec::BallAngle { resolution_deg, .. } => resolution_deg.to_radians(),
            _ => 0.0,
        }
    }

    /// Model steps between readings at step `h`: `1 / (rate h)`, which must be a whole
    /// number (errors name the key).
    pub fn every(&self, h: f64, index: usize) -> Result<u32> {
        let every = 1.0 / (self.rate() * h);
        let n = every.round();
        if n < 1.0 || (every / n - 1.0).abs() > 1e-6 {
            bail!(
                "invalid value for `sensors[{index}].rate`: {} Hz (the model's step rate, {} Hz, must be a whole multiple of it)",
                self.rate(),
                1.0 / h
            );
        }
        Ok(n as u32)
    }

    /// One reading of the true value `x` \[SI\]: plus the bias and the noise (from `rng`),
    /// quantized, and at the rail when at or beyond the range.
    pub fn read(&self, x: f64, rng: &mut crate::wind::Rng) -> f64 {
        let range = self.range();
        let mut y = x + self.bias() + self.noise_sd_raw() * rng.sample::<f64, _>(StandardNormal);
        let q = self.resolution();
        if q > 0.0 {
            y = (y / q).round() * q;
        }
        y.clamp(-range, range)
    }

    /// The noise without the quantization's part (the quantization is applied as such).
    fn noise_sd_raw(&self) -> f64 {
        match *self {
            SensorSpec::BallAngle { noise_deg, .. } => noise_deg.to_radians(),
            _ => self.noise_sd(),
        }
    }

    /// Checks the values (errors name the key `sensors[index].…`).
    pub fn validate(&self, index: usize) -> Result<()> {
        let key = |k: &str| format!("sensors[{index}].{k}");
        let pos = |x: f64, k: &str| finite_positive(x, &key(k));
        let finite = |x: f64, k: &str| -> Result<()> {
            if !x.is_finite() {
                bail!("invalid value for `{}`: must be finite", key(k));
            }
            Ok(())
        };
        match *self {
            SensorSpec::TipAccel {
                noise_density_ug,
                bandwidth,
                bias_mg,
                range_g,
                rate,
                ..
            } => {
                pos(noise_density_ug, "noise_density_ug")?;
                pos(bandwidth, "bandwidth")?;
                finite(bias_mg, "bias_mg")?;
                pos(range_g, "range_g")?;
                pos(rate, "rate")?;
                if bandwidth > 0.5 * rate {
                    bail!(
                        "invalid value for `{}`: {bandwidth} Hz (at most half of `rate`)",
                        key("bandwidth")
                    );
                }
            }
            SensorSpec::BallAngle {
                noise_deg,
                resolution_deg,
                bias_deg,
                range_deg,
                rate,
                ..
            } => {
                pos(noise_deg, "noise_deg")?;
                if !resolution_deg.is_finite() || resolution_deg < 0.0 {
                    bail!(
                        "invalid value for `{}`: must be finite and not negative",
                        key("resolution_deg")
                    );
                }
                finite(bias_deg, "bias_deg")?;
                pos(range_deg, "range_deg")?;
                pos(rate, "rate")?;
            }
            SensorSpec::RootStrain {
                noise_ue,
                bias_ue,
                range_ue,
                rate,
                ..
            } => {
                pos(noise_ue, "noise_ue")?;
                finite(bias_ue, "bias_ue")?;
                pos(range_ue, "range_ue")?;
                pos(rate, "rate")?;
            }
        }
        Ok(())
    }
}

impl From<SensorSection> for SensorSpec {
    fn from(s: SensorSection) -> Self {
        SensorSpec::TipAccel {
            noise_density_ug: s.noise_density_ug,
            bandwidth: s.bandwidth,
            bias_mg: s.bias_mg,
            range_g: s.range_g,
            rate: s.rate,
            seed: s.seed,
        }
    }
}

/// `[sensor]`: a MEMS accelerometer at the arm tip, vertical axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSection {
    /// Noise density \[µg/√Hz\].
    pub noise_density_ug: f64,
    /// Constant bias \[mg\] (unknown to the estimator).
    pub bias_mg: f64,
    /// Full-scale range ± \[g\] (readings clip there).
    pub range_g: f64,
    /// Output data rate \[Hz\] (the estimator's sample rate).
    pub rate: f64,
    /// Bandwidth of the sensor's filter \[Hz\] (the noise is white up to it).
    pub bandwidth: f64,
    /// Seed of the noise.
    #[serde(default)]
    pub seed: u64,
}

/// Standard gravity \[m/s²\]: the g of the sensor's units.
pub const G0: f64 = 9.80665;

impl SensorSection {
    /// White-noise standard deviation of a reading, noise density · √bandwidth \[m/s²\].
    pub fn noise_sd(&self) -> f64 {
        self.noise_density_ug * 1e-6 * G0 * self.bandwidth.sqrt()
    }

    /// The range ± \[m/s²\].
    pub fn range(&self) -> f64 {
        self.range_g * G0
    }

    /// One reading of the true acceleration `a` \[m/s²\]: plus the bias and white noise
    /// (σ = [`SensorSection::noise_sd`], drawn from `rng`), clipped at the range.
    pub fn read(&self, a: f64, rng: &mut crate::wind::Rng) -> f64 {
        let range = self.range();
        (a + self.bias_mg * 1e-3 * G0 + self.noise_sd() * rng.sample::<f64, _>(StandardNormal))
            .clamp(-range, range)
    }

    /// The estimator runs at the sensor rate: the step `h` must be `1 / rate`.
    pub fn check_step(&self, h: f64) -> Result<()> {
        if ((1.0 / h) / self.rate - 1.0).abs() > 1e-9 {
            bail!(
                "`integrator.step` ({h} s) must be 1 / `sensor.rate` ({} Hz): the estimator runs at the sensor rate",
                self.rate
            );
        }
        Ok(())
    }

    /// Checks the values (errors name the key).
    pub fn validate(&self) -> Result<()> {
        finite_positive(self.noise_density_ug, "sensor.noise_density_ug")?;
        finite_positive(self.range_g, "sensor.range_g")?;
        finite_positive(self.rate, "sensor.rate")?;
        finite_positive(self.bandwidth, "sensor.bandwidth")?;
        if !self.bias_mg.is_finite() {
            bail!("invalid value for `sensor.bias_mg`: must be finite");
        }
        if self.bandwidth > 0.5 * self.rate {
            bail!(
                "invalid value for `sensor.bandwidth`: {} Hz (at most half of `sensor.rate`)",
                self.bandwidth
            );
        }
        Ok(())
    }
}
