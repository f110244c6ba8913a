//! `fmu`: packages the reduced model of a scene as an FMI 3.0 or 2.0 co-simulation FMU.
//!
//! The FMU holds `modelDescription.xml` (generated from the variable table of `absorber-fmu`,
//! with the scene's parameters as start values), `resources/scene.cfg` (the scene's model and
//! parameters, read by the library when it is instantiated) and the shared library
//! `binaries/<platform>/absorber.so`. The library is the `absorber-fmu` crate's `cdylib`:
//! cargo builds it together with `host-sim` (a dependency's `cdylib` lands in `target/<profile>/
//! deps/`; `cargo build -p absorber-fmu` puts it in `target/<profile>/`), and this command
//! takes it from beside its own executable, or from `--library`. A library whose build marker
//! differs from the one compiled into this `host-sim` (built from other sources) is refused.

use crate::cli::{FmiVersion, FmuArgs};
use absorber_fmu::config::{Config, Kind as FmuKind};
use absorber_fmu::xml::{self, Version};
use absorber_sim::scene::{Kind, Precision, Scene, Solver};
use anyhow::{anyhow, bail, Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The FMU configuration of a scene (errors name the scene key).
pub fn config_of(s: &Scene) -> Result<Config> {
    let f = &s.file;
    if f.solver != Solver::Core {
        bail!("invalid value for `solver`: full (an FMU packages the reduced model: use --solver core)");
    }
    let kind = match f.kind {
        Kind::Beam => FmuKind::Beam,
        Kind::Tip => FmuKind::Tip,
        Kind::Locked => FmuKind::Locked,
        Kind::Free => FmuKind::Free,
        Kind::FreeNostops => FmuKind::FreeNostops,
    };
    let detail = match &f.arm {
        Some(arm) => arm.detail_category()?,
        None => absorber_core::monitor::DetailCategory::EPrime,
    };
    let config = Config {
        name: f.name.clone(),
        kind,
        elements: f.elements,
        single: f.precision == Precision::F32,
        detail,
        stop_time: f.duration,
        params: s.params()?,
    };
    // The model must start: parameter errors name the scene key, as `run` does.
    absorber_fmu::sim::build(&config, &config.params, 0.0, 0.0)
        .map_err(|e| absorber_sim::scene::map_core_error(e, s))?;
    Ok(config)
}

/// The library to package: `--library`, or the one cargo built beside this executable.
fn library(given: Option<&Path>) -> Result<(PathBuf, Vec<u8>)> {
    let marker = absorber_fmu::BUILD_MARKER.as_bytes();
    let has_marker = |bytes: &[u8]| bytes.windows(marker.len()).any(|w| w == marker);
    if let Some(p) = given {
        let bytes = std::fs::read(p).with_context(|| {
            format!(
                "invalid value for `--library`: cannot read `{}`",
                p.display()
            )
        })?;
        if !has_marker(&bytes) {
            bail!(
                "invalid value for `--library`: `{}` is not the absorber-fmu library of this host-sim's sources (rebuild both: cargo build --release -p host-sim)",
                p.display()
            );
        }
        return Ok((p.to_path_buf(), bytes));
    }
    let exe = std::env::current_exe().context("cannot locate the host-sim executable")?;
    let dir = exe.parent().map(Path::to_path_buf).unwrap_or_default();
    let name = "libabsorber_fmu.so";
    let candidates = [
        dir.join("deps").join(name),
        dir.join(name),
        dir.parent().map(|d| d.join(name)).unwrap_or_default(),
    ];
    let mut stale = Vec::new();
    for c in &candidates {
        if let Ok(bytes) = std::fs::read(c) {
            if has_marker(&bytes) {
                return Ok((c.clone(), bytes));
            }
            stale.push(c.display().to_string());
        }
    }
    if stale.is_empty() {
        bail!(
            "the FMU's shared library `{name}` is not beside host-sim (looked in {}); build it with \
             `cargo build --release -p host-sim -p absorber-fmu`, or give it with --library",
            candidates
                .iter()
                .map(|c| format!("`{}`", c.display()))
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
    bail!(
        "the FMU's shared library beside host-sim was built from other sources ({}); rebuild: \
         `cargo build --release -p host-sim -p absorber-fmu`",
        stale.join(", ")
    )
}

/// Writes the FMU archive to `path`.
fn write_fmu(path: &Path, config: &Config, version: Version, library: &[u8]) -> Result<()> {
    let file = std::fs::File::create(path)?;
    let mut z = zip::ZipWriter::new(std::io::BufWriter::new(file));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let so = format!(
        "binaries/{}/{}.so",
        version.platform(),
        xml::MODEL_IDENTIFIER
    );
    let (description, cfg) = (xml::model_description(config, version), config.to_text());
    let files: [(&str, &[u8]); 3] = [
        ("modelDescription.xml", description.as_bytes()),
        ("resources/scene.cfg", cfg.as_bytes()),
        (so.as_str(), library),
    ];
    for (name, bytes) in files {
        let opts = if name.ends_with(".so") {
            opts.unix_permissions(0o755)
        } else {
            opts
        };
        z.start_file(name, opts)?;
        z.write_all(bytes)?;
    }
    z.finish()?.flush()?;
    Ok(())
}

/// `fmu`.
pub fn run(a: &FmuArgs) -> Result<()> {
    if a.out.extension().is_none_or(|e| e != "fmu") {
        bail!(
            "invalid value for `--out`: `{}` (an FMU file name ends in .fmu)",
            a.out.display()
        );
    }
    // Checked (writable, locked) before anything is built.
    let (mut dir, name) = absorber_sim::output::OutputDir::for_file(&a.out, "fmu")
        .map_err(|e| anyhow!("invalid value for `--out`: {e:#}"))?;
    let s = super::load(&a.scene)?;
    let config = config_of(&s)?;
    let (lib_path, lib) = library(a.library.as_deref())?;
    let version = match a.fmi_version {
        FmiVersion::V3 => Version::Fmi3,
        FmiVersion::V2 => Version::Fmi2,
    };
    dir.write_with(&name, |tmp| write_fmu(tmp, &config, version, &lib))?;
    let written = dir.commit(
        absorber_sim::output::Status::Complete,
        serde_json::Value::Null,
    )?;
    let vars = absorber_fmu::vars::of_kind(config.kind).count();
    println!(
        "{}: FMI {} co-simulation FMU of scene {} ({} elements, {}, h = {} s), {} variables, library {}",
        written
            .first()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| a.out.display().to_string()),
        match version {
            Version::Fmi3 => "3.0",
            Version::Fmi2 => "2.0",
        },
        config.name,
        config.elements,
        if config.single { "f32" } else { "f64" },
        config.step(),
        vars,
        lib_path.display()
    );
    Ok(())
}
