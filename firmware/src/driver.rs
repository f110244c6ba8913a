//! The scene driver: one run of a scene with its printing and fingerprint, shared by the
//! target and the host reference.

use crate::{base_accel, stress, Setup, Sim, STEP_MS};
use absorber_core::{Error, Outcome};
use core::fmt::{self, Write};
#[cfg(not(target_os = "none"))]
use core::mem::MaybeUninit;

/// 64-bit FNV-1a over 32-bit words (each word fed as 4 bytes, little end first).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Folds one word in.
    pub fn word(&mut self, w: u32) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// What a run did.
#[derive(Clone, Copy, Debug, Default)]
pub struct Summary {
    /// Fingerprint of every step's state and report.
    pub hash: u64,
    /// Steps that hit a stop.
    pub impacts: u32,
    /// Impacts after which the ball stayed on the stop.
    pub stuck: u32,
    /// Newton iterations summed over all steps.
    pub iterations: u32,
    /// Most Newton iterations in one step.
    pub max_iterations: u32,
    /// Steps that returned an error (state kept, run continued).
    pub errors: u32,
    /// Steps taken at the work cap (`Outcome::Capped`).
    pub capped: u32,
    /// Steps that restarted the model (`Outcome::Restarted`).
    pub restarts: u32,
    /// Most work units in one step.
    pub max_work: u32,
    /// Longest run of error steps (errors, capped or restarting steps) in a row.
    pub longest_error_run: u32,
}

impl Summary {
    /// Steps that did not converge normally: errors, capped and restarting steps.
    pub fn error_steps(&self) -> u32 {
        self.errors + self.capped + self.restarts
    }
}

/// Hooks around each step (the firmware measures the stack there; the host does nothing).
pub trait Probe {
    /// Just before `Sim::step`.
    fn before_step(&mut self) {}
    /// Just after it.
    fn after_step(&mut self) {}
}

/// Does nothing.
pub struct NoProbe;
impl Probe for NoProbe {}

/// Short name of an error (no float formatting: keeps the model's flash figure honest).
pub fn error_name(e: &Error) -> &'static str {
    match e {
        Error::InvalidParameter { field, .. } => field,
        Error::NonFiniteInput => "NonFiniteInput",
        Error::NoConvergence { .. } => "NoConvergence",
        Error::NonFiniteState => "NonFiniteState",
        Error::Singular => "Singular",
        Error::WorkCap => "WorkCap",
        _ => "other",
    }
}

/// A float printed as `{:e}` and its bit pattern (the text the host and the target compare).
pub(crate) struct F(pub(crate) f32);
impl fmt::Display for F {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:e} ({:08x})", self.0, self.0.to_bits())
    }
}

/// Runs the scene for [`STEPS`](crate::STEPS) steps (a stress scene: its own steps and input) from the
/// model's current state, printing to `out`. The text is identical on the host and on the
/// target.
pub fn run<M: Sim, W: Write, P: Probe>(
    m: &mut M,
    setup: &Setup,
    out: &mut W,
    probe: &mut P,
) -> Summary {
    let h = m.h();
    let steps = setup.steps();
    let _ = writeln!(
        out,
        "scene {} h={} steps={} A={:e} f={:e}",
        M::name(),
        F(h),
        steps,
        setup.amplitude(),
        M::frequency()
    );
    if let Some(st) = setup.stress {
        let _ = writeln!(out, "stress {}", st.name);
    }
    let _ = writeln!(out, "static tip={}", F(m.static_tip()));
    {
        use absorber_core::work as w;
        let _ = writeln!(
            out,
            "work cap={} refresh={} residual={} solve={} fallback={}",
            m.work_cap(),
            w::REFRESH,
            w::RESIDUAL,
            w::SOLVE,
            w::FALLBACK
        );
    }
    let mut hash = Fnv::default();
    let mut s = Summary::default();
    if let Some(rate) = setup.stress.and_then(|st| st.spin) {
        if let Err(e) = m.spin_start(rate) {
            let _ = writeln!(out, "spun start failed: {}", error_name(&e));
        }
    }
    let mut rng = stress::Rng::default();
    let mut run = 0u32;
    // Impact steps printed on the current line (16 per line).
    let mut on_line = 0u32;
    for k in 1..=steps {
        let accel = match setup.stress {
            Some(st) => st.accel(k, h, M::frequency(), &mut rng),
            None => base_accel(k, h, M::frequency()),
        };
        m.environment(accel);
        probe.before_step();
        let r = m.step(accel);
        probe.after_step();
        let normal = match r {
            Ok(rep) => {
                s.iterations += rep.iterations;
                s.max_iterations = s.max_iterations.max(rep.iterations);
                s.max_work = s.max_work.max(u32::from(rep.work));
                hash.word(rep.iterations);
                hash.word(rep.increment.to_bits());
                hash.word(u32::from(rep.work));
                hash.word(rep.outcome as u32);
                if let Some(i) = rep.impact {
                    s.impacts += 1;
                    s.stuck += u32::from(i.stuck);
                    for w in [i.time, i.relative_speed, i.impulse, i.energy_loss] {
                        hash.word(w.to_bits());
                    }
                    hash.word(u32::from(i.stuck));
                    // Which steps hit a stop, 16 per line (the report looks up the worst step).
                    if on_line == 0 {
                        let _ = write!(out, "impact steps:");
                    }
                    let _ = write!(out, " {k}");
                    on_line += 1;
                    if on_line == 16 {
                        let _ = writeln!(out);
                        on_line = 0;
                    }
                }
                match rep.outcome {
                    Outcome::Converged => true,
                    Outcome::Capped => {
                        s.capped += 1;
                        false
                    }
                    Outcome::Restarted => {
                        s.restarts += 1;
                        false
                    }
                }
            }
            Err(e) => {
                s.errors += 1;
                hash.word(0xdead_0000 | s.errors);
                if s.errors <= 20 {
                    let _ = writeln!(out, "step {k}: error {} (state kept)", error_name(&e));
                }
                false
            }
        };
        run = if normal { 0 } else { run + 1 };
        s.longest_error_run = s.longest_error_run.max(run);
        m.state_words(&mut |w| hash.word(w));
        // Every whole second of simulated time (k h crosses j seconds).
        if (k * STEP_MS) / 1000 != ((k - 1) * STEP_MS) / 1000 {
            if on_line != 0 {
                let _ = writeln!(out);
                on_line = 0;
            }
            let _ = writeln!(out, "k={k} tip={} ball={}", F(m.tip()), F(m.ball()));
            m.second(out, &mut |w| hash.word(w));
        }
    }
    if on_line != 0 {
        let _ = writeln!(out);
    }
    s.hash = hash.0;
    let _ = writeln!(
        out,
        "impacts={} stuck={} iterations={} max_iterations={} errors={}",
        s.impacts, s.stuck, s.iterations, s.max_iterations, s.errors
    );
    let _ = writeln!(
        out,
        "capped={} restarts={} error_steps={} longest_error_run={} max_work={}",
        s.capped,
        s.restarts,
        s.error_steps(),
        s.longest_error_run,
        s.max_work
    );
    let _ = writeln!(out, "state_hash=0x{:016x}", s.hash);
    s
}

/// Host side: runs the scene (`stress=<name>` on the command line: a stress scene) and prints
/// the reference (the firmware must print the same).
#[cfg(not(target_os = "none"))]
pub fn host_main<M: Sim>() {
    use std::io::Write as _;
    struct Out(String);
    impl Write for Out {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            self.0.push_str(s);
            Ok(())
        }
    }
    let mut setup = Setup::default();
    for a in std::env::args().skip(1) {
        if setup.arg(&a).is_err() {
            eprintln!("unknown stress scene in `{a}`");
            std::process::exit(4);
        }
    }
    let mut out = Out(String::new());
    let mut slot = Box::new(MaybeUninit::<M>::uninit());
    let code = match M::init_in(&mut slot, &setup) {
        Ok(m) => {
            run(m, &setup, &mut out, &mut NoProbe);
            0
        }
        Err(e) => {
            let _ = writeln!(out, "init failed: {}", error_name(&e));
            3
        }
    };
    let _ = std::io::stdout().write_all(out.0.as_bytes());
    std::process::exit(code);
}
