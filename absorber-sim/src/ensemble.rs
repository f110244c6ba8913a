//! Ensembles of a chaotic run: K members from seeded perturbations of the ball's initial state,
//! and every statistic as mean ± standard deviation and min–max over the members.
//!
//! **Members.** Member 0 is the scene itself (so an ensemble of one is the plain run, byte for
//! byte). Member k ≥ 1 starts with the ball's initial angle shifted by `δθ₀` and its initial
//! orbit rate set to `δθ̇₀`, drawn uniformly from `±`[`ANGLE_SPREAD_DEG`] and
//! `±`[`RATE_SPREAD`] by the ChaCha8 generator of `rand` seeded with `seed` on stream `k`: the
//! same seed gives the same members on any machine and thread count. The sizes are far below anything that changes
//! the physics (0.1° against swings of 65°, 0.01 rad/s against rates of 5–10 rad/s) and far
//! above rounding: the members decorrelate within seconds once the ball hits the stops, while
//! the statistics of the motion do not depend on them.
//!
//! **Statistics.** [`aggregate`] turns the members' summaries (JSON objects of the same shape)
//! into one: every number becomes `{"mean", "sd", "min", "max", "k"}` (sample standard
//! deviation, `k` the members that gave a finite value), everything else is member 0's.

use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::{Map, Value};

/// Half width of the uniform perturbation of the initial ball angle \[deg\].
pub const ANGLE_SPREAD_DEG: f64 = 0.1;

/// Half width of the uniform initial ball orbit rate θ̇₀ \[rad/s\].
pub const RATE_SPREAD: f64 = 0.01;

/// The default seed of the members' perturbations.
pub const DEFAULT_SEED: u64 = 1;

/// The perturbation of one member: `(δθ₀ [deg], θ̇₀ [rad/s])`; `(0, 0)` for member 0. Drawn
/// from ChaCha8 (`rand`) seeded with `seed`, on stream `member`: the same pair on any machine,
/// thread count and member order.
pub fn perturbation(seed: u64, member: usize) -> (f64, f64) {
    if member == 0 {
        return (0.0, 0.0);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(member as u64);
    let angle = rng.random_range(-ANGLE_SPREAD_DEG..=ANGLE_SPREAD_DEG);
    let rate = rng.random_range(-RATE_SPREAD..=RATE_SPREAD);
    (angle, rate)
}

/// An ensemble's size and seed (`--ensemble`, `--seed`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ensemble {
    /// Members K (1: the plain run).
    pub k: usize,
    /// Seed of the perturbations.
    pub seed: u64,
}

impl Ensemble {
    /// Checked: at least one member, at most [`MAX_MEMBERS`].
    pub fn new(k: usize, seed: u64) -> anyhow::Result<Self> {
        if k == 0 || k > MAX_MEMBERS {
            anyhow::bail!("invalid value for `--ensemble`: {k} (allowed: 1 to {MAX_MEMBERS})");
        }
        Ok(Self { k, seed })
    }

    /// The plain run (one member, the scene itself).
    pub fn single() -> Self {
        Self {
            k: 1,
            seed: DEFAULT_SEED,
        }
    }

    /// More than one member.
    pub fn is_ensemble(&self) -> bool {
        self.k > 1
    }

    /// The members' perturbations as JSON (`member`, `initial_angle_offset_deg`,
    /// `initial_rate`).
    pub fn json(&self) -> Value {
        let members: Vec<Value> = (0..self.k)
            .map(|m| {
                let (a, r) = perturbation(self.seed, m);
                serde_json::json!({ "member": m, "initial_angle_offset_deg": a, "initial_rate": r })
            })
            .collect();
        serde_json::json!({ "k": self.k, "seed": self.seed, "members": members })
    }

    /// `f(member)` for every member, in parallel (rayon), in member order.
    pub fn map<R: Send>(&self, f: impl Fn(usize) -> R + Sync + Send) -> Vec<R> {
        (0..self.k).into_par_iter().map(f).collect()
    }
}

/// Largest ensemble.
pub const MAX_MEMBERS: usize = 10_000;

/// A scene that an ensemble perturbs: a free ball (the other kinds are not chaotic: their
/// members would all be one run).
pub fn check_scene(scene: &crate::scene::Scene, e: Ensemble) -> anyhow::Result<()> {
    if e.is_ensemble() && !scene.file.kind.free_ball() {
        anyhow::bail!(
            "invalid value for `--ensemble`: {} needs a free ball (the scene's kind is `{}`, whose \
             runs do not depend on the ball's initial state)",
            e.k,
            scene.file.kind.name()
        );
    }
    Ok(())
}

/// The scene of member `member` of an ensemble seeded with `seed` (the scene itself for
/// member 0).
pub fn member_scene(scene: &crate::scene::Scene, seed: u64, member: usize) -> crate::scene::Scene {
    let mut s = scene.clone();
    if member > 0 {
        let (angle, rate) = perturbation(seed, member);
        s.file.ball.initial_angle_deg += angle;
        s.file.ball.initial_rate += rate;
    }
    s
}

/// Mean, sample standard deviation, min and max of a statistic over the `k` members that gave a
/// finite value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one member).
    pub sd: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Members with a finite value.
    pub k: usize,
}

impl Spread {
    /// Of the finite values among `xs` (all NaN when there is none).
    pub fn of(xs: &[f64]) -> Self {
        let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        let k = v.len();
        if k == 0 {
            return Self {
                mean: f64::NAN,
                sd: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
                k,
            };
        }
        let mean = v.iter().sum::<f64>() / k as f64;
        let sd = if k > 1 {
            (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (k - 1) as f64).sqrt()
        } else {
            0.0
        };
        Self {
            mean,
            sd,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            k,
        }
    }

    /// As JSON.
    pub fn json(&self) -> Value {
        serde_json::json!({ "mean": self.mean, "sd": self.sd, "min": self.min, "max": self.max, "k": self.k })
    }

    /// `mean ± sd (min–max)` with `prec` decimals after scaling by `scale`.
    pub fn text(&self, scale: f64, prec: usize) -> String {
        format!(
            "{:.p$} ± {:.p$} ({:.p$}–{:.p$})",
            self.mean * scale,
            self.sd * scale,
            self.min * scale,
            self.max * scale,
            p = prec
        )
    }
}

/// The members' summaries (objects of one shape) as one: numbers become [`Spread`] objects,
/// objects are aggregated key by key, everything else is member 0's, and so are the keys in
/// `keep` (settings every member shares, such as `steady_from`). A member without a key (or
/// with `null`) counts as a missing value. One member gives member 0's summary unchanged.
pub fn aggregate(members: &[Value], keep: &[&str]) -> Value {
    let Some(first) = members.first() else {
        return Value::Null;
    };
    if members.len() == 1 {
        return first.clone();
    }
    match first {
        Value::Object(map) => {
            let mut out = Map::new();
            for (key, v0) in map {
                let column: Vec<Value> = members
                    .iter()
                    .map(|m| m.get(key).cloned().unwrap_or(Value::Null))
                    .collect();
                out.insert(
                    key.clone(),
                    if (v0.is_number() || v0.is_object()) && !keep.contains(&key.as_str()) {
                        aggregate(&column, keep)
                    } else {
                        v0.clone()
                    },
                );
            }
            Value::Object(out)
        }
        Value::Number(_) => {
            let xs: Vec<f64> = members
                .iter()
                .map(|m| m.as_f64().unwrap_or(f64::NAN))
                .collect();
            Spread::of(&xs).json()
        }
        other => other.clone(),
    }
}

/// The number `v` as read from a summary: itself, or the mean of a [`Spread`] object.
pub fn value(v: &Value) -> f64 {
    match v {
        Value::Object(m) => m.get("mean").and_then(Value::as_f64).unwrap_or(f64::NAN),
        other => other.as_f64().unwrap_or(f64::NAN),
    }
}

/// The statistic `v` (a number or a [`Spread`] object) scaled by `scale` as text: `x` with
/// `prec` decimals, or `mean ± sd (min–max)`.
pub fn text(v: &Value, scale: f64, prec: usize) -> String {
    match spread_of(v) {
        Some(s) => s.text(scale, prec),
        None => format!("{:.p$}", value(v) * scale, p = prec),
    }
}

/// A count (an integer, or a [`Spread`] object of counts) as text: `n`, or
/// `mean ± sd (min–max)` with one decimal.
pub fn count_text(v: &Value) -> String {
    match v.as_u64() {
        Some(n) => n.to_string(),
        None => text(v, 1.0, 1),
    }
}

/// The [`Spread`] of a JSON object written by [`Spread::json`].
pub fn spread_of(v: &Value) -> Option<Spread> {
    let m = v.as_object()?;
    let f = |k: &str| m.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN);
    Some(Spread {
        mean: f(m.get("mean").map(|_| "mean")?),
        sd: f("sd"),
        min: f("min"),
        max: f("max"),
        k: m.get("k").and_then(Value::as_u64).unwrap_or(0) as usize,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_a_known_set() {
        let s = Spread::of(&[1.0, 2.0, 3.0, 4.0, f64::NAN]);
        assert_eq!((s.mean, s.min, s.max, s.k), (2.5, 1.0, 4.0, 4));
        assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn perturbations_are_seeded_bounded_and_zero_for_member_zero() {
        assert_eq!(perturbation(7, 0), (0.0, 0.0));
        assert_eq!(perturbation(7, 3), perturbation(7, 3));
        assert_ne!(perturbation(7, 3), perturbation(8, 3));
        for k in 1..1000 {
            let (a, r) = perturbation(DEFAULT_SEED, k);
            assert!(a.abs() <= ANGLE_SPREAD_DEG && r.abs() <= RATE_SPREAD);
        }
    }

    #[test]
    fn aggregate_keeps_one_member_and_spreads_numbers() {
        let a = serde_json::json!({"x": 1.0, "name": "a", "c": {"y": 2}});
        let b = serde_json::json!({"x": 3.0, "name": "b", "c": {"y": 4}});
        assert_eq!(aggregate(std::slice::from_ref(&a), &[]), a);
        let g = aggregate(&[a.clone(), b.clone()], &[]);
        assert_eq!(g["name"], "a");
        assert_eq!(g["x"]["mean"], 2.0);
        assert_eq!(g["c"]["y"]["max"], 4.0);
        assert_eq!(g["x"]["k"], 2);
        assert_eq!(value(&g["x"]), 2.0);
        assert_eq!(aggregate(&[a, b], &["x"])["x"], 1.0);
    }
}
