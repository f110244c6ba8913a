//! The FMU's variables: one table ([`VARIABLES`]) that gives every variable its value
//! reference, name, type, causality, unit and where its value lives. `modelDescription.xml`
//! ([`crate::xml`]) is generated from it, and the get/set functions of both FMI versions
//! ([`crate::instance`]) look values up in it: there is no second list to keep in step.
//!
//! Value references are fixed numbers (not positions): a variable keeps its reference when
//! others are added. The parameters are the scene's physical parameters in SI units (angles in
//! radians), with the scene's values as start values.

use crate::config::Kind;
use absorber_core::Params;

/// FMI causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// The independent variable (time).
    Independent,
    /// Set by the importer before initialization.
    Parameter,
    /// Set by the importer before each step.
    Input,
    /// Computed by the FMU.
    Output,
}

impl Causality {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            Self::Independent => "independent",
            Self::Parameter => "parameter",
            Self::Input => "input",
            Self::Output => "output",
        }
    }
}

/// FMI variability.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Set before initialization only.
    Fixed,
    /// Changes discretely (integer outputs).
    Discrete,
    /// Changes continuously (real inputs and outputs, time).
    Continuous,
}

impl Variability {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Discrete => "discrete",
            Self::Continuous => "continuous",
        }
    }
}

/// The variable's type: FMI 3 `Float64`/`Int32`, FMI 2 `Real`/`Integer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Type {
    /// 64-bit floating point.
    Float64,
    /// 32-bit signed integer.
    Int32,
}

/// Which scenes have the variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applies {
    /// Every scene.
    All,
    /// Scenes with a tip mass (all but `beam`).
    Tip,
    /// Scenes with a ball, locked or free.
    Ball,
    /// Scenes with a free ball.
    FreeBall,
}

impl Applies {
    /// Whether a scene of `kind` has the variable.
    pub fn to(self, kind: Kind) -> bool {
        match self {
            Self::All => true,
            Self::Tip => kind != Kind::Beam,
            Self::Ball => matches!(kind, Kind::Locked | Kind::Free | Kind::FreeNostops),
            Self::FreeBall => matches!(kind, Kind::Free | Kind::FreeNostops),
        }
    }
}

/// The outputs, in the order of [`crate::sim::Outputs`]'s fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Tip deflection relative to the base \[m\].
    TipDeflection,
    /// Absolute vertical acceleration of the tip \[m/s²\].
    TipAcceleration,
    /// Root stress \[Pa\].
    RootStress,
    /// Ball angle θ from the downward vertical \[rad\].
    BallAngle,
    /// Ball angle relative to the housing α = θ − ψ \[rad\].
    BallRelativeAngle,
    /// Normal force of the track on the ball \[N\].
    NormalForce,
    /// Miner damage so far \[-\].
    Damage,
    /// Contact state code.
    Contact,
}

/// Where a variable's value lives.
#[derive(Clone, Copy)]
pub enum Slot {
    /// The FMU's time \[s\].
    Time,
    /// Input `k` ([`INPUTS`]).
    Input(usize),
    /// An output.
    Output(Output),
    /// A field of the model's parameters.
    Param {
        /// Reads it.
        get: fn(&Params<f64>) -> f64,
        /// Writes it.
        set: fn(&mut Params<f64>, f64),
    },
}

/// One variable of the FMU.
#[derive(Clone, Copy)]
pub struct Var {
    /// FMI value reference.
    pub vr: u32,
    /// Structured name (`beam.length`).
    pub name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// Type.
    pub ty: Type,
    /// Unit (a name of [`UNITS`]), or none for a dimensionless number.
    pub unit: Option<&'static str>,
    /// Scenes that have it.
    pub applies: Applies,
    /// Its value.
    pub slot: Slot,
}

/// Names of the inputs, in slot order: base acceleration \[m/s²\], tip load \[N\].
pub const INPUTS: [&str; 2] = ["base_acceleration", "tip_load"];

/// A unit: name and SI base-unit exponents (kg, m, s, rad).
pub struct Unit {
    /// Name as used by the variables.
    pub name: &'static str,
    /// Exponents of kg, m, s, rad.
    pub exponents: [i32; 4],
}

/// Every unit a variable uses.
pub const UNITS: [Unit; 11] = [
    Unit {
        name: "m",
        exponents: [0, 1, 0, 0],
    },
    Unit {
        name: "m2",
        exponents: [0, 2, 0, 0],
    },
    Unit {
        name: "m4",
        exponents: [0, 4, 0, 0],
    },
    Unit {
        name: "kg",
        exponents: [1, 0, 0, 0],
    },
    Unit {
        name: "kg.m2",
        exponents: [1, 2, 0, 0],
    },
    Unit {
        name: "s",
        exponents: [0, 0, 1, 0],
    },
    Unit {
        name: "m/s2",
        exponents: [0, 1, -2, 0],
    },
    Unit {
        name: "N",
        exponents: [1, 1, -2, 0],
    },
    Unit {
        name: "Pa",
        exponents: [1, -1, -2, 0],
    },
    Unit {
        name: "rad",
        exponents: [0, 0, 0, 1],
    },
    Unit {
        name: "rad/s",
        exponents: [0, 0, -1, 1],
    },
];

macro_rules! param {
    ($vr:expr, $name:expr, $unit:expr, $applies:ident, $desc:expr, $($f:ident).+) => {
        Var {
            vr: $vr,
            name: $name,
            description: $desc,
            causality: Causality::Parameter,
            variability: Variability::Fixed,
            ty: Type::Float64,
            unit: $unit,
            applies: Applies::$applies,
            slot: Slot::Param {
                get: |p| p.$($f).+,
                set: |p, x| p.$($f).+ = x,
            },
        }
    };
}

const fn output(
    vr: u32,
    name: &'static str,
    unit: Option<&'static str>,
    applies: Applies,
    description: &'static str,
    which: Output,
) -> Var {
    let ty = match which {
        Output::Contact => Type::Int32,
        _ => Type::Float64,
    };
    Var {
        vr,
        name,
        description,
        causality: Causality::Output,
        variability: match ty {
            Type::Int32 => Variability::Discrete,
            Type::Float64 => Variability::Continuous,
        },
        ty,
        unit,
        applies,
        slot: Slot::Output(which),
    }
}

const fn input(vr: u32, k: usize, unit: &'static str, description: &'static str) -> Var {
    Var {
        vr,
        name: INPUTS[k],
        description,
        causality: Causality::Input,
        variability: Variability::Continuous,
        ty: Type::Float64,
        unit: Some(unit),
        applies: Applies::All,
        slot: Slot::Input(k),
    }
}

/// Every variable of the FMU (those a scene does not have are left out of its
/// `modelDescription.xml`, [`Applies`]).
pub const VARIABLES: &[Var] = &[
    Var {
        vr: 0,
        name: "time",
        description: "Simulation time",
        causality: Causality::Independent,
        variability: Variability::Continuous,
        ty: Type::Float64,
        unit: Some("s"),
        applies: Applies::All,
        slot: Slot::Time,
    },
    input(
        1,
        0,
        "m/s2",
        "Base acceleration, positive up, gravity removed; held over each communication step and applied at its end",
    ),
    input(
        2,
        1,
        "N",
        "Vertical force on the beam end, positive up; held over each communication step",
    ),
    output(10, "tip_deflection", Some("m"), Applies::All, "Vertical deflection of the beam end relative to the base, static sag included", Output::TipDeflection),
    output(11, "tip_acceleration", Some("m/s2"), Applies::All, "Absolute vertical acceleration of the beam end (base included, gravity not): what a tip accelerometer reads", Output::TipAcceleration),
    output(12, "root_stress", Some("Pa"), Applies::All, "Bending stress at the clamp, top fibre, tension positive (clamp reaction moment over the section modulus)", Output::RootStress),
    output(13, "ball_angle", Some("rad"), Applies::Ball, "Ball angle theta from the downward vertical", Output::BallAngle),
    output(14, "ball_relative_angle", Some("rad"), Applies::Ball, "Ball angle relative to the housing, theta - psi", Output::BallRelativeAngle),
    output(15, "normal_force", Some("N"), Applies::FreeBall, "Normal force of the track on the ball (negative: the track would pull; 0 in flight)", Output::NormalForce),
    output(16, "damage", None, Applies::All, "Miner damage at the clamp since the start (rainflow, AASHTO S-N curve of the scene's detail, open cycles counted as halves)", Output::Damage),
    output(17, "contact", None, Applies::FreeBall, "Ball contact: 0 on the track, +1/-1 resting on the positive/negative stop, 2 in flight, 3 rolling beyond the stops", Output::Contact),
    param!(100, "beam.length", Some("m"), All, "Beam length L", beam.length),
    param!(101, "beam.mass", Some("kg"), All, "Beam mass", beam.mass),
    param!(102, "beam.area", Some("m2"), All, "Cross-section area a", beam.area),
    param!(103, "beam.modulus", Some("Pa"), All, "Young's modulus E", beam.modulus),
    param!(104, "beam.inertia", Some("m4"), All, "Second moment of area I", beam.inertia),
    param!(110, "tip.mass", Some("kg"), Tip, "Tip mass m_t", tip.mass),
    param!(111, "tip.inertia", Some("kg.m2"), Tip, "Tip mass moment of inertia J_t about its centre", tip.inertia),
    param!(112, "tip.offset", Some("m"), Tip, "Distance from the tip mass centre up to the beam end", tip.offset),
    param!(120, "ball.mass", Some("kg"), Ball, "Ball mass m_b", ball.mass),
    param!(121, "ball.inertia", Some("kg.m2"), Ball, "Ball moment of inertia J_b about its centre", ball.inertia),
    param!(122, "ball.radius", Some("m"), Ball, "Ball radius r_b", ball.radius),
    param!(123, "ball.track_radius", Some("m"), Ball, "Track radius R", ball.track_radius),
    param!(124, "ball.stop_angle", Some("rad"), FreeBall, "Stop angle relative to the housing", ball.stop_angle),
    param!(125, "ball.restitution", None, FreeBall, "Coefficient of restitution of a stop impact", ball.restitution),
    param!(126, "ball.stick_speed", Some("rad/s"), FreeBall, "Relative speed below which a stop impact is plastic", ball.stick_speed),
    param!(127, "ball.initial_angle", Some("rad"), FreeBall, "Ball angle from the downward vertical at the start", ball.initial_angle),
    param!(128, "ball.landing_restitution", None, FreeBall, "Coefficient of normal restitution of a landing on the track", ball.landing_restitution),
    param!(130, "damping.stiffness_proportional", Some("s"), All, "Stiffness-proportional damping coefficient c in C = c K", damping.stiffness_proportional),
    param!(131, "gravity", Some("m/s2"), All, "Gravity g along -y", gravity),
    param!(140, "calibration.bending_stiffness", None, All, "Calibration factor on E I", calibration.bending_stiffness),
    param!(141, "calibration.axial_stiffness", None, All, "Calibration factor on E a", calibration.axial_stiffness),
    param!(142, "calibration.mass_lumping", None, All, "Fraction of lumped mass in the element mass matrix", calibration.mass_lumping),
];

/// The variable with value reference `vr` that a scene of `kind` has.
pub fn find(vr: u32, kind: Kind) -> Option<&'static Var> {
    VARIABLES
        .iter()
        .find(|v| v.vr == vr)
        .filter(|v| v.applies.to(kind))
}

/// The variables a scene of `kind` has, in table order.
pub fn of_kind(kind: Kind) -> impl Iterator<Item = &'static Var> {
    VARIABLES.iter().filter(move |v| v.applies.to(kind))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Value references and names are unique; every unit is defined; every parameter's setter
    /// writes what its getter reads.
    #[test]
    fn the_table_is_consistent() {
        for (i, a) in VARIABLES.iter().enumerate() {
            for b in &VARIABLES[i + 1..] {
                assert_ne!(a.vr, b.vr, "{} and {}", a.name, b.name);
                assert_ne!(a.name, b.name);
            }
            if let Some(u) = a.unit {
                assert!(UNITS.iter().any(|x| x.name == u), "{u}");
            }
            if let Slot::Param { get, set } = a.slot {
                let mut p = Params::<f64>::default();
                set(&mut p, 1234.5);
                assert_eq!(get(&p), 1234.5, "{}", a.name);
            }
        }
    }
}
