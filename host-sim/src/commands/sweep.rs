//! `sweep`: the frequency response, one streamed run per frequency in parallel.

use super::{check_excitations, describe, load, pool, progress_bar};
use crate::cli::SweepArgs;
use crate::ensemble::{spread_of, Ensemble};
use crate::output::{command_line, with_output, OutputDir, PointsFailed, Status};
use crate::plot::{render, Panel, Series};
use crate::scene::Scene;
use crate::sweep::{aggregate_point, sweep, sweep_members, SweepPoint, PAPER_FREQUENCIES};
use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::time::Instant;

/// What `sweep` checks before it computes: a harmonic scene, the frequencies (default: the
/// paper's) against the step, and the window `last`; returns the frequencies.
fn check(s: &Scene, freqs: Option<&[f64]>, last: f64) -> Result<Vec<f64>> {
    let freqs = freqs.map_or_else(|| PAPER_FREQUENCIES.to_vec(), <[f64]>::to_vec);
    if s.file.excitation.kind != crate::scene::ExcitationType::Harmonic {
        bail!("sweep needs a harmonic excitation (the scene has type = \"csv\")");
    }
    let h = s.file.integrator.step;
    check_excitations(
        &freqs,
        &[s.file.excitation.amplitude_or_paper()],
        h,
        "--freqs",
        "--amplitude",
    )?;
    let duration = s.steps() as f64 * h;
    if !last.is_finite() || last < 10.0 * h || last >= duration {
        bail!(
            "invalid value for `--last`: {last} (the steady-state window must hold at least 10 steps, \
             {} s, and be shorter than the run, {duration} s)",
            10.0 * h
        );
    }
    Ok(freqs)
}

/// `sweep` in memory (the Python package's `sweep`): the same checks and the same parallel runs
/// on `jobs` threads (default and at most: the cores and the frequencies), one point per frequency (failed points carry their
/// error).
pub fn sweep_in_memory(
    s: &Scene,
    freqs: Option<&[f64]>,
    last: f64,
    jobs: Option<usize>,
) -> Result<Vec<SweepPoint>> {
    let freqs = check(s, freqs, last)?;
    let pool = pool(jobs, freqs.len())?;
    pool.install(|| sweep(s, &freqs, last, &|_| {}))
}

/// An ensemble's sweep in memory (the Python package's `sweep(..., ensemble=K)`): per frequency
/// the aggregated point ([`crate::sweep::aggregate_point`]).
pub fn sweep_ensemble_in_memory(
    s: &Scene,
    freqs: Option<&[f64]>,
    last: f64,
    jobs: Option<usize>,
    e: Ensemble,
) -> Result<Vec<Value>> {
    let freqs = check(s, freqs, last)?;
    let pool = pool(jobs, freqs.len() * e.k)?;
    let members = pool.install(|| sweep_members(s, &freqs, last, e, &|_| {}))?;
    Ok(members.iter().map(|m| aggregate_point(m)).collect())
}

pub fn sweep_cmd(a: &SweepArgs) -> Result<()> {
    let s = load(&a.scene)?;
    let ens = a.ensemble.ensemble()?;
    crate::ensemble::check_scene(&s, ens)?;
    if ens.is_ensemble() {
        return sweep_ensemble_cmd(a, &s, ens);
    }
    let freqs = check(&s, a.freqs.as_deref(), a.last)?;
    let pool = pool(a.jobs, freqs.len())?;
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    let out = OutputDir::open(&dir, Some("sweep"), &command_line())?;
    let t0 = Instant::now();
    let ((points, csv_path, png), _files) = with_output(out, |out| {
        let pb = progress_bar(
            (freqs.len() * s.steps()) as u64,
            &format!("sweep ({} threads)", pool.current_num_threads()),
        );
        let points = pool.install(|| sweep(&s, &freqs, a.last, &|n| pb.inc(n)))?;
        pb.finish_and_clear();
        let csv_path = out.write("sweep.csv", &crate::sweep::csv(&points))?;
        let png = if a.no_plots {
            None
        } else {
            Some(out.write_with("sweep.png", |p| plot(p, &s, &points, a.last))?)
        };
        let failed = points.iter().filter(|p| p.failed()).count();
        let status = Status::of_points(failed);
        let extra = json!({ "points": points.len(), "failed": failed });
        Ok(((points, csv_path, png), status, extra))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let failed: Vec<&SweepPoint> = points.iter().filter(|p| p.failed()).collect();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "duration": s.file.duration, "last": a.last, "points": points, "failed": failed.len(), "csv": csv_path, "plot": png, "wall_time": wall })
        );
    } else {
        println!("{}", describe(&s));
        println!("  f [Hz]   tip Y [mm]   ball max|θ| [deg]   ball θ half p-p [deg]   impacts");
        for p in &points {
            match &p.error {
                None => println!(
                    "  {:6.3}   {:10.4}   {:17.2}   {:21.2}   {:7}",
                    p.frequency,
                    p.tip_amplitude * 1e3,
                    p.ball_max_deg,
                    p.ball_amplitude_deg,
                    p.impacts,
                ),
                Some(e) => println!("  {:6.3}   FAILED: {e}", p.frequency),
            }
        }
        println!("wrote {}", csv_path.display());
        if let Some(p) = &png {
            println!("wrote {}", p.display());
        }
        println!("wall time {wall:.2} s ({} runs)", points.len());
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

/// `sweep --ensemble K` (K > 1): every member at every frequency; the table and the JSON give
/// each statistic over the members, the CSV every run, the plot the mean with min–max bars.
fn sweep_ensemble_cmd(a: &SweepArgs, s: &Scene, ens: Ensemble) -> Result<()> {
    let freqs = check(s, a.freqs.as_deref(), a.last)?;
    let pool = pool(a.jobs, freqs.len() * ens.k)?;
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| s.file.outputs.directory.clone());
    let out = OutputDir::open(&dir, Some("sweep"), &command_line())?;
    let t0 = Instant::now();
    let ((points, csv_path, png), _files) = with_output(out, |out| {
        let pb = progress_bar(
            (ens.k * freqs.len() * s.steps()) as u64,
            &format!(
                "sweep, ensemble of {} ({} threads)",
                ens.k,
                pool.current_num_threads()
            ),
        );
        let members = pool.install(|| sweep_members(s, &freqs, a.last, ens, &|n| pb.inc(n)))?;
        pb.finish_and_clear();
        let csv_path = out.write("sweep.csv", &crate::sweep::csv_members(&members, ens))?;
        let points: Vec<Value> = members.iter().map(|m| aggregate_point(m)).collect();
        let png = if a.no_plots {
            None
        } else {
            Some(out.write_with("sweep.png", |p| plot_ensemble(p, s, &points, a.last, ens))?)
        };
        let failed = points.iter().filter(|p| !p["error"].is_null()).count();
        let status = Status::of_points(failed);
        let extra = json!({ "points": points.len(), "failed": failed, "ensemble": ens.k });
        Ok(((points, csv_path, png), status, extra))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let failed = points.iter().filter(|p| !p["error"].is_null()).count();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "duration": s.file.duration, "last": a.last, "ensemble": ens.json(), "points": points, "failed": failed, "csv": csv_path, "plot": png, "wall_time": wall })
        );
    } else {
        println!("{}", describe(s));
        println!("{}", super::run::ensemble_line(ens));
        println!("  f [Hz]   tip Y [mm]                    ball max|θ| [deg]        ball θ half p-p [deg]    impacts");
        for p in &points {
            let f = crate::ensemble::value(&p["frequency"]);
            match p["error"].as_str() {
                None => println!(
                    "  {f:6.3}   {:28}  {:23}  {:23}  {}",
                    crate::ensemble::text(&p["tip_amplitude"], 1e3, 4),
                    crate::ensemble::text(&p["ball_max_deg"], 1.0, 2),
                    crate::ensemble::text(&p["ball_amplitude_deg"], 1.0, 2),
                    crate::ensemble::count_text(&p["impacts"]),
                ),
                Some(e) => println!("  {f:6.3}   FAILED: {e}"),
            }
        }
        println!("wrote {}", csv_path.display());
        if let Some(p) = &png {
            println!("wrote {}", p.display());
        }
        println!("wall time {wall:.2} s ({} runs)", points.len() * ens.k);
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
    last: f64,
    ens: Ensemble,
) -> Result<()> {
    let ok: Vec<&Value> = points.iter().filter(|p| p["error"].is_null()).collect();
    let failed: Vec<f64> = points
        .iter()
        .filter(|p| !p["error"].is_null())
        .map(|p| crate::ensemble::value(&p["frequency"]))
        .collect();
    let band = |key: &str, label: &str, color: usize| -> Vec<Series> {
        let pick = |g: fn(&crate::ensemble::Spread) -> f64| -> Vec<(f64, f64)> {
            ok.iter()
                .filter_map(|p| {
                    spread_of(&p[key]).map(|sp| (crate::ensemble::value(&p["frequency"]), g(&sp)))
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
            "Frequency response: scene {}, {}, base {} mm; last {} s of {} s; ensemble of {} (mean, min–max)",
            s.file.name,
            s.file.kind.name(),
            s.file.excitation.amplitude_or_paper() * 1e3,
            last,
            s.file.duration,
            ens.k,
        ),
        &[
            Panel::new(
                "Beam tip",
                "excitation frequency [Hz]",
                "Y (half peak-to-peak) [m]",
                band("tip_amplitude", "Y", 0),
            )
            .with_failed(failed.clone()),
            Panel::new("Ball", "excitation frequency [Hz]", "θ [deg]", {
                let mut v = band("ball_max_deg", "max |θ|", 1);
                v.extend(band("ball_amplitude_deg", "half p-p", 2));
                v
            })
            .with_failed(failed),
        ],
        2,
        1,
        (1100, 900),
    )
}

fn plot(
    path: &std::path::Path,
    s: &crate::scene::Scene,
    points: &[SweepPoint],
    last: f64,
) -> Result<()> {
    let ok: Vec<&SweepPoint> = points.iter().filter(|p| !p.failed()).collect();
    let failed: Vec<f64> = points
        .iter()
        .filter(|p| p.failed())
        .map(|p| p.frequency)
        .collect();
    render(
        path,
        &format!(
            "Frequency response: scene {}, {}, base {} mm; last {} s of {} s",
            s.file.name,
            s.file.kind.name(),
            s.file.excitation.amplitude_or_paper() * 1e3,
            last,
            s.file.duration,
        ),
        &[
            Panel::new(
                "Beam tip",
                "excitation frequency [Hz]",
                "Y (half peak-to-peak) [m]",
                vec![Series::marked(
                    "",
                    ok.iter().map(|p| (p.frequency, p.tip_amplitude)).collect(),
                )],
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
