//! `[arm]`: a tapered tube with signal heads.

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// `[arm]`: a tapered circular tube with signal heads ([`absorber_core::ArmParams`]).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArmSection {
    /// Outer diameter at the root \[m\].
    pub root_diameter: f64,
    /// Outer diameter at the tip \[m\].
    pub tip_diameter: f64,
    /// Wall thickness \[m\].
    pub wall: f64,
    /// Density \[kg/m³\].
    #[serde(default = "steel_density")]
    pub density: f64,
    /// Signal heads and other point masses (at most 6).
    #[serde(default)]
    pub heads: Vec<HeadSection>,
    /// AASHTO detail category of the root connection (`A` … `E'`).
    #[serde(default = "default_detail")]
    pub detail: String,
}

fn steel_density() -> f64 {
    7850.0
}

fn default_detail() -> String {
    "E'".into()
}

/// One `[[arm.heads]]` entry.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HeadSection {
    /// Distance from the root \[m\].
    pub position: f64,
    /// Mass \[kg\].
    pub mass: f64,
}

impl ArmSection {
    /// The core's arm parameters. Errors name the key.
    pub fn params(&self) -> Result<absorber_core::ArmParams<f64>> {
        use absorber_core::loads::{PointMass, MAX_POINT_MASSES};
        if self.heads.len() > MAX_POINT_MASSES {
            bail!(
                "invalid value for `arm.heads`: {} heads (at most {MAX_POINT_MASSES})",
                self.heads.len()
            );
        }
        let mut point_masses = [PointMass {
            position: 0.0,
            mass: 0.0,
        }; MAX_POINT_MASSES];
        for (slot, h) in point_masses.iter_mut().zip(&self.heads) {
            *slot = PointMass {
                position: h.position,
                mass: h.mass,
            };
        }
        Ok(absorber_core::ArmParams {
            root_diameter: self.root_diameter,
            tip_diameter: self.tip_diameter,
            wall: self.wall,
            density: self.density,
            point_masses,
        })
    }

    /// The AASHTO detail category named by `detail`.
    pub fn detail_category(&self) -> Result<absorber_core::monitor::fatigue::DetailCategory> {
        use absorber_core::monitor::fatigue::DetailCategory;
        DetailCategory::ALL
            .into_iter()
            .find(|c| c.name() == self.detail)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "invalid value for `arm.detail`: `{}` (one of A, B, B', C, C', D, E, E')",
                    self.detail
                )
            })
    }
}

/// The wind's view of an arm: its outer diameter along the length.
pub fn taper_of(arm: &ArmSection, length: f64) -> crate::wind::Taper {
    crate::wind::Taper {
        length,
        root: arm.root_diameter,
        tip: arm.tip_diameter,
    }
}
