//! One FMU instance, whatever the FMI version: its mode, parameters, inputs, model and
//! logger. `fmi2.rs` and `fmi3.rs` only translate the C calls to these methods and the
//! [`Status`] back.
//!
//! **Time and the input.** The model has a fixed step h (the scene's `integrator.step`). A
//! communication step of k·h runs k steps; any other length is refused (`Discard`, nothing
//! done, a log message). Inputs are held over the communication step (zero-order hold, the
//! FMI default); the core's step solves its equations at the end of the step, with the held
//! base acceleration and tip load. A run sampled on the grid (`host-sim run`, where step k
//! takes the sample at t_k) is reproduced by setting, before the step from t_k, the sample of
//! t_(k+1).
//!
//! **State.** [`Instance::snapshot`] copies everything that determines the future (model,
//! monitor, inputs, parameters, mode); restoring it continues bit for bit. The serialized form
//! is a header (magic, format, library build, instantiation token, model type, sizes) and the
//! model's bytes; it is read back only by the same library build with the same token.

use crate::config::{Config, Fnv};
use crate::sim::{self, Outputs, Sim};
use crate::vars::{self, Causality, Output, Slot, Type, Var};
use absorber_core::{Error, Params};

/// Largest |base acceleration| a step accepts \[m/s²\] (the core's limit).
pub const MAX_BASE_ACCEL: f64 = absorber_core::MAX_BASE_ACCEL;
/// Largest |tip load| \[N\] (the core's limit).
pub const MAX_TIP_LOAD: f64 = absorber_core::loads::MAX_LOAD;

/// Result of a call (the same numbers in FMI 2 and 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Done.
    Ok = 0,
    /// Done, with a remark.
    Warning = 1,
    /// Not done; the instance is unchanged and usable.
    Discard = 2,
    /// Failed; only reset, state restore or free are allowed now.
    Error = 3,
    /// The instance is unusable.
    Fatal = 4,
}

impl Status {
    /// The log category of a message of this status.
    pub fn category(self) -> &'static str {
        match self {
            Status::Ok => "logEvents",
            Status::Warning => "logStatusWarning",
            Status::Discard => "logStatusDiscard",
            Status::Error => "logStatusError",
            Status::Fatal => "logStatusFatal",
        }
    }
}

/// The log categories (`modelDescription.xml` lists them).
pub const LOG_CATEGORIES: [(&str, &str); 5] = [
    ("logEvents", "Initialization, reset, termination"),
    ("logStatusWarning", "Calls that succeeded with a remark"),
    (
        "logStatusDiscard",
        "Calls refused without a change (a communication step that is not k h)",
    ),
    (
        "logStatusError",
        "Calls that failed (bad parameter or input, a step of the model that failed)",
    ),
    ("logStatusFatal", "Unusable instance"),
];

/// Where messages go: the importer's callback, by FMI version.
pub trait Log {
    /// Passes `message` of `status` to the importer.
    fn log(&self, status: Status, category: &str, message: &str);
}

/// The instance's mode (FMI state machine, co-simulation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// After instantiate or reset: parameters and inputs may be set.
    Instantiated,
    /// Initialization mode: as instantiated; outputs may be read.
    Initialization,
    /// Step mode: inputs may be set, steps taken.
    Step,
    /// After terminate: outputs may be read.
    Terminated,
    /// After an error: reset, state restore or free.
    Failed,
}

/// Everything that determines the instance's future (an FMU state).
pub struct Snapshot {
    mode: Mode,
    params: Params<f64>,
    inputs: [f64; 2],
    start_time: f64,
    sim: Option<Box<dyn Sim>>,
}

impl Clone for Snapshot {
    fn clone(&self) -> Self {
        Self {
            mode: self.mode,
            params: self.params,
            inputs: self.inputs,
            start_time: self.start_time,
            sim: self.sim.as_ref().map(|s| s.clone_box()),
        }
    }
}

/// An FMU instance.
pub struct Instance {
    /// The importer's name for it.
    pub name: String,
    /// Debug logging on: `logEvents` messages are passed on too.
    pub logging: bool,
    log: Box<dyn Log>,
    config: Config,
    token: String,
    now: Snapshot,
}

/// Magic of a serialized state.
const MAGIC: u64 = u64::from_le_bytes(*b"ABSFMUST");
/// Format of the serialized state.
const FORMAT: u64 = 1;
/// Header words: magic, format, build, token, model type, model bytes, mode, start time,
/// two inputs, number of parameters.
const HEADER_WORDS: usize = 11;

fn hash(s: &str) -> u64 {
    let mut h = Fnv::new();
    h.write(s.as_bytes());
    h.0
}

fn mode_code(m: Mode) -> u64 {
    match m {
        Mode::Instantiated => 0,
        Mode::Initialization => 1,
        Mode::Step => 2,
        Mode::Terminated => 3,
        Mode::Failed => 4,
    }
}

fn mode_of(code: u64) -> Option<Mode> {
    [
        Mode::Instantiated,
        Mode::Initialization,
        Mode::Step,
        Mode::Terminated,
        Mode::Failed,
    ]
    .into_iter()
    .find(|m| mode_code(*m) == code)
}

/// The parameter variables of `kind`'s table, in table order.
fn parameters(config: &Config) -> impl Iterator<Item = &'static Var> {
    vars::of_kind(config.kind).filter(|v| v.causality == Causality::Parameter)
}

impl Instance {
    /// A new instance of `config` (parameters at their start values, inputs 0).
    pub fn new(name: &str, config: Config, logging: bool, log: Box<dyn Log>) -> Self {
        let token = config.token();
        Self {
            name: name.to_string(),
            logging,
            log,
            now: Snapshot {
                mode: Mode::Instantiated,
                params: config.params,
                inputs: [0.0; 2],
                start_time: 0.0,
                sim: None,
            },
            config,
            token,
        }
    }

    /// The instantiation token of the configuration.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The mode.
    pub fn mode(&self) -> Mode {
        self.now.mode
    }

    /// Logs `message` (every status but `Ok` always; `Ok` only with debug logging on) and
    /// returns `status`.
    pub fn say(&self, status: Status, message: &str) -> Status {
        if status != Status::Ok || self.logging {
            self.log.log(status, status.category(), message);
        }
        status
    }

    /// An error: logged, and the instance fails.
    fn fail(&mut self, message: &str) -> Status {
        self.now.mode = Mode::Failed;
        self.say(Status::Error, message)
    }

    /// Current time \[s\].
    pub fn time(&self) -> f64 {
        let steps = self.now.sim.as_ref().map_or(0, |s| s.steps());
        self.now.start_time + steps as f64 * self.config.step()
    }

    /// A core error in words, with the variable it concerns and its value.
    fn describe(&self, e: &Error) -> String {
        match e {
            Error::InvalidParameter { field, reason } => {
                let value = vars::of_kind(self.config.kind)
                    .find(|v| v.name == *field)
                    .and_then(|v| match v.slot {
                        Slot::Param { get, .. } => Some(format!(" = {}", get(&self.now.params))),
                        _ => None,
                    })
                    .unwrap_or_default();
                format!("invalid parameter `{field}`{value}: {reason}")
            }
            other => format!("{other}"),
        }
    }

    /// Switches to initialization mode with the experiment's start time.
    pub fn enter_initialization(&mut self, start_time: f64) -> Status {
        if self.now.mode != Mode::Instantiated {
            return self.say(
                Status::Error,
                "enter initialization mode: only allowed after instantiate or reset",
            );
        }
        if !start_time.is_finite() {
            return self.say(Status::Error, "start time is not finite");
        }
        self.now.start_time = start_time;
        self.now.mode = Mode::Initialization;
        Status::Ok
    }

    /// Builds the model (if the outputs were not read in initialization mode already).
    fn ensure_model(&mut self) -> Result<(), String> {
        if self.now.sim.is_some() {
            return Ok(());
        }
        self.check_inputs()?;
        let [a, f] = self.now.inputs;
        match sim::build(&self.config, &self.now.params, a, f) {
            Ok(s) => {
                self.now.sim = Some(s);
                Ok(())
            }
            Err(e) => Err(format!(
                "cannot start the model: {} (the static equilibrium is solved from the parameters)",
                self.describe(&e)
            )),
        }
    }

    /// Leaves initialization mode: the model is built at rest in its static equilibrium.
    pub fn exit_initialization(&mut self) -> Status {
        if self.now.mode != Mode::Initialization {
            return self.say(
                Status::Error,
                "exit initialization mode: only allowed in initialization mode",
            );
        }
        match self.ensure_model() {
            Ok(()) => {
                self.now.mode = Mode::Step;
                let msg = format!(
                    "model {} ({} elements, {}) started at rest, h = {} s",
                    self.config.kind.name(),
                    self.config.elements,
                    if self.config.single { "f32" } else { "f64" },
                    self.config.step()
                );
                self.say(Status::Ok, &msg)
            }
            Err(m) => self.fail(&m),
        }
    }

    /// Inputs finite and within the core's limits (errors name the input).
    fn check_inputs(&self) -> Result<(), String> {
        let limits = [MAX_BASE_ACCEL, MAX_TIP_LOAD];
        for ((name, x), max) in vars::INPUTS.iter().zip(self.now.inputs).zip(limits) {
            if !x.is_finite() || x.abs() > max {
                return Err(format!(
                    "invalid input `{name}` = {x}: must be finite and within ±{max:e}"
                ));
            }
        }
        Ok(())
    }

    fn variable(&self, vr: u32, ty: Type) -> Result<&'static Var, String> {
        match vars::find(vr, self.config.kind) {
            Some(v) if v.ty == ty => Ok(v),
            Some(v) => Err(format!(
                "variable `{}` (value reference {vr}) is not of type {ty:?}",
                v.name
            )),
            None => Err(format!(
                "no variable with value reference {vr} in this FMU (scene kind {})",
                self.config.kind.name()
            )),
        }
    }

    /// The outputs now; in initialization mode the model is built from the current values.
    fn outputs(&mut self) -> Result<Outputs, String> {
        if self.now.mode == Mode::Initialization {
            self.ensure_model()?;
        }
        self.now
            .sim
            .as_ref()
            .map(|s| s.outputs())
            .ok_or_else(|| "outputs are available from initialization mode on".to_string())
    }

    /// `fmi*GetFloat64`/`GetReal`.
    pub fn get_f64(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        if vrs.len() != values.len() {
            return self.say(
                Status::Error,
                "get: as many values as value references needed",
            );
        }
        let mut out: Option<Outputs> = None;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            let v = match self.variable(*vr, Type::Float64) {
                Ok(v) => v,
                Err(m) => return self.say(Status::Error, &m),
            };
            *value = match v.slot {
                Slot::Time => self.time(),
                Slot::Input(k) => self.now.inputs.get(k).copied().unwrap_or(f64::NAN),
                Slot::Param { get, .. } => get(&self.now.params),
                Slot::Output(o) => {
                    let outputs = match out {
                        Some(x) => x,
                        None => match self.outputs() {
                            Ok(x) => *out.insert(x),
                            Err(m) => {
                                let m = format!("get `{}`: {m}", v.name);
                                return self.fail(&m);
                            }
                        },
                    };
                    match o {
                        Output::TipDeflection => outputs.tip_deflection,
                        Output::TipAcceleration => outputs.tip_acceleration,
                        Output::RootStress => outputs.root_stress,
                        Output::BallAngle => outputs.ball_angle,
                        Output::BallRelativeAngle => outputs.ball_relative_angle,
                        Output::NormalForce => outputs.normal_force,
                        Output::Damage => outputs.damage,
                        Output::Contact => f64::from(outputs.contact),
                    }
                }
            };
        }
        Status::Ok
    }

    /// `fmi*GetInt32`/`GetInteger`.
    pub fn get_i32(&mut self, vrs: &[u32], values: &mut [i32]) -> Status {
        if vrs.len() != values.len() {
            return self.say(
                Status::Error,
                "get: as many values as value references needed",
            );
        }
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            if let Err(m) = self.variable(*vr, Type::Int32) {
                return self.say(Status::Error, &m);
            }
            match self.outputs() {
                Ok(o) => *value = o.contact,
                Err(m) => return self.fail(&format!("get `contact`: {m}")),
            }
        }
        Status::Ok
    }

    /// `fmi*SetFloat64`/`SetReal`: parameters before the end of initialization, inputs
    /// until termination.
    pub fn set_f64(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if vrs.len() != values.len() {
            return self.say(
                Status::Error,
                "set: as many values as value references needed",
            );
        }
        for (vr, value) in vrs.iter().zip(values) {
            let v = match self.variable(*vr, Type::Float64) {
                Ok(v) => v,
                Err(m) => return self.say(Status::Error, &m),
            };
            let mode = self.now.mode;
            match v.slot {
                Slot::Input(k) if mode != Mode::Terminated && mode != Mode::Failed => {
                    if let Some(x) = self.now.inputs.get_mut(k) {
                        *x = *value;
                    }
                    if mode != Mode::Step {
                        // The start follows the input: rebuild on the next read.
                        self.now.sim = None;
                    }
                }
                Slot::Param { set, .. }
                    if matches!(mode, Mode::Instantiated | Mode::Initialization) =>
                {
                    set(&mut self.now.params, *value);
                    self.now.sim = None;
                }
                _ => {
                    let m = format!(
                        "variable `{}` (value reference {vr}, causality {}) cannot be set in mode {mode:?}",
                        v.name,
                        v.causality.name()
                    );
                    return self.say(Status::Error, &m);
                }
            }
        }
        Status::Ok
    }

    /// A communication step from `t` of length `dt`: k = dt / h steps. Returns the status and
    /// the time reached.
    pub fn do_step(&mut self, t: f64, dt: f64) -> (Status, f64) {
        if self.now.mode != Mode::Step {
            let m = format!(
                "do step: only allowed in step mode (mode {:?})",
                self.now.mode
            );
            return (self.say(Status::Error, &m), self.time());
        }
        let h = self.config.step();
        let now = self.time();
        if !(t.is_finite() && (t - now).abs() <= 1e-6 * h + 4.0 * f64::EPSILON * now.abs()) {
            let m = format!(
                "do step refused: currentCommunicationPoint {t} s is not the FMU's time {now} s (start + steps × h)"
            );
            return (self.say(Status::Discard, &m), now);
        }
        let k = (dt / h).round();
        if !(dt.is_finite() && k >= 1.0 && (dt - k * h).abs() <= 1e-6 * h && k <= 1e12) {
            let m = format!(
                "do step refused: communicationStepSize {dt} s is not a whole multiple k·h of the model's fixed step h = {h} s (k ≥ 1, within 1e-6·h); nothing was done"
            );
            return (self.say(Status::Discard, &m), now);
        }
        if let Err(m) = self.check_inputs() {
            return (self.fail(&format!("do step at t = {now} s: {m}")), now);
        }
        let [a, f] = self.now.inputs;
        let Some(sim) = self.now.sim.as_mut() else {
            return (self.fail("do step: no model (initialization failed)"), now);
        };
        let n = k as u64;
        let failed = (0..n).find_map(|j| sim.step(a, f).err().map(|e| (j, e)));
        let reached = self.time();
        if let Some((j, e)) = failed {
            let m = format!(
                "step {} of {n} of the communication step from t = {t} s failed at t = {reached} s \
                 (base_acceleration = {a} m/s2, tip_load = {f} N): {}; the model keeps the state of t = {reached} s",
                j + 1,
                self.describe(&e)
            );
            return (self.fail(&m), reached);
        }
        (Status::Ok, reached)
    }

    /// `fmi*Terminate`.
    pub fn terminate(&mut self) -> Status {
        match self.now.mode {
            Mode::Step | Mode::Initialization | Mode::Failed => {
                self.now.mode = Mode::Terminated;
                self.say(Status::Ok, "terminated")
            }
            m => self.say(
                Status::Error,
                &format!("terminate: not allowed in mode {m:?}"),
            ),
        }
    }

    /// `fmi*Reset`: back to the state after instantiation (start values, no model).
    pub fn reset(&mut self) -> Status {
        self.now = Snapshot {
            mode: Mode::Instantiated,
            params: self.config.params,
            inputs: [0.0; 2],
            start_time: 0.0,
            sim: None,
        };
        self.say(Status::Ok, "reset")
    }

    /// The FMU state (a copy of everything that determines the future).
    pub fn snapshot(&self) -> Snapshot {
        self.now.clone()
    }

    /// Restores a state of this instance (or of another of the same FMU).
    pub fn restore(&mut self, s: &Snapshot) -> Status {
        let restored = match (&mut self.now.sim, &s.sim) {
            (Some(mine), Some(theirs)) => mine.restore(theirs.as_ref()),
            _ => false,
        };
        if !restored {
            self.now.sim = s.sim.as_ref().map(|m| m.clone_box());
        }
        self.now.mode = s.mode;
        self.now.params = s.params;
        self.now.inputs = s.inputs;
        self.now.start_time = s.start_time;
        Status::Ok
    }

    /// Size of `s` serialized \[bytes\].
    pub fn serialized_size(&self, s: &Snapshot) -> usize {
        8 * (HEADER_WORDS + parameters(&self.config).count())
            + s.sim.as_ref().map_or(0, |m| m.byte_len())
    }

    /// Writes `s` into `out` (of [`Instance::serialized_size`] bytes).
    pub fn serialize(&self, s: &Snapshot, out: &mut [u8]) -> Status {
        if out.len() != self.serialized_size(s) {
            return self.say(
                Status::Error,
                "serialize: the buffer size is not the serialized state size",
            );
        }
        let sim_len = s.sim.as_ref().map_or(0, |m| m.byte_len());
        let mut words = vec![
            MAGIC,
            FORMAT,
            hash(crate::BUILD_ID),
            hash(&self.token),
            s.sim.as_ref().map_or(0, |m| m.type_tag()),
            sim_len as u64,
            mode_code(s.mode),
            s.start_time.to_bits(),
            s.inputs[0].to_bits(),
            s.inputs[1].to_bits(),
            parameters(&self.config).count() as u64,
        ];
        for v in parameters(&self.config) {
            if let Slot::Param { get, .. } = v.slot {
                words.push(get(&s.params).to_bits());
            }
        }
        let (head, tail) = out.split_at_mut(8 * words.len());
        for (chunk, w) in head.chunks_exact_mut(8).zip(&words) {
            chunk.copy_from_slice(&w.to_le_bytes());
        }
        match &s.sim {
            Some(m) if m.write_bytes(tail) => Status::Ok,
            None if tail.is_empty() => Status::Ok,
            _ => self.say(Status::Error, "serialize: model size mismatch"),
        }
    }

    /// Reads a state written by [`Instance::serialize`] of this library build and FMU.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot, Status> {
        let err = |m: &str| Err(self.say(Status::Error, &format!("deserialize: {m}")));
        let word = |i: usize| -> Option<u64> {
            let b = bytes.get(8 * i..8 * i + 8)?;
            let mut a = [0u8; 8];
            a.copy_from_slice(b);
            Some(u64::from_le_bytes(a))
        };
        let head: Option<Vec<u64>> = (0..HEADER_WORDS).map(word).collect();
        let Some(head) = head else {
            return err("too short for a serialized state of this FMU");
        };
        if head[0] != MAGIC || head[1] != FORMAT {
            return err("not a serialized state of this FMU (magic or format)");
        }
        if head[2] != hash(crate::BUILD_ID) || head[3] != hash(&self.token) {
            return err("the state was serialized by another build of the library or another FMU (instantiation token)");
        }
        let n_params = parameters(&self.config).count();
        if head[10] != n_params as u64 {
            return err("parameter count mismatch");
        }
        let Some(mode) = mode_of(head[6]) else {
            return err("bad mode");
        };
        let mut params = self.config.params;
        for (i, v) in parameters(&self.config).enumerate() {
            if let (Slot::Param { set, .. }, Some(w)) = (v.slot, word(HEADER_WORDS + i)) {
                set(&mut params, f64::from_bits(w));
            }
        }
        let start = 8 * (HEADER_WORDS + n_params);
        let Some(model_bytes) = bytes.get(start..) else {
            return err("truncated");
        };
        if model_bytes.len() as u64 != head[5] {
            return err("the model's size does not match the header");
        }
        let sim = if head[5] == 0 {
            None
        } else {
            // A model of the right type to read into: built from the configuration.
            let c = &self.config;
            let mut m = match sim::build(c, &c.params, 0.0, 0.0) {
                Ok(m) => m,
                Err(e) => return err(&format!("cannot build the model: {}", self.describe(&e))),
            };
            if m.type_tag() != head[4] || m.byte_len() != model_bytes.len() {
                return err("the model type does not match this FMU's");
            }
            // SAFETY: magic, format, library build, instantiation token, model type tag and
            // size all match: the bytes were written by `write_bytes` of this same model type
            // in this same library build (the FMI contract: a serialized state is restored
            // only into the FMU that serialized it).
            if !unsafe { m.read_bytes(model_bytes) } {
                return err("model size mismatch");
            }
            Some(m)
        };
        Ok(Snapshot {
            mode,
            params,
            inputs: [f64::from_bits(head[8]), f64::from_bits(head[9])],
            start_time: f64::from_bits(head[7]),
            sim,
        })
    }
}

#[cfg(test)]
mod tests;
