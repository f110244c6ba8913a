//! Running a scene: the solver chosen by the scene, the excitation on the step grid, one
//! [`Row`] per step, CSV output.

use crate::excitation::{self, Excitation};
use crate::scene::{Scene, Solver};
use absorber_full::sim::Simulator;
use anyhow::{anyhow, bail, Result};

/// Builds the scene's solver at rest in the static equilibrium with input `base_accel0` at t = 0.
pub fn build_simulator(scene: &Scene, base_accel0: f64) -> Result<Box<dyn Simulator>> {
    let mut sim = build_at_rest(scene, base_accel0)?;
    let rate = scene.file.ball.initial_rate;
    if rate != 0.0 && scene.file.kind.free_ball() {
        sim.set_ball_rate(rate).map_err(|e| {
            anyhow!(
                "cannot start with `ball.initial_rate` = {rate} rad/s: {}",
                crate::scene::physical_failure(e, scene)
            )
        })?;
    }
    Ok(sim)
}

/// The scene's solver at rest in the static equilibrium (the ball at `ball.initial_angle_deg`,
/// without its initial rate).
fn build_at_rest(scene: &Scene, base_accel0: f64) -> Result<Box<dyn Simulator>> {
    let f = &scene.file;
    let params = scene.params()?;
    match f.solver {
        Solver::Core => {
            crate::core_sim::build(f.kind, f.elements, f.precision, &params, base_accel0)
                .map_err(|e| start_error(e, scene))
        }
        Solver::Full => {
            use crate::scene::{Kind, Precision};
            use absorber_full::{FullSolver, SceneKind};
            if f.precision != Precision::F64 {
                bail!("the full solver is f64 only (use --precision f64 or --solver core)");
            }
            if params.integrator.events != absorber_core::EventLocation::Crossing {
                bail!(
                    "`integrator.events = \"step-end\"` is an option of the embedded core; the \
                     full solver, the reference, always splits the step at an event (use \
                     --solver core, or events = \"crossing\")"
                );
            }
            let kind = match f.kind {
                Kind::Beam => SceneKind::BeamOnly,
                Kind::Tip => SceneKind::TipMass,
                Kind::Locked => SceneKind::LockedBall,
                Kind::Free => SceneKind::FreeBall,
                Kind::FreeNostops => SceneKind::FreeBallNoStops,
            };
            let sim = FullSolver::at_rest(params, kind, f.elements, base_accel0)
                .map_err(|e| start_error(e, scene))?;
            Ok(Box::new(sim))
        }
    }
}

/// A failure to start: a parameter error names its key; a failed static solve says so.
fn start_error(e: absorber_core::Error, scene: &Scene) -> anyhow::Error {
    match e {
        absorber_core::Error::InvalidParameter { .. } => crate::scene::map_core_error(e, scene),
        other => anyhow!(
            "cannot start: the static equilibrium under gravity could not be solved ({}); check \
             that the magnitudes of `beam.*`, `tip.*`, `ball.*` and `gravity` describe a beam that \
             can carry its load",
            crate::scene::physical_failure(other, scene)
        ),
    }
}

/// One output sample. SI units, angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Time \[s\].
    pub t: f64,
    /// Base displacement y_b \[m\].
    pub base_y: f64,
    /// Absolute vertical position of the beam end, y_b + deflection \[m\].
    pub tip_y: f64,
    /// Deflection of the beam end relative to the base (static sag included) \[m\].
    pub tip_deflection: f64,
    /// Tip mass rotation ψ \[rad\].
    pub tip_angle: f64,
    /// Ball orbit angle θ from the downward vertical \[rad\] (NaN without a free ball: a
    /// locked ball turns with the tip mass, [`Row::tip_angle`]; so are its rates and spin).
    pub ball_angle: f64,
    /// Ball angle relative to the housing α = θ − ψ \[rad\].
    pub ball_rel_angle: f64,
    /// Energies \[J\] with absolute velocities (base velocity included).
    pub energies: absorber_core::Energies<f64>,
    /// Newton iterations of the step that ended here (0 at t = 0).
    pub iterations: u32,
    /// A stop impact happened in the step that ended here.
    pub impact: bool,
    /// Base acceleration ÿ_b \[m/s²\].
    pub base_accel: f64,
    /// Relative tip velocity ẏ \[m/s\].
    pub tip_velocity: f64,
    /// ψ̇ \[rad/s\].
    pub tip_rate: f64,
    /// θ̇ \[rad/s\].
    pub ball_rate: f64,
    /// α̇ \[rad/s\].
    pub ball_rel_rate: f64,
    /// Ball spin angle φ = ψ − (ρ/r_b) α \[rad\] (paper eq. 28; 0 in the static state).
    pub ball_spin: f64,
    /// φ̇ \[rad/s\].
    pub ball_spin_rate: f64,
    /// Normal force of the track on the ball \[N\] (negative: the track pulls, which a real
    /// track cannot; NaN without a free ball; `absorber_core::ContactForces`).
    pub normal_force: f64,
    /// Tangential force of the track on the ball \[N\] (rolling friction; plus the stop's
    /// reaction while the ball rests on a stop; NaN without a free ball).
    pub tangential_force: f64,
    /// 1: the ball is on the track, 0: in flight (NaN without a free ball).
    pub contact: f64,
    /// Absolute vertical acceleration of the beam end, ÿ_b + the relative acceleration
    /// \[m/s²\] (gravity not included: what a tip accelerometer reads).
    pub tip_acceleration: f64,
    /// The ball left the track during the step (not a CSV column).
    pub separated: bool,
    /// A landing during the step: `(bounced, required friction |P_t|/P_n)` (not a CSV column).
    pub landing: Option<(bool, f64)>,
    /// How many separations, landings and stop impacts the step had (a step can hold several;
    /// not a CSV column: `impact` says whether there was one).
    pub events: absorber_core::EventCounts,
}

/// The CSV header (also documents the columns).
pub const CSV_HEADER: &str = "\
# host-sim run: one row per output step. SI units, angles in rad.
# t [s]; base_y: base displacement y_b [m]; tip_y: absolute vertical position of the beam end (y_b + deflection) [m];
# tip_deflection: beam end relative to the base, static sag included [m]; tip_angle: tip mass rotation psi [rad];
# ball_angle: ball orbit angle theta from the downward vertical [rad]; ball_rel_angle: theta - psi [rad]
#   (these, the ball's rates and spin are NaN unless the ball is free: a locked ball turns with the tip mass, tip_angle);
# beam_strain, beam_kinetic, beam_potential, tip_kinetic, tip_potential, ball_kinetic, ball_potential [J]
#   (kinetic with absolute velocities, potentials as changes from the static state plus the base displacement);
# iterations: Newton iterations of the step; impact: 1 if the ball hit a stop in the step;
# base_accel [m/s^2]; tip_velocity [m/s]; tip_rate, ball_rate, ball_rel_rate [rad/s];
# ball_spin: phi = psi - (rho/r_b)(theta - psi) [rad]; ball_spin_rate [rad/s];
# normal_force: track on ball, towards the track centre [N] (< 0: the track pulls: a real ball would leave it);
# tangential_force: track on ball along increasing theta [N] (friction rolling needs; plus a stop's reaction);
# contact: 1 the ball is on the track, 0 it flies inside the housing (then ball_angle is the polar angle of its centre);
# tip_acceleration: absolute vertical acceleration of the beam end, base_accel + relative [m/s^2] (what a tip accelerometer reads, gravity not included)
t,base_y,tip_y,tip_deflection,tip_angle,ball_angle,ball_rel_angle,beam_strain,beam_kinetic,beam_potential,tip_kinetic,tip_potential,ball_kinetic,ball_potential,iterations,impact,base_accel,tip_velocity,tip_rate,ball_rate,ball_rel_rate,ball_spin,ball_spin_rate,normal_force,tangential_force,contact,tip_acceleration";

/// Names of the CSV columns, in order (the last line of [`CSV_HEADER`]).
pub fn csv_columns() -> Vec<&'static str> {
    CSV_HEADER
        .lines()
        .last()
        .unwrap_or_default()
        .split(',')
        .collect()
}

impl Row {
    /// The row's values in the order of [`csv_columns`] (`iterations` and `impact` as numbers).
    pub fn values(&self) -> [f64; 27] {
        let e = &self.energies;
        [
            self.t,
            self.base_y,
            self.tip_y,
            self.tip_deflection,
            self.tip_angle,
            self.ball_angle,
            self.ball_rel_angle,
            e.beam_strain,
            e.beam_kinetic,
            e.beam_potential,
            e.tip_kinetic,
            e.tip_potential,
            e.ball_kinetic,
            e.ball_potential,
            f64::from(self.iterations),
            f64::from(u8::from(self.impact)),
            self.base_accel,
            self.tip_velocity,
            self.tip_rate,
            self.ball_rate,
            self.ball_rel_rate,
            self.ball_spin,
            self.ball_spin_rate,
            self.normal_force,
            self.tangential_force,
            self.contact,
            self.tip_acceleration,
        ]
    }

    /// The row as a CSV line (no newline): [`Row::values`], `iterations` and `impact` as
    /// integers, `contact` as 0 or 1 (or NaN), everything else with 10 significant digits in
    /// Rust's `{:.9e}` form, byte for byte (`push_sci10`, checked against `format!`).
    pub fn csv(&self) -> String {
        let mut b = Vec::with_capacity(27 * 17);
        self.write_csv(&mut b);
        // (ASCII only: the conversion cannot fail.)
        String::from_utf8(b).unwrap_or_default()
    }

    /// [`Row::csv`] appended to `b` as ASCII bytes (no allocation when `b` has room).
    pub fn write_csv(&self, b: &mut Vec<u8>) {
        for (i, x) in self.values().iter().enumerate() {
            if i > 0 {
                b.push(b',');
            }
            match i {
                14 => push_u32(b, self.iterations),
                15 => b.push(if self.impact { b'1' } else { b'0' }),
                25 if x.is_finite() => b.push(if *x > 0.5 { b'1' } else { b'0' }),
                _ => push_sci10(b, *x),
            }
        }
    }
}

/// Appends `n` in decimal (as `n.to_string()`).
fn push_u32(b: &mut Vec<u8>, n: u32) {
    let mut buf = [0u8; 10];
    let mut k = buf.len();
    let mut n = n;
    loop {
        k -= 1;
        buf[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    b.extend_from_slice(&buf[k..]);
}

/// `10^k`, k = 0..=22: exact in `f64` (`5^22 < 2^53`).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Appends `x` exactly as `format!("{x:.9e}")` does (the exact binary value rounded to 10
/// significant digits, `d.ddddddddde±x`), at a fraction of its cost. With `E` the decimal
/// exponent of `|x|` and `|9 − E| ≤ 44`, `y = |x|·10^(9−E)` (or `|x| / 10^(E−9)`) takes one
/// or two correctly rounded operations by exact powers of ten (`10^k`, `k ≤ 22`), so
/// `|y − Y| ≤ 2⁻⁵²·Y < 2.3·10⁻⁶` for the exact `Y ∈ [10⁹, 10¹⁰)` (each rounding at most
/// 2⁻⁵³ relative); the 10 digits are `round(Y)`, which is `round(y)` unless `Y`'s fraction
/// is within that of ½ (an error across an integer moves `⌊y⌋` and the fraction together:
/// the same rounded integer). Values whose
/// fraction `y − ⌊y⌋` is within 10⁻⁴ of ½ (about 2·10⁻⁴ of all), `E` outside `−35..=53` and
/// subnormals go through `format!` itself; zeros, NaN and ±∞ are written as `format!` spells
/// them. Checked against `format!` in the tests.
fn push_sci10(b: &mut Vec<u8>, x: f64) {
    let fallback = |b: &mut Vec<u8>| b.extend_from_slice(format!("{x:.9e}").as_bytes());
    let a = x.abs();
    // `format!`'s spelling of the special values (the columns without a ball are NaN).
    let special: Option<&[u8]> = if x.is_nan() {
        Some(b"NaN")
    } else if x == f64::INFINITY {
        Some(b"inf")
    } else if x == f64::NEG_INFINITY {
        Some(b"-inf")
    } else if x == 0.0 {
        Some(if x.is_sign_negative() {
            b"-0.000000000e0"
        } else {
            b"0.000000000e0"
        })
    } else {
        None
    };
    if let Some(text) = special {
        return b.extend_from_slice(text);
    }
    if a < f64::MIN_POSITIVE {
        return fallback(b);
    }
    let scaled = |e10: i32| -> Option<f64> {
        let k = 9 - e10;
        let (big, rest) = match k.unsigned_abs() as usize {
            j if j > 22 => (true, j - 22),
            j => (false, j),
        };
        let p = *POW10.get(rest)?;
        Some(match (k >= 0, big) {
            (true, false) => a * p,
            (true, true) => a * 1e22 * p,
            (false, false) => a / p,
            (false, true) => a / 1e22 / p,
        })
    };
    // E is ⌊e₂ log₁₀ 2⌋ or one more (a ∈ [2^e₂, 2^(e₂+1))). The floor in integers,
    // log₁₀ 2 ≈ 78913 / 2¹⁸ with an arithmetic shift: equal to the floating-point floor for
    // every normal exponent (test `log10_floor_in_integers`), without a libm call on a target
    // without SSE4.1.
    let e2 = ((a.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let mut e10 = (e2 * 78_913) >> 18;
    let Some(mut y) = scaled(e10) else {
        return fallback(b);
    };
    if y < 1e9 {
        // (Not reached: E ≥ the estimate.)
        return fallback(b);
    }
    if y >= 1e10 {
        e10 += 1;
        // (y may now round to just below 10⁹; round(y) below gives 10⁹ then.)
        match scaled(e10) {
            Some(v) => y = v,
            None => return fallback(b),
        }
    }
    // ⌊y⌋ by truncation (y ∈ [10⁹, 10¹⁰) is positive; exact, no libm `floor`).
    let whole = y as u64;
    let frac = y - whole as f64;
    if (frac - 0.5).abs() <= 1e-4 {
        return fallback(b);
    }
    let mut mant = whole + u64::from(frac > 0.5);
    if mant == 10_000_000_000 {
        mant = 1_000_000_000;
        e10 += 1;
    }
    // Sign, d.ddddddddd, e, sign, at most 2 exponent digits (|E| ≤ 54 here).
    if e10.unsigned_abs() >= 100 {
        return fallback(b);
    }
    let mut out = [0u8; 17];
    let mut k = usize::from(x < 0.0);
    out[0] = b'-';
    // The 9 digits after the point two at a time (mant < 10¹⁰: its first digit is < 10).
    let mut rest = mant % 1_000_000_000;
    let mut pos = k + 10;
    let pair = |r: u64, pos: usize, out: &mut [u8; 17]| {
        out[pos] = b'0' + (r % 10) as u8;
        out[pos - 1] = b'0' + (r / 10) as u8;
    };
    for _ in 0..4 {
        pair(rest % 100, pos, &mut out);
        rest /= 100;
        pos -= 2;
    }
    out[k + 2] = b'0' + rest as u8;
    out[k] = b'0' + (mant / 1_000_000_000) as u8;
    out[k + 1] = b'.';
    out[k + 11] = b'e';
    k += 12;
    if e10 < 0 {
        out[k] = b'-';
        k += 1;
    }
    let e = e10.unsigned_abs();
    if e >= 10 {
        pair(u64::from(e), k + 1, &mut out);
        k += 2;
    } else {
        out[k] = b'0' + e as u8;
        k += 1;
    }
    b.extend_from_slice(&out[..k]);
}

/// Steps a scene through `steps` steps, calling `sink` with the initial row and after every
/// step. `progress(k)` is called every 500 steps. A failed step ends the run with an error
/// naming the time.
pub fn simulate(
    scene: &Scene,
    exc: &Excitation,
    steps: usize,
    mut sink: impl FnMut(&Row),
    progress: impl FnMut(usize),
) -> Result<()> {
    simulate_with(
        scene,
        exc,
        steps,
        |r| {
            sink(r);
            Ok(())
        },
        progress,
    )
}

/// As [`simulate`], with a sink that can fail (e.g. a full disk): its error ends the run.
pub fn simulate_with(
    scene: &Scene,
    exc: &Excitation,
    steps: usize,
    mut sink: impl FnMut(&Row) -> Result<()>,
    mut progress: impl FnMut(usize),
) -> Result<()> {
    let params = scene.params()?;
    let spin_ratio = params.ball.path_radius() / params.ball.radius;
    let b0 = exc.at(0);
    let mut sim = build_simulator(scene, b0.accel)?;
    // A locked ball has no angle of its own: it turns with the tip mass (θ = ψ), which the
    // `tip_angle` column already gives; its angle columns are NaN, as without a ball.
    let free = scene.file.kind.free_ball();
    let row = |sim: &dyn Simulator, k: usize, report: Option<&absorber_core::StepReport<f64>>| {
        let mut o = sim.observe();
        if !free {
            o.ball_angle = f64::NAN;
            o.ball_rate = f64::NAN;
            o.ball_relative_angle = f64::NAN;
            o.ball_relative_rate = f64::NAN;
        }
        let contact = sim.contact_forces();
        let b = exc.at(k);
        Row {
            t: o.time,
            base_y: b.displacement,
            tip_y: b.displacement + o.tip_deflection,
            tip_deflection: o.tip_deflection,
            tip_angle: o.tip_angle,
            ball_angle: o.ball_angle,
            ball_rel_angle: o.ball_relative_angle,
            energies: sim.energies(b.velocity, b.displacement),
            iterations: report.map_or(0, |r| r.iterations),
            impact: report.is_some_and(|r| r.impact.is_some()),
            base_accel: b.accel,
            tip_velocity: o.tip_velocity,
            tip_rate: o.tip_rate,
            ball_rate: o.ball_rate,
            ball_rel_rate: o.ball_relative_rate,
            ball_spin: o.tip_angle - spin_ratio * o.ball_relative_angle,
            ball_spin_rate: o.tip_rate - spin_ratio * o.ball_relative_rate,
            normal_force: contact.map_or(f64::NAN, |c| c.0),
            tangential_force: contact.map_or(f64::NAN, |c| c.1),
            contact: contact.map_or(f64::NAN, |_| if sim.in_flight() { 0.0 } else { 1.0 }),
            tip_acceleration: b.accel + o.tip_acceleration,
            separated: report.is_some_and(|r| r.separation.is_some()),
            landing: report
                .and_then(|r| r.landing)
                .map(|l| (l.bounced, l.required_friction().unwrap_or(f64::NAN))),
            events: report.map_or_else(Default::default, |r| r.events),
        }
    };
    sink(&row(sim.as_ref(), 0, None))?;
    for k in 1..=steps {
        let b = exc.at(k);
        let report = sim.step(b.accel).map_err(|e| {
            anyhow!(
                "step {k} of {steps} (t = {:.4} s, base acceleration {:.4e} m/s²) failed: {}",
                k as f64 * scene.file.integrator.step,
                b.accel,
                scene_error(e, scene)
            )
        })?;
        sink(&row(sim.as_ref(), k, Some(&report)))?;
        if k % 500 == 0 {
            progress(k);
            crate::interrupt::check()?;
        }
    }
    progress(steps);
    Ok(())
}

fn scene_error(e: absorber_core::Error, scene: &Scene) -> anyhow::Error {
    crate::scene::map_core_error(e, scene)
}

/// The excitation of a scene for its duration.
pub fn scene_excitation(scene: &Scene) -> Result<Excitation> {
    excitation::of_scene(scene, scene.steps())
}

/// Runs a scene for its duration and keeps every row (for the fixed, short runs of the
/// reports; commands stream with [`simulate`] and [`RunStats`]).
pub fn run_rows(scene: &Scene, progress: impl FnMut(usize)) -> Result<Vec<Row>> {
    let exc = scene_excitation(scene)?;
    let steps = scene.steps();
    let mut rows = Vec::new();
    rows.try_reserve(steps + 1)
        .map_err(|_| anyhow!("a run of {steps} steps does not fit in memory here"))?;
    simulate(scene, &exc, steps, |r| rows.push(*r), progress)?;
    Ok(rows)
}

/// The one definition of "steady" of `paper`, `run`, `sweep` and `fatigue`: every sample with
/// t ≥ `from` (the transient `outputs.transient`, 20 s by default, or `sweep --last`'s start),
/// to the end of the run; every steady figure of a table row is over this window. The label
/// their tables and JSON carry.
pub fn steady_label(from: f64) -> String {
    format!("steady: t ≥ {} s to the end", secs(from))
}

/// A time in seconds as a reader writes it: to the microsecond, trailing zeros dropped
/// (`4.999`, not the sum's `4.9990000000000006`).
pub fn secs(t: f64) -> String {
    trimmed(t, 6)
}

/// `x` with `decimals` decimals, trailing zeros and a trailing point dropped.
pub fn trimmed(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Summary figures of a run, accumulated row by row in fixed memory.
#[derive(Clone, Debug)]
pub struct RunStats {
    steady_from: f64,
    window: f64,
    end: f64,
    first: Option<Row>,
    last_t: f64,
    tip_max: f64,
    tip_lo: f64,
    tip_hi: f64,
    ball_max: f64,
    ball_lo: f64,
    ball_hi: f64,
    impacts: u64,
    max_iterations: u32,
    beam_first: (f64, u64),
    beam_last: (f64, u64),
    ball_first: (f64, u64),
    ball_last: (f64, u64),
    /// Σ (tip deflection − static)² and samples over the steady window.
    tip_square: (f64, u64),
    /// Stop impacts in the steady window.
    steady_impacts: u64,
    contact: ContactStats,
}

/// What the track had to do: how often it pulled the ball (N < 0), the smallest N, and the
/// largest friction coefficient rolling needed (|F_t|/N with N > 0, off the stops).
#[derive(Clone, Copy, Debug, Default)]
struct ContactStats {
    /// m_b g \[N\], the stop angle \[rad\] and the friction coefficient (`None`: no free ball).
    ball: Option<(f64, f64, f64)>,
    samples: u64,
    /// Samples off the stops with N > 0 where rolling needs more than the friction coefficient.
    slips: u64,
    steady_slips: u64,
    pulled: u64,
    steady_samples: u64,
    steady_pulled: u64,
    min_normal: f64,
    max_mu: f64,
    /// Samples in flight, whole run and steady part.
    flying: u64,
    steady_flying: u64,
    separations: u64,
    landings: u64,
    bounces: u64,
    /// Plastic landings whose rough impulse needed more friction than the coefficient.
    slipping_landings: u64,
    max_landing_mu: f64,
    /// Separations and landings in the steady window.
    steady_separations: u64,
    steady_landings: u64,
    /// Shortest flight counted by `long_flights` \[s\].
    resolution: f64,
    /// Time of the last row on the track before the current flight (None: on the track).
    flight_start: Option<f64>,
    /// Last row's time.
    previous: Option<f64>,
    /// Flights (from a take-off to the next row on the track, bounces included) of at least
    /// `resolution` that started in the steady window.
    steady_long_flights: u64,
}

impl RunStats {
    /// Also reports the track's forces on a free ball: `(m_b g [N], stop angle [rad], friction
    /// coefficient)` (`None` for scenes without a free ball).
    pub fn with_ball(mut self, ball: Option<(f64, f64, f64)>) -> Self {
        self.contact.ball = ball;
        self.contact.min_normal = f64::INFINITY;
        self
    }

    /// For a run ending at `end` \[s\] whose steady state starts at `steady_from` \[s\]; the mean
    /// energies are taken over the first and the last min(10 s, end/2).
    pub fn new(end: f64, steady_from: f64) -> Self {
        Self {
            steady_from,
            window: 10.0f64.min(end / 2.0),
            end,
            first: None,
            last_t: 0.0,
            tip_max: f64::NAN,
            tip_lo: f64::INFINITY,
            tip_hi: f64::NEG_INFINITY,
            ball_max: f64::NAN,
            ball_lo: f64::INFINITY,
            ball_hi: f64::NEG_INFINITY,
            impacts: 0,
            max_iterations: 0,
            beam_first: (0.0, 0),
            beam_last: (0.0, 0),
            ball_first: (0.0, 0),
            ball_last: (0.0, 0),
            tip_square: (0.0, 0),
            steady_impacts: 0,
            contact: ContactStats {
                resolution: crate::scene::FLIGHT_RESOLUTION,
                ..ContactStats::default()
            },
        }
    }

    /// Counts flights of at least `resolution` \[s\] apart (`outputs.flight_resolution`).
    pub fn with_flight_resolution(mut self, resolution: f64) -> Self {
        self.contact.resolution = resolution;
        self
    }

    /// Adds a row.
    pub fn push(&mut self, r: &Row) {
        let first = *self.first.get_or_insert(*r);
        let static_d = first.tip_deflection;
        self.last_t = r.t;
        let d = r.tip_deflection - static_d;
        if d.is_finite() {
            self.tip_max = self.tip_max.max(d.abs());
        }
        let th = r.ball_angle.to_degrees();
        if th.is_finite() {
            self.ball_max = self.ball_max.max(th.abs());
        }
        // Half a step of slack: the grid time k·h may round just below the window start.
        let eps = 1e-9 * self.end.max(1.0);
        if r.t >= self.steady_from - eps {
            self.tip_lo = self.tip_lo.min(r.tip_deflection);
            self.tip_hi = self.tip_hi.max(r.tip_deflection);
            if d.is_finite() {
                self.tip_square.0 += d * d;
                self.tip_square.1 += 1;
            }
            self.steady_impacts += u64::from(r.events.impacts);
            if th.is_finite() {
                self.ball_lo = self.ball_lo.min(th);
                self.ball_hi = self.ball_hi.max(th);
            }
        }
        self.impacts += u64::from(r.events.impacts);
        self.max_iterations = self.max_iterations.max(r.iterations);
        if let (Some((_, stop, mu)), true) = (self.contact.ball, r.normal_force.is_finite()) {
            let c = &mut self.contact;
            let flying = u64::from(r.contact == 0.0);
            c.flying += flying;
            c.separations += u64::from(r.events.separations);
            let steady = r.t >= self.steady_from - eps;
            if steady {
                c.steady_separations += u64::from(r.events.separations);
                c.steady_landings += u64::from(r.events.landings);
            }
            c.flight(r.t, r.contact == 0.0, self.steady_from - eps);
            c.landings += u64::from(r.events.landings);
            c.bounces += u64::from(r.events.bounces);
            if let Some((bounced, need)) = r.landing {
                if !bounced && need.is_finite() {
                    c.slipping_landings += u64::from(need > mu);
                    c.max_landing_mu = c.max_landing_mu.max(need);
                }
            }
            if r.t >= self.steady_from - eps {
                c.steady_flying += flying;
            }
            let pulled = u64::from(r.normal_force < 0.0);
            // On a stop the tangential force is the stop's, not friction's.
            let on_stop = r.ball_rel_angle.abs() >= stop * (1.0 - 1e-9);
            let need = r.tangential_force.abs() / r.normal_force;
            let slips = u64::from(r.normal_force > 0.0 && !on_stop && need > mu);
            c.samples += 1;
            c.pulled += pulled;
            c.slips += slips;
            if r.t >= self.steady_from - eps {
                c.steady_samples += 1;
                c.steady_pulled += pulled;
                c.steady_slips += slips;
            }
            c.min_normal = c.min_normal.min(r.normal_force);
            if r.normal_force > 0.0 && !on_stop {
                c.max_mu = c.max_mu.max(need);
            }
        }
        let e = &r.energies;
        let beam = e.beam_strain - first.energies.beam_strain + e.beam_kinetic + e.beam_potential;
        let ball = e.ball_kinetic + e.ball_potential;
        let add = |acc: &mut (f64, u64), x: f64| {
            acc.0 += x;
            acc.1 += 1;
        };
        if r.t <= self.window + eps {
            add(&mut self.beam_first, beam);
            add(&mut self.ball_first, ball);
        }
        if r.t >= self.end - self.window - eps {
            add(&mut self.beam_last, beam);
            add(&mut self.ball_last, ball);
        }
    }

    /// The summary as JSON (the `run`/`paper` output).
    pub fn json(&self) -> serde_json::Value {
        let half = |lo: f64, hi: f64| if lo <= hi { 0.5 * (hi - lo) } else { f64::NAN };
        let mean = |a: (f64, u64)| if a.1 > 0 { a.0 / a.1 as f64 } else { f64::NAN };
        let span = self.last_t - self.steady_from;
        let rate = |n: u64| {
            if span > 0.0 {
                n as f64 / span
            } else {
                f64::NAN
            }
        };
        serde_json::json!({
            "duration": self.last_t,
            "steady_from": self.steady_from,
            "static_tip_deflection": self.first.map(|r| r.tip_deflection).unwrap_or(f64::NAN),
            "tip_amplitude_max": self.tip_max,
            "tip_amplitude_steady": half(self.tip_lo, self.tip_hi),
            "ball_angle_max_deg": self.ball_max,
            "ball_angle_steady_deg": half(self.ball_lo, self.ball_hi),
            "impacts": self.impacts,
            "max_iterations": self.max_iterations,
            "energy_window": self.window,
            "beam_energy_first": mean(self.beam_first),
            "beam_energy_last": mean(self.beam_last),
            "ball_energy_first": mean(self.ball_first),
            "ball_energy_last": mean(self.ball_last),
            "tip_rms_steady": mean(self.tip_square).sqrt(),
            "impact_rate_steady": rate(self.steady_impacts),
            "contact": self.contact.json(self.last_t - self.steady_from),
        })
    }
}

impl ContactStats {
    /// Follows the flights row by row: a flight runs from the last row on the track to the next
    /// one (its bounces included), so its length is counted in whole steps.
    fn flight(&mut self, t: f64, flying: bool, steady_from: f64) {
        if flying {
            if self.flight_start.is_none() {
                // (The first row of a run is on the track.)
                self.flight_start = Some(self.previous.unwrap_or(t));
            }
        } else if let Some(t0) = self.flight_start.take() {
            if t - t0 >= self.resolution * (1.0 - 1e-9) && t0 >= steady_from {
                self.steady_long_flights += 1;
            }
        }
        self.previous = Some(t);
    }

    fn json(&self, span: f64) -> serde_json::Value {
        let Some((weight, _, mu)) = self.ball else {
            return serde_json::Value::Null;
        };
        let frac = |k: u64, n: u64| if n > 0 { k as f64 / n as f64 } else { f64::NAN };
        let rate = |n: u64| {
            if span > 0.0 {
                n as f64 / span
            } else {
                f64::NAN
            }
        };
        serde_json::json!({
            "track_pulls_fraction": frac(self.pulled, self.samples),
            "track_pulls_fraction_steady": frac(self.steady_pulled, self.steady_samples),
            "normal_force_min": self.min_normal,
            "normal_force_min_over_weight": self.min_normal / weight,
            "required_friction_max": self.max_mu,
            "friction": mu,
            "slip_fraction": frac(self.slips, self.samples),
            "slip_fraction_steady": frac(self.steady_slips, self.steady_samples),
            "flight_fraction": frac(self.flying, self.samples),
            "flight_fraction_steady": frac(self.steady_flying, self.steady_samples),
            "separations": self.separations,
            "landings": self.landings,
            "bounces": self.bounces,
            "landings_slipping": self.slipping_landings,
            "landing_friction_max": self.max_landing_mu,
            "separation_rate_steady": rate(self.steady_separations),
            "landing_rate_steady": rate(self.steady_landings),
            "long_flight_rate_steady": rate(self.steady_long_flights),
            "flight_resolution": self.resolution,
        })
    }
}

/// Half the peak-to-peak value of `x` over the samples with t ≥ `from` (NaN if none).
pub fn half_range(rows: &[Row], from: f64, x: impl Fn(&Row) -> f64) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in rows.iter().filter(|r| r.t >= from) {
        let v = x(r);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo <= hi {
        0.5 * (hi - lo)
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::{push_sci10, push_u32};

    fn agrees(x: f64) {
        let mut s = Vec::new();
        push_sci10(&mut s, x);
        assert_eq!(
            s,
            format!("{x:.9e}").as_bytes(),
            "bits {:#018x}",
            x.to_bits()
        );
    }

    /// `push_sci10`'s decimal exponent estimate in integers equals the floating-point floor
    /// of `e₂ log₁₀ 2` for every normal binary exponent.
    #[test]
    fn log10_floor_in_integers() {
        for e2 in -1022i32..=1023 {
            let exact = (f64::from(e2) * std::f64::consts::LOG10_2).floor() as i32;
            assert_eq!((e2 * 78_913) >> 18, exact, "e2 = {e2}");
        }
    }

    /// The CSV's number format is `format!("{x:.9e}")` byte for byte: random bit patterns,
    /// random magnitudes of the output's range, and values at and next to the midpoints of
    /// the 10th digit (where the shortest digits are a tie), powers of ten, carries.
    #[test]
    fn sci10_is_std_format() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..100_000 {
            agrees(f64::from_bits(next()));
            // Integers and values just below a power of ten (the carry).
            let m = next() % 100_000_000_000;
            let e = (next() % 30) as i32 - 15;
            agrees(m as f64 * 10f64.powi(e));
            agrees((1.0 - (next() % 1000) as f64 * f64::EPSILON) * 10f64.powi(e));
            let mag = (next() % 100) as i32 - 45;
            let unit = (next() >> 11) as f64 / (1u64 << 53) as f64;
            agrees((unit - 0.5) * 10f64.powi(mag));
            // A midpoint of the 10th digit (11 digits ending in 5) and its neighbours.
            let m = 10_000_000_000 + next() % 90_000_000_000;
            let tie: f64 = format!("{}.{:010}5e{mag}", m / 10_000_000_000, m % 10_000_000_000)
                .parse()
                .unwrap_or(0.0);
            for y in [tie, tie.next_up(), tie.next_down(), -tie] {
                agrees(y);
            }
        }
        for x in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            9.9999999995,
            9.999999999499999,
            99_999_999_995.0,
            1e-300,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 3.0,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            agrees(x);
        }
        for e in -320..=308 {
            let p: f64 = format!("1e{e}").parse().unwrap_or(0.0);
            for y in [p, p.next_up(), p.next_down()] {
                agrees(y);
            }
        }
    }

    #[test]
    fn u32_is_to_string() {
        for n in [0, 1, 9, 10, 99, 100, 12_345, u32::MAX] {
            let mut s = Vec::new();
            push_u32(&mut s, n);
            assert_eq!(s, n.to_string().as_bytes());
        }
    }
}
