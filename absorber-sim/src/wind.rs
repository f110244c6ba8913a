//! Wind and traffic loads on a traffic-signal arm, as time histories of the core's per-sample
//! loads ([`absorber_core::Loads`]): a vertical force at the tip and a vertical line load per
//! element, positive up. The sources and coefficients are in `docs/monitoring.md`.
//!
//! The arm is horizontal and the wind blows across it, so the loads that bend it in the
//! vertical plane of the model are **vertical**: the lift of vortices shed by the signal heads
//! with backplates (Cruzado, Letchford & Kopp 2013), the vertical turbulence of natural wind
//! (buffeting), and the upward gust under the arm when a truck passes (AASHTO LRFD-LTS §11.7.1;
//! Kaczinski, Dexter & Van Dien 1998, NCHRP Report 412). Forces on the heads act at the tip (the
//! loads carry one point force): a simplification the truth and the estimator share.
//!
//! - [`LoadComponent::VortexShedding`]: `F(t) = ½ ρ U² A C_L sin(2π f_s t)` with the shedding
//!   frequency `f_s = St U / D` (Blevins 1990, *Flow-Induced Vibration*, ch. 3), on while
//!   `t` lies in one of the episodes.
//! - [`LoadComponent::Buffeting`]: quasi-steady vertical force of the vertical gust w′(t) on the
//!   arm, `q(x, t) = ½ ρ U D(x) C_D w′(t)` \[N/m\] (the drag along the relative wind, whose
//!   vertical component is `½ρ|V|² D C_D · w′/|V|`), and on the heads `½ ρ U A C_D,h w′(t)`; w′
//!   Gaussian with the Kaimal spectrum of the vertical component (Kaimal et al. 1972,
//!   *Q. J. R. Meteorol. Soc.* 98:563) `n S_w(n) / σ_w² = 2 f / (1 + 5.3 f^{5/3}) / c`,
//!   `f = n z / U` (c normalizes the band to σ_w² exactly), `σ_w = 0.5 I_u U` (Panofsky & Dutton
//!   1984: σ_w/σ_u ≈ 0.5 near the ground), synthesized as a sum of cosines with random phases
//!   (Shinozuka & Deodatis 1991), seeded; fully correlated along the arm (conservative).
//! - [`LoadComponent::TruckGust`]: upward pressure `p` on the arm's projected width between
//!   `x0` and `x1` (above a lane), a half-sine pulse of duration τ at each passage time.
//! - [`LoadComponent::Csv`]: `t, tip_force, line_load` columns, linear in between.

use crate::csvio;
use anyhow::{bail, Context, Result};
use rand::RngExt;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Air density at 15 °C, sea level \[kg/m³\] (ISO 2533).
pub const AIR_DENSITY: f64 = 1.225;

/// One load source of a scene's `[[loads]]` list.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum LoadComponent {
    /// Vortex shedding from the signal heads: harmonic lift at the tip.
    VortexShedding {
        /// Wind speed U \[m/s\].
        speed: f64,
        /// Across-wind depth D of the head with backplate \[m\].
        depth: f64,
        /// Strouhal number St \[-\].
        strouhal: f64,
        /// Lift coefficient amplitude C_L \[-\].
        lift_coefficient: f64,
        /// Reference area A of all heads \[m²\].
        area: f64,
        /// Episodes `[start, end]` \[s\] in which the vortices lock in (empty: always).
        #[serde(default)]
        episodes: Vec<[f64; 2]>,
    },
    /// Buffeting by the vertical turbulence of natural wind.
    Buffeting {
        /// Mean wind speed U \[m/s\].
        mean_speed: f64,
        /// Longitudinal turbulence intensity I_u = σ_u / U \[-\].
        turbulence_intensity: f64,
        /// Height z above ground \[m\].
        height: f64,
        /// Drag coefficient of the arm C_D \[-\].
        drag_coefficient: f64,
        /// Heads: area times force coefficient A·C_D,h \[m²\].
        head_force_area: f64,
        /// Random seed.
        seed: u64,
        /// Spectrum of the vertical gust: `kaimal` (default) or `von-karman`.
        #[serde(default)]
        spectrum: Spectrum,
        /// Integral length scale of the vertical gust \[m\] (von Kármán only; default half
        /// the height, Simiu & Scanlan 1996).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        length_scale: Option<f64>,
    },
    /// Truck-induced gust: half-sine pressure pulses on a stretch of the arm.
    TruckGust {
        /// Peak pressure p \[Pa\] (times the drag coefficient).
        pressure: f64,
        /// Start and end of the loaded stretch \[m from the root\].
        from: f64,
        /// End of the loaded stretch \[m\].
        to: f64,
        /// Pulse duration τ \[s\].
        duration: f64,
        /// Passage times \[s\].
        times: Vec<f64>,
    },
    /// Forces from a CSV file: `t [s], tip_force [N], line_load [N/m]`.
    Csv {
        /// File, relative to the scene file.
        file: PathBuf,
    },
}

/// The spectrum of the vertical gust of [`LoadComponent::Buffeting`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Spectrum {
    /// Kaimal et al. 1972: `n S_w / σ² ∝ 2f / (1 + 5.3 f^{5/3})`, `f = n z / U`.
    #[default]
    Kaimal,
    /// von Kármán (vertical component; ESDU 85020, Simiu & Scanlan 1996):
    /// `n S_w / σ² = 4 f (1 + 755.2 f²) / (1 + 283.2 f²)^{11/6}`, `f = n L_w / U`.
    VonKarman,
}

/// The arm's outer diameter along its length (the projected width for the wind).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Taper {
    /// Length \[m\].
    pub length: f64,
    /// Outer diameter at the root \[m\].
    pub root: f64,
    /// Outer diameter at the tip \[m\].
    pub tip: f64,
}

impl Taper {
    fn diameter(&self, x: f64) -> f64 {
        self.root + (self.tip - self.root) * x / self.length
    }
}

/// Loads ready to sample: the components with their random series drawn.
#[derive(Clone, Debug)]
pub struct LoadModel {
    taper: Taper,
    parts: Vec<Part>,
}

#[derive(Clone, Debug)]
enum Part {
    Harmonic {
        amplitude: f64,
        omega: f64,
        episodes: Vec<[f64; 2]>,
    },
    Gust {
        /// `½ ρ U C_D` per unit diameter and gust speed \[kg/m³·m/s\].
        arm: f64,
        /// `½ ρ U A C_D,h` \[N per m/s\].
        head: f64,
        series: Series,
    },
    Truck {
        pressure: f64,
        from: f64,
        to: f64,
        duration: f64,
        times: Vec<f64>,
    },
    Table(Vec<[f64; 3]>),
}

/// A stationary Gaussian series as a sum of cosines.
#[derive(Clone, Debug)]
struct Series {
    amp: Vec<f64>,
    omega: Vec<f64>,
    phase: Vec<f64>,
}

impl Series {
    fn at(&self, t: f64) -> f64 {
        self.amp
            .iter()
            .zip(&self.omega)
            .zip(&self.phase)
            .map(|((a, w), p)| a * (w * t + p).cos())
            .sum()
    }
}

/// The seeded generator of every random stream of the host (gust phases, sensor noise,
/// surrogate loads, fleet records, the accuracy study's noise): ChaCha8 of `rand`, the same
/// stream for the same seed on every machine. Normal samples come from `rand_distr`
/// (`StandardNormal`). The firmware and the core's no_std tests keep their own tiny xorshift
/// generators: no heap, and their instruction counts and state hashes are pinned.
pub type Rng = rand::rngs::ChaCha8Rng;

/// The generator seeded with `seed` (stream 0).
pub fn seeded(seed: u64) -> Rng {
    use rand::SeedableRng;
    Rng::seed_from_u64(seed)
}

/// Kaimal's vertical spectrum shape `n S_w(n) / σ² ∝ 2f / (1 + 5.3 f^{5/3})`, `f = n z / U`,
/// as a one-sided density in n (unnormalized).
pub fn kaimal_vertical(n: f64, height: f64, speed: f64) -> f64 {
    let f = n * height / speed;
    2.0 * f / (1.0 + 5.3 * f.powf(5.0 / 3.0)) / n
}

/// von Kármán's vertical spectrum shape `n S_w(n) / σ² = 4f (1 + 755.2 f²) / (1 + 283.2 f²)^{11/6}`,
/// `f = n L / U`, as a one-sided density in n (unnormalized).
pub fn von_karman_vertical(n: f64, length: f64, speed: f64) -> f64 {
    let f = n * length / speed;
    4.0 * f * (1.0 + 755.2 * f * f) / (1.0 + 283.2 * f * f).powf(11.0 / 6.0) / n
}

/// Frequencies of the synthesized gust: 0.002 … 20 Hz, log-spaced.
const GUST_BAND: (f64, f64, usize) = (0.002, 20.0, 1500);

fn gust_series(sigma: f64, shape: &dyn Fn(f64) -> f64, seed: u64) -> Series {
    let (lo, hi, n) = GUST_BAND;
    let mut rng = seeded(seed);
    let ratio = (hi / lo).powf(1.0 / n as f64);
    let mut amp = Vec::with_capacity(n);
    let mut omega = Vec::with_capacity(n);
    let mut phase = Vec::with_capacity(n);
    let mut var = 0.0;
    for k in 0..n {
        let (f0, f1) = (lo * ratio.powi(k as i32), lo * ratio.powi(k as i32 + 1));
        // Frequency jittered inside its band: no exact period of the sum.
        let f = f0 + (f1 - f0) * rng.random::<f64>();
        let s = shape(f) * (f1 - f0);
        var += s;
        amp.push(s);
        omega.push(2.0 * PI * f);
        phase.push(2.0 * PI * rng.random::<f64>());
    }
    // Scale so that the variance Σ a²/2 is σ² exactly.
    for a in amp.iter_mut() {
        *a = (2.0 * *a / var).sqrt() * sigma;
    }
    Series { amp, omega, phase }
}

impl LoadModel {
    /// Builds the loads of `components` on an arm of diameter `taper`; CSV paths are relative
    /// to `base_dir`. Errors name the key (`loads[i].field`).
    pub fn new(components: &[LoadComponent], taper: Taper, base_dir: &Path) -> Result<Self> {
        let mut parts = Vec::new();
        for (i, c) in components.iter().enumerate() {
            let key = |field: &str| format!("loads[{i}].{field}");
            let pos = |x: f64, field: &str| -> Result<()> {
                if !(x.is_finite() && x > 0.0) {
                    bail!(
                        "invalid value for `{}`: {x} (must be finite and positive)",
                        key(field)
                    );
                }
                Ok(())
            };
            parts.push(match c {
                LoadComponent::VortexShedding {
                    speed,
                    depth,
                    strouhal,
                    lift_coefficient,
                    area,
                    episodes,
                } => {
                    pos(*speed, "speed")?;
                    pos(*depth, "depth")?;
                    pos(*strouhal, "strouhal")?;
                    pos(*area, "area")?;
                    if !lift_coefficient.is_finite() || *lift_coefficient < 0.0 {
                        bail!(
                            "invalid value for `{}`: must be finite and not negative",
                            key("lift_coefficient")
                        );
                    }
                    for e in episodes {
                        if !(e[0].is_finite() && e[1].is_finite() && e[0] <= e[1]) {
                            bail!(
                                "invalid value for `{}`: {e:?} (need start <= end)",
                                key("episodes")
                            );
                        }
                    }
                    Part::Harmonic {
                        amplitude: 0.5 * AIR_DENSITY * speed * speed * area * lift_coefficient,
                        omega: 2.0 * PI * strouhal * speed / depth,
                        episodes: episodes.clone(),
                    }
                }
                LoadComponent::Buffeting {
                    mean_speed,
                    turbulence_intensity,
                    height,
                    drag_coefficient,
                    head_force_area,
                    seed,
                    spectrum,
                    length_scale,
                } => {
                    pos(*mean_speed, "mean_speed")?;
                    pos(*turbulence_intensity, "turbulence_intensity")?;
                    pos(*height, "height")?;
                    pos(*drag_coefficient, "drag_coefficient")?;
                    if !head_force_area.is_finite() || *head_force_area < 0.0 {
                        bail!(
                            "invalid value for `{}`: must be finite and not negative",
                            key("head_force_area")
                        );
                    }
                    let sigma_w = 0.5 * turbulence_intensity * mean_speed;
                    let (z, u) = (*height, *mean_speed);
                    let series = match spectrum {
                        Spectrum::Kaimal => {
                            if length_scale.is_some() {
                                bail!(
                                    "invalid value for `{}`: only for `spectrum = \"von-karman\"`",
                                    key("length_scale")
                                );
                            }
                            gust_series(sigma_w, &|n| kaimal_vertical(n, z, u), *seed)
                        }
                        Spectrum::VonKarman => {
                            let l = length_scale.unwrap_or(0.5 * z);
                            pos(l, "length_scale")?;
                            gust_series(sigma_w, &|n| von_karman_vertical(n, l, u), *seed)
                        }
                    };
                    Part::Gust {
                        arm: 0.5 * AIR_DENSITY * mean_speed * drag_coefficient,
                        head: 0.5 * AIR_DENSITY * mean_speed * head_force_area,
                        series,
                    }
                }
                LoadComponent::TruckGust {
                    pressure,
                    from,
                    to,
                    duration,
                    times,
                } => {
                    pos(*duration, "duration")?;
                    if !pressure.is_finite() {
                        bail!("invalid value for `{}`: must be finite", key("pressure"));
                    }
                    if !(0.0 <= *from && from < to && *to <= taper.length) {
                        bail!(
                            "invalid value for `{}`/`{}`: need 0 <= from < to <= arm length {}",
                            key("from"),
                            key("to"),
                            taper.length
                        );
                    }
                    Part::Truck {
                        pressure: *pressure,
                        from: *from,
                        to: *to,
                        duration: *duration,
                        times: times.clone(),
                    }
                }
                LoadComponent::Csv { file } => {
                    let path = base_dir.join(file);
                    let text = std::fs::read_to_string(&path).with_context(|| {
                        format!("cannot read `{}` ({})", key("file"), path.display())
                    })?;
                    Part::Table(parse_table(&text).with_context(|| key("file"))?)
                }
            });
        }
        Ok(Self { taper, parts })
    }

    /// The loads at time `t` on `n` equal elements: tip force \[N\] and line load per element
    /// \[N/m\] (element averages: exact for the linear taper).
    pub fn sample(&self, t: f64, n: usize) -> (f64, Vec<f64>) {
        let mut tip = 0.0;
        let mut line = vec![0.0; n];
        let l = self.taper.length / n as f64;
        for p in &self.parts {
            match p {
                Part::Harmonic {
                    amplitude,
                    omega,
                    episodes,
                } => {
                    let on = episodes.is_empty() || episodes.iter().any(|e| t >= e[0] && t <= e[1]);
                    if on {
                        tip += amplitude * (omega * t).sin();
                    }
                }
                Part::Gust { arm, head, series } => {
                    let w = series.at(t);
                    tip += head * w;
                    for (k, q) in line.iter_mut().enumerate() {
                        *q += arm * self.taper.diameter((k as f64 + 0.5) * l) * w;
                    }
                }
                Part::Truck {
                    pressure,
                    from,
                    to,
                    duration,
                    times,
                } => {
                    let shape: f64 = times
                        .iter()
                        .filter(|t0| t >= **t0 && t <= **t0 + duration)
                        .map(|t0| (PI * (t - t0) / duration).sin())
                        .sum();
                    if shape != 0.0 {
                        for (k, q) in line.iter_mut().enumerate() {
                            let (a, b) = (k as f64 * l, (k + 1) as f64 * l);
                            let (lo, hi) = (a.max(*from), b.min(*to));
                            if hi > lo {
                                let d = self.taper.diameter(0.5 * (lo + hi));
                                *q += pressure * d * shape * (hi - lo) / l;
                            }
                        }
                    }
                }
                Part::Table(rows) => {
                    let (p, w) = interpolate(rows, t);
                    tip += p;
                    line.iter_mut().for_each(|q| *q += w);
                }
            }
        }
        (tip, line)
    }
}

impl LoadModel {
    /// The root-moment-equivalent tip force at time `t` \[N\]: the tip force plus the line
    /// loads' moment about the root over the arm's length (on `n` elements).
    pub fn tip_equivalent(&self, t: f64, n: usize) -> f64 {
        let (tip, line) = self.sample(t, n);
        let l = self.taper.length / n as f64;
        let moment: f64 = line
            .iter()
            .enumerate()
            .map(|(k, w)| w * l * (k as f64 + 0.5) * l)
            .sum();
        tip + moment / self.taper.length
    }

    /// RMS of the tip-equivalent force's change per step `h` over `duration` \[N\]: how fast
    /// the site's design loads move, the scale of a monitor's load model.
    pub fn increment_rms(&self, h: f64, duration: f64) -> f64 {
        let steps = (duration / h).round().max(1.0) as usize;
        let mut last = self.tip_equivalent(0.0, 16);
        let mut sum = 0.0;
        for k in 1..=steps {
            let x = self.tip_equivalent(k as f64 * h, 16);
            sum += (x - last) * (x - last);
            last = x;
        }
        (sum / steps as f64).sqrt()
    }
}

fn parse_table(text: &str) -> Result<Vec<[f64; 3]>> {
    let mut rows: Vec<[f64; 3]> = Vec::new();
    let mut source = csvio::Rows::new(text.as_bytes(), b',');
    while let Some(row) = source.next_row()? {
        let v = match row.numbers() {
            Some(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => v,
            _ if rows.is_empty() => continue, // a header
            _ if row.cells().len() != 3 => bail!(
                "line {}: need three numbers `t, tip_force, line_load`, found {} cells",
                row.line(),
                row.cells().len()
            ),
            // One of the three is not a finite number: the error names it.
            _ => ["t", "tip_force", "line_load"]
                .iter()
                .enumerate()
                .map(|(i, name)| row.number(i, name))
                .collect::<Result<Vec<f64>>>()?,
        };
        if let Some(last) = rows.last() {
            if v[0] <= last[0] {
                bail!("line {}: time must increase", row.line());
            }
        }
        rows.push([v[0], v[1], v[2]]);
    }
    if rows.is_empty() {
        bail!("no data rows (`t, tip_force, line_load`)");
    }
    Ok(rows)
}

fn interpolate(rows: &[[f64; 3]], t: f64) -> (f64, f64) {
    let i = rows.partition_point(|r| r[0] <= t);
    match (i.checked_sub(1).and_then(|j| rows.get(j)), rows.get(i)) {
        (Some(a), Some(b)) => {
            let s = (t - a[0]) / (b[0] - a[0]);
            (a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]))
        }
        (Some(a), None) => (a[1], a[2]),
        (None, Some(b)) => (b[1], b[2]),
        (None, None) => (0.0, 0.0),
    }
}

#[cfg(test)]
mod tests;
