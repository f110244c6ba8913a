//! The monitor's functions: configuration, `absorber_monitor_init`, record and read.

use super::*;

/// Fills `config` with the monitor's defaults (`MonitorConfig::paper`: rectangle section,
/// clamp-reaction moment, AASHTO category E′ with the CAFT cutoff, no gate, blocks of 8).
///
/// # Safety
/// `config` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_config_default(
    config: *mut AbsorberMonitorConfig,
) -> AbsorberStatus {
    if config.is_null() {
        return AbsorberStatus::NullPointer;
    }
    let c = AbsorberMonitorConfig {
        size: size_of::<AbsorberMonitorConfig>() as u32,
        detail_category: 7,
        threshold_rule: ABSORBER_THRESHOLD_CUTOFF,
        block: 8,
        gate: 0.0,
        extreme_fibre: 0.0,
    };
    // SAFETY: non-null, valid for a write.
    unsafe { config.write(c) };
    AbsorberStatus::Ok
}

pub(crate) fn monitor_config<T: Real>(
    c: &AbsorberMonitorConfig,
    params: &Params<T>,
) -> Result<MonitorConfig<T>, Error> {
    if c.size as usize != size_of::<AbsorberMonitorConfig>() {
        return Err(invalid(
            "monitor.size",
            "is not sizeof(AbsorberMonitorConfig): fill it with absorber_monitor_config_default()",
        ));
    }
    let mut m = MonitorConfig::paper(params)?;
    let category = DetailCategory::ALL
        .get(c.detail_category as usize)
        .copied()
        .ok_or(invalid("monitor.detail_category", "must be 0 (A) … 7 (E')"))?;
    let rule = match c.threshold_rule {
        ABSORBER_THRESHOLD_CUTOFF => ThresholdRule::Cutoff,
        ABSORBER_THRESHOLD_EXTENDED => ThresholdRule::Extended,
        ABSORBER_THRESHOLD_ALL_ONCE_EXCEEDED => ThresholdRule::AllOnceExceeded,
        _ => {
            return Err(invalid(
                "monitor.threshold_rule",
                "must be an ABSORBER_THRESHOLD_* constant",
            ))
        }
    };
    m.curve = category.curve(rule);
    m.block = match u16::try_from(c.block) {
        Ok(b) if b >= 1 => b,
        _ => return Err(invalid("monitor.block", "must lie in 1 ..= 65535")),
    };
    m.gate = lit(c.gate);
    if c.extreme_fibre != 0.0 {
        m.section = RootSection::new(&params.beam, lit(c.extreme_fibre))?;
    }
    Ok(m)
}

/// The value given for the field named `field` of a monitor's configuration `c` (`None` for
/// the model's `beam.*`, which its own construction already checked).
#[cold]
#[inline(never)]
fn monitor_value(c: &AbsorberMonitorConfig, field: &str) -> Option<f64> {
    let code = |x: u32| Some(f64::from(x));
    match field {
        "monitor.size" => code(c.size),
        "monitor.detail_category" => code(c.detail_category),
        "monitor.threshold_rule" => code(c.threshold_rule),
        "monitor.block" => code(c.block),
        "monitor.gate" => Some(c.gate),
        "monitor.extreme_fibre" => Some(c.extreme_fibre),
        _ => None,
    }
}

/// Builds a monitor.
///
/// # Safety
/// As [`absorber_monitor_init`].
pub(crate) unsafe fn monitor_init<T: Scalar>(
    storage: *mut c_void,
    storage_size: usize,
    model: &dyn Erased<T>,
    config: &AbsorberMonitorConfig,
    out: *mut *mut AbsorberMonitor,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all calls): pointers forwarded from the caller.
    unsafe {
        if storage_size < size_of::<Slot<Monitor<T>>>() {
            return fail_with(
                error,
                AbsorberStatus::Storage,
                "storage_size",
                "is smaller than ABSORBER_MONITOR_SIZE_F32/_F64",
                Some(storage_size as f64),
            );
        }
        let slot = storage.cast::<Slot<Monitor<T>>>();
        // The monitor is built in place in the slot's value (its window alone is kilobytes: a
        // C caller's boot stack does not carry a copy); the header is cleared first and
        // written last, so that a failed build leaves no valid handle.
        core::ptr::addr_of_mut!((*slot).magic).write(0);
        let value = &mut *core::ptr::addr_of_mut!((*slot).value).cast::<MaybeUninit<Monitor<T>>>();
        if let Err(e) =
            monitor_config(config, model.params()).and_then(|c| model.new_monitor_in(value, c))
        {
            return fail_core(error, &e, |f| monitor_value(config, f));
        }
        core::ptr::addr_of_mut!((*slot).tag).write(T::MONITOR_TAG);
        core::ptr::addr_of_mut!((*slot).magic).write(MONITOR_MAGIC);
        out.write(slot.cast::<AbsorberMonitor>());
    }
    AbsorberStatus::Ok
}

/// Builds the on-device monitor of `model` (root stress, rainflow fatigue, impact log,
/// windowed indicators; `docs/monitoring.md`) in `storage` (`ABSORBER_MONITOR_SIZE_F32` or
/// `_F64` bytes by the model's scalar, aligned to `ABSORBER_MODEL_ALIGN`). The model's current
/// state is the first sample. `config` NULL means the defaults.
///
/// # Safety
/// `storage` valid for writes of `storage_size` bytes and not otherwise used while the monitor
/// is; `model` a live handle of [`absorber_init`]; `config` NULL or valid for reads; `monitor`
/// valid for a write; `error` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn absorber_monitor_init(
    storage: *mut c_void,
    storage_size: usize,
    model: *const AbsorberModel,
    config: *const AbsorberMonitorConfig,
    monitor: *mut *mut AbsorberMonitor,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    // SAFETY (all calls): pointers forwarded from the caller.
    unsafe {
        if storage.is_null() || monitor.is_null() {
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
        let mut c = AbsorberMonitorConfig {
            size: 0,
            detail_category: 0,
            threshold_rule: 0,
            block: 0,
            gate: 0.0,
            extreme_fibre: 0.0,
        };
        if config.is_null() {
            absorber_monitor_config_default(&mut c);
        } else {
            let size = config.cast::<u32>().read();
            if size as usize != size_of::<AbsorberMonitorConfig>() {
                return fail_with(
                    error,
                    AbsorberStatus::InvalidParameter,
                    "monitor.size",
                    "is not sizeof(AbsorberMonitorConfig): fill it with absorber_monitor_config_default()",
                    Some(f64::from(size)),
                );
            }
            c = *config;
        }
        match model_of::<f32>(model) {
            Ok(m) => return monitor_init::<f32>(storage, storage_size, m, &c, monitor, error),
            Err(AbsorberStatus::Precision) => {}
            Err(s) => return fail(error, s, "model", "is not a model built by absorber_init"),
        }
        match model_of::<f64>(model) {
            Ok(m) => monitor_init::<f64>(storage, storage_size, m, &c, monitor, error),
            Err(s) => fail(error, s, "model", "is not a model built by absorber_init"),
        }
    }
}

/// Records.
///
/// # Safety
/// As [`absorber_monitor_record_f32`].
pub(crate) unsafe fn monitor_record<T: Scalar>(
    monitor: *mut AbsorberMonitor,
    model: *const AbsorberModel,
    report: *const AbsorberReport<T>,
    base_accel: T,
    stress: *mut T,
) -> AbsorberStatus {
    if report.is_null() {
        return AbsorberStatus::NullPointer;
    }
    // SAFETY: forwarded.
    let (mon, m, r) = unsafe {
        (
            try_status!(monitor_of::<T>(monitor)),
            try_status!(model_of::<T>(model)),
            &*report,
        )
    };
    let side = if r.impact_side < 0 {
        Side::Negative
    } else {
        Side::Positive
    };
    let rep = StepReport {
        iterations: r.iterations,
        increment: r.increment,
        impact: (r.impact != 0).then_some(Impact {
            time: r.impact_time,
            side,
            relative_speed: r.impact_relative_speed,
            impulse: r.impact_impulse,
            energy_loss: r.impact_energy_loss,
            stuck: r.impact_stuck != 0,
        }),
        separation: (r.separation != 0).then_some(r.separation_time),
        landing: (r.landing != 0).then_some(absorber_core::Landing {
            time: r.landing_time,
            normal_speed: r.landing_normal_speed,
            normal_impulse: r.landing_normal_impulse,
            tangential_impulse: r.landing_tangential_impulse,
            bounced: r.landing == 1,
        }),
        work: u16::try_from(r.work).unwrap_or(u16::MAX),
        outcome: match r.outcome {
            ABSORBER_OUTCOME_CAPPED => Outcome::Capped,
            ABSORBER_OUTCOME_RESTARTED => Outcome::Restarted,
            _ => Outcome::Converged,
        },
        // The C report carries one event of each kind (its flags): counted as such.
        events: absorber_core::EventCounts {
            separations: u8::from(r.separation != 0),
            landings: u8::from(r.landing != 0),
            bounces: u8::from(r.landing == 1),
            impacts: u8::from(r.impact != 0),
        },
    };
    match m.record(mon, &rep, base_accel) {
        Ok(s) => {
            if !stress.is_null() {
                // SAFETY: non-null, valid for a write.
                unsafe { stress.write(s) };
            }
            AbsorberStatus::Ok
        }
        Err(e) => status_of(&e),
    }
}

twins! {
    /// Records `model`'s state after a successful step into the monitor: `report` is what
    /// [`absorber_step_f32`] wrote, `base_accel` its input. `stress` (may be NULL) receives the root
    /// stress \[Pa\]. A non-finite stress is refused (`ABSORBER_STATUS_NON_FINITE_STATE`, counted).
    ///
    /// # Safety
    /// `monitor` a live handle of [`absorber_monitor_init`] made for `model`; `model` a live handle
    /// of [`absorber_init`]; `report` valid for reads; `stress` NULL or valid for a write.
    fn absorber_monitor_record_f32 / absorber_monitor_record_f64 (double model) (
        monitor: *mut AbsorberMonitor,
        model: *const AbsorberModel,
        report: *const AbsorberReportF32 => *const AbsorberReportF64,
        base_accel: f32 => f64,
        stress: *mut f32 => *mut f64,
    ) {
        // SAFETY: forwarded.
        unsafe { monitor_record(monitor, model, report, base_accel, stress) }
    }
}

pub(crate) fn reading<T: Real>(m: &Monitor<T>) -> AbsorberMonitorReading<T> {
    let f = m.fatigue();
    let c = m.fatigue_closed();
    let v = m.indicators();
    let imp = m.impacts();
    AbsorberMonitorReading {
        root_stress: m.root_stress(),
        static_root_stress: m.static_root_stress(),
        root_moment: m.root_moment(),
        damage: f.damage,
        equivalent_range: f.equivalent_range,
        cycles: f.cycles,
        max_range: f.max_range,
        closed_damage: c.damage,
        closed_equivalent_range: c.equivalent_range,
        closed_cycles: c.cycles,
        closed_max_range: c.max_range,
        damage_rate_per_hour: m.damage_rate_per_hour(),
        tip_rms: v.tip_rms,
        tip_peak: v.tip_peak,
        ball_rms: v.ball_rms,
        beam_energy: v.beam_energy,
        ball_energy: v.ball_energy,
        elapsed: m.elapsed(),
        impact_max_relative_speed: imp.max_relative_speed(),
        impact_energy_loss: imp.energy_loss(),
        samples: m.samples(),
        reversals: m.rainflow().reversals(),
        overflows: m.rainflow().overflows(),
        residue_len: m.rainflow().residue_len() as u32,
        rejected: m.rejected(),
        impacts: imp.total(),
        impacts_stuck: imp.stuck(),
        flight_fraction: m.flight_fraction(),
        peak_rolling_friction: m.flight().peak_rolling_friction,
        peak_landing_friction: m.flight().peak_landing_friction,
        separations: m.flight().separations,
        landings: m.flight().landings,
    }
}

twins! {
    /// Everything a `float` monitor has accumulated (fatigue with and without the residue, the
    /// window indicators, impact and sample counts). O(residue + window) work.
    ///
    /// # Safety
    /// `monitor` a live handle of [`absorber_monitor_init`]; `out` valid for a write.
    fn absorber_monitor_read_f32 / absorber_monitor_read_f64 (double monitor) <T> (
        monitor: *const AbsorberMonitor,
        out: *mut AbsorberMonitorReadingF32 => *mut AbsorberMonitorReadingF64,
    ) {
        if out.is_null() {
            return AbsorberStatus::NullPointer;
        }
        // SAFETY: forwarded; `out` non-null and valid for a write.
        unsafe {
            let m = try_status!(monitor_of::<T>(monitor));
            out.write(reading(m));
        }
        AbsorberStatus::Ok
    }
}
