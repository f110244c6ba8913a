//! `sweep`: the frequency response, one streamed run per frequency in parallel.

use super::{check_excitations, describe, load, pool, progress_bar};
use crate::cli::SweepArgs;
use crate::output::{command_line, with_output, OutputDir, PointsFailed, Status};
use crate::plot::{render, Panel, Series};
use crate::scene::Scene;
use crate::sweep::{sweep, SweepPoint, PAPER_FREQUENCIES};
use anyhow::{bail, Result};
use serde_json::json;
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

pub fn sweep_cmd(a: &SweepArgs) -> Result<()> {
    let s = load(&a.scene)?;
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
