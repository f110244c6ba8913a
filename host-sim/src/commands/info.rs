//! `static`, `modes`, `tune`: the linearized model, printed.

use super::{describe, load};
use crate::cli::{InfoArgs, ModesArgs, TuneArgs};
use absorber_sim::output::{OutputDir, Status};
use absorber_sim::scene::Scene;
use absorber_sim::simulate::linear::{lowest_frequencies, static_summary, structure};
use absorber_sim::tune::tune;
use anyhow::{bail, Result};
use serde_json::json;

use absorber_sim::tune::ARM_ELEMENTS;

/// The line that says which structure an arm scene's figures describe.
fn arm_note(s: &Scene) -> Option<String> {
    s.file.arm.as_ref().map(|_| {
        format!(
            "structure                  the [arm]: tapered tube with its heads, full solver, {ARM_ELEMENTS} elements, f64 (as `tune`)"
        )
    })
}

pub fn static_cmd(a: &InfoArgs) -> Result<()> {
    let s = load(&a.scene.scene_args())?;
    let summary = static_summary(&s)?;
    let d = summary["static_tip_deflection"]
        .as_f64()
        .unwrap_or(f64::NAN);
    if a.json {
        println!("{summary}");
    } else {
        println!("{}", describe(&s));
        if let Some(n) = arm_note(&s) {
            println!("{n}");
        }
        println!("static tip deflection: {d:.6e} m ({:.3} mm)", d * 1e3);
    }
    Ok(())
}

pub fn modes(a: &ModesArgs) -> Result<()> {
    if a.count == 0 {
        anyhow::bail!("invalid value for `--count`: 0 (must be at least 1)");
    }
    let s = load(&a.scene.scene_args())?;
    let (sim, elements) = structure(&s)?;
    let f = lowest_frequencies(&s, a.count)?;
    let p = s.params()?;
    // Damping per mode: the structure's (C = c K: ζ = c ω / 2) and the integrator's own.
    let structural: Vec<f64> = f
        .iter()
        .map(|x| p.damping.stiffness_proportional * std::f64::consts::PI * x)
        .collect();
    let numerical: Vec<Option<f64>> = f
        .iter()
        .map(|x| absorber_sim::integrator::numerical_damping(&p.integrator, *x))
        .collect();
    if a.json {
        println!(
            "{}",
            json!({ "scene": s.file.name, "kind": s.file.kind.name(), "arm": s.file.arm.is_some(), "elements": elements, "solver": sim.solver_name(), "frequencies": f, "structural_damping": structural, "numerical_damping": numerical })
        );
    } else {
        println!("{}", describe(&s));
        if let Some(n) = arm_note(&s) {
            println!("{n}");
        }
        // C = c K_bending: ζ = c ω / 2 holds for the bending modes; the axial modes (the
        // highest ones, kHz) get no structural damping.
        println!("mode  frequency [Hz]  damping ratio: structural (c ω/2, bending)  numerical (integrator)");
        for (i, x) in f.iter().enumerate() {
            let num = match numerical[i] {
                Some(z) => format!("{z:.3e}"),
                None => "not resolved by the step".into(),
            };
            println!(
                "{:>4}  {x:>14.4}  {:>40.3e}  {num:>22}",
                i + 1,
                structural[i]
            );
        }
        if s.file.kind.free_ball() {
            println!(
                "(ball on a fixed housing: {:.4} Hz)",
                p.ball.fixed_housing_frequency(p.gravity)
            );
        }
    }
    Ok(())
}

pub fn tune_cmd(a: &TuneArgs) -> Result<()> {
    let s = load(&a.scene.scene_args())?;
    if !a.ratio.is_finite() || a.ratio <= 0.0 {
        bail!(
            "invalid value for `--ratio`: {} (must be finite and positive)",
            a.ratio
        );
    }
    if s.file.arm.is_some() {
        if a.write.is_some() {
            bail!(
                "`--write` writes the tuned track radius into a `[ball]` scene; an `[arm]` scene (`{}`) gets the ball it would need printed, not a scene",
                a.scene.scene
            );
        }
        // A real arm: the ball this scale would need, and whether it fits in a signal head.
        let t = absorber_sim::tune::arm_track_radius(&s, a.ratio)?;
        if a.json {
            println!("{}", serde_json::to_string(&t)?);
        } else {
            println!("{}", describe(&s));
            println!(
                "arm first frequency        {:.4} Hz (full solver, 16 elements)",
                t.arm_frequency
            );
            println!(
                "ball at {} × f1            {:.4} Hz needs track radius R = {:.0} mm (ρ = R − r_b = {:.0} mm)",
                a.ratio,
                t.ball_frequency,
                t.track_radius * 1e3,
                t.path_radius * 1e3
            );
            if !t.buildable_in_signal_head {
                println!(
                    "NOT BUILDABLE in a signal head: the track needs {:.0} mm of free space, a head offers about {:.0} mm",
                    2e3 * t.track_radius,
                    1e3 * absorber_sim::tune::SIGNAL_HEAD_SPACE
                );
            }
        }
        return Ok(());
    }
    // The output directory is checked (and locked) before the computation.
    let out = match &a.write {
        Some(path) => {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default();
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => std::path::PathBuf::from("."),
            };
            Some((OutputDir::open(&dir, None, "tune")?, name))
        }
        None => None,
    };
    let t = tune(&s, a.ratio)?;
    if let Some((mut dir, name)) = out {
        let mut tuned = s.clone();
        tuned.file.name = "tuned".into();
        tuned.file.ball.track_radius = (t.track_radius * 1e9).round() / 1e9;
        let text = format!(
            "# Paper scene with the track radius tuned by `host-sim tune` so that the ball's frequency is\n\
             # {} × the beam's first frequency in the coupled linearized model ({:.4} Hz / {:.4} Hz).\n{}",
            a.ratio,
            t.ball_frequency,
            t.beam_frequency,
            tuned.to_toml()?
        );
        dir.write(&name, &text)?;
        dir.commit(Status::Complete, serde_json::Value::Null)?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&t)?);
    } else {
        println!("{}", describe(&s));
        println!(
            "tuned track radius R       {:.6} mm (ρ = R − r_b = {:.6} mm)",
            t.track_radius * 1e3,
            t.path_radius * 1e3
        );
        println!(
            "coupled model              ball {:.4} Hz, beam {:.4} Hz, ratio {:.6}",
            t.ball_frequency, t.beam_frequency, t.ratio
        );
        println!(
            "ball on a fixed housing    {:.4} Hz;  locked-ball first frequency {:.4} Hz",
            t.fixed_housing_frequency, t.locked_frequency
        );
        if let Some(p) = &a.write {
            println!("wrote {}", p.display());
        }
    }
    Ok(())
}
