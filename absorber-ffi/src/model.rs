//! The model's functions: parameters, `absorber_init`, step and restart, and the reads of
//! outputs, energies, root stress and state.

use super::*;

/// Fills `params` with the paper's Table 1 (h = 3 ms, Newton tolerance 1e-5, at most 100
/// iterations, one Newton matrix per step, no damping, g = 9.81 m/s²) and sets `size`.
///
/// # Safety
/// `params` is NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn absorber_params_default(params: *mut AbsorberParams) -> AbsorberStatus {
    if params.is_null() {
        return AbsorberStatus::NullPointer;
    }
    let d = Params::<f64>::default();
    let p = AbsorberParams {
        size: size_of::<AbsorberParams>() as u32,
        beam: AbsorberBeamParams {
            length: d.beam.length,
            mass: d.beam.mass,
            area: d.beam.area,
            modulus: d.beam.modulus,
            inertia: d.beam.inertia,
        },
        tip: AbsorberTipParams {
            mass: d.tip.mass,
            inertia: d.tip.inertia,
            offset: d.tip.offset,
        },
        ball: AbsorberBallParams {
            mass: d.ball.mass,
            inertia: d.ball.inertia,
            radius: d.ball.radius,
            track_radius: d.ball.track_radius,
            stop_angle: d.ball.stop_angle,
            restitution: d.ball.restitution,
            stick_speed: d.ball.stick_speed,
            initial_angle: d.ball.initial_angle,
            impact_model: match d.ball.impact_model {
                ImpactModel::Instantaneous => ABSORBER_IMPACT_INSTANTANEOUS,
                ImpactModel::OverStep => ABSORBER_IMPACT_OVER_STEP,
            },
        },
        integrator: AbsorberIntegratorParams {
            gamma: d.integrator.gamma,
            beta: d.integrator.beta,
            step: d.integrator.step,
            tolerance: d.integrator.tolerance,
            max_iterations: d.integrator.max_iterations,
            newton: match d.integrator.newton {
                NewtonKind::Full => ABSORBER_NEWTON_FULL,
                NewtonKind::Modified => ABSORBER_NEWTON_MODIFIED,
                NewtonKind::PerStep => ABSORBER_NEWTON_PER_STEP,
            },
            accept_after_budget: u8::from(d.integrator.accept_after_budget),
            events: match d.integrator.events {
                EventLocation::Crossing => ABSORBER_EVENTS_CROSSING,
                EventLocation::StepEnd => ABSORBER_EVENTS_STEP_END,
            },
        },
        damping: AbsorberDampingParams {
            stiffness_proportional: d.damping.stiffness_proportional,
        },
        gravity: d.gravity,
        alpha_m: d.integrator.alpha_m,
        alpha_f: d.integrator.alpha_f,
        calibration: AbsorberCalibrationParams {
            bending_stiffness: d.calibration.bending_stiffness,
            axial_stiffness: d.calibration.axial_stiffness,
            mass_lumping: d.calibration.mass_lumping,
        },
        flight: u32::from(d.ball.flight),
        landing_restitution: d.ball.landing_restitution,
        max_work: d.integrator.max_work,
        at_cap: match d.integrator.at_cap {
            AtCap::Take => ABSORBER_AT_CAP_TAKE,
            AtCap::Keep => ABSORBER_AT_CAP_KEEP,
        },
    };
    // SAFETY: non-null, valid for writes by the caller's guarantee.
    unsafe { params.write(p) };
    AbsorberStatus::Ok
}

/// Switches `params` to the generalized-α integrator with high-frequency spectral radius
/// `rho_inf` (0 to 1): sets γ, β, α_m and α_f (`absorber_core::Integrator::generalized_alpha`;
/// Chung & Hulbert 1993). Little numerical damping at the resolved modes, `rho_inf` per step at
/// the unresolved ones: use it with structural damping (`damping.stiffness_proportional`).
/// A `rho_inf` outside \[0, 1\] gives weights that `absorber_init` rejects by name.
///
/// # Safety
/// `params` is NULL or valid for reads and writes of one `AbsorberParams`.
#[no_mangle]
pub unsafe extern "C" fn absorber_params_generalized_alpha(
    params: *mut AbsorberParams,
    rho_inf: f64,
) -> AbsorberStatus {
    // SAFETY: NULL or valid by the caller's guarantee.
    let Some(p) = (unsafe { params.as_mut() }) else {
        return AbsorberStatus::NullPointer;
    };
    let i = Params::<f64>::default()
        .integrator
        .generalized_alpha(rho_inf);
    p.integrator.gamma = i.gamma;
    p.integrator.beta = i.beta;
    p.alpha_m = i.alpha_m;
    p.alpha_f = i.alpha_f;
    AbsorberStatus::Ok
}

/// Storage a variant needs in this build \[bytes\] (at most its `ABSORBER_MODEL_SIZE_*`), or 0
/// for an unknown variant or one not compiled in.
#[no_mangle]
pub extern "C" fn absorber_model_size(variant: u32) -> usize {
    match variant {
        #[cfg(feature = "free-n3-f32")]
        ABSORBER_VARIANT_FREE_N3_F32 => size_of::<Slot<FreeN3F32>>(),
        #[cfg(feature = "locked-n3-f32")]
        ABSORBER_VARIANT_LOCKED_N3_F32 => size_of::<Slot<LockedN3F32>>(),
        #[cfg(feature = "beam-n3-f32")]
        ABSORBER_VARIANT_BEAM_N3_F32 => size_of::<Slot<BeamN3F32>>(),
        #[cfg(feature = "free-n6-f32")]
        ABSORBER_VARIANT_FREE_N6_F32 => size_of::<Slot<FreeN6F32>>(),
        #[cfg(feature = "free-n3-f64")]
        ABSORBER_VARIANT_FREE_N3_F64 => size_of::<Slot<FreeN3F64>>(),
        _ => 0,
    }
}

/// Builds a model of `variant` in `storage`: validates `params`, solves the static equilibrium
/// under gravity and starts from it at rest, with `base_accel` \[m/s²\] as the input at t = 0.
/// On success `*model` is the handle (it points into `storage`).
///
/// On failure nothing is written to `*model`; if `error` is not NULL it receives the status,
/// the bad field's dotted name (`"beam.modulus"`, `"integrator.step"`, `"size"`,
/// `"storage_size"`, `"variant"`), the value given for it (`value`, with `has_value` = 1) and the
/// reason (the allowed range). The storage may have been overwritten.
///
/// # Safety
/// `storage` is valid for writes of `storage_size` bytes and not used otherwise while the model
/// is; `params` is valid for reads of `params->size` bytes (NULL is refused); `model` valid for
/// a write; `error` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_init(
    storage: *mut c_void,
    storage_size: usize,
    variant: u32,
    params: *const AbsorberParams,
    base_accel: f64,
    model: *mut *mut AbsorberModel,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all `fail`/`build` calls): `error`, `storage`, `model` forwarded from the caller.
    unsafe {
        if storage.is_null() || params.is_null() || model.is_null() {
            return fail(error, AbsorberStatus::NullPointer, "", "NULL argument");
        }
        if storage.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
            return fail(
                error,
                AbsorberStatus::Storage,
                "storage",
                "is not aligned to ABSORBER_MODEL_ALIGN",
            );
        }
        // Read the size first: an older caller's struct may be shorter than ours.
        let size = params.cast::<u32>().read();
        if size as usize != size_of::<AbsorberParams>() {
            return fail_with(
                error,
                AbsorberStatus::InvalidParameter,
                "size",
                "is not sizeof(AbsorberParams) of this library: fill the struct with absorber_params_default()",
                Some(f64::from(size)),
            );
        }
        let p = &*params;
        let (s, a, t, m, e) = (storage_size, base_accel, variant, model, error);
        match variant {
            #[cfg(feature = "free-n3-f32")]
            ABSORBER_VARIANT_FREE_N3_F32 => {
                build::<f32, absorber_core::FreeBall, 3, 13>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "locked-n3-f32")]
            ABSORBER_VARIANT_LOCKED_N3_F32 => {
                build::<f32, absorber_core::LockedBall, 3, 12>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "beam-n3-f32")]
            ABSORBER_VARIANT_BEAM_N3_F32 => {
                build::<f32, absorber_core::BeamOnly, 3, 12>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "free-n6-f32")]
            ABSORBER_VARIANT_FREE_N6_F32 => {
                build::<f32, absorber_core::FreeBall, 6, 25>(storage, s, t, p, a, m, e)
            }
            #[cfg(feature = "free-n3-f64")]
            ABSORBER_VARIANT_FREE_N3_F64 => {
                build::<f64, absorber_core::FreeBall, 3, 13>(storage, s, t, p, a, m, e)
            }
            _ => fail_with(
                error,
                AbsorberStatus::Variant,
                "variant",
                "is not an ABSORBER_VARIANT_* compiled into this library",
                Some(f64::from(variant)),
            ),
        }
    }
}

impl AbsorberStatus {
    /// Every status, in the order of their values.
    const ALL: [AbsorberStatus; 15] = [
        AbsorberStatus::Ok,
        AbsorberStatus::InvalidParameter,
        AbsorberStatus::NonFiniteInput,
        AbsorberStatus::InputOutOfRange,
        AbsorberStatus::NoConvergence,
        AbsorberStatus::NonFiniteState,
        AbsorberStatus::Singular,
        AbsorberStatus::NullPointer,
        AbsorberStatus::Storage,
        AbsorberStatus::Variant,
        AbsorberStatus::Precision,
        AbsorberStatus::NotInitialized,
        AbsorberStatus::BufferTooSmall,
        AbsorberStatus::Other,
        AbsorberStatus::WorkCap,
    ];

    /// The status whose value is `raw`, if there is one.
    fn from_raw(raw: i32) -> Option<AbsorberStatus> {
        Self::ALL.into_iter().find(|s| *s as i32 == raw)
    }
}

/// A short, static, NUL-terminated name of a status (`"ok"`, `"invalid parameter"`, …);
/// `"unknown status"` for a value that is none (the argument is the status's integer value, so
/// that any value C can pass is defined behaviour).
#[no_mangle]
pub extern "C" fn absorber_status_name(status: i32) -> *const c_char {
    let Some(status) = AbsorberStatus::from_raw(status) else {
        return c"unknown status".as_ptr();
    };
    let s: &'static core::ffi::CStr = match status {
        AbsorberStatus::Ok => c"ok",
        AbsorberStatus::InvalidParameter => c"invalid parameter",
        AbsorberStatus::NonFiniteInput => c"base acceleration not finite",
        AbsorberStatus::InputOutOfRange => c"base acceleration out of range",
        AbsorberStatus::NoConvergence => c"no convergence",
        AbsorberStatus::NonFiniteState => c"non-finite state",
        AbsorberStatus::Singular => c"singular",
        AbsorberStatus::NullPointer => c"NULL pointer",
        AbsorberStatus::Storage => c"storage too small or misaligned",
        AbsorberStatus::Variant => c"unknown variant",
        AbsorberStatus::Precision => c"wrong precision",
        AbsorberStatus::NotInitialized => c"not initialized",
        AbsorberStatus::BufferTooSmall => c"buffer too small",
        AbsorberStatus::Other => c"other error",
        AbsorberStatus::WorkCap => c"work cap reached",
    };
    s.as_ptr()
}

pub(crate) fn report_of<T: Real>(r: &StepReport<T>) -> AbsorberReport<T> {
    let z = T::zero();
    let l = r.landing;
    let mut out = AbsorberReport {
        iterations: r.iterations,
        increment: r.increment,
        separation: u8::from(r.separation.is_some()),
        landing: l.map_or(0, |l| if l.bounced { 1 } else { 2 }),
        separation_time: r.separation.unwrap_or(z),
        landing_time: l.map_or(z, |l| l.time),
        landing_normal_speed: l.map_or(z, |l| l.normal_speed),
        landing_normal_impulse: l.map_or(z, |l| l.normal_impulse),
        landing_tangential_impulse: l.map_or(z, |l| l.tangential_impulse),
        impact: 0,
        impact_stuck: 0,
        impact_side: 0,
        impact_time: z,
        impact_relative_speed: z,
        impact_impulse: z,
        impact_energy_loss: z,
        work: u32::from(r.work),
        outcome: match r.outcome {
            Outcome::Converged => ABSORBER_OUTCOME_CONVERGED,
            Outcome::Capped => ABSORBER_OUTCOME_CAPPED,
            Outcome::Restarted => ABSORBER_OUTCOME_RESTARTED,
        },
    };
    if let Some(i) = &r.impact {
        out.impact = 1;
        out.impact_stuck = u8::from(i.stuck);
        out.impact_side = match i.side {
            Side::Positive => 1,
            Side::Negative => -1,
        };
        out.impact_time = i.time;
        out.impact_relative_speed = i.relative_speed;
        out.impact_impulse = i.impulse;
        out.impact_energy_loss = i.energy_loss;
    }
    out
}

/// Steps the model.
///
/// # Safety
/// `model` as in [`model_of`]; `report` NULL or valid for a write.
#[inline(always)]
pub(crate) unsafe fn step<T: Scalar>(
    model: *mut AbsorberModel,
    base_accel: T,
    report: *mut AbsorberReport<T>,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    match m.step(base_accel) {
        Ok(r) => {
            if !report.is_null() {
                // SAFETY: non-null, valid for a write by the caller's guarantee.
                unsafe { report.write(report_of(&r)) };
            }
            AbsorberStatus::Ok
        }
        Err(e) => status_of(&e),
    }
}

twins! {
    /// Advances a `float` model by one step h to the new base acceleration ÿ_b(t + h) \[m/s²\]
    /// (measured, positive up, gravity removed). On error the state is exactly as before the call
    /// (log it and feed the next sample). `report` may be NULL.
    ///
    /// # Safety
    /// `model` is a handle of [`absorber_init`] whose storage is live and not used concurrently;
    /// `report` is NULL or valid for a write.
    fn absorber_step_f32 / absorber_step_f64 (double model) (
        model: *mut AbsorberModel,
        base_accel: f32 => f64,
        report: *mut AbsorberReportF32 => *mut AbsorberReportF64,
    ) {
        // SAFETY: forwarded.
        unsafe { step(model, base_accel, report) }
    }
}

/// Restarts.
///
/// # Safety
/// `model` as in [`model_of`].
pub(crate) unsafe fn restart<T: Scalar>(
    model: *mut AbsorberModel,
    base_accel: T,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    match m.restart(base_accel) {
        Ok(()) => AbsorberStatus::Ok,
        Err(e) => status_of(&e),
    }
}

twins! {
    /// Restarts a `float` model at t = 0 from its static equilibrium, at rest, with input
    /// `base_accel` \[m/s²\] (recovers from any state a run of failed steps can leave).
    ///
    /// # Safety
    /// `model` is a live handle of [`absorber_init`].
    fn absorber_restart_f32 / absorber_restart_f64 (double model) (
        model: *mut AbsorberModel,
        base_accel: f32 => f64,
    ) {
        // SAFETY: forwarded.
        unsafe { restart(model, base_accel) }
    }
}

/// Writes `value(model)` to `out`.
///
/// # Safety
/// `model` as in [`model_of`]; `out` NULL or valid for a write.
pub(crate) unsafe fn read<T: Scalar, R>(
    model: *const AbsorberModel,
    out: *mut R,
    value: impl FnOnce(&dyn Erased<T>) -> Result<R, AbsorberStatus>,
) -> AbsorberStatus {
    if out.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    let v = try_status!(value(m));
    // SAFETY: non-null, valid for a write by the caller's guarantee.
    unsafe { out.write(v) };
    AbsorberStatus::Ok
}

twins! {
    /// The outputs of a `float` model now: tip deflection and rotation, ball angles, their rates.
    ///
    /// # Safety
    /// `model` is a live handle of [`absorber_init`]; `out` valid for a write.
    fn absorber_outputs_f32 / absorber_outputs_f64 (double model) <T> (
        model: *const AbsorberModel,
        out: *mut AbsorberOutputsF32 => *mut AbsorberOutputsF64,
    ) {
        // SAFETY: forwarded.
        unsafe { read::<T, _>(model, out, |m| Ok(m.outputs())) }
    }
}

twins! {
    /// Energies of a `float` model's bodies \[J\]; pass the base velocity \[m/s\] and displacement
    /// \[m\] for absolute kinetic energies, or 0 and 0 for the frame moving with the base
    /// (`ABSORBER_STATUS_NON_FINITE_INPUT` and nothing written if either is not finite).
    ///
    /// # Safety
    /// `model` is a live handle of [`absorber_init`]; `out` valid for a write.
    fn absorber_energies_f32 / absorber_energies_f64 (double model) <T> (
        model: *const AbsorberModel,
        base_velocity: f32 => f64,
        base_displacement: f32 => f64,
        out: *mut AbsorberEnergiesF32 => *mut AbsorberEnergiesF64,
    ) {
        // SAFETY: forwarded.
        unsafe {
            read::<T, _>(model, out, |m| {
                if !(base_velocity.is_finite() && base_displacement.is_finite()) {
                    return Err(AbsorberStatus::NonFiniteInput);
                }
                Ok(m.energies(base_velocity, base_displacement))
            })
        }
    }
}

twins! {
    /// Root bending stress of a `float` model now (top fibre, tension positive) \[Pa\]: the clamp
    /// reaction moment over the section modulus of the rectangle implied by the beam's area and
    /// second moment (as the monitor's default).
    ///
    /// # Safety
    /// `model` is a live handle of [`absorber_init`]; `stress` valid for a write.
    fn absorber_root_stress_f32 / absorber_root_stress_f64 (double model) <T> (
        model: *const AbsorberModel,
        stress: *mut f32 => *mut f64,
    ) {
        // SAFETY: forwarded.
        unsafe {
            read::<T, _>(model, stress, |m| {
                m.root_stress().map_err(|e| status_of(&e))
            })
        }
    }
}

/// Copies the state.
///
/// # Safety
/// As [`absorber_state_f32`].
pub(crate) unsafe fn state<T: Scalar>(
    model: *const AbsorberModel,
    info: *mut AbsorberStateInfo<T>,
    q: *mut T,
    v: *mut T,
    a: *mut T,
    capacity: usize,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    let m = try_status!(unsafe { model_of::<T>(model) });
    let (sq, sv, sa, i) = m.state();
    for (dst, src) in [(q, sq), (v, sv), (a, sa)] {
        if dst.is_null() {
            continue;
        }
        if capacity < src.len() {
            return AbsorberStatus::BufferTooSmall;
        }
        // SAFETY: `dst` is valid for `capacity` ≥ `src.len()` writes by the caller's guarantee
        // and does not overlap the model.
        unsafe { core::ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len()) };
    }
    if !info.is_null() {
        // SAFETY: non-null, valid for a write.
        unsafe { info.write(i) };
    }
    AbsorberStatus::Ok
}

twins! {
    /// The full dynamic state of a `float` model: `info` gets D, time, steps, last input and
    /// contact; `q`, `v`, `a` (each NULL or an array of `capacity` ≥ D floats, e.g.
    /// `ABSORBER_MAX_DOFS`) get the coordinates (displacements from the straight reference \[m, -\],
    /// then the ball's spin angle \[rad\]), their velocities and accelerations relative to the base.
    ///
    /// # Safety
    /// `model` is a live handle of [`absorber_init`]; `info` NULL or valid for a write; `q`, `v`,
    /// `a` NULL or valid for `capacity` writes each.
    fn absorber_state_f32 / absorber_state_f64 (double model) (
        model: *const AbsorberModel,
        info: *mut AbsorberStateInfoF32 => *mut AbsorberStateInfoF64,
        q: *mut f32 => *mut f64,
        v: *mut f32 => *mut f64,
        a: *mut f32 => *mut f64,
        capacity: usize,
    ) {
        // SAFETY: forwarded.
        unsafe { state(model, info, q, v, a, capacity) }
    }
}
