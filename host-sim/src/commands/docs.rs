//! `stability`, `accuracy`, `validation`: the studies that write docs/.

use crate::cli::ValidationArgs;
use crate::output::PointsFailed;
use anyhow::{bail, Result};

pub fn stability(a: &crate::stability::StabilityArgs) -> Result<()> {
    if !(a.drift_duration.is_finite() && a.drift_duration > 0.0) {
        bail!(
            "invalid value for `--drift-duration`: {} (must be finite and positive) [s]",
            a.drift_duration
        );
    }
    if a.jobs == Some(0) {
        bail!("invalid value for `--jobs`: 0 (must be at least 1)");
    }
    if a.only.is_some()
        && (a.out == std::path::Path::new("docs/stability.md") || is_the_document(&a.out))
    {
        bail!(
            "`--only` runs a subset of the matrix, which must not replace docs/stability.md: give \
             `--out` another file (e.g. --out /tmp/stability-subset.md)"
        );
    }
    crate::stability::command(a)
}

pub fn accuracy(a: &crate::accuracy::AccuracyArgs) -> Result<()> {
    if a.repeats == Some(0) {
        bail!("invalid value for `--repeats`: 0 (must be at least 1)");
    }
    crate::accuracy::run(a)
}

pub fn validation(a: &ValidationArgs) -> Result<()> {
    let t0 = std::time::Instant::now();
    let failed = crate::validation::write(&a.out, &a.img, a.converged, &|stage| {
        eprintln!("validation: {stage}…")
    })?;
    eprintln!(
        "validation: wrote {} in {:.1} s",
        a.out.display(),
        t0.elapsed().as_secs_f64()
    );
    if failed > 0 {
        return Err(PointsFailed(format!(
            "{failed} validation sweep run(s) failed (marked FAILED in {} and its figure)",
            a.out.display()
        ))
        .into());
    }
    Ok(())
}

/// `path` is docs/stability.md (of the working directory or of this workspace), however spelt.
fn is_the_document(path: &std::path::Path) -> bool {
    let canon = |p: &std::path::Path| -> Option<std::path::PathBuf> {
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => std::path::Path::new("."),
        };
        Some(std::fs::canonicalize(parent).ok()?.join(p.file_name()?))
    };
    let Some(target) = canon(path) else {
        return false;
    };
    let ours = [
        std::path::PathBuf::from("docs/stability.md"),
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/stability.md"),
    ];
    ours.iter().any(|p| canon(p) == Some(target.clone()))
}
