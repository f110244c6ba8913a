//! The layout of a model or monitor in caller storage (magic, variant, scalar) and the
//! dispatch from an opaque handle to the typed model behind it.

use super::*;

pub(crate) const MODEL_MAGIC: u32 = 0x4142_534d; // "ABSM"
pub(crate) const MONITOR_MAGIC: u32 = 0x4142_534e; // "ABSN"

/// What lives in the caller's storage: a tag, then the value. `repr(C)`: the tag is at offset 0
/// for every `M`, so it can be read before the type is known.
#[repr(C)]
pub(crate) struct Slot<M> {
    pub(crate) magic: u32,
    pub(crate) tag: u32,
    pub(crate) value: M,
}

/// The header every slot starts with.
#[repr(C)]
pub(crate) struct Head {
    magic: u32,
    tag: u32,
}

/// A model of scalar `T`, its type erased (one indirect call per API call).
pub(crate) trait Erased<T: Real> {
    fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error>;
    fn restart(&mut self, base_accel: T) -> Result<(), Error>;
    fn outputs(&self) -> AbsorberOutputs<T>;
    fn energies(&self, base_velocity: T, base_displacement: T) -> AbsorberEnergies<T>;
    fn state(&self) -> (&[T], &[T], &[T], AbsorberStateInfo<T>);
    fn root_stress(&self) -> Result<T, Error>;
    /// Builds the monitor of this model in `slot` (in place: no monitor on the stack).
    fn new_monitor_in<'a>(
        &self,
        slot: &'a mut MaybeUninit<Monitor<T>>,
        config: MonitorConfig<T>,
    ) -> Result<&'a mut Monitor<T>, Error>;
    fn record(
        &self,
        monitor: &mut Monitor<T>,
        report: &StepReport<T>,
        base_accel: T,
    ) -> Result<T, Error>;
    fn params(&self) -> &Params<T>;
}

pub(crate) fn contact_code(c: Contact) -> i32 {
    match c {
        Contact::Off => 0,
        Contact::OnStop(Side::Positive) => 1,
        Contact::OnStop(Side::Negative) => -1,
        Contact::InFlight => 2,
        Contact::Beyond => 3,
    }
}

/// Number of unknowns of a model type.
pub(crate) trait Dofs {
    const DOFS: usize;
}
impl<T: Real, S: Scene, const N: usize, const D: usize> Dofs for Model<T, S, N, D> {
    const DOFS: usize = D;
}

impl<T: Real, S: Scene, const N: usize, const D: usize> Erased<T> for Model<T, S, N, D> {
    #[inline]
    fn step(&mut self, base_accel: T) -> Result<StepReport<T>, Error> {
        Model::step(self, base_accel)
    }

    fn restart(&mut self, base_accel: T) -> Result<(), Error> {
        Model::restart(self, base_accel)
    }

    fn outputs(&self) -> AbsorberOutputs<T> {
        let z = T::zero();
        let s = self.state();
        let (tip_angle, tip_rate) = self.tip_angle();
        let ball = self.ball_angle();
        let rel = self.ball_relative_angle();
        AbsorberOutputs {
            time: self.time(),
            tip_deflection: self.tip_deflection(),
            tip_velocity: self.tip_velocity(),
            static_tip_deflection: self.static_tip_deflection(),
            tip_angle,
            tip_rate,
            ball_angle: ball.map_or(z, |b| b.0),
            ball_rate: ball.map_or(z, |b| b.1),
            ball_relative_angle: rel.map_or(z, |b| b.0),
            ball_relative_rate: rel.map_or(z, |b| b.1),
            has_ball: u8::from(ball.is_some()),
            contact: contact_code(s.contact),
            steps: s.steps,
        }
    }

    fn energies(&self, base_velocity: T, base_displacement: T) -> AbsorberEnergies<T> {
        let e = Model::energies(self, base_velocity, base_displacement);
        AbsorberEnergies {
            beam_strain: e.beam_strain,
            beam_kinetic: e.beam_kinetic,
            beam_potential: e.beam_potential,
            tip_kinetic: e.tip_kinetic,
            tip_potential: e.tip_potential,
            ball_kinetic: e.ball_kinetic,
            ball_potential: e.ball_potential,
            total: e.total(),
        }
    }

    fn state(&self) -> (&[T], &[T], &[T], AbsorberStateInfo<T>) {
        let s = Model::state(self);
        (s.q.as_slice(), s.v.as_slice(), s.a.as_slice(), {
            let (ball_centre, ball_velocity) = self
                .ball_centre()
                .unwrap_or(([T::zero(); 2], [T::zero(); 2]));
            AbsorberStateInfo {
                dofs: D as u32,
                contact: contact_code(s.contact),
                steps: s.steps,
                time: s.time,
                base_accel: s.base_accel,
                ball_centre,
                ball_velocity,
            }
        })
    }

    fn root_stress(&self) -> Result<T, Error> {
        let section = RootSection::rectangle(&self.params().beam)?;
        Ok(section.stress_of_moment(section.root_moment(self, MomentEstimate::Reaction)))
    }

    fn new_monitor_in<'a>(
        &self,
        slot: &'a mut MaybeUninit<Monitor<T>>,
        config: MonitorConfig<T>,
    ) -> Result<&'a mut Monitor<T>, Error> {
        Monitor::new_in(slot, config, self)
    }

    fn record(
        &self,
        monitor: &mut Monitor<T>,
        report: &StepReport<T>,
        base_accel: T,
    ) -> Result<T, Error> {
        monitor.record(self, report, base_accel)
    }

    fn params(&self) -> &Params<T> {
        Model::params(self)
    }
}

/// The scalar of a function family (`f32` or `f64`) and its variants.
pub(crate) trait Scalar: Real {
    /// Tag of a monitor of this scalar.
    const MONITOR_TAG: u32;
    /// The model behind `slot` if its variant has this scalar (and is compiled in).
    ///
    /// # Safety
    /// `slot` points to a live `Slot` made by [`absorber_init`] with variant `tag`.
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<Self>>;
}

/// `&mut slot.value` of a slot of type `Slot<M>`.
///
/// # Safety
/// `slot` points to a live `Slot<M>`.
pub(crate) unsafe fn value<'a, M>(slot: *mut Head) -> &'a mut M {
    // SAFETY: the caller guarantees a live `Slot<M>`, which starts with a `Head`.
    unsafe { &mut (*slot.cast::<Slot<M>>()).value }
}

impl Scalar for f32 {
    const MONITOR_TAG: u32 = 32;
    #[inline]
    #[allow(unused_unsafe, unused_variables)] // when no variant of this scalar is compiled in
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<f32>> {
        // SAFETY (every arm): the tag was written together with a value of that variant.
        unsafe {
            match tag {
                #[cfg(feature = "free-n3-f32")]
                ABSORBER_VARIANT_FREE_N3_F32 => Some(value::<FreeN3F32>(slot)),
                #[cfg(feature = "locked-n3-f32")]
                ABSORBER_VARIANT_LOCKED_N3_F32 => Some(value::<LockedN3F32>(slot)),
                #[cfg(feature = "beam-n3-f32")]
                ABSORBER_VARIANT_BEAM_N3_F32 => Some(value::<BeamN3F32>(slot)),
                #[cfg(feature = "free-n6-f32")]
                ABSORBER_VARIANT_FREE_N6_F32 => Some(value::<FreeN6F32>(slot)),
                _ => None,
            }
        }
    }
}

impl Scalar for f64 {
    const MONITOR_TAG: u32 = 64;
    #[inline]
    #[allow(unused_unsafe, unused_variables)] // when no variant of this scalar is compiled in
    unsafe fn erased<'a>(slot: *mut Head, tag: u32) -> Option<&'a mut dyn Erased<f64>> {
        // SAFETY: as for f32.
        unsafe {
            match tag {
                #[cfg(feature = "free-n3-f64")]
                ABSORBER_VARIANT_FREE_N3_F64 => Some(value::<FreeN3F64>(slot)),
                _ => None,
            }
        }
    }
}

/// Checks a model handle and returns the model behind it.
///
/// # Safety
/// `model` is NULL or a handle returned by [`absorber_init`] whose storage is still live and
/// not used by another call at the same time.
#[inline]
pub(crate) unsafe fn model_of<'a, T: Scalar>(
    model: *const AbsorberModel,
) -> Result<&'a mut dyn Erased<T>, AbsorberStatus> {
    let head = model.cast::<Head>().cast_mut();
    if head.is_null() {
        return Err(AbsorberStatus::NullPointer);
    }
    if head.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: non-null and aligned; the caller guarantees it points to live storage.
    let (magic, tag) = unsafe { ((*head).magic, (*head).tag) };
    if magic != MODEL_MAGIC {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: the magic says `absorber_init` wrote a slot with this tag.
    match unsafe { T::erased(head, tag) } {
        Some(m) => Ok(m),
        None if variant_is_known(tag) => Err(AbsorberStatus::Precision),
        None => Err(AbsorberStatus::NotInitialized),
    }
}

pub(crate) fn variant_is_known(tag: u32) -> bool {
    (ABSORBER_VARIANT_FREE_N3_F32..=ABSORBER_VARIANT_FREE_N3_F64).contains(&tag)
}

/// Checks a monitor handle and returns the monitor behind it.
///
/// # Safety
/// As [`model_of`], for a handle of [`absorber_monitor_init`].
pub(crate) unsafe fn monitor_of<'a, T: Scalar>(
    monitor: *const AbsorberMonitor,
) -> Result<&'a mut Monitor<T>, AbsorberStatus> {
    let head = monitor.cast::<Head>().cast_mut();
    if head.is_null() {
        return Err(AbsorberStatus::NullPointer);
    }
    if head.cast::<u8>().align_offset(ABSORBER_MODEL_ALIGN) != 0 {
        return Err(AbsorberStatus::NotInitialized);
    }
    // SAFETY: non-null, aligned, live by the caller's guarantee.
    let (magic, tag) = unsafe { ((*head).magic, (*head).tag) };
    if magic != MONITOR_MAGIC {
        return Err(AbsorberStatus::NotInitialized);
    }
    if tag != T::MONITOR_TAG {
        return Err(AbsorberStatus::Precision);
    }
    // SAFETY: the magic and tag say a `Slot<Monitor<T>>` lives there.
    Ok(unsafe { value::<Monitor<T>>(head) })
}

pub(crate) fn status_of(e: &Error) -> AbsorberStatus {
    match e {
        Error::InvalidParameter { .. } => AbsorberStatus::InvalidParameter,
        Error::NonFiniteInput => AbsorberStatus::NonFiniteInput,
        Error::InputOutOfRange => AbsorberStatus::InputOutOfRange,
        Error::NoConvergence { .. } => AbsorberStatus::NoConvergence,
        Error::NonFiniteState => AbsorberStatus::NonFiniteState,
        Error::Singular => AbsorberStatus::Singular,
        Error::WorkCap => AbsorberStatus::WorkCap,
        _ => AbsorberStatus::Other,
    }
}

/// Copies `s` into `dst` as a NUL-terminated C string (truncated to fit).
pub(crate) fn copy_str(dst: &mut [c_char], s: &str) {
    let n = s.len().min(dst.len().saturating_sub(1));
    for (d, b) in dst.iter_mut().zip(s.as_bytes().iter().take(n)) {
        *d = *b as c_char;
    }
    if let Some(end) = dst.get_mut(n) {
        *end = 0;
    }
}

/// Writes the error details (if `error` is not NULL) and returns the status.
///
/// # Safety
/// `error` is NULL or valid for writes.
pub(crate) unsafe fn fail(
    error: *mut AbsorberError,
    status: AbsorberStatus,
    field: &str,
    reason: &str,
) -> AbsorberStatus {
    // SAFETY: forwarded.
    unsafe { fail_with(error, status, field, reason, None) }
}

/// [`fail`] with the value given for `field` (`None`: not about one numeric field).
///
/// # Safety
/// `error` is NULL or valid for writes.
pub(crate) unsafe fn fail_with(
    error: *mut AbsorberError,
    status: AbsorberStatus,
    field: &str,
    reason: &str,
    value: Option<f64>,
) -> AbsorberStatus {
    if !error.is_null() {
        let mut e = AbsorberError {
            status,
            field: [0; ABSORBER_FIELD_LEN],
            reason: [0; ABSORBER_REASON_LEN],
            value: value.unwrap_or(f64::NAN),
            has_value: u8::from(value.is_some()),
        };
        copy_str(&mut e.field, field);
        copy_str(&mut e.reason, reason);
        // SAFETY: non-null and valid for writes by the caller's guarantee.
        unsafe { error.write(e) };
    }
    status
}

/// Writes the details of a core error; `value_of` gives the value of the field an
/// [`Error::InvalidParameter`] names.
///
/// # Safety
/// `error` is NULL or valid for writes.
pub(crate) unsafe fn fail_core(
    error: *mut AbsorberError,
    e: &Error,
    value_of: impl FnOnce(&str) -> Option<f64>,
) -> AbsorberStatus {
    let (field, reason) = match e {
        Error::InvalidParameter { field, reason } => (*field, *reason),
        Error::NonFiniteInput => ("", "base acceleration is not finite"),
        Error::InputOutOfRange => ("", "base acceleration beyond 1e4 m/s^2"),
        Error::NoConvergence { .. } => ("", "Newton did not converge"),
        Error::NonFiniteState => ("", "state became non-finite"),
        Error::Singular => ("", "singular system matrix"),
        Error::WorkCap => ("", "the step's work cap was reached"),
        _ => ("", "error"),
    };
    let value = if field.is_empty() {
        None
    } else {
        value_of(field)
    };
    // SAFETY: forwarded from the caller.
    unsafe { fail_with(error, status_of(e), field, reason, value) }
}

/// The value the caller gave in `p` for the field named `field`: the `double` as passed (the
/// core's [`Params::value_of`] of the parameters read in `f64`, where `lit` is exact), or the
/// number of an enumeration, flag or size. `None` for a name that is none of `p`'s numbers.
/// Cold and never inlined: its `f64` parameters are on the stack of a failed call only, not in
/// the frame of every `absorber_init` (the boot stack the firmware budgets).
#[cold]
#[inline(never)]
pub(crate) fn param_value(p: &AbsorberParams, field: &str) -> Option<f64> {
    let code = |x: u32| Some(f64::from(x));
    match field {
        "size" => code(p.size),
        "ball.impact_model" => code(p.ball.impact_model),
        "integrator.newton" => code(p.integrator.newton),
        "integrator.accept_after_budget" => code(u32::from(p.integrator.accept_after_budget)),
        "integrator.events" => code(p.integrator.events),
        "flight" => code(p.flight),
        "at_cap" => code(p.at_cap),
        _ => to_params::<f64>(p).ok()?.value_of(field),
    }
}

pub(crate) fn invalid(field: &'static str, reason: &'static str) -> Error {
    Error::InvalidParameter { field, reason }
}

/// The core's parameters from the C struct (each value rounded to nearest into `T`).
pub(crate) fn to_params<T: Real>(p: &AbsorberParams) -> Result<Params<T>, Error> {
    if p.size as usize != size_of::<AbsorberParams>() {
        return Err(invalid(
            "size",
            "is not sizeof(AbsorberParams) of this library: fill the struct with absorber_params_default() and rebuild against this header",
        ));
    }
    let mut q = Params::<T>::default();
    q.beam.length = lit(p.beam.length);
    q.beam.mass = lit(p.beam.mass);
    q.beam.area = lit(p.beam.area);
    q.beam.modulus = lit(p.beam.modulus);
    q.beam.inertia = lit(p.beam.inertia);
    q.tip.mass = lit(p.tip.mass);
    q.tip.inertia = lit(p.tip.inertia);
    q.tip.offset = lit(p.tip.offset);
    let b = &p.ball;
    q.ball.mass = lit(b.mass);
    q.ball.inertia = lit(b.inertia);
    q.ball.radius = lit(b.radius);
    q.ball.track_radius = lit(b.track_radius);
    q.ball.stop_angle = lit(b.stop_angle);
    q.ball.restitution = lit(b.restitution);
    q.ball.stick_speed = lit(b.stick_speed);
    q.ball.initial_angle = lit(b.initial_angle);
    q.ball.impact_model = match b.impact_model {
        ABSORBER_IMPACT_OVER_STEP => ImpactModel::OverStep,
        ABSORBER_IMPACT_INSTANTANEOUS => ImpactModel::Instantaneous,
        _ => {
            return Err(invalid(
                "ball.impact_model",
                "must be ABSORBER_IMPACT_OVER_STEP or ABSORBER_IMPACT_INSTANTANEOUS",
            ))
        }
    };
    let i = &p.integrator;
    q.integrator.gamma = lit(i.gamma);
    q.integrator.beta = lit(i.beta);
    q.integrator.step = lit(i.step);
    q.integrator.tolerance = lit(i.tolerance);
    q.integrator.max_iterations = i.max_iterations;
    q.integrator.newton = match i.newton {
        ABSORBER_NEWTON_PER_STEP => NewtonKind::PerStep,
        ABSORBER_NEWTON_FULL => NewtonKind::Full,
        ABSORBER_NEWTON_MODIFIED => NewtonKind::Modified,
        _ => {
            return Err(invalid(
                "integrator.newton",
                "must be ABSORBER_NEWTON_PER_STEP, _FULL or _MODIFIED",
            ))
        }
    };
    q.integrator.accept_after_budget = match i.accept_after_budget {
        0 => false,
        1 => true,
        _ => return Err(invalid("integrator.accept_after_budget", "must be 0 or 1")),
    };
    q.integrator.events = match i.events {
        ABSORBER_EVENTS_CROSSING => EventLocation::Crossing,
        ABSORBER_EVENTS_STEP_END => EventLocation::StepEnd,
        _ => {
            return Err(invalid(
                "integrator.events",
                "must be ABSORBER_EVENTS_CROSSING or ABSORBER_EVENTS_STEP_END",
            ))
        }
    };
    q.damping.stiffness_proportional = lit(p.damping.stiffness_proportional);
    q.gravity = lit(p.gravity);
    q.integrator.alpha_m = lit(p.alpha_m);
    q.integrator.alpha_f = lit(p.alpha_f);
    q.calibration.bending_stiffness = lit(p.calibration.bending_stiffness);
    q.calibration.axial_stiffness = lit(p.calibration.axial_stiffness);
    q.calibration.mass_lumping = lit(p.calibration.mass_lumping);
    q.ball.flight = match p.flight {
        0 => false,
        1 => true,
        _ => return Err(invalid("flight", "must be 0 or 1")),
    };
    q.ball.landing_restitution = lit(p.landing_restitution);
    q.integrator.max_work = p.max_work;
    q.integrator.at_cap = match p.at_cap {
        ABSORBER_AT_CAP_TAKE => AtCap::Take,
        ABSORBER_AT_CAP_KEEP => AtCap::Keep,
        _ => {
            return Err(invalid(
                "at_cap",
                "must be ABSORBER_AT_CAP_TAKE or ABSORBER_AT_CAP_KEEP",
            ))
        }
    };
    Ok(q)
}

/// Builds a `Model<T, S, N, D>` in `storage`.
///
/// # Safety
/// `storage` is valid for writes of `size` bytes; `out` and `error` as in [`absorber_init`].
pub(crate) unsafe fn build<T: Real, S: Scene, const N: usize, const D: usize>(
    storage: *mut c_void,
    size: usize,
    tag: u32,
    params: &AbsorberParams,
    base_accel: f64,
    out: *mut *mut AbsorberModel,
    error: *mut AbsorberError,
) -> AbsorberStatus {
    if size < size_of::<Slot<Model<T, S, N, D>>>() {
        // SAFETY: forwarded.
        return unsafe {
            fail_with(
                error,
                AbsorberStatus::Storage,
                "storage_size",
                "is smaller than ABSORBER_MODEL_SIZE_<VARIANT>",
                Some(size as f64),
            )
        };
    }
    let p = match to_params::<T>(params) {
        Ok(p) => p,
        // SAFETY: forwarded.
        Err(e) => return unsafe { fail_core(error, &e, |f| param_value(params, f)) },
    };
    let slot = storage.cast::<Slot<Model<T, S, N, D>>>();
    // SAFETY: the storage is large enough (checked) and aligned (checked by the caller); any
    // earlier content is plain data (no destructor to run). The model is built in place in the
    // slot's value (no model on the caller's boot stack); the header is cleared first and
    // written last, so that a failed build leaves no valid handle.
    unsafe {
        core::ptr::addr_of_mut!((*slot).magic).write(0);
        let value =
            &mut *core::ptr::addr_of_mut!((*slot).value).cast::<MaybeUninit<Model<T, S, N, D>>>();
        if let Err(e) = Model::<T, S, N, D>::at_rest_in(value, p, lit(base_accel)) {
            return fail_core(error, &e, |f| param_value(params, f));
        }
        core::ptr::addr_of_mut!((*slot).tag).write(tag);
        core::ptr::addr_of_mut!((*slot).magic).write(MODEL_MAGIC);
        out.write(slot.cast::<AbsorberModel>());
    }
    AbsorberStatus::Ok
}
