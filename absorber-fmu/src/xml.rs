//! `modelDescription.xml` of FMI 3.0 and FMI 2.0, generated from the variable table
//! ([`crate::vars::VARIABLES`]) and the configuration: the variables, their value references,
//! units and start values come from the same source as the library's get/set functions.

use crate::config::Config;
use crate::instance::LOG_CATEGORIES;
use crate::vars::{self, Causality, Slot, Type, Var, UNITS};
use std::fmt::Write as _;

/// FMI version of an FMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    /// FMI 2.0.
    Fmi2,
    /// FMI 3.0.
    Fmi3,
}

impl Version {
    /// The platform folder of the binary inside the FMU (64-bit Linux).
    pub fn platform(self) -> &'static str {
        match self {
            Version::Fmi2 => "linux64",
            Version::Fmi3 => "x86_64-linux",
        }
    }
}

/// The FMU's model identifier (file name of its shared library without the extension).
pub const MODEL_IDENTIFIER: &str = "absorber";

/// XML-escapes `s` for an attribute value.
fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if (c as u32) < 0x20 => o.push(' '),
            c => o.push(c),
        }
    }
    o
}

/// Shortest round-trip form of a float (as XML needs it: no `inf`).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn start_of(v: &Var, config: &Config) -> Option<f64> {
    match v.slot {
        Slot::Param { get, .. } => Some(get(&config.params)),
        Slot::Input(_) => Some(0.0),
        _ => None,
    }
}

fn unit_definitions(out: &mut String) {
    out.push_str("  <UnitDefinitions>\n");
    for u in &UNITS {
        let _ = write!(out, "    <Unit name=\"{}\"><BaseUnit", esc(u.name));
        for (name, e) in ["kg", "m", "s", "rad"].iter().zip(u.exponents) {
            if e != 0 {
                let _ = write!(out, " {name}=\"{e}\"");
            }
        }
        out.push_str("/></Unit>\n");
    }
    out.push_str("  </UnitDefinitions>\n");
}

fn log_categories(out: &mut String) {
    out.push_str("  <LogCategories>\n");
    for (name, description) in LOG_CATEGORIES {
        let _ = writeln!(
            out,
            "    <Category name=\"{name}\" description=\"{}\"/>",
            esc(description)
        );
    }
    out.push_str("  </LogCategories>\n");
}

fn description(config: &Config) -> String {
    format!(
        "Free pendulum vibration absorber on a flexible cantilever (reduced model, {} scene \"{}\", {} elements, {}): co-simulation with a fixed step h = {} s",
        config.kind.name(),
        config.name,
        config.elements,
        if config.single { "f32" } else { "f64" },
        config.step()
    )
}

/// The `modelDescription.xml` of `config` for FMI `version`.
pub fn model_description(config: &Config, version: Version) -> String {
    let vars: Vec<&Var> = vars::of_kind(config.kind).collect();
    let h = num(config.step());
    let mut o = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let common = format!(
        "modelName=\"absorber.{}\"\n  description=\"{}\"\n  author=\"absorber\"\n  version=\"{}\"\n  generationTool=\"host-sim fmu {}\"\n  variableNamingConvention=\"structured\"",
        esc(&config.name),
        esc(&description(config)),
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_VERSION"),
    );
    match version {
        Version::Fmi3 => {
            let _ = write!(
                o,
                "<fmiModelDescription\n  fmiVersion=\"3.0\"\n  {common}\n  instantiationToken=\"{}\">\n",
                config.token()
            );
            let _ = writeln!(
                o,
                "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"false\" fixedInternalStepSize=\"{h}\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" canReturnEarlyAfterIntermediateUpdate=\"false\" hasEventMode=\"false\" providesIntermediateUpdate=\"false\"/>"
            );
        }
        Version::Fmi2 => {
            let _ = write!(
                o,
                "<fmiModelDescription\n  fmiVersion=\"2.0\"\n  {common}\n  guid=\"{}\"\n  numberOfEventIndicators=\"0\">\n",
                config.token()
            );
            let _ = writeln!(
                o,
                "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"false\" canInterpolateInputs=\"false\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" canNotUseMemoryManagementFunctions=\"true\"/>"
            );
        }
    }
    unit_definitions(&mut o);
    log_categories(&mut o);
    let _ = writeln!(
        o,
        "  <DefaultExperiment startTime=\"0.0\" stopTime=\"{}\" stepSize=\"{h}\"/>",
        num(config.stop_time)
    );
    o.push_str("  <ModelVariables>\n");
    for v in &vars {
        match version {
            Version::Fmi3 => fmi3_variable(&mut o, v, config),
            Version::Fmi2 => fmi2_variable(&mut o, v, config),
        }
    }
    o.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    let outputs: Vec<(usize, &&Var)> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .collect();
    match version {
        Version::Fmi3 => {
            for (_, v) in &outputs {
                let _ = writeln!(o, "    <Output valueReference=\"{}\"/>", v.vr);
            }
            for (_, v) in &outputs {
                let _ = writeln!(o, "    <InitialUnknown valueReference=\"{}\"/>", v.vr);
            }
        }
        Version::Fmi2 => {
            o.push_str("    <Outputs>\n");
            for (i, _) in &outputs {
                let _ = writeln!(o, "      <Unknown index=\"{}\"/>", i + 1);
            }
            o.push_str("    </Outputs>\n    <InitialUnknowns>\n");
            for (i, _) in &outputs {
                let _ = writeln!(o, "      <Unknown index=\"{}\"/>", i + 1);
            }
            o.push_str("    </InitialUnknowns>\n");
        }
    }
    o.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    o
}

fn attributes(v: &Var) -> String {
    let mut a = format!(
        "name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{}\" variability=\"{}\"",
        esc(v.name),
        v.vr,
        esc(v.description),
        v.causality.name(),
        v.variability.name()
    );
    if v.causality == Causality::Parameter {
        a.push_str(" initial=\"exact\"");
    }
    a
}

fn fmi3_variable(o: &mut String, v: &Var, config: &Config) {
    let tag = match v.ty {
        Type::Float64 => "Float64",
        Type::Int32 => "Int32",
    };
    let _ = write!(o, "    <{tag} {}", attributes(v));
    if let Some(u) = v.unit {
        let _ = write!(o, " unit=\"{}\"", esc(u));
    }
    if let Some(s) = start_of(v, config) {
        let _ = write!(o, " start=\"{}\"", num(s));
    }
    o.push_str("/>\n");
}

fn fmi2_variable(o: &mut String, v: &Var, config: &Config) {
    let tag = match v.ty {
        Type::Float64 => "Real",
        Type::Int32 => "Integer",
    };
    let _ = write!(o, "    <ScalarVariable {}>\n      <{tag}", attributes(v));
    if let Some(u) = v.unit {
        let _ = write!(o, " unit=\"{}\"", esc(u));
    }
    if let Some(s) = start_of(v, config) {
        let _ = write!(o, " start=\"{}\"", num(s));
    }
    o.push_str("/>\n    </ScalarVariable>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Kind;

    /// Every variable of the table that the scene has appears once with its value reference,
    /// the parameters with the configuration's values as start values; variables of other
    /// scenes are left out.
    #[test]
    fn description_lists_the_table() {
        let mut c = crate::config::tests::paper();
        c.params.beam.modulus = 2.5e11;
        for version in [Version::Fmi2, Version::Fmi3] {
            let x = model_description(&c, version);
            for v in vars::VARIABLES {
                let needle = format!("name=\"{}\" valueReference=\"{}\"", v.name, v.vr);
                assert_eq!(x.matches(&needle).count(), 1, "{}", v.name);
            }
            assert!(x.contains("start=\"250000000000.0\""));
            c.kind = Kind::Beam;
            let beam = model_description(&c, version);
            assert!(!beam.contains("ball.mass") && !beam.contains("tip.mass"));
            c.kind = Kind::Free;
        }
    }
}
