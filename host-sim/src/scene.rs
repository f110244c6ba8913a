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

use absorber_core::{
    BallParams, BeamParams, Calibration, Damping, EventLocation, ImpactModel, Integrator,
    NewtonKind, Params, TipParams,
};
use anyhow::{anyhow, bail, Context, Result};
use rand::RngExt;
use rand_distr::StandardNormal;
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

/// `[beam]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeamSection {
    /// Total length L \[m\].
    pub length: f64,
    /// Total mass \[kg\].
    pub mass: f64,
    /// Cross-section area \[m²\].
    pub area: f64,
    /// Young's modulus \[Pa\].
    pub modulus: f64,
    /// Second moment of area \[m⁴\].
    pub inertia: f64,
}

/// `[tip]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TipSection {
    /// Mass m_t \[kg\].
    pub mass: f64,
    /// Moment of inertia J_t \[kg·m²\].
    pub inertia: f64,
    /// Distance u_t2 from the tip mass centre up to the beam end \[m\].
    pub offset: f64,
}

/// How the stop impulse is spread (scene-file spelling of [`ImpactModel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ImpactSetting {
    /// Impulse spread over the step (default).
    OverStep,
    /// Instantaneous impact of the discrete model.
    Instantaneous,
}

/// `[ball]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BallSection {
    /// Mass m_b \[kg\].
    pub mass: f64,
    /// Moment of inertia J_b \[kg·m²\].
    pub inertia: f64,
    /// Ball radius r_b \[m\].
    pub radius: f64,
    /// Track radius R \[m\].
    pub track_radius: f64,
    /// Stop angle \[deg\].
    pub stop_angle_deg: f64,
    /// Coefficient of restitution at the stops \[-\].
    pub restitution: f64,
    /// Below this relative speed a stop impact is plastic \[rad/s\].
    pub stick_speed: f64,
    /// Initial ball angle from the downward vertical \[deg\].
    pub initial_angle_deg: f64,
    /// Initial orbit rate of the ball θ̇(0) \[rad/s\] (default 0: at rest relative to the
    /// housing; the members of an ensemble, [`crate::ensemble`], get a small one).
    #[serde(skip_serializing_if = "is_zero")]
    pub initial_rate: f64,
    /// Impact model.
    pub impact_model: ImpactSetting,
    /// Contact time of a stop impact \[s\] for the over-step impulse (0: the time step, the
    /// paper's model; `absorber_core::BallParams::stop_contact_time`).
    pub stop_contact_time: f64,
    /// Static friction coefficient between ball and track \[-\]: the model assumes rolling
    /// without slip, and `run` reports how long rolling would need more than this. Clean, dry
    /// steel on steel is about 0.5–0.8, lubricated 0.1–0.2 (engineering handbooks, e.g. Marks'
    /// *Standard Handbook for Mechanical Engineers*, table of friction coefficients); default
    /// 0.5, the low end of dry steel.
    pub friction: f64,
    /// The ball may leave the track when the track would have to pull it, fly inside the
    /// housing and land again (default `true`; `false`: the paper's bilateral track).
    pub flight: bool,
    /// Coefficient of normal restitution of a landing on the track \[-\] (default 0.5, the
    /// stops' value).
    pub landing_restitution: f64,
    /// Shortest flight a bounce may start \[s\] (0: the time step;
    /// `absorber_core::BallParams::min_bounce_time`).
    pub min_bounce_time: f64,
    /// Height a flight must reach to count as a separation \[m\] (0: every take-off; allowed
    /// 0 ≤ `lift_height` < R − r_b; `absorber_core::BallParams::lift_height`).
    #[serde(skip_serializing_if = "is_zero")]
    pub lift_height: f64,
}

/// `[damping]`: stiffness-proportional structural damping, off by default.
#[derive(Clone, Debug, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DampingSection {
    /// Coefficient c in C = c K \[s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness_proportional: Option<f64>,
    /// Damping ratio ζ at `frequency` (alternative to `stiffness_proportional`) \[-\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    /// Frequency at which `ratio` holds \[Hz\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
}

/// `[calibration]`: factors of the reduced beam ([`absorber_core::Calibration`]), written by
/// `host-sim calibrate`. Left out (or all at their defaults): the paper's model.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrationSection {
    /// The element count the factors were fitted for: a run with another count (`--elements`)
    /// leaves them out, with a warning (they hold for one mesh only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elements: Option<usize>,
    /// Factor on E·I \[-\] (1: none).
    pub bending_stiffness: f64,
    /// Factor on E·a \[-\] (1: none).
    pub axial_stiffness: f64,
    /// Lumped fraction of the element mass matrix \[-\] (0: consistent).
    pub mass_lumping: f64,
}

impl Default for CalibrationSection {
    fn default() -> Self {
        Self::from(&Calibration::<f64>::default())
    }
}

impl From<&Calibration<f64>> for CalibrationSection {
    fn from(c: &Calibration<f64>) -> Self {
        Self {
            elements: None,
            bending_stiffness: c.bending_stiffness,
            axial_stiffness: c.axial_stiffness,
            mass_lumping: c.mass_lumping,
        }
    }
}

impl CalibrationSection {
    /// No calibration (the section is then not written).
    pub fn is_identity(&self) -> bool {
        self.calibration().is_identity()
    }

    /// The core's calibration.
    pub fn calibration(&self) -> Calibration<f64> {
        Calibration {
            bending_stiffness: self.bending_stiffness,
            axial_stiffness: self.axial_stiffness,
            mass_lumping: self.mass_lumping,
            bending_gradient: 0.0,
        }
    }
}

/// `[integrator]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct IntegratorSection {
    /// `newmark` (γ, β as given; the paper's) or `generalized-alpha` (γ, β, α_m, α_f from
    /// `rho_inf`; Chung & Hulbert 1993).
    pub scheme: SchemeSetting,
    /// High-frequency spectral radius ρ∞ ∈ \[0, 1\] of the generalized-α scheme (required by
    /// it, not allowed with Newmark).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rho_inf: Option<f64>,
    /// Newmark γ.
    pub gamma: f64,
    /// Newmark β.
    pub beta: f64,
    /// Time step h \[s\].
    pub step: f64,
    /// Newton tolerance.
    pub tolerance: f64,
    /// Newton iteration budget.
    pub max_iterations: u32,
    /// Newton variant: `per-step` (one Jacobian per step, reused while it contracts; the
    /// default), `full` (Jacobian every iteration, the paper's literal method) or `modified`
    /// (kept across steps).
    pub newton: NewtonSetting,
    /// Accept the iterate after `max_iterations` instead of failing the step.
    pub accept_after_budget: bool,
    /// Where an event inside a step goes: `crossing` (the step split at it, exact timing; the
    /// default) or `step-end` (at the end of its step: bounded cost, late by less than a step;
    /// the embedded core only).
    pub events: EventSetting,
}

/// Scene-file spelling of [`absorber_core::EventLocation`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventSetting {
    /// At the crossing inside the step (default).
    #[default]
    Crossing,
    /// At the end of the step in which the event happened.
    StepEnd,
}

/// Scene-file spelling of the time integration scheme ([`absorber_core::Integrator`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SchemeSetting {
    /// Newmark's method with the scene's γ and β (default; the paper's).
    #[default]
    Newmark,
    /// The generalized-α method with spectral radius `rho_inf`.
    GeneralizedAlpha,
}

/// Scene-file spelling of [`absorber_core::NewtonKind`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NewtonSetting {
    /// One Newton matrix per step, reused while it contracts (default).
    PerStep,
    /// Full Newton–Raphson.
    Full,
    /// Modified Newton (factored Jacobian kept while it contracts).
    Modified,
}

/// Kind of base excitation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExcitationType {
    /// y_b = A sin(2π f t).
    Harmonic,
    /// Measured base acceleration from a CSV file.
    Csv,
}

/// `[excitation]`. A harmonic excitation without `amplitude` or `frequency` takes the paper's
/// 0.5 mm and 4.13 Hz.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default = "ExcitationSection::unset")]
pub struct ExcitationSection {
    /// `harmonic` or `csv`.
    #[serde(rename = "type")]
    pub kind: ExcitationType,
    /// Base displacement amplitude A \[m\] (harmonic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f64>,
    /// Frequency f \[Hz\] (harmonic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
    /// CSV file of `t, accel` (csv), relative to the scene file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// High-pass corner of the record's baseline correction \[Hz\] (csv; default 0.1 Hz,
    /// `excitation::HIGHPASS_CORNER`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub highpass: Option<f64>,
}

/// `[outputs]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputsSection {
    /// Directory for CSV and plots (relative to the working directory).
    pub directory: PathBuf,
    /// Which plots: `time`, `fft`, `phase`, `energy`.
    pub plots: Vec<Plot>,
    /// Transient left out of the FFT and the steady-state amplitudes \[s\].
    pub transient: f64,
    /// Write every n-th step to the CSV.
    pub every: usize,
    /// Shortest flight the contact statistics count \[s\]: a take-off into a flight at least
    /// this long is a separation of the summary's separation rate (docs/model.md, "Contact
    /// statistics": shorter flights are grazing, and their number depends on h and N).
    #[serde(skip_serializing_if = "is_default_resolution")]
    pub flight_resolution: f64,
}

/// The default [`OutputsSection::flight_resolution`] \[s\].
pub const FLIGHT_RESOLUTION: f64 = 0.01;

fn is_default_resolution(x: &f64) -> bool {
    *x == FLIGHT_RESOLUTION
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A plot of `run`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Plot {
    /// Time histories of the tip and the ball (paper Figs. 8, 11, 16, 20–23).
    Time,
    /// FFT of the tip and the ball after the transient (Figs. 11, 16, 22).
    Fft,
    /// Phase planes y–ẏ, φ–φ̇, θ–ψ (Figs. 9, 12, 14, 15).
    Phase,
    /// Energy curves (Figs. 17–19).
    Energy,
}

/// A scene as written in a file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneFile {
    /// Name for reports.
    pub name: String,
    /// Bodies.
    pub kind: Kind,
    /// Number of beam elements.
    pub elements: usize,
    /// Scalar.
    pub precision: Precision,
    /// Solver.
    pub solver: Solver,
    /// Simulated time \[s\].
    pub duration: f64,
    /// Gravity \[m/s²\].
    pub gravity: f64,
    /// Beam.
    pub beam: BeamSection,
    /// Tip mass.
    pub tip: TipSection,
    /// Ball.
    pub ball: BallSection,
    /// Damping.
    pub damping: DampingSection,
    /// Integrator.
    pub integrator: IntegratorSection,
    /// Excitation.
    pub excitation: ExcitationSection,
    /// Outputs.
    pub outputs: OutputsSection,
    /// Calibration of the reduced beam (`host-sim calibrate`; none by default).
    #[serde(skip_serializing_if = "CalibrationSection::is_identity")]
    pub calibration: CalibrationSection,
    /// A real arm: tapered tube and signal heads (replaces the uniform `[beam]` section's mass,
    /// area and inertia; see `absorber_core::loads`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm: Option<ArmSection>,
    /// Loads on the arm (`[[loads]]`, summed; see [`crate::wind`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<crate::wind::LoadComponent>,
    /// The tip accelerometer of a monitor (`host-sim estimate`): the older single-sensor
    /// form, read as one `[[sensors]]` entry of type `tip_accel`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor: Option<SensorSection>,
    /// The monitor's sensors (`[[sensors]]`, any subset of `tip_accel`, `ball_angle`,
    /// `root_strain`; `host-sim estimate`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensors: Vec<SensorSpec>,
}

/// One `[[sensors]]` entry: a sensor of the monitor, in its data sheet's units. The noise is
/// white with the standard deviation of one sample; the bias is a constant offset the
/// estimator does not know beyond its installation's zero calibration; a reading at or
/// beyond the range reads the rail (clipped).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SensorSpec {
    /// MEMS accelerometer at the tip, vertical axis.
    TipAccel {
        /// Noise density \[µg/√Hz\].
        noise_density_ug: f64,
        /// Bandwidth of its filter \[Hz\] (the noise is white up to it).
        bandwidth: f64,
        /// Constant bias \[mg\].
        #[serde(default)]
        bias_mg: f64,
        /// Full-scale range ± \[g\].
        range_g: f64,
        /// Output data rate \[Hz\] (a divisor of the model's step rate).
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
    /// Ball angle relative to the housing: a magnetic angle encoder in the housing's wall.
    BallAngle {
        /// Noise, standard deviation of one sample \[°\].
        noise_deg: f64,
        /// Resolution (quantization step) \[°\] (0: none).
        #[serde(default)]
        resolution_deg: f64,
        /// Constant offset \[°\].
        #[serde(default)]
        bias_deg: f64,
        /// Range ± \[°\].
        #[serde(default = "half_turn")]
        range_deg: f64,
        /// Output data rate \[Hz\].
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
    /// Foil strain gauge at the clamp, top fibre, along the arm.
    RootStrain {
        /// Noise, standard deviation of one sample \[µε\].
        noise_ue: f64,
        /// Constant offset \[µε\] (zero drift after installation).
        #[serde(default)]
        bias_ue: f64,
        /// Range ± \[µε\] (the bridge amplifier's full scale).
        range_ue: f64,
        /// Output data rate \[Hz\].
        rate: f64,
        /// Seed of the noise.
        #[serde(default)]
        seed: u64,
    },
}

fn half_turn() -> f64 {
    180.0
}

impl SensorSpec {
    /// The kind.
    pub fn kind(&self) -> absorber_core::estimator::SensorKind {
        use absorber_core::estimator::SensorKind;
        match self {
            SensorSpec::TipAccel { .. } => SensorKind::TipAccel,
            SensorSpec::BallAngle { .. } => SensorKind::BallAngle,
            SensorSpec::RootStrain { .. } => SensorKind::RootStrain,
        }
    }

    /// Standard deviation of one sample's noise, with the quantization's `step/√12` \[SI\].
    pub fn noise_sd(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel {
                noise_density_ug,
                bandwidth,
                ..
            } => noise_density_ug * 1e-6 * G0 * bandwidth.sqrt(),
            SensorSpec::BallAngle {
                noise_deg,
                resolution_deg,
                ..
            } => (noise_deg.powi(2) + resolution_deg.powi(2) / 12.0)
                .sqrt()
                .to_radians(),
            SensorSpec::RootStrain { noise_ue, .. } => noise_ue * 1e-6,
        }
    }

    /// The bias \[SI\].
    pub fn bias(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { bias_mg, .. } => bias_mg * 1e-3 * G0,
            SensorSpec::BallAngle { bias_deg, .. } => bias_deg.to_radians(),
            SensorSpec::RootStrain { bias_ue, .. } => bias_ue * 1e-6,
        }
    }

    /// The range ± \[SI\].
    pub fn range(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { range_g, .. } => range_g * G0,
            SensorSpec::BallAngle { range_deg, .. } => range_deg.to_radians(),
            SensorSpec::RootStrain { range_ue, .. } => range_ue * 1e-6,
        }
    }

    /// The output data rate \[Hz\].
    pub fn rate(&self) -> f64 {
        match *self {
            SensorSpec::TipAccel { rate, .. }
            | SensorSpec::BallAngle { rate, .. }
            | SensorSpec::RootStrain { rate, .. } => rate,
        }
    }

    /// The seed of its noise.
    pub fn seed(&self) -> u64 {
        match *self {
            SensorSpec::TipAccel { seed, .. }
            | SensorSpec::BallAngle { seed, .. }
            | SensorSpec::RootStrain { seed, .. } => seed,
        }
    }

    /// Quantization step \[SI\] (0: none).
    pub fn resolution(&self) -> f64 {
        match *self {
            SensorSpec::BallAngle { resolution_deg, .. } => resolution_deg.to_radians(),
            _ => 0.0,
        }
    }

    /// Model steps between readings at step `h`: `1 / (rate h)`, which must be a whole
    /// number (errors name the key).
    pub fn every(&self, h: f64, index: usize) -> Result<u32> {
        let every = 1.0 / (self.rate() * h);
        let n = every.round();
        if n < 1.0 || (every / n - 1.0).abs() > 1e-6 {
            bail!(
                "invalid value for `sensors[{index}].rate`: {} Hz (the model's step rate, {} Hz, must be a whole multiple of it)",
                self.rate(),
                1.0 / h
            );
        }
        Ok(n as u32)
    }

    /// One reading of the true value `x` \[SI\]: plus the bias and the noise (from `rng`),
    /// quantized, and at the rail when at or beyond the range.
    pub fn read(&self, x: f64, rng: &mut crate::wind::Rng) -> f64 {
        let range = self.range();
        let mut y = x + self.bias() + self.noise_sd_raw() * rng.sample::<f64, _>(StandardNormal);
        let q = self.resolution();
        if q > 0.0 {
            y = (y / q).round() * q;
        }
        y.clamp(-range, range)
    }

    /// The noise without the quantization's part (the quantization is applied as such).
    fn noise_sd_raw(&self) -> f64 {
        match *self {
            SensorSpec::BallAngle { noise_deg, .. } => noise_deg.to_radians(),
            _ => self.noise_sd(),
        }
    }

    /// Checks the values (errors name the key `sensors[index].…`).
    pub fn validate(&self, index: usize) -> Result<()> {
        let key = |k: &str| format!("sensors[{index}].{k}");
        let pos = |x: f64, k: &str| finite_positive(x, &key(k));
        let finite = |x: f64, k: &str| -> Result<()> {
            if !x.is_finite() {
                bail!("invalid value for `{}`: must be finite", key(k));
            }
            Ok(())
        };
        match *self {
            SensorSpec::TipAccel {
                noise_density_ug,
                bandwidth,
                bias_mg,
                range_g,
                rate,
                ..
            } => {
                pos(noise_density_ug, "noise_density_ug")?;
                pos(bandwidth, "bandwidth")?;
                finite(bias_mg, "bias_mg")?;
                pos(range_g, "range_g")?;
                pos(rate, "rate")?;
                if bandwidth > 0.5 * rate {
                    bail!(
                        "invalid value for `{}`: {bandwidth} Hz (at most half of `rate`)",
                        key("bandwidth")
                    );
                }
            }
            SensorSpec::BallAngle {
                noise_deg,
                resolution_deg,
                bias_deg,
                range_deg,
                rate,
                ..
            } => {
                pos(noise_deg, "noise_deg")?;
                if !resolution_deg.is_finite() || resolution_deg < 0.0 {
                    bail!(
                        "invalid value for `{}`: must be finite and not negative",
                        key("resolution_deg")
                    );
                }
                finite(bias_deg, "bias_deg")?;
                pos(range_deg, "range_deg")?;
                pos(rate, "rate")?;
            }
            SensorSpec::RootStrain {
                noise_ue,
                bias_ue,
                range_ue,
                rate,
                ..
            } => {
                pos(noise_ue, "noise_ue")?;
                finite(bias_ue, "bias_ue")?;
                pos(range_ue, "range_ue")?;
                pos(rate, "rate")?;
            }
        }
        Ok(())
    }
}

impl From<SensorSection> for SensorSpec {
    fn from(s: SensorSection) -> Self {
        SensorSpec::TipAccel {
            noise_density_ug: s.noise_density_ug,
            bandwidth: s.bandwidth,
            bias_mg: s.bias_mg,
            range_g: s.range_g,
            rate: s.rate,
            seed: s.seed,
        }
    }
}

/// `[arm]`: a tapered circular tube with signal heads ([`absorber_core::ArmParams`]).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArmSection {
    /// Outer diameter at the root \[m\].
    pub root_diameter: f64,
    /// Outer diameter at the tip \[m\].
    pub tip_diameter: f64,
    /// Wall thickness \[m\].
    pub wall: f64,
    /// Density \[kg/m³\].
    #[serde(default = "steel_density")]
    pub density: f64,
    /// Signal heads and other point masses (at most 6).
    #[serde(default)]
    pub heads: Vec<HeadSection>,
    /// AASHTO detail category of the root connection (`A` … `E'`).
    #[serde(default = "default_detail")]
    pub detail: String,
}

fn steel_density() -> f64 {
    7850.0
}

fn default_detail() -> String {
    "E'".into()
}

/// One `[[arm.heads]]` entry.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HeadSection {
    /// Distance from the root \[m\].
    pub position: f64,
    /// Mass \[kg\].
    pub mass: f64,
}

/// `[sensor]`: a MEMS accelerometer at the arm tip, vertical axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSection {
    /// Noise density \[µg/√Hz\].
    pub noise_density_ug: f64,
    /// Constant bias \[mg\] (unknown to the estimator).
    pub bias_mg: f64,
    /// Full-scale range ± \[g\] (readings clip there).
    pub range_g: f64,
    /// Output data rate \[Hz\] (the estimator's sample rate).
    pub rate: f64,
    /// Bandwidth of the sensor's filter \[Hz\] (the noise is white up to it).
    pub bandwidth: f64,
    /// Seed of the noise.
    #[serde(default)]
    pub seed: u64,
}

impl ArmSection {
    /// The core's arm parameters. Errors name the key.
    pub fn params(&self) -> Result<absorber_core::ArmParams<f64>> {
        use absorber_core::loads::{PointMass, MAX_POINT_MASSES};
        if self.heads.len() > MAX_POINT_MASSES {
            bail!(
                "invalid value for `arm.heads`: {} heads (at most {MAX_POINT_MASSES})",
                self.heads.len()
            );
        }
        let mut point_masses = [PointMass {
            position: 0.0,
            mass: 0.0,
        }; MAX_POINT_MASSES];
        for (slot, h) in point_masses.iter_mut().zip(&self.heads) {
            *slot = PointMass {
                position: h.position,
                mass: h.mass,
            };
        }
        Ok(absorber_core::ArmParams {
            root_diameter: self.root_diameter,
            tip_diameter: self.tip_diameter,
            wall: self.wall,
            density: self.density,
            point_masses,
        })
    }

    /// The AASHTO detail category named by `detail`.
    pub fn detail_category(&self) -> Result<absorber_core::monitor::fatigue::DetailCategory> {
        use absorber_core::monitor::fatigue::DetailCategory;
        DetailCategory::ALL
            .into_iter()
            .find(|c| c.name() == self.detail)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "invalid value for `arm.detail`: `{}` (one of A, B, B', C, C', D, E, E')",
                    self.detail
                )
            })
    }
}

/// Standard gravity \[m/s²\]: the g of the sensor's units.
pub const G0: f64 = 9.80665;

impl SceneFile {
    /// The monitor's sensors: `[[sensors]]`, or the older `[sensor]` as one `tip_accel`.
    pub fn sensor_specs(&self) -> Vec<SensorSpec> {
        if !self.sensors.is_empty() {
            self.sensors.clone()
        } else {
            self.sensor.map(SensorSpec::from).into_iter().collect()
        }
    }
}

impl SensorSection {
    /// White-noise standard deviation of a reading, noise density · √bandwidth \[m/s²\].
    pub fn noise_sd(&self) -> f64 {
        self.noise_density_ug * 1e-6 * G0 * self.bandwidth.sqrt()
    }

    /// The range ± \[m/s²\].
    pub fn range(&self) -> f64 {
        self.range_g * G0
    }

    /// One reading of the true acceleration `a` \[m/s²\]: plus the bias and white noise
    /// (σ = [`SensorSection::noise_sd`], drawn from `rng`), clipped at the range.
    pub fn read(&self, a: f64, rng: &mut crate::wind::Rng) -> f64 {
        let range = self.range();
        (a + self.bias_mg * 1e-3 * G0 + self.noise_sd() * rng.sample::<f64, _>(StandardNormal))
            .clamp(-range, range)
    }

    /// The estimator runs at the sensor rate: the step `h` must be `1 / rate`.
    pub fn check_step(&self, h: f64) -> Result<()> {
        if ((1.0 / h) / self.rate - 1.0).abs() > 1e-9 {
            bail!(
                "`integrator.step` ({h} s) must be 1 / `sensor.rate` ({} Hz): the estimator runs at the sensor rate",
                self.rate
            );
        }
        Ok(())
    }

    /// Checks the values (errors name the key).
    pub fn validate(&self) -> Result<()> {
        finite_positive(self.noise_density_ug, "sensor.noise_density_ug")?;
        finite_positive(self.range_g, "sensor.range_g")?;
        finite_positive(self.rate, "sensor.rate")?;
        finite_positive(self.bandwidth, "sensor.bandwidth")?;
        if !self.bias_mg.is_finite() {
            bail!("invalid value for `sensor.bias_mg`: must be finite");
        }
        if self.bandwidth > 0.5 * self.rate {
            bail!(
                "invalid value for `sensor.bandwidth`: {} Hz (at most half of `sensor.rate`)",
                self.bandwidth
            );
        }
        Ok(())
    }
}

impl Default for BeamSection {
    fn default() -> Self {
        let p = Params::<f64>::default().beam;
        Self {
            length: p.length,
            mass: p.mass,
            area: p.area,
            modulus: p.modulus,
            inertia: p.inertia,
        }
    }
}
impl Default for TipSection {
    fn default() -> Self {
        let p = Params::<f64>::default().tip;
        Self {
            mass: p.mass,
            inertia: p.inertia,
            offset: p.offset,
        }
    }
}
impl Default for BallSection {
    fn default() -> Self {
        let p = Params::<f64>::default().ball;
        Self {
            mass: p.mass,
            inertia: p.inertia,
            radius: p.radius,
            track_radius: p.track_radius,
            stop_angle_deg: round_deg(p.stop_angle),
            restitution: p.restitution,
            stick_speed: p.stick_speed,
            initial_angle_deg: round_deg(p.initial_angle),
            initial_rate: 0.0,
            impact_model: match p.impact_model {
                ImpactModel::Instantaneous => ImpactSetting::Instantaneous,
                ImpactModel::OverStep => ImpactSetting::OverStep,
            },
            stop_contact_time: p.stop_contact_time,
            friction: 0.5,
            flight: p.flight,
            landing_restitution: p.landing_restitution,
            min_bounce_time: p.min_bounce_time,
            lift_height: p.lift_height,
        }
    }
}
impl Default for IntegratorSection {
    fn default() -> Self {
        let p = Params::<f64>::default().integrator;
        Self {
            scheme: SchemeSetting::Newmark,
            rho_inf: None,
            gamma: p.gamma,
            beta: p.beta,
            step: p.step,
            tolerance: p.tolerance,
            max_iterations: p.max_iterations,
            newton: match p.newton {
                NewtonKind::PerStep => NewtonSetting::PerStep,
                NewtonKind::Full => NewtonSetting::Full,
                NewtonKind::Modified => NewtonSetting::Modified,
            },
            accept_after_budget: p.accept_after_budget,
            events: match p.events {
                EventLocation::Crossing => EventSetting::Crossing,
                EventLocation::StepEnd => EventSetting::StepEnd,
            },
        }
    }
}
impl Default for ExcitationSection {
    fn default() -> Self {
        Self {
            kind: ExcitationType::Harmonic,
            amplitude: Some(0.5e-3),
            frequency: Some(4.13),
            file: None,
            highpass: None,
        }
    }
}
impl ExcitationSection {
    /// Harmonic, nothing given (what a `[excitation]` table starts from).
    pub fn unset() -> Self {
        Self {
            kind: ExcitationType::Harmonic,
            amplitude: None,
            frequency: None,
            file: None,
            highpass: None,
        }
    }
    /// Amplitude \[m\] (paper 0.5 mm when not given).
    pub fn amplitude_or_paper(&self) -> f64 {
        self.amplitude.unwrap_or(0.5e-3)
    }
    /// Frequency \[Hz\] (paper 4.13 Hz when not given).
    pub fn frequency_or_paper(&self) -> f64 {
        self.frequency.unwrap_or(4.13)
    }
}

impl Default for OutputsSection {
    fn default() -> Self {
        Self {
            directory: PathBuf::from("out"),
            plots: vec![Plot::Time, Plot::Fft, Plot::Phase, Plot::Energy],
            transient: 20.0,
            every: 1,
            flight_resolution: FLIGHT_RESOLUTION,
        }
    }
}
impl Default for SceneFile {
    fn default() -> Self {
        Self {
            name: "paper".into(),
            kind: Kind::Free,
            elements: 3,
            precision: Precision::F64,
            solver: Solver::Core,
            duration: 60.0,
            gravity: Params::<f64>::default().gravity,
            beam: BeamSection::default(),
            tip: TipSection::default(),
            ball: BallSection::default(),
            damping: DampingSection::default(),
            integrator: IntegratorSection::default(),
            excitation: ExcitationSection::default(),
            outputs: OutputsSection::default(),
            calibration: CalibrationSection::default(),
            arm: None,
            loads: Vec::new(),
            sensor: None,
            sensors: Vec::new(),
        }
    }
}

fn round_deg(rad: f64) -> f64 {
    (rad.to_degrees() * 1e9).round() / 1e9
}

/// A loaded scene: the file's content and the directory its relative paths refer to.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The settings.
    pub file: SceneFile,
    /// Directory of the scene file (for `excitation.file`); the working directory otherwise.
    pub base_dir: PathBuf,
}

/// The built-in scene names.
pub const BUILT_IN: [&str; 2] = ["paper", "physics"];

/// The physics scene (`scenes/physics.toml`, built in as `physics`).
pub const PHYSICS_TOML: &str = include_str!("../../scenes/physics.toml");

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

    /// Checks everything: the model parameters (through the core's validation), the mesh, the
    /// excitation and the outputs. Errors name the scene-file key.
    pub fn validate(&self) -> Result<()> {
        let f = &self.file;
        if f.solver == Solver::Core && !ELEMENTS.contains(&f.elements) {
            bail!(
                "invalid value for `elements`: {} (the core solver supports 1, 2, 3, 4, 6, 8, 16)",
                f.elements
            );
        }
        if f.elements == 0 || f.elements > 1000 {
            bail!(
                "invalid value for `elements`: {} (must lie in 1 ..= 1000)",
                f.elements
            );
        }
        finite_positive(f.duration, "duration")?;
        finite_positive(f.outputs.flight_resolution, "outputs.flight_resolution")?;
        if !f.ball.initial_rate.is_finite() {
            bail!(
                "invalid value for `ball.initial_rate`: {} (must be finite)",
                f.ball.initial_rate
            );
        }
        if let Some(n) = f.calibration.elements {
            if n != f.elements && !f.calibration.is_identity() {
                bail!(
                    "`calibration.elements` = {n}: the scene's calibration was fitted for {n} elements, \
                     the scene has {} (refit it with `host-sim calibrate --elements {}`)",
                    f.elements,
                    f.elements
                );
            }
        }
        let p = self.params()?;
        self.check_limits(&p)?;
        let e = &f.excitation;
        match e.kind {
            ExcitationType::Harmonic => {
                let a = e.amplitude_or_paper();
                if !a.is_finite() || a < 0.0 {
                    bail!("invalid value for `excitation.amplitude`: {a} (must be finite and not negative)");
                }
                let fr = e.frequency_or_paper();
                finite_positive(fr, "excitation.frequency")?;
                check_harmonic(
                    a,
                    fr,
                    f.integrator.step,
                    "excitation.amplitude",
                    "excitation.frequency",
                )?;
                if e.file.is_some() {
                    bail!("`excitation.file` is only for type = \"csv\"");
                }
            }
            ExcitationType::Csv => {
                if e.file.is_none() {
                    bail!("missing `excitation.file` for a csv excitation");
                }
                if e.amplitude.is_some() || e.frequency.is_some() {
                    bail!("`excitation.amplitude`/`excitation.frequency` are only for type = \"harmonic\"");
                }
            }
        }
        if let Some(arm) = &f.arm {
            arm.detail_category()?;
            // The heads by the key users write (the core names its array, not the entry).
            let length = f.beam.length;
            for (i, h) in arm.heads.iter().enumerate() {
                if !h.mass.is_finite() || h.mass < 0.0 {
                    bail!(
                        "invalid value for `arm.heads[{i}].mass`: {} (must be finite and not negative) [kg]",
                        h.mass
                    );
                }
                if !h.position.is_finite() || !(0.0..=length).contains(&h.position) {
                    bail!(
                        "invalid value for `arm.heads[{i}].position`: {} (must lie in 0 ..= {length} m, the distance from the root along the arm, `beam.length`)",
                        h.position
                    );
                }
            }
            arm.params()?
                .validate(&p.beam)
                .map_err(|e| map_core_error(e, self))?;
            if f.kind != Kind::Beam {
                bail!("`[arm]` needs `kind = \"beam\"` (heads are `[[arm.heads]]` point masses)");
            }
        }
        if !f.loads.is_empty() {
            let Some(arm) = &f.arm else {
                bail!("`[[loads]]` needs an `[arm]` (the loads act on the arm's projected width)");
            };
            crate::wind::LoadModel::new(&f.loads, taper_of(arm, f.beam.length), &self.base_dir)?;
        }
        if let Some(sensor) = &f.sensor {
            sensor.validate()?;
        }
        if f.sensor.is_some() && !f.sensors.is_empty() {
            bail!("give the monitor's sensors as `[[sensors]]` only (the single `[sensor]` is the older form of one `tip_accel`)");
        }
        let mut seen = Vec::new();
        for (i, s) in f.sensors.iter().enumerate() {
            s.validate(i)?;
            if seen.contains(&s.kind()) {
                bail!(
                    "invalid value for `sensors[{i}].type`: a second `{}` (one sensor of each type)",
                    s.kind().id()
                );
            }
            if s.kind() == absorber_core::estimator::SensorKind::BallAngle && f.kind != Kind::Free {
                bail!("invalid value for `sensors[{i}].type`: `ball_angle` needs `kind = \"free\"` (a ball to measure)");
            }
            seen.push(s.kind());
        }
        let o = &f.outputs;
        if !o.transient.is_finite() || o.transient < 0.0 {
            bail!(
                "invalid value for `outputs.transient`: {} (must be finite and not negative)",
                o.transient
            );
        }
        if o.every == 0 {
            bail!("invalid value for `outputs.every`: 0 (must be at least 1)");
        }
        Ok(())
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

    /// Host-side limits beyond the core's parameter checks: the run length, a Newton
    /// tolerance that can give the documented accuracy, magnitudes the model can represent.
    fn check_limits(&self, p: &Params<f64>) -> Result<()> {
        let f = &self.file;
        let h = f.integrator.step;
        let n = f.duration / h;
        if n.round() < 1.0 {
            bail!(
                "invalid value for `duration`: {} s is shorter than one step (integrator.step = {h} s); \
                 allowed: at least one step",
                f.duration
            );
        }
        if n.round() > MAX_STEPS as f64 {
            bail!(
                "invalid value for `duration`: {} s is {:.3e} steps of {h} s; allowed: at most {:.0e} steps \
                 (a run is limited to {:.0e} steps; use a larger step or a shorter duration)",
                f.duration,
                n,
                MAX_STEPS as f64,
                MAX_STEPS as f64
            );
        }
        if f.integrator.tolerance > MAX_TOLERANCE {
            bail!(
                "invalid value for `integrator.tolerance`: {} (allowed: at most {MAX_TOLERANCE:e}; a looser \
                 Newton tolerance does not give the documented accuracy; default 1e-5, scale it with h²)",
                f.integrator.tolerance
            );
        }
        if f.gravity.is_nan() || f.gravity.abs() > MAX_ACCEL {
            bail!(
                "invalid value for `gravity`: {} m/s² (allowed: |gravity| ≤ {MAX_ACCEL} m/s²)",
                f.gravity
            );
        }
        if p.beam.length < 1e-3 {
            bail!(
                "invalid value for `beam.length`: {} m (allowed: at least 1e-3 m)",
                p.beam.length
            );
        }
        let ei = p.beam.modulus * p.beam.inertia;
        if !ei.is_normal() || ei > 1e12 {
            bail!(
                "invalid value for `beam.modulus` × `beam.inertia`: {} Pa × {} m⁴ = E·I = {ei:e} N·m² \
                 is not representable (allowed: 1e-300 < E·I ≤ 1e12 N·m²)",
                num(p.beam.modulus),
                num(p.beam.inertia)
            );
        }
        self.check_magnitudes(p)?;
        // Static sag of a cantilever under its load: tip masses at the end, the beam's own
        // weight distributed (wL⁴/8EI). A beam that sags more than half its length cannot carry
        // the scene (the static solve would fail with a message about Newton).
        let l = p.beam.length;
        let mut end_mass = 0.0;
        if f.kind != Kind::Beam {
            end_mass += p.tip.mass;
        }
        if f.kind.has_ball() {
            end_mass += p.ball.mass;
        }
        let sag = p.gravity.abs() * l.powi(3) * (end_mass / 3.0 + p.beam.mass / 8.0) / ei;
        if sag.is_nan() || sag > 0.5 * l {
            bail!(
                "invalid values for `beam.modulus`/`beam.inertia`/`beam.length` against the load \
                 `beam.mass`/`tip.mass`/`ball.mass`/`gravity`: the beam cannot carry it (estimated static \
                 sag {sag:.3e} m, more than half its length {l} m); allowed: a sag below L/2 (stiffer or \
                 shorter beam, lighter masses or smaller gravity)"
            );
        }
        Ok(())
    }

    /// Magnitudes the model can represent: the dimensionless ratios that meet in one entry of
    /// the mass or stiffness matrix.
    ///
    /// Masses, inertias and stiffnesses enter the matrices linearly, lengths squared (as
    /// m·u², m_b·ρ², J_b·(ρ/r_b)²). Two contributions whose ratio is beyond 1/ε (ε = 2.2e-16,
    /// f64) cannot share a sum or a pivot: the smaller is lost in rounding and the matrix is
    /// singular in f64 (condition number ≥ 1/ε). So mass, inertia and stiffness ratios must
    /// lie in [ε, 1/ε] and length ratios in [√ε, 1/√ε]. The one physical bound: a ball's
    /// moment of inertia about its centre is at most m_b·r_b² (all its mass on its surface).
    /// The error names the key farther from the paper's value (the one most likely mistyped),
    /// with its value, the partner it is compared with and the allowed range of the key.
    fn check_magnitudes(&self, p: &Params<f64>) -> Result<()> {
        let f = &self.file;
        let d = SceneFile::default();
        let eps = f64::EPSILON;
        let (lo, hi) = (eps, 1.0 / eps);
        let (lo2, hi2) = (eps.sqrt(), 1.0 / eps.sqrt());
        let b = &p.beam;
        // The key of a pair farther (in decades) from its paper value.
        let far = |x: f64, x0: f64| (x / x0).log10().abs();
        // `a` = `value` of `key` over `partner` must lie in [lo, hi]·`partner`.
        let ratio = |key: &str,
                     value: f64,
                     unit: &str,
                     partner: &str,
                     partner_value: f64,
                     (lo, hi): (f64, f64),
                     why: &str|
         -> Result<()> {
            let r = value / partner_value;
            if r.is_finite() && (lo..=hi).contains(&r) {
                return Ok(());
            }
            bail!(
                "invalid value for `{key}`: {} {unit} against {partner} = {} {unit}; \
                 allowed: {:.3e} ..= {:.3e} {unit} ({why})",
                num(value),
                num(partner_value),
                lo * partner_value,
                hi * partner_value
            )
        };
        let why_lin = "beyond 1/ε = 4.5e15 apart, the two cannot share an entry of the f64 \
                       mass or stiffness matrix: it is singular";
        let why_sq = "a length enters the inertias squared: beyond 1/√ε = 6.7e7 apart the f64 \
                      mass matrix is singular";
        // Beam: axial stiffness E·a/L against bending stiffness E·I/L³, i.e. a·L² against I.
        let al2 = b.area * b.length * b.length;
        let far_length = far(b.length, d.beam.length);
        if far_length > far(b.inertia, d.beam.inertia) && far_length > far(b.area, d.beam.area) {
            // The length farthest from the paper's: a·L² against I means L against √(I/a).
            ratio(
                "beam.length",
                b.length,
                "m",
                "√(`beam.inertia`/`beam.area`) (axial against bending stiffness)",
                (b.inertia / b.area).sqrt(),
                (lo2, hi2),
                why_lin,
            )?;
        } else if far(b.inertia, d.beam.inertia) > far(b.area, d.beam.area) {
            ratio(
                "beam.inertia",
                b.inertia,
                "m⁴",
                "`beam.area`·`beam.length`² (bending against axial stiffness)",
                al2,
                (lo, hi),
                why_lin,
            )?;
        } else {
            ratio(
                "beam.area",
                b.area,
                "m²",
                "`beam.inertia`/`beam.length`² (axial against bending stiffness)",
                b.inertia / (b.length * b.length),
                (lo, hi),
                why_lin,
            )?;
        }
        let has_tip = f.kind != Kind::Beam;
        let has_ball = f.kind.has_ball();
        // End masses against the beam's mass (one node of the mass matrix carries both).
        let mut masses: Vec<(&str, f64, f64)> = Vec::new();
        if has_tip {
            masses.push(("tip.mass", p.tip.mass, d.tip.mass));
        }
        if has_ball {
            masses.push(("ball.mass", p.ball.mass, d.ball.mass));
        }
        for (key, m, m0) in masses {
            if far(b.mass, d.beam.mass) > far(m, m0) {
                ratio(
                    "beam.mass",
                    b.mass,
                    "kg",
                    &format!("`{key}`"),
                    m,
                    (lo, hi),
                    why_lin,
                )?;
            } else {
                ratio(key, m, "kg", "`beam.mass`", b.mass, (lo, hi), why_lin)?;
            }
        }
        if has_tip {
            // The tip's rotational inertia and offset against the beam's m·L².
            let ml2 = b.mass * b.length * b.length;
            ratio(
                "tip.inertia",
                p.tip.inertia,
                "kg·m²",
                "`beam.mass`·`beam.length`²",
                ml2,
                (0.0, hi),
                why_lin,
            )?;
            ratio(
                "tip.offset",
                p.tip.offset,
                "m",
                "`beam.length`",
                b.length,
                (0.0, hi2),
                why_sq,
            )?;
        }
        if has_ball {
            let bl = &p.ball;
            // The ball's orbit radius against the beam, its spin ratio ρ/r_b.
            ratio(
                "ball.track_radius",
                bl.track_radius,
                "m",
                "`beam.length`",
                b.length,
                (0.0, hi2),
                why_sq,
            )?;
            let rho = bl.track_radius - bl.radius;
            // Physical: a ball's inertia about its centre is at most m_b·r_b².
            let jmax = bl.mass * bl.radius * bl.radius;
            if bl.inertia.is_nan() || bl.inertia > jmax {
                let rmin = (bl.inertia / bl.mass).sqrt();
                if far(bl.radius, d.ball.radius) > far(bl.inertia, d.ball.inertia) {
                    bail!(
                        "invalid value for `ball.radius`: {} m with `ball.inertia` = {} kg·m² and \
                         `ball.mass` = {} kg; allowed: at least √(inertia/mass) = {rmin:.4e} m (a ball's \
                         moment of inertia about its centre is at most mass·radius², all of it on the \
                         surface; a solid ball has 0.4)",
                        num(bl.radius),
                        num(bl.inertia),
                        num(bl.mass)
                    );
                }
                bail!(
                    "invalid value for `ball.inertia`: {} kg·m² with `ball.mass` = {} kg and \
                     `ball.radius` = {} m; allowed: 0 ..= mass·radius² = {jmax:.4e} kg·m² (a ball's \
                     moment of inertia about its centre is at most mass·radius², all of it on the \
                     surface; a solid ball has 0.4·mass·radius²)",
                    num(bl.inertia),
                    num(bl.mass),
                    num(bl.radius)
                );
            }
            let why_spin = "the ball spins ρ/r_b times faster than it orbits and that ratio \
                            enters its inertia squared: beyond 1/√ε = 6.7e7 the f64 mass matrix \
                            is singular";
            if far(bl.radius, d.ball.radius) > far(bl.track_radius, d.ball.track_radius) {
                ratio(
                    "ball.radius",
                    bl.radius,
                    "m",
                    "the orbit radius ρ = `ball.track_radius` − `ball.radius`",
                    rho,
                    (lo2, hi2),
                    why_spin,
                )?;
            } else {
                ratio(
                    "ball.track_radius",
                    rho,
                    "m (as ρ = track_radius − radius)",
                    "`ball.radius`",
                    bl.radius,
                    (lo2, hi2),
                    why_spin,
                )?;
            }
        }
        Ok(())
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

/// Largest number of steps of one run (memory stays fixed, but time and disk do not).
pub const MAX_STEPS: u64 = 1_000_000_000;
/// Loosest Newton tolerance accepted (the documented accuracy needs 1e-5 at h = 3 ms).
pub const MAX_TOLERANCE: f64 = 1e-3;
/// Largest base acceleration (harmonic peak or CSV sample) and |gravity| \[m/s²\] (≈ 100 g).
pub const MAX_ACCEL: f64 = 1000.0;
/// Fewest steps per excitation period without a warning.
pub const STEPS_PER_PERIOD_WARN: f64 = 20.0;

/// Checks a harmonic excitation against the step: below the Nyquist limit 1/(2h), peak
/// acceleration A (2πf)² at most [`MAX_ACCEL`]. Errors name `amp_key`/`freq_key`.
pub fn check_harmonic(
    amplitude: f64,
    frequency: f64,
    h: f64,
    amp_key: &str,
    freq_key: &str,
) -> Result<()> {
    let nyquist = 0.5 / h;
    if frequency.is_nan() || frequency >= nyquist {
        bail!(
            "invalid value for `{freq_key}`: {frequency} Hz is at or above the step's Nyquist limit \
             1/(2h) = {nyquist} Hz (h = {h} s); allowed: below {nyquist} Hz (well below: at least \
             {STEPS_PER_PERIOD_WARN} steps per period), or use a smaller step"
        );
    }
    let w = std::f64::consts::TAU * frequency;
    let peak = amplitude * w * w;
    if peak.is_nan() || peak > MAX_ACCEL {
        bail!(
            "invalid value for `{amp_key}`: {amplitude} m at {frequency} Hz is a peak base acceleration of \
             {peak:.4e} m/s²; allowed: at most {MAX_ACCEL} m/s² (≈ 100 g)"
        );
    }
    Ok(())
}

/// A warning when a period of `frequency` has fewer than [`STEPS_PER_PERIOD_WARN`] steps.
pub fn harmonic_warning(frequency: f64, h: f64, key: &str) -> Option<String> {
    let per = 1.0 / (frequency * h);
    (per < STEPS_PER_PERIOD_WARN).then(|| {
        format!(
            "warning: `{key}` = {frequency} Hz has only {per:.1} steps per period (h = {h} s); \
             the step resolves it poorly (amplitude and phase errors); use h ≤ {:.3e} s",
            1.0 / (STEPS_PER_PERIOD_WARN * frequency)
        )
    })
}

/// A value as users write it: plain in 1e-4 ..< 1e6, in exponent notation beyond (where the
/// plain form runs to hundreds of digits).
fn num(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn finite_positive(x: f64, key: &str) -> Result<()> {
    if !x.is_finite() || x <= 0.0 {
        bail!("invalid value for `{key}`: {x} (must be finite and positive)");
    }
    Ok(())
}

/// The scene-file key of a core parameter name, and the value written there.
fn scene_key(field: &str, s: &Scene) -> (String, String) {
    let f = &s.file;
    let v = num;
    match field {
        "ball.stop_angle" => ("ball.stop_angle_deg".into(), v(f.ball.stop_angle_deg)),
        "ball.initial_angle" => ("ball.initial_angle_deg".into(), v(f.ball.initial_angle_deg)),
        "beam.length" => (field.into(), v(f.beam.length)),
        "beam.mass" => (field.into(), v(f.beam.mass)),
        "beam.area" => (field.into(), v(f.beam.area)),
        "beam.modulus" => (field.into(), v(f.beam.modulus)),
        "beam.inertia" => (field.into(), v(f.beam.inertia)),
        "tip.mass" => (field.into(), v(f.tip.mass)),
        "tip.inertia" => (field.into(), v(f.tip.inertia)),
        "tip.offset" => (field.into(), v(f.tip.offset)),
        "ball.mass" => (field.into(), v(f.ball.mass)),
        "ball.inertia" => (field.into(), v(f.ball.inertia)),
        "ball.radius" => (field.into(), v(f.ball.radius)),
        "ball.track_radius" => (field.into(), v(f.ball.track_radius)),
        "ball.restitution" => (field.into(), v(f.ball.restitution)),
        "ball.stick_speed" => (field.into(), v(f.ball.stick_speed)),
        "ball.landing_restitution" => (field.into(), v(f.ball.landing_restitution)),
        "ball.stop_contact_time" => (field.into(), v(f.ball.stop_contact_time)),
        "ball.min_bounce_time" => (field.into(), v(f.ball.min_bounce_time)),
        "ball.lift_height" => (field.into(), v(f.ball.lift_height)),
        "integrator.gamma" => (field.into(), v(f.integrator.gamma)),
        "integrator.beta" => (field.into(), v(f.integrator.beta)),
        "integrator.step" => (field.into(), v(f.integrator.step)),
        "integrator.alpha_m" | "integrator.alpha_f" => (
            "integrator.rho_inf".into(),
            f.integrator.rho_inf.map_or("?".into(), v),
        ),
        "integrator.tolerance" => (field.into(), v(f.integrator.tolerance)),
        "integrator.max_iterations" => (field.into(), f.integrator.max_iterations.to_string()),
        "damping.stiffness_proportional" => (
            field.into(),
            format!("{:?}", f.damping.stiffness_proportional),
        ),
        "gravity" => (field.into(), v(f.gravity)),
        "calibration.bending_stiffness" => (field.into(), v(f.calibration.bending_stiffness)),
        "calibration.axial_stiffness" => (field.into(), v(f.calibration.axial_stiffness)),
        "calibration.mass_lumping" => (field.into(), v(f.calibration.mass_lumping)),
        "arm.root_diameter" | "arm.tip_diameter" | "arm.wall" | "arm.density" => {
            let a = f.arm.as_ref();
            let x = a.map(|a| match field {
                "arm.root_diameter" => a.root_diameter,
                "arm.tip_diameter" => a.tip_diameter,
                "arm.wall" => a.wall,
                _ => a.density,
            });
            (field.into(), x.map_or("?".into(), v))
        }
        other => (other.into(), "?".into()),
    }
}

/// Turns a core error into a message naming the scene-file key.
pub fn map_core_error(e: absorber_core::Error, scene: &Scene) -> anyhow::Error {
    match e {
        absorber_core::Error::InvalidParameter { field, reason } => {
            let (key, value) = scene_key(field, scene);
            let reason = if key.ends_with("_deg") {
                reason.replace("pi", "180 deg")
            } else {
                reason.to_string()
            };
            // The partner a reason compares with, and its value.
            let partner = match field {
                "ball.track_radius" => format!("; `ball.radius` = {}", num(scene.file.ball.radius)),
                "ball.initial_angle" => {
                    format!(
                        "; `ball.stop_angle_deg` = {}",
                        num(scene.file.ball.stop_angle_deg)
                    )
                }
                "arm.wall" => scene.file.arm.as_ref().map_or(String::new(), |a| {
                    format!(
                        "; `arm.root_diameter` = {}, `arm.tip_diameter` = {}",
                        num(a.root_diameter),
                        num(a.tip_diameter)
                    )
                }),
                _ => String::new(),
            };
            anyhow!("invalid value for `{key}`: {value} ({reason}{partner})")
        }
        other => anyhow!(physical_failure(other, scene)),
    }
}

/// A failure of the solution (not of the input) in words a user understands, with the likely
/// cause and what to try.
pub fn physical_failure(e: absorber_core::Error, scene: &Scene) -> String {
    use absorber_core::Error as E;
    let h = scene.file.integrator.step;
    let tol = scene.file.integrator.tolerance;
    match e {
        E::NoConvergence { iterations, increment } => format!(
            "the solver did not converge: after {iterations} Newton iterations the correction was still \
             {increment:.2e} (tolerance {tol:e}); likely cause: the motion changes too fast for the step \
             h = {h} s (violent input, stop impacts, a very flexible or very stiff beam); try a smaller \
             `integrator.step` (--step) or a larger `integrator.max_iterations`"
        ),
        E::Singular => "the equations of motion became singular (the model reached a configuration it \
             cannot represent, e.g. a beam folded over or a vanishing mass); likely cause: an excitation \
             or parameters far outside the model's range"
            .to_string(),
        E::NonFiniteState => format!(
            "the motion diverged (positions or velocities became infinite); likely cause: an excitation \
             or parameters far outside the model's range, or a step h = {h} s too large for them"
        ),
        E::NonFiniteInput => {
            "the base acceleration is not a finite number (check the excitation)".to_string()
        }
        other => other.to_string(),
    }
}

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

/// The wind's view of an arm: its outer diameter along the length.
pub fn taper_of(arm: &ArmSection, length: f64) -> crate::wind::Taper {
    crate::wind::Taper {
        length,
        root: arm.root_diameter,
        tip: arm.tip_diameter,
    }
}
