//! Scene files (TOML): every parameter of the model, the scene kind, mesh, precision,
//! excitation, integrator, solver, duration and outputs.
//!
//! Every section and key is optional; what is left out takes the paper's value (Table 1, the
//! built-in `paper` scene). Unknown keys are errors naming the key; bad values are errors naming
//! the field. Units are SI; angles in a scene file are in degrees (`*_deg`).
//!
//! ```toml
//! name = "paper"
//! kind = "free"          # beam | tip | locked | free | free-nostops
//! elements = 3           # core: 1, 2, 3, 4, 6, 8 or 16; full: any
//! precision = "f64"      # f32 | f64
//! solver = "core"        # core | full
//! duration = 60.0        # s
//! gravity = 9.81         # m/s², along −y
//!
//! [beam]       # length [m], mass [kg], area [m²], modulus [Pa], inertia [m⁴]
//! [tip]        # mass [kg], inertia [kg·m²], offset [m] (u_t2, centre below the beam end)
//! [ball]       # mass, inertia, radius, track_radius, stop_angle_deg, restitution,
//!              # stick_speed [rad/s], initial_angle_deg, impact_model = "over-step" | "instantaneous",
//!              # friction, flight = true | false, landing_restitution
//! [damping]    # stiffness_proportional [s], or ratio [-] at frequency [Hz]
//! [integrator] # scheme (newmark | generalized-alpha), rho_inf, gamma, beta, step [s], tolerance, max_iterations
//! [excitation] # type = "harmonic", amplitude [m], frequency [Hz]
//!              # or type = "csv", file = "base.csv" (columns t [s], accel [m/s²])
//! [outputs]    # directory, plots = ["time", "fft", "phase", "energy"], transient [s], every
//! [calibration] # bending_stiffness, axial_stiffness [-] (factors on E·I, E·a), mass_lumping [-]
//!              # (written by `host-sim calibrate`; left out: none, the paper's model)
//! ```

mod arm;
mod checks;
mod overrides;
mod sections;
mod sensors;
#[cfg(test)]
mod tests;

pub use arm::*;
pub use checks::*;
pub use overrides::Overrides;
pub use sections::*;
pub use sensors::*;

use absorber_core::{
    BallParams, BeamParams, Damping, EventLocation, ImpactModel, Integrator, NewtonKind, Params,
    TipParams,
};
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Which bodies the scene contains (the core's compile-time scenes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// The cantilever alone.
    Beam,
    /// Cantilever + tip mass.
    Tip,
    /// Cantilever + tip mass + ball locked in the housing (passive absorber).
    Locked,
    /// Cantilever + tip mass + free ball with stops (the paper's absorber).
    Free,
    /// Free ball without stops.
    FreeNostops,
}

impl Kind {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Beam => "beam",
            Kind::Tip => "tip",
            Kind::Locked => "locked",
            Kind::Free => "free",
            Kind::FreeNostops => "free-nostops",
        }
    }
    /// The scene has a ball.
    pub fn has_ball(self) -> bool {
        matches!(self, Kind::Locked | Kind::Free | Kind::FreeNostops)
    }
    /// The scene has a free ball (one more unknown).
    pub fn free_ball(self) -> bool {
        matches!(self, Kind::Free | Kind::FreeNostops)
    }
}

/// Scalar of the solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Precision {
    /// Single precision (as on the Cortex-M4F).
    F32,
    /// Double precision.
    F64,
}

/// Which solver runs the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Solver {
    /// The embedded reduced model (`absorber-core`).
    #[default]
    Core,
    /// The full multibody solver (`absorber_full`).
    Full,
}

impl Solver {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Solver::Core => "core",
            Solver::Full => "full",
        }
    }
}

/// Element counts the core is compiled for.
pub const ELEMENTS: [usize; 7] = [1, 2, 3, 4, 6, 8, 16];

/// A loaded scene: the file's content and the directory its relative paths refer to.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The settings.
    pub file: SceneFile,
    /// Directory of the scene file (for `excitation.file`); the working directory otherwise.
    pub base_dir: PathBuf,
}

impl Scene {
    /// The paper's scene (Table 1, free ball, 3 elements, f64, 0.5 mm at 4.13 Hz, 60 s).
    pub fn paper() -> Self {
        Self {
            file: SceneFile::default(),
            base_dir: PathBuf::from("."),
        }
    }

    /// The physics scene (built in: `scenes/physics.toml`): Table 1's absorber with a steel
    /// arm's damping, generalized-α, compliant stops, the calibrated embedded model.
    pub fn physics() -> Result<Self> {
        Self::from_toml(PHYSICS_TOML).context("built-in scene `physics`")
    }

    /// `paper` or `physics` (built in) or a path to a TOML file.
    pub fn load(spec: &str) -> Result<Self> {
        let scene = Self::read(spec)?;
        scene
            .validate()
            .with_context(|| format!("scene `{spec}`"))?;
        Ok(scene)
    }

    /// As [`Scene::load`] without the validation (for overrides applied before it).
    pub fn read(spec: &str) -> Result<Self> {
        if spec == "paper" {
            return Ok(Self::paper());
        }
        if spec == "physics" {
            return Self::physics();
        }
        let path = Path::new(spec);
        let text = std::fs::read_to_string(path).with_context(|| {
            // A bare name: the shipped scene of that name, if there is one here.
            let shipped = Path::new("scenes").join(format!("{spec}.toml"));
            if path.extension().is_none() && shipped.is_file() {
                format!(
                    "cannot read scene `{spec}` (the only built-in scene is `paper`; did you mean `{}`?)",
                    shipped.display()
                )
            } else if path.extension().is_none() {
                format!(
                    "cannot read scene `{spec}` (the only built-in scene is `paper`; others are TOML files, e.g. `scenes/tuned.toml` in the repository)"
                )
            } else {
                format!("cannot read scene `{spec}`")
            }
        })?;
        let file = parse(&text).with_context(|| format!("scene `{spec}`"))?;
        let base_dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let scene = Self {
            file,
            base_dir: if base_dir.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                base_dir
            },
        };
        Ok(scene)
    }

    /// Parses scene text (relative paths refer to the working directory) and validates it.
    pub fn from_toml(text: &str) -> Result<Self> {
        let scene = Self {
            file: parse(text)?,
            base_dir: PathBuf::from("."),
        };
        scene.validate()?;
        Ok(scene)
    }

    /// The model parameters (f64), validated for the scene kind. Errors name the scene key.
    pub fn params(&self) -> Result<Params<f64>> {
        let f = &self.file;
        let d = &f.damping;
        let damping = match (d.stiffness_proportional, d.ratio, d.frequency) {
            (None, None, None) => Damping { stiffness_proportional: 0.0 },
            (Some(c), None, None) => Damping { stiffness_proportional: c },
            (None, Some(z), Some(fr)) => {
                finite_positive(fr, "damping.frequency")?;
                if !z.is_finite() || z < 0.0 {
                    bail!("invalid value for `damping.ratio`: {z} (must be finite and not negative)");
                }
                Damping::from_ratio(z, fr)
            }
            (None, Some(_), None) => bail!("`damping.ratio` needs `damping.frequency`"),
            (None, None, Some(_)) => bail!("`damping.frequency` needs `damping.ratio`"),
            _ => bail!("give either `damping.stiffness_proportional` or `damping.ratio` with `damping.frequency`"),
        };
        let b = &f.ball;
        finite_positive(b.friction, "ball.friction")?;
        let p = Params {
            beam: BeamParams {
                length: f.beam.length,
                mass: f.beam.mass,
                area: f.beam.area,
                modulus: f.beam.modulus,
                inertia: f.beam.inertia,
            },
            tip: TipParams {
                mass: f.tip.mass,
                inertia: f.tip.inertia,
                offset: f.tip.offset,
            },
            ball: BallParams {
                mass: b.mass,
                inertia: b.inertia,
                radius: b.radius,
                track_radius: b.track_radius,
                stop_angle: b.stop_angle_deg.to_radians(),
                restitution: b.restitution,
                stick_speed: b.stick_speed,
                initial_angle: b.initial_angle_deg.to_radians(),
                impact_model: match b.impact_model {
                    ImpactSetting::OverStep => ImpactModel::OverStep,
                    ImpactSetting::Instantaneous => ImpactModel::Instantaneous,
                },
                stop_contact_time: b.stop_contact_time,
                flight: b.flight,
                landing_restitution: b.landing_restitution,
                min_bounce_time: b.min_bounce_time,
                lift_height: b.lift_height,
            },
            integrator: {
                // Field by field, so that core fields without a scene key keep their default.
                let mut i: Integrator<f64> = Params::<f64>::default().integrator;
                i.gamma = f.integrator.gamma;
                i.beta = f.integrator.beta;
                i.step = f.integrator.step;
                i.tolerance = f.integrator.tolerance;
                i.max_iterations = f.integrator.max_iterations;
                i.newton = match f.integrator.newton {
                    NewtonSetting::PerStep => NewtonKind::PerStep,
                    NewtonSetting::Full => NewtonKind::Full,
                    NewtonSetting::Modified => NewtonKind::Modified,
                };
                i.accept_after_budget = f.integrator.accept_after_budget;
                i.events = match f.integrator.events {
                    EventSetting::Crossing => EventLocation::Crossing,
                    EventSetting::StepEnd => EventLocation::StepEnd,
                };
                let fi = &f.integrator;
                match (fi.scheme, fi.rho_inf) {
                    (SchemeSetting::Newmark, None) => {}
                    (SchemeSetting::Newmark, Some(_)) => bail!(
                        "`integrator.rho_inf` needs `integrator.scheme = \"generalized-alpha\"`"
                    ),
                    (SchemeSetting::GeneralizedAlpha, None) => bail!(
                        "`integrator.scheme = \"generalized-alpha\"` needs `integrator.rho_inf` (0 to 1; e.g. 0.8)"
                    ),
                    (SchemeSetting::GeneralizedAlpha, Some(r)) => {
                        if !(0.0..=1.0).contains(&r) {
                            bail!("invalid value for `integrator.rho_inf`: {r} (must lie in [0, 1])");
                        }
                        let paper = IntegratorSection::default();
                        if fi.gamma != paper.gamma || fi.beta != paper.beta {
                            bail!("`integrator.gamma` and `integrator.beta` are set by `integrator.rho_inf` with the generalized-alpha scheme: leave them out");
                        }
                        i = i.generalized_alpha(r);
                    }
                }
                i
            },
            damping,
            gravity: f.gravity,
            calibration: f.calibration.calibration(),
        };
        let has_tip = f.kind != Kind::Beam;
        p.validate(has_tip, f.kind.has_ball())
            .map_err(|e| map_core_error(e, self))?;
        Ok(p)
    }

    /// Number of steps of `duration` (validated scenes: 1 ..= [`MAX_STEPS`]).
    pub fn steps(&self) -> usize {
        let n = (self.file.duration / self.file.integrator.step).round();
        if n.is_finite() && n >= 0.0 {
            (n as usize).min(MAX_STEPS as usize)
        } else {
            0
        }
    }

    /// Warnings about settings that are allowed but poorly resolved (printed on stderr).
    pub fn warnings(&self) -> Vec<String> {
        let f = &self.file;
        let mut w = Vec::new();
        if f.excitation.kind == ExcitationType::Harmonic {
            let fr = f.excitation.frequency_or_paper();
            let h = f.integrator.step;
            if let Some(m) = harmonic_warning(fr, h, "excitation.frequency") {
                w.push(m);
            }
        }
        if f.arm.is_some() || !f.loads.is_empty() {
            w.push("warning: `[arm]`, `[[loads]]` and `[[sensors]]` are used by `estimate`, `tune`, `modes` and `static`; the other commands (`run`, `sweep`, `fatigue`) model the uniform `[beam]` shaken at its base".into());
        }
        w
    }

    /// The scene as TOML text (with a comment header).
    pub fn to_toml(&self) -> Result<String> {
        Ok(toml::to_string(&self.file)?)
    }
}

/// The built-in scene names.
pub const BUILT_IN: [&str; 2] = ["paper", "physics"];

/// The physics scene (`scenes/physics.toml`, built in as `physics`).
pub const PHYSICS_TOML: &str = include_str!("../../../scenes/physics.toml");

/// Largest number of steps of one run (memory stays fixed, but time and disk do not).
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Loosest Newton tolerance accepted (the documented accuracy needs 1e-5 at h = 3 ms).
pub const MAX_TOLERANCE: f64 = 1e-3;

/// Largest base acceleration (harmonic peak or CSV sample) and |gravity| \[m/s²\] (≈ 100 g).
pub const MAX_ACCEL: f64 = 1000.0;

/// Fewest steps per excitation period without a warning.
pub const STEPS_PER_PERIOD_WARN: f64 = 20.0;

/// Parses scene text; errors are one line and name the key.
pub fn parse(text: &str) -> Result<SceneFile> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| one_line(&e, text, ""))?;
    serde_path_to_error::deserialize::<_, SceneFile>(de).map_err(|e| {
        let path = e.path().to_string();
        one_line(e.inner(), text, &path)
    })
}

fn one_line(e: &toml::de::Error, text: &str, path: &str) -> anyhow::Error {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let at = line.map(|l| format!(" (line {l})")).unwrap_or_default();
    let msg = e.message().trim().replace('\n', " ");
    if path.is_empty() || path == "." {
        // A syntax error names the line; the key written on it too (`length =` with no value
        // is reported by the parser as an unquoted string).
        let key = line.and_then(|l| text.lines().nth(l - 1)).and_then(|l| {
            let (k, v) = l.split_once('=')?;
            let k = k.trim();
            (!k.is_empty() && !k.starts_with('[') && !k.starts_with('#')).then_some((k, v.trim()))
        });
        if let Some((k, value)) = key {
            let section = line
                .and_then(|l| {
                    text.lines()
                        .take(l - 1)
                        .filter_map(|t| t.trim().strip_prefix('['))
                        .filter_map(|t| t.split(']').next())
                        .last()
                })
                .map(|t| format!("{}.", t.trim_start_matches('[')))
                .unwrap_or_default();
            return if value.is_empty() {
                anyhow!(
                    "`{section}{k}`: no value (allowed: a number, a quoted string, true/false, an \
                     array or a table){at}"
                )
            } else {
                anyhow!("`{section}{k}` = `{value}`: {msg}{at}")
            };
        }
        anyhow!("{msg}{at}")
    } else {
        anyhow!("`{path}`: {msg}{at}")
    }
}
