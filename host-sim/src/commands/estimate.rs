//! `host-sim estimate`: the twin experiment of the root-stress estimator
//! ([`crate::estimate::twin`]).

use crate::cli::EstimateArgs;
use crate::estimate::{twin, LabReport, LabSeries, TwinReport, TwinSeries};
use crate::output::{OutputDir, Status};
use crate::plot::{render, Panel, Series};
use crate::scene::Scene;
use anyhow::{bail, Result};

/// Runs the command.
pub fn run(a: &EstimateArgs) -> Result<()> {
    let scene = Scene::load(&a.scene)?;
    if let Some(step) = a.load_step {
        if !(step.is_finite() && step > 0.0) {
            bail!("invalid value for `--load-step`: {step} (must be finite and positive)");
        }
    }
    if !(a.load_time.is_finite() && a.load_time > 0.0) {
        bail!(
            "invalid value for `--load-time`: {} (must be finite and positive)",
            a.load_time
        );
    }
    if a.lab {
        if a.emit_firmware.is_some() {
            bail!("`--emit-firmware` belongs to the twin (the firmware runs the mast arm's estimator), not to `--lab`");
        }
        let duration = a.duration.unwrap_or(scene.file.duration);
        let mut scene = scene;
        if let Some(f) = a.frequency {
            if !(f.is_finite() && f > 0.0) {
                bail!("invalid value for `--frequency`: {f} (must be finite and positive)");
            }
            scene.file.excitation.frequency = Some(f);
        }
        let mut out = match &a.out {
            Some(dir) => Some(OutputDir::open(dir, Some("lab"), "estimate --lab")?),
            None => None,
        };
        let load = crate::estimate::FilterLoad {
            step: a.load_step,
            time: a.load_time,
        };
        let (r, series) = crate::estimate::lab(&scene, duration, a.tip_force, load)?;
        if let Some(mut dir) = out.take() {
            write_lab_files(&mut dir, &r, &series)?;
            dir.commit(Status::Complete, serde_json::to_value(&r)?)?;
        }
        if a.json {
            println!("{}", serde_json::to_string(&r)?);
            return Ok(());
        }
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
            "ball locked (a model without the ball's motion): RMS {:.3} MPa; difference {:.1} % of the truth's RMS",
            r.locked_stress_rms_mpa, r.exclusion_error_pct
        );
        println!(
            "Miner damage, locked / free (category E', no threshold): {:.3}; with the CAFT cutoff: {:.3}",
            r.damage_ratio, r.damage_ratio_cutoff
        );
        println!(
            "estimators (core, 3 elements, f32; calibration E·I × {:.4}, E·a × {:.4}, lumping {:.3}; sensor noise σ {:.2e} m/s²; load model: step σ {:.3e} N, τ {} s):",
            r.calibration[0], r.calibration[1], r.calibration[2], r.sensor_noise, r.load_step, r.load_time
        );
        println!(
            "  {:<55} {:>12} {:>8} {:>10} {:>10} {:>7}",
            "case", "RMS error %", "damage", "load RMS N", "innov./sd", "failed"
        );
        for e in &r.estimators {
            println!(
                "  {:<55} {:>12.1} {:>8.3} {:>10.4} {:>10.2} {:>7}",
                e.case,
                e.stress_rms_error_pct,
                e.damage_ratio,
                e.load_rms,
                e.innovation_ratio,
                e.failed
            );
        }
        return Ok(());
    }
    if a.frequency.is_some() {
        bail!("`--frequency` belongs to `--lab` (the twin's loads come from the scene)");
    }
    if let Some(path) = &a.emit_firmware {
        let text = crate::estimate::firmware_constants(&scene)?;
        crate::output::atomic_write(path, text.as_bytes())?;
        println!("wrote {}", path.display());
        return Ok(());
    }
    let duration = a.duration.unwrap_or(scene.file.duration);
    let mut out = match &a.out {
        Some(dir) => Some(OutputDir::open(dir, Some("estimate"), "estimate")?),
        None => None,
    };
    let (report, series) = twin(&scene, duration, a.load_step.unwrap_or(0.5), a.load_time)?;
    if let Some(dir) = out.as_mut() {
        write_files(dir, &report, &series)?;
    }
    if let Some(dir) = out {
        dir.commit(Status::Complete, serde_json::to_value(&report)?)?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
        return Ok(());
    }
    let r = &report;
    println!(
        "twin: truth = full solver, 16 elements, f64; estimate = core, 3 elements, f32 (E·I × {:.4}: f1 {:.4} Hz as the truth's {:.4} Hz)",
        r.bending_factor, r.frequencies.1, r.frequencies.0
    );
    println!(
        "sensor noise σ {:.2e} m/s²; {} samples, {} clipped, {} failed; innovations' RMS / their steady-state sd {:.2} (1: the model explains the measurement to the noise)",
        r.noise.measurement, r.samples, r.clipped, r.failed, r.innovation_ratio
    );
    println!(
        "root stress: true RMS about the mean {:.3} MPa, mean true {:.2} / estimated {:.2} MPa",
        r.true_stress_rms_mpa, r.mean_stress_mpa.0, r.mean_stress_mpa.1
    );
    println!(
        "static stress under gravity: truth {:.2} MPa, estimator's model {:.2} MPa",
        r.static_stress_mpa.0, r.static_stress_mpa.1
    );
    println!(
        "RMS error of the dynamic stress {:.2} % of the true RMS ({:.2} % with the static difference); filter sd {:.3} MPa, {:.1} % of samples within ±2 sd",
        r.stress_rms_error_pct,
        r.stress_rms_error_total_pct,
        r.stress_sd_mpa,
        100.0 * r.within_two_sd
    );
    println!(
        "Miner damage (category {}, no threshold): true {:.3e}, estimated {:.3e}, ratio {:.3}; with the CAFT cutoff: ratio {:.3}",
        r.category, r.damage_true, r.damage_estimated, r.damage_ratio, r.damage_ratio_cutoff
    );
    println!(
        "stress-range histogram (cycles per {} MPa bin):",
        r.histogram.bin_mpa
    );
    println!("  range MPa      true  estimated");
    for (i, (t, e)) in r
        .histogram
        .truth
        .iter()
        .zip(&r.histogram.estimate)
        .enumerate()
    {
        if *t > 0.0 || *e > 0.0 {
            println!(
                "  {:>4}–{:<4} {:>9.1} {:>10.1}",
                i as f64 * r.histogram.bin_mpa,
                (i + 1) as f64 * r.histogram.bin_mpa,
                t,
                e
            );
        }
    }
    Ok(())
}

/// `lab.csv`, `lab.json` and `lab_stress.png` of the lab study.
fn write_lab_files(dir: &mut OutputDir, r: &LabReport, s: &LabSeries) -> Result<()> {
    let mut csv = String::from(
        "# host-sim estimate --lab: t [s]; root stress [Pa]: truth with the ball free, full solver with the ball locked, \
         estimators (core N = 3 f32) without the ball and with the ball in the state on the free truth, locked estimator on the locked truth\n\
         t,free,locked,estimate_ball_left_out,estimate_ball_in_state,estimate_control\n",
    );
    for i in 0..s.time.len() {
        csv.push_str(&format!(
            "{:.3},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}\n",
            s.time[i], s.free[i], s.locked[i], s.left_out[i], s.in_state[i], s.control[i]
        ));
    }
    dir.write("lab.csv", &csv)?;
    dir.write("lab.json", &serde_json::to_string_pretty(r)?)?;
    let mpa = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time.iter().zip(v).map(|(t, x)| (*t, x / 1e6)).collect()
    };
    let panels = [
        Panel::new(
            "estimator without the ball, free-ball truth",
            "t [s]",
            "root stress [MPa]",
            vec![
                Series::line("truth (ball free)", mpa(&s.free)).colored(0),
                Series::line("estimate, ball left out", mpa(&s.left_out)).colored(1),
            ],
        ),
        Panel::new(
            "estimator with the ball in its state, free-ball truth",
            "t [s]",
            "root stress [MPa]",
            vec![
                Series::line("truth (ball free)", mpa(&s.free)).colored(0),
                Series::line("estimate, ball in the state", mpa(&s.in_state)).colored(2),
            ],
        ),
        Panel::new(
            "control: ball locked in truth and estimator",
            "t [s]",
            "root stress [MPa]",
            vec![
                Series::line("truth (ball locked)", mpa(&s.locked)).colored(3),
                Series::line("estimate, locked-ball model", mpa(&s.control)).colored(1),
            ],
        ),
    ];
    let title = format!(
        "lab scene, tip force {} N at {} Hz: root stress, truth and estimates from the tip accelerometer",
        r.force_amplitude, r.force_frequency
    );
    dir.write_with("lab_stress.png", |p| {
        render(p, &title, &panels, 3, 1, (1200, 1100))
    })?;
    Ok(())
}

fn write_files(dir: &mut OutputDir, r: &TwinReport, s: &TwinSeries) -> Result<()> {
    let mut csv = String::from(
        "# host-sim estimate: t [s], true and estimated root stress [Pa], measured tip acceleration [m/s^2], estimated tip load [N]\n\
         t,stress_true,stress_estimated,tip_accel_measured,load_estimated\n",
    );
    for i in 0..s.time.len() {
        csv.push_str(&format!(
            "{:.3},{:.6e},{:.6e},{:.6e},{:.6e}\n",
            s.time[i], s.truth[i], s.estimate[i], s.measured[i], s.load[i]
        ));
    }
    dir.write("estimate.csv", &csv)?;
    dir.write("estimate.json", &serde_json::to_string_pretty(r)?)?;
    let mpa = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time.iter().zip(v).map(|(t, x)| (*t, x / 1e6)).collect()
    };
    // The whole run, and a 20 s window in the middle of it.
    let t_end = s.time.last().copied().unwrap_or(0.0);
    let (w0, w1) = (0.5 * t_end - 10.0, 0.5 * t_end + 10.0);
    let window = |v: &[f64]| -> Vec<(f64, f64)> {
        mpa(v)
            .into_iter()
            .filter(|(t, _)| *t >= w0 && *t <= w1)
            .collect()
    };
    let panels = [
        Panel::new(
            "root stress, whole run",
            "t [s]",
            "stress [MPa]",
            vec![
                Series::line("truth (full solver, N = 16)", mpa(&s.truth)).colored(0),
                Series::line("estimate (core, N = 3, f32)", mpa(&s.estimate)).colored(1),
            ],
        ),
        Panel::new(
            "root stress, 20 s window",
            "t [s]",
            "stress [MPa]",
            vec![
                Series::line("truth", window(&s.truth)).colored(0),
                Series::line("estimate", window(&s.estimate)).colored(1),
            ],
        ),
    ];
    dir.write_with("estimate_stress.png", |p| {
        render(
            p,
            "root stress: truth and estimate from the tip accelerometer",
            &panels,
            2,
            1,
            (1200, 900),
        )
    })?;
    let h = &r.histogram;
    let bars = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .enumerate()
            .filter(|(_, c)| **c > 0.0)
            .map(|(i, c)| ((i as f64 + 0.5) * h.bin_mpa, c.log10()))
            .collect()
    };
    let hist = [Panel::new(
        "rainflow stress ranges",
        "range [MPa]",
        "log10 cycles per bin",
        vec![
            Series::marked("truth", bars(&h.truth)).colored(0),
            Series::marked("estimate", bars(&h.estimate)).colored(1),
        ],
    )];
    dir.write_with("estimate_histogram.png", |p| {
        render(p, "stress-range histogram", &hist, 1, 1, (900, 600))
    })?;
    Ok(())
}
