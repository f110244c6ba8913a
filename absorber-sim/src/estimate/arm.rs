//! The twin of a real arm (`host-sim estimate --scene scenes/mast-arm.toml`): the full solver
//! (16 elements, `f64`) of the scene's arm under its `[[loads]]`, read by its `[[sensors]]`;
//! the estimators (core, `N = 3`, `f32`, E·I and its gradient along the arm calibrated so that
//! f₁ and f₂ are the truth's, [`calibrate_arm`]) with each
//! sensor set the scene allows (tip accelerometer, root strain gauge, both), and the
//! constant-gain baseline on the accelerometer.

use super::filter::{self, Setup, X_ALPHA, X_NEWMARK};
use super::{
    clamp_stress, constant, core, damage_of, rms_about_mean, EstimatorReport, Truth, N,
    TRUTH_ELEMENTS, TRUTH_TOLERANCE,
};
use crate::scene::{Scene, SensorSpec};
use crate::wind::LoadModel;
use absorber_core::estimator::SensorKind;
use absorber_core::loads::{arm_section, ArmParams};
use absorber_core::monitor::fatigue::DetailCategory;
use absorber_core::monitor::stress::RootSection;
use absorber_core::{Arm, BeamOnly, Model, Params};
use anyhow::{anyhow, bail, Result};
use serde::Serialize;

/// Unknowns of the reduced arm.
pub const D: usize = 4 * N;
/// The reduced arm model.
pub type ArmModel<T> = Model<T, Arm<BeamOnly>, N, D>;
/// The 16-element core arm (the truth's discretization, for the stress factors).
type ArmReference = Model<f64, Arm<BeamOnly>, TRUTH_ELEMENTS, { 4 * TRUTH_ELEMENTS }>;

/// The twin's results.
#[derive(Clone, Debug, Serialize)]
pub struct TwinReport {
    /// Top-level verdict: that of the extended Kalman filter with all the scene's sensors.
    pub verdict: &'static str,
    /// Simulated time \[s\].
    pub duration: f64,
    /// AASHTO category of the root.
    pub category: String,
    /// RMS of the true root stress about its mean \[MPa\].
    pub true_stress_rms_mpa: f64,
    /// Largest true rainflow range \[MPa\].
    pub max_range_mpa: f64,
    /// Static root stress under gravity: truth, estimator's model \[MPa\].
    pub static_stress_mpa: (f64, f64),
    /// First frequency of the truth (16 elements) and of the reduced model, calibrated \[Hz\].
    pub frequencies: (f64, f64),
    /// Second frequency of the truth and of the reduced model, calibrated \[Hz\].
    pub second_frequencies: (f64, f64),
    /// The calibration's bending-stiffness factor.
    pub bending_factor: f64,
    /// The calibration's gradient of that factor along the arm.
    pub bending_gradient: f64,
    /// The filter's load model, noise model and stress factors.
    pub setup: Setup,
    /// Readings beyond the tip accelerometer's range, in % of its readings.
    pub clipped_pct: f64,
    /// The estimators.
    pub estimators: Vec<EstimatorReport>,
    /// Stress-range histogram of the truth and of the first estimator with all sensors.
    pub histogram: Histogram,
}

/// Rainflow stress-range histogram.
#[derive(Clone, Debug, Serialize)]
pub struct Histogram {
    /// Bin width \[MPa\].
    pub bin_mpa: f64,
    /// Cycles per bin, truth.
    pub truth: Vec<f64>,
    /// Cycles per bin, estimate.
    pub estimate: Vec<f64>,
}

/// Time histories of the twin.
#[derive(Clone, Debug, Default)]
pub struct TwinSeries {
    /// Time \[s\].
    pub time: Vec<f64>,
    /// True root stress \[Pa\].
    pub truth: Vec<f64>,
    /// Each estimator's root stress \[Pa\] (in the report's order).
    pub estimates: Vec<Vec<f64>>,
    /// Measured tip acceleration \[m/s²\] (NaN between readings or without the sensor).
    pub measured: Vec<f64>,
}

/// The root section of an arm: `c = D_root / 2`, `I` of the root ring.
pub fn root_section(params: &Params<f64>, arm: &ArmParams<f64>) -> Result<RootSection<f64>> {
    let (_, i) = arm.section_at(0.0, params.beam.length);
    let mut beam = params.beam;
    beam.inertia = i;
    RootSection::new(&beam, 0.5 * arm.root_diameter).map_err(core)
}

/// First frequency of the reduced arm model \[Hz\].
pub fn reduced_frequency(params: &Params<f64>, arm: &ArmParams<f64>) -> Result<f64> {
    let m = ArmModel::<f64>::arm_at_rest(*params, arm, 0.0).map_err(core)?;
    Ok(m.natural_frequencies().map_err(core)?[0])
}

/// The bending-stiffness factor that gives the reduced model the first frequency `target`
/// (secant iteration on `f₁ ∝ √factor` to 1e-9 relative).
pub fn calibrate_bending(params: &Params<f64>, arm: &ArmParams<f64>, target: f64) -> Result<f64> {
    let mut p = *params;
    let mut factor = 1.0;
    for _ in 0..20 {
        p.calibration.bending_stiffness = factor;
        let f = reduced_frequency(&p, arm)?;
        if (f / target - 1.0).abs() < 1e-9 {
            return Ok(factor);
        }
        factor *= (target / f).powi(2);
    }
    bail!("the reduced model's bending calibration did not converge")
}

/// The reduced arm's first two frequencies \[Hz\].
pub fn reduced_pair(params: &Params<f64>, arm: &ArmParams<f64>) -> Result<(f64, f64)> {
    let m = ArmModel::<f64>::arm_at_rest(*params, arm, 0.0).map_err(core)?;
    let f = m.natural_frequencies().map_err(core)?;
    Ok((f[0], f[1]))
}

/// The calibration that gives the reduced arm the truth's first two frequencies `target`
/// (docs/monitoring.md, "Calibrated on f₁ and f₂"): the uniform E·I factor `b` and its linear
/// gradient along the arm `g` (`absorber_core::Calibration`), by Newton on `(ln f₁, ln f₂)`
/// with a central-difference Jacobian, from the f₁-only factor ([`calibrate_bending`], `g = 0`),
/// to 1e-9 relative. Why these two: `∂ ln f_i / ∂ ln EI_k` is half the share of element `k`
/// in mode `i`'s strain energy (Rayleigh); the first mode's lies at the clamp, the second's
/// further out, so `b` moves both alike and `g` moves f₂ against f₁. The mass blend cannot: it
/// lowers f₂/f₁ (lumping), and the reduced model's is already low.
pub fn calibrate_arm(
    params: &Params<f64>,
    arm: &ArmParams<f64>,
    target: (f64, f64),
) -> Result<absorber_core::Calibration<f64>> {
    let mut c = params.calibration;
    c.bending_stiffness = calibrate_bending(params, arm, target.0)?;
    c.bending_gradient = 0.0;
    let eval = |c: &absorber_core::Calibration<f64>| -> Result<[f64; 2]> {
        let mut p = *params;
        p.calibration = *c;
        let (a, b) = reduced_pair(&p, arm)?;
        Ok([(a / target.0).ln(), (b / target.1).ln()])
    };
    for _ in 0..30 {
        let r = eval(&c)?;
        if r[0].abs() < 1e-9 && r[1].abs() < 1e-9 {
            return Ok(c);
        }
        let (db, dg) = (1e-5 * c.bending_stiffness, 1e-5);
        let column = |set: &dyn Fn(&mut absorber_core::Calibration<f64>, f64), d: f64| {
            let (mut up, mut down) = (c, c);
            set(&mut up, d);
            set(&mut down, -d);
            let (ru, rd) = (eval(&up)?, eval(&down)?);
            Ok::<_, anyhow::Error>([(ru[0] - rd[0]) / (2.0 * d), (ru[1] - rd[1]) / (2.0 * d)])
        };
        let jb = column(&|c, d| c.bending_stiffness += d, db)?;
        let jg = column(&|c, d| c.bending_gradient += d, dg)?;
        let det = jb[0] * jg[1] - jg[0] * jb[1];
        if det.is_nan() || det.abs() <= 1e-300 {
            break;
        }
        c.bending_stiffness -= (jg[1] * r[0] - jg[0] * r[1]) / det;
        c.bending_gradient -= (-jb[1] * r[0] + jb[0] * r[1]) / det;
        if c.validate().is_err() {
            bail!(
                "the reduced arm's calibration to f1 and f2 left its range (E·I factor {}, gradient {})",
                c.bending_stiffness,
                c.bending_gradient
            );
        }
    }
    bail!("the reduced arm's calibration to f1 and f2 did not converge")
}

/// The arm of a scene: parameters, arm, category, sensors, loads.
pub struct ArmScene {
    /// Parameters.
    pub params: Params<f64>,
    /// The arm.
    pub arm: ArmParams<f64>,
    /// AASHTO category of its root.
    pub category: DetailCategory,
    /// The monitor's sensors.
    pub specs: Vec<SensorSpec>,
    /// Its loads.
    pub loads: LoadModel,
}

impl ArmScene {
    /// The arm scene of `scene` (errors name what is missing).
    pub fn of(scene: &Scene) -> Result<Self> {
        let f = &scene.file;
        let arm_file = f
            .arm
            .as_ref()
            .ok_or_else(|| anyhow!("`estimate` needs a scene with an `[arm]`"))?;
        let specs = f.sensor_specs();
        if specs.is_empty() {
            bail!("`estimate` needs a scene with `[[sensors]]`");
        }
        let params = scene.params()?;
        let loads = LoadModel::new(
            &f.loads,
            crate::scene::taper_of(arm_file, params.beam.length),
            &scene.base_dir,
        )?;
        Ok(Self {
            arm: arm_file.params()?,
            category: arm_file.detail_category()?,
            params,
            specs,
            loads,
        })
    }
}

/// The full solver of the arm under the tip and line loads of `loads(t)`.
fn truth(
    a: &ArmScene,
    steps: usize,
    loads: &dyn Fn(f64) -> (f64, Vec<f64>),
) -> Result<(Truth, (f64, f64))> {
    let params = a.params;
    let h = params.integrator.step;
    let mut pt = params;
    pt.integrator.tolerance = TRUTH_TOLERANCE;
    let mut s = absorber_full::FullSolver::arm_at_rest(
        pt,
        absorber_full::SceneKind::BeamOnly,
        TRUTH_ELEMENTS,
        &a.arm,
        0.0,
    )
    .map_err(core)?;
    let f = s.frequencies().map_err(core)?;
    let f12 = (f[0], f[1]);
    let section = root_section(&params, &a.arm)?;
    let sec0 = arm_section(
        &a.arm,
        &params.beam,
        &params.calibration,
        params.damping.stiffness_proportional,
        0,
        TRUTH_ELEMENTS,
    );
    let stress_of = |st: &absorber_full::FullState, line0: f64| {
        let applied =
            sec0.weight(params.gravity + st.base_accel) + sec0.beam.element.line_load_force(line0);
        clamp_stress(&sec0.beam, applied, &section, st)
    };
    let tip = 4 * TRUTH_ELEMENTS + 1;
    let static_stress = stress_of(s.state(), 0.0);
    let mut t = Truth {
        stress: vec![static_stress],
        static_stress,
        tip_accel: vec![s.state().a[tip]],
        ball_angle: vec![0.0; steps + 1],
        base_accel: vec![0.0; steps + 1],
        modulus: params.beam.modulus,
        impacts: 0,
        flying: 0,
        kind: "locked",
    };
    for k in 1..=steps {
        let time = k as f64 * h;
        let (p, line) = loads(time);
        s.set_loads(p, &line).map_err(core)?;
        s.step(0.0)
            .map_err(|e| anyhow!("truth step at t = {time:.3} s: {e}"))?;
        t.stress.push(stress_of(s.state(), line[0]));
        t.tip_accel.push(s.state().a[tip]);
    }
    Ok((t, f12))
}

/// The filter's setup for the arm (module doc of [`filter`]): corner at f₁, load scale from
/// the design loads' increments, stress factors from the 16-element arm, ε from calibration
/// runs under seeded tip forces with the design loads' spectrum ([`filter::surrogate`]), the
/// draws of `seeds` pooled (the studies: [`filter::calibration_seeds`] of [`filter::ARM_CALIBRATION_DRAWS`]).
fn setup(
    a: &ArmScene,
    pc: &Params<f64>,
    section: &RootSection<f64>,
    window: u32,
    seeds: &[u64],
) -> Result<Setup> {
    let h = pc.integrator.step;
    let model = ArmModel::<f64>::arm_at_rest(*pc, &a.arm, 0.0).map_err(core)?;
    let ours = filter::modal_stress_ratios(&model, section)?;
    let reference = ArmReference::arm_at_rest(a.params, &a.arm, 0.0).map_err(core)?;
    let theirs = filter::modal_stress_ratios(&reference, section)?;
    let history: Vec<f64> = (0..=(600.0 / h).round() as usize)
        .map(|k| a.loads.tip_equivalent(k as f64 * h, TRUTH_ELEMENTS))
        .collect();
    let (load_sd, corner) = filter::load_prior(&history, h);
    let (factors, mode_frequencies) = filter::stress_factors(ours, theirs, corner);
    let mut s = Setup {
        load_sd,
        load_corner: corner,
        model_error: 0.0,
        event_error: 0.0,
        stress_factors: factors,
        mode_frequencies,
        window,
        adapt_time: filter::adapt_time(),
        load_rms: super::rms(&history),
    };
    // Calibration: 60 s of a tip force with the design load's spectrum (another realization)
    // per draw, the draws pooled.
    const SECONDS: f64 = 60.0;
    let steps = (SECONDS / h).round() as usize;
    let mut draws = Vec::new();
    for seed in seeds {
        let force = filter::surrogate(&history, steps, h, *seed);
        let loads = |t: f64| {
            (
                force.get((t / h).round() as usize).copied().unwrap_or(0.0),
                vec![0.0; TRUTH_ELEMENTS],
            )
        };
        let (t, _) = truth(a, steps, &loads)?;
        let m = filter::measure(&t, &a.specs, h, 1)?;
        draws.push((t, m));
    }
    // ε from the tip accelerometer's innovations: what the online estimate (ADAPT_TIME) has
    // not yet caught, from the start (a scene without the accelerometer: ε = 0, the online
    // estimate alone).
    if a.specs.iter().any(|x| x.kind() == SensorKind::TipAccel) {
        s.model_error = filter::matched(|eps| {
            let mut c = s;
            c.model_error = eps;
            let runs = draws
                .iter()
                .map(|(t, m)| {
                    run_filter(pc, a, &c, section, m, &[SensorKind::TipAccel], t).map(|r| r.excess)
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(filter::Excess::pooled(runs).quiet_excess())
        })?;
    }
    Ok(s)
}

/// One run of the arm's filter (Newmark or generalized-α, as the scene integrates).
fn run_filter(
    pc: &Params<f64>,
    a: &ArmScene,
    setup: &Setup,
    section: &RootSection<f64>,
    m: &filter::Measured,
    kinds: &[SensorKind],
    t: &Truth,
) -> Result<filter::Run> {
    let h = pc.integrator.step;
    let cfg = filter::config(setup, section, m, kinds)?;
    let model = ArmModel::<f32>::arm_at_rest(super::params_f32(pc), &super::arm_f32(&a.arm), 0.0)
        .map_err(core)?;
    if pc.integrator.is_newmark() {
        filter::run::<Arm<BeamOnly>, D, X_NEWMARK>("arm", model, cfg, m, kinds, t, a.category, h)
    } else {
        filter::run::<Arm<BeamOnly>, D, X_ALPHA>("arm", model, cfg, m, kinds, t, a.category, h)
    }
}

/// The twin of `scene` over `duration` seconds (module doc); `baseline`: the constant-gain
/// filter's load model.
pub fn twin(
    scene: &Scene,
    duration: f64,
    baseline: constant::BaselineLoad,
) -> Result<(TwinReport, TwinSeries)> {
    if !(duration.is_finite() && duration > 0.0) {
        bail!("invalid value for `--duration`: {duration} (must be finite and positive)");
    }
    baseline.validate()?;
    let a = ArmScene::of(scene)?;
    let params = a.params;
    let h = params.integrator.step;
    for (i, s) in a.specs.iter().enumerate() {
        s.every(h, i)?;
        if s.kind() == SensorKind::BallAngle {
            bail!("invalid value for `sensors[{i}].type`: the arm has no ball (`ball_angle`)");
        }
    }
    let steps = (duration / h).round() as usize;
    let (truth, f_truth) = truth(&a, steps, &|t| a.loads.sample(t, TRUTH_ELEMENTS))?;
    let section = root_section(&params, &a.arm)?;
    let mut pc = params;
    pc.calibration = calibrate_arm(&params, &a.arm, f_truth)?;
    let f_reduced = reduced_pair(&pc, &a.arm)?;
    pc.integrator.tolerance = super::ESTIMATOR_TOLERANCE;
    let window = (1.0 / h).round() as u32;
    let s = setup(
        &a,
        &pc,
        &section,
        window,
        &filter::calibration_seeds(filter::ARM_CALIBRATION_DRAWS),
    )?;
    // Only the start is known at rest: the loads act from t = 0.
    let m = filter::measure(&truth, &a.specs, h, 1)?;
    let has = |k: SensorKind| a.specs.iter().any(|s| s.kind() == k);
    let all: Vec<SensorKind> = SensorKind::ALL.into_iter().filter(|k| has(*k)).collect();
    let mut sets: Vec<Vec<SensorKind>> = Vec::new();
    for set in [
        vec![SensorKind::TipAccel],
        vec![SensorKind::RootStrain],
        all.clone(),
    ] {
        if !set.is_empty() && set.iter().all(|k| has(*k)) && !sets.contains(&set) {
            sets.push(set);
        }
    }
    let mut estimators = Vec::new();
    let mut estimates = Vec::new();
    let mut top = "ok";
    let mut best: Option<usize> = None;
    for set in &sets {
        let r = run_filter(&pc, &a, &s, &section, &m, set, &truth)?;
        if *set == all {
            top = r.report.verdict;
            best = Some(estimators.len());
        }
        estimators.push(r.report);
        estimates.push(r.stress);
    }
    if let Some(spec) = m.spec(SensorKind::TipAccel) {
        let noise = constant::FilterNoise {
            measurement: spec.noise_sd(),
            load_step: baseline.step.unwrap_or(super::LOAD_STEP),
            bias_step: filter::ACCEL_BIAS_WALK,
            load_time: baseline.time,
            step: h,
        };
        let mut pd = pc;
        pd.integrator.tolerance = 1e-13;
        pd.integrator.newton = absorber_core::NewtonKind::Full;
        let design = ArmModel::<f64>::arm_at_rest(pd, &a.arm, 0.0).map_err(core)?;
        let model =
            ArmModel::<f32>::arm_at_rest(super::params_f32(&pc), &super::arm_f32(&a.arm), 0.0)
                .map_err(core)?;
        let check = constant::LoadCheck {
            design_rms: s.load_rms,
            window: s.window,
        };
        let (r, st) = constant::run(
            "arm", &design, model, &section, &noise, &m, &truth, a.category, check,
        )?;
        estimators.push(r);
        estimates.push(st);
    }
    let (_, _, r_true) = damage_of(a.category, truth.stress.get(1..).unwrap_or_default())?;
    let best = best.unwrap_or(0);
    let r_est = match estimates.get(best) {
        Some(e) => damage_of(a.category, e)?.2,
        None => Vec::new(),
    };
    let max_range = r_true.iter().fold(0.0f64, |m, r| m.max(r.0));
    // A 1, 2, 5 or 10 MPa… bin: at most 25 bins up to the largest true range.
    let bin = [1e6, 2e6, 5e6, 1e7, 2e7, 5e7, 1e8]
        .into_iter()
        .find(|b| max_range / b < 25.0)
        .unwrap_or(1e8);
    let bins = ((max_range / bin).floor() as usize + 1).min(1000);
    let hist = |r: &[(f64, f64)]| {
        let mut hv = vec![0.0; bins];
        for (x, count) in r.iter().filter(|(x, _)| x.is_finite()) {
            if let Some(b) = hv.get_mut(((x / bin).floor() as usize).min(bins - 1)) {
                *b += count;
            }
        }
        hv
    };
    let accel = m.values[SensorKind::TipAccel.index()].as_ref();
    let clipped = estimators
        .iter()
        .find(|e| e.estimator == "ekf" && e.sensors.contains(&SensorKind::TipAccel.id()))
        .map_or(0, |e| e.clipped[SensorKind::TipAccel.index()]);
    let readings = accel.map_or(0, |v| v.iter().skip(1).flatten().count());
    let static_est = ArmModel::<f64>::arm_at_rest(pc, &a.arm, 0.0)
        .map(|m| section.stress_of_moment(absorber_core::monitor::stress::root_reaction_moment(&m)))
        .map_err(core)?;
    let report = TwinReport {
        verdict: top,
        duration,
        category: a.category.name().into(),
        true_stress_rms_mpa: rms_about_mean(&truth.stress) / 1e6,
        max_range_mpa: max_range / 1e6,
        static_stress_mpa: (truth.static_stress / 1e6, static_est / 1e6),
        frequencies: (f_truth.0, f_reduced.0),
        second_frequencies: (f_truth.1, f_reduced.1),
        bending_factor: pc.calibration.bending_stiffness,
        bending_gradient: pc.calibration.bending_gradient,
        setup: s,
        clipped_pct: 100.0 * clipped as f64 / readings.max(1) as f64,
        estimators,
        histogram: Histogram {
            bin_mpa: bin / 1e6,
            truth: hist(&r_true),
            estimate: hist(&r_est),
        },
    };
    let series = TwinSeries {
        time: (1..=steps).map(|k| k as f64 * h).collect(),
        truth: truth.stress.get(1..).unwrap_or_default().to_vec(),
        estimates,
        measured: (1..=steps)
            .map(|k| {
                accel
                    .and_then(|v| v.get(k).copied().flatten())
                    .unwrap_or(f64::NAN)
            })
            .collect(),
    };
    Ok((report, series))
}

#[cfg(test)]
mod tests;
