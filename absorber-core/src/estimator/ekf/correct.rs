//! The measurement update: the predicted readings, their rows in the modal coordinates, the
//! scalar updates of the factored covariance (Bierman) and the state's correction.

use super::{Ekf, Estimate};
use crate::error::Error;
use crate::estimator::sensors::{ReadingUse, Readings, SensorKind, KINDS};
use crate::estimator::ud::{bierman_f, quadratic, quadratic_f, row_of};
use crate::loads::MAX_LOAD;
use crate::model::Model;
use crate::scalar::{is_positive, lit, Real};
use crate::scene::{BallKind, Scene};
use crate::state::{Contact, StepReport};
use crate::step::ancf::TangentBlocks;
use crate::step::tip;
use nalgebra::{SMatrix, SVector};

impl<T: Real, S: Scene, const N: usize, const D: usize, const M: usize, const X: usize>
    Ekf<T, S, N, D, M, X>
{
    /// The model's prediction of a sensor's reading (without its bias) in its current state.
    pub(super) fn predicted(&self, model: &Model<T, S, N, D>, kind: SensorKind) -> T {
        let s = model.state();
        match kind {
            SensorKind::TipAccel => s.a.get(Self::TIP).copied().unwrap_or(T::zero()) + s.base_accel,
            SensorKind::BallAngle => model.ball_relative_angle().map_or(T::zero(), |(a, _)| a),
            SensorKind::RootStrain => self.root_stress(model) / self.modulus,
        }
    }

    /// The linearization, the correction and the covariance's propagation of a sample whose
    /// model step succeeded. On error nothing of the filter has changed (the caller restores
    /// the model).
    pub(super) fn correct(
        &mut self,
        model: &mut Model<T, S, N, D>,
        readings: &Readings<T>,
        report: StepReport<T>,
    ) -> Result<Estimate<T>, Error> {
        let (ld, off) = (Self::LD, Self::OFF);
        let root_tangent = self.directions(model)?;
        let contact = model.state().contact;
        // The ball's relative angle is in the filter's subspace only while it rolls off the
        // stops (held on a stop it is fixed; flying, it is the flight state's).
        let ball_free = matches!(S::BALL, BallKind::Free) && contact == Contact::Off;
        // A landing, a separation, or a release from a stop (which the report does not name).
        let released = matches!(self.last_contact, Contact::OnStop(_)) && contact == Contact::Off;
        let ball_event = report.impact.is_some()
            || report.landing.is_some()
            || report.separation.is_some()
            || released;
        let since_event = if ball_event {
            0
        } else {
            self.since_event.saturating_add(1)
        };
        let near_event = matches!(S::BALL, BallKind::Free)
            && (!ball_free || since_event < self.config.event_window);
        let rows = self.measurement_rows(model, &root_tangent);
        // The measurement updates, on copies of the factors (committed at the end).
        let (mut u, mut d) = (self.ud_u, self.ud_d);
        let mut delta = SVector::<T, X>::zeros();
        let mut est_innov = [T::zero(); KINDS];
        let mut est_var = [T::zero(); KINDS];
        let mut used = [ReadingUse::None; KINDS];
        let mut expected = [false; KINDS];
        let mut lost = [false; KINDS];
        let (mut nis_sum, mut nis_count) = (T::zero(), 0u32);
        let k_sample = self.samples.saturating_add(1);
        let mut rms2 = self.rms2;
        let mut adapt = self.adapt;
        let slot = usize::from(near_event);
        let mut model_error_ratio = [T::zero(); KINDS];
        for kind in SensorKind::ALL {
            let k = kind.index();
            let Some(sensor) = self.config.sensors.get(kind).copied() else {
                continue;
            };
            let predicted = self.predicted(model, kind);
            // Running mean square of the predicted dynamic value (the model error's scale).
            let dynamic = match kind {
                SensorKind::RootStrain => predicted - self.static_stress / self.modulus,
                _ => predicted,
            };
            if let Some(r) = rms2.get_mut(k) {
                *r += self.rms_weight * (dynamic * dynamic - *r);
            }
            let Some(y) = readings.get(kind) else {
                continue;
            };
            if sensor.every > 1 && !k_sample.is_multiple_of(u64::from(sensor.every)) {
                continue;
            }
            let (Some(row), Some(use_k), Some(x), Some(l)) = (
                rows.get(k),
                used.get_mut(k),
                expected.get_mut(k),
                lost.get_mut(k),
            ) else {
                continue;
            };
            *x = true;
            if !y.is_finite() {
                *use_k = ReadingUse::Invalid;
                *l = true;
                continue;
            }
            if y.abs() >= sensor.range {
                *use_k = ReadingUse::Clipped;
                *l = true;
                continue;
            }
            if kind == SensorKind::BallAngle && !ball_free {
                *use_k = ReadingUse::Skipped;
                continue;
            }
            let bias = self.bias.get(k).copied().unwrap_or(T::zero());
            // Linearized: the predicted reading moves with the corrections made so far.
            let innovation = y - predicted - bias - row.dot(&delta);
            let scale2 = rms2.get(k).copied().unwrap_or(T::zero());
            let mut floor2 = sensor.model_error * sensor.model_error;
            if near_event {
                floor2 += self.config.event_error * self.config.event_error;
            }
            let (mean, weight) = adapt
                .get(k)
                .and_then(|a| a.get(slot))
                .copied()
                .unwrap_or((T::zero(), T::zero()));
            let measured = if is_positive(weight) {
                mean / weight
            } else {
                T::zero()
            };
            let model2 = (floor2 * scale2).max(measured);
            if let Some(x) = model_error_ratio.get_mut(k) {
                *x = if is_positive(scale2) {
                    (model2 / scale2).sqrt()
                } else {
                    T::zero()
                };
            }
            let noise2 = sensor.noise * sensor.noise;
            let r = noise2 + model2;
            // Huber's bound on the correction (a robust Kalman update, Masreliez & Martin
            // 1977): an innovation beyond `gate` of its predicted sd — an event the model put
            // elsewhere in time (a landing, an impact), not Gaussian noise — is used with the
            // noise variance that brings it to `gate` sd exactly.
            // `Uᵀ h`, once for the predicted variance and the update.
            let f = u.tr_mul(row);
            let hph = quadratic_f(&f, &d);
            let s0 = hph + r;
            let nis = innovation * innovation / s0;
            let gate = self.config.gate;
            if is_positive(self.adapt_weight) {
                // The excess of this innovation over the prediction without model error,
                // winsorized at the gate.
                let mut nu2 = innovation * innovation;
                if is_positive(gate) && nu2 > gate * gate * s0 {
                    nu2 = gate * gate * s0;
                }
                let w = self.adapt_weight;
                if let Some(a) = adapt.get_mut(k).and_then(|a| a.get_mut(slot)) {
                    a.0 += w * (nu2 - hph - noise2 - a.0);
                    a.1 += w * (T::one() - a.1);
                }
            }
            let mut r_used = r;
            *use_k = ReadingUse::Used;
            if is_positive(gate) && nis > gate * gate {
                r_used = innovation * innovation / (gate * gate) - (s0 - r);
                *use_k = ReadingUse::Capped;
            }
            let (gain, _) = bierman_f(&mut u, &mut d, f, r_used).ok_or(Error::NonFiniteState)?;
            delta += gain * innovation;
            nis_sum += nis;
            nis_count += 1;
            if let (Some(iv), Some(vv)) = (est_innov.get_mut(k), est_var.get_mut(k)) {
                *iv = innovation;
                *vv = s0;
            }
        }
        // The dummy measurement that the load's running mean is zero.
        let mean_sd = self.config.load_mean_sd;
        if is_positive(self.mean_weight) && is_positive(mean_sd) {
            let mean_prior = (T::one() - self.mean_weight) * self.load_mean
                + self.mean_weight
                    * (self.load_map[0][0] * self.load + self.load_map[0][1] * self.load_rate);
            let innovation = -mean_prior - delta[ld + 2];
            // The row is the unit vector of the slot: `Uᵀ h` is U's row.
            let f = row_of(&u, ld + 2);
            let (gain, _) =
                bierman_f(&mut u, &mut d, f, mean_sd * mean_sd).ok_or(Error::NonFiniteState)?;
            delta += gain * innovation;
        }
        // The correction in physical coordinates, onto the model's state at n + 1.
        let physical = delta.component_mul(&self.scale);
        let [[a11, a12], [a21, a22]] = self.load_map;
        let load = a11 * self.load + a12 * self.load_rate + physical[ld];
        let load_rate = a21 * self.load + a22 * self.load_rate + physical[ld + 1];
        let load_mean = (T::one() - self.mean_weight) * self.load_mean
            + self.mean_weight * (a11 * self.load + a12 * self.load_rate)
            + physical[ld + 2];
        if !load.is_finite() || !load_rate.is_finite() || load.abs() > lit(MAX_LOAD) {
            return Err(Error::NonFiniteState);
        }
        self.apply(model, &physical, ball_free)?;
        // Committed from here on.
        self.ud_u = u;
        self.ud_d = d;
        self.rms2 = rms2;
        self.adapt = adapt;
        self.load = load;
        self.load_rate = load_rate;
        self.load_mean = load_mean;
        for (k, b) in self.bias.iter_mut().enumerate() {
            *b += physical[off + k];
        }
        self.last_contact = contact;
        self.since_event = since_event;
        // The stress's variance: its row over the posterior at n (the state at n + 1 is a
        // linear function of it).
        let mut row = rows
            .get(SensorKind::RootStrain.index())
            .copied()
            .unwrap_or(SVector::zeros())
            * self.modulus;
        row[off + SensorKind::RootStrain.index()] = T::zero();
        let stress_var = quadratic(&self.ud_u, &self.ud_d, &row);
        let load_sd = quadratic_f(&row_of(&self.ud_u, ld), &self.ud_d)
            .max(T::zero())
            .sqrt();
        // Propagation to the next sample's prior.
        self.propagate(model, ball_free, ball_event, &report);
        self.samples = k_sample;
        let stress = self.root_stress(model);
        let failed = (stress - self.static_stress).abs() > self.config.health.stress_limit;
        let verdict = self
            .health
            .record(expected, lost, nis_sum, nis_count, failed);
        let ball_angle = model.ball_relative_angle().map_or(T::zero(), |(a, _)| a);
        Ok(Estimate {
            root_stress: stress,
            root_stress_sd: stress_var.max(T::zero()).sqrt(),
            tip_deflection: model.tip_deflection(),
            load: self.load,
            load_sd,
            ball_angle,
            innovation: est_innov,
            innovation_var: est_var,
            used,
            model_error: model_error_ratio,
            nis_sum,
            nis_count,
            verdict,
            report,
        })
    }

    /// The rows `H` of each sensor's reading over the filter's scaled coordinates at `n`
    /// (zero rows for absent sensors; the root-strain row, times the modulus and without its
    /// bias, is the stress row), with the root element's axial tangent at the step's end as
    /// [`Ekf::directions`] returns it.
    pub(super) fn measurement_rows(
        &self,
        model: &Model<T, S, N, D>,
        root_tangent: &TangentBlocks<T>,
    ) -> [SVector<T, X>; KINDS] {
        let rec = self.rec;
        let (ld, off) = (Self::LD, Self::OFF);
        let mut rows = [SVector::<T, X>::zeros(); KINDS];
        let s = model.state();
        // Filter coordinate c → (direction, mode whose shape is in δq* (c < M) or δv*).
        let direction = |c: usize| -> Option<usize> {
            if c < 2 * M {
                Some(c)
            } else if c == ld {
                Some(2 * M)
            } else {
                None
            }
        };
        // Tip acceleration: δx_tip.
        if let Some(row) = rows.get_mut(SensorKind::TipAccel.index()) {
            for c in 0..=ld {
                if let Some(j) = direction(c) {
                    row[c] = self.dx[(Self::TIP, j)];
                }
            }
            row[off + SensorKind::TipAccel.index()] = T::one();
        }
        // Ball angle: ∇α · δq', δq' = δq* + c_q δx (only read with the sensor).
        if matches!(S::BALL, BallKind::Free)
            && self.config.sensors.get(SensorKind::BallAngle).is_some()
        {
            let x = Model::<T, S, N, D>::local(&s.q, &s.v, &s.a);
            let grad = tip::gap_gradient(&model.sys.inertia, &x);
            let end = 4 * N - 4;
            let dot = |c: usize, m: &SMatrix<T, D, X>| -> T {
                grad.iter()
                    .enumerate()
                    .map(|(k, g)| *g * m[(end + k, c)])
                    .fold(T::zero(), |a, b| a + b)
            };
            let phi_dot = |i: usize| -> T {
                grad.iter()
                    .enumerate()
                    .map(|(k, g)| *g * self.consistent[(end + k, i)])
                    .fold(T::zero(), |a, b| a + b)
            };
            if let Some(row) = rows.get_mut(SensorKind::BallAngle.index()) {
                for c in 0..=ld {
                    if let Some(j) = direction(c) {
                        let mut v = rec.c_q * dot(j, &self.dx);
                        if c < M {
                            v += phi_dot(c);
                        } else if c == ld {
                            v += grad
                                .iter()
                                .enumerate()
                                .map(|(k, g)| *g * self.residual[end + k])
                                .fold(T::zero(), |a, b| a + b);
                        }
                        row[c] = v;
                    }
                }
                row[off + SensorKind::BallAngle.index()] = T::one();
            }
        }
        // Root strain (and stress): (g_q·δq' + g_v·δv' + g_a·δx) / E.
        let g_eff = model.sys.effective_gravity(s.base_accel);
        let mut g = self.stress_gradients_of(model, g_eff, root_tangent);
        for (gk, wk) in g.iter_mut().zip(self.recover.iter()) {
            *gk += *wk;
        }
        let inv_e = T::one() / self.modulus;
        if let Some(row) = rows.get_mut(SensorKind::RootStrain.index()) {
            for c in 0..=ld {
                if let Some(j) = direction(c) {
                    let dx = self.dx.column(j);
                    let mut v = rec.c_q * g[0].dot(&dx) + rec.c_v * g[1].dot(&dx) + g[2].dot(&dx);
                    if c < M {
                        v += g[0].dot(&self.consistent.column(c));
                    } else if c < 2 * M {
                        v += g[1].dot(&self.consistent.column(c - M));
                    } else if c == ld {
                        v += g[0].dot(&self.residual);
                    }
                    row[c] = v * inv_e;
                }
            }
            row[off + SensorKind::RootStrain.index()] = T::one();
        }
        // To the scaled coordinates.
        for row in rows.iter_mut() {
            *row = row.component_mul(&self.scale);
        }
        rows
    }

    /// Moves the model's state at `n + 1` by the correction `delta` (physical coordinates of
    /// the filter at `n`; module doc), keeps a held ball on its stop and a flying ball's
    /// spin, and keeps the ball inside the stops.
    fn apply(
        &self,
        model: &mut Model<T, S, N, D>,
        delta: &SVector<T, X>,
        ball_free: bool,
    ) -> Result<(), Error> {
        let rec = self.rec;
        let mut dx = SVector::<T, D>::zeros();
        let mut s = *model.state();
        for i in 0..M {
            let phi = self.consistent.column(i);
            s.q.axpy(delta[i], &phi, T::one());
            s.v.axpy(delta[M + i], &phi, T::one());
            if rec.blocks == 3 {
                s.pseudo_accel.axpy(delta[2 * M + i], &phi, T::one());
            }
            dx.axpy(delta[i], &self.dx.column(i), T::one());
            dx.axpy(delta[M + i], &self.dx.column(M + i), T::one());
        }
        dx.axpy(delta[Self::LD], &self.dx.column(2 * M), T::one());
        s.q.axpy(delta[Self::LD], &self.residual, T::one());
        // Positions take the whole linear correction: `c_q δx` moves the stiff (axial and
        // high) coordinates to where the step puts them for the corrected predictor
        // (quasi-statically). Velocities and accelerations take its modal part only: the
        // stiff part of `c_v δx` and `δx` is the integrator's jump of a stiff mode started off
        // its equilibrium, which the filter's subspace does not hold (it treats the stiff
        // coordinates as slaved), and which would ring into the next predictor.
        s.q.axpy(rec.c_q, &dx, T::one());
        let modal = self.consistent * (self.basis.projection * dx);
        s.v.axpy(rec.c_v, &modal, T::one());
        s.a += modal;
        if rec.blocks == 3 {
            s.pseudo_accel.axpy(rec.kappa, &modal, T::one());
        } else {
            s.pseudo_accel = s.a;
        }
        if let (BallKind::Free, Contact::OnStop(side)) = (S::BALL, s.contact) {
            // Held: the ball stays on the stop, whatever the housing's correction.
            model.sys.hold_on_stop(&mut s, side);
        } else if matches!(S::BALL, BallKind::Free) && !ball_free {
            // Flying (or beyond the stops): the spin is not the filter's; keep the model's.
            let m0 = model.state();
            for (x, x0) in [
                (&mut s.q, &m0.q),
                (&mut s.v, &m0.v),
                (&mut s.a, &m0.a),
                (&mut s.pseudo_accel, &m0.pseudo_accel),
            ] {
                if let (Some(a), Some(b)) = (x.get_mut(Self::SPIN), x0.get(Self::SPIN)) {
                    *a = *b;
                }
            }
        }
        let finite = |x: &SVector<T, D>| x.iter().all(|z| z.is_finite());
        if !(finite(&s.q) && finite(&s.v) && finite(&s.a) && finite(&s.pseudo_accel)) {
            return Err(Error::NonFiniteState);
        }
        if S::STOPS && ball_free {
            // Keep the corrected ball inside the stops (the model's crossing test needs the
            // start of a step on the track's side).
            let stop = model.params().ball.stop_angle * lit::<T>(0.9999);
            let alpha = model.sys.relative_angle(&s);
            if alpha.abs() > stop {
                let k = model.sys.inertia.orbit_per_spin;
                let target = if alpha > T::zero() { stop } else { -stop };
                if let Some(spin) = s.q.get_mut(Self::SPIN) {
                    *spin += (alpha - target) / k;
                }
            }
        }
        model.set_state(s);
        Ok(())
    }
}
