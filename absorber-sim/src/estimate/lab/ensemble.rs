//! The lab study at the working point over a seeded ensemble: each member draws every sensor's
//! noise from its own seeds and starts the truth's ball a little off; the statistics over the
//! members.

use super::{lab_member, LabReport};
use crate::ensemble::Spread;
use crate::estimate::{constant, EstimatorReport};
use crate::scene::Scene;
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;

/// One estimator over a [`LabEnsemble`]'s members.
#[derive(Clone, Debug, Serialize)]
pub struct EnsembleEstimator {
    /// As in [`EstimatorReport`].
    pub estimator: &'static str,
    /// As in [`EstimatorReport`].
    pub model: &'static str,
    /// As in [`EstimatorReport`].
    pub sensors: Vec<&'static str>,
    /// As in [`EstimatorReport`].
    pub truth: &'static str,
    /// Stress RMS error \[%\] over the members.
    pub stress_rms_error_pct: Spread,
    /// Damage ratio over the members.
    pub damage_ratio: Spread,
    /// Each member's mean NIS per measurement.
    pub nis: Spread,
    /// Members with each run verdict (ok, degraded, failed).
    pub member_verdicts: [usize; 3],
    /// Fraction of all the members' samples with each verdict (ok, degraded, failed).
    pub verdict_fractions: [f64; 3],
    /// The ensemble's verdict: the run rule ([`crate::estimate::run_verdict`]) on the pooled fractions.
    pub verdict: &'static str,
}

/// The lab study over a seeded ensemble of realizations ([`lab_member`] `0..members`).
///
/// At the working point the free ball is chaotic, and its side is a coin toss: the tip's
/// vertical acceleration is even in the ball's angle to first order (its reaction goes with
/// `cos α` and `α̇²`), so a ball swinging on the other side explains the accelerometer almost
/// as well; only the weaker odd coupling (the housing turns with the tip's slope) separates
/// the two. Each lock-in episode starts the ball from near plumb, where the parametric
/// instability picks its side from rounding-level differences — in the truth and in the
/// filter's model alike. A filter with the tip accelerometer alone that picks the other side
/// keeps it for the episode: its stress stays right (the stress is even in `α` too), its ball
/// angle is off by twice the swing. With the episodes' onsets, where the filter's ball and the
/// truth's part, one run's mean NIS and verdict are draws that move with any rounding-level
/// change (the filter's own summation order, a sensor seed, 10⁻¹² rad of initial angle); the
/// ensemble's mean, spread and pooled verdict are what is reported.
#[derive(Clone, Debug, Serialize)]
pub struct LabEnsemble {
    /// Realizations.
    pub members: u32,
    /// Forcing frequency \[Hz\].
    pub force_frequency: f64,
    /// Per estimator (in the reports' order).
    pub estimators: Vec<EnsembleEstimator>,
    /// Each member's report.
    pub reports: Vec<LabReport>,
}

impl LabEnsemble {
    /// The ensemble entry of an estimator.
    pub fn find(
        &self,
        estimator: &str,
        model: &str,
        sensors: &[&str],
        truth: &str,
    ) -> Option<&EnsembleEstimator> {
        self.estimators.iter().find(|e| {
            e.estimator == estimator && e.model == model && e.sensors == sensors && e.truth == truth
        })
    }
}

/// The lab study ([`lab`]) over `members` realizations ([`lab_member`] `0..members`).
pub fn lab_ensemble(
    scene: &Scene,
    duration: f64,
    amplitude: f64,
    baseline: constant::BaselineLoad,
    members: u32,
) -> Result<LabEnsemble> {
    if members == 0 {
        bail!("invalid ensemble size: 0 (at least 1)");
    }
    // The members in parallel, in member order (as the ensemble module's `Ensemble::map`).
    let reports = (0..members)
        .into_par_iter()
        .map(|m| Ok(lab_member(scene, duration, amplitude, baseline, m)?.0))
        .collect::<Result<Vec<LabReport>>>()?;
    let Some(first) = reports.first() else {
        bail!("invalid ensemble size: 0 (at least 1)");
    };
    let estimators = first
        .estimators
        .iter()
        .enumerate()
        .map(|(i, e0)| {
            let each: Vec<&EstimatorReport> =
                reports.iter().filter_map(|r| r.estimators.get(i)).collect();
            let fig = |f: fn(&EstimatorReport) -> f64| {
                Spread::of(&each.iter().map(|e| f(e)).collect::<Vec<_>>())
            };
            let mut member_verdicts = [0usize; 3];
            let mut fractions = [0.0f64; 3];
            for e in &each {
                let v = match e.verdict {
                    "failed" => 2,
                    "degraded" => 1,
                    _ => 0,
                };
                member_verdicts[v] += 1;
                for (a, b) in fractions.iter_mut().zip(e.verdict_fractions) {
                    *a += b / each.len() as f64;
                }
            }
            EnsembleEstimator {
                estimator: e0.estimator,
                model: e0.model,
                sensors: e0.sensors.clone(),
                truth: e0.truth,
                stress_rms_error_pct: fig(|e| e.stress_rms_error_pct),
                damage_ratio: fig(|e| e.damage_ratio),
                nis: fig(|e| e.nis),
                member_verdicts,
                verdict_fractions: fractions,
                verdict: crate::estimate::run_verdict(&fractions),
            }
        })
        .collect();
    Ok(LabEnsemble {
        members,
        force_frequency: first.force_frequency,
        estimators,
        reports,
    })
}
