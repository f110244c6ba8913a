//! One wind record of a fleet study: a real arm (`[arm]`) under its `[[loads]]` (wind
//! turbulence, vortex shedding, truck gusts; [`crate::wind`]), stepped by the core, with the
//! root stress counted by the core's rainflow and Miner's rule ([`StressDamage`]). Plain data
//! in, plain data out, so that a study can farm records out to any number of processes and
//! add their results up exactly ([`RecordResult::histogram`]: integer counts on fixed bins).
//!
//! **The absorber.** [`Absorber::None`] is the scene's arm (`kind = "beam"`, the signal heads
//! as point masses). [`Absorber::Free`] adds at the arm's end the scene's `[tip]` (the housing)
//! and `[ball]` (a free ball with stops in its track): the core's `Arm<FreeBall>`;
//! [`Absorber::Locked`] the same masses with the ball locked (`Arm<LockedBall>`), the
//! comparison that separates the absorber's effect from its mass.
//!
//! **Damage.** The root stress (clamp reaction moment over the section modulus of the root
//! ring, as `estimate`) of every step goes through rainflow (ASTM E1049) and Miner's rule on
//! the AASHTO S–N curve of `arm.detail`, the open residue counted as half cycles at the end:
//! with the constant-amplitude threshold as a cutoff (`damage`, as the monitor) and with the
//! S–N line continued below it (`damage_extended`). Each cycle's range is also counted in
//! [`RANGE_BINS`] bins of [`RANGE_BIN`] Pa (half cycles as 1, full as 2; the last bin holds
//! everything above), so that the histograms of records add exactly.

use crate::scene::Scene;
use crate::wind::{LoadComponent, LoadModel};
use absorber_core::loads::{ArmParams, Loads};
use absorber_core::monitor::fatigue::StressDamage;
use absorber_core::monitor::rainflow::Cycle;
use absorber_core::monitor::stress::{MomentEstimate, RootSection};
use absorber_core::scalar::{lit, to_f64};
use absorber_core::{Arm, BeamOnly, FreeBall, LockedBall, Model, Params, Real, Scene as CoreScene};
use anyhow::{anyhow, bail, Result};
use rand::Rng as _;
use serde::Serialize;

/// Width of a stress-range bin \[Pa\].
pub const RANGE_BIN: f64 = 0.25e6;
/// Number of stress-range bins (0 … 100 MPa; the last also holds every larger range).
pub const RANGE_BINS: usize = 400;

/// Which absorber the arm carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Absorber {
    /// The bare arm.
    None,
    /// Housing and ball at the arm's end, the ball locked (its mass only).
    Locked,
    /// Housing and free ball at the arm's end (the absorber).
    Free,
}

impl Absorber {
    /// From its name (`none`, `locked`, `free`); the error names `absorber`.
    pub fn from_name(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Self::None),
            "locked" => Ok(Self::Locked),
            "free" => Ok(Self::Free),
            other => bail!("invalid value for `absorber`: {other:?} (allowed: none, locked, free)"),
        }
    }
}

/// What one record gives.
#[derive(Clone, Debug, Serialize)]
pub struct RecordResult {
    /// Simulated time \[s\].
    pub duration: f64,
    /// Steps.
    pub steps: usize,
    /// Miner damage, cycles below the constant-amplitude threshold doing none \[-\].
    pub damage: f64,
    /// Miner damage with the S–N line continued below the threshold \[-\].
    pub damage_extended: f64,
    /// Half cycles per stress-range bin ([`RANGE_BIN`], [`RANGE_BINS`]).
    #[serde(skip)]
    pub histogram: Vec<u64>,
    /// Largest stress range \[Pa\].
    pub max_range: f64,
    /// RMS of the root stress about its mean \[Pa\].
    pub stress_rms: f64,
    /// Largest |tip deflection − static| \[m\].
    pub tip_peak: f64,
    /// Static root stress \[Pa\].
    pub static_stress: f64,
    /// Time \[s\] of the kept samples (every `every`-th step, the start included).
    #[serde(skip)]
    pub time: Vec<f64>,
    /// Root stress \[Pa\] of the kept samples.
    #[serde(skip)]
    pub root_stress: Vec<f64>,
    /// Tip deflection \[m\] of the kept samples.
    #[serde(skip)]
    pub tip_deflection: Vec<f64>,
}

/// The histogram bin of a stress range.
pub fn bin_of(range: f64) -> usize {
    let k = (range / RANGE_BIN).floor();
    if k.is_finite() && k >= 0.0 {
        (k as usize).min(RANGE_BINS - 1)
    } else {
        RANGE_BINS - 1
    }
}

/// The scene's loads with every buffeting seed replaced by one drawn from `seed` (a record's
/// turbulence realization).
fn reseeded(loads: &[LoadComponent], seed: u64) -> Vec<LoadComponent> {
    let mut rng = crate::wind::seeded(seed);
    loads
        .iter()
        .map(|c| {
            let mut c = c.clone();
            if let LoadComponent::Buffeting { seed, .. } = &mut c {
                *seed = rng.next_u64();
            }
            c
        })
        .collect()
}

fn core(e: absorber_core::Error) -> anyhow::Error {
    anyhow!("{e}")
}

/// The parameters, the arm and its root section of a scene with `absorber`; errors name the
/// scene key.
fn setup(scene: &Scene, absorber: Absorber) -> Result<(Params<f64>, ArmParams<f64>)> {
    let f = &scene.file;
    let arm_file = f.arm.as_ref().ok_or_else(|| {
        anyhow!("a fleet record needs a scene with an `[arm]` (e.g. scenes/mast-arm.toml)")
    })?;
    if f.kind != crate::scene::Kind::Beam {
        bail!("invalid value for `kind`: a fleet record's scene is the bare arm (`kind = \"beam\"`); choose the absorber with `absorber`");
    }
    let params = scene.params()?;
    if absorber != Absorber::None {
        params
            .validate(true, true)
            .map_err(|e| crate::scene::map_core_error(e, scene))?;
    }
    Ok((params, arm_file.params()?))
}

/// The reduced arm's lowest natural frequencies \[Hz\] with `absorber` (its ball free or
/// locked), at the static equilibrium.
pub fn frequencies(scene: &Scene, absorber: Absorber) -> Result<Vec<f64>> {
    let (p, arm) = setup(scene, absorber)?;
    macro_rules! freq {
        ($s:ty, $n:literal, $d:expr) => {
            Model::<f64, Arm<$s>, $n, { $d }>::arm_at_rest(p, &arm, 0.0)
                .and_then(|m| m.natural_frequencies().map(|f| f.iter().copied().collect()))
                .map_err(|e| crate::scene::map_core_error(e, scene))
        };
    }
    match (absorber, scene.file.elements) {
        (Absorber::None, 3) => freq!(BeamOnly, 3, 12),
        (Absorber::None, 6) => freq!(BeamOnly, 6, 24),
        (Absorber::Locked, 3) => freq!(LockedBall, 3, 12),
        (Absorber::Locked, 6) => freq!(LockedBall, 6, 24),
        (Absorber::Free, 3) => freq!(FreeBall, 3, 13),
        (Absorber::Free, 6) => freq!(FreeBall, 6, 25),
        (_, n) => bail!("invalid value for `elements`: {n} (a fleet record runs 3 or 6 elements)"),
    }
}

/// Runs one record: `scene`'s arm with `absorber` under its loads, the buffeting reseeded from
/// `seed`, for `duration` seconds; keeps every `every`-th sample.
pub fn record(
    scene: &Scene,
    seed: u64,
    duration: f64,
    absorber: Absorber,
    every: usize,
) -> Result<RecordResult> {
    if !(duration.is_finite() && duration > 0.0) {
        bail!("invalid value for `duration`: {duration} (must be finite and positive)");
    }
    if every == 0 {
        bail!("invalid value for `every`: 0 (must be at least 1)");
    }
    let (params, arm) = setup(scene, absorber)?;
    let f = &scene.file;
    let arm_file = f.arm.as_ref().ok_or_else(|| anyhow!("no `[arm]`"))?;
    let loads = LoadModel::new(
        &reseeded(&f.loads, seed),
        crate::scene::taper_of(arm_file, params.beam.length),
        &scene.base_dir,
    )?;
    let section = crate::estimate::arm::root_section(&params, &arm)?;
    let run = Run {
        params,
        arm,
        section,
        loads,
        steps: (duration / params.integrator.step).round().max(1.0) as usize,
        every,
        category: arm_file.detail_category()?,
    };
    macro_rules! go {
        ($t:ty, $s:ty, $n:literal, $d:expr) => {
            run.go::<$t, $s, $n, { $d }>(scene)
        };
    }
    use crate::scene::Precision::{F32, F64};
    match (f.precision, absorber, f.elements) {
        (F32, Absorber::None, 3) => go!(f32, BeamOnly, 3, 12),
        (F32, Absorber::Locked, 3) => go!(f32, LockedBall, 3, 12),
        (F32, Absorber::Free, 3) => go!(f32, FreeBall, 3, 13),
        (F32, Absorber::None, 6) => go!(f32, BeamOnly, 6, 24),
        (F32, Absorber::Locked, 6) => go!(f32, LockedBall, 6, 24),
        (F32, Absorber::Free, 6) => go!(f32, FreeBall, 6, 25),
        (F64, Absorber::None, 3) => go!(f64, BeamOnly, 3, 12),
        (F64, Absorber::Locked, 3) => go!(f64, LockedBall, 3, 12),
        (F64, Absorber::Free, 3) => go!(f64, FreeBall, 3, 13),
        (F64, Absorber::None, 6) => go!(f64, BeamOnly, 6, 24),
        (F64, Absorber::Locked, 6) => go!(f64, LockedBall, 6, 24),
        (F64, Absorber::Free, 6) => go!(f64, FreeBall, 6, 25),
        (_, _, n) => {
            bail!("invalid value for `elements`: {n} (a fleet record runs 3 or 6 elements)")
        }
    }
}

/// A record ready to run.
struct Run {
    params: Params<f64>,
    arm: ArmParams<f64>,
    section: RootSection<f64>,
    loads: LoadModel,
    steps: usize,
    every: usize,
    category: absorber_core::monitor::DetailCategory,
}

impl Run {
    fn go<T: Real, S: CoreScene, const N: usize, const D: usize>(
        &self,
        scene: &Scene,
    ) -> Result<RecordResult> {
        let p = absorber_fmu::sim::cast_params::<T>(&self.params);
        let mut model = Model::<T, Arm<S>, N, D>::arm_at_rest(
            p,
            &crate::core_sim::cast_arm(&self.arm),
            T::zero(),
        )
        .map_err(|e| crate::scene::map_core_error(e, scene))?;
        let s = &self.section;
        let section = RootSection::<T> {
            bending_rigidity: lit(s.bending_rigidity),
            stress_per_curvature: lit(s.stress_per_curvature),
            extreme_fibre: lit(s.extreme_fibre),
        };
        let stress = |m: &Model<T, Arm<S>, N, D>| {
            to_f64(section.stress_of_moment(section.root_moment(m, MomentEstimate::Reaction)))
        };
        let static_tip = to_f64(model.static_tip_deflection());
        let static_stress = stress(&model);
        let mut damage = StressDamage::<f64, 512>::new(self.category).map_err(core)?;
        let mut histogram = vec![0u64; RANGE_BINS];
        let keep = self.steps / self.every + 1;
        let (mut time, mut root, mut tip) = (
            Vec::with_capacity(keep),
            Vec::with_capacity(keep),
            Vec::with_capacity(keep),
        );
        let h = self.params.integrator.step;
        let mut loads = Loads::<T, N>::zero();
        let (mut sum, mut sum2, mut peak, mut max_range) = (0.0, 0.0, 0.0f64, 0.0f64);
        let count = |c: &Cycle<f64>, histogram: &mut [u64], max_range: &mut f64| {
            if let Some(b) = histogram.get_mut(bin_of(c.range)) {
                *b += c.halves();
            }
            *max_range = max_range.max(c.range);
        };
        for k in 0..=self.steps {
            if k % 500 == 0 {
                crate::interrupt::check()?;
            }
            if k > 0 {
                let t = k as f64 * h;
                let (tip_force, line) = self.loads.sample(t, N);
                loads.tip_force = lit(tip_force);
                for (d, q) in loads.line_load.iter_mut().zip(&line) {
                    *d = lit(*q);
                }
                model.step_with_loads(T::zero(), &loads).map_err(|e| {
                    anyhow!(
                        "step {k} (t = {t:.2} s) failed: {}",
                        crate::scene::physical_failure(e, scene)
                    )
                })?;
            }
            let x = stress(&model);
            let y = to_f64(model.tip_deflection());
            damage
                .push(x, &mut |c: &Cycle<f64>| {
                    count(c, &mut histogram, &mut max_range)
                })
                .map_err(|e| anyhow!("root stress at step {k}: {e}"))?;
            sum += x;
            sum2 += x * x;
            peak = peak.max((y - static_tip).abs());
            if k % self.every == 0 {
                time.push(k as f64 * h);
                root.push(x);
                tip.push(y);
            }
        }
        damage
            .rainflow()
            .residue(&mut |c: Cycle<f64>| count(&c, &mut histogram, &mut max_range));
        let (extended, cutoff) = damage.damage();
        let n = (self.steps + 1) as f64;
        let mean = sum / n;
        Ok(RecordResult {
            duration: self.steps as f64 * h,
            steps: self.steps,
            damage: cutoff,
            damage_extended: extended,
            max_range,
            histogram,
            stress_rms: (sum2 / n - mean * mean).max(0.0).sqrt(),
            tip_peak: peak,
            static_stress,
            time,
            root_stress: root,
            tip_deflection: tip,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mast_arm() -> Scene {
        let mut s = Scene::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/mast-arm.toml"
        ))
        .expect("scene");
        s.file.sensor = None;
        s
    }

    /// A record is reproducible (same seed, same bits; another seed, another turbulence), and
    /// its damage and histogram are those of a separate rainflow pass over its own stress
    /// history (every step kept): nothing is lost between the steps and the counts, and the
    /// residue is in both.
    #[test]
    fn records_are_reproducible_and_count_every_cycle() {
        let s = mast_arm();
        let a = record(&s, 7, 60.0, Absorber::None, 1).expect("record");
        let b = record(&s, 7, 60.0, Absorber::None, 1).expect("record");
        let c = record(&s, 8, 60.0, Absorber::None, 1).expect("record");
        assert_eq!(a.damage_extended.to_bits(), b.damage_extended.to_bits());
        assert_eq!(a.histogram, b.histogram);
        assert_ne!(a.damage_extended.to_bits(), c.damage_extended.to_bits());
        let category = s.file.arm.as_ref().and_then(|x| x.detail_category().ok());
        let mut d = StressDamage::<f64, 512>::new(category.expect("detail")).expect("counter");
        let mut hist = vec![0u64; RANGE_BINS];
        for x in &a.root_stress {
            d.push(*x, &mut |cy: &Cycle<f64>| {
                hist[bin_of(cy.range)] += cy.halves()
            })
            .expect("finite");
        }
        d.rainflow()
            .residue(&mut |cy: Cycle<f64>| hist[bin_of(cy.range)] += cy.halves());
        assert_eq!(a.time.len(), 6001);
        assert_eq!(hist, a.histogram);
        assert_eq!(d.damage().0.to_bits(), a.damage_extended.to_bits());
        assert!(a.stress_rms > 1e5 && a.damage_extended > 0.0, "{a:?}");
    }

    /// Bad input names the field.
    #[test]
    fn bad_input_names_the_field() {
        let s = mast_arm();
        let e = |r: Result<RecordResult>| r.err().map(|e| format!("{e:#}")).unwrap_or_default();
        assert!(e(record(&s, 1, -1.0, Absorber::None, 1)).contains("`duration`"));
        assert!(e(record(&s, 1, 1.0, Absorber::None, 0)).contains("`every`"));
        let mut t = s.clone();
        t.file.elements = 4;
        assert!(e(record(&t, 1, 1.0, Absorber::None, 1)).contains("`elements`"));
        assert!(Absorber::from_name("big")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
            .contains("`absorber`"));
    }
}
