//! `fatigue`: damage rate at the clamp vs frequency, free vs locked ball.

use super::load;
use crate::cli::{FatigueArgs, Moment};
use absorber_core::monitor::{MomentEstimate, MonitorConfig, ThresholdRule};
use absorber_sim::ensemble::Ensemble;
use absorber_sim::fatigue::{
    comparison_csv, csv, csv_members, fatigue_members, fatigue_points, ratio, Comparison,
    FatiguePoint,
};
use absorber_sim::output::{command_line, with_output, OutputDir, PointsFailed, Status};
use absorber_sim::plot::{render, Panel, Series};
use absorber_sim::simulate::{check_excitations, pool};
use absorber_sim::sweep::PAPER_FREQUENCIES;
use anyhow::Result;
use serde_json::{json, Value};

/// Palette index of the free ball and of the locked ball (the same on both panels).
const FREE: usize = 0;
const LOCKED: usize = 1;

pub fn run(a: &FatigueArgs) -> Result<()> {
    let mut s = load(&a.scene)?;
    if a.scene.duration.is_none() && a.scene.model.scene == "paper" {
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
    check_excitations(
        &freqs,
        &amps,
        s.file.integrator.step,
        "--freqs",
        "--amplitudes",
    )?;
    if amps.iter().any(|&x| x <= 0.0) {
        anyhow::bail!("invalid value for `--amplitudes`: must be positive");
    }
    if ![3, 8, 16].contains(&s.file.elements) {
        anyhow::bail!(
            "invalid value for `elements`: {} (fatigue supports 3, 8 or 16)",
            s.file.elements
        );
    }
    if let Some(m) = a.calibrate_against {
        if ![3, 8, 16].contains(&m) {
            anyhow::bail!(
                "invalid value for `--calibrate-against`: {m} (fatigue supports 3, 8 or 16 elements)"
            );
        }
    }
    let steady_from = absorber_sim::simulate::time::steady_start(None, &s)?;
    let window = format!("steady: t ≥ {steady_from} s to the end");
    let ens = a.ensemble.ensemble()?;
    if ens.is_ensemble() && a.calibrate_against.is_some() {
        anyhow::bail!(
            "`--calibrate-against` runs one member only: use it without `--ensemble` (or with \
             --ensemble 1)"
        );
    }
    let detail = a.category.detail();
    let config = MonitorConfig {
        moment: match a.moment {
            Moment::Reaction => MomentEstimate::Reaction,
            Moment::Curvature => MomentEstimate::Curvature,
        },
        curve: detail.curve(ThresholdRule::Cutoff),
        ..MonitorConfig::paper(&params)?
    };
    let pool = pool(a.jobs, 2 * freqs.len() * amps.len())?;
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    let out = OutputDir::open(&dir, Some("fatigue"), &command_line())?;
    let t0 = std::time::Instant::now();
    let moment = format!("{:?}", a.moment).to_lowercase();
    eprintln!(
        "fatigue: {} runs of {} s on {} threads…",
        2 * freqs.len() * amps.len() * ens.k,
        s.file.duration,
        pool.current_num_threads()
    );
    let ((points, members, csv_path, png, comparison), _files) = with_output(out, |out| {
        let members = pool.install(|| {
            fatigue_members(
                &params,
                s.file.elements,
                config,
                &freqs,
                &amps,
                s.file.duration,
                steady_from,
                ens,
            )
        })?;
        // Member 0 (the scene itself) of every point: the plain run's points.
        let points: Vec<FatiguePoint> = members.iter().filter_map(|m| m.first().cloned()).collect();
        let text = if ens.is_ensemble() {
            csv_members(&members, ens, detail.name(), &moment)
        } else {
            csv(&points, detail.name(), &moment)
        };
        let csv_path = out.write("fatigue.csv", &text)?;
        let png = if a.no_plots {
            None
        } else {
            let title = format!(
                "Root fatigue, AASHTO {} (t ≥ {steady_from} s of {} s runs, {} elements, base ±{:.2} mm){}",
                detail.name(),
                s.file.duration,
                s.file.elements,
                amps.first().copied().unwrap_or(0.0) * 1e3,
                if ens.is_ensemble() {
                    format!("; ensemble of {}: mean, ± sd dashed, min–max thin", ens.k)
                } else {
                    String::new()
                }
            );
            Some(if ens.is_ensemble() {
                out.write_with("fatigue.png", |p| plot_members(p, &title, &members, &amps))?
            } else {
                out.write_with("fatigue.png", |p| plot(p, &title, &points, &amps))?
            })
        };
        let mut failed = members
            .iter()
            .filter(|m| m.iter().any(FatiguePoint::failed))
            .count();
        let mut comparison = None;
        if let Some(m) = a.calibrate_against {
            let n = s.file.elements;
            let (reference, free) = absorber_sim::calibrate::reference(&s, m)?;
            let fit = absorber_sim::calibrate::fit(&s, n, &reference, free)?;
            let mut cal = params;
            cal.calibration = fit.calibration;
            let mut plain = params;
            plain.calibration = absorber_core::Calibration::default();
            let run = |p: &absorber_core::Params<f64>, k: usize| {
                pool.install(|| {
                    fatigue_points(p, k, config, &freqs, &amps, s.file.duration, steady_from)
                })
            };
            let (calibrated, converged) = (run(&cal, n)?, run(&plain, m)?);
            let rows: Vec<Comparison> = points
                .iter()
                .zip(calibrated)
                .zip(converged)
                .map(|((p, c), r)| Comparison {
                    model: p.clone(),
                    calibrated: c,
                    converged: r,
                })
                .collect();
            failed += rows.iter().filter(|c| c.failed()).count();
            out.write("fatigue_calibrated.csv", &comparison_csv(&rows, n, m))?;
            if !a.no_plots {
                let title = format!(
                    "Damage rate / {m} elements: {n} elements as given and calibrated ({} s runs)",
                    s.file.duration
                );
                out.write_with("fatigue_calibrated.png", |p| {
                    plot_comparison(p, &title, &rows, n)
                })?;
            }
            comparison = Some((rows, fit.calibration, n, m));
        }
        let status = Status::of_points(failed);
        let extra = json!({
            "points": points.len(),
            "failed": failed,
            "steady_from": steady_from,
            "steady": window,
        });
        Ok(((points, members, csv_path, png, comparison), status, extra))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "fatigue at the clamp: category {} (m = 3, CAFT cutoff), {} elements, {} s runs, moment from the {moment}",
        detail.name(),
        s.file.elements,
        s.file.duration
    );
    println!(
        "{window}: every column over it; damage rate = its Miner damage per hour of it (the start-up from rest is not service loading)"
    );
    if ens.is_ensemble() {
        return ensemble_table(&members, ens, &csv_path, png.as_deref(), wall);
    }
    println!(
        "  f [Hz]  A [mm]   D/h free     D/h locked   S_eq free/locked [MPa]   impacts  in flight"
    );
    for p in &points {
        if p.failed() {
            let why = [("free", &p.free.error), ("locked", &p.locked.error)]
                .iter()
                .filter_map(|(w, e)| e.as_deref().map(|e| format!("{w} ball: {e}")))
                .collect::<Vec<_>>()
                .join("; ");
            println!(
                "  {:6.3}  {:6.3}   FAILED: {why}",
                p.frequency,
                p.amplitude * 1e3
            );
            continue;
        }
        println!(
            "  {:6.3}  {:6.3}   {:10.3e}   {:10.3e}   {:8.2} / {:8.2}       {:5}  {:6.1} %",
            p.frequency,
            p.amplitude * 1e3,
            p.free.damage_rate,
            p.locked.damage_rate,
            p.free.equivalent_range / 1e6,
            p.locked.equivalent_range / 1e6,
            p.free.impacts,
            100.0 * p.free.flight_fraction,
        );
    }
    if let Some((rows, c, n, m)) = &comparison {
        println!(
            "damage rate per hour: {n} elements as given, calibrated (bending {:.6}, axial {:.6}, lumping {:.6}; fitted to the full solver with {m}), core with {m}",
            c.bending_stiffness, c.axial_stiffness, c.mass_lumping
        );
        println!("  f [Hz]   locked: N{n}       cal.       N{m}    cal./N{m}  N{n}/N{m}  | free: N{n}       cal.       N{m}    cal./N{m}");
        for r in rows {
            if r.failed() {
                println!("  {:6.3}   FAILED", r.converged.frequency);
                continue;
            }
            let (l, f) = (&r.converged.locked, &r.converged.free);
            let free = if r.free_chaotic() {
                format!(
                    "{:10.3e} {:10.3e} {:10.3e}   (chaotic)",
                    r.model.free.damage_rate, r.calibrated.free.damage_rate, f.damage_rate
                )
            } else {
                format!(
                    "{:10.3e} {:10.3e} {:10.3e}   {:6.3}",
                    r.model.free.damage_rate,
                    r.calibrated.free.damage_rate,
                    f.damage_rate,
                    ratio(r.calibrated.free.damage_rate, f.damage_rate)
                )
            };
            println!(
                "  {:6.3}   {:10.3e} {:10.3e} {:10.3e}   {:6.3}   {:6.3}  | {free}",
                r.converged.frequency,
                r.model.locked.damage_rate,
                r.calibrated.locked.damage_rate,
                l.damage_rate,
                ratio(r.calibrated.locked.damage_rate, l.damage_rate),
                ratio(r.model.locked.damage_rate, l.damage_rate),
            );
        }
        println!("wrote {}", dir.join("fatigue_calibrated.csv").display());
    }
    println!("wrote {}", csv_path.display());
    if let Some(p) = &png {
        println!("wrote {}", p.display());
    }
    println!("wall time {wall:.2} s ({} runs)", 2 * points.len());
    let failed = points.iter().filter(|p| p.failed()).count();
    if failed > 0 {
        return Err(PointsFailed(format!(
            "{failed} of {} fatigue points failed (marked FAILED in the table, {} and the plot)",
            points.len(),
            csv_path.display()
        ))
        .into());
    }
    Ok(())
}

/// The table of `fatigue --ensemble K`: per point, each figure over the members as
/// `mean ± sd (min–max)`; a point with a failed member is FAILED.
fn ensemble_table(
    members: &[Vec<FatiguePoint>],
    ens: Ensemble,
    csv_path: &std::path::Path,
    png: Option<&std::path::Path>,
    wall: f64,
) -> Result<()> {
    use absorber_sim::ensemble::{aggregate, count_text, text};
    println!("{}", super::run::ensemble_line(ens));
    println!("  f [Hz]  A [mm]   D/h free                                   D/h locked                                 impacts (free)   in flight [%]");
    let mut failed = 0;
    for m in members {
        let Some(p0) = m.first() else { continue };
        if let Some((k, p)) = m.iter().enumerate().find(|(_, p)| p.failed()) {
            failed += 1;
            let why = [&p.free.error, &p.locked.error]
                .iter()
                .filter_map(|e| e.as_deref())
                .collect::<Vec<_>>()
                .join("; ");
            println!(
                "  {:6.3}  {:6.3}   FAILED: member {k}: {why}",
                p0.frequency,
                p0.amplitude * 1e3
            );
            continue;
        }
        let values: Vec<Value> = m
            .iter()
            .map(|p| serde_json::to_value(p).unwrap_or_default())
            .collect();
        let g = aggregate(&values, &["frequency", "amplitude"]);
        let sci = |v: &Value| match absorber_sim::ensemble::spread_of(v) {
            Some(sp) => format!(
                "{:.3e} ± {:.1e} ({:.3e}–{:.3e})",
                sp.mean, sp.sd, sp.min, sp.max
            ),
            None => format!("{:.3e}", absorber_sim::ensemble::value(v)),
        };
        println!(
            "  {:6.3}  {:6.3}   {:41}  {:41}  {:15}  {}",
            p0.frequency,
            p0.amplitude * 1e3,
            sci(&g["free"]["damage_rate"]),
            sci(&g["locked"]["damage_rate"]),
            count_text(&g["free"]["impacts"]),
            text(&g["free"]["flight_fraction"], 100.0, 1),
        );
    }
    println!("wrote {}", csv_path.display());
    if let Some(p) = png {
        println!("wrote {} (mean, ± sd, min–max of the members)", p.display());
    }
    println!("wall time {wall:.2} s ({} runs)", 2 * members.len() * ens.k);
    if failed > 0 {
        return Err(PointsFailed(format!(
            "{failed} of {} fatigue points had a failed run (marked FAILED in the table and {})",
            members.len(),
            csv_path.display()
        ))
        .into());
    }
    Ok(())
}

fn plot(path: &std::path::Path, title: &str, points: &[FatiguePoint], amps: &[f64]) -> Result<()> {
    let log = |x: f64| if x > 0.0 { x.log10() } else { f64::NAN };
    let mut damage = Vec::new();
    let mut seq = Vec::new();
    for (k, &amp) in amps.iter().enumerate() {
        let pts: Vec<&FatiguePoint> = points
            .iter()
            .filter(|p| p.amplitude == amp && !p.failed())
            .collect();
        let tag = if amps.len() > 1 {
            format!(" {:.2} mm", amp * 1e3)
        } else {
            String::new()
        };
        // One colour per scene (free, locked) and amplitude, the same on both panels.
        let (cf, cl) = (FREE + 2 * k, LOCKED + 2 * k);
        damage.push(
            Series::marked(
                &format!("free ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, log(p.free.damage_rate)))
                    .collect(),
            )
            .colored(cf),
        );
        damage.push(
            Series::marked(
                &format!("locked ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, log(p.locked.damage_rate)))
                    .collect(),
            )
            .colored(cl),
        );
        seq.push(
            Series::marked(
                &format!("free ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, p.free.equivalent_range / 1e6))
                    .collect(),
            )
            .colored(cf),
        );
        seq.push(
            Series::marked(
                &format!("locked ball{tag}"),
                pts.iter()
                    .map(|p| (p.frequency, p.locked.equivalent_range / 1e6))
                    .collect(),
            )
            .colored(cl),
        );
    }
    let failed: Vec<f64> = points
        .iter()
        .filter(|p| p.failed())
        .map(|p| p.frequency)
        .collect();
    render_damage(
        path,
        title,
        "Miner damage rate (CAFT cutoff; no marker: no damage, every range below it)",
        damage,
        seq,
        failed,
    )
}

/// The fatigue plot's two panels: damage rate (log10, panel title `damage_title`) and S_eq
/// against frequency, failed frequencies marked on both.
fn render_damage(
    path: &std::path::Path,
    title: &str,
    damage_title: &str,
    damage: Vec<Series>,
    seq: Vec<Series>,
    failed: Vec<f64>,
) -> Result<()> {
    render(
        path,
        title,
        &[
            Panel::new(
                damage_title,
                "excitation frequency [Hz]",
                "log10(damage per hour)",
                damage,
            )
            .with_failed(failed.clone()),
            Panel::new(
                "Equivalent stress range S_eq = (Σ n S³ / Σ n)^(1/3)",
                "excitation frequency [Hz]",
                "S_eq [MPa]",
                seq,
            )
            .with_failed(failed),
        ],
        2,
        1,
        (1000, 900),
    )
}

/// Mean, standard deviation, smallest and largest of a figure over the members.
struct Stats {
    mean: f64,
    sd: f64,
    min: f64,
    max: f64,
}

/// The [`Stats`] of `xs` (NaN for none).
fn spread(xs: &[f64]) -> Stats {
    if xs.is_empty() {
        return Stats {
            mean: f64::NAN,
            sd: f64::NAN,
            min: f64::NAN,
            max: f64::NAN,
        };
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let (min, max) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    Stats {
        mean,
        sd: var.sqrt(),
        min,
        max,
    }
}

/// The ensemble's fatigue plot: per scene (free, locked) and amplitude the members' mean
/// (markers, a wide line), mean ± sd (dashed) and min–max (thin lines) in one colour; the
/// damage panel over log10 of the members' rates (the rates span decades; a member without
/// damage, all ranges below the cutoff, has no logarithm and is left out), S_eq in MPa. A point with a
/// failed member is marked failed.
fn plot_members(
    path: &std::path::Path,
    title: &str,
    members: &[Vec<FatiguePoint>],
    amps: &[f64],
) -> Result<()> {
    let log = |x: f64| if x > 0.0 { x.log10() } else { f64::NAN };
    let ok: Vec<&Vec<FatiguePoint>> = members
        .iter()
        .filter(|m| !m.is_empty() && !m.iter().any(FatiguePoint::failed))
        .collect();
    let failed: Vec<f64> = members
        .iter()
        .filter(|m| m.iter().any(FatiguePoint::failed))
        .filter_map(|m| m.first().map(|p| p.frequency))
        .collect();
    let bands = |amp: f64, name: &str, color: usize, f: &dyn Fn(&FatiguePoint) -> f64| {
        let stats: Vec<(f64, Stats)> = ok
            .iter()
            .filter(|m| m[0].amplitude == amp)
            .map(|m| {
                let xs: Vec<f64> = m.iter().map(f).filter(|x| x.is_finite()).collect();
                (m[0].frequency, spread(&xs))
            })
            .collect();
        let pick = |g: &dyn Fn(&Stats) -> f64| -> Vec<(f64, f64)> {
            stats.iter().map(|(x, sp)| (*x, g(sp))).collect()
        };
        vec![
            Series::marked(&format!("{name} mean"), pick(&|s| s.mean))
                .colored(color)
                .width(2),
            Series::line(&format!("{name} ± sd"), pick(&|s| s.mean + s.sd))
                .colored(color)
                .dashed(),
            Series::line("", pick(&|s| s.mean - s.sd))
                .colored(color)
                .dashed(),
            Series::line(&format!("{name} min–max"), pick(&|s| s.min)).colored(color),
            Series::line("", pick(&|s| s.max)).colored(color),
        ]
    };
    let mut damage = Vec::new();
    let mut seq = Vec::new();
    for (k, &amp) in amps.iter().enumerate() {
        let tag = if amps.len() > 1 {
            format!(" {:.2} mm", amp * 1e3)
        } else {
            String::new()
        };
        let (cf, cl) = (FREE + 2 * k, LOCKED + 2 * k);
        let (free, locked) = (format!("free{tag}"), format!("locked{tag}"));
        damage.extend(bands(amp, &free, cf, &|p| log(p.free.damage_rate)));
        damage.extend(bands(amp, &locked, cl, &|p| log(p.locked.damage_rate)));
        seq.extend(bands(amp, &free, cf, &|p| p.free.equivalent_range / 1e6));
        seq.extend(bands(amp, &locked, cl, &|p| {
            p.locked.equivalent_range / 1e6
        }));
    }
    render_damage(
        path,
        title,
        "Miner damage rate (CAFT cutoff): log10 statistics of the members with damage > 0",
        damage,
        seq,
        failed,
    )
}

/// Damage-rate ratios to the converged mesh per frequency: locked ball (as given, calibrated),
/// free ball calibrated where its motion is not chaotic.
fn plot_comparison(
    path: &std::path::Path,
    title: &str,
    rows: &[Comparison],
    n: usize,
) -> Result<()> {
    let ok: Vec<&Comparison> = rows.iter().filter(|r| !r.failed()).collect();
    let pts = |f: &dyn Fn(&Comparison) -> f64| -> Vec<(f64, f64)> {
        ok.iter()
            .map(|r| (r.converged.frequency, f(r)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let series = vec![
        Series::marked(
            &format!("locked ball, N = {n} as given"),
            pts(&|r| ratio(r.model.locked.damage_rate, r.converged.locked.damage_rate)),
        )
        .colored(2),
        Series::marked(
            &format!("locked ball, N = {n} calibrated"),
            pts(&|r| {
                ratio(
                    r.calibrated.locked.damage_rate,
                    r.converged.locked.damage_rate,
                )
            }),
        )
        .colored(LOCKED),
        Series::marked(
            &format!("free ball (no stop contact), N = {n} calibrated"),
            pts(&|r| {
                if r.free_chaotic() {
                    f64::NAN
                } else {
                    ratio(r.calibrated.free.damage_rate, r.converged.free.damage_rate)
                }
            }),
        )
        .colored(FREE),
    ];
    let failed: Vec<f64> = rows
        .iter()
        .filter(|r| r.failed())
        .map(|r| r.converged.frequency)
        .collect();
    render(
        path,
        title,
        &[Panel::new(
            "Miner damage rate relative to the converged mesh",
            "excitation frequency [Hz]",
            "damage rate / converged",
            series,
        )
        .with_failed(failed)],
        1,
        1,
        (1000, 500),
    )
}
