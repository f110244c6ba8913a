//! `calibrate` and `identify`: the reduced model fitted to the converged one or to a measured
//! pole ([`absorber_sim::calibrate`], [`absorber_sim::identify`]).

use super::{describe, load};
use crate::cli::{CalibrateArgs, IdentifyArgs};
use absorber_sim::calibrate::{fit, fit_damping, fit_f1, reference, Characteristics, DampingFit};
use absorber_sim::calibrate::{residual_line, residual_quality, MAX_RESIDUAL};
use absorber_sim::identify::{identify as identify_record, read_csv, Grade, Identified, Verdict};
use absorber_sim::output::{OutputDir, Status};
use absorber_sim::scene::{CalibrationSection, DampingSection, ExcitationType, ELEMENTS};
use anyhow::{bail, Context, Result};
use serde_json::json;

/// Largest reference mesh (the full solver's cost grows with it; 16 is converged to 1e-6).
const MAX_REFERENCE_ELEMENTS: usize = 256;

fn row(name: &str, unit: &str, r: f64, u: f64, c: f64) -> String {
    let e = |x: f64| 100.0 * (x / r - 1.0);
    format!(
        "{:<22} {:>14.7} {:>14.7} {:>+9.4} % {:>14.7} {:>+9.4} %",
        format!("{name} [{unit}]"),
        r,
        u,
        e(u),
        c,
        e(c)
    )
}

fn table(reference: &Characteristics, un: &Characteristics, cal: &Characteristics) -> String {
    let mut s = format!(
        "{:<22} {:>14} {:>14} {:>11} {:>14} {:>11}\n",
        "quantity", "reference", "uncalibrated", "error", "calibrated", "error"
    );
    s += &row("f1, ball locked", "Hz", reference.f1, un.f1, cal.f1);
    s.push('\n');
    s += &row("f2, ball locked", "Hz", reference.f2, un.f2, cal.f2);
    s.push('\n');
    if let (Some(r), Some(u), Some(c)) = (reference.free, un.free, cal.free) {
        s += &row("free-ball beam mode", "Hz", r, u, c);
        s.push('\n');
    }
    s += &row(
        "static tip sag",
        "mm",
        -reference.sag * 1e3,
        -un.sag * 1e3,
        -cal.sag * 1e3,
    );
    s.push('\n');
    s
}

pub fn calibrate(a: &CalibrateArgs) -> Result<()> {
    let mut s = load(&a.scene)?;
    let n = s.file.elements;
    if !ELEMENTS.contains(&n) {
        bail!("invalid value for `elements`: {n} (the core is built for {ELEMENTS:?} elements)");
    }
    let m = a.reference_elements;
    if m <= n || m > MAX_REFERENCE_ELEMENTS {
        bail!(
            "invalid value for `--reference-elements`: {m} (must lie in {} ..= {MAX_REFERENCE_ELEMENTS}: the reference is the converged model the {n}-element model is fitted to, so it must be finer; 16 is converged to 1e-6)",
            n + 1
        );
    }
    let targets = match &a.from_identified {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read `{}`", path.display()))?;
            let id: Identified = toml::from_str(&text).with_context(|| {
                format!(
                    "invalid value for `--from-identified`: `{}` is not a file written by `identify`",
                    path.display()
                )
            })?;
            let mut why = id.reasons.clone();
            if why.is_empty() {
                why = id.check(None);
            }
            if id.verdict == Verdict::Unusable || !why.is_empty() {
                bail!(
                    "invalid value for `--from-identified`: `{}` holds an unusable identification ({})",
                    path.display(),
                    why.join("; ")
                );
            }
            Some((Some(id.f1), Some(id.zeta)))
        }
        None if a.target_f1.is_some() || a.target_zeta.is_some() => {
            Some((a.target_f1, a.target_zeta))
        }
        None => None,
    };
    // Checked (and locked) before the computation.
    let (mut dir, name) = OutputDir::for_file(&a.out, "calibrate")?;
    let (reference, free_index) = reference(&s, m)?;
    let fit = fit(&s, n, &reference, free_index)?;
    let quality = residual_quality(fit.worst(), fit.capped);
    if quality.grade == Grade::Failed {
        bail!(
            "the calibration does not fit the {m}-element reference: {}, after {} Levenberg–Marquardt iterations{} (at most {MAX_RESIDUAL:.0e}{}); no scene written. A {n}-element model fits a converged reference to below 1e-3 (docs/model.md, \"Calibration\"): check `--reference-elements` (16 is converged) and the scene's beam",
            residual_line(&quality),
            fit.iterations,
            if fit.capped { ", the iteration cap" } else { "" },
            if fit.capped { ", or 1e-3 at the cap" } else { "" },
        );
    }
    let mut params = s.params()?;
    params.calibration = fit.calibration;
    let mut pole = None;
    let mut damping: Option<DampingFit> = None;
    if let Some((f1, zeta)) = targets {
        let mut f_model = absorber_sim::calibrate::scene_beam_mode(&s, &params, fit.model.f1)?;
        if let Some(f1) = f1 {
            f_model = fit_f1(&s, &mut params, f1)?;
        }
        if let Some(z) = zeta {
            let i = &s.file.integrator;
            let d = fit_damping(f_model, z, i.gamma, i.beta, i.step)?;
            s.file.integrator.gamma = d.gamma;
            s.file.integrator.beta = d.beta;
            s.file.damping = DampingSection {
                stiffness_proportional: None,
                ratio: Some(d.structural_ratio),
                frequency: Some(f_model),
            };
            damping = Some(d);
        }
        pole = Some((f1, zeta, f_model));
    }
    s.file.calibration = CalibrationSection::from(&params.calibration);
    s.file.calibration.elements = Some(n);
    s.file.name = format!("{}-calibrated-n{n}", s.file.name);
    // A relative excitation file refers to the scene's directory: keep it reachable.
    if s.file.excitation.kind == ExcitationType::Csv {
        if let Some(f) = &s.file.excitation.file {
            if f.is_relative() {
                s.file.excitation.file = Some(std::path::absolute(s.base_dir.join(f))?);
            }
        }
    }
    s.validate()?;
    let mut header = format!(
        "# Written by `host-sim calibrate`: {n} elements calibrated against the full solver with {m}\n\
         # elements (uncalibrated): f1 and f2 with the ball locked, the free-ball beam mode, the static\n\
         # sag. Fit: {}. Physics of the factors: docs/model.md, \"Calibration\".\n",
        residual_line(&quality)
    );
    if let Some((f1, zeta, fm)) = pole {
        header += &format!(
            "# Then fitted to a measured pole: f1 = {} Hz, zeta = {} (model beam mode {fm:.6} Hz).\n",
            f1.map(|v| format!("{v}")).unwrap_or("-".into()),
            zeta.map(|v| format!("{v}")).unwrap_or("-".into()),
        );
    }
    let text = format!("{header}{}", s.to_toml()?);
    // The file must load as written (the round trip every other command relies on).
    absorber_sim::scene::parse(&text).context("internal: the written scene does not parse")?;
    let path = dir.write(&name, &text)?;
    dir.commit(Status::Complete, serde_json::Value::Null)?;
    if a.json {
        println!(
            "{}",
            json!({
                "scene": s.file.name,
                "elements": n,
                "reference_elements": m,
                "calibration": CalibrationSection::from(&params.calibration),
                "fit": fit,
                "quality": [&quality],
                "errors": fit.model.errors(&reference),
                "pole": pole.map(|(f1, z, fm)| json!({"target_f1": f1, "target_zeta": z, "model_f1": fm})),
                "damping": damping,
                "out": path,
            })
        );
        return Ok(());
    }
    println!("{}", describe(&s));
    println!(
        "reference: full solver, {m} elements, uncalibrated; model: core, {n} elements, f64 ({} Levenberg–Marquardt iterations)",
        fit.iterations
    );
    print!("{}", table(&reference, &fit.uncalibrated, &fit.model));
    let c = &fit.calibration;
    println!(
        "calibration: bending_stiffness = {:.9}, axial_stiffness = {:.9}, mass_lumping = {:.9}",
        c.bending_stiffness, c.axial_stiffness, c.mass_lumping
    );
    println!("{}", residual_line(&quality));
    if let Some((f1, _, fm)) = pole {
        if f1.is_some() {
            println!(
                "measured pole: bending_stiffness = {:.9} puts the beam mode at {fm:.6} Hz",
                params.calibration.bending_stiffness
            );
        }
    }
    if let Some(d) = damping {
        println!(
            "damping at f1: integrator (gamma = {:.4}, beta = {:.4}, h = {} s) {:.4} %, structural {:.4} %, total {:.4} %",
            d.gamma,
            d.beta,
            s.file.integrator.step,
            100.0 * d.numerical_ratio,
            100.0 * d.structural_ratio,
            100.0 * d.total_ratio
        );
        if d.structural_ratio == 0.0 {
            println!(
                "note: the integrator alone damped more than the target; gamma lowered to {:.4} (high modes are then damped less)",
                d.gamma
            );
        }
    }
    println!("wrote {}", path.display());
    Ok(())
}

pub fn identify(a: &IdentifyArgs) -> Result<()> {
    let band = match a.band.as_deref() {
        None => None,
        Some([lo, hi]) => Some((*lo, *hi)),
        Some(v) => bail!(
            "invalid value for `--band`: {} (allowed: two frequencies `lo,hi` [Hz], 0 < lo < hi)",
            v.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
        ),
    };
    let out = match &a.out {
        Some(p) => Some(OutputDir::for_file(p, "identify")?),
        None => None,
    };
    let rec = read_csv(&a.csv, &a.time_column, &a.column)?;
    let id = identify_record(&rec, a.record, band, &a.column)?;
    // `decay` or `ambient`, as the option spells it.
    let kind = format!("{:?}", a.record).to_lowercase();
    let mut written = None;
    if let Some((mut dir, name)) = out {
        let text = format!(
            "# Written by `host-sim identify` from `{}` (column `{}`, {:?} record); 1-sigma\n\
             # uncertainties. Use with `host-sim calibrate --from-identified <this file>`.\n{}",
            a.csv.display(),
            a.column,
            kind,
            toml::to_string(&id)?
        );
        written = Some(dir.write(&name, &text)?);
        dir.commit(Status::Complete, serde_json::Value::Null)?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&id)?);
    } else {
        println!(
            "record {} column {}: {} samples at {} s ({kind} record)",
            a.csv.display(),
            a.column,
            rec.x.len(),
            rec.dt,
        );
        println!(
            "f1   = {:.6} ± {:.6} Hz ({:.3} %)",
            id.f1,
            id.f1_uncertainty,
            100.0 * id.f1_uncertainty / id.f1
        );
        println!(
            "zeta = {:.6} ± {:.6} ({:.4} % ± {:.4} %)",
            id.zeta,
            id.zeta_uncertainty,
            100.0 * id.zeta,
            100.0 * id.zeta_uncertainty
        );
        println!(
            "fit window {:.3} … {:.3} s{}",
            id.window.0,
            id.window.1,
            if id.triggers > 0 {
                format!(", {} random-decrement triggers", id.triggers)
            } else {
                String::new()
            }
        );
        for q in &id.quality {
            println!(
                "{:<17} {:>8.3} {:<18} expected {:<40} {}",
                q.figure,
                q.value,
                q.unit,
                q.expected,
                q.grade.word()
            );
        }
        // The worst grade says how far to trust a usable result.
        let worst = id.quality.iter().map(|q| q.grade).max_by_key(|g| *g as u8);
        let weak: Vec<&str> = id
            .quality
            .iter()
            .filter(|q| Some(q.grade) == worst && q.grade != Grade::Ok)
            .map(|q| q.figure.as_str())
            .collect();
        match id.verdict {
            Verdict::Usable if weak.is_empty() => println!("verdict: usable (every figure ok)"),
            Verdict::Usable => println!(
                "verdict: usable, with care: {} {}",
                weak.join(", "),
                worst.map_or("", |g| g.word())
            ),
            Verdict::Unusable => println!("verdict: UNUSABLE ({})", id.reasons.join("; ")),
        }
        if let Some(p) = written {
            println!("wrote {}", p.display());
        }
    }
    if id.verdict == Verdict::Unusable {
        bail!(
            "no usable pole in `{}` column `{}`: {}",
            a.csv.display(),
            a.column,
            id.reasons.join("; ")
        );
    }
    Ok(())
}
