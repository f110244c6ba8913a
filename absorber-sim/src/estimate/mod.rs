//! The monitor's estimators against the full solver: `host-sim estimate`.
//!
//! **Truth**: the full solver (16 elements, `f64`), free ball with flight where the scene has
//! one, under loads the estimators never see. **Measurements**: each sensor of the scene's
//! `[[sensors]]` reads the truth ([`crate::scene::SensorSpec::read`]: bias, white noise,
//! quantization, clipping at the range, its own rate). **Estimators**: the core (`N = 3`,
//! `f32`, calibrated to the 16-element reference), either the extended Kalman filter of
//! [`absorber_core::estimator::ekf`] with a subset of the sensors ([`filter`]) or the
//! constant-gain filter it replaces ([`constant`], tip accelerometer only). **Scores** per
//! estimator: RMS of the dynamic root-stress error (each stress minus its own static value) in
//! % of the truth's RMS about its mean; Miner damage ratio estimated / true (rainflow of the
//! core's monitor, the arm's AASHTO category, straight S–N line); the mean normalized
//! innovation squared per scalar measurement (NIS, 1 for a consistent filter); the health
//! verdict.
//!
//! Two studies: the arm of a scene with `[arm]` and `[[loads]]` ([`arm`]: the twin of a real
//! mast arm under wind) and the paper's lab arm with its free ball under a wind-like tip force
//! ([`lab`]: where the absorber works).

pub mod arm;
pub mod constant;
pub mod filter;
pub mod lab;

pub use arm::{twin, TwinReport};
pub use constant::{design, BaselineLoad, FilterNoise};
pub use lab::{lab, LabReport};

use absorber_core::monitor::fatigue::{DetailCategory, StressDamage};
use absorber_core::monitor::rainflow::Cycle;
use absorber_core::monitor::stress::RootSection;
use absorber_core::{ArmParams, Params};
use anyhow::{anyhow, bail, Result};
use serde::Serialize;

/// Most steps a study runs: the truth, the estimators and their histories are held in memory
/// (a few hundred bytes per step: about 2 GB here); 2^23 steps are 23 h at the arm's 10 ms.
pub const MAX_STEPS: f64 = 8_388_608.0;

/// Fewest steps a study runs: its statistics (RMS errors, damage ratios) need a response to
/// measure; 100 steps are 1 s at the arm's 10 ms.
pub const MIN_STEPS: f64 = 100.0;

/// Checks a study's `--duration` against its step `h` \[s\] before anything is allocated.
pub fn check_duration(duration: f64, h: f64) -> Result<()> {
    let steps = duration / h;
    if !(duration.is_finite() && (MIN_STEPS..=MAX_STEPS).contains(&steps)) {
        bail!(
            "invalid value for `--duration`: {duration} s (must lie in {} ..= {} s: {MIN_STEPS} to {MAX_STEPS} steps of h = {h} s; the study holds every step in memory)",
            MIN_STEPS * h,
            MAX_STEPS * h
        );
    }
    Ok(())
}

/// Standard deviation of the constant-gain estimator's tip-load random walk per sample \[N\]
/// (the twin's and the firmware's default).
pub const LOAD_STEP: f64 = 0.5;
/// Time constant of its tip-load model \[s\].
pub const LOAD_TIME: f64 = 5.0;

/// The estimator's model: `N = 3` elements.
pub const N: usize = 3;
/// Newton tolerance of the estimator's model (scaled position increment): the finest `f32`
/// allows (8ε rounded up). The predicted measurement is an acceleration, and Newmark's
/// acceleration carries a position error divided by `βh²`: a coarser tolerance would bound it
/// only by several m/s².
pub const ESTIMATOR_TOLERANCE: f64 = 1e-6;
/// Newton tolerance of the truth (`f64`): its accelerations are the measurement.
pub const TRUTH_TOLERANCE: f64 = 1e-11;
/// Elements of the truth.
pub const TRUTH_ELEMENTS: usize = 16;

/// `absorber_core::Error` → `anyhow`.
pub fn core(e: absorber_core::Error) -> anyhow::Error {
    anyhow!("{e}")
}

/// What the truth did, per step (index 0 is the start, at rest), for the scores and the
/// sensors.
#[derive(Clone, Debug, Default)]
pub struct Truth {
    /// Root stress at the clamp \[Pa\].
    pub stress: Vec<f64>,
    /// Static root stress under gravity \[Pa\].
    pub static_stress: f64,
    /// Absolute vertical tip acceleration \[m/s²\].
    pub tip_accel: Vec<f64>,
    /// Ball angle relative to the housing \[rad\] (zero without a ball).
    pub ball_angle: Vec<f64>,
    /// Base acceleration \[m/s²\] (the estimators' known input).
    pub base_accel: Vec<f64>,
    /// Young's modulus of the root section \[Pa\] (strain = stress / E).
    pub modulus: f64,
    /// Stop impacts.
    pub impacts: u64,
    /// Steps with the ball in flight.
    pub flying: usize,
    /// `free` (a free ball) or `locked` (a ball fixed in its housing, or none).
    pub kind: &'static str,
}

impl Truth {
    /// The value a sensor of `kind` reads at step `k` (before its own errors).
    pub fn value(&self, kind: absorber_core::estimator::SensorKind, k: usize) -> f64 {
        use absorber_core::estimator::SensorKind;
        let at = |v: &[f64]| v.get(k).copied().unwrap_or(0.0);
        match kind {
            SensorKind::TipAccel => at(&self.tip_accel) + at(&self.base_accel),
            SensorKind::BallAngle => at(&self.ball_angle),
            SensorKind::RootStrain => at(&self.stress) / self.modulus,
        }
    }

    /// Steps taken (the start excluded).
    pub fn steps(&self) -> usize {
        self.stress.len().saturating_sub(1)
    }
}

/// One estimator's scores against one truth (the JSON of `estimate --json`).
#[derive(Clone, Debug, Serialize)]
pub struct EstimatorReport {
    /// `ekf` (the extended Kalman filter) or `constant-gain` (the filter it replaces).
    pub estimator: &'static str,
    /// The estimator's model: `free-ball`, `locked-ball` (the ball left out) or `arm`.
    pub model: &'static str,
    /// Sensors it reads: ids `tip_accel`, `ball_angle`, `root_strain`.
    pub sensors: Vec<&'static str>,
    /// The truth it is fed: `free` (free ball with flight) or `locked` (no moving ball).
    pub truth: &'static str,
    /// RMS of the dynamic root-stress error, % of the truth's RMS about its mean.
    pub stress_rms_error_pct: f64,
    /// Miner damage estimated / true (straight S–N line).
    pub damage_ratio: f64,
    /// Mean normalized innovation squared per scalar measurement (1: consistent); NaN for
    /// the constant-gain filter, whose innovations' sd is its steady-state one (the ratio of
    /// their RMS is `innovation_ratio`).
    pub nis: f64,
    /// Health verdict of the run: `failed` if the estimate was failed for ≥ 1 % of the
    /// samples, else `degraded` if it was degraded or worse for ≥ 1 %, else `ok`.
    pub verdict: &'static str,
    /// Fraction of the samples with each verdict (ok, degraded, failed).
    pub verdict_fractions: [f64; 3],
    /// Share of the estimated damage accumulated while the verdict was not `ok` \[%\].
    pub damage_degraded_pct: f64,
    /// Fraction of samples whose stress error lies within ±2 of the filter's own sd.
    pub within_two_sd: f64,
    /// RMS of the innovations over their predicted sd (tip accelerometer).
    pub innovation_ratio: f64,
    /// Samples the estimator refused (failed steps).
    pub failed: usize,
    /// Readings clipped at the range, per sensor kind (tip_accel, ball_angle, root_strain).
    pub clipped: [usize; 3],
    /// Readings used with a bounded weight (beyond the filter's gate).
    pub capped: usize,
    /// RMS of the estimated tip load \[N\].
    pub load_rms: f64,
    /// Each quality figure beside its expected range and a word ([`Quality`]).
    pub quality: Vec<Quality>,
}

/// One quality figure of an estimator beside the range it should lie in, and a word:
/// `ok` inside `expected`, `poor` inside `tolerated`, `failed` outside, `none` when the
/// estimator has no such figure (NaN).
#[derive(Clone, Debug, Serialize)]
pub struct Quality {
    /// `nis`, `within_two_sd`, `innovation_ratio`, `stress_rms_error_pct`, `damage_ratio`.
    pub figure: &'static str,
    /// Its value.
    pub value: f64,
    /// The range of a consistent filter (NIS, coverage, innovation ratio) or of the targets
    /// (error, damage ratio).
    pub expected: [f64; 2],
    /// The wider range still called `poor`.
    pub tolerated: [f64; 2],
    /// `ok`, `poor`, `failed` or `none`.
    pub word: &'static str,
}

impl Quality {
    fn of(figure: &'static str, value: f64, expected: [f64; 2], tolerated: [f64; 2]) -> Self {
        let inside = |r: [f64; 2]| value >= r[0] && value <= r[1];
        let word = if value.is_nan() {
            "none"
        } else if inside(expected) {
            "ok"
        } else if inside(tolerated) {
            "poor"
        } else {
            "failed"
        };
        Self {
            figure,
            value,
            expected,
            tolerated,
            word,
        }
    }
}

/// The quality figures of a report against their ranges. A consistent filter's mean NIS per
/// measurement is 1 (here 0.5–2, poor within a further factor 2); its innovations' RMS over
/// their predicted sd is the square root (0.71–1.41, poor 0.5–2); a Gaussian error lies
/// within ±2 of its sd 95.4 % of the time (0.9–0.99: fewer means overconfident, more
/// underconfident; poor 0.8–0.999). The stress RMS error and the damage ratio against the
/// monitor's targets: ≤ 10 % and 0.8–1.25 (poor: ≤ 20 % and 0.67–1.5).
pub fn quality(r: &EstimatorReport) -> Vec<Quality> {
    vec![
        Quality::of("nis", r.nis, [0.5, 2.0], [0.25, 4.0]),
        Quality::of("within_two_sd", r.within_two_sd, [0.9, 0.99], [0.8, 0.999]),
        Quality::of(
            "innovation_ratio",
            r.innovation_ratio,
            [0.5f64.sqrt(), 2.0f64.sqrt()],
            [0.5, 2.0],
        ),
        Quality::of(
            "stress_rms_error_pct",
            r.stress_rms_error_pct,
            [0.0, 10.0],
            [0.0, 20.0],
        ),
        Quality::of("damage_ratio", r.damage_ratio, [0.8, 1.25], [0.67, 1.5]),
    ]
}

/// The core's fatigue pipeline (as in the firmware) on a stress history: damage without
/// threshold, with the CAFT cutoff, and the ranges with their counts.
pub(crate) struct Damage {
    counter: StressDamage<f64, 512>,
    ranges: Vec<(f64, f64)>,
}

impl Damage {
    pub(crate) fn new(category: DetailCategory) -> Result<Self> {
        Ok(Self {
            counter: StressDamage::new(category).map_err(core)?,
            ranges: Vec::new(),
        })
    }

    pub(crate) fn push(&mut self, x: f64) -> Result<()> {
        let r = &mut self.ranges;
        self.counter
            .push(x, &mut |cy: &Cycle<f64>| r.push((cy.range, cy.count())))
            .map_err(core)
    }

    /// As [`Damage::push`], handing every cycle it closes to `f` too.
    pub(crate) fn push_with(&mut self, x: f64, f: &mut impl FnMut(&Cycle<f64>)) -> Result<()> {
        let r = &mut self.ranges;
        self.counter
            .push(x, &mut |cy: &Cycle<f64>| {
                r.push((cy.range, cy.count()));
                f(cy);
            })
            .map_err(core)
    }

    /// Damage so far, the open residue as half cycles: (extended, cutoff).
    pub(crate) fn damage(&self) -> (f64, f64) {
        self.counter.damage()
    }

    pub(crate) fn finish(mut self) -> (f64, f64, Vec<(f64, f64)>) {
        let (e, c) = self.counter.damage();
        let r = &mut self.ranges;
        self.counter
            .rainflow()
            .residue(&mut |cy: Cycle<f64>| r.push((cy.range, cy.count())));
        (e, c, self.ranges)
    }
}

/// Damage without threshold, with the cutoff, and the ranges with their counts.
pub(crate) type DamageSum = (f64, f64, Vec<(f64, f64)>);

/// Miner damage of a stress history \[Pa\].
pub(crate) fn damage_of(category: DetailCategory, x: &[f64]) -> Result<DamageSum> {
    let mut d = Damage::new(category)?;
    for v in x {
        d.push(*v)?;
    }
    Ok(d.finish())
}

/// Mean of `x`.
pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// RMS of `x`.
pub(crate) fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// RMS of `x` about its mean.
pub(crate) fn rms_about_mean(x: &[f64]) -> f64 {
    let m = mean(x);
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// RMS of the dynamic stress error in % of the truth's RMS about its mean: each history minus
/// its own static stress (`estimate[k]` against `truth.stress[k + 1]`).
pub(crate) fn stress_error_pct(truth: &Truth, estimate: &[f64], static_estimate: f64) -> f64 {
    let offset = static_estimate - truth.static_stress;
    let t = truth.stress.get(1..).unwrap_or_default();
    let err: Vec<f64> = estimate
        .iter()
        .zip(t)
        .map(|(e, tr)| e - tr - offset)
        .collect();
    100.0 * rms(&err) / rms_about_mean(t)
}

/// The root stress of the full solver's state from the clamp reaction of its element 0: `−r₃`
/// of the element residual `M ä + K (u + c u̇) + Q_l(u) − applied` is the moment the clamp
/// carries (the core's formula of [`absorber_core::monitor::stress`] on the full solver's
/// coordinates).
pub(crate) fn clamp_stress(
    b: &absorber_core::shared::Beam<f64>,
    applied: absorber_core::shared::ElementVector<f64>,
    section: &RootSection<f64>,
    st: &absorber_full::FullState,
) -> f64 {
    use absorber_core::shared::ElementVector;
    let u = ElementVector::<f64>::from_fn(|i, _| st.q[i]);
    let v = ElementVector::<f64>::from_fn(|i, _| st.v[i]);
    let a = ElementVector::<f64>::from_fn(|i, _| st.a[i]);
    let r = b.mass * a + b.stiffness * (u + v * b.damping) + b.quadrature.force(&u) - applied;
    section.stress_of_moment(-r[3])
}

/// The `f32` parameters of a model (the firmware's and the estimators' precision).
pub fn params_f32(p: &Params<f64>) -> Params<f32> {
    crate::core_sim::params_f32(p)
}

/// The `f32` arm.
pub fn arm_f32(a: &ArmParams<f64>) -> ArmParams<f32> {
    crate::core_sim::cast_arm(a)
}

/// The `f32` root section.
pub fn section_f32(s: &RootSection<f64>) -> RootSection<f32> {
    RootSection {
        bending_rigidity: s.bending_rigidity as f32,
        stress_per_curvature: s.stress_per_curvature as f32,
        extreme_fibre: s.extreme_fibre as f32,
    }
}

/// A run's verdict from the fractions of its samples with each verdict (ok, degraded,
/// failed): `failed` if ≥ 1 % were failed, else `degraded` if ≥ 1 % were degraded or worse,
/// else `ok`.
pub fn run_verdict(fractions: &[f64; 3]) -> &'static str {
    if fractions[2] >= 0.01 {
        "failed"
    } else if fractions[1] + fractions[2] >= 0.01 {
        "degraded"
    } else {
        "ok"
    }
}

/// The worst verdict over the reports of the estimators a monitor with the scene's sensors
/// would run (their `verdict`), for the top-level `verdict` of `estimate --json`.
pub fn worst_verdict<'a>(reports: impl Iterator<Item = &'a EstimatorReport>) -> &'static str {
    let rank = |v: &str| match v {
        "failed" => 2,
        "degraded" => 1,
        _ => 0,
    };
    reports
        .map(|r| r.verdict)
        .max_by_key(|v| rank(v))
        .unwrap_or("ok")
}
