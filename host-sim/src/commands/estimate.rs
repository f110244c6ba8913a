//! `host-sim estimate`: the monitor's estimators against the full solver
//! ([`crate::estimate`]): the twin of a real arm, the lab study, the regimes' table.

use crate::cli::EstimateArgs;
use crate::estimate::arm::TwinSeries;
use crate::estimate::lab::LabSeries;
use crate::estimate::{EstimatorReport, LabReport, TwinReport};
use crate::output::{OutputDir, Status};
use crate::plot::{render, Panel, Series};
use crate::scene::Scene;
use anyhow::{bail, Result};

/// Runs the command.
/// Most steps a study runs: the truth, the estimators and their histories are held in memory
/// (a few hundred bytes per step: about 2 GB here); 2^23 steps are 23 h at the arm's 10 ms.
const MAX_STEPS: f64 = 8_388_608.0;

/// Fewest steps a study runs: its statistics (RMS errors, damage ratios) need a response to
/// measure; 100 steps are 1 s at the arm's 10 ms.
const MIN_STEPS: f64 = 100.0;

/// Checks `--duration` against the scene's step before anything is allocated.
fn check_duration(duration: f64, h: f64) -> Result<()> {
    let steps = duration / h;
    if !(duration.is_finite() && (MIN_STEPS..=MAX_STEPS).contains(&steps)) {
        bail!(
            "invalid value for `--duration`: {duration} s (must lie in {} ..= {} s: {MIN_STEPS} to {MAX_STEPS} steps of h = {h} s; the study holds every step in memory)",
            MIN_STEPS * h,
            MAX_STEPS * h
        );
    }
    Ok(())
}

pub fn run(a: &EstimateArgs) -> Result<()> {
    if let Some(path) = &a.table {
        if a.lab || a.out.is_some() || a.emit_firmware.is_some() || a.json {
            bail!("`--table` runs every regime and writes its table: give it alone (with `--duration` at most)");
        }
        if let Some(d) = a.duration {
            // The table's regimes run at 3 ms (lab) and 10 ms (arm).
            check_duration(d, 0.01)?;
            check_duration(d, 0.003)?;
        }
        return crate::estimate::table::write(path, a.duration);
    }
    let scene = Scene::load(&a.scene)?;
    let baseline = crate::estimate::BaselineLoad {
        step: a.load_step,
        time: a.load_time,
    };
    baseline.validate()?;
    if a.lab {
        if a.emit_firmware.is_some() {
            bail!("`--emit-firmware` takes the arm's scene (`--scene scenes/mast-arm.toml`), not `--lab`");
        }
        let duration = a.duration.unwrap_or(scene.file.duration);
        let h = scene.file.integrator.step;
        check_duration(duration, h)?;
        let mut scene = scene;
        if let Some(f) = a.frequency {
            if !(f.is_finite() && f > 0.0) {
                bail!("invalid value for `--frequency`: {f} (must be finite and positive)");
            }
            // The Nyquist limit and the resolution warning, as `run` has them.
            super::check_excitations(&[f], &[], h, "--frequency", "")?;
            crate::scene::check_harmonic(0.0, f, h, "", "--frequency")?;
            scene.file.excitation.frequency = Some(f);
        }
        let mut out = match &a.out {
            Some(dir) => Some(OutputDir::open(dir, Some("lab"), "estimate --lab")?),
            None => None,
        };
        let (r, series) = crate::estimate::lab(&scene, duration, a.tip_force, baseline)?;
        if let Some(mut dir) = out.take() {
            write_lab_files(&mut dir, &r, &series)?;
            dir.commit(Status::Complete, serde_json::to_value(&r)?)?;
        }
        if a.json {
            println!("{}", serde_json::to_string(&r)?);
            return Ok(());
        }
        print_lab(&r);
        return Ok(());
    }
    if a.frequency.is_some() {
        bail!("`--frequency` belongs to `--lab` (the twin's loads come from the scene)");
    }
    if let Some(path) = &a.emit_firmware {
        let text = crate::estimate::firmware::constants(&scene)?;
        crate::output::atomic_write(path, text.as_bytes())?;
        println!("wrote {}", path.display());
        return Ok(());
    }
    let duration = a.duration.unwrap_or(scene.file.duration);
    check_duration(duration, scene.file.integrator.step)?;
    let mut out = match &a.out {
        Some(dir) => Some(OutputDir::open(dir, Some("estimate"), "estimate")?),
        None => None,
    };
    let (report, series) = crate::estimate::twin(&scene, duration, baseline)?;
    if let Some(mut dir) = out.take() {
        // The S–N threshold of the arm's detail (constant-amplitude fatigue threshold) [MPa].
        let threshold = scene
            .file
            .arm
            .as_ref()
            .and_then(|a| a.detail_category().ok())
            .map(|d| (d.name(), d.threshold_ksi() * 6.894_757));
        write_files(&mut dir, &report, &series, threshold)?;
        dir.commit(Status::Complete, serde_json::to_value(&report)?)?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
        return Ok(());
    }
    print_twin(&report);
    Ok(())
}

/// The per-estimator table of a study.
fn print_estimators(e: &[EstimatorReport]) {
    println!(
        "  {:<14} {:<12} {:<34} {:<7} {:>10} {:>8} {:>7} {:>9} {:>11}",
        "estimator",
        "model",
        "sensors",
        "truth",
        "RMS err %",
        "damage",
        "NIS",
        "verdict",
        "clipped"
    );
    for r in e {
        println!(
            "  {:<14} {:<12} {:<34} {:<7} {:>10.1} {:>8.3} {:>7.2} {:>9} {:>11}",
            r.estimator,
            r.model,
            r.sensors.join("+"),
            r.truth,
            r.stress_rms_error_pct,
            r.damage_ratio,
            r.nis,
            r.verdict,
            r.clipped.iter().sum::<usize>()
        );
        let figures: Vec<String> = r
            .quality
            .iter()
            .map(|q| {
                format!(
                    "{} {:.3} (expected {:.2}–{:.2}): {}",
                    q.figure, q.value, q.expected[0], q.expected[1], q.word
                )
            })
            .collect();
        println!("      {}", figures.join("; "));
    }
}

fn print_setup(s: &crate::estimate::filter::Setup) {
    println!(
        "filter: load model sd {:.3e} N, corner {:.2} Hz; model error ε {:.4}, near events ε_e {:.4}; stress factors {:.3} {:.3} {:.3}",
        s.load_sd,
        s.load_corner / std::f64::consts::TAU,
        s.model_error,
        s.event_error,
        s.stress_factors[0],
        s.stress_factors[1],
        s.stress_factors[2]
    );
    let [ours, theirs] = s.mode_frequencies;
    println!(
        "filter modes [Hz]: reduced {:.3} {:.3} {:.3}; reference (16 elements) {:.3} {:.3} {:.3}",
        ours[0], ours[1], ours[2], theirs[0], theirs[1], theirs[2]
    );
}

fn print_lab(r: &LabReport) {
    println!(
        "lab: full solver, 16 elements; tip force {} N at {} Hz in lock-in episodes {:?} s, no base motion, {} s",
        r.force_amplitude, r.force_frequency, r.episodes, r.duration
    );
    println!(
        "truth (free ball, flight on): root stress RMS {:.3} MPa, {} stop impacts, ball in flight {:.1} % of the time",
        r.free_stress_rms_mpa,
        r.impacts,
        100.0 * r.flight_fraction
    );
    println!(
        "ball locked: RMS {:.3} MPa; difference {:.1} % of the truth's RMS; Miner damage locked / free {:.3}",
        r.locked_stress_rms_mpa, r.exclusion_error_pct, r.exclusion_damage_ratio
    );
    println!(
        "estimators: core, 3 elements, f32; calibration E·I × {:.4}, E·a × {:.4}, lumping {:.3}",
        r.calibration[0], r.calibration[1], r.calibration[2]
    );
    print_setup(&r.setup);
    print_estimators(&r.estimators);
    println!(
        "verdict (filter with all sensors, free truth): {}",
        r.verdict
    );
}

fn print_twin(r: &TwinReport) {
    println!(
        "twin: truth = full solver, 16 elements, f64; estimate = core, 3 elements, f32 (E·I × {:.4}: f1 {:.4} Hz as the truth's {:.4} Hz); {} s",
        r.bending_factor, r.frequencies.1, r.frequencies.0, r.duration
    );
    println!(
        "root stress: true RMS about the mean {:.3} MPa, largest range {:.1} MPa; static: truth {:.2}, model {:.2} MPa; tip accelerometer clipped {:.1} % of its readings",
        r.true_stress_rms_mpa, r.max_range_mpa, r.static_stress_mpa.0, r.static_stress_mpa.1, r.clipped_pct
    );
    print_setup(&r.setup);
    print_estimators(&r.estimators);
    println!("verdict (filter with all sensors): {}", r.verdict);
}

/// `lab.csv`, `lab.json` and `lab_stress.png` of the lab study.
fn write_lab_files(dir: &mut OutputDir, r: &LabReport, s: &LabSeries) -> Result<()> {
    let names: Vec<String> = r
        .estimators
        .iter()
        .map(|e| {
            format!(
                "{}_{}_{}_{}",
                e.estimator,
                e.model,
                e.sensors.join("+"),
                e.truth
            )
        })
        .collect();
    let mut csv = format!(
        "# host-sim estimate --lab: t [s]; root stress [Pa]: truth with the ball free, full solver with the ball locked, each estimator\nt,free,locked,{}\n",
        names.join(",")
    );
    for i in 0..s.time.len() {
        csv.push_str(&format!(
            "{:.3},{:.6e},{:.6e}",
            s.time[i], s.free[i], s.locked[i]
        ));
        for e in &s.estimates {
            csv.push_str(&format!(",{:.6e}", e.get(i).copied().unwrap_or(f64::NAN)));
        }
        csv.push('\n');
    }
    dir.write("lab.csv", &csv)?;
    dir.write("lab.json", &serde_json::to_string_pretty(r)?)?;
    let mpa = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time.iter().zip(v).map(|(t, x)| (*t, x / 1e6)).collect()
    };
    // Three panels: the filter with the ball and its sensors, the ball left out, the control.
    let pick = |model: &str, truth: &str, most: bool| -> Option<usize> {
        let it = r
            .estimators
            .iter()
            .enumerate()
            .filter(|(_, e)| e.estimator == "ekf" && e.model == model && e.truth == truth);
        if most {
            it.max_by_key(|(_, e)| e.sensors.len()).map(|(i, _)| i)
        } else {
            it.min_by_key(|(_, e)| e.sensors.len()).map(|(i, _)| i)
        }
    };
    let mut panels = Vec::new();
    for (title, truth_label, truth_series, idx) in [
        (
            "extended Kalman filter, ball in the model, all sensors; free-ball truth",
            "truth (ball free)",
            &s.free,
            pick("free-ball", "free", true),
        ),
        (
            "extended Kalman filter, ball in the model, tip accelerometer; free-ball truth",
            "truth (ball free)",
            &s.free,
            pick("free-ball", "free", false),
        ),
        (
            "control: ball locked in truth and filter",
            "truth (ball locked)",
            &s.locked,
            pick("locked-ball", "locked", false),
        ),
    ] {
        if let Some(i) = idx {
            panels.push(Panel::new(
                title,
                "t [s]",
                "root stress [MPa]",
                vec![
                    Series::line(truth_label, mpa(truth_series))
                        .colored(0)
                        .width(2),
                    Series::line(&names[i], mpa(&s.estimates[i]))
                        .colored(1)
                        .dashed(),
                    Series::line(
                        "estimate − truth",
                        mpa(&s.estimates[i]
                            .iter()
                            .zip(truth_series.iter())
                            .map(|(e, t)| e - t)
                            .collect::<Vec<f64>>()),
                    )
                    .colored(2),
                ],
            ));
        }
    }
    let title = format!(
        "lab scene, tip force {} N at {} Hz: root stress, truth and estimates",
        r.force_amplitude, r.force_frequency
    );
    let rows = panels.len().max(1);
    dir.write_with("lab_stress.png", |p| {
        render(p, &title, &panels, rows, 1, (1200, 370 * rows as u32))
    })?;
    Ok(())
}

fn write_files(
    dir: &mut OutputDir,
    r: &TwinReport,
    s: &TwinSeries,
    threshold: Option<(&str, f64)>,
) -> Result<()> {
    let names: Vec<String> = r
        .estimators
        .iter()
        .map(|e| format!("{}_{}", e.estimator, e.sensors.join("+")))
        .collect();
    let mut csv = format!(
        "# host-sim estimate: t [s], true root stress [Pa], each estimator's [Pa], measured tip acceleration [m/s^2]\nt,stress_true,{},tip_accel_measured\n",
        names.join(",")
    );
    for i in 0..s.time.len() {
        csv.push_str(&format!("{:.3},{:.6e}", s.time[i], s.truth[i]));
        for e in &s.estimates {
            csv.push_str(&format!(",{:.6e}", e.get(i).copied().unwrap_or(f64::NAN)));
        }
        csv.push_str(&format!(",{:.6e}\n", s.measured[i]));
    }
    dir.write("estimate.csv", &csv)?;
    dir.write("estimate.json", &serde_json::to_string_pretty(r)?)?;
    let mpa = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time.iter().zip(v).map(|(t, x)| (*t, x / 1e6)).collect()
    };
    let t_end = s.time.last().copied().unwrap_or(0.0);
    let (w0, w1) = (0.5 * t_end - 10.0, 0.5 * t_end + 10.0);
    let window = |v: &[f64]| -> Vec<(f64, f64)> {
        mpa(v)
            .into_iter()
            .filter(|(t, _)| *t >= w0 && *t <= w1)
            .collect()
    };
    let first = s.estimates.first().map_or(&[][..], |v| v.as_slice());
    let label = names.first().map_or("estimate", |n| n.as_str());
    // Truth solid and wide, the estimate dashed on top; the residual on its own panel.
    let residual = |v: &[f64]| -> Vec<f64> { v.iter().zip(&s.truth).map(|(e, t)| e - t).collect() };
    let panels = [
        Panel::new(
            "root stress, whole run",
            "t [s]",
            "stress [MPa]",
            vec![
                Series::line("truth (full solver, N = 16)", mpa(&s.truth))
                    .colored(0)
                    .width(2),
                Series::line(label, mpa(first)).colored(1).dashed(),
            ],
        ),
        Panel::new(
            "root stress, 20 s window",
            "t [s]",
            "stress [MPa]",
            vec![
                Series::line("truth", window(&s.truth)).colored(0).width(2),
                Series::line(label, window(first)).colored(1).dashed(),
            ],
        ),
        Panel::new(
            "residual: estimate − truth, 20 s window",
            "t [s]",
            "stress [MPa]",
            vec![Series::line("estimate − truth", window(&residual(first))).colored(2)],
        ),
    ];
    dir.write_with("estimate_stress.png", |p| {
        render(
            p,
            "root stress: truth and estimate (core, N = 3, f32)",
            &panels,
            3,
            1,
            (1200, 1200),
        )
    })?;
    // Exceedance: cycles with a range at least S, against S (the upper edge of each bin).
    let h = &r.histogram;
    let exceed = |v: &[f64]| -> Vec<(f64, f64)> {
        let mut above = 0.0;
        let mut pts: Vec<(f64, f64)> = v
            .iter()
            .enumerate()
            .rev()
            .filter_map(|(i, c)| {
                above += c;
                (above > 0.0).then(|| (i as f64 * h.bin_mpa, above.log10()))
            })
            .collect();
        pts.reverse();
        pts
    };
    let (truth, estimate) = (exceed(&h.truth), exceed(&h.estimate));
    let mut series = vec![
        Series::line("truth", truth.clone()).colored(0).width(2),
        Series::line("estimate (all sensors)", estimate.clone())
            .colored(1)
            .dashed(),
    ];
    if let Some((name, t)) = threshold {
        let top = truth
            .iter()
            .chain(&estimate)
            .map(|p| p.1)
            .fold(0.0f64, f64::max);
        series.push(
            Series::line(
                &format!("S–N threshold, detail {name}: {t:.1} MPa"),
                vec![(t, 0.0), (t, top)],
            )
            .colored(3)
            .width(2),
        );
    }
    let hist = [Panel::new(
        "rainflow stress ranges: cycles with a range ≥ S",
        "stress range S [MPa]",
        "log10 cycles ≥ S",
        series,
    )];
    dir.write_with("estimate_histogram.png", |p| {
        render(p, "stress-range exceedance", &hist, 1, 1, (900, 600))
    })?;
    Ok(())
}
