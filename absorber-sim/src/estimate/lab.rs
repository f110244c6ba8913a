//! The lab study: the paper's arm with its free ball, no base motion, under a wind-like tip
//! force — vortex shedding locked in at the scene's excitation frequency, 20 s episodes every
//! 30 s with 2 s ramps —, where the absorber works.
//!
//! Truths (full solver, 16 elements, `f64`): the free ball with flight, and the same arm with
//! the ball locked in its housing (its mass there, its motion not: what a monitor model
//! without the ball predicts). Estimators (core, `N = 3`, `f32`, calibrated to the
//! 16-element reference as `host-sim calibrate` does):
//! - the extended Kalman filter with the free ball in its model, on the free truth, with each
//!   sensor set the scene allows (tip accelerometer; with the ball-angle sensor; with the
//!   root strain gauge too; the gauge alone);
//! - the same filter with the ball left out (locked-ball model) on the free truth;
//! - the control, where the model is right: the locked-ball filter on the locked truth;
//! - the constant-gain filter it replaces (ball left out, and the control).
//!
//! Sensors: the scene's `[[sensors]]`, or [`default_sensors`] at the scene's step rate.

use super::filter::{self, Measured, Setup, X_NEWMARK};
use super::{
    clamp_stress, constant, core, damage_of, rms_about_mean, EstimatorReport, Truth, N,
    TRUTH_ELEMENTS, TRUTH_TOLERANCE,
};
pub use crate::ensemble::Spread;
use crate::scene::{Scene, SensorSpec};
use absorber_core::estimator::SensorKind;
use absorber_core::monitor::fatigue::DetailCategory;
use absorber_core::monitor::stress::RootSection;
use absorber_core::{FreeBall, Loaded, LockedBall, Model, Params};
use absorber_full::sim::Simulator;
use absorber_full::{FullSolver, SceneKind};
use anyhow::{bail, Result};
use serde::Serialize;

mod ensemble;
pub use ensemble::*;

/// The lab study's results.
#[derive(Clone, Debug, Serialize)]
pub struct LabReport {
    /// Top-level verdict: that of the extended Kalman filter with all the scene's sensors on
    /// the free truth (the monitor as configured).
    pub verdict: &'static str,
    /// Tip force amplitude \[N\].
    pub force_amplitude: f64,
    /// Lock-in (forcing) frequency \[Hz\].
    pub force_frequency: f64,
    /// Lock-in episodes `[start, end]` \[s\].
    pub episodes: Vec<[f64; 2]>,
    /// Simulated time \[s\].
    pub duration: f64,
    /// Truth (free ball, flight on): RMS of the root stress about its mean \[MPa\].
    pub free_stress_rms_mpa: f64,
    /// Ball locked in the housing \[MPa\].
    pub locked_stress_rms_mpa: f64,
    /// RMS of the difference locked − free, about its mean, in % of the truth's RMS.
    pub exclusion_error_pct: f64,
    /// Miner damage of the locked-ball stress over the truth's (category E′, straight line).
    pub exclusion_damage_ratio: f64,
    /// Truth's stop impacts.
    pub impacts: u64,
    /// Truth's fraction of the time with the ball in flight.
    pub flight_fraction: f64,
    /// The `N = 3` model's calibration (E·I, E·a, lumped mass fraction).
    pub calibration: [f64; 3],
    /// The filter's load model, noise model and stress factors (free-ball model).
    pub setup: Setup,
    /// The same for the locked-ball model.
    pub setup_locked: Setup,
    /// The estimators.
    pub estimators: Vec<EstimatorReport>,
}

/// Root-stress histories \[Pa\], one per step.
#[derive(Clone, Debug, Default)]
pub struct LabSeries {
    /// Time \[s\].
    pub time: Vec<f64>,
    /// Truth, free ball.
    pub free: Vec<f64>,
    /// Ball locked (full solver).
    pub locked: Vec<f64>,
    /// Each estimator's (in the report's order).
    pub estimates: Vec<Vec<f64>>,
}

/// The lab study's sensors when the scene has none: the mast arm's MEMS accelerometer
/// (ADXL355 class: 25 µg/√Hz, 20 mg bias, ±2 g, filtered at a quarter of the rate), a
/// 12-bit magnetic angle encoder on the ball (AS5600 class: 0.088° steps, 0.05° noise, 0.5°
/// offset) and a foil strain gauge at the clamp (1 µε noise, 20 µε offset, ±3000 µε), all at
/// the scene's step rate.
pub fn default_sensors(h: f64) -> Vec<SensorSpec> {
    let rate = 1.0 / h;
    vec![
        SensorSpec::TipAccel {
            noise_density_ug: 25.0,
            bandwidth: 0.25 * rate,
            bias_mg: 20.0,
            range_g: 2.0,
            rate,
            seed: 1,
        },
        SensorSpec::BallAngle {
            noise_deg: 0.05,
            resolution_deg: 360.0 / 4096.0,
            bias_deg: 0.5,
            range_deg: 180.0,
            rate,
            seed: 2,
        },
        SensorSpec::RootStrain {
            noise_ue: 1.0,
            bias_ue: 20.0,
            range_ue: 3000.0,
            rate,
            seed: 3,
        },
    ]
}

/// Tip force of the lab study \[N\] at time `t`: vortex shedding locked in at `frequency`
/// during `episodes`, with a 2 s cosine ramp at both ends of an episode.
pub fn lab_force(t: f64, amplitude: f64, frequency: f64, episodes: &[[f64; 2]]) -> f64 {
    let ramp = 2.0;
    let w = episodes
        .iter()
        .map(|[a, b]| {
            if t <= *a || t >= *b {
                0.0
            } else {
                let x = ((t - a).min(b - t) / ramp).min(1.0);
                0.5 - 0.5 * (std::f64::consts::PI * x).cos()
            }
        })
        .fold(0.0f64, f64::max);
    w * amplitude * (2.0 * std::f64::consts::PI * frequency * t).sin()
}

/// The full solver of the lab arm (`kind`), 16 elements, under the tip force `force(t)`.
fn truth(
    params: &Params<f64>,
    kind: SceneKind,
    steps: usize,
    force: &dyn Fn(f64) -> f64,
) -> Result<Truth> {
    let mut p = *params;
    p.integrator.tolerance = TRUTH_TOLERANCE;
    let h = p.integrator.step;
    let section = RootSection::rectangle(&p.beam).map_err(core)?;
    let element = absorber_core::shared::Element::of_beam(&p.beam, &p.calibration, TRUTH_ELEMENTS);
    let beam = absorber_core::shared::Beam::new(element, p.damping.stiffness_proportional);
    let zero_line = vec![0.0; TRUTH_ELEMENTS];
    let tip = 4 * TRUTH_ELEMENTS + 1;
    let stress_of = |st: &absorber_full::FullState| {
        clamp_stress(
            &beam,
            beam.element.gravity_force(p.gravity + st.base_accel),
            &section,
            st,
        )
    };
    let mut s = FullSolver::at_rest(p, kind, TRUTH_ELEMENTS, 0.0).map_err(core)?;
    let ball = |s: &FullSolver| {
        let b = s.observe().ball_relative_angle;
        if b.is_finite() {
            b
        } else {
            0.0
        }
    };
    let mut t = Truth {
        stress: Vec::with_capacity(steps + 1),
        static_stress: stress_of(s.state()),
        tip_accel: Vec::with_capacity(steps + 1),
        ball_angle: Vec::with_capacity(steps + 1),
        base_accel: vec![0.0; steps + 1],
        modulus: p.beam.modulus,
        impacts: 0,
        flying: 0,
        kind: if kind == SceneKind::FreeBall {
            "free"
        } else {
            "locked"
        },
    };
    t.stress.push(t.static_stress);
    t.tip_accel.push(s.state().a[tip]);
    t.ball_angle.push(ball(&s));
    for k in 1..=steps {
        let time = k as f64 * h;
        s.set_loads(force(time), &zero_line).map_err(core)?;
        let r = s
            .step(0.0)
            .map_err(|e| anyhow::anyhow!("truth step at t = {time:.3} s: {e}"))?;
        t.impacts += u64::from(r.impact.is_some());
        t.flying += usize::from(s.in_flight());
        t.stress.push(stress_of(s.state()));
        t.tip_accel.push(s.state().a[tip]);
        t.ball_angle.push(ball(&s));
    }
    Ok(t)
}

/// The estimators' parameters: `N = 3` calibrated to the 16-element reference, starting with
/// the ball plumb (a monitor does not know its angle).
fn estimator_params(scene: &Scene) -> Result<(Params<f64>, [f64; 3])> {
    let (reference, free_index) = crate::calibrate::reference(scene, TRUTH_ELEMENTS)?;
    let fit = crate::calibrate::fit(scene, N, &reference, free_index)?;
    let mut pc = scene.params()?;
    pc.calibration = fit.calibration;
    pc.ball.initial_angle = 0.0;
    Ok((
        pc,
        [
            fit.calibration.bending_stiffness,
            fit.calibration.axial_stiffness,
            fit.calibration.mass_lumping,
        ],
    ))
}

/// The filter's setup for the model of scene `S` (`D` unknowns): corner at the fundamental
/// bending mode, load scale from the lab force's increments, stress factors from the
/// 16-element model; the noise model from the calibration runs ([`calibrate_noise`]).
fn setup<S: absorber_core::Scene, const D: usize, const DR: usize>(
    pc: &Params<f64>,
    reference: &Params<f64>,
    section: &RootSection<f64>,
    prior: (f64, f64),
    window: u32,
) -> Result<(Setup, Model<f64, S, N, D>)> {
    let model = Model::<f64, S, N, D>::at_rest(*pc, 0.0).map_err(core)?;
    let ours = filter::modal_stress_ratios(&model, section)?;
    let full = Model::<f64, S, TRUTH_ELEMENTS, DR>::at_rest(*reference, 0.0).map_err(core)?;
    let theirs = filter::modal_stress_ratios(&full, section)?;
    let (factors, mode_frequencies) = filter::stress_factors(ours, theirs, prior.1);
    Ok((
        Setup {
            load_sd: prior.0,
            load_corner: prior.1,
            model_error: 0.0,
            event_error: 0.0,
            stress_factors: factors,
            mode_frequencies,
            window,
            adapt_time: filter::adapt_time(),
            load_rms: prior.0,
        },
        model,
    ))
}

/// The noise model (module doc of [`filter`]): under tip forces with the design load's
/// spectrum ([`filter::surrogate`] of `design`, the seeded draws of
/// [`filter::calibration_seeds`] of [`filter::LAB_CALIBRATION_DRAWS`] pooled: not the study's force), the locked-ball
/// filter on the locked truth gives ε (and, where ε = 0 leaves the innovations smaller than
/// predicted, the load model's variance scale λ: [`filter::matched_load_scale`]); the
/// free-ball filter with ε on the free truth gives ε_e near the ball's events (the ball
/// reaches the stops near the 2:1 tuning).
#[allow(clippy::too_many_arguments)]
fn calibrate_noise(
    pc: &Params<f64>,
    truth_params: &Params<f64>,
    section: &RootSection<f64>,
    specs: &[SensorSpec],
    design: &[f64],
    free: &mut Setup,
    locked: &mut Setup,
) -> Result<()> {
    let h = pc.integrator.step;
    const SECONDS: f64 = 30.0;
    let steps = (SECONDS / h).round() as usize;
    let accel = [SensorKind::TipAccel];
    let category = DetailCategory::EPrime;
    let forces: Vec<Vec<f64>> = filter::calibration_seeds(filter::LAB_CALIBRATION_DRAWS)
        .into_iter()
        .map(|seed| filter::surrogate(design, steps, h, seed))
        .collect();
    let at = |f: &[f64], t: f64| f.get((t / h).round() as usize).copied().unwrap_or(0.0);
    let mut locked_draws = Vec::new();
    for f in &forces {
        let t = truth(truth_params, SceneKind::LockedBall, steps, &|x| at(f, x))?;
        let m = measure_for(&t, specs, h)?;
        locked_draws.push((t, m));
    }
    // The locked-ball filter on the locked calibration truths with the setup `s`, pooled.
    let run_locked = |s: &Setup| -> Result<filter::Excess> {
        let mut runs = Vec::new();
        for (t, m) in &locked_draws {
            let r = run_locked_ball(s, section, super::params_f32(pc), m, t, category, h)?;
            runs.push(r.excess);
        }
        Ok(filter::Excess::pooled(runs))
    };
    let eps = filter::matched(|eps| {
        let mut s = *locked;
        s.model_error = eps;
        Ok(run_locked(&s)?.quiet_excess())
    })?;
    free.model_error = eps;
    locked.model_error = eps;
    if eps == 0.0 {
        let lambda = filter::matched_load_scale(|lambda| {
            let mut s = *locked;
            s.load_sd *= lambda.sqrt();
            Ok(run_locked(&s)?.quiet_ratio())
        })?;
        locked.load_sd *= lambda.sqrt();
        free.load_sd *= lambda.sqrt();
    }
    let mut free_draws = Vec::new();
    for f in &forces {
        let t = truth(truth_params, SceneKind::FreeBall, steps, &|x| at(f, x))?;
        let m = measure_for(&t, specs, h)?;
        free_draws.push((t, m));
    }
    free.event_error = filter::matched(|eps_e| {
        let mut s = *free;
        s.event_error = eps_e;
        let mut runs = Vec::new();
        for (t, m) in &free_draws {
            let cfg = filter::config(&s, section, m, &accel)?;
            let model = Model::<f32, Loaded<FreeBall>, N, { 4 * N + 1 }>::at_rest(
                super::params_f32(pc),
                0.0,
            )
            .map_err(core)?;
            let r = filter::run::<Loaded<FreeBall>, { 4 * N + 1 }, X_NEWMARK>(
                "free-ball",
                model,
                cfg,
                m,
                &accel,
                t,
                category,
                h,
            )?;
            runs.push(r.excess);
        }
        Ok(filter::Excess::pooled(runs).event_excess())
    })?;
    Ok(())
}

/// The sensors of `specs` on a lab truth, at rest for its first [`filter::QUIET`] seconds
/// (the first episode ramps up from 2 s).
/// The locked-ball filter on the tip accelerometer (the model without the ball's motion, set up
/// by `setup`) run on one truth and its measurements: the study's baseline and the noise
/// calibration's runs.
fn run_locked_ball(
    setup: &Setup,
    section: &RootSection<f64>,
    params: Params<f32>,
    measured: &Measured,
    truth: &Truth,
    category: DetailCategory,
    h: f64,
) -> Result<filter::Run> {
    let accel = [SensorKind::TipAccel];
    let cfg = filter::config(setup, section, measured, &accel)?;
    let model =
        Model::<f32, Loaded<LockedBall>, N, { 4 * N }>::at_rest(params, 0.0).map_err(core)?;
    filter::run::<Loaded<LockedBall>, { 4 * N }, X_NEWMARK>(
        "locked-ball",
        model,
        cfg,
        measured,
        &accel,
        truth,
        category,
        h,
    )
}

fn measure_for(truth: &Truth, specs: &[SensorSpec], h: f64) -> Result<Measured> {
    filter::measure(truth, specs, h, (filter::QUIET / h).round() as usize)
}

/// The lab study of `scene` (module doc) over `duration` seconds with a tip force of
/// `amplitude` newtons at the scene's excitation frequency; `baseline`: the constant-gain
/// filter's load model. Realization 0 of [`lab_member`].
pub fn lab(
    scene: &Scene,
    duration: f64,
    amplitude: f64,
    baseline: constant::BaselineLoad,
) -> Result<(LabReport, LabSeries)> {
    lab_member(scene, duration, amplitude, baseline, 0)
}

/// Rounding-level offset of the truth's initial ball angle per realization \[rad\].
pub const MEMBER_ANGLE: f64 = 1e-12;

/// The sensor `spec` of realization `member`: its noise seed moved by `member` (Weyl
/// increment, so realizations never share a stream); realization 0 keeps it.
fn reseeded(mut spec: SensorSpec, member: u64) -> SensorSpec {
    match &mut spec {
        SensorSpec::TipAccel { seed, .. }
        | SensorSpec::BallAngle { seed, .. }
        | SensorSpec::RootStrain { seed, .. } => {
            *seed = seed.wrapping_add(member.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        }
    }
    spec
}

/// One realization of the lab study ([`lab`]): realization `member` draws every sensor's
/// noise from its own seeds ([`reseeded`]) and starts the truth's ball `member` ×
/// [`MEMBER_ANGLE`] off the scene's initial angle. At the working point the free ball is
/// chaotic: that rounding-level change gives another trajectory of the same statistics, and
/// another side for the ball in each lock-in episode (doc of [`LabEnsemble`]).
pub fn lab_member(
    scene: &Scene,
    duration: f64,
    amplitude: f64,
    baseline: constant::BaselineLoad,
    member: u32,
) -> Result<(LabReport, LabSeries)> {
    if !(duration.is_finite() && duration > 0.0) {
        bail!("invalid value for `--duration`: {duration} (must be finite and positive)");
    }
    if !(amplitude.is_finite() && amplitude > 0.0) {
        bail!("invalid value for `--tip-force`: {amplitude} (must be finite and positive)");
    }
    baseline.validate()?;
    if scene.file.kind != crate::scene::Kind::Free {
        bail!(
            "the lab study needs a scene with the free ball between stops (`kind = \"free\"`, e.g. `paper`), not `{}`",
            scene.file.kind.name()
        );
    }
    // The first lock-in episode ramps up from 2 s to 4 s.
    if duration < 5.0 {
        bail!("invalid value for `--duration`: {duration} (the lab study needs at least 5 s: its first episode ramps up from 2 s to 4 s)");
    }
    let frequency = match scene.file.excitation.frequency {
        Some(f) if f.is_finite() && f > 0.0 => f,
        _ => bail!("the lab study drives the tip at the scene's `excitation.frequency`: none set"),
    };
    let mut params = scene.params()?;
    params.ball.initial_angle += f64::from(member) * MEMBER_ANGLE;
    let h = params.integrator.step;
    if !params.integrator.is_newmark() {
        bail!("the lab study's filter runs the scene's Newmark integrator (`integrator.scheme`)");
    }
    let specs = {
        let s = scene.file.sensor_specs();
        let s = if s.is_empty() { default_sensors(h) } else { s };
        s.into_iter()
            .map(|x| reseeded(x, u64::from(member)))
            .collect::<Vec<_>>()
    };
    let steps = (duration / h).round() as usize;
    // Lock-in episodes of 20 s every 30 s (vortex shedding comes and goes with the wind).
    let episodes: Vec<[f64; 2]> = (0..)
        .map(|k| [2.0 + 30.0 * k as f64, 22.0 + 30.0 * k as f64])
        .take_while(|[a, _]| *a < duration)
        .collect();
    let force = |t: f64| lab_force(t, amplitude, frequency, &episodes);
    let free = truth(&params, SceneKind::FreeBall, steps, &force)?;
    let locked = truth(&params, SceneKind::LockedBall, steps, &force)?;
    let section = RootSection::rectangle(&params.beam).map_err(core)?;
    let category = DetailCategory::EPrime;
    let diff: Vec<f64> = locked
        .stress
        .iter()
        .zip(&free.stress)
        .map(|(l, f)| l - f)
        .collect();
    let (d_free, _, _) = damage_of(category, &free.stress)?;
    let (d_locked, _, _) = damage_of(category, &locked.stress)?;
    // The filters.
    let (pc, calibration) = estimator_params(scene)?;
    let history: Vec<f64> = (0..=steps).map(|k| force(k as f64 * h)).collect();
    let prior = filter::load_prior(&history, h);
    let window = (1.0 / h).round() as u32;
    const L: usize = 4 * N;
    const F: usize = 4 * N + 1;
    let (mut s_free, _) = setup::<Loaded<FreeBall>, F, { 4 * TRUTH_ELEMENTS + 1 }>(
        &pc, &params, &section, prior, window,
    )?;
    let (mut s_locked, _) = setup::<Loaded<LockedBall>, L, { 4 * TRUTH_ELEMENTS }>(
        &pc, &params, &section, prior, window,
    )?;
    calibrate_noise(
        &pc,
        &params,
        &section,
        &specs,
        &history,
        &mut s_free,
        &mut s_locked,
    )?;
    let m_free = measure_for(&free, &specs, h)?;
    let m_locked = measure_for(&locked, &specs, h)?;
    let has = |k: SensorKind| specs.iter().any(|s| s.kind() == k);
    let mut sets: Vec<Vec<SensorKind>> = Vec::new();
    let all: Vec<SensorKind> = SensorKind::ALL.into_iter().filter(|k| has(*k)).collect();
    for set in [
        vec![SensorKind::TipAccel],
        vec![SensorKind::TipAccel, SensorKind::BallAngle],
        vec![SensorKind::RootStrain],
        all.clone(),
    ] {
        if set.iter().all(|k| has(*k)) && !sets.contains(&set) {
            sets.push(set);
        }
    }
    let p32 = super::params_f32(&pc);
    let mut estimators = Vec::new();
    let mut estimates = Vec::new();
    let mut top = "ok";
    for set in &sets {
        let cfg = filter::config(&s_free, &section, &m_free, set)?;
        let model = Model::<f32, Loaded<FreeBall>, N, F>::at_rest(p32, 0.0).map_err(core)?;
        let r = filter::run::<Loaded<FreeBall>, F, X_NEWMARK>(
            "free-ball",
            model,
            cfg,
            &m_free,
            set,
            &free,
            category,
            h,
        )?;
        if *set == all {
            top = r.report.verdict;
        }
        estimators.push(r.report);
        estimates.push(r.stress);
    }
    if has(SensorKind::TipAccel) {
        for (t, m) in [(&free, &m_free), (&locked, &m_locked)] {
            let r = run_locked_ball(&s_locked, &section, p32, m, t, category, h)?;
            estimators.push(r.report);
            estimates.push(r.stress);
        }
        // The constant-gain filter (the baseline): its default load model follows the
        // forcing's largest change per sample, 2π f A h, over τ = 5 s.
        let noise = constant::FilterNoise {
            measurement: m_free
                .spec(SensorKind::TipAccel)
                .map_or(0.0, SensorSpec::noise_sd),
            load_step: baseline
                .step
                .unwrap_or(2.0 * std::f64::consts::PI * frequency * amplitude * h),
            bias_step: filter::ACCEL_BIAS_WALK,
            load_time: baseline.time,
            step: h,
        };
        let mut pd = pc;
        pd.integrator.tolerance = 1e-13;
        pd.integrator.newton = absorber_core::NewtonKind::Full;
        let design = Model::<f64, Loaded<LockedBall>, N, L>::at_rest(pd, 0.0).map_err(core)?;
        for (t, m) in [(&free, &m_free), (&locked, &m_locked)] {
            let model = Model::<f32, Loaded<LockedBall>, N, L>::at_rest(p32, 0.0).map_err(core)?;
            let (r, s) = constant::run(
                "locked-ball",
                &design,
                model,
                &section,
                &noise,
                m,
                t,
                category,
                constant::LoadCheck {
                    design_rms: super::rms(&history),
                    window,
                },
            )?;
            estimators.push(r);
            estimates.push(s);
        }
    }
    let series = LabSeries {
        time: (1..=steps).map(|k| k as f64 * h).collect(),
        free: free.stress.get(1..).unwrap_or_default().to_vec(),
        locked: locked.stress.get(1..).unwrap_or_default().to_vec(),
        estimates,
    };
    let report = LabReport {
        verdict: top,
        force_amplitude: amplitude,
        force_frequency: frequency,
        episodes,
        duration,
        free_stress_rms_mpa: rms_about_mean(&free.stress) / 1e6,
        locked_stress_rms_mpa: rms_about_mean(&locked.stress) / 1e6,
        exclusion_error_pct: 100.0 * rms_about_mean(&diff) / rms_about_mean(&free.stress),
        exclusion_damage_ratio: d_locked / d_free,
        impacts: free.impacts,
        flight_fraction: free.flying as f64 / steps.max(1) as f64,
        calibration,
        setup: s_free,
        setup_locked: s_locked,
        estimators,
    };
    Ok((report, series))
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod targets;
