//! The regimes × sensor sets × estimators table of `docs/monitoring.md`
//! (`absorber-studies monitoring`): the lab study off the absorber's tuning and at its
//! working point, and the mast arm's scenes of `scenes/` (first-mode wind, von Kármán wind,
//! second-mode vortex lock-in read by a ±8 g and by the shipped ±2 g accelerometer).

use absorber_sim::estimate::lab::EnsembleEstimator;
use absorber_sim::estimate::EstimatorReport;
use absorber_sim::scene::Scene;
use anyhow::{Context, Result};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// The lab study's forcing frequencies \[Hz\] and their regimes.
pub const LAB: [(f64, &str); 4] = [
    (3.70, "lab, off tuning (3.70 Hz)"),
    (4.05, "lab, working point (4.05 Hz)"),
    (4.10, "lab, working point (4.10 Hz)"),
    (4.13, "lab, working point (4.13 Hz)"),
];

/// Realizations of the lab study at the working point (the free ball is chaotic there: doc
/// of [`absorber_sim::estimate::lab::LabEnsemble`]); off tuning one.
pub const LAB_MEMBERS: u32 = 4;

/// The arm's scenes (in `scenes/`) and their regimes.
pub const ARM: [(&str, &str); 4] = [
    ("mast-arm.toml", "mast arm, first-mode wind"),
    ("mast-arm-von-karman.toml", "mast arm, von Kármán wind"),
    (
        "mast-arm-second-mode.toml",
        "mast arm, second-mode lock-in, ±8 g",
    ),
    (
        "mast-arm-second-mode-2g.toml",
        "mast arm, second-mode lock-in, ±2 g (clips)",
    ),
];

/// One regime's results.
#[derive(Clone, Debug, Serialize)]
pub struct Regime {
    /// What it is.
    pub regime: String,
    /// Top-level verdict (the filter with all the scene's sensors).
    pub verdict: &'static str,
    /// Its estimators (the lab's: realization 0).
    pub estimators: Vec<EstimatorReport>,
    /// Realizations (1: one run).
    pub members: u32,
    /// The lab's estimators over its realizations (empty for the arm).
    pub ensemble: Vec<EnsembleEstimator>,
}

/// The scene `name` of `scenes/` (from the working directory, else the workspace's).
fn scene_file(name: &str) -> std::path::PathBuf {
    let here = Path::new("scenes").join(name);
    if here.exists() {
        here
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("scenes")
            .join(name)
    }
}

/// The rows of an ensemble regime: each figure's mean with its least and greatest, the NIS
/// mean ± sd, the pooled verdict and the members' verdicts.
fn ensemble_rows(md: &mut String, g: &Regime) {
    for e in &g.ensemble {
        let nis = if e.nis.mean.is_finite() {
            format!("{:.2} ± {:.2}", e.nis.mean, e.nis.sd)
        } else {
            "–".into()
        };
        let [ok, degraded, failed] = e.member_verdicts;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.1} % ({:.1}–{:.1}) | {:.3} ({:.3}–{:.3}) | {} | {} ({ok} / {degraded} / {failed}) |",
            g.regime,
            e.truth,
            e.estimator,
            e.model,
            e.sensors.join(" + "),
            e.stress_rms_error_pct.mean,
            e.stress_rms_error_pct.min,
            e.stress_rms_error_pct.max,
            e.damage_ratio.mean,
            e.damage_ratio.min,
            e.damage_ratio.max,
            nis,
            e.verdict
        );
    }
}

/// The markers between which [`write`] puts the table in an existing file.
pub const BEGIN: &str = "<!-- absorber-studies monitoring: begin (generated, do not edit) -->";
/// See [`BEGIN`].
pub const END: &str = "<!-- absorber-studies monitoring: end -->";

/// The text of `path` with the table `md` between [`BEGIN`] and [`END`] (a file without the
/// markers, or none, gets the table alone).
fn splice(path: &Path, md: &str) -> Result<String> {
    let old = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    match (old.find(BEGIN), old.find(END)) {
        (Some(a), Some(b)) if a < b => Ok(format!("{}{BEGIN}\n{md}{}", &old[..a], &old[b..])),
        (None, None) => Ok(md.to_string()),
        _ => anyhow::bail!(
            "{}: the table's markers are broken (`{BEGIN}` must come before `{END}`)",
            path.display()
        ),
    }
}

/// Runs every regime (`duration` overrides the scenes' and the lab's 60 s) and writes the
/// markdown table to `path` (between [`BEGIN`] and [`END`] if the file has them, e.g.
/// `docs/monitoring.md`) and the JSON beside it (`.json`).
pub fn write(path: &Path, duration: Option<f64>) -> Result<()> {
    let mut regimes = Vec::new();
    for (f, name) in LAB {
        eprintln!("monitoring: {name} …");
        let mut scene = Scene::paper();
        scene.file.excitation.frequency = Some(f);
        let members = if f < 4.0 { 1 } else { LAB_MEMBERS };
        let mut ens = absorber_sim::estimate::lab::lab_ensemble(
            &scene,
            duration.unwrap_or(60.0),
            0.05,
            absorber_sim::estimate::BaselineLoad::default(),
            members,
        )?;
        let r = ens.reports.swap_remove(0);
        regimes.push(Regime {
            regime: name.into(),
            verdict: r.verdict,
            estimators: r.estimators,
            members,
            ensemble: ens.estimators,
        });
    }
    for (file, name) in ARM {
        eprintln!("monitoring: {name} …");
        let scene = Scene::load(scene_file(file).to_string_lossy().as_ref())
            .with_context(|| format!("scene {file}"))?;
        let d = duration.unwrap_or(scene.file.duration);
        let (r, _) = absorber_sim::estimate::twin(
            &scene,
            d,
            absorber_sim::estimate::BaselineLoad::default(),
        )?;
        regimes.push(Regime {
            regime: name.into(),
            verdict: r.verdict,
            estimators: r.estimators,
            members: 1,
            ensemble: Vec::new(),
        });
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| regime | truth | estimator | model | sensors | stress RMS error | damage ratio | NIS | verdict |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---:|---:|---:|---|");
    for g in &regimes {
        if g.members > 1 {
            ensemble_rows(&mut md, g);
            continue;
        }
        for e in &g.estimators {
            let nis = if e.nis.is_finite() {
                format!("{:.2}", e.nis)
            } else {
                "–".into()
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {:.1} % | {:.3} | {} | {} |",
                g.regime,
                e.truth,
                e.estimator,
                e.model,
                e.sensors.join(" + "),
                e.stress_rms_error_pct,
                e.damage_ratio,
                nis,
                e.verdict
            );
        }
    }
    let _ = writeln!(
        md,
        "\nWorking-point rows: mean (least–greatest) over {LAB_MEMBERS} realizations (sensor seeds and 10⁻¹² rad of the truth's initial ball angle), NIS mean ± sd, the verdict on the pooled samples and the members' verdicts (ok / degraded / failed)."
    );
    let text = splice(path, &md)?;
    absorber_sim::output::atomic_write(path, text.as_bytes())?;
    let json = path.with_extension("json");
    absorber_sim::output::atomic_write(&json, serde_json::to_string_pretty(&regimes)?.as_bytes())?;
    eprintln!(
        "monitoring: wrote {} and {}",
        path.display(),
        json.display()
    );
    Ok(())
}
