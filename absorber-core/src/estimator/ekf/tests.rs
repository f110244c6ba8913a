use super::*;
use crate::estimator::health::HealthConfig;
use crate::estimator::sensors::Sensor;
use crate::estimator::sensors::{SensorKind, SensorSet};
use crate::estimator::ud::quadratic;
use crate::estimator::ud::{bierman, thornton};
use crate::loads::Loads;
use crate::model::Model;
use crate::monitor::stress::RootSection;
use crate::scene::{Loaded, LockedBall};
use crate::Params;
use nalgebra::{SMatrix, SVector};

type Sc = Loaded<LockedBall>;

pub(super) fn config<const M: usize>(sensors: SensorSet<f64>) -> EkfConfig<f64, M> {
    EkfConfig {
        sensors,
        load_sd: 0.01,
        load_corner: 2.0 * core::f64::consts::PI * 4.1,
        load_order: 1,
        load_mean_time: 0.0,
        load_mean_sd: 0.0,
        section: RootSection::rectangle(&Params::<f64>::default().beam).expect("section"),
        stress_factors: [1.0; M],
        initial_accel: 0.1,
        modal_noise: 0.0,
        impact_sd: 0.2,
        ball_restart_sd: [0.05, 1.0],
        rms_time: 1.0,
        health: HealthConfig::new(300),
        gate: 3.0,
        event_error: 0.0,
        event_window: 30,
        adapt_time: 0.0,
    }
}

fn accelerometer() -> SensorSet<f64> {
    SensorSet::empty().with(SensorKind::TipAccel, Sensor::new(2e-3, 20.0))
}

/// A seeded standard normal generator (Box–Muller on a 64-bit LCG).
pub(super) struct Normal(u64);
impl Normal {
    pub(super) fn next(&mut self) -> f64 {
        let mut u = || {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (2.0 * core::f64::consts::PI * b).cos()
    }
}

/// The directions through the step are the step's sensitivity: perturbing the predictor
/// along a mode (position or velocity) or the load (with its residual static mode) and
/// stepping again moves the new acceleration by the direction's `δx` (central
/// differences, relative 1e-4), at a deformed, moving state.
#[test]
fn directions_are_the_steps_sensitivity() {
    let mut p = Params::<f64>::default();
    p.integrator.tolerance = 1e-12;
    // Full Newton: the last factors are those of the converged step (with the default
    // per-step Newton they are the first iterate's, about 1 % off in a swinging step).
    p.integrator.newton = crate::NewtonKind::Full;
    let mut m = Model::<f64, Sc, 3, 12>::at_rest(p, 0.0).expect("model");
    for k in 0..200 {
        let f = 0.05 * (0.08 * k as f64).sin();
        m.step_with_loads(0.0, &Loads::uniform(f, 0.0))
            .expect("step");
    }
    let mut ekf = Ekf::<f64, Sc, 3, 12, 3, 12>::new(&m, config(accelerometer())).expect("ekf");
    let start = *m.state();
    let load = 0.02;
    let step_from = |s: &crate::State<f64, 12>, load: f64| {
        let mut mm = m.clone();
        mm.set_state(*s);
        mm.step_with_loads(0.0, &Loads::uniform(load, 0.0))
            .expect("step");
        *mm.state()
    };
    let mut mm = m.clone();
    mm.step_with_loads(0.0, &Loads::uniform(load, 0.0))
        .expect("step");
    let psi = ekf.residual;
    ekf.directions(&mut mm).expect("directions");
    let h = p.integrator.step;
    for j in 0..7 {
        // The velocity terms are weak: a larger step keeps the differences above the
        // Newton solution's own rounding.
        let eps = if (3..6).contains(&j) { 1e-5 } else { 1e-7 };
        let perturb = |sign: f64| {
            let mut s = start;
            let mut l = load;
            if j < 3 {
                s.q += ekf.basis.shape(j) * (sign * eps);
            } else if j < 6 {
                let w = ekf.basis.shape(j - 3) * (sign * eps);
                s.v += w;
                s.q -= w * h;
            } else {
                s.q += psi * (sign * eps);
                l += sign * eps;
            }
            step_from(&s, l).a
        };
        let fd = (perturb(1.0) - perturb(-1.0)) / (2.0 * eps);
        let dx = ekf.dx.column(j).into_owned();
        assert!(
            (fd - dx).amax() <= 1e-4 * dx.amax(),
            "direction {j}: {fd} vs {dx}"
        );
    }
}

fn dense(u: &SMatrix<f64, 5, 5>, d: &SVector<f64, 5>) -> SMatrix<f64, 5, 5> {
    u * SMatrix::from_diagonal(d) * u.transpose()
}

/// Bierman's and Thornton's updates of the factors equal the textbook covariance
/// formulas (`P − P hᵀ h P / s`, `F P Fᵀ + G Q Gᵀ`) to rounding.
#[test]
fn factored_updates_equal_the_covariance_formulas() {
    let mut rng = Normal(7);
    let mut u = SMatrix::<f64, 5, 5>::from_fn(|_, _| rng.next());
    for i in 0..5 {
        for j in 0..=i {
            u[(i, j)] = if i == j { 1.0 } else { 0.0 };
        }
    }
    let d = SVector::<f64, 5>::from_fn(|i, _| 0.5 + i as f64);
    let p = dense(&u, &d);
    let h = SVector::<f64, 5>::from_fn(|_, _| rng.next());
    let r = 0.3;
    let (mut u1, mut d1) = (u, d);
    let (k, s) = bierman(&mut u1, &mut d1, &h, r).expect("update");
    let ph = p * h;
    let s_ref = h.dot(&ph) + r;
    assert!((s - s_ref).abs() < 1e-12);
    assert!((k - ph / s_ref).amax() < 1e-12);
    let p_ref = p - ph * ph.transpose() / s_ref;
    assert!((dense(&u1, &d1) - p_ref).amax() < 1e-12);
    assert!((quadratic(&u1, &d1, &h) - h.dot(&(p_ref * h))).abs() < 1e-12);
    let f = SMatrix::<f64, 5, 5>::from_fn(|_, _| rng.next());
    let g = SMatrix::<f64, 5, 3>::from_fn(|_, _| rng.next());
    let q = [0.2, 0.0, 1.5];
    let fu = f * u;
    let mut w1: [[f64; 5]; 5] = core::array::from_fn(|i| core::array::from_fn(|k| fu[(i, k)]));
    let mut w2: [[f64; 3]; 5] = core::array::from_fn(|i| core::array::from_fn(|k| g[(i, k)]));
    let d1: [f64; 5] = core::array::from_fn(|k| d[k]);
    let (mut u2, mut d2) = (SMatrix::<f64, 5, 5>::zeros(), SVector::<f64, 5>::zeros());
    thornton(&mut w1, &d1, 5, &mut w2, &q, 3, &mut u2, &mut d2);
    let qm = SMatrix::<f64, 3, 3>::from_diagonal(&SVector::from(q));
    let p2 = f * p * f.transpose() + g * qm * g.transpose();
    assert!((dense(&u2, &d2) - p2).amax() < 1e-12);
    // Rows with leading zeros (an upper triangular F: the load's and the biases' rows) and
    // a zero-weight column left out (compacted away, as `propagate` does): the same
    // formula, with that column's variance zero.
    let mut ft = f;
    for i in 0..5 {
        for j in 0..i {
            ft[(i, j)] = 0.0;
        }
    }
    let mut dz = d;
    dz[1] = 0.0;
    let fu = ft * u;
    let keep = [0usize, 2, 3, 4];
    let mut w1 = [[0.0f64; 5]; 5];
    let mut d1 = [0.0f64; 5];
    for (c, k) in keep.iter().enumerate() {
        d1[c] = dz[*k];
        for i in 0..5 {
            w1[i][c] = fu[(i, *k)];
        }
    }
    let mut w2: [[f64; 3]; 5] = core::array::from_fn(|i| core::array::from_fn(|k| g[(i, k)]));
    // Only the last two rows feel the noise: leading zeros in the noise block too.
    for row in w2.iter_mut().take(3) {
        *row = [0.0; 3];
    }
    let mut gz = g;
    for i in 0..3 {
        for k in 0..3 {
            gz[(i, k)] = 0.0;
        }
    }
    thornton(&mut w1, &d1, keep.len(), &mut w2, &q, 3, &mut u2, &mut d2);
    let p3 = ft * dense(&u, &dz) * ft.transpose() + gz * qm * gz.transpose();
    assert!((dense(&u2, &d2) - p3).amax() < 1e-12);
}

/// The load models sample their continuous processes: the stationary variance is
/// invariant under the step (`A P∞ Aᵀ + Q = P∞`), for both orders.
#[test]
fn load_models_keep_their_stationary_variance() {
    for order in [1u8, 2] {
        let (a, l) = load_model(0.3, 20.0, 0.003, order);
        let p: [[f64; 2]; 2] = if order == 1 {
            [[0.09, 0.0], [0.0, 0.0]]
        } else {
            [[0.09, 0.0], [0.0, 400.0 * 0.09]]
        };
        for i in 0..2 {
            for j in 0..2 {
                let mut x = 0.0f64;
                for k in 0..2 {
                    for m in 0..2 {
                        x += a[i][k] * p[k][m] * a[j][m];
                    }
                    x += l[i][k] * l[j][k];
                }
                assert!(
                    (x - p[i][j]).abs() < 1e-12 * (1.0 + p[i][j]),
                    "order {order} ({i},{j})"
                );
            }
        }
    }
}
