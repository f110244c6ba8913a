//! `paper` and `run`: one scene in time, streamed (fixed memory whatever the duration).

use super::{describe, load};
use crate::cli::{PaperArgs, RunArgs};
use absorber_sim::ensemble::Ensemble;
use absorber_sim::figures::{run_plots, PlotData};
use absorber_sim::output::{command_line, with_output, OutputDir, Status};
use absorber_sim::run::{scene_excitation, CSV_HEADER};
use absorber_sim::scene::{Kind, Scene};
use absorber_sim::simulate::time::{
    ensemble_summary, other_members, plan, steady_start, stream, stream_with,
};
use absorber_sim::simulate::{pool, progress_bar};
use anyhow::Result;
use serde_json::{json, Value};
use std::time::Instant;

/// The number under `k` (a [`absorber_sim::ensemble::Spread`]'s mean in an ensemble's summary).
fn num(v: &Value, k: &str) -> f64 {
    v.get(k).map_or(f64::NAN, absorber_sim::ensemble::value)
}

/// The statistic under `k` scaled by `scale` with `prec` decimals (`mean ± sd (min–max)` in
/// an ensemble's summary).
fn stat(v: &Value, k: &str, scale: f64, prec: usize) -> String {
    absorber_sim::ensemble::text(v.get(k).unwrap_or(&Value::Null), scale, prec)
}

/// The count under `k` (`mean ± sd (min–max)` in an ensemble's summary).
fn count(v: &Value, k: &str) -> String {
    absorber_sim::ensemble::count_text(v.get(k).unwrap_or(&Value::Null))
}

/// A friction ratio: plain below 1000 (`4.73`), else in exponent form (`1.162e4`, where a
/// near-zero normal force makes it large).
fn ratio(x: f64) -> String {
    if x.abs() < 1e3 {
        format!("{x:.2}")
    } else {
        format!("{x:.3e}")
    }
}

/// The stop impacts of the steady window (what `sweep`'s impacts column counts): their number
/// from the steady rate of a single run, the rate's statistics in an ensemble's summary.
fn steady_impacts(s: &Value) -> String {
    let from = num(s, "steady_from");
    match s.get("impact_rate_steady").and_then(Value::as_f64) {
        Some(rate) => format!("{:.0} for t ≥ {from} s", rate * (num(s, "duration") - from)),
        None => format!(
            "{}/s for t ≥ {from} s",
            stat(s, "impact_rate_steady", 1.0, 2)
        ),
    }
}

/// The summary lines of `paper` and `run` (an ensemble's statistics as `mean ± sd (min–max)`).
pub fn summary_lines(s: &Value) -> Vec<String> {
    let w = num(s, "energy_window");
    let mut lines = vec![
        format!(
            "static tip deflection      {} mm",
            stat(s, "static_tip_deflection", 1e3, 3)
        ),
        format!(
            "tip amplitude              max {} mm; steady (t ≥ {} s, half peak-to-peak) {} mm",
            stat(s, "tip_amplitude_max", 1e3, 3),
            num(s, "steady_from"),
            stat(s, "tip_amplitude_steady", 1e3, 3)
        ),
        match s.get("ball").and_then(Value::as_str) {
            Some("locked") => "ball                       locked in the housing: it turns with the tip mass (no angle, stop impacts or flight of its own)".to_string(),
            Some("none") => "ball                       none in this scene".to_string(),
            _ => format!(
                "ball angle θ               max {}°; steady {}°; {} stop impacts in the run, {}",
                stat(s, "ball_angle_max_deg", 1.0, 1),
                stat(s, "ball_angle_steady_deg", 1.0, 1),
                count(s, "impacts"),
                steady_impacts(s)
            ),
        },
        format!(
            "mean energy [mJ]           beam {} (first {w:.1} s) → {} (last {w:.1} s); ball {} → {}",
            stat(s, "beam_energy_first", 1e3, 3),
            stat(s, "beam_energy_last", 1e3, 3),
            stat(s, "ball_energy_first", 1e3, 3),
            stat(s, "ball_energy_last", 1e3, 3)
        ),
    ];
    if let Some(c) = s.get("contact").filter(|c| c.is_object()) {
        let separations = num(c, "separations");
        if separations > 0.0 {
            lines.push(format!(
                "ball in flight             {} % of the time ({} % for t ≥ {} s): {} separations, {} landings ({} bounces; counts of short hops depend on h: docs/chaos.md)",
                stat(c, "flight_fraction", 100.0, 1),
                stat(c, "flight_fraction_steady", 100.0, 1),
                num(s, "steady_from"),
                count(c, "separations"),
                count(c, "landings"),
                count(c, "bounces"),
            ));
            let rolling = match (
                c.get("landings").and_then(Value::as_u64),
                c.get("bounces").and_then(Value::as_u64),
            ) {
                (Some(l), Some(b)) => (l - b.min(l)).to_string(),
                _ => format!("{:.1}", num(c, "landings") - num(c, "bounces")),
            };
            lines.push(format!(
                "landing on the track       {} of {rolling} rolling landings need more friction than μ = {} (peak |P_t|/P_n {})",
                count(c, "landings_slipping"),
                num(c, "friction"),
                stat(c, "landing_friction_max", 1.0, 2),
            ));
        }
        if separations == 0.0 || separations.is_nan() {
            lines.push(format!(
            "track contact              N < 0 (the track pulls: a real ball would leave it) {} % of the time ({} % for t ≥ {} s), min N = {} m_b g",
            stat(c, "track_pulls_fraction", 100.0, 1),
            stat(c, "track_pulls_fraction_steady", 100.0, 1),
            num(s, "steady_from"),
            stat(c, "normal_force_min_over_weight", 1.0, 2),
        ));
        }
        let peak = match absorber_sim::ensemble::spread_of(
            c.get("required_friction_max").unwrap_or(&Value::Null),
        ) {
            Some(p) => format!("{} ({}–{})", ratio(p.mean), ratio(p.min), ratio(p.max)),
            None => ratio(num(c, "required_friction_max")),
        };
        lines.push(format!(
            "rolling without slip       needs more friction than μ = {} {} % of the time ({} % for t ≥ {} s; peak |F_t|/N {peak})",
            num(c, "friction"),
            stat(c, "slip_fraction", 100.0, 1),
            stat(c, "slip_fraction_steady", 100.0, 1),
            num(s, "steady_from"),
        ));
    }
    lines
}

pub fn paper(a: &PaperArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let from = steady_start(None, &s)?;
    let sim = absorber_sim::run::build_simulator(&s, 0.0)?;
    let freqs = sim
        .natural_frequencies()
        .map_err(|e| absorber_sim::scene::map_core_error(e, &s))?;
    let exc = scene_excitation(&s)?;
    let free = stream(&s, &exc, from, "free ball", |_| Ok(()))?;
    let mut locked = None;
    if s.file.kind.free_ball() {
        let mut l = s.clone();
        l.file.kind = Kind::Locked;
        locked = Some(stream(&l, &exc, from, "locked ball", |_| Ok(()))?);
    }
    // Beside the paper's integrator (its damping depends on h), the physics scene: the same
    // absorber with a steel arm's damping and an integrator whose damping does not.
    let physics = if step_damping_line(&s).is_some() && s.file.kind.free_ball() {
        let p = Scene::physics()?;
        let exc = scene_excitation(&p)?;
        let from = steady_start(None, &p)?;
        Some((
            p.clone(),
            stream(&p, &exc, from, "physics scene", |_| Ok(()))?,
        ))
    } else {
        None
    };
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "frequencies": freqs.iter().take(3).collect::<Vec<_>>(), "run": free, "locked": locked, "physics": physics.as_ref().map(|p| &p.1), "wall_time": wall })
        );
        return Ok(());
    }
    for line in paper_lines(&s, &freqs, &free, locked.as_ref()) {
        println!("{line}");
    }
    if let Some((p, summary)) = &physics {
        println!("{}", physics_line(p, summary));
    }
    eprintln!("wall time                  {wall:.2} s");
    Ok(())
}

/// What `paper` prints on stdout (the README shows it; a test keeps them equal).
pub fn paper_lines(s: &Scene, freqs: &[f64], free: &Value, locked: Option<&Value>) -> Vec<String> {
    let mut out = vec![describe(s)];
    if let Some(line) = step_damping_line(s) {
        out.push(line);
    }
    let f: Vec<String> = freqs.iter().take(3).map(|x| format!("{x:.3}")).collect();
    out.push(format!("lowest frequencies         {} Hz", f.join(", ")));
    out.extend(summary_lines(free));
    if let Some(l) = locked {
        out.push(format!(
            "locked ball (passive)      tip amplitude max {:.3} mm, steady {:.3} mm",
            1e3 * num(l, "tip_amplitude_max"),
            1e3 * num(l, "tip_amplitude_steady")
        ));
    }
    out
}

/// The physics scene's summary in one line, printed by `paper` beside a scene whose
/// integrator's damping depends on h: what the same absorber does with a steel arm's damping
/// and generalized-α (docs/chaos.md measures how these figures converge).
pub fn physics_line(p: &Scene, summary: &Value) -> String {
    let f = &p.file;
    let c = summary.get("contact").unwrap_or(&Value::Null);
    format!(
        "physics scene              `--scene physics` ({} % structural damping, generalized-α, {} calibrated elements {}, h = {} s, {} s at {} Hz): steady tip amplitude {} mm, tip RMS {} mm, {} stop impacts/s, ball in flight {} % (t ≥ {} s)",
        100.0 * f.damping.ratio.unwrap_or(0.0),
        f.elements,
        match f.precision {
            absorber_sim::scene::Precision::F32 => "f32",
            absorber_sim::scene::Precision::F64 => "f64",
        },
        f.integrator.step,
        f.duration,
        f.excitation.frequency_or_paper(),
        stat(summary, "tip_amplitude_steady", 1e3, 3),
        stat(summary, "tip_rms_steady", 1e3, 3),
        stat(summary, "impact_rate_steady", 1.0, 2),
        stat(c, "flight_fraction_steady", 100.0, 1),
        num(summary, "steady_from"),
    )
}

/// For Newmark with γ > ½ (the paper's integrator): one line saying that its damping is
/// numerical and depends on h. For small ωh the scheme damps a mode of angular frequency ω by
/// ξ ≈ (γ − ½) ω h / 2 of critical (Hughes, *The Finite Element Method*, §9.3); it is given at
/// the excitation frequency, where the response is.
pub fn step_damping_line(s: &Scene) -> Option<String> {
    let i = &s.file.integrator;
    if i.rho_inf.is_some() || i.gamma <= 0.5 {
        return None;
    }
    let f = s.file.excitation.frequency_or_paper();
    let xi = (i.gamma - 0.5) * std::f64::consts::TAU * f * i.step / 2.0;
    Some(format!(
        "integrator damping         numerical, depends on h: Newmark γ = {} damps {:.2} % of critical at {f} Hz with h = {} s (∝ h; `--scene physics`: generalized-α and a steel arm's damping)",
        i.gamma,
        100.0 * xi,
        i.step
    ))
}

pub fn run(a: &RunArgs) -> Result<()> {
    let t0 = Instant::now();
    let s = load(&a.scene)?;
    let f = &s.file;
    let ens = a.ensemble.ensemble()?;
    absorber_sim::ensemble::check_scene(&s, ens)?;
    let (exc, from, every) = plan(&s, a.transient, a.every)?;
    let workers = pool(None, ens.k)?;
    let plots = if a.no_plots {
        Vec::new()
    } else {
        a.plots.clone().unwrap_or_else(|| f.outputs.plots.clone())
    };
    let dir = a.out.clone().unwrap_or_else(|| f.outputs.directory.clone());
    let stem = f.name.replace(['/', '\\', ' '], "_");
    let stem = if stem.is_empty() || stem.starts_with('.') {
        format!("run{stem}")
    } else {
        stem
    };
    let out = OutputDir::open(&dir, Some(&stem), &command_line())?;
    let title = describe(&s);
    let ((sum, csv, pngs), _files) = with_output(out, |out| {
        let mut csv = out.stream(&format!("{stem}.csv"))?;
        csv.line(CSV_HEADER)?;
        let mut data = (!plots.is_empty()).then(|| PlotData::new(from));
        let mut k = 0u64;
        let what = if ens.is_ensemble() {
            format!("run (ensemble of {})", ens.k)
        } else {
            "run".to_string()
        };
        let pb = progress_bar((ens.k * s.steps()) as u64, &what);
        // Member 0 (the scene itself) writes the CSV and the plots; the others, in parallel
        // beside it, give their summaries.
        let (first, others) = workers.install(|| {
            rayon::join(
                || {
                    stream_with(&s, &exc, from, &pb, |r| {
                        if let Some(d) = data.as_mut() {
                            d.push(r);
                        }
                        let write = k.is_multiple_of(every as u64);
                        k += 1;
                        if write {
                            csv.line(&r.csv())
                        } else {
                            Ok(())
                        }
                    })
                },
                || other_members(&s, &exc, from, ens, &pb),
            )
        });
        pb.finish_and_clear();
        let sum = ensemble_summary(first?, others?);
        let csv = out.finish(csv)?;
        let pngs = match &data {
            Some(d) => run_plots(out, &stem, &title, d, &plots)?,
            None => Vec::new(),
        };
        Ok(((sum.clone(), csv, pngs), Status::Complete, sum))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    if a.json {
        let mut out = json!({ "scene": f.name, "csv": csv, "plots": pngs, "summary": sum, "wall_time": wall });
        if ens.is_ensemble() {
            out["ensemble"] = ens.json();
        }
        println!("{out}");
    } else {
        println!("{title}");
        if ens.is_ensemble() {
            println!("{}", ensemble_line(ens));
        }
        for line in summary_lines(&sum) {
            println!("{line}");
        }
        if ens.is_ensemble() {
            println!("(CSV and plots: member 0, the scene itself)");
        }
        println!("wrote {}", csv.display());
        for p in &pngs {
            println!("wrote {}", p.display());
        }
        println!(
            "wrote {}",
            dir.join(format!("{stem}.manifest.json")).display()
        );
        println!("wall time {wall:.2} s");
    }
    Ok(())
}

/// The line that introduces an ensemble's statistics.
pub fn ensemble_line(e: Ensemble) -> String {
    format!(
        "ensemble of {} runs (seed {}; initial ball angle ± {}°, rate ± {} rad/s): mean ± sd (min–max)",
        e.k,
        e.seed,
        absorber_sim::ensemble::ANGLE_SPREAD_DEG,
        absorber_sim::ensemble::RATE_SPREAD
    )
}
