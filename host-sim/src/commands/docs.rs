//! `stability`, `accuracy`, `validation`: the studies that write docs/.

use crate::cli::ValidationArgs;
use crate::output::PointsFailed;
use anyhow::{bail, Result};

pub fn stability(a: &crate::stability::StabilityArgs) -> Result<()> {
    if a.only.is_some() && a.out == std::path::Path::new("docs/stability.md") {
        bail!(
            "`--only` runs a subset of the matrix, which must not replace docs/stability.md: give \
             `--out` another file (e.g. --out /tmp/stability-subset.md)"
        );
    }
    crate::stability::command(a)
}

pub fn accuracy(a: &crate::accuracy::AccuracyArgs) -> Result<()> {
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
