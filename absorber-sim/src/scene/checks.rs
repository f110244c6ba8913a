//! What a scene is checked for before a run: ranges, magnitudes and the step against the
//! excitation; errors that name the field.

use super::{
    taper_of, ExcitationType, Kind, Scene, SceneFile, Solver, ELEMENTS, MAX_ACCEL, MAX_STEPS,
    MAX_TOLERANCE, STEPS_PER_PERIOD_WARN,
};
use absorber_core::Params;
use anyhow::{anyhow, bail, Result};

impl Scene {
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
}

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

pub(super) fn finite_positive(x: f64, key: &str) -> Result<()> {
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
