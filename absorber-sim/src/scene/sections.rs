//! The scene file's sections (`[beam]`, `[tip]`, `[ball]`, …) as TOML reads them, and their
//! defaults (the paper's Table 1).

use super::{ArmSection, Kind, Precision, SensorSection, SensorSpec, Solver};
use absorber_core::{Calibration, EventLocation, ImpactModel, NewtonKind, Params};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

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
