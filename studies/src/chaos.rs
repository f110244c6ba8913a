//! `absorber-studies chaos`: how far the free ball's statistics depend on the step, the mesh and the
//! solver, beside how far they depend on the initial state (the spread of an ensemble); writes
//! docs/chaos.md.
//!
//! For each excitation frequency and each configuration (solver, elements, precision) and step
//! h, an ensemble of K runs of the physics scene ([`absorber_sim::scene::Scene::physics`]) from
//! seeded perturbations of the ball's initial state ([`absorber_sim::ensemble`]); each statistic is
//! the mean ± sd (min–max) over the members that completed. A statistic of the embedded model
//! (core, 3 elements calibrated, f32, 3 ms) *converges* when it is within
//! `max(spread, 10 %)` of the reference (the full solver, 16 elements, f64, at the finest
//! step), the spread being the larger of the two ensembles' standard deviations; otherwise it
//! is marked **not converged**. A member whose Newton solve fails is counted as a failure.

use absorber_sim::ensemble::{perturbation, Ensemble, Spread};
use absorber_sim::scene::{CalibrationSection, Precision, Scene, Solver};
use anyhow::{Context, Result};
use clap::Args;
use rayon::prelude::*;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::PathBuf;

/// `chaos` options.
#[derive(Args, Debug, Clone)]
pub struct ChaosArgs {
    /// Markdown output.
    #[arg(long, default_value = "docs/chaos.md")]
    pub out: PathBuf,
    /// Excitation frequencies [Hz].
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "3.90,4.05,4.10,4.13,4.25"
    )]
    pub freqs: Vec<f64>,
    /// Time steps h [s].
    #[arg(long, value_delimiter = ',', default_value = "0.003,0.001,0.0005")]
    pub steps: Vec<f64>,
    /// Configurations: `core3` (3 elements calibrated, f32: the embedded model), `core16`
    /// (core, 16 elements, f64), `full16` (full solver, 16 elements, f64), `core6`, `full6`.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "core3,core6,core16,full6,full16"
    )]
    pub configs: Vec<String>,
    /// Members of each ensemble.
    #[arg(long, default_value_t = 8)]
    pub ensemble: usize,
    /// Seed of the perturbations.
    #[arg(long, default_value_t = absorber_sim::ensemble::DEFAULT_SEED)]
    pub seed: u64,
    /// Simulated time of each run [s].
    #[arg(long, default_value_t = 120.0)]
    pub duration: f64,
    /// Start of the steady-state window [s].
    #[arg(long, default_value_t = 20.0)]
    pub transient: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// One configuration of the grid.
#[derive(Clone, Debug, PartialEq)]
struct Config {
    name: String,
    solver: Solver,
    elements: usize,
    precision: Precision,
    /// Keep the physics scene's calibration (fitted for 3 elements).
    calibrated: bool,
}

impl Config {
    fn parse(name: &str) -> Result<Self> {
        let (solver, n) = if let Some(n) = name.strip_prefix("core") {
            (Solver::Core, n)
        } else if let Some(n) = name.strip_prefix("full") {
            (Solver::Full, n)
        } else {
            anyhow::bail!("invalid value for `--configs`: `{name}` (core<N> or full<N>)");
        };
        let elements: usize = n.parse().with_context(|| {
            format!("invalid value for `--configs`: `{name}` (core<N> or full<N>)")
        })?;
        let embedded = solver == Solver::Core && elements == 3;
        Ok(Self {
            name: name.to_string(),
            solver,
            elements,
            precision: if embedded {
                Precision::F32
            } else {
                Precision::F64
            },
            calibrated: embedded,
        })
    }

    fn label(&self) -> String {
        format!(
            "{} N = {}{} {}",
            self.solver.name(),
            self.elements,
            if self.calibrated { " cal." } else { "" },
            match self.precision {
                Precision::F32 => "f32",
                Precision::F64 => "f64",
            }
        )
    }

    fn scene(&self, f: f64, h: f64, duration: f64) -> Result<Scene> {
        let mut s = Scene::physics()?;
        let file = &mut s.file;
        file.solver = self.solver;
        file.elements = self.elements;
        file.precision = self.precision;
        if !self.calibrated {
            file.calibration = CalibrationSection::default();
        }
        file.excitation.frequency = Some(f);
        file.integrator.step = h;
        file.duration = duration;
        s.validate()?;
        Ok(s)
    }
}

/// The statistics compared: summary key (a `/` path), label, scale, decimals.
const STATS: [(&str, &str, f64, usize); 6] = [
    ("tip_amplitude_steady", "steady tip amplitude [mm]", 1e3, 3),
    ("tip_rms_steady", "tip RMS [mm]", 1e3, 3),
    ("impact_rate_steady", "stop impacts [1/s]", 1.0, 2),
    (
        "contact/flight_fraction_steady",
        "flight share [%]",
        100.0,
        2,
    ),
    (
        "contact/separation_rate_steady",
        "separations [1/s]",
        1.0,
        2,
    ),
    (
        "contact/long_flight_rate_steady",
        "flights ≥ 10 ms [1/s]",
        1.0,
        2,
    ),
];

fn at<'a>(v: &'a Value, path: &str) -> &'a Value {
    path.split('/').fold(v, |v, k| &v[k])
}

/// One ensemble: the statistics over its completed members and its failures.
struct Cell {
    stats: Vec<Spread>,
    failures: Vec<String>,
}

/// The relative tolerance of the convergence test.
pub const TOLERANCE: f64 = 0.10;

/// `a` (embedded) against `r` (reference): `|a − r| ≤ max(spread, 10 % |r|)`, the spread the
/// larger standard deviation. Where the reference is 0 (no stop impact, no flight at all) only
/// the spread is left: two zeros agree, a statistic the reference does not have at all must lie
/// within the spread of the two ensembles.
pub fn converges(a: &Spread, r: &Spread) -> bool {
    let diff = (a.mean - r.mean).abs();
    let spread = a.sd.max(r.sd);
    diff <= spread.max(TOLERANCE * r.mean.abs()) && a.k > 0 && r.k > 0
}

/// Whether the reference prints as 0 at the table's precision (`scale`, `prec` as in
/// [`Spread::text`]): a percentage of it would be a ratio of rounding noise.
fn shows_zero(r: &Spread, scale: f64, prec: usize) -> bool {
    (r.mean * scale).abs() < 0.5 * 10f64.powi(-(prec as i32))
}

/// `a − r` and the spread as text: relative to the reference in %, or, where the reference
/// prints as 0 (a relative difference has no meaning), in the statistic's own unit.
fn difference(a: &Spread, r: &Spread, scale: f64, prec: usize) -> String {
    let spread = a.sd.max(r.sd);
    if !shows_zero(r, scale, prec) {
        format!(
            "{:+.1} % ({:.1} %)",
            100.0 * (a.mean - r.mean) / r.mean.abs(),
            100.0 * spread / r.mean.abs()
        )
    } else {
        format!(
            "{:+.p$} ({:.p$}), reference 0",
            (a.mean - r.mean) * scale,
            spread * scale,
            p = prec
        )
    }
}

/// How far `a` is off `r`, for a verdict: "N % off", or where the reference prints as 0 what
/// `a` has.
fn off(a: &Spread, r: &Spread, scale: f64, prec: usize, what: &str) -> String {
    if !shows_zero(r, scale, prec) {
        format!(
            "{what} {:.0} % off",
            100.0 * (a.mean - r.mean).abs() / r.mean.abs()
        )
    } else {
        format!(
            "{what} {:.p$} where the reference has 0",
            a.mean * scale,
            p = prec
        )
    }
}

/// Runs the study and writes the document.
pub fn run(a: &ChaosArgs) -> Result<()> {
    let e = Ensemble::new(a.ensemble, a.seed)?;
    let configs: Vec<Config> = a
        .configs
        .iter()
        .map(|c| Config::parse(c))
        .collect::<Result<_>>()?;
    for &h in &a.steps {
        if !h.is_finite() || h <= 0.0 {
            anyhow::bail!("invalid value for `--steps`: {h} (must be finite and positive)");
        }
    }
    for &f in &a.freqs {
        if !f.is_finite() || f <= 0.0 {
            anyhow::bail!("invalid value for `--freqs`: {f} (must be finite and positive) [Hz]");
        }
    }
    if !(a.duration.is_finite() && a.duration > 0.0) {
        anyhow::bail!(
            "invalid value for `--duration`: {} (must be finite and positive) [s]",
            a.duration
        );
    }
    if !(a.transient.is_finite() && (0.0..a.duration).contains(&a.transient)) {
        anyhow::bail!(
            "invalid value for `--transient`: {} (allowed: 0 ≤ transient < `--duration` = {}) [s]",
            a.transient,
            a.duration
        );
    }
    if a.jobs == Some(0) {
        anyhow::bail!("invalid value for `--jobs`: 0 (must be at least 1)");
    }
    // Every scene is built (and checked) before any run.
    let mut jobs = Vec::new();
    for &f in &a.freqs {
        for c in &configs {
            for &h in &a.steps {
                let s = c.scene(f, h, a.duration)?;
                for m in 0..e.k {
                    jobs.push((
                        f,
                        c.clone(),
                        h,
                        m,
                        absorber_sim::ensemble::member_scene(&s, e.seed, m),
                    ));
                }
            }
        }
    }
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(64 << 20);
    if let Some(j) = a.jobs {
        pool = pool.num_threads(j.max(1));
    }
    let pool = pool.build()?;
    let t0 = std::time::Instant::now();
    let total = jobs.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<(Result<Value>, f64)> = pool.install(|| {
        jobs.par_iter()
            .map(|(f, c, h, m, s)| {
                let t = std::time::Instant::now();
                let r = absorber_sim::simulate::summary_in_memory(s, Some(a.transient));
                let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                eprintln!(
                    "chaos: {n}/{total} ({f} Hz, {}, h = {h} s, member {m}){}",
                    c.label(),
                    if r.is_err() { ": FAILED" } else { "" }
                );
                (r, t.elapsed().as_secs_f64())
            })
            .collect()
    });
    let wall = t0.elapsed().as_secs_f64();
    // Group into cells (the jobs are in cell order, K members each).
    let mut cells = Vec::new();
    for (chunk, results) in jobs.chunks(e.k).zip(results.chunks(e.k)) {
        let (f, c, h, _, _) = &chunk[0];
        let mut failures = Vec::new();
        let mut ok = Vec::new();
        for ((_, _, _, m, _), (r, _)) in chunk.iter().zip(results) {
            match r {
                Ok(v) => ok.push(v.clone()),
                Err(err) => failures.push(format!("member {m}: {err:#}")),
            }
        }
        let stats = STATS
            .iter()
            .map(|(key, ..)| {
                let xs: Vec<f64> = ok
                    .iter()
                    .map(|v| at(v, key).as_f64().unwrap_or(f64::NAN))
                    .collect();
                Spread::of(&xs)
            })
            .collect();
        cells.push((*f, c.clone(), *h, Cell { stats, failures }));
    }
    let cpu: f64 = results.iter().map(|(_, t)| t).sum();
    let doc = document(a, e, &configs, &cells, wall, cpu);
    absorber_sim::output::atomic_write(&a.out, doc.as_bytes())?;
    let failures: usize = cells.iter().map(|c| c.3.failures.len()).sum();
    eprintln!(
        "chaos: wrote {} ({total} runs, {failures} failed, {wall:.0} s)",
        a.out.display()
    );
    Ok(())
}

fn document(
    a: &ChaosArgs,
    e: Ensemble,
    configs: &[Config],
    cells: &[(f64, Config, f64, Cell)],
    wall: f64,
    cpu: f64,
) -> String {
    let mut d = String::new();
    let list = |xs: &[f64]| {
        xs.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let _ = writeln!(
        d,
        "# Chaos with error bars: the free ball's statistics against h, N and the solver\n"
    );
    let _ = writeln!(
        d,
        "Generated by `absorber-studies chaos --freqs {} --steps {} --configs {} --ensemble {} --seed {} \
         --duration {} --transient {}` ({} runs, {wall:.0} s on this machine, {cpu:.0} s of run \
         time). Do not edit by hand.\n",
        list(&a.freqs),
        list(&a.steps),
        a.configs.join(","),
        e.k,
        e.seed,
        a.duration,
        a.transient,
        cells.len() * e.k
    );
    let _ =
        writeln!(
        d,
        "The scene is the built-in `physics` scene (`scenes/physics.toml`: Table 1's absorber, a \
         steel arm's structural damping, generalized-α, stops with a contact time of their own \
         and a shortest bounce; docs/model.md), at each frequency and step, in each \
         configuration: {}. Each cell is an ensemble of {} runs from seeded perturbations of the \
         ball's initial state (angle ± {}°, orbit rate ± {} rad/s, uniform; member 0 unperturbed): \
         mean ± standard deviation (min–max) over the members that completed, over the steady \
         window t ≥ {} s. The perturbations change no physics: the spread of an ensemble is the \
         uncertainty of a statistic that chaos leaves, and a difference between configurations \
         smaller than it is not a difference.\n",
        configs.iter().map(Config::label).collect::<Vec<_>>().join("; "),
        e.k,
        absorber_sim::ensemble::ANGLE_SPREAD_DEG,
        absorber_sim::ensemble::RATE_SPREAD,
        a.transient
    );
    let _ = writeln!(
        d,
        "Statistics: the steady tip amplitude (half peak-to-peak), the tip RMS about the static \
         sag, the rate of stop impacts, the share of the time the ball flies, the rate of \
         separations (take-offs whose flight rises at least `ball.lift_height` = 10 µm off the \
         track: lower hops, made by the rigid track on the flexible housing, grow in number \
         without bound as h shrinks; docs/model.md, \"Contact statistics\"), and the rate of \
         flights of at least 10 ms (a flight counted from the last step on the track to the \
         next, in whole steps).\n"
    );
    let full_freqs = [3.90, 4.05, 4.10, 4.13, 4.25];
    let full_configs = ["core3", "core6", "core16", "full6", "full16"];
    let reduced = !full_freqs.iter().all(|f| a.freqs.contains(f))
        || !full_configs
            .iter()
            .all(|c| a.configs.iter().any(|x| x == c));
    if reduced {
        let _ = writeln!(
            d,
            "This is a reduced grid (the frequencies and configurations above). The whole study \
             adds 3.90, 4.05 and 4.25 Hz and 6 elements: `absorber-studies chaos --freqs {} --configs {}` \
             (about {:.0}× the run time above).\n",
            list(&full_freqs),
            full_configs.join(","),
            (full_freqs.len() * full_configs.len()) as f64
                / (a.freqs.len() * a.configs.len()).max(1) as f64
        );
    }
    let failures: usize = cells.iter().map(|c| c.3.failures.len()).sum();
    let _ = writeln!(
        d,
        "**Newton failures: {failures} of {} runs.**\n",
        cells.len() * e.k
    );
    for &f in &a.freqs {
        let _ = writeln!(d, "## {f} Hz\n");
        let mut head = String::from("| configuration | h [ms] |");
        let mut rule = String::from("|---|---|");
        for (_, label, ..) in STATS {
            let _ = write!(head, " {label} |");
            rule.push_str("---|");
        }
        head.push_str(" failed |");
        rule.push_str("---|");
        let _ = writeln!(d, "{head}\n{rule}");
        for (_, c, h, cell) in cells.iter().filter(|x| x.0 == f) {
            let mut row = format!("| {} | {} |", c.label(), h * 1e3);
            for ((_, _, scale, prec), s) in STATS.iter().zip(&cell.stats) {
                if s.k == 0 {
                    row.push_str(" — |");
                } else {
                    let _ = write!(row, " {} |", s.text(*scale, *prec));
                }
            }
            let _ = write!(row, " {}/{} |", cell.failures.len(), e.k);
            let _ = writeln!(d, "{row}");
        }
        let _ = writeln!(d);
        // The embedded model against the reference.
        let find = |name: &str, h: f64| {
            cells
                .iter()
                .find(|x| x.0 == f && x.1.name == name && x.2 == h)
                .map(|x| &x.3)
        };
        let coarse = a.steps.iter().copied().fold(f64::NAN, f64::max);
        let fine = a.steps.iter().copied().fold(f64::NAN, f64::min);
        let reference = configs
            .iter()
            .rev()
            .find(|c| c.solver == Solver::Full)
            .or(configs.last());
        let embedded = configs.iter().find(|c| c.calibrated);
        if let (Some(r), Some(m)) = (reference, embedded) {
            if let (Some(rc), Some(mc), Some(rh)) = (
                find(&r.name, fine),
                find(&m.name, coarse),
                find(&r.name, coarse),
            ) {
                let _ = writeln!(
                    d,
                    "The embedded model ({} at {} ms) against the reference ({} at {} ms), and the \
                     reference's own step convergence ({} ms against {} ms): a statistic converges \
                     when both differences are at most max(spread, {} %), the spread being the larger \
                     standard deviation of the two ensembles compared.\n",
                    m.label(),
                    coarse * 1e3,
                    r.label(),
                    fine * 1e3,
                    coarse * 1e3,
                    fine * 1e3,
                    TOLERANCE * 100.0
                );
                let _ = writeln!(
                    d,
                    "| statistic | embedded | reference | embedded − reference (spread) | reference {} ms − {} ms (spread) | verdict |",
                    coarse * 1e3,
                    fine * 1e3
                );
                let _ = writeln!(d, "|---|---|---|---|---|---|");
                for ((((_, label, scale, prec), sm), sr), sh) in
                    STATS.iter().zip(&mc.stats).zip(&rc.stats).zip(&rh.stats)
                {
                    let ok_m = converges(sm, sr);
                    let ok_h = converges(sh, sr);
                    let embedded = off(sm, sr, *scale, *prec, "embedded");
                    let in_h = off(sh, sr, *scale, *prec, "at the coarse step");
                    let verdict = match (ok_m, ok_h) {
                        (true, true) if sm.mean == 0.0 && sr.mean == 0.0 && sh.mean == 0.0 => {
                            "converged (0 in all three)".to_string()
                        }
                        (true, true) => "converged".to_string(),
                        (false, true) => format!("**not converged** ({embedded})"),
                        (true, false) => format!("**not converged in h** (reference {in_h})"),
                        (false, false) => {
                            format!("**not converged** ({embedded}; reference {in_h})")
                        }
                    };
                    let _ = writeln!(
                        d,
                        "| {label} | {} | {} | {} | {} | {verdict} |",
                        sm.text(*scale, *prec),
                        sr.text(*scale, *prec),
                        difference(sm, sr, *scale, *prec),
                        difference(sh, sr, *scale, *prec),
                    );
                }
                let _ = writeln!(d);
            }
        }
    }
    let all: Vec<&String> = cells.iter().flat_map(|c| c.3.failures.iter()).collect();
    if !all.is_empty() {
        let _ = writeln!(d, "## Failed runs\n");
        for (f, c, h, cell) in cells {
            for msg in &cell.failures {
                let _ = writeln!(d, "- {f} Hz, {}, h = {} ms: {msg}", c.label(), h * 1e3);
            }
        }
        let _ = writeln!(d);
    }
    let _ = writeln!(
        d,
        "Member perturbations (seed {}): {}.\n",
        e.seed,
        (1..e.k.min(9))
            .map(|m| {
                let (a, r) = perturbation(e.seed, m);
                format!("{m}: {a:+.4}°, {r:+.5} rad/s")
            })
            .collect::<Vec<_>>()
            .join("; ")
    );
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spread(mean: f64, sd: f64) -> Spread {
        Spread {
            mean,
            sd,
            min: mean - sd,
            max: mean + sd,
            k: 8,
        }
    }

    /// A statistic that is 0 in the reference (no flight at all off tuning) is compared in its
    /// own unit: never a NaN or an infinite percentage in the document.
    #[test]
    fn a_zero_reference_is_compared_in_the_statistics_unit() {
        let zero = spread(0.0, 0.0);
        let hops = spread(4e-4, 2e-4); // a flight share of 0.04 % ± 0.02 %
        assert!(converges(&zero, &zero));
        assert!(
            !converges(&hops, &zero),
            "0.04 % against none is outside a 0.02 % spread"
        );
        assert!(converges(&spread(1e-4, 2e-4), &zero));
        assert_eq!(
            difference(&zero, &zero, 100.0, 2),
            "+0.00 (0.00), reference 0"
        );
        assert_eq!(
            difference(&hops, &zero, 100.0, 2),
            "+0.04 (0.02), reference 0"
        );
        assert_eq!(
            off(&hops, &zero, 100.0, 2, "embedded"),
            "embedded 0.04 where the reference has 0"
        );
        // A reference that only rounds to 0 (0.0007 %) is not a base for a percentage either.
        let trace = spread(7e-6, 5e-6);
        assert_eq!(
            difference(&hops, &trace, 100.0, 2),
            "+0.04 (0.02), reference 0"
        );
        assert!(!converges(&hops, &trace));
        // A reference that is not 0 keeps the relative form and the 10 % rule.
        let r = spread(2.0, 0.05);
        assert_eq!(difference(&spread(2.1, 0.05), &r, 1.0, 2), "+5.0 % (2.5 %)");
        assert!(converges(&spread(2.19, 0.05), &r));
        assert!(!converges(&spread(2.21, 0.05), &r));
        assert_eq!(
            off(&spread(2.5, 0.0), &r, 1.0, 2, "embedded"),
            "embedded 25 % off"
        );
    }
}
