//! The constant-gain estimator's host side (the baseline the extended Kalman filter
//! replaces): its steady-state gain ([`design`]) and its run against a truth ([`run`]).
//!
//! The gain is the steady-state Kalman gain of the model's own step map, linearized by
//! central differences about the static state, augmented with the tip load (Gauss–Markov)
//! and the accelerometer's bias (random walk), the Riccati equation iterated to convergence in
//! `f64`; the core applies it per sample (`absorber_core::estimator::constant`).

use super::filter::Measured;
use super::{core, damage_of, rms, run_verdict, stress_error_pct, EstimatorReport, Truth, N};
use absorber_core::estimator::{Estimator, Gain, SensorKind};
use absorber_core::loads::Loads;
use absorber_core::monitor::fatigue::DetailCategory;
use absorber_core::monitor::stress::{root_reaction_moment, RootSection};
use absorber_core::{Model, Scene as CoreScene};
use anyhow::{bail, Result};
use nalgebra::{DMatrix, DVector, SVector};
use serde::Serialize;

/// Noise settings of the filter design.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FilterNoise {
    /// Measurement noise σ \[m/s²\].
    pub measurement: f64,
    /// Standard deviation of the tip load's random-walk increment per sample \[N\].
    pub load_step: f64,
    /// Standard deviation of the bias's random-walk increment per sample \[m/s²\].
    pub bias_step: f64,
    /// Time constant τ of the load's Gauss–Markov model \[s\].
    pub load_time: f64,
    /// Sample period h \[s\].
    pub step: f64,
}

/// The constant-gain baseline's tip-load model as the user sets it (`--load-step`,
/// `--load-time`): the random walk's sd per sample (`None`: the study's default) and the
/// Gauss–Markov time constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaselineLoad {
    /// Standard deviation of the load's increment per sample \[N\] (`None`: the default).
    pub step: Option<f64>,
    /// Time constant \[s\].
    pub time: f64,
}

impl Default for BaselineLoad {
    fn default() -> Self {
        Self {
            step: None,
            time: 5.0,
        }
    }
}

impl BaselineLoad {
    /// Checks the values (errors name the option).
    pub fn validate(&self) -> Result<()> {
        if let Some(step) = self.step {
            if !(step.is_finite() && step > 0.0) {
                bail!("invalid value for `--load-step`: {step} (must be finite and positive)");
            }
        }
        if !(self.time.is_finite() && self.time > 0.0) {
            bail!(
                "invalid value for `--load-time`: {} (must be finite and positive)",
                self.time
            );
        }
        Ok(())
    }
}

/// Packs a state into `(q, v, a, pseudo_accel)`.
fn pack<const D: usize>(s: &absorber_core::State<f64, D>) -> DVector<f64> {
    DVector::from_iterator(
        4 * D,
        s.q.iter()
            .chain(s.v.iter())
            .chain(s.a.iter())
            .chain(s.pseudo_accel.iter())
            .copied(),
    )
}

fn unpack<const D: usize>(
    base: &absorber_core::State<f64, D>,
    x: &DVector<f64>,
) -> absorber_core::State<f64, D> {
    let mut s = *base;
    let part = |k: usize| SVector::<f64, D>::from_iterator(x.rows(k * D, D).iter().copied());
    s.q = part(0);
    s.v = part(1);
    s.a = part(2);
    s.pseudo_accel = part(3);
    s
}

/// The steady-state gain of the estimator for `model` (at its static state, `f64`, tight
/// Newton tolerance), root `section` and `noise` (module doc of
/// [`absorber_core::estimator`]): the step map linearized by central differences, augmented
/// with the tip load and the bias, the Riccati equation iterated to a relative change of the
/// gain below 1e-10. Any scene with loads: the arm ([`ArmModel`]), or the paper's bodies
/// with the ball locked or free (`Loaded<LockedBall>`, `Loaded<FreeBall>`, the lab study).
pub fn design<S: CoreScene, const D: usize>(
    model: &Model<f64, S, N, D>,
    section: &RootSection<f64>,
    noise: &FilterNoise,
) -> Result<Gain<f64, D>> {
    let nx = 4 * D;
    let n = nx + 2;
    let s0 = *model.state();
    let step = |x: &DVector<f64>, load: f64| -> Result<DVector<f64>> {
        let mut m = model.clone();
        m.set_state(unpack(&s0, x));
        m.step_with_loads(0.0, &Loads::uniform(load, 0.0))
            .map_err(core)?;
        Ok(pack(m.state()))
    };
    let x0 = pack(&s0);
    let mut a = DMatrix::<f64>::zeros(n, n);
    // Perturbations: 1 µm (or µrad) of position, and the rates it implies at 10 rad/s.
    let scales = [1e-6, 1e-5, 1e-4, 1e-4];
    for j in 0..nx {
        let eps = scales[j / D];
        let mut xp = x0.clone();
        xp[j] += eps;
        let mut xm = x0.clone();
        xm[j] -= eps;
        let col = (step(&xp, 0.0)? - step(&xm, 0.0)?) / (2.0 * eps);
        a.view_mut((0, j), (nx, 1)).copy_from(&col);
    }
    let g = (step(&x0, 1.0)? - step(&x0, -1.0)?) / 2.0;
    let phi = (-noise.step / noise.load_time).exp();
    a.view_mut((0, nx), (nx, 1)).copy_from(&(&g * phi));
    a[(nx, nx)] = phi;
    a[(nx + 1, nx + 1)] = 1.0;
    // Process noise: the load's increment enters through G and the load itself.
    let mut gl = DVector::<f64>::zeros(n);
    gl.rows_mut(0, nx).copy_from(&g);
    gl[nx] = 1.0;
    let mut q = &gl * gl.transpose() * noise.load_step.powi(2);
    q[(nx + 1, nx + 1)] += noise.bias_step.powi(2);
    // Measurement: the absolute tip acceleration (a of the end node's y) plus the bias.
    let tip = 2 * D + (4 * N - 3);
    let mut h = DVector::<f64>::zeros(n);
    h[tip] = 1.0;
    h[nx + 1] = 1.0;
    let r = noise.measurement.powi(2);
    // The load's random walk as the accelerometer sees it, against the measurement noise:
    // beyond 1/√ε the measurement's variance is lost in rounding beside the load's
    // (S = h P hᵀ + r) and the Riccati iteration cannot converge. Refused before it runs.
    let seen = noise.load_step * g[tip].abs() / noise.measurement;
    let most = 1.0 / f64::EPSILON.sqrt();
    if seen.is_nan() || seen > most {
        bail!(
            "invalid value for `--load-step`: {:e} N per sample: the tip accelerometer sees it as \
             {:.3e} m/s², {seen:.3e} times its noise σ = {:.3e} m/s²; allowed: at most {:.3e} N \
             (1/√ε = {most:.1e} times the noise: beyond, the noise is lost in rounding and the \
             filter's Riccati iteration cannot converge; on the lab scene it converged at 3e5 times the noise, not at 3e6)",
            noise.load_step,
            noise.load_step * g[tip].abs(),
            noise.measurement,
            most * noise.measurement / g[tip].abs()
        );
    }
    // Balanced coordinates x̃ = T⁻¹x (T diagonal, powers of two: exact): the step map mixes
    // positions, rates and accelerations of stiff axial modes, entries over ~14 decades, and
    // the Riccati iteration's rounding floor in raw units lay above its convergence test.
    let t = balance(&a);
    let a = DMatrix::from_fn(n, n, |i, j| a[(i, j)] * t[j] / t[i]);
    let q = DMatrix::from_fn(n, n, |i, j| q[(i, j)] / (t[i] * t[j]));
    let h = DVector::from_fn(n, |i, _| h[i] * t[i]);
    let mut p = q.clone();
    let mut k = DVector::<f64>::zeros(n);
    let mut post = p.clone();
    let mut innovation_var = r;
    let mut converged = false;
    for _ in 0..400_000 {
        let pm = &a * &p * a.transpose() + &q;
        let ph = &pm * &h;
        let s = h.dot(&ph) + r;
        innovation_var = s;
        let k_new = ph / s;
        let ikh = DMatrix::<f64>::identity(n, n) - &k_new * h.transpose();
        // Joseph form: stays symmetric positive semi-definite in rounding.
        post = &ikh * &pm * ikh.transpose() + &k_new * k_new.transpose() * r;
        let change = (&k_new - &k).amax();
        k = k_new;
        p = post.clone();
        if change <= 1e-10 * k.amax() {
            converged = true;
            break;
        }
    }
    if !converged {
        bail!(
            "the estimator's Riccati iteration did not converge (load random walk `--load-step` \
             = {:e} N per sample, `--load-time` = {} s, measurement noise σ = {:.3e} m/s²): try a \
             smaller `--load-step`",
            noise.load_step,
            noise.load_time,
            noise.measurement
        );
    }
    // Back to physical coordinates: K = T K̃, P = T P̃ T.
    let k = DVector::from_fn(n, |i, _| k[i] * t[i]);
    let post = DMatrix::from_fn(n, n, |i, j| post[(i, j)] * t[i] * t[j]);
    // Stress sensitivity to the state, by central differences of the clamp reaction.
    let mut c = DVector::<f64>::zeros(n);
    let stress = |x: &DVector<f64>| {
        let mut m = model.clone();
        m.set_state(unpack(&s0, x));
        section.stress_of_moment(root_reaction_moment(&m))
    };
    for j in 0..nx {
        let eps = scales[j / D];
        let mut xp = x0.clone();
        xp[j] += eps;
        let mut xm = x0.clone();
        xm[j] -= eps;
        c[j] = (stress(&xp) - stress(&xm)) / (2.0 * eps);
    }
    let part = |i: usize| SVector::<f64, D>::from_iterator(k.rows(i * D, D).iter().copied());
    // The position rows are dropped: the gain is linearized at the static state, where a
    // correction of the vertical slopes leaves the axial strain ε = d₁ + ½|d|² unchanged to
    // first order; at a deflected state it does not (the ½ d₂² term), so position corrections
    // pump the axial modes (E·a ≈ 10⁹ N) and the loop diverged once the tip swung ±0.3 m
    // (tested: a perfect model under a resonant tip force). Velocities and accelerations carry
    // the correction into the positions through the integrator, within the model's kinematics.
    let gain = Gain {
        q: SVector::zeros(),
        v: part(1),
        a: part(2),
        pseudo_accel: part(3),
        load: k[nx],
        load_decay: phi,
        bias: k[nx + 1],
        stress_sd: c.dot(&(&post * &c)).max(0.0).sqrt(),
        load_sd: post[(nx, nx)].max(0.0).sqrt(),
        innovation_sd: innovation_var.sqrt(),
    };
    Ok(gain)
}

/// Diagonal balancing of a square matrix (Osborne's iteration as in LAPACK's `gebal`, powers
/// of two): `t` such that `T⁻¹ A T` has rows and columns of comparable norms.
fn balance(a: &DMatrix<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut t = vec![1.0f64; n];
    for _ in 0..100 {
        let mut done = true;
        for i in 0..n {
            let (mut col, mut row) = (0.0, 0.0);
            for j in (0..n).filter(|&j| j != i) {
                col += (a[(j, i)] * t[i] / t[j]).abs();
                row += (a[(i, j)] * t[j] / t[i]).abs();
            }
            if col == 0.0 || row == 0.0 {
                continue;
            }
            let mut f = 1.0;
            let (mut c, mut r) = (col, row);
            while c < r / 2.0 {
                c *= 2.0;
                r /= 2.0;
                f *= 2.0;
            }
            while c >= r * 2.0 {
                c /= 2.0;
                r *= 2.0;
                f /= 2.0;
            }
            if (c + r) < 0.95 * (col + row) {
                done = false;
                t[i] *= f;
            }
        }
        if done {
            break;
        }
    }
    t
}

/// The constant-gain filter's own consistency check (its verdict). Its innovations cannot
/// judge it: the random-walk load absorbs whatever the model misses (at the lab arm's working
/// point the ball's reaction, 1.5–2.4 N RMS of estimated load against a 0.035 N force), so
/// they stay small when the stress is wrong. The load estimate does not: the estimated tip
/// load's mean square over a sliding window, per unit of the design load's mean square, is a
/// normalized squared residual like the EKF's NIS and gets its health thresholds
/// ([`absorber_core::estimator::HealthConfig`]: above 4 `degraded`, above 25 `failed`).
#[derive(Clone, Copy, Debug)]
pub struct LoadCheck {
    /// RMS of the design load about zero \[N\] (the site's loads, or the lab force).
    pub design_rms: f64,
    /// Window \[samples\].
    pub window: u32,
}

/// Runs the constant-gain estimator of scene `S` (`f32` model `model` at rest; its gain
/// designed in `f64` on `design_model` for `noise`) on the tip accelerometer of `measured`,
/// and scores it against `truth`.
#[allow(clippy::too_many_arguments)]
pub fn run<S: CoreScene, const D: usize>(
    model_name: &'static str,
    design_model: &Model<f64, S, N, D>,
    model: Model<f32, S, N, D>,
    section: &RootSection<f64>,
    noise: &FilterNoise,
    measured: &Measured,
    truth: &Truth,
    category: DetailCategory,
    check: LoadCheck,
) -> Result<(EstimatorReport, Vec<f64>)> {
    let Some(spec) = measured.spec(SensorKind::TipAccel) else {
        bail!("the constant-gain estimator needs a `tip_accel` sensor");
    };
    let gain = design(design_model, section, noise)?;
    let mut est = Estimator::new(
        model,
        gain.cast::<f32>(),
        super::section_f32(section),
        spec.range() as f32,
    )
    .map_err(core)?;
    let kinds = [SensorKind::TipAccel];
    if let Some(y0) = measured.quiet_means(&kinds).get(SensorKind::TipAccel) {
        est.initialize_bias(0.0, y0).map_err(core)?;
    }
    let static_est = f64::from(est.root_stress());
    let mut last = static_est;
    let (mut failed, mut clipped) = (0, 0);
    let (mut innov, mut loads) = (Vec::new(), Vec::new());
    let mut stress = Vec::with_capacity(truth.steps());
    let accel = measured.values[SensorKind::TipAccel.index()]
        .as_ref()
        .map_or(&[][..], |v| v.as_slice());
    let mut last_y = 0.0f32;
    let health = absorber_core::estimator::HealthConfig::<f64>::new(check.window.max(1));
    let window = check.window.max(1) as usize;
    let design_ms = (check.design_rms * check.design_rms).max(f64::MIN_POSITIVE);
    let (mut ring, mut ring_sum) = (vec![0.0f64; window], 0.0f64);
    let mut lost = vec![false; window];
    let mut lost_n = 0usize;
    let mut verdicts = [0usize; 3];
    for k in 1..=truth.steps() {
        // Between readings (a sensor slower than the model) the last one is held.
        if let Some(Some(y)) = accel.get(k) {
            last_y = *y as f32;
        }
        let base = truth.base_accel.get(k).copied().unwrap_or(0.0) as f32;
        let now_lost = match est.update(base, last_y) {
            Ok(e) => {
                last = f64::from(e.root_stress);
                clipped += usize::from(e.clipped);
                if !e.clipped {
                    innov.push(f64::from(e.innovation));
                }
                e.clipped
            }
            Err(_) => {
                failed += 1;
                true
            }
        };
        stress.push(last);
        let load = f64::from(est.load());
        loads.push(load);
        // The window's normalized load and lost readings (clipped, or a refused step).
        let slot = k % window;
        let x = if load.is_finite() {
            load * load / design_ms
        } else {
            f64::INFINITY
        };
        ring_sum += x - ring[slot];
        ring[slot] = x;
        lost_n = lost_n + usize::from(now_lost) - usize::from(lost[slot]);
        lost[slot] = now_lost;
        let filled = k.min(window) as f64;
        let ratio = ring_sum / filled;
        let lost_frac = lost_n as f64 / filled;
        let v = if !ratio.is_finite() || ratio > health.failed_nis || lost_frac > health.failed_clip
        {
            2
        } else if ratio > health.degraded_nis || lost_n > 0 {
            1
        } else {
            0
        };
        verdicts[v] += 1;
    }
    let (d_est, _, _) = damage_of(category, &stress)?;
    let (d_true, _, _) = damage_of(category, truth.stress.get(1..).unwrap_or_default())?;
    let n = truth.steps().max(1) as f64;
    let frac = verdicts.map(|v| v as f64 / n);
    let report = EstimatorReport {
        estimator: "constant-gain",
        model: model_name,
        sensors: vec![SensorKind::TipAccel.id()],
        truth: truth.kind,
        stress_rms_error_pct: stress_error_pct(truth, &stress, static_est),
        damage_ratio: d_est / d_true,
        nis: f64::NAN,
        verdict: run_verdict(&frac),
        verdict_fractions: frac,
        damage_degraded_pct: f64::NAN,
        within_two_sd: {
            let sd = gain.stress_sd;
            let offset = static_est - truth.static_stress;
            let t = truth.stress.get(1..).unwrap_or_default();
            let inside = stress
                .iter()
                .zip(t)
                .filter(|(e, tr)| (*e - *tr - offset).abs() <= 2.0 * sd)
                .count();
            inside as f64 / stress.len().max(1) as f64
        },
        innovation_ratio: rms(&innov) / gain.innovation_sd,
        failed,
        clipped: [clipped, 0, 0],
        capped: 0,
        load_rms: rms(&loads),
        quality: Vec::new(),
    };
    let report = EstimatorReport {
        quality: super::quality(&report),
        ..report
    };
    Ok((report, stress))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::arm::{root_section, ArmModel};
    use crate::scene::Scene;

    /// With a perfect model (the truth is the estimator's own model in `f64`), a resonant tip
    /// force of 8 N that the estimator does not get and a 20 mg bias, the estimated root stress
    /// follows the true one within 1 % of the stress amplitude over 150 s (the filter's
    /// steady-state sd is 0.35 MPa against ±60 MPa of swing: 1 % leaves room for the onset).
    #[test]
    fn estimator_follows_a_resonant_load_it_is_not_given() {
        let scene = Scene::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/mast-arm.toml"
        ))
        .expect("scene");
        let arm = scene.file.arm.as_ref().expect("arm").params().expect("arm");
        let mut params = scene.params().expect("params");
        params.integrator.tolerance = 1e-11;
        let section = root_section(&params, &arm).expect("section");
        let mut pd = params;
        pd.integrator.newton = absorber_core::NewtonKind::Full;
        let m = ArmModel::<f64>::arm_at_rest(pd, &arm, 0.0).expect("model");
        let noise = FilterNoise {
            measurement: 1.2e-3,
            load_step: 0.5,
            bias_step: 2.5e-6,
            load_time: 5.0,
            step: 0.01,
        };
        let g = design(&m, &section, &noise).expect("gain");
        let mut est = Estimator::new(
            ArmModel::<f64>::arm_at_rest(params, &arm, 0.0).expect("model"),
            g,
            section,
            20.0,
        )
        .expect("estimator");
        let mut truth = ArmModel::<f64>::arm_at_rest(params, &arm, 0.0).expect("model");
        let f1 = truth.natural_frequencies().expect("modes")[0];
        let bias = 0.196;
        est.initialize_bias(0.0, bias).expect("finite");
        let (mut worst, mut swing) = (0.0f64, 0.0f64);
        let static_stress = est.root_stress();
        for k in 1..=15_000 {
            let p = 8.0 * (2.0 * std::f64::consts::PI * f1 * k as f64 * 0.01).sin();
            truth
                .step_with_loads(0.0, &Loads::uniform(p, 0.0))
                .expect("truth");
            let y = truth.state().a[4 * N - 3] + bias;
            let e = est.update(0.0, y).expect("estimate");
            let s_true = section.stress_of_moment(root_reaction_moment(&truth));
            worst = worst.max((e.root_stress - s_true).abs());
            swing = swing.max((s_true - static_stress).abs());
        }
        assert!(swing > 50e6, "swing {swing}");
        assert!(worst < 0.01 * swing, "worst error {worst} Pa of {swing} Pa");
    }
}
