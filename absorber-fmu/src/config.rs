//! What an FMU is built for: the scene's kind, element count, scalar, fatigue detail and every
//! parameter of the model (`Params<f64>`, integrator included). `host-sim fmu` writes it to
//! `resources/scene.cfg` inside the `.fmu` ([`Config::to_text`]); the shared library reads it
//! when it is instantiated ([`Config::parse`]) and takes the parameters' start values from it.
//! Numbers are written in Rust's shortest round-trip form, so the library gets the scene's
//! values bit for bit.

use absorber_core::monitor::DetailCategory;
use absorber_core::{AtCap, EventLocation, ImpactModel, NewtonKind, Params};
use std::fmt::Write as _;

/// File name of the configuration inside the FMU's `resources/` folder.
pub const FILE: &str = "scene.cfg";

/// Which bodies the model has (the scene's `kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The cantilever alone.
    Beam,
    /// Cantilever + tip mass.
    Tip,
    /// Cantilever + tip mass + ball locked in the housing.
    Locked,
    /// Cantilever + tip mass + free ball with stops.
    Free,
    /// Free ball without stops.
    FreeNostops,
}

impl Kind {
    /// All kinds.
    pub const ALL: [Kind; 5] = [
        Kind::Beam,
        Kind::Tip,
        Kind::Locked,
        Kind::Free,
        Kind::FreeNostops,
    ];

    /// The scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Beam => "beam",
            Kind::Tip => "tip",
            Kind::Locked => "locked",
            Kind::Free => "free",
            Kind::FreeNostops => "free-nostops",
        }
    }

    /// The kind of a scene-file name.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// The kind has a tip mass.
    pub fn has_tip(self) -> bool {
        self != Kind::Beam
    }

    /// The kind has a ball (locked or free).
    pub fn has_ball(self) -> bool {
        matches!(self, Kind::Locked | Kind::Free | Kind::FreeNostops)
    }
}

/// Element counts the FMU's library is compiled for (those of `host-sim run`).
pub const ELEMENTS: [usize; 7] = [1, 2, 3, 4, 6, 8, 16];

/// The FMU's model.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Scene name (for the model name).
    pub name: String,
    /// Bodies.
    pub kind: Kind,
    /// Beam elements (one of [`ELEMENTS`]).
    pub elements: usize,
    /// `true`: the model computes in `f32` (as the firmware), else `f64`.
    pub single: bool,
    /// AASHTO detail category of the clamp (fatigue damage output).
    pub detail: DetailCategory,
    /// Stop time of the default experiment \[s\] (the scene's duration).
    pub stop_time: f64,
    /// The model's parameters (start values of the parameter variables).
    pub params: Params<f64>,
}

/// The `f64` fields of `Params` with their names, read and written by the same code.
macro_rules! float_fields {
    ($m:ident) => {
        $m!(
            beam.length,
            beam.mass,
            beam.area,
            beam.modulus,
            beam.inertia,
            tip.mass,
            tip.inertia,
            tip.offset,
            ball.mass,
            ball.inertia,
            ball.radius,
            ball.track_radius,
            ball.stop_angle,
            ball.restitution,
            ball.stick_speed,
            ball.initial_angle,
            ball.landing_restitution,
            ball.stop_contact_time,
            ball.min_bounce_time,
            integrator.gamma,
            integrator.beta,
            integrator.alpha_m,
            integrator.alpha_f,
            integrator.step,
            integrator.tolerance,
            damping.stiffness_proportional,
            gravity,
            calibration.bending_stiffness,
            calibration.axial_stiffness,
            calibration.mass_lumping
        )
    };
}

/// A configuration error: the key and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// The key (`integrator.step`), or `line N`.
    pub key: String,
    /// Why.
    pub reason: String,
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key, self.reason)
    }
}

fn bad(key: &str, reason: impl Into<String>) -> ConfigError {
    ConfigError {
        key: key.to_string(),
        reason: reason.into(),
    }
}

impl Config {
    /// The time step h \[s\].
    pub fn step(&self) -> f64 {
        self.params.integrator.step
    }

    /// The text of `resources/scene.cfg`: `key = value` lines.
    pub fn to_text(&self) -> String {
        let p = &self.params;
        let mut s = String::from(
            "# absorber FMU: the model and its parameters (written by host-sim fmu)\n",
        );
        let _ = writeln!(s, "name = {}", self.name.replace('\n', " "));
        let _ = writeln!(s, "kind = {}", self.kind.name());
        let _ = writeln!(s, "elements = {}", self.elements);
        let _ = writeln!(s, "precision = {}", if self.single { "f32" } else { "f64" });
        let _ = writeln!(s, "detail = {}", self.detail.name());
        let _ = writeln!(s, "stop_time = {:?}", self.stop_time);
        macro_rules! write_floats {
            ($($a:ident $(. $b:ident)?),*) => {
                $(let _ = writeln!(s, "{} = {:?}", stringify!($a $(. $b)?).replace(' ', ""), p.$a $(. $b)?);)*
            };
        }
        float_fields!(write_floats);
        let _ = writeln!(
            s,
            "integrator.max_iterations = {}",
            p.integrator.max_iterations
        );
        let _ = writeln!(
            s,
            "integrator.newton = {}",
            match p.integrator.newton {
                NewtonKind::PerStep => "per-step",
                NewtonKind::Full => "full",
                NewtonKind::Modified => "modified",
            }
        );
        let _ = writeln!(
            s,
            "integrator.accept_after_budget = {}",
            p.integrator.accept_after_budget
        );
        let _ = writeln!(
            s,
            "integrator.events = {}",
            match p.integrator.events {
                EventLocation::Crossing => "crossing",
                EventLocation::StepEnd => "step-end",
            }
        );
        let _ = writeln!(
            s,
            "ball.impact_model = {}",
            match p.ball.impact_model {
                ImpactModel::OverStep => "over-step",
                ImpactModel::Instantaneous => "instantaneous",
            }
        );
        let _ = writeln!(s, "ball.flight = {}", p.ball.flight);
        let _ = writeln!(s, "integrator.max_work = {}", p.integrator.max_work);
        let _ = writeln!(
            s,
            "integrator.at_cap = {}",
            match p.integrator.at_cap {
                AtCap::Take => "take",
                AtCap::Keep => "keep",
            }
        );
        s
    }

    /// Reads [`Config::to_text`]'s format. Every key must be there exactly once; errors name
    /// the key.
    pub fn parse(text: &str) -> Result<Self, ConfigError> {
        let mut pairs: Vec<(&str, &str)> = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let (k, v) = line
                .split_once('=')
                .ok_or_else(|| bad(&format!("line {}", i + 1), "is not `key = value`"))?;
            let k = k.trim();
            if pairs.iter().any(|(x, _)| *x == k) {
                return Err(bad(k, "is given twice"));
            }
            pairs.push((k, v.trim()));
        }
        let get = |key: &str| -> Result<&str, ConfigError> {
            pairs
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| *v)
                .ok_or_else(|| bad(key, "is missing"))
        };
        let float = |key: &str| -> Result<f64, ConfigError> {
            get(key)?
                .parse::<f64>()
                .map_err(|_| bad(key, "is not a number"))
        };
        let flag = |key: &str| -> Result<bool, ConfigError> {
            match get(key)? {
                "true" => Ok(true),
                "false" => Ok(false),
                _ => Err(bad(key, "must be true or false")),
            }
        };
        let kind = Kind::from_name(get("kind")?)
            .ok_or_else(|| bad("kind", "must be beam, tip, locked, free or free-nostops"))?;
        let elements = get("elements")?
            .parse::<usize>()
            .ok()
            .filter(|n| ELEMENTS.contains(n))
            .ok_or_else(|| bad("elements", "must be 1, 2, 3, 4, 6, 8 or 16"))?;
        let single = match get("precision")? {
            "f32" => true,
            "f64" => false,
            _ => return Err(bad("precision", "must be f32 or f64")),
        };
        let detail_name = get("detail")?;
        let detail = DetailCategory::ALL
            .into_iter()
            .find(|c| c.name() == detail_name)
            .ok_or_else(|| bad("detail", "must be one of A, B, B', C, C', D, E, E'"))?;
        let mut p = Params::<f64>::default();
        macro_rules! read_floats {
            ($($a:ident $(. $b:ident)?),*) => {
                $(p.$a $(. $b)? = float(&stringify!($a $(. $b)?).replace(' ', ""))?;)*
            };
        }
        float_fields!(read_floats);
        p.integrator.max_iterations = get("integrator.max_iterations")?
            .parse()
            .map_err(|_| bad("integrator.max_iterations", "is not a whole number"))?;
        p.integrator.newton = match get("integrator.newton")? {
            "per-step" => NewtonKind::PerStep,
            "full" => NewtonKind::Full,
            "modified" => NewtonKind::Modified,
            _ => {
                return Err(bad(
                    "integrator.newton",
                    "must be per-step, full or modified",
                ))
            }
        };
        p.integrator.accept_after_budget = flag("integrator.accept_after_budget")?;
        p.integrator.max_work = get("integrator.max_work")?
            .parse()
            .map_err(|_| bad("integrator.max_work", "is not a whole number"))?;
        p.integrator.at_cap = match get("integrator.at_cap")? {
            "take" => AtCap::Take,
            "keep" => AtCap::Keep,
            _ => return Err(bad("integrator.at_cap", "must be take or keep")),
        };
        p.integrator.events = match get("integrator.events")? {
            "crossing" => EventLocation::Crossing,
            "step-end" => EventLocation::StepEnd,
            _ => return Err(bad("integrator.events", "must be crossing or step-end")),
        };
        p.ball.impact_model = match get("ball.impact_model")? {
            "over-step" => ImpactModel::OverStep,
            "instantaneous" => ImpactModel::Instantaneous,
            _ => {
                return Err(bad(
                    "ball.impact_model",
                    "must be over-step or instantaneous",
                ))
            }
        };
        p.ball.flight = flag("ball.flight")?;
        let config = Self {
            name: get("name")?.to_string(),
            kind,
            elements,
            single,
            detail,
            stop_time: float("stop_time")?,
            params: p,
        };
        if !(config.step().is_finite() && config.step() > 0.0) {
            return Err(bad("integrator.step", "must be finite and positive"));
        }
        Ok(config)
    }

    /// The instantiation token (FMI 3) / GUID (FMI 2): a hash of this configuration and of
    /// the library's sources ([`crate::BUILD_ID`]) in the GUID form. The library refuses an
    /// instantiation whose token differs from the one of the configuration it reads.
    pub fn token(&self) -> String {
        let mut h = Fnv::new();
        h.write(crate::BUILD_MARKER.as_bytes());
        h.write(self.to_text().as_bytes());
        let a = h.0;
        h.write(b"second half");
        let b = h.0;
        format!(
            "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
            a >> 32,
            (a >> 16) & 0xffff,
            a & 0xffff,
            b >> 48,
            b & 0xffff_ffff_ffff
        )
    }
}

/// FNV-1a, 64 bit (tokens and state tags: stable across runs and builds).
pub(crate) struct Fnv(pub(crate) u64);

impl Fnv {
    pub(crate) fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    pub(crate) fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn paper() -> Config {
        Config {
            name: "paper".into(),
            kind: Kind::Free,
            elements: 3,
            single: false,
            detail: DetailCategory::EPrime,
            stop_time: 60.0,
            params: Params::default(),
        }
    }

    /// The text form gives the configuration back bit for bit, with every non-default
    /// enumeration too; a missing or bad key is named.
    #[test]
    fn text_round_trips_and_errors_name_the_key() {
        let mut c = paper();
        c.params.beam.modulus = 1.0 / 3.0 * 6e11;
        c.params.integrator.newton = NewtonKind::Modified;
        c.params.integrator.events = EventLocation::StepEnd;
        c.params.ball.impact_model = ImpactModel::Instantaneous;
        c.params.ball.flight = false;
        c.detail = DetailCategory::CPrime;
        c.single = true;
        let back = Config::parse(&c.to_text()).expect("parses");
        assert_eq!(back, c);
        assert_eq!(
            back.params.beam.modulus.to_bits(),
            c.params.beam.modulus.to_bits()
        );
        let text = c.to_text().replace("integrator.step = 0.003\n", "");
        assert_eq!(
            Config::parse(&text).err().map(|e| e.key),
            Some("integrator.step".into())
        );
        let text = c.to_text().replace("elements = 3", "elements = 5");
        assert_eq!(
            Config::parse(&text).err().map(|e| e.key),
            Some("elements".into())
        );
        assert_ne!(c.token(), paper().token());
    }
}
