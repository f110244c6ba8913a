//! `absorber-studies stability`: the command that runs the matrix and writes the page.

use super::*;

/// `absorber-studies stability`: runs the matrix and the drift study, writes `docs/stability.md`.
#[derive(clap::Args, Debug, Clone)]
pub struct StabilityArgs {
    /// Markdown output.
    #[arg(long, default_value = "docs/stability.md")]
    pub out: std::path::PathBuf,
    /// Short runs only (the subset of `cargo test`), no long runs, no drift study.
    #[arg(long)]
    pub quick: bool,
    /// Only cases whose group or name contains this text. A subset never replaces
    /// docs/stability.md: give `--out` another file.
    #[arg(long)]
    pub only: Option<String>,
    /// Length of the drift study [s] (f32 beside f64 at 3.70 Hz).
    #[arg(long, default_value_t = 3600.0)]
    pub drift_duration: f64,
    /// Parallel cases (default: available cores, at most 2).
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// Runs cases on `jobs` threads (each case in its own big-stack thread), in order. Each worker
/// keeps what it ran and hands it back when joined (a worker that panicked leaves its cases at
/// their default outcome).
pub fn run_all(
    cases: &[Case],
    jobs: usize,
    progress: impl Fn(&Case, &Outcome) + Sync,
) -> Vec<Outcome> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<Outcome>> = vec![None; cases.len()];
    std::thread::scope(|s| {
        let workers: Vec<_> = (0..jobs.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(c) = cases.get(i) else { break };
                        let o = run_case(c);
                        progress(c, &o);
                        done.push((i, o));
                    }
                    done
                })
            })
            .collect();
        for w in workers {
            for (i, o) in w.join().unwrap_or_default() {
                if let Some(r) = results.get_mut(i) {
                    *r = Some(o);
                }
            }
        }
    });
    results.into_iter().map(Option::unwrap_or_default).collect()
}

/// The command.
pub fn command(args: &StabilityArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let length = if args.quick {
        Length::Quick
    } else {
        Length::Full
    };
    // The document's directory: writable and ours before hours of computation.
    let (mut out_dir, out_name) =
        absorber_sim::output::OutputDir::for_file(&args.out, "stability")?;
    let mut cases = matrix(length);
    if let Some(only) = &args.only {
        cases.retain(|c| c.group.contains(only.as_str()) || c.name.contains(only.as_str()));
        if cases.is_empty() {
            anyhow::bail!(
                "invalid value for `--only`: `{only}` (no case's group or name contains it; the groups: {})",
                {
                    let mut g: Vec<&str> = matrix(length).iter().map(|c| c.group).collect();
                    g.sort_unstable();
                    g.dedup();
                    g.join(", ")
                }
            );
        }
    }
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .min(2)
    });
    eprintln!("stability: {} cases on {jobs} threads", cases.len());
    let outcomes = run_all(&cases, jobs, |c, o| {
        eprintln!(
            "  {} {:<45} {:<8} start {:>9} margin {:>9} at {:>7.3} floor/scale {:>8} iters {:>3}/{:.2} {:.1} s{}",
            match (o.passes(&c.expect), c.known_issue) {
                (true, _) => "ok  ",
                (false, Some(_)) => "KNOWN",
                (false, None) => "FAIL",
            },
            c.name,
            c.engine.name(),
            fmt_e(o.margin_startup),
            fmt_e(o.margin),
            o.excess_at,
            fmt_e(o.floor / o.scale),
            o.max_iterations,
            o.mean_iterations,
            o.seconds,
            o.error.as_deref().map(|e| format!(" [{e}]")).unwrap_or_default()
        );
    });
    let results: Vec<(Case, Outcome)> = cases.into_iter().zip(outcomes).collect();
    let failed = results
        .iter()
        .filter(|(c, o)| !o.passes(&c.expect) && c.known_issue.is_none())
        .count();
    let drift_windows = if args.quick || args.drift_duration <= 0.0 {
        None
    } else {
        eprintln!(
            "stability: drift study, {} s at 3.70 Hz",
            args.drift_duration
        );
        Some(drift(3.70, args.drift_duration, 300.0).map_err(anyhow::Error::from)?)
    };
    let md = report(
        &results,
        drift_windows.as_deref(),
        args,
        t0.elapsed().as_secs_f64(),
    );
    out_dir.write(&out_name, &md)?;
    out_dir.commit(
        absorber_sim::output::Status::Complete,
        serde_json::Value::Null,
    )?;
    let known = results
        .iter()
        .filter(|(c, o)| !o.passes(&c.expect) && c.known_issue.is_some())
        .count();
    println!(
        "{} cases: {} as expected, {known} known issues (reported), {failed} unexpected; wrote {}",
        results.len(),
        results.len() - failed - known,
        args.out.display()
    );
    if failed > 0 {
        anyhow::bail!(
            "{failed} stability case(s) did not behave as expected (see {})",
            args.out.display()
        );
    }
    Ok(())
}
