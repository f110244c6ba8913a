//! `host-sim estimate`: the monitor's estimators against the full solver
//! ([`absorber_sim::estimate`]): the twin of a real arm and the lab study (the regimes' table is
//! `absorber-studies monitoring`).

use crate::cli::EstimateArgs;
use absorber_sim::estimate::arm::TwinSeries;
use absorber_sim::estimate::check_duration;
use absorber_sim::estimate::lab::LabSeries;
use absorber_sim::estimate::{EstimatorReport, LabReport, Quality, TwinReport};
use absorber_sim::output::{OutputDir, Status};
use absorber_sim::plot::{render, Panel, Series};
use absorber_sim::scene::Scene;
use anyhow::{bail, Context, Result};
use serde_json::{json, Value};

/// Checks `--tip-force` before anything runs: finite, positive and no more than the arm can
/// carry, as a scene's sag is checked: a static tip deflection F·L³/(3·E·I) of at most half
/// the length.
fn check_tip_force(force: f64, scene: &Scene) -> Result<f64> {
    let p = scene.params()?;
    let (l, ei) = (p.beam.length, p.beam.modulus * p.beam.inertia);
    let most = 0.5 * l * 3.0 * ei / l.powi(3);
    if !(force.is_finite() && force > 0.0 && force <= most) {
        bail!(
            "invalid value for `--tip-force`: {force:e} N (allowed: 0 < force ≤ {most:.4e} N: \
             under more, the arm's static tip deflection F·L³/(3·E·I) exceeds half its length \
             {l} m; default 0.05 N)"
        );
    }
    Ok(most)
}

/// Runs the command.
pub fn run(a: &EstimateArgs) -> Result<()> {
    let scene = Scene::load(&a.scene)?;
    let baseline = absorber_sim::estimate::BaselineLoad {
        step: a.load_step,
        time: a.load_time,
    };
    baseline.validate()?;
    if a.lab {
        let duration = a.duration.unwrap_or(scene.file.duration);
        let h = scene.file.integrator.step;
        check_duration(duration, h)?;
        let most_force = check_tip_force(a.tip_force, &scene)?;
        let mut scene = scene;
        if let Some(f) = a.frequency {
            if !(f.is_finite() && f > 0.0) {
                bail!("invalid value for `--frequency`: {f} (must be finite and positive)");
            }
            // The Nyquist limit and the resolution warning, as `run` has them.
            absorber_sim::simulate::check_excitations(&[f], &[], h, "--frequency", "")?;
            absorber_sim::scene::check_harmonic(0.0, f, h, "", "--frequency")?;
            scene.file.excitation.frequency = Some(f);
        }
        let mut out = match &a.out {
            Some(dir) => Some(OutputDir::open(dir, Some("lab"), "estimate --lab")?),
            None => None,
        };
        let (r, series) = absorber_sim::estimate::lab(&scene, duration, a.tip_force, baseline)
            .with_context(|| {
                format!(
                    "the lab study failed under `--tip-force` {} N (allowed: at most {most_force:.4e} \
                     N, what the arm carries statically; near resonance the motion is larger: try \
                     a smaller force, default 0.05 N)",
                    a.tip_force
                )
            })?;
        if let Some(mut dir) = out.take() {
            write_lab_files(&mut dir, &r, &series)?;
            dir.commit(Status::Complete, graded_json(&r, &r.estimators)?)?;
        }
        if a.json {
            println!("{}", graded_json(&r, &r.estimators)?);
            return Ok(());
        }
        print_lab(&r);
        return Ok(());
    }
    if a.frequency.is_some() {
        bail!(
            "invalid option `--frequency` {}: allowed only with `--lab` (the twin's loads come from the scene)",
            a.frequency.unwrap_or(f64::NAN)
        );
    }
    let duration = a.duration.unwrap_or(scene.file.duration);
    check_duration(duration, scene.file.integrator.step)?;
    let mut out = match &a.out {
        Some(dir) => Some(OutputDir::open(dir, Some("estimate"), "estimate")?),
        None => None,
    };
    let (report, series) = absorber_sim::estimate::twin(&scene, duration, baseline)?;
    if let Some(mut dir) = out.take() {
        // The S–N threshold of the arm's detail (constant-amplitude fatigue threshold) [MPa].
        let threshold = scene
            .file
            .arm
            .as_ref()
            .and_then(|a| a.detail_category().ok())
            .map(|d| (d.name(), d.threshold_ksi() * 6.894_757));
        write_files(&mut dir, &report, &series, threshold)?;
        dir.commit(Status::Complete, graded_json(&report, &report.estimators)?)?;
    }
    if a.json {
        println!("{}", graded_json(&report, &report.estimators)?);
        return Ok(());
    }
    print_twin(&report);
    Ok(())
}

/// The worst word among an estimator's quality figures (`failed` > `poor` > `ok`; a figure
/// the estimator does not have, `none`, is skipped): its grade against the truth.
pub fn grade(q: &[Quality]) -> &'static str {
    let rank = |w: &str| match w {
        "failed" => 2,
        "poor" => 1,
        _ => 0,
    };
    q.iter()
        .filter(|f| f.word != "none")
        .map(|f| f.word)
        .max_by_key(|w| rank(w))
        .unwrap_or("ok")
}

/// The estimator the top-level verdict is about: the extended Kalman filter with the most
/// sensors (all the scene's), the first such (in `--lab`, the one on the free-ball truth).
fn headline(e: &[EstimatorReport]) -> Option<usize> {
    e.iter()
        .enumerate()
        .filter(|(_, r)| r.estimator == "ekf")
        .max_by_key(|(i, r)| (r.sensors.len(), std::cmp::Reverse(*i)))
        .map(|(i, _)| i)
}

/// A quality figure as a reader reads it: name, value and expected range in the figure's
/// unit, and why it is missing when the estimator has none.
fn figure_text(q: &Quality) -> String {
    let (name, scale, unit, digits, missing) = match q.figure {
        "nis" => ("NIS", 1.0, "", 2, "none: a constant gain has no covariance"),
        "within_two_sd" => ("within ±2 sd", 100.0, " %", 1, "none"),
        "innovation_ratio" => (
            "innovation RMS / sd",
            1.0,
            "",
            2,
            "none: no tip accelerometer",
        ),
        "stress_rms_error_pct" => ("stress RMS error", 1.0, " %", 1, "none"),
        "damage_ratio" => ("damage ratio", 1.0, "", 3, "none"),
        other => (other, 1.0, "", 3, "none"),
    };
    if q.word == "none" || !q.value.is_finite() {
        return format!("{name} –, {missing}");
    }
    let [lo, hi] = q.expected;
    let range = if lo == 0.0 {
        format!("≤ {}{unit}", fmt_bound(hi * scale))
    } else {
        format!("{}–{}{unit}", fmt_bound(lo * scale), fmt_bound(hi * scale))
    };
    format!(
        "{name} {:.digits$}{unit} (expected {range}): {}",
        q.value * scale,
        q.word
    )
}

/// A range bound with the digits it needs (0.5, 2, 0.71, 90, 99).
fn fmt_bound(x: f64) -> String {
    absorber_sim::run::trimmed(x, 2)
}

/// The per-estimator table of a study.
fn print_estimators(e: &[EstimatorReport]) {
    println!(
        "  {:<14} {:<12} {:<34} {:<7} {:>10} {:>8} {:>7} {:>9} {:>8} {:>8}",
        "estimator",
        "model",
        "sensors",
        "truth",
        "RMS err %",
        "damage",
        "NIS",
        "health",
        "grade",
        "clipped"
    );
    for r in e {
        let nis = if r.nis.is_finite() {
            format!("{:.2}", r.nis)
        } else {
            "–".into()
        };
        println!(
            "  {:<14} {:<12} {:<34} {:<7} {:>10.1} {:>8.3} {:>7} {:>9} {:>8} {:>8}",
            r.estimator,
            r.model,
            r.sensors.join("+"),
            r.truth,
            r.stress_rms_error_pct,
            r.damage_ratio,
            nis,
            r.verdict,
            grade(&r.quality),
            r.clipped.iter().sum::<usize>()
        );
        let figures: Vec<String> = r.quality.iter().map(figure_text).collect();
        println!("      {}", figures.join("; "));
    }
    println!(
        "  health: the monitor's own check on the device (a run is degraded or failed when ≥ 1 % of its samples are); grade: the worst of the figures below each row, against the truth (ok inside the expected range, poor inside a wider one, failed outside)"
    );
}

/// The closing verdict lines: the headline filter's grade against the truth (with the figures
/// that set it) and its health check.
fn print_verdict(e: &[EstimatorReport], what: &str) {
    let Some(r) = headline(e).map(|i| &e[i]) else {
        return;
    };
    let g = grade(&r.quality);
    let why: Vec<String> = r
        .quality
        .iter()
        .filter(|q| q.word == g && g != "ok")
        .map(|q| {
            let t = figure_text(q);
            t.trim_end_matches(&format!(": {g}")).to_string()
        })
        .collect();
    let [ok, degraded, failed] = r.verdict_fractions;
    println!(
        "verdict ({what}, {} {}): grade against the truth {g}{}; health {} ({:.1} % of samples ok, {:.1} % degraded, {:.1} % failed)",
        r.estimator,
        r.sensors.join("+"),
        if why.is_empty() {
            String::new()
        } else {
            format!(": {}", why.join(", "))
        },
        r.verdict,
        100.0 * ok,
        100.0 * degraded,
        100.0 * failed
    );
}

/// The report as JSON with each estimator's `grade` (the worst of its `quality` words) and
/// the top-level `grade` (the headline filter's, the one `verdict` is about).
fn graded_json<T: serde::Serialize>(r: &T, e: &[EstimatorReport]) -> Result<Value> {
    let mut v = serde_json::to_value(r)?;
    if let Some(list) = v.get_mut("estimators").and_then(Value::as_array_mut) {
        for (j, r) in list.iter_mut().zip(e) {
            if let Some(o) = j.as_object_mut() {
                o.insert("grade".into(), json!(grade(&r.quality)));
            }
        }
    }
    if let (Some(o), Some(i)) = (v.as_object_mut(), headline(e)) {
        o.insert("grade".into(), json!(grade(&e[i].quality)));
    }
    Ok(v)
}

fn print_setup(s: &absorber_sim::estimate::filter::Setup) {
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
    print_verdict(&r.estimators, "filter with all sensors, free truth");
}

fn print_twin(r: &TwinReport) {
    println!(
        "twin: truth = full solver, 16 elements, f64; estimate = core, 3 elements, f32 (E·I × {:.4}, gradient {:+.4}: f1 {:.4} / f2 {:.4} Hz as the truth's {:.4} / {:.4} Hz); {} s",
        r.bending_factor,
        r.bending_gradient,
        r.frequencies.1,
        r.second_frequencies.1,
        r.frequencies.0,
        r.second_frequencies.0,
        r.duration
    );
    println!(
        "root stress: true RMS about the mean {:.3} MPa, largest range {:.1} MPa; static: truth {:.2}, model {:.2} MPa; tip accelerometer clipped {:.1} % of its readings",
        r.true_stress_rms_mpa, r.max_range_mpa, r.static_stress_mpa.0, r.static_stress_mpa.1, r.clipped_pct
    );
    print_setup(&r.setup);
    print_estimators(&r.estimators);
    print_verdict(&r.estimators, "filter with all sensors");
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
    dir.write(
        "lab.json",
        &serde_json::to_string_pretty(&graded_json(r, &r.estimators)?)?,
    )?;
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
            "EKF with the ball, all sensors; truth: ball free",
            "truth (ball free)",
            &s.free,
            pick("free-ball", "free", true),
        ),
        (
            "EKF with the ball, tip accelerometer; truth: ball free",
            "truth (ball free)",
            &s.free,
            pick("free-ball", "free", false),
        ),
        (
            "control: ball locked in truth and EKF",
            "truth (ball locked)",
            &s.locked,
            pick("locked-ball", "locked", false),
        ),
    ] {
        if let Some(i) = idx {
            // A 3 s window around the truth's largest swing, where the waveforms can be told
            // apart (60 s of a 4 Hz arm are a solid band); the residual over the whole run on
            // its own scale beside it.
            let s0 = truth_series.first().copied().unwrap_or(0.0);
            let peak = s
                .time
                .iter()
                .zip(truth_series.iter())
                .max_by(|a, b| (a.1 - s0).abs().total_cmp(&(b.1 - s0).abs()))
                .map_or(0.0, |(t, _)| *t);
            let t_end = s.time.last().copied().unwrap_or(0.0);
            let w0 = (peak - 1.5).clamp(0.0, (t_end - 3.0).max(0.0));
            let zoom = |v: &[f64]| -> Vec<(f64, f64)> {
                mpa(v)
                    .into_iter()
                    .filter(|(t, _)| *t >= w0 && *t <= w0 + 3.0)
                    .collect()
            };
            let residual: Vec<f64> = s.estimates[i]
                .iter()
                .zip(truth_series.iter())
                .map(|(e, t)| e - t)
                .collect();
            panels.push(Panel::new(
                &format!("{title}: t = {w0:.1} … {:.1} s", w0 + 3.0),
                "t [s]",
                "root stress [MPa]",
                vec![
                    Series::line(truth_label, zoom(truth_series))
                        .colored(0)
                        .width(3),
                    Series::line(&names[i], zoom(&s.estimates[i]))
                        .colored(1)
                        .dashed(),
                ],
            ));
            panels.push(Panel::new(
                &format!(
                    "estimate − truth, whole run (RMS error {:.1} % of the true dynamic RMS)",
                    r.estimators[i].stress_rms_error_pct
                ),
                "t [s]",
                "stress [MPa]",
                vec![Series::line("estimate − truth", mpa(&residual)).colored(2)],
            ));
        }
    }
    let title = format!(
        "lab scene, tip force {} N at {} Hz: root stress, truth and estimates",
        r.force_amplitude, r.force_frequency
    );
    let rows = (panels.len() / 2).max(1);
    dir.write_with("lab_stress.png", |p| {
        render(p, &title, &panels, rows, 2, (1600, 370 * rows as u32))
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
    dir.write(
        "estimate.json",
        &serde_json::to_string_pretty(&graded_json(r, &r.estimators)?)?,
    )?;
    let mpa = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time.iter().zip(v).map(|(t, x)| (*t, x / 1e6)).collect()
    };
    let first = s.estimates.first().map_or(&[][..], |v| v.as_slice());
    let label = names.first().map_or("estimate", |n| n.as_str());
    // The scores are of the dynamic stress (each minus its own static value): so are the
    // plots, truth solid and wide, the estimate dashed on top, the residual on its own panel.
    let (static_truth, static_model) = r.static_stress_mpa;
    let dynamic = |v: &[f64], s0: f64| -> Vec<f64> { v.iter().map(|x| x - s0 * 1e6).collect() };
    let (truth_dyn, first_dyn) = (
        dynamic(&s.truth, static_truth),
        dynamic(first, static_model),
    );
    let residual: Vec<f64> = first_dyn
        .iter()
        .zip(&truth_dyn)
        .map(|(e, t)| e - t)
        .collect();
    // The whole run as the RMS over 10 s blocks: 600 s of a 1 Hz arm are a solid band.
    let block_rms = |v: &[f64]| -> Vec<(f64, f64)> {
        let mut pts = Vec::new();
        let (mut sum, mut n, mut t0) = (0.0, 0usize, s.time.first().copied().unwrap_or(0.0));
        for (t, x) in s.time.iter().zip(v) {
            sum += (x / 1e6).powi(2);
            n += 1;
            if t - t0 >= 10.0 - 1e-9 {
                pts.push((0.5 * (t0 + t), (sum / n as f64).sqrt()));
                (sum, n, t0) = (0.0, 0, *t);
            }
        }
        pts
    };
    // The 20 s window around the 10 s block with the largest true RMS (where fatigue is).
    let t_end = s.time.last().copied().unwrap_or(0.0);
    let centre = block_rms(&truth_dyn)
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.5 * t_end, |p| p.0);
    let w0 = (centre - 10.0).clamp(0.0, (t_end - 20.0).max(0.0));
    let w1 = w0 + 20.0;
    let window = |v: &[f64]| -> Vec<(f64, f64)> {
        mpa(v)
            .into_iter()
            .filter(|(t, _)| *t >= w0 && *t <= w1)
            .collect()
    };
    let statics = format!("static removed: truth {static_truth:.1}, model {static_model:.1} MPa");
    let panels = [
        Panel::new(
            "dynamic root stress, RMS over 10 s blocks, whole run",
            "t [s]",
            "RMS stress [MPa]",
            vec![
                Series::line("truth (full solver, N = 16)", block_rms(&truth_dyn))
                    .colored(0)
                    .width(3),
                Series::marked(label, block_rms(&first_dyn))
                    .colored(1)
                    .dashed(),
            ],
        ),
        Panel::new(
            &format!("dynamic root stress, 20 s window at the largest RMS ({statics})"),
            "t [s]",
            "stress [MPa]",
            vec![
                Series::line("truth", window(&truth_dyn))
                    .colored(0)
                    .width(2),
                Series::line(label, window(&first_dyn)).colored(1).dashed(),
            ],
        ),
        Panel::new(
            "residual: estimate − truth (dynamic), 20 s window",
            "t [s]",
            "stress [MPa]",
            vec![Series::line("estimate − truth", window(&residual)).colored(2)],
        ),
    ];
    dir.write_with("estimate_stress.png", |p| {
        render(
            p,
            &format!(
                "root stress: truth and estimate (core, N = 3, f32); RMS error {:.1} % of the true dynamic RMS",
                r.estimators.first().map_or(f64::NAN, |e| e.stress_rms_error_pct)
            ),
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
