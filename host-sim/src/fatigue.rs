//! `host-sim fatigue`: fatigue damage rate at the clamp vs base frequency (and amplitude), with
//! the free ball and with the ball locked (the paper's passive case), from the core's on-device
//! monitor (`absorber_core::monitor`): root stress → streaming rainflow → Miner's rule on an
//! AASHTO S–N curve. One run per (frequency, amplitude, scene), in parallel (rayon).
//!
//! Damage rate = Miner damage of the whole run (start-up transient included, residue counted as
//! half cycles) per hour of simulated time. Runs that fail keep what they computed and say why.

use crate::cli::SceneArgs;
use crate::excitation::Excitation;
use crate::plot::{render, Panel, Series};
use crate::sweep::PAPER_FREQUENCIES;
use absorber_core::monitor::{
    DetailCategory, MomentEstimate, Monitor, MonitorConfig, NoTwin, ThresholdRule,
};
use absorber_core::{FreeBall, LockedBall, Model, Params, Scene as CoreScene};
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;

/// AASHTO detail category (command-line spelling).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Category {
    /// A
    A,
    /// B
    B,
    /// B′
    #[value(name = "b-prime")]
    BPrime,
    /// C
    C,
    /// C′
    #[value(name = "c-prime")]
    CPrime,
    /// D
    D,
    /// E
    E,
    /// E′ (fillet-welded mast-arm socket; default)
    #[value(name = "e-prime")]
    EPrime,
}

impl Category {
    fn detail(self) -> DetailCategory {
        match self {
            Self::A => DetailCategory::A,
            Self::B => DetailCategory::B,
            Self::BPrime => DetailCategory::BPrime,
            Self::C => DetailCategory::C,
            Self::CPrime => DetailCategory::CPrime,
            Self::D => DetailCategory::D,
            Self::E => DetailCategory::E,
            Self::EPrime => DetailCategory::EPrime,
        }
    }
}

/// Root-moment estimate (command-line spelling).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Moment {
    /// Clamp reaction on the root slope coordinate (exact statics; default).
    Reaction,
    /// E I r″ at the root node (5.8 % low in statics with 3 elements).
    Curvature,
}

/// `fatigue`.
#[derive(Args, Debug)]
pub struct FatigueArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Excitation frequencies [Hz] (default: the paper's 14, 3.50 … 4.70).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    freqs: Option<Vec<f64>>,
    /// Base amplitudes [m] (default: the scene's, paper 0.5e-3).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    amplitudes: Option<Vec<f64>>,
    /// AASHTO detail category of the root connection.
    #[arg(long, value_enum, default_value_t = Category::EPrime)]
    category: Category,
    /// Root-moment estimate.
    #[arg(long, value_enum, default_value_t = Moment::Reaction)]
    moment: Moment,
    /// Worker threads (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output directory for fatigue.csv and fatigue.png (default: the scene's `outputs.directory`).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Skip the PNG.
    #[arg(long)]
    no_plots: bool,
}

/// One run's fatigue figures.
#[derive(Clone, Debug, Serialize)]
pub struct RunFatigue {
    /// Miner damage per hour [1/h].
    pub damage_rate: f64,
    /// Equivalent stress range S_eq [Pa].
    pub equivalent_range: f64,
    /// Largest rainflow range [Pa].
    pub max_range: f64,
    /// Cycles counted.
    pub cycles: f64,
    /// Static root stress [Pa].
    pub static_stress: f64,
    /// RMS tip deflection about static over the last window [m].
    pub tip_rms: f64,
    /// Stop impacts.
    pub impacts: u32,
    /// Residue overflows (0 = exact counting).
    pub overflows: u32,
    /// Simulated time [s].
    pub time: f64,
    /// Why the run stopped early.
    pub error: Option<String>,
}

/// Free and locked at one excitation.
#[derive(Clone, Debug, Serialize)]
pub struct FatiguePoint {
    /// Frequency [Hz].
    pub frequency: f64,
    /// Base amplitude [m].
    pub amplitude: f64,
    /// Free ball.
    pub free: RunFatigue,
    /// Locked ball.
    pub locked: RunFatigue,
}

fn run_one<S: CoreScene, const N: usize, const D: usize>(
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: usize,
) -> RunFatigue {
    let fail = |e: String| RunFatigue {
        damage_rate: f64::NAN,
        equivalent_range: f64::NAN,
        max_range: f64::NAN,
        cycles: 0.0,
        static_stress: f64::NAN,
        tip_rms: f64::NAN,
        impacts: 0,
        overflows: 0,
        time: 0.0,
        error: Some(e),
    };
    let mut model = match Model::<f64, S, N, D>::at_rest(*params, exc.at(0).accel) {
        Ok(m) => m,
        Err(e) => return fail(e.to_string()),
    };
    let mut mon: Monitor<f64, NoTwin> = match Monitor::new(config, &model) {
        Ok(m) => m,
        Err(e) => return fail(e.to_string()),
    };
    let mut error = None;
    for k in 1..=steps {
        let a = exc.at(k).accel;
        let r = model.step(a).and_then(|r| mon.record(&model, &r, a));
        if let Err(e) = r {
            error = Some(format!("t = {:.3} s: {e}", model.time()));
            break;
        }
    }
    let f = mon.fatigue();
    RunFatigue {
        damage_rate: mon.damage_rate_per_hour(),
        equivalent_range: f.equivalent_range,
        max_range: f.max_range,
        cycles: f.cycles,
        static_stress: mon.static_root_stress(),
        tip_rms: mon.indicators().tip_rms,
        impacts: mon.impacts().total(),
        overflows: mon.rainflow().overflows(),
        time: mon.elapsed(),
        error,
    }
}

fn run_pair(
    elements: usize,
    params: &Params<f64>,
    config: MonitorConfig<f64>,
    exc: &Excitation,
    steps: usize,
) -> Result<(RunFatigue, RunFatigue)> {
    Ok(match elements {
        3 => (
            run_one::<FreeBall, 3, 13>(params, config, exc, steps),
            run_one::<LockedBall, 3, 12>(params, config, exc, steps),
        ),
        8 => (
            run_one::<FreeBall, 8, 33>(params, config, exc, steps),
            run_one::<LockedBall, 8, 32>(params, config, exc, steps),
        ),
        n => bail!("fatigue supports 3 or 8 elements (got {n})"),
    })
}

/// Computes the fatigue points (free and locked) for every frequency × amplitude.
pub fn fatigue_points(
    params: &Params<f64>,
    elements: usize,
    config: MonitorConfig<f64>,
    frequencies: &[f64],
    amplitudes: &[f64],
    duration: f64,
) -> Result<Vec<FatiguePoint>> {
    for &x in frequencies.iter().chain(amplitudes) {
        if !x.is_finite() || x <= 0.0 {
            bail!("invalid frequency or amplitude {x} (must be finite and positive)");
        }
    }
    let h = params.integrator.step;
    let steps = (duration / h).round() as usize;
    let jobs: Vec<(f64, f64)> = amplitudes
        .iter()
        .flat_map(|&a| frequencies.iter().map(move |&f| (f, a)))
        .collect();
    jobs.par_iter()
        .map(|&(f, a)| {
            let exc = Excitation::harmonic(a, f, h);
            let (free, locked) = run_pair(elements, params, config, &exc, steps)?;
            Ok(FatiguePoint {
                frequency: f,
                amplitude: a,
                free,
                locked,
            })
        })
        .collect()
}

/// CSV of the points.
pub fn csv(points: &[FatiguePoint], category: &str, moment: &str) -> String {
    let mut s = format!(
        "# host-sim fatigue: root-stress damage rate, AASHTO category {category} (m = 3, CAFT cutoff), moment estimate {moment}\n\
         # damage_rate [1/h] = Miner damage of the run (residue as half cycles) per hour; s_eq, max_range, static_stress [MPa]; tip_rms [mm] over the last window\n\
         frequency,amplitude,free_damage_rate,locked_damage_rate,free_s_eq,locked_s_eq,free_max_range,locked_max_range,static_stress,free_tip_rms,locked_tip_rms,free_impacts,free_overflows,locked_overflows,error\n"
    );
    for p in points {
        let err = [&p.free.error, &p.locked.error]
            .iter()
            .filter_map(|e| e.as_deref())
            .collect::<Vec<_>>()
            .join("; ")
            .replace(',', ";");
        s.push_str(&format!(
            "{},{},{:.6e},{:.6e},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{}\n",
            p.frequency,
            p.amplitude,
            p.free.damage_rate,
            p.locked.damage_rate,
            p.free.equivalent_range / 1e6,
            p.locked.equivalent_range / 1e6,
            p.free.max_range / 1e6,
            p.locked.max_range / 1e6,
            p.free.static_stress / 1e6,
            p.free.tip_rms * 1e3,
            p.locked.tip_rms * 1e3,
            p.free.impacts,
            p.free.overflows,
            p.locked.overflows,
            err
        ));
    }
    s
}

/// Runs the command.
pub fn run(a: &FatigueArgs) -> Result<()> {
    let mut s = a.scene.load()?;
    if a.scene.duration.is_none() && a.scene.scene == "paper" {
        s.file.duration = 60.0;
    }
    let params = s.params()?;
    let freqs = a
        .freqs
        .clone()
        .unwrap_or_else(|| PAPER_FREQUENCIES.to_vec());
    let amps = a
        .amplitudes
        .clone()
        .unwrap_or_else(|| vec![s.file.excitation.amplitude_or_paper()]);
    let detail = a.category.detail();
    let config = MonitorConfig {
        moment: match a.moment {
            Moment::Reaction => MomentEstimate::Reaction,
            Moment::Curvature => MomentEstimate::Curvature,
        },
        curve: detail.curve(ThresholdRule::Cutoff),
        ..MonitorConfig::paper(&params)?
    };
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create output directory `{}`", dir.display()))?;
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(64 << 20);
    if let Some(j) = a.jobs {
        pool = pool.num_threads(j.max(1));
    }
    let pool = pool.build()?;
    let t0 = std::time::Instant::now();
    let points = pool.install(|| {
        fatigue_points(
            &params,
            s.file.elements,
            config,
            &freqs,
            &amps,
            s.file.duration,
        )
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let moment = format!("{:?}", a.moment).to_lowercase();
    let csv_path = dir.join("fatigue.csv");
    std::fs::write(&csv_path, csv(&points, detail.name(), &moment))
        .with_context(|| format!("cannot write `{}`", csv_path.display()))?;
    println!(
        "fatigue at the clamp: category {} (m = 3, CAFT cutoff), {} elements, {} s runs, moment from the {moment}",
        detail.name(),
        s.file.elements,
        s.file.duration
    );
    println!("  f [Hz]  A [mm]   D/h free     D/h locked   S_eq free/locked [MPa]   impacts");
    for p in &points {
        println!(
            "  {:6.3}  {:6.3}   {:10.3e}   {:10.3e}   {:8.2} / {:8.2}       {:5}{}",
            p.frequency,
            p.amplitude * 1e3,
            p.free.damage_rate,
            p.locked.damage_rate,
            p.free.equivalent_range / 1e6,
            p.locked.equivalent_range / 1e6,
            p.free.impacts,
            [&p.free.error, &p.locked.error]
                .iter()
                .filter_map(|e| e.as_deref())
                .map(|e| format!("   FAILED: {e}"))
                .collect::<String>()
        );
    }
    println!("wrote {}", csv_path.display());
    if !a.no_plots {
        let png = dir.join("fatigue.png");
        let log = |x: f64| if x > 0.0 { x.log10() } else { f64::NAN };
        let mut damage = Vec::new();
        let mut seq = Vec::new();
        for &amp in &amps {
            let pts: Vec<&FatiguePoint> = points.iter().filter(|p| p.amplitude == amp).collect();
            let tag = if amps.len() > 1 {
                format!(" {:.2} mm", amp * 1e3)
            } else {
                String::new()
            };
            damage.push(Series::marked(
                &format!("free ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, log(p.free.damage_rate)))
                    .collect(),
            ));
            damage.push(Series::marked(
                &format!("locked ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, log(p.locked.damage_rate)))
                    .collect(),
            ));
            seq.push(Series::marked(
                &format!("free ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, p.free.equivalent_range / 1e6))
                    .collect(),
            ));
            seq.push(Series::marked(
                &format!("locked ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, p.locked.equivalent_range / 1e6))
                    .collect(),
            ));
        }
        render(
            &png,
            &format!(
                "Root fatigue, AASHTO {} ({} s runs, {} elements, base ±{:.2} mm)",
                detail.name(),
                s.file.duration,
                s.file.elements,
                amps.first().copied().unwrap_or(0.0) * 1e3
            ),
            &[
                Panel::new(
                    "Miner damage rate (CAFT cutoff)",
                    "excitation frequency [Hz]",
                    "log10(damage per hour)",
                    damage,
                ),
                Panel::new(
                    "Equivalent stress range S_eq = (Σ n S³ / Σ n)^(1/3)",
                    "excitation frequency [Hz]",
                    "S_eq [MPa]",
                    seq,
                ),
            ],
            2,
            1,
            (1000, 900),
        )?;
        println!("wrote {}", png.display());
    }
    println!("wall time {wall:.2} s ({} runs)", 2 * points.len());
    Ok(())
}
