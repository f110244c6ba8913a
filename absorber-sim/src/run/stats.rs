//! A run's summary statistics: steady amplitude, RMS, energies, contact statistics.

use super::Row;

/// Summary figures of a run, accumulated row by row in fixed memory.
#[derive(Clone, Debug)]
pub struct RunStats {
    steady_from: f64,
    window: f64,
    end: f64,
    first: Option<Row>,
    last_t: f64,
    tip_max: f64,
    tip_lo: f64,
    tip_hi: f64,
    ball_max: f64,
    ball_lo: f64,
    ball_hi: f64,
    impacts: u64,
    max_iterations: u32,
    beam_first: (f64, u64),
    beam_last: (f64, u64),
    ball_first: (f64, u64),
    ball_last: (f64, u64),
    /// Σ (tip deflection − static)² and samples over the steady window.
    tip_square: (f64, u64),
    /// Stop impacts in the steady window.
    steady_impacts: u64,
    contact: ContactStats,
}

/// What the track had to do: how often it pulled the ball (N < 0), the smallest N, and the
/// largest friction coefficient rolling needed (|F_t|/N with N > 0, off the stops).
#[derive(Clone, Copy, Debug, Default)]
struct ContactStats {
    /// m_b g \[N\], the stop angle \[rad\] and the friction coefficient (`None`: no free ball).
    ball: Option<(f64, f64, f64)>,
    samples: u64,
    /// Samples off the stops with N > 0 where rolling needs more than the friction coefficient.
    slips: u64,
    steady_slips: u64,
    pulled: u64,
    steady_samples: u64,
    steady_pulled: u64,
    min_normal: f64,
    max_mu: f64,
    /// Samples in flight, whole run and steady part.
    flying: u64,
    steady_flying: u64,
    separations: u64,
    landings: u64,
    bounces: u64,
    /// Plastic landings whose rough impulse needed more friction than the coefficient.
    slipping_landings: u64,
    max_landing_mu: f64,
    /// Separations and landings in the steady window.
    steady_separations: u64,
    steady_landings: u64,
    /// Shortest flight counted by `long_flights` \[s\].
    resolution: f64,
    /// Time of the last row on the track before the current flight (None: on the track).
    flight_start: Option<f64>,
    /// Last row's time.
    previous: Option<f64>,
    /// Flights (from a take-off to the next row on the track, bounces included) of at least
    /// `resolution` that started in the steady window.
    steady_long_flights: u64,
}

impl RunStats {
    /// Also reports the track's forces on a free ball: `(m_b g [N], stop angle [rad], friction
    /// coefficient)` (`None` for scenes without a free ball).
    pub fn with_ball(mut self, ball: Option<(f64, f64, f64)>) -> Self {
        self.contact.ball = ball;
        self.contact.min_normal = f64::INFINITY;
        self
    }

    /// For a run ending at `end` \[s\] whose steady state starts at `steady_from` \[s\]; the mean
    /// energies are taken over the first and the last min(10 s, end/2).
    pub fn new(end: f64, steady_from: f64) -> Self {
        Self {
            steady_from,
            window: 10.0f64.min(end / 2.0),
            end,
            first: None,
            last_t: 0.0,
            tip_max: f64::NAN,
            tip_lo: f64::INFINITY,
            tip_hi: f64::NEG_INFINITY,
            ball_max: f64::NAN,
            ball_lo: f64::INFINITY,
            ball_hi: f64::NEG_INFINITY,
            impacts: 0,
            max_iterations: 0,
            beam_first: (0.0, 0),
            beam_last: (0.0, 0),
            ball_first: (0.0, 0),
            ball_last: (0.0, 0),
            tip_square: (0.0, 0),
            steady_impacts: 0,
            contact: ContactStats {
                resolution: crate::scene::FLIGHT_RESOLUTION,
                ..ContactStats::default()
            },
        }
    }

    /// Counts flights of at least `resolution` \[s\] apart (`outputs.flight_resolution`).
    pub fn with_flight_resolution(mut self, resolution: f64) -> Self {
        self.contact.resolution = resolution;
        self
    }

    /// Adds a row.
    pub fn push(&mut self, r: &Row) {
        let first = *self.first.get_or_insert(*r);
        let static_d = first.tip_deflection;
        self.last_t = r.t;
        let d = r.tip_deflection - static_d;
        if d.is_finite() {
            self.tip_max = self.tip_max.max(d.abs());
        }
        let th = r.ball_angle.to_degrees();
        if th.is_finite() {
            self.ball_max = self.ball_max.max(th.abs());
        }
        // Half a step of slack: the grid time k·h may round just below the window start.
        let eps = 1e-9 * self.end.max(1.0);
        if r.t >= self.steady_from - eps {
            self.tip_lo = self.tip_lo.min(r.tip_deflection);
            self.tip_hi = self.tip_hi.max(r.tip_deflection);
            if d.is_finite() {
                self.tip_square.0 += d * d;
                self.tip_square.1 += 1;
            }
            self.steady_impacts += u64::from(r.events.impacts);
            if th.is_finite() {
                self.ball_lo = self.ball_lo.min(th);
                self.ball_hi = self.ball_hi.max(th);
            }
        }
        self.impacts += u64::from(r.events.impacts);
        self.max_iterations = self.max_iterations.max(r.iterations);
        if let (Some((_, stop, mu)), true) = (self.contact.ball, r.normal_force.is_finite()) {
            let c = &mut self.contact;
            let flying = u64::from(r.contact == 0.0);
            c.flying += flying;
            c.separations += u64::from(r.events.separations);
            let steady = r.t >= self.steady_from - eps;
            if steady {
                c.steady_separations += u64::from(r.events.separations);
                c.steady_landings += u64::from(r.events.landings);
            }
            c.flight(r.t, r.contact == 0.0, self.steady_from - eps);
            c.landings += u64::from(r.events.landings);
            c.bounces += u64::from(r.events.bounces);
            if let Some((bounced, need)) = r.landing {
                if !bounced && need.is_finite() {
                    c.slipping_landings += u64::from(need > mu);
                    c.max_landing_mu = c.max_landing_mu.max(need);
                }
            }
            if r.t >= self.steady_from - eps {
                c.steady_flying += flying;
            }
            let pulled = u64::from(r.normal_force < 0.0);
            // On a stop the tangential force is the stop's, not friction's.
            let on_stop = r.ball_rel_angle.abs() >= stop * (1.0 - 1e-9);
            let need = r.tangential_force.abs() / r.normal_force;
            let slips = u64::from(r.normal_force > 0.0 && !on_stop && need > mu);
            c.samples += 1;
            c.pulled += pulled;
            c.slips += slips;
            if r.t >= self.steady_from - eps {
                c.steady_samples += 1;
                c.steady_pulled += pulled;
                c.steady_slips += slips;
            }
            c.min_normal = c.min_normal.min(r.normal_force);
            if r.normal_force > 0.0 && !on_stop {
                c.max_mu = c.max_mu.max(need);
            }
        }
        let e = &r.energies;
        let beam = e.beam_strain - first.energies.beam_strain + e.beam_kinetic + e.beam_potential;
        let ball = e.ball_kinetic + e.ball_potential;
        let add = |acc: &mut (f64, u64), x: f64| {
            acc.0 += x;
            acc.1 += 1;
        };
        if r.t <= self.window + eps {
            add(&mut self.beam_first, beam);
            add(&mut self.ball_first, ball);
        }
        if r.t >= self.end - self.window - eps {
            add(&mut self.beam_last, beam);
            add(&mut self.ball_last, ball);
        }
    }

    /// The summary as JSON (the `run`/`paper` output).
    pub fn json(&self) -> serde_json::Value {
        let half = |lo: f64, hi: f64| if lo <= hi { 0.5 * (hi - lo) } else { f64::NAN };
        let mean = |a: (f64, u64)| if a.1 > 0 { a.0 / a.1 as f64 } else { f64::NAN };
        let span = self.last_t - self.steady_from;
        let rate = |n: u64| {
            if span > 0.0 {
                n as f64 / span
            } else {
                f64::NAN
            }
        };
        serde_json::json!({
            "duration": self.last_t,
            "steady_from": self.steady_from,
            "static_tip_deflection": self.first.map(|r| r.tip_deflection).unwrap_or(f64::NAN),
            "tip_amplitude_max": self.tip_max,
            "tip_amplitude_steady": half(self.tip_lo, self.tip_hi),
            "ball_angle_max_deg": self.ball_max,
            "ball_angle_steady_deg": half(self.ball_lo, self.ball_hi),
            "impacts": self.impacts,
            "max_iterations": self.max_iterations,
            "energy_window": self.window,
            "beam_energy_first": mean(self.beam_first),
            "beam_energy_last": mean(self.beam_last),
            "ball_energy_first": mean(self.ball_first),
            "ball_energy_last": mean(self.ball_last),
            "tip_rms_steady": mean(self.tip_square).sqrt(),
            "impact_rate_steady": rate(self.steady_impacts),
            "contact": self.contact.json(self.last_t - self.steady_from),
        })
    }
}

impl ContactStats {
    /// Follows the flights row by row: a flight runs from the last row on the track to the next
    /// one (its bounces included), so its length is counted in whole steps.
    fn flight(&mut self, t: f64, flying: bool, steady_from: f64) {
        if flying {
            if self.flight_start.is_none() {
                // (The first row of a run is on the track.)
                self.flight_start = Some(self.previous.unwrap_or(t));
            }
        } else if let Some(t0) = self.flight_start.take() {
            if t - t0 >= self.resolution * (1.0 - 1e-9) && t0 >= steady_from {
                self.steady_long_flights += 1;
            }
        }
        self.previous = Some(t);
    }

    fn json(&self, span: f64) -> serde_json::Value {
        let Some((weight, _, mu)) = self.ball else {
            return serde_json::Value::Null;
        };
        let frac = |k: u64, n: u64| if n > 0 { k as f64 / n as f64 } else { f64::NAN };
        let rate = |n: u64| {
            if span > 0.0 {
                n as f64 / span
            } else {
                f64::NAN
            }
        };
        serde_json::json!({
            "track_pulls_fraction": frac(self.pulled, self.samples),
            "track_pulls_fraction_steady": frac(self.steady_pulled, self.steady_samples),
            "normal_force_min": self.min_normal,
            "normal_force_min_over_weight": self.min_normal / weight,
            "required_friction_max": self.max_mu,
            "friction": mu,
            "slip_fraction": frac(self.slips, self.samples),
            "slip_fraction_steady": frac(self.steady_slips, self.steady_samples),
            "flight_fraction": frac(self.flying, self.samples),
            "flight_fraction_steady": frac(self.steady_flying, self.steady_samples),
            "separations": self.separations,
            "landings": self.landings,
            "bounces": self.bounces,
            "landings_slipping": self.slipping_landings,
            "landing_friction_max": self.max_landing_mu,
            "separation_rate_steady": rate(self.steady_separations),
            "landing_rate_steady": rate(self.steady_landings),
            "long_flight_rate_steady": rate(self.steady_long_flights),
            "flight_resolution": self.resolution,
        })
    }
}

/// Half the peak-to-peak value of `x` over the samples with t ≥ `from` (NaN if none).
pub fn half_range(rows: &[Row], from: f64, x: impl Fn(&Row) -> f64) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in rows.iter().filter(|r| r.t >= from) {
        let v = x(r);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo <= hi {
        0.5 * (hi - lo)
    } else {
        f64::NAN
    }
}
