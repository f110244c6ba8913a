//! `sweep`: the frequency response, one streamed run per frequency in parallel.

use super::{describe, load};
use crate::cli::SweepArgs;
use absorber_sim::ensemble::{spread_of, Ensemble};
use absorber_sim::output::{command_line, with_output, OutputDir, PointsFailed, Status};
use absorber_sim::plot::{render, Panel, Series};
use absorber_sim::scene::Scene;
use absorber_sim::simulate::response::{check, locked_points, locked_scene, window};
use absorber_sim::simulate::{pool, progress_bar};
use absorber_sim::sweep::{aggregate_point, sweep, sweep_members, SweepPoint};
use anyhow::Result;
use serde_json::{json, Value};
use std::time::Instant;

pub fn sweep_cmd(a: &SweepArgs) -> Result<()> {
    let s = load(&a.scene)?;
    let ens = a.ensemble.ensemble()?;
    absorber_sim::ensemble::check_scene(&s, ens)?;
    if ens.is_ensemble() {
        return sweep_ensemble_cmd(a, &s, ens);
    }
    let from = window(&s, a.last)?;
    let freqs = check(&s, a.freqs.as_deref(), from)?;
    let pool = pool(a.jobs, freqs.len())?;
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    let out = OutputDir::open(&dir, Some("sweep"), &command_line())?;
    let t0 = Instant::now();
    // The table, CSV, JSON and plot compare with the ball locked (the paper's passive case),
    // run alongside.
    let locked_scene = locked_scene(&s);
    let runs = freqs.len() * (1 + usize::from(locked_scene.is_some()));
    let ((points, locked, csv_path, png), _files) = with_output(out, |out| {
        let pb = progress_bar(
            (runs * s.steps()) as u64,
            &format!("sweep ({} threads)", pool.current_num_threads()),
        );
        let points = pool.install(|| sweep(&s, &freqs, from, &|n| pb.inc(n)))?;
        let locked =
            pool.install(|| locked_points(locked_scene.as_ref(), &freqs, from, &|n| pb.inc(n)))?;
        pb.finish_and_clear();
        let csv_path = out.write(
            "sweep.csv",
            &absorber_sim::sweep::csv(&points, &locked, from),
        )?;
        let png = if a.no_plots {
            None
        } else {
            Some(out.write_with("sweep.png", |p| plot(p, &s, &points, &locked, from))?)
        };
        let failed = points.iter().filter(|p| p.failed()).count();
        let status = Status::of_points(failed);
        let extra = json!({ "points": points.len(), "failed": failed });
        Ok(((points, locked, csv_path, png), status, extra))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let failed: Vec<&SweepPoint> = points.iter().filter(|p| p.failed()).collect();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "duration": s.file.duration, "last": s.steps() as f64 * s.file.integrator.step - from, "steady_from": from, "steady": absorber_sim::run::steady_label(from), "points": points, "locked": locked, "failed": failed.len(), "csv": csv_path, "plot": png, "wall_time": wall })
        );
    } else {
        println!("{}", describe(&s));
        println!(
            "every column over the steady window: {}",
            absorber_sim::run::steady_label(from)
        );
        // The ball locked (the plot's dashed curve) beside the free ball, when it was run.
        let locked_head = if locked.is_empty() {
            ""
        } else {
            "   locked: tip Y [mm]"
        };
        println!("  f [Hz]   tip Y [mm]   ball max|θ| [deg]   ball θ half p-p [deg]   impacts   flight [%]{locked_head}");
        for (i, p) in points.iter().enumerate() {
            let locked_y = locked_cell(locked.get(i));
            match &p.error {
                None => println!(
                    "  {:6.3}   {:10.4}   {:17.2}   {:21.2}   {:7}   {:10.1}{locked_y}",
                    p.frequency,
                    p.tip_amplitude * 1e3,
                    p.ball_max_deg,
                    p.ball_amplitude_deg,
                    p.impacts,
                    100.0 * p.flight_fraction,
                ),
                Some(e) => println!("  {:6.3}   FAILED: {e}", p.frequency),
            }
        }
        println!("wrote {}", csv_path.display());
        if let Some(p) = &png {
            println!("wrote {}", p.display());
        }
        println!(
            "wall time {wall:.2} s ({} runs, {} with the ball locked)",
            points.len() + locked.len(),
            locked.len()
        );
    }
    if !failed.is_empty() {
        return Err(PointsFailed(format!(
            "{} of {} sweep runs failed (marked FAILED in the table, {} and the plot)",
            failed.len(),
            points.len(),
            csv_path.display()
        ))
        .into());
    }
    Ok(())
}

/// The table's locked-ball cell: its tip amplitude in mm, FAILED, or nothing (not run).
fn locked_cell(l: Option<&SweepPoint>) -> String {
    match l {
        Some(l) if l.error.is_none() => format!("   {:19.4}", l.tip_amplitude * 1e3),
        Some(_) => format!("   {:>19}", "FAILED"),
        None => String::new(),
    }
}

/// `sweep --ensemble K` (K > 1): every member at every frequency; the table and the JSON give
/// each statistic over the members, the CSV every run, the plot the mean with min–max bars.
fn sweep_ensemble_cmd(a: &SweepArgs, s: &Scene, ens: Ensemble) -> Result<()> {
    let from = window(s, a.last)?;
    let freqs = check(s, a.freqs.as_deref(), from)?;
    let pool = pool(a.jobs, freqs.len() * ens.k)?;
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    let out = OutputDir::open(&dir, Some("sweep"), &command_line())?;
    let t0 = Instant::now();
    let l = locked_scene(s);
    let ((points, locked, csv_path, png), _files) = with_output(out, |out| {
        let pb = progress_bar(
            ((ens.k + usize::from(l.is_some())) * freqs.len() * s.steps()) as u64,
            &format!(
                "sweep, ensemble of {} ({} threads)",
                ens.k,
                pool.current_num_threads()
            ),
        );
        let members = pool.install(|| sweep_members(s, &freqs, from, ens, &|n| pb.inc(n)))?;
        let locked = pool.install(|| locked_points(l.as_ref(), &freqs, from, &|n| pb.inc(n)))?;
        pb.finish_and_clear();
        let csv_path = out.write(
            "sweep.csv",
            &absorber_sim::sweep::csv_members(&members, &locked, ens, from),
        )?;
        let points: Vec<Value> = members.iter().map(|m| aggregate_point(m)).collect();
        let png = if a.no_plots {
            None
        } else {
            Some(out.write_with("sweep.png", |p| {
                plot_ensemble(p, s, &points, &locked, from, ens)
            })?)
        };
        let failed = points.iter().filter(|p| !p["error"].is_null()).count();
        let status = Status::of_points(failed);
        let extra = json!({ "points": points.len(), "failed": failed, "ensemble": ens.k });
        Ok(((points, locked, csv_path, png), status, extra))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let failed = points.iter().filter(|p| !p["error"].is_null()).count();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "duration": s.file.duration, "last": s.steps() as f64 * s.file.integrator.step - from, "steady_from": from, "steady": absorber_sim::run::steady_label(from), "ensemble": ens.json(), "points": points, "locked": locked, "failed": failed, "csv": csv_path, "plot": png, "wall_time": wall })
        );
    } else {
        println!("{}", describe(s));
        println!("{}", super::run::ensemble_line(ens));
        let locked_head = if locked.is_empty() {
            ""
        } else {
            "   locked: tip Y [mm]"
        };
        println!("  f [Hz]   tip Y [mm]                    ball max|θ| [deg]        ball θ half p-p [deg]    impacts{locked_head}");
        for (i, p) in points.iter().enumerate() {
            let f = absorber_sim::ensemble::value(&p["frequency"]);
            match p["error"].as_str() {
                None => println!(
                    "  {f:6.3}   {:28}  {:23}  {:23}  {:7}{}",
                    absorber_sim::ensemble::text(&p["tip_amplitude"], 1e3, 4),
                    absorber_sim::ensemble::text(&p["ball_max_deg"], 1.0, 2),
                    absorber_sim::ensemble::text(&p["ball_amplitude_deg"], 1.0, 2),
                    absorber_sim::ensemble::count_text(&p["impacts"]),
                    locked_cell(locked.get(i)),
                ),
                Some(e) => println!("  {f:6.3}   FAILED: {e}"),
            }
        }
        println!("wrote {}", csv_path.display());
        if let Some(p) = &png {
            println!("wrote {}", p.display());
        }
        println!(
            "wall time {wall:.2} s ({} runs, {} with the ball locked)",
            points.len() * ens.k + locked.len(),
            locked.len()
        );
    }
    if failed > 0 {
        return Err(PointsFailed(format!(
            "{failed} of {} sweep points had a failed run (marked FAILED in the table, {} and the plot)",
            points.len(),
            csv_path.display()
        ))
        .into());
    }
    Ok(())
}

/// The ensemble's frequency response: the mean (markers) between lines through the members'
/// smallest and largest values, in one colour per statistic.
fn plot_ensemble(
    path: &std::path::Path,
    s: &Scene,
    points: &[Value],
    locked: &[SweepPoint],
    from: f64,
    ens: Ensemble,
) -> Result<()> {
    let ok: Vec<&Value> = points.iter().filter(|p| p["error"].is_null()).collect();
    let failed: Vec<f64> = points
        .iter()
        .filter(|p| !p["error"].is_null())
        .map(|p| absorber_sim::ensemble::value(&p["frequency"]))
        .collect();
    let band = |key: &str, label: &str, color: usize, scale: f64| -> Vec<Series> {
        let pick = |g: fn(&absorber_sim::ensemble::Spread) -> f64| -> Vec<(f64, f64)> {
            ok.iter()
                .filter_map(|p| {
                    spread_of(&p[key]).map(|sp| {
                        (
                            absorber_sim::ensemble::value(&p["frequency"]),
                            scale * g(&sp),
                        )
                    })
                })
                .collect()
        };
        vec![
            Series::marked(&format!("{label} mean"), pick(|sp| sp.mean)).colored(color),
            Series::line(&format!("{label} min"), pick(|sp| sp.min)).colored(color),
            Series::line(&format!("{label} max"), pick(|sp| sp.max)).colored(color),
        ]
    };
    render(
        path,
        &format!(
            "Frequency response: scene {}, {}, base {} mm; {} of {} s; ensemble of {} (mean, min–max)",
            s.file.name,
            s.file.kind.name(),
            s.file.excitation.amplitude_or_paper() * 1e3,
            absorber_sim::run::steady_label(from),
            s.file.duration,
            ens.k,
        ),
        &[
            Panel::new(
                "Beam tip",
                "excitation frequency [Hz]",
                "Y (half peak-to-peak) [mm]",
                {
                    let mut v = band("tip_amplitude", "Y", 0, 1e3);
                    v.extend(locked_series(locked));
                    v
                },
            )
            .with_failed(failed.clone()),
            Panel::new("Ball", "excitation frequency [Hz]", "θ [deg]", {
                let mut v = band("ball_max_deg", "max |θ|", 1, 1.0);
                v.extend(band("ball_amplitude_deg", "half p-p", 2, 1.0));
                v
            })
            .with_failed(failed),
        ],
        2,
        1,
        (1100, 900),
    )
}

/// The locked ball's tip amplitude as the plots draw it (dashed grey; none when not run).
fn locked_series(locked: &[SweepPoint]) -> Option<Series> {
    (!locked.is_empty()).then(|| {
        Series::marked(
            "ball locked (passive)",
            locked
                .iter()
                .filter(|p| !p.failed())
                .map(|p| (p.frequency, 1e3 * p.tip_amplitude))
                .collect(),
        )
        .dashed()
        .colored(absorber_sim::plot::GREY)
    })
}

fn plot(
    path: &std::path::Path,
    s: &absorber_sim::scene::Scene,
    points: &[SweepPoint],
    locked: &[SweepPoint],
    from: f64,
) -> Result<()> {
    let ok: Vec<&SweepPoint> = points.iter().filter(|p| !p.failed()).collect();
    let mut tip = vec![Series::marked(
        s.file.kind.name(),
        ok.iter()
            .map(|p| (p.frequency, 1e3 * p.tip_amplitude))
            .collect(),
    )];
    tip.extend(locked_series(locked));
    let failed: Vec<f64> = points
        .iter()
        .filter(|p| p.failed())
        .map(|p| p.frequency)
        .collect();
    render(
        path,
        &format!(
            "Frequency response: scene {}, {}, base {} mm; {} of {} s",
            s.file.name,
            s.file.kind.name(),
            s.file.excitation.amplitude_or_paper() * 1e3,
            absorber_sim::run::steady_label(from),
            s.file.duration,
        ),
        &[
            Panel::new(
                "Beam tip",
                "excitation frequency [Hz]",
                "Y (half peak-to-peak) [mm]",
                tip,
            )
            .with_failed(failed.clone()),
            Panel::new(
                "Ball",
                "excitation frequency [Hz]",
                "θ [deg]",
                vec![
                    Series::marked(
                        "max |θ|",
                        ok.iter().map(|p| (p.frequency, p.ball_max_deg)).collect(),
                    ),
                    Series::marked(
                        "half peak-to-peak",
                        ok.iter()
                            .map(|p| (p.frequency, p.ball_amplitude_deg))
                            .collect(),
                    ),
                ],
            )
            .with_failed(failed),
        ],
        2,
        1,
        (1100, 900),
    )
}
