//! `absorber-studies accuracy`: the whole study and the generated `docs/accuracy.md`.

mod page;

use page::Ctx;

use super::*;
use anyhow::{Context, Result};
use clap::Args;
use rayon::prelude::*;

/// `accuracy`.
#[derive(Args, Debug, Clone)]
pub struct AccuracyArgs {
    /// CI-sized run: 10 s scenes, coarser reference (N = 8, h = 1 ms), fewer repetitions.
    #[arg(long)]
    pub quick: bool,
    /// Cache of the reference trajectories (default `$CARGO_TARGET_DIR/accuracy-cache` or
    /// `target/accuracy-cache`).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Where `accuracy.md` and `img/` go (default: the workspace's `docs/`; with `--quick`,
    /// `<cache>/quick-report/`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Timing repetitions per candidate (median).
    #[arg(long)]
    pub repeats: Option<usize>,
    /// Print each candidate's label and its `fw-cost` arguments (tab-separated) and stop: the
    /// list `scripts/accuracy-cost.sh` counts instructions for.
    #[arg(long)]
    pub firmware_configs: bool,
}

/// Sizes of one study.
#[derive(Clone, Debug)]
struct Plan {
    duration: f64,
    last: f64,
    n_ref: usize,
    h_ref: f64,
    conv_n: Vec<usize>,
    conv_h: Vec<f64>,
    conv_t: f64,
    timing_seconds: f64,
    repeats: usize,
}

fn plan(a: &AccuracyArgs) -> Plan {
    if a.quick {
        Plan {
            duration: 10.0,
            last: 5.0,
            n_ref: 8,
            h_ref: 0.001,
            conv_n: vec![3, 4, 8],
            conv_h: vec![0.002, 0.001],
            conv_t: 2.0,
            timing_seconds: 2.0,
            repeats: a.repeats.unwrap_or(3),
        }
    } else {
        Plan {
            duration: 60.0,
            last: 20.0,
            n_ref: 8,
            h_ref: 0.0005,
            conv_n: vec![3, 4, 6, 8, 12, 16],
            conv_h: vec![0.002, 0.001, 0.0005, 0.00025],
            conv_t: 5.0,
            timing_seconds: 10.0,
            repeats: a.repeats.unwrap_or(7),
        }
    }
}

/// The candidates: one factor at a time around [`Config::DEFAULT`], then combinations.
pub fn candidates() -> Vec<Config> {
    let d = Config::DEFAULT;
    let mut v = vec![d];
    for n in [1, 2, 4, 6] {
        v.push(d.with(|c| c.elements = n));
    }
    for h in [0.001, 0.002, 0.005, 0.010] {
        v.push(d.with(|c| c.step = h));
    }
    v.push(d.with(|c| c.f32 = false));
    for k in [1, 2, 3] {
        v.push(d.with(|c| c.newton = Newton::Budget(k)));
    }
    v.push(d.with(|c| c.newton = Newton::Modified));
    // Combinations.
    v.push(d.with(|c| c.rule = Rule::Paper).with(|c| c.step = 0.001));
    v.push(d.with(|c| {
        c.elements = 4;
        c.step = 0.002;
    }));
    v.push(d.with(|c| {
        c.elements = 4;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| {
        c.elements = 4;
        c.step = 0.002;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| {
        c.newton = Newton::Budget(2);
        c.step = 0.002;
    }));
    v.push(d.with(|c| {
        c.elements = 2;
        c.step = 0.005;
        c.newton = Newton::Budget(2);
    }));
    v.push(d.with(|c| {
        c.elements = 6;
        c.step = 0.001;
        c.f32 = false;
    }));
    v.push(d.with(|c| {
        c.elements = 4;
        c.step = 0.001;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| {
        c.elements = 6;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| {
        c.elements = 6;
        c.step = 0.005;
    }));
    v.push(d.with(|c| {
        c.elements = 6;
        c.step = 0.005;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| {
        c.elements = 4;
        c.step = 0.005;
        c.newton = Newton::Modified;
    }));
    v.push(d.with(|c| c.elements = 6).with(|c| c.f32 = false));
    v
}

/// One candidate's results.
#[derive(Clone, Debug)]
struct Row {
    cfg: Config,
    f1: f64,
    errors: Vec<Errors>,
    failures: Vec<Option<String>>,
    iterations_per_step: Vec<f64>,
    time: f64,
    /// Host time over the default's, paired interleaved median.
    ratio: f64,
    /// Cortex-M4F instructions per simulated second (docs/accuracy-cost.json), if counted.
    m4: Option<f64>,
}

/// Every candidate: [`candidates`] and the calibrated ones (fitted to the converged full
/// solver, N = 16).
fn all_candidates() -> Result<Vec<Config>> {
    let mut cands = candidates();
    for n in [2, 3, 4, 6] {
        cands.push(calibrated(Config::DEFAULT.with(|c| c.elements = n), 16)?);
    }
    // Events at the step end (the bounded worst step), default and calibrated N = 3.
    cands.push(Config::DEFAULT.with(|c| c.step_end = true));
    cands.push(calibrated(Config::DEFAULT.with(|c| c.step_end = true), 16)?);
    // The firmware's default: events at the step end and the work cap (section 7).
    cands.push(Config::DEFAULT.with(|c| {
        c.step_end = true;
        c.capped = true;
    }));
    Ok(cands)
}

/// Instructions per step of each configuration on the Cortex-M4F, by label, from
/// `docs/accuracy-cost.json` (written by `scripts/accuracy-cost.sh`; a configuration whose
/// steps fail is costed over all its steps, failed ones included); checked against the
/// arguments it was counted with, so a stale file cannot lend its numbers to a changed
/// configuration.
fn m4_costs() -> std::collections::HashMap<String, (String, f64)> {
    let path = workspace_root().join("docs/accuracy-cost.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Default::default();
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return Default::default();
    };
    v.as_object()
        .map(|o| {
            o.iter()
                .filter_map(|(k, x)| {
                    let args = x.get("args")?.as_str()?.to_string();
                    let ips = x.get("instructions_per_step")?.as_f64()?;
                    Some((k.clone(), (args, ips)))
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Results of the convergence studies.
#[derive(Clone, Debug)]
struct Convergence {
    /// (N, f1, RMS dynamic tip over conv_t, full-solver s per simulated s).
    by_n: Vec<(usize, f64, f64, f64)>,
    /// (h, RMS dynamic tip, max |tip − finest| on the grid).
    by_h: Vec<(f64, f64, f64)>,
    /// Same with the free ball at 3.70 Hz (no impacts): (h, max |tip − finest|, max |θ − finest|).
    by_h_free: Vec<(f64, f64, f64)>,
}

fn rms_dynamic(t: &Trajectory) -> f64 {
    (t.tip
        .iter()
        .map(|x| (x - t.static_tip).powi(2))
        .sum::<f64>()
        / t.tip.len().max(1) as f64)
        .sqrt()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn convergence(p: &Plan, cache: &Path) -> Result<Convergence> {
    let all = scenes();
    let locked = all
        .iter()
        .find(|s| s.name == "locked-4.13")
        .expect("scene list");
    let free = all
        .iter()
        .find(|s| s.name == "free-3.70")
        .expect("scene list");
    let by_n = p
        .conv_n
        .par_iter()
        .map(|&n| -> Result<(usize, f64, f64, f64)> {
            let f1 = full_f1(n)?;
            let t = cached_full(cache, &reference_config(n, p.h_ref), locked, p.conv_t)?;
            Ok((n, f1, rms_dynamic(&t), t.wall / p.conv_t))
        })
        .collect::<Result<Vec<_>>>()?;
    let jobs: Vec<(f64, &TestScene)> = p
        .conv_h
        .iter()
        .flat_map(|&h| [(h, locked), (h, free)])
        .collect();
    let runs = jobs
        .par_iter()
        .map(|&(h, s)| cached_full(cache, &reference_config(p.n_ref, h), s, p.conv_t))
        .collect::<Result<Vec<_>>>()?;
    let finest = |name: &str| {
        jobs.iter()
            .zip(&runs)
            .filter(|(j, _)| j.1.name == name)
            .min_by(|a, b| a.0 .0.total_cmp(&b.0 .0))
            .map(|(_, t)| t.clone())
            .expect("runs")
    };
    let (fl, ff) = (finest(locked.name), finest(free.name));
    let mut by_h = Vec::new();
    let mut by_h_free = Vec::new();
    for (j, t) in jobs.iter().zip(&runs) {
        if j.1.name == locked.name {
            by_h.push((j.0, rms_dynamic(t), max_diff(&t.tip, &fl.tip)));
        } else {
            by_h_free.push((j.0, max_diff(&t.tip, &ff.tip), max_diff(&t.ball, &ff.ball)));
        }
    }
    Ok(Convergence {
        by_n,
        by_h,
        by_h_free,
    })
}

/// Runs the study and writes the report.
pub fn run(a: &AccuracyArgs) -> Result<()> {
    if a.firmware_configs {
        for c in all_candidates()? {
            if let Some(args) = c.firmware_args() {
                println!("{}\t{args}", c.label());
            }
        }
        return Ok(());
    }
    let started = Instant::now();
    let p = plan(a);
    let cache = a.cache.clone().unwrap_or_else(default_cache);
    let out = a.out.clone().unwrap_or_else(|| {
        if a.quick {
            cache.join("quick-report")
        } else {
            workspace_root().join("docs")
        }
    });
    eprintln!(
        "accuracy: cache {}, report {}",
        cache.display(),
        out.display()
    );
    // The report directory writable and ours (one command at a time) before any computation;
    // the files themselves are written atomically.
    let _lock = absorber_sim::output::OutputDir::open(&out, None, "accuracy")?;
    // 1. Convergence of the reference.
    let conv = convergence(&p, &cache)?;
    eprintln!(
        "accuracy: convergence done ({:.0} s)",
        started.elapsed().as_secs_f64()
    );
    // 2. References.
    let all = scenes();
    let rcfg = reference_config(p.n_ref, p.h_ref);
    let refs = all
        .par_iter()
        .map(|s| cached_full(&cache, &rcfg, s, p.duration))
        .collect::<Result<Vec<_>>>()?;
    for (s, r) in all.iter().zip(&refs) {
        if let Some(e) = &r.error {
            anyhow::bail!("reference {} failed: {e}", s.name);
        }
    }
    let f1_ref = full_f1(p.n_ref)?;
    eprintln!(
        "accuracy: references done ({:.0} s)",
        started.elapsed().as_secs_f64()
    );
    // Pointwise window: up to the reference's first impact (chaotic after it).
    let windows: Vec<f64> = refs
        .iter()
        .map(|r| {
            r.impacts
                .first()
                .map(|t| (t / GRID).floor() * GRID)
                .unwrap_or(p.duration)
        })
        .collect();
    // 3. Candidates (in parallel), 4. timing (sequential, after).
    // The calibrated models are fitted to the converged full solver (N = 16).
    let cands = all_candidates()?;
    let jobs: Vec<(usize, usize)> = (0..cands.len())
        .flat_map(|c| (0..all.len()).map(move |s| (c, s)))
        .collect();
    let runs = jobs
        .par_iter()
        .map(|&(c, s)| run_embedded(&cands[c], &all[s], p.duration))
        .collect::<Result<Vec<_>>>()?;
    let f1s = cands
        .par_iter()
        .map(embedded_f1)
        .collect::<Result<Vec<_>>>()?;
    eprintln!(
        "accuracy: candidates done ({:.0} s)",
        started.elapsed().as_secs_f64()
    );
    let timing_scene = all
        .iter()
        .find(|s| s.name == "free-4.13")
        .expect("scene list");
    let costs = m4_costs();
    let mut rows = Vec::new();
    for (c, cfg) in cands.iter().enumerate() {
        let time = time_per_second(cfg, timing_scene, p.timing_seconds, p.repeats)?;
        let ratio = paired_ratio(
            cfg,
            &Config::DEFAULT,
            timing_scene,
            p.timing_seconds,
            p.repeats,
        )?;
        let m4 = cfg.firmware_args().and_then(|args| {
            costs
                .get(&cfg.label())
                .filter(|(a, _)| *a == args)
                .map(|(_, ips)| ips / cfg.step)
        });
        let mut errors = Vec::new();
        let mut failures = Vec::new();
        let mut its = Vec::new();
        for s in 0..all.len() {
            let t = &runs[c * all.len() + s];
            errors.push(compare(t, &refs[s], windows[s], p.last));
            failures.push(t.error.clone());
            its.push(t.iterations as f64 / t.steps.max(1) as f64);
        }
        rows.push(Row {
            cfg: *cfg,
            f1: f1s[c],
            errors,
            failures,
            iterations_per_step: its,
            time,
            ratio,
            m4,
        });
    }
    eprintln!(
        "accuracy: timing done ({:.0} s)",
        started.elapsed().as_secs_f64()
    );
    let ctx = Ctx {
        p,
        conv,
        all,
        refs,
        windows,
        f1_ref,
        rows,
        rcfg,
        runs,
    };
    std::fs::create_dir_all(out.join("img"))
        .with_context(|| format!("cannot create `{}`", out.join("img").display()))?;
    let md = ctx.write(&out, a.quick, started)?;
    absorber_sim::output::atomic_write(&out.join("accuracy.md"), md.as_bytes())?;
    eprintln!(
        "accuracy: wrote {} ({:.0} s)",
        out.join("accuracy.md").display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
