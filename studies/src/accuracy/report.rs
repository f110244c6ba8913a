//! `absorber-studies accuracy`: the whole study and the generated `docs/accuracy.md`.

use super::*;
use anyhow::{Context, Result};
use clap::Args;
use host_sim::plot::{render, Panel, Series};
use rayon::prelude::*;
use std::fmt::Write as _;

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
    let _lock = host_sim::output::OutputDir::open(&out, None, "accuracy")?;
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
    host_sim::output::atomic_write(&out.join("accuracy.md"), md.as_bytes())?;
    eprintln!(
        "accuracy: wrote {} ({:.0} s)",
        out.join("accuracy.md").display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

struct Ctx {
    p: Plan,
    conv: Convergence,
    all: Vec<TestScene>,
    refs: Vec<Trajectory>,
    windows: Vec<f64>,
    f1_ref: f64,
    rows: Vec<Row>,
    rcfg: Config,
    runs: Vec<Trajectory>,
}

/// The single error number of the Pareto plot: the worst, over the scenes that are not chaotic
/// in the reference, of the RMS tip error over the whole run, in % of the reference's peak
/// dynamic deflection.
fn pareto_error(row: &Row, ctx: &Ctx) -> f64 {
    // A configuration that stops on any scene (e.g. a budget that cannot absorb an impact) is
    // not a candidate for the front.
    if row.failures.iter().any(Option::is_some) {
        return f64::INFINITY;
    }
    let mut e: f64 = 0.0;
    for (s, r) in ctx.refs.iter().enumerate() {
        if r.impacts.is_empty() {
            e = e.max(100.0 * row.errors[s].tip_rms / peak_dynamic(r));
        }
    }
    e
}

fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(x, y)| {
            y.is_finite()
                && !points
                    .iter()
                    .any(|&(x2, y2)| y2.is_finite() && x2 <= x && y2 <= y && (x2 < x || y2 < y))
        })
        .collect()
}

fn pct(x: f64, scale: f64) -> String {
    let v = 100.0 * x / scale;
    if !v.is_finite() {
        "fails".into()
    } else if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn sep(x: Option<f64>) -> String {
    x.map(|t| format!("{t:.1}"))
        .unwrap_or_else(|| "never".into())
}

impl Ctx {
    /// Every candidate has an exact Cortex-M4F count (else the cost axis is host time).
    fn exact(&self) -> bool {
        self.rows.iter().all(|r| r.m4.is_some())
    }

    /// The cost axis: millions of Cortex-M4F instructions per simulated second when every
    /// candidate was counted, host µs per simulated second otherwise.
    fn cost(&self, r: &Row) -> f64 {
        if self.exact() {
            r.m4.unwrap_or(f64::NAN) / 1e6
        } else {
            r.time * 1e6
        }
    }

    fn cost_title(&self) -> &'static str {
        if self.exact() {
            "M4 instructions per simulated s [10⁶] (QEMU, exact)"
        } else {
            "host µs per simulated s (median)"
        }
    }

    fn cost_cell(&self, r: &Row) -> String {
        if self.exact() {
            format!("{:.2}", self.cost(r))
        } else {
            format!("{:.0}", self.cost(r))
        }
    }

    fn idx(&self, name: &str) -> usize {
        self.all.iter().position(|s| s.name == name).expect("scene")
    }

    fn write(&self, out: &Path, quick: bool, started: Instant) -> Result<String> {
        let p = &self.p;
        let mut m = String::new();
        let cmd = if quick {
            "cargo run --release -p absorber-studies -- accuracy --quick"
        } else {
            "cargo run --release -p absorber-studies -- accuracy"
        };
        writeln!(m, "# Error against run time of the embedded model\n")?;
        writeln!(
            m,
            "Generated by `{cmd}` (do not edit by hand; reference trajectories are cached under \
             `$CARGO_TARGET_DIR/accuracy-cache`, so a rerun only re-runs the core). \
             This run took {:.0} s of wall time on the build machine (2 shared cores).\n",
            started.elapsed().as_secs_f64()
        )?;
        writeln!(m, "{}", include_str!("intro.md"))?;
        // Convergence.
        writeln!(m, "## 1. The reference and its convergence\n")?;
        writeln!(
            m,
            "Reference: `absorber_full::FullSolver`, **N = {}**, **h = {} ms**, `f64`, full Newton \
             to **1e-10**, damping-matched integrator (γ = {:.3}, β = {:.4}, C = {:.2e} s · K_t). \
             Full-solver cost at this size: {:.1} s of host time per simulated second.\n",
            self.rcfg.elements,
            self.rcfg.step * 1e3,
            integrator_for(self.rcfg.step).0,
            integrator_for(self.rcfg.step).1,
            integrator_for(self.rcfg.step).2,
            self.refs.iter().map(|r| r.wall).sum::<f64>() / (self.refs.len() as f64 * p.duration),
        )?;
        writeln!(
            m,
            "**Mesh** (locked ball, 4.13 Hz, h = {} ms, first {} s; RMS of tip − static):\n",
            p.h_ref * 1e3,
            p.conv_t
        )?;
        writeln!(m, "| N | f₁ [Hz] | f₁ − f₁(N={}) [%] | RMS tip [mm] | vs N={} [%] | full solver [s per simulated s] |", self.conv.by_n.last().map(|x| x.0).unwrap_or(0), self.conv.by_n.last().map(|x| x.0).unwrap_or(0))?;
        writeln!(m, "|---:|---:|---:|---:|---:|---:|")?;
        let (_, f_fine, r_fine, _) = *self.conv.by_n.last().expect("conv");
        for &(n, f1, r, w) in &self.conv.by_n {
            writeln!(
                m,
                "| {n} | {f1:.5} | {:+.3} | {:.4} | {:+.3} | {w:.2} |",
                100.0 * (f1 / f_fine - 1.0),
                r * 1e3,
                100.0 * (r / r_fine - 1.0)
            )?;
        }
        writeln!(
            m,
            "\n**Step** (N = {}, first {} s; max difference to the finest step on the 10 ms grid):\n",
            p.n_ref, p.conv_t
        )?;
        writeln!(m, "| h [ms] | γ | locked 4.13 Hz: RMS tip [mm] | max Δtip [µm] | free 3.70 Hz: max Δtip [µm] | max Δθ [mrad] |")?;
        writeln!(m, "|---:|---:|---:|---:|---:|---:|")?;
        for (i, &(h, r, d)) in self.conv.by_h.iter().enumerate() {
            let (_, df, db) = self.conv.by_h_free[i];
            writeln!(
                m,
                "| {} | {:.3} | {:.4} | {:.2} | {:.2} | {:.3} |",
                h * 1e3,
                integrator_for(h).0,
                r * 1e3,
                d * 1e6,
                df * 1e6,
                db * 1e3
            )?;
        }
        self.plot_convergence(out)?;
        writeln!(m, "\n![convergence](img/accuracy_convergence.png)\n")?;
        // Scenes.
        writeln!(m, "## 2. Scenes\n")?;
        writeln!(m, "| scene | reference: peak dynamic tip [mm] | steady amplitude (last {} s) [mm] | impacts | first impact [s] | pointwise window [s] |", p.last)?;
        writeln!(m, "|---|---:|---:|---:|---:|---:|")?;
        for (s, r) in self.all.iter().zip(&self.refs) {
            let (amp, _, _, _) = statistics(r, p.last);
            writeln!(
                m,
                "| {} | {:.3} | {:.3} | {} | {} | {:.2} |",
                s.title,
                peak_dynamic(r) * 1e3,
                amp * 1e3,
                r.impacts.len(),
                r.impacts
                    .first()
                    .map(|t| format!("{t:.2}"))
                    .unwrap_or_else(|| "–".into()),
                self.windows[self.idx(s.name)]
            )?;
        }
        writeln!(m)?;
        // Main table.
        let pts: Vec<(f64, f64)> = self
            .rows
            .iter()
            .map(|r| (self.cost(r), pareto_error(r, self)))
            .collect();
        let front = pareto_front(&pts);
        writeln!(m, "## 3. Candidates: error and cost\n")?;
        writeln!(m, "{}", include_str!("table-notes.md"))?;
        let (l, f37, n) = (
            self.idx("locked-4.13"),
            self.idx("free-3.70"),
            self.idx("locked-noise"),
        );
        let f413 = self.idx("free-4.13");
        writeln!(m, "| configuration | Pareto | {title} | host time × default (paired median) | Newton it./step (free 4.13) | f₁ err [%] | locked 4.13: RMS / max tip err, 5 s [%] | locked 4.13: RMS / max, {d} s [%] | locked 4.13: amplitude err [%] | free 3.70: RMS / max tip, {d} s [%] | free 3.70: max θ err [mrad] | locked noise: RMS / max, {d} s [%] | free 4.13: max tip err before 1st impact [%] | free 4.13: separation [s] | E [%] |", title = self.cost_title(), d = p.duration)?;
        writeln!(
            m,
            "|---|:-:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        )?;
        for (i, r) in self.rows.iter().enumerate() {
            let sc = |s: usize| peak_dynamic(&self.refs[s]);
            let (amp_ref, _, _, _) = statistics(&self.refs[l], p.last);
            let e = &r.errors;
            writeln!(
                m,
                "| {}{} | {} | {} | {:.2} | {:.2} | {:+.2} | {} / {} | {} / {} | {:+.2} | {} / {} | {:.2} | {} / {} | {} | {} | {} |",
                r.cfg.label(),
                if r.cfg == Config::DEFAULT { " (default)" } else { "" },
                if front[i] { "●" } else { "" },
                self.cost_cell(r),
                r.ratio,
                r.iterations_per_step[f413],
                100.0 * (r.f1 / self.f1_ref - 1.0),
                pct(e[l].tip_rms_5, sc(l)),
                pct(e[l].tip_max_5, sc(l)),
                pct(e[l].tip_rms, sc(l)),
                pct(e[l].tip_max, sc(l)),
                100.0 * (e[l].amplitude / amp_ref - 1.0),
                pct(e[f37].tip_rms, sc(f37)),
                pct(e[f37].tip_max, sc(f37)),
                e[f37].ball_max * 1e3,
                pct(e[n].tip_rms, sc(n)),
                pct(e[n].tip_max, sc(n)),
                pct(e[f413].tip_max, sc(f413)),
                sep(e[f413].separation),
                if pts[i].1.is_finite() { format!("{:.2}", pts[i].1) } else { "fails".into() },
            )?;
        }
        let fails: Vec<String> = self
            .rows
            .iter()
            .flat_map(|r| {
                r.failures.iter().zip(&self.all).filter_map(move |(f, s)| {
                    f.as_ref()
                        .map(|f| format!("- `{}` on {}: {f}", r.cfg.label(), s.title))
                })
            })
            .collect();
        if !fails.is_empty() {
            writeln!(
                m,
                "\nRuns that stopped early (their errors are shown as `fails`):\n"
            )?;
            for f in fails {
                writeln!(m, "{f}")?;
            }
        }
        self.plot_pareto(out, &pts, &front)?;
        writeln!(m, "\n![error vs run time](img/accuracy_pareto.png)\n")?;
        // Chaotic statistics.
        writeln!(
            m,
            "## 4. Chaotic scenes: statistics, not pointwise errors\n"
        )?;
        writeln!(m, "{}", include_str!("chaos-notes.md"))?;
        let chaotic: Vec<usize> = (0..self.all.len())
            .filter(|&s| !self.refs[s].impacts.is_empty())
            .collect();
        write!(m, "| configuration |")?;
        for &s in &chaotic {
            write!(
                m,
                " {}: tip RMS [mm] / impacts/s / θ RMS [deg] / separation [s] |",
                self.all[s].title
            )?;
        }
        writeln!(m)?;
        write!(m, "|---|")?;
        for _ in &chaotic {
            write!(m, "---:|")?;
        }
        writeln!(m)?;
        write!(m, "| **reference** |")?;
        for &s in &chaotic {
            let (_, d, b, ips) = statistics(&self.refs[s], p.last);
            write!(
                m,
                " {:.2} / {:.2} / {:.1} / – |",
                d * 1e3,
                ips,
                b.to_degrees()
            )?;
        }
        writeln!(m)?;
        for r in &self.rows {
            write!(m, "| {} |", r.cfg.label())?;
            for &s in &chaotic {
                let e = &r.errors[s];
                if r.failures[s].is_some() {
                    write!(m, " fails |")?;
                } else {
                    write!(
                        m,
                        " {:.2} / {:.2} / {:.1} / {} |",
                        e.dyn_rms * 1e3,
                        e.impacts_per_s,
                        e.ball_rms.to_degrees(),
                        sep(e.separation)
                    )?;
                }
            }
            writeln!(m)?;
        }
        self.plot_traces(out)?;
        writeln!(
            m,
            "\n![tip error of the default configuration](img/accuracy_traces.png)\n"
        )?;
        self.key_numbers(&mut m, &pts)?;
        writeln!(m, "{}", include_str!("recommendation.md"))?;
        m.push_str(&super::cap::section()?);
        Ok(m)
    }

    fn key_numbers(&self, m: &mut String, pts: &[(f64, f64)]) -> Result<()> {
        let find = |c: Config| self.rows.iter().position(|r| r.cfg == c);
        let d = Config::DEFAULT;
        let l = self.idx("locked-4.13");
        let (amp_ref, _, _, _) = statistics(&self.refs[l], self.p.last);
        writeln!(m, "## 5. Key numbers (from the tables above)\n")?;
        writeln!(m, "| configuration | {} | × default | host time × default (paired) | E [%] | locked 4.13 Hz amplitude err [%] | f₁ err [%] |", self.cost_title())?;
        writeln!(m, "|---|---:|---:|---:|---:|---:|---:|")?;
        let d_cost = find(d)
            .map(|i| self.cost(&self.rows[i]))
            .unwrap_or(f64::NAN);
        let list = [
            d,
            d.with(|c| c.newton = Newton::Modified),
            d.with(|c| c.elements = 4)
                .with(|c| c.newton = Newton::Modified),
            d.with(|c| c.elements = 6),
            d.with(|c| c.elements = 6)
                .with(|c| c.newton = Newton::Modified),
            d.with(|c| c.elements = 6).with(|c| c.f32 = false),
        ];
        // The calibrated candidates (their factors are fitted, so found by their flag).
        let calibrated = self
            .rows
            .iter()
            .filter(|r| r.cfg.calibration.is_some())
            .map(|r| r.cfg);
        for c in list.into_iter().chain(calibrated) {
            if let Some(i) = find(c) {
                let r = &self.rows[i];
                writeln!(
                    m,
                    "| {} | {} | {:.2} | {:.2} | {:.2} | {:+.2} | {:+.2} |",
                    c.label(),
                    self.cost_cell(r),
                    self.cost(r) / d_cost,
                    r.ratio,
                    pts[i].1,
                    100.0 * (r.errors[l].amplitude / amp_ref - 1.0),
                    100.0 * (r.f1 / self.f1_ref - 1.0)
                )?;
            }
        }
        writeln!(m)?;
        Ok(())
    }

    fn plot_convergence(&self, out: &Path) -> Result<()> {
        let c = &self.conv;
        let f: Vec<(f64, f64)> = c.by_n.iter().map(|x| (x.0 as f64, x.1)).collect();
        let r: Vec<(f64, f64)> = c.by_n.iter().map(|x| (x.0 as f64, x.2 * 1e3)).collect();
        let h: Vec<(f64, f64)> = c
            .by_h
            .iter()
            .filter(|x| x.2 > 0.0)
            .map(|x| (x.0 * 1e3, x.2 * 1e6))
            .collect();
        let hf: Vec<(f64, f64)> = c
            .by_h_free
            .iter()
            .filter(|x| x.1 > 0.0)
            .map(|x| (x.0 * 1e3, x.1 * 1e6))
            .collect();
        render(
            &out.join("img/accuracy_convergence.png"),
            "Convergence of the full-solver reference",
            &[
                Panel::new(
                    "f₁, locked ball",
                    "N",
                    "f₁ [Hz]",
                    vec![Series::marked("", f)],
                ),
                Panel::new(
                    "RMS tip deflection, locked 4.13 Hz, 5 s",
                    "N",
                    "RMS [mm]",
                    vec![Series::marked("", r)],
                ),
                Panel::new(
                    "max |tip − tip(finest h)|",
                    "h [ms]",
                    "[µm]",
                    vec![
                        Series::marked("locked 4.13 Hz", h),
                        Series::marked("free 3.70 Hz", hf),
                    ],
                ),
            ],
            1,
            3,
            (1500, 450),
        )
    }

    fn plot_traces(&self, out: &Path) -> Result<()> {
        let d = self
            .rows
            .iter()
            .position(|r| r.cfg == Config::DEFAULT)
            .expect("default");
        let nsc = self.all.len();
        let mut panels = Vec::new();
        for name in ["locked-4.13", "free-4.13"] {
            let s = self.idx(name);
            let r = &self.refs[s];
            let c = &self.runs[d * nsc + s];
            let pts = |f: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
                (0..c.tip.len().min(r.tip.len()))
                    .map(|j| (Trajectory::time(j), f(j)))
                    .collect()
            };
            panels.push(Panel::new(
                &format!("{}: tip deflection − static", self.all[s].title),
                "t [s]",
                "[mm]",
                vec![
                    Series::line("reference", pts(&|j| (r.tip[j] - r.static_tip) * 1e3)),
                    Series::line("N3 h3 f32", pts(&|j| (c.tip[j] - r.static_tip) * 1e3)),
                ],
            ));
            panels.push(Panel::new(
                &format!("{}: tip error (default − reference)", self.all[s].title),
                "t [s]",
                "[mm]",
                vec![Series::line("", pts(&|j| (c.tip[j] - r.tip[j]) * 1e3))],
            ));
        }
        render(
            &out.join("img/accuracy_traces.png"),
            "Default embedded configuration against the reference",
            &panels,
            2,
            2,
            (1500, 900),
        )
    }

    fn plot_pareto(&self, out: &Path, pts: &[(f64, f64)], front: &[bool]) -> Result<()> {
        host_sim::output::atomic_with(&out.join("img/accuracy_pareto.png"), |p| {
            self.plot_pareto_at(p, pts, front)
        })
    }

    fn plot_pareto_at(&self, path: &Path, pts: &[(f64, f64)], front: &[bool]) -> Result<()> {
        use plotters::prelude::*;
        use plotters::style::{register_font, FontStyle};
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
        let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("plot {}: {e}", path.display());
        let fin: Vec<(f64, f64, usize)> = pts
            .iter()
            .enumerate()
            .filter(|(_, p)| p.0.is_finite() && p.1.is_finite() && p.0 > 0.0 && p.1 > 0.0)
            .map(|(i, p)| (p.0, p.1, i))
            .collect();
        let (x0, x1) = fin.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
        let (y0, y1) = fin.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
        let root = BitMapBackend::new(path, (1300, 850)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                if self.exact() {
                    "Error vs Cortex-M4F instructions (log–log); ● Pareto front"
                } else {
                    "Error vs host run time (log–log); ● Pareto front"
                },
                ("sans-serif", 22),
            )
            .margin(15)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(
                ((x0 / 1.5)..(x1 * 1.5)).log_scale(),
                ((y0 / 1.5)..(y1 * 1.5)).log_scale(),
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(if self.exact() {
                "Cortex-M4F instructions per simulated second, millions (QEMU, free ball 4.13 Hz)"
            } else {
                "host µs per simulated second (free ball 4.13 Hz)"
            })
            .y_desc("E: worst RMS tip error, non-chaotic scenes [% of peak]")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v}"))
            .draw()
            .map_err(|e| err(&e))?;
        let mut fr: Vec<(f64, f64)> = fin
            .iter()
            .filter(|p| front[p.2])
            .map(|p| (p.0, p.1))
            .collect();
        fr.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(fr, RED.stroke_width(2)))
            .map_err(|e| err(&e))?;
        for &(x, y, i) in &fin {
            let color = if front[i] { RED } else { BLUE };
            chart
                .draw_series(std::iter::once(Circle::new((x, y), 5, color.filled())))
                .map_err(|e| err(&e))?;
            let label = self.rows[i].cfg.label();
            chart
                .draw_series(std::iter::once(Text::new(
                    label,
                    (x * 1.04, y),
                    ("sans-serif", 12).into_font().color(&color),
                )))
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
        Ok(())
    }
}
