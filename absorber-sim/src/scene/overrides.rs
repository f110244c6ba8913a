//! The overrides of a loaded scene: what the command line's options (`--solver`, `--elements`,
//! `--frequency`, …) and the Python package's keyword arguments replace.

use super::{CalibrationSection, ExcitationType, Kind, Precision, Scene, Solver};
use anyhow::Result;

/// Values that replace the scene's own (`None`: the scene's). A harmonic frequency or amplitude
/// makes the excitation harmonic.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    /// Solver.
    pub solver: Option<Solver>,
    /// Bodies.
    pub kind: Option<Kind>,
    /// Beam elements.
    pub elements: Option<usize>,
    /// Scalar.
    pub precision: Option<Precision>,
    /// Harmonic excitation frequency \[Hz\].
    pub frequency: Option<f64>,
    /// Harmonic base amplitude \[m\].
    pub amplitude: Option<f64>,
    /// Simulated time \[s\].
    pub duration: Option<f64>,
    /// Time step h \[s\].
    pub step: Option<f64>,
}

impl Overrides {
    /// Applies the overrides to a loaded scene and validates it (the command line's
    /// options and the Python package's keyword overrides come through this).
    pub fn apply(&self, mut s: Scene) -> Result<Scene> {
        let f = &mut s.file;
        if let Some(v) = self.solver {
            f.solver = v;
        }
        if let Some(v) = self.kind {
            f.kind = v;
        }
        if let Some(v) = self.elements {
            if f.calibration.elements.is_some_and(|n| n != v) {
                // Calibration factors hold for the mesh they were fitted for only.
                eprintln!(
                    "note: the scene's [calibration] was fitted for {} elements; with --elements {v} \
                     it is left out",
                    f.calibration.elements.unwrap_or(0)
                );
                f.calibration = CalibrationSection::default();
            }
            f.elements = v;
        }
        if let Some(v) = self.precision {
            f.precision = v;
        }
        if self.frequency.is_some() || self.amplitude.is_some() {
            if f.excitation.kind != ExcitationType::Harmonic {
                f.excitation.kind = ExcitationType::Harmonic;
                f.excitation.file = None;
            }
            f.excitation.frequency = self.frequency.or(f.excitation.frequency);
            f.excitation.amplitude = self.amplitude.or(f.excitation.amplitude);
        }
        if let Some(v) = self.duration {
            f.duration = v;
        }
        if let Some(v) = self.step {
            f.integrator.step = v;
        }
        s.validate()?;
        Ok(s)
    }
}
