//! The C API against independent references: the Rust firmware's scene driver
//! (`absorber_firmware::run`, the source of `fw-free`'s and `fw-free-monitor`'s state
//! fingerprints) and the core called directly. Every call below goes through the `extern "C"`
//! functions exactly as C code would.

use absorber_core::{FreeBallModel, Params};
use absorber_ffi::*;
use absorber_firmware::{base_accel, Fnv, NoProbe, Setup, Sim, WithMonitor, STEPS, STEP_MS};
use core::ffi::{c_void, CStr};
use core::ptr::{null, null_mut};

#[repr(C, align(8))]
struct Storage<const B: usize>([u8; B]);

fn storage<const B: usize>() -> Box<Storage<B>> {
    Box::new(Storage([0; B]))
}

fn text(s: &[core::ffi::c_char]) -> String {
    let bytes: Vec<u8> = s
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8(bytes).expect("UTF-8")
}

fn defaults() -> AbsorberParams {
    let mut p = core::mem::MaybeUninit::<AbsorberParams>::uninit();
    // SAFETY: valid for a write.
    assert_eq!(
        unsafe { absorber_params_default(p.as_mut_ptr()) },
        AbsorberStatus::Ok
    );
    // SAFETY: written above.
    unsafe { p.assume_init() }
}

/// The firmware's parameters (`absorber_firmware::firmware_params`): the defaults with every
/// event at the step end and the deadline's work cap.
fn firmware() -> AbsorberParams {
    let mut p = defaults();
    p.integrator.events = ABSORBER_EVENTS_STEP_END;
    p.max_work = ABSORBER_WORK_DEADLINE;
    p
}

/// An error struct with every field set to what no failure writes.
fn blank() -> AbsorberError {
    AbsorberError {
        status: AbsorberStatus::Ok,
        field: [1; ABSORBER_FIELD_LEN],
        reason: [1; ABSORBER_REASON_LEN],
        value: 0.5,
        has_value: 7,
    }
}

/// Builds `variant` in `st`; returns the status, the handle and the error.
fn init<const B: usize>(
    st: &mut Storage<B>,
    variant: u32,
    p: &AbsorberParams,
) -> (AbsorberStatus, *mut AbsorberModel, AbsorberError) {
    let mut m = null_mut();
    let mut e = blank();
    // SAFETY: storage of B bytes, aligned to 8; all pointers valid.
    let s = unsafe {
        absorber_init(
            st.0.as_mut_ptr().cast::<c_void>(),
            B,
            variant,
            p,
            0.0,
            &mut m,
            &mut e,
        )
    };
    (s, m, e)
}

/// The firmware driver's fingerprint of a run through the C API: the same words in the same
/// order as `absorber_firmware::run` (report, then state, then the per-second extras).
fn fingerprint(model: *mut AbsorberModel, monitor: Option<*mut AbsorberMonitor>) -> u64 {
    let h = 1e-3 * STEP_MS as f32;
    let mut hash = Fnv::default();
    let (mut errors, mut record_errors) = (0u32, 0u32);
    let (mut q, mut v, mut a) = ([0f32; ABSORBER_MAX_DOFS], [0f32; 25], [0f32; 25]);
    for k in 1..=STEPS {
        let accel = base_accel(k, h, absorber_firmware::FREQUENCY_HZ);
        let mut r = AbsorberReportF32::default();
        // SAFETY: live handle, valid report.
        let s = unsafe { absorber_step_f32(model, accel, &mut r) };
        if s == AbsorberStatus::Ok {
            hash.word(r.iterations);
            hash.word(r.increment.to_bits());
            hash.word(r.work);
            hash.word(r.outcome);
            if r.impact != 0 {
                for w in [
                    r.impact_time,
                    r.impact_relative_speed,
                    r.impact_impulse,
                    r.impact_energy_loss,
                ] {
                    hash.word(w.to_bits());
                }
                hash.word(u32::from(r.impact_stuck));
            }
            if let Some(mon) = monitor {
                // SAFETY: live handles.
                let rs = unsafe { absorber_monitor_record_f32(mon, model, &r, accel, null_mut()) };
                if rs != AbsorberStatus::Ok {
                    record_errors += 1;
                }
            }
        } else {
            errors += 1;
            hash.word(0xdead_0000 | errors);
        }
        let mut info = AbsorberStateInfoF32::default();
        // SAFETY: arrays of 25 floats.
        let s = unsafe {
            absorber_state_f32(
                model,
                &mut info,
                q.as_mut_ptr(),
                v.as_mut_ptr(),
                a.as_mut_ptr(),
                ABSORBER_MAX_DOFS,
            )
        };
        assert_eq!(s, AbsorberStatus::Ok);
        let d = info.dofs as usize;
        for x in q[..d].iter().chain(&v[..d]).chain(&a[..d]) {
            hash.word(x.to_bits());
        }
        hash.word(info.time.to_bits());
        hash.word(info.base_accel.to_bits());
        // The firmware's contact words: 0 on the track, 1 / 2 on the positive / negative stop,
        // 3 in flight followed by the ball's centre and velocity, 4 beyond the stops.
        hash.word(match info.contact {
            0 => 0,
            1 => 1,
            2 => 3,
            3 => 4,
            _ => 2,
        });
        if info.contact == 2 {
            for x in info.ball_centre.iter().chain(info.ball_velocity.iter()) {
                hash.word(x.to_bits());
            }
        }
        let second = (k * STEP_MS) / 1000 != ((k - 1) * STEP_MS) / 1000;
        if let Some(mon) = monitor {
            let mut m = AbsorberMonitorReadingF32::default();
            // SAFETY: live handle.
            assert_eq!(
                unsafe { absorber_monitor_read_f32(mon, &mut m) },
                AbsorberStatus::Ok
            );
            for x in [
                m.root_stress,
                m.closed_damage,
                m.closed_cycles,
                m.closed_max_range,
            ] {
                hash.word(x.to_bits());
            }
            hash.word(m.reversals as u32);
            hash.word((m.reversals >> 32) as u32);
            hash.word(m.residue_len);
            hash.word((m.overflows ^ (m.overflows >> 32)) as u32);
            hash.word(m.samples as u32);
            hash.word(m.rejected);
            hash.word(m.impacts);
            hash.word(record_errors);
            if second {
                for x in [
                    m.root_stress,
                    m.damage,
                    m.equivalent_range,
                    m.cycles,
                    m.max_range,
                    m.tip_rms,
                    m.tip_peak,
                    m.ball_rms,
                    m.beam_energy,
                    m.ball_energy,
                ] {
                    hash.word(x.to_bits());
                }
            }
        }
    }
    hash.0
}

/// The Rust firmware's fingerprint of scene `M` (what `fw-*` prints as `state_hash`).
fn firmware_hash<M: Sim>() -> u64 {
    let mut m = M::init().expect("the scene starts");
    let mut out = String::new();
    absorber_firmware::run(&mut m, &Setup::default(), &mut out, &mut NoProbe).hash
}

#[test]
fn free_ball_through_the_c_api_reproduces_the_fw_free_fingerprint_bit_for_bit() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let reference = firmware_hash::<FreeBallModel<f32, 3, 13>>();
    assert_eq!(fingerprint(m, None), reference);
}

#[test]
fn locked_and_beam_variants_reproduce_their_firmware_fingerprints() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_LOCKED_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_LOCKED_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let reference = firmware_hash::<absorber_core::LockedBallModel<f32, 3, 12>>();
    assert_eq!(fingerprint(m, None), reference);
    let mut st = storage::<ABSORBER_MODEL_SIZE_BEAM_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_BEAM_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let reference = firmware_hash::<absorber_core::BeamModel<f32, 3, 12>>();
    assert_eq!(fingerprint(m, None), reference);
}

#[test]
fn monitor_through_the_c_api_reproduces_the_fw_free_monitor_fingerprint() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let mut ms = storage::<ABSORBER_MONITOR_SIZE_F32>();
    let mut mon = null_mut();
    // SAFETY: storage of the documented size; NULL config = defaults; NULL error allowed.
    let s = unsafe {
        absorber_monitor_init(
            ms.0.as_mut_ptr().cast(),
            ABSORBER_MONITOR_SIZE_F32,
            m,
            null(),
            &mut mon,
            null_mut(),
        )
    };
    assert_eq!(s, AbsorberStatus::Ok);
    let reference = firmware_hash::<WithMonitor<FreeBallModel<f32, 3, 13>>>();
    assert_eq!(fingerprint(m, Some(mon)), reference);
}

#[test]
fn f64_variant_matches_the_core_called_directly() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F64>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F64, &defaults());
    assert_eq!(s, AbsorberStatus::Ok);
    let mut direct: FreeBallModel<f64, 3, 13> =
        FreeBallModel::at_rest(Params::default(), 0.0).expect("starts");
    let w = 2.0 * std::f64::consts::PI * 4.13;
    for k in 1..=2000 {
        let accel = -0.5e-3 * w * w * (w * k as f64 * 0.003).sin();
        let mut r = AbsorberReportF64::default();
        // SAFETY: live handle.
        assert_eq!(
            unsafe { absorber_step_f64(m, accel, &mut r) },
            AbsorberStatus::Ok
        );
        let d = direct.step(accel).expect("steps");
        assert_eq!(r.iterations, d.iterations);
        assert_eq!(r.impact != 0, d.impact.is_some());
    }
    let mut o = AbsorberOutputsF64::default();
    let mut e = AbsorberEnergiesF64::default();
    let mut stress = 0.0;
    // SAFETY: live handle, valid outputs.
    unsafe {
        assert_eq!(absorber_outputs_f64(m, &mut o), AbsorberStatus::Ok);
        assert_eq!(
            absorber_energies_f64(m, 0.0, 0.0, &mut e),
            AbsorberStatus::Ok
        );
        assert_eq!(absorber_root_stress_f64(m, &mut stress), AbsorberStatus::Ok);
    }
    assert_eq!(
        o.tip_deflection.to_bits(),
        direct.tip_deflection().to_bits()
    );
    let (alpha, _) = direct.ball_relative_angle().expect("free ball");
    assert_eq!(o.ball_relative_angle.to_bits(), alpha.to_bits());
    assert_eq!(o.steps, 2000);
    assert_eq!(o.has_ball, 1);
    let de = direct.energies(0.0, 0.0);
    assert_eq!(e.ball_kinetic.to_bits(), de.ball_kinetic.to_bits());
    assert_eq!(e.total.to_bits(), de.total().to_bits());
    // Root stress: the clamp moment of the paper's 0.5 mm run is of the order of MPa.
    assert!(stress.is_finite() && stress.abs() > 1e5 && stress.abs() < 1e9);
}

/// Calibration and generalized-α set through the C struct reach the core: the same run, bit for
/// bit, as the core built directly from the same `Params` (calibrated N = 3 factors of
/// docs/accuracy.md, ρ∞ = 0.8, 0.3 % structural damping at 4.13 Hz).
#[test]
fn calibration_and_generalized_alpha_reach_the_core() {
    let mut p = defaults();
    // SAFETY: valid struct.
    assert_eq!(
        unsafe { absorber_params_generalized_alpha(&mut p, 0.8) },
        AbsorberStatus::Ok
    );
    p.calibration.bending_stiffness = 0.999742391777782;
    p.calibration.axial_stiffness = 0.023104155113940053;
    p.calibration.mass_lumping = 0.020902945207054487;
    p.damping.stiffness_proportional = 2.0 * 0.003 / (2.0 * std::f64::consts::PI * 4.13);
    let mut core = Params::<f64>::default();
    core.integrator = core.integrator.generalized_alpha(0.8);
    core.calibration.bending_stiffness = p.calibration.bending_stiffness;
    core.calibration.axial_stiffness = p.calibration.axial_stiffness;
    core.calibration.mass_lumping = p.calibration.mass_lumping;
    core.damping.stiffness_proportional = p.damping.stiffness_proportional;
    assert!(p.alpha_m != 0.0 && p.alpha_f != 0.0);
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F64>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F64, &p);
    assert_eq!(s, AbsorberStatus::Ok);
    let mut direct: FreeBallModel<f64, 3, 13> = FreeBallModel::at_rest(core, 0.0).expect("starts");
    let w = 2.0 * std::f64::consts::PI * 4.13;
    for k in 1..=1000 {
        let accel = -0.5e-3 * w * w * (w * k as f64 * 0.003).sin();
        let mut r = AbsorberReportF64::default();
        // SAFETY: live handle.
        assert_eq!(
            unsafe { absorber_step_f64(m, accel, &mut r) },
            AbsorberStatus::Ok
        );
        direct.step(accel).expect("steps");
    }
    let mut o = AbsorberOutputsF64::default();
    // SAFETY: live handle, valid output.
    assert_eq!(
        unsafe { absorber_outputs_f64(m, &mut o) },
        AbsorberStatus::Ok
    );
    assert_eq!(
        o.tip_deflection.to_bits(),
        direct.tip_deflection().to_bits()
    );
    // And a bad calibration factor is named.
    let mut q = defaults();
    q.calibration.axial_stiffness = 2.0;
    let (s, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F64, &q);
    assert_eq!(s, AbsorberStatus::InvalidParameter);
    assert_eq!(text(&e.field), "calibration.axial_stiffness");
}

/// The value an error reports: `(has_value, value)` with the value's bits (NaN compares).
fn value(e: &AbsorberError) -> (u8, u64) {
    (e.has_value, e.value.to_bits())
}

#[test]
fn a_bad_parameter_is_refused_with_the_name_of_its_field_and_its_value() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let mut p = defaults();
    p.beam.modulus = -200e9;
    let (s, m, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(s, AbsorberStatus::InvalidParameter);
    assert!(m.is_null());
    assert_eq!(e.status, AbsorberStatus::InvalidParameter);
    assert_eq!(text(&e.field), "beam.modulus");
    assert_eq!(text(&e.reason), "must be positive");
    assert_eq!(value(&e), (1, (-200e9f64).to_bits()));
    let mut p = defaults();
    p.integrator.step = f64::NAN;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "integrator.step");
    assert_eq!(value(&e), (1, f64::NAN.to_bits()));
    // The value as given, not as the `float` variant rounds it (1e-7 is no f32).
    let mut p = defaults();
    p.integrator.tolerance = 1e-7;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "integrator.tolerance");
    assert_eq!(value(&e), (1, 1e-7f64.to_bits()));
    // A rule between two fields: the named field's value.
    let mut p = defaults();
    p.ball.track_radius = 0.5 * p.ball.radius;
    let mut sd = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F64>();
    let (_, _, e) = init(&mut sd, ABSORBER_VARIANT_FREE_N3_F64, &p);
    assert_eq!(text(&e.field), "ball.track_radius");
    assert_eq!(value(&e), (1, p.ball.track_radius.to_bits()));
    let mut p = defaults();
    p.ball.impact_model = 7;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "ball.impact_model");
    assert_eq!(value(&e), (1, 7.0f64.to_bits()));
    let mut p = defaults();
    p.integrator.events = 2;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "integrator.events");
    assert_eq!(value(&e), (1, 2.0f64.to_bits()));
    let mut p = defaults();
    p.max_work = 10;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "integrator.max_work");
    assert_eq!(value(&e), (1, 10.0f64.to_bits()));
    let mut p = defaults();
    p.at_cap = 2;
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "at_cap");
    assert_eq!(value(&e), (1, 2.0f64.to_bits()));
    // The beam-only scene does not validate the ball (as the core).
    let mut p = defaults();
    p.ball.mass = -1.0;
    let mut sb = storage::<ABSORBER_MODEL_SIZE_BEAM_N3_F32>();
    assert_eq!(
        init(&mut sb, ABSORBER_VARIANT_BEAM_N3_F32, &p).0,
        AbsorberStatus::Ok
    );
    let (_, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(text(&e.field), "ball.mass");
}

/// The work cap through the C API: under noise over the whole input range every step's report
/// stays within `max_work`, flags its outcome, and a capped step with `ABSORBER_AT_CAP_KEEP`
/// returns `ABSORBER_STATUS_WORK_CAP` with the state as it was.
#[test]
fn the_work_cap_and_its_outcomes_reach_the_c_api() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let mut seed = 0x1234_5678u32;
    let mut outcomes = [0u32; 3];
    for _ in 0..500 {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        let a = ((seed >> 8) as f32 / 8_388_608.0 - 1.0) * 1.0e4;
        let mut r = AbsorberReportF32::default();
        // SAFETY: live handle, valid report.
        if unsafe { absorber_step_f32(m, a, &mut r) } == AbsorberStatus::Ok {
            assert!(r.work <= ABSORBER_WORK_DEADLINE, "{}", r.work);
            outcomes[r.outcome as usize] += 1;
        }
    }
    assert!(outcomes[1] > 0 && outcomes[2] > 0, "{outcomes:?}");
    let mut p = firmware();
    p.at_cap = ABSORBER_AT_CAP_KEEP;
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (_, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    let mut r = AbsorberReportF32::default();
    // SAFETY: live handle, valid report.
    let s = unsafe { absorber_step_f32(m, 5000.0, &mut r) };
    assert_eq!(s, AbsorberStatus::WorkCap);
}

#[test]
fn a_struct_of_another_size_storage_too_small_and_unknown_variants_are_refused() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let mut p = defaults();
    p.size -= 8;
    let (s, _, e) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &p);
    assert_eq!(s, AbsorberStatus::InvalidParameter);
    assert_eq!(text(&e.field), "size");
    assert_eq!(value(&e), (1, f64::from(p.size).to_bits()));
    let mut small = storage::<1024>();
    let (s, _, e) = init(&mut small, ABSORBER_VARIANT_FREE_N3_F32, &defaults());
    assert_eq!(s, AbsorberStatus::Storage);
    assert_eq!(text(&e.field), "storage_size");
    assert_eq!(value(&e), (1, 1024.0f64.to_bits()));
    let (s, _, e) = init(&mut st, 99, &defaults());
    assert_eq!(s, AbsorberStatus::Variant);
    assert_eq!(text(&e.field), "variant");
    assert_eq!(value(&e), (1, 99.0f64.to_bits()));
    // Misaligned storage.
    let mut big = storage::<{ ABSORBER_MODEL_SIZE_FREE_N3_F32 + 8 }>();
    let mut m = null_mut();
    // SAFETY: one byte in, still inside the allocation.
    let s = unsafe {
        absorber_init(
            big.0.as_mut_ptr().add(1).cast(),
            ABSORBER_MODEL_SIZE_FREE_N3_F32,
            ABSORBER_VARIANT_FREE_N3_F32,
            &defaults(),
            0.0,
            &mut m,
            null_mut(),
        )
    };
    assert_eq!(s, AbsorberStatus::Storage);
    // Every variant fits its documented storage in this build.
    for (v, size) in [
        (
            ABSORBER_VARIANT_FREE_N3_F32,
            ABSORBER_MODEL_SIZE_FREE_N3_F32,
        ),
        (
            ABSORBER_VARIANT_LOCKED_N3_F32,
            ABSORBER_MODEL_SIZE_LOCKED_N3_F32,
        ),
        (
            ABSORBER_VARIANT_BEAM_N3_F32,
            ABSORBER_MODEL_SIZE_BEAM_N3_F32,
        ),
        (
            ABSORBER_VARIANT_FREE_N6_F32,
            ABSORBER_MODEL_SIZE_FREE_N6_F32,
        ),
        (
            ABSORBER_VARIANT_FREE_N3_F64,
            ABSORBER_MODEL_SIZE_FREE_N3_F64,
        ),
    ] {
        let n = absorber_model_size(v);
        assert!(n > 1000 && n <= size, "variant {v}: {n} > {size}");
    }
    assert_eq!(absorber_model_size(0), 0);
}

#[test]
fn wrong_handles_and_inputs_are_errors_and_keep_the_state() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (_, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &defaults());
    let mut r = AbsorberReportF64::default();
    // SAFETY: all handles are live or NULL, or point to zeroed storage.
    unsafe {
        assert_eq!(absorber_step_f64(m, 0.0, &mut r), AbsorberStatus::Precision);
        assert_eq!(
            absorber_step_f32(null_mut(), 0.0, null_mut()),
            AbsorberStatus::NullPointer
        );
        let mut zero = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
        assert_eq!(
            absorber_step_f32(zero.0.as_mut_ptr().cast(), 0.0, null_mut()),
            AbsorberStatus::NotInitialized
        );
        assert_eq!(absorber_step_f32(m, 1.0, null_mut()), AbsorberStatus::Ok);
        let mut before = AbsorberOutputsF32::default();
        absorber_outputs_f32(m, &mut before);
        assert_eq!(
            absorber_step_f32(m, f32::NAN, null_mut()),
            AbsorberStatus::NonFiniteInput
        );
        assert_eq!(
            absorber_step_f32(m, 1e6, null_mut()),
            AbsorberStatus::InputOutOfRange
        );
        let mut after = AbsorberOutputsF32::default();
        absorber_outputs_f32(m, &mut after);
        assert_eq!(before, after);
        assert_eq!(after.steps, 1);
        let mut q = [0f32; 4];
        assert_eq!(
            absorber_state_f32(m, null_mut(), q.as_mut_ptr(), null_mut(), null_mut(), 4),
            AbsorberStatus::BufferTooSmall
        );
        let name = CStr::from_ptr(absorber_status_name(AbsorberStatus::Precision as i32));
        assert_eq!(name.to_str(), Ok("wrong precision"));
    }
}

/// Every function is total over what C can pass: a status value that is none (C allows any
/// int in an enum; before, `absorber_status_name(999)` read a jump table out of bounds and
/// crashed) and non-finite numbers (before, `absorber_energies_f32(m, NAN, NAN, &o)` returned
/// OK with 7 of 8 outputs NaN).
#[test]
fn out_of_range_statuses_and_non_finite_numbers_are_defined() {
    for raw in [-1, 15, 999, i32::MIN, i32::MAX] {
        // SAFETY: the function returns a static NUL-terminated string for any value.
        let name = unsafe { CStr::from_ptr(absorber_status_name(raw)) };
        assert_eq!(name.to_str(), Ok("unknown status"), "{raw}");
    }
    for raw in 0..15 {
        // SAFETY: as above.
        let name = unsafe { CStr::from_ptr(absorber_status_name(raw)) };
        assert_ne!(name.to_str(), Ok("unknown status"), "{raw}");
    }
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (_, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &defaults());
    let mut e = AbsorberEnergiesF32::default();
    // SAFETY: live handle, valid output.
    unsafe {
        assert_eq!(
            absorber_energies_f32(m, 0.0, 0.0, &mut e),
            AbsorberStatus::Ok
        );
        let good = e;
        for (v, d) in [(f32::NAN, 0.0), (0.0, f32::INFINITY), (f32::NAN, f32::NAN)] {
            assert_eq!(
                absorber_energies_f32(m, v, d, &mut e),
                AbsorberStatus::NonFiniteInput
            );
            assert_eq!(e, good, "nothing written");
        }
    }
}

/// A monitor's bad configuration is reported with its value too; an error about no one
/// number has none.
#[test]
fn monitor_errors_carry_the_value_and_other_errors_none() {
    let mut st = storage::<ABSORBER_MODEL_SIZE_FREE_N3_F32>();
    let (s, m, _) = init(&mut st, ABSORBER_VARIANT_FREE_N3_F32, &firmware());
    assert_eq!(s, AbsorberStatus::Ok);
    let mut ms = storage::<ABSORBER_MONITOR_SIZE_F32>();
    let monitor = |c: &AbsorberMonitorConfig, ms: &mut Storage<ABSORBER_MONITOR_SIZE_F32>| {
        let (mut mon, mut e) = (null_mut(), blank());
        // SAFETY: storage of the documented size, live model, valid config and outputs.
        let s = unsafe {
            absorber_monitor_init(
                ms.0.as_mut_ptr().cast(),
                ABSORBER_MONITOR_SIZE_F32,
                m,
                c,
                &mut mon,
                &mut e,
            )
        };
        (s, e)
    };
    let mut c = core::mem::MaybeUninit::<AbsorberMonitorConfig>::uninit();
    // SAFETY: valid for a write, then written.
    let c = unsafe {
        absorber_monitor_config_default(c.as_mut_ptr());
        c.assume_init()
    };
    let (s, e) = monitor(&AbsorberMonitorConfig { block: 0, ..c }, &mut ms);
    assert_eq!(s, AbsorberStatus::InvalidParameter);
    assert_eq!(text(&e.field), "monitor.block");
    assert_eq!(value(&e), (1, 0.0f64.to_bits()));
    let (_, e) = monitor(&AbsorberMonitorConfig { gate: -0.25, ..c }, &mut ms);
    assert_eq!(text(&e.field), "monitor.gate");
    assert_eq!(value(&e), (1, (-0.25f64).to_bits()));
    let (s, e) = monitor(&c, &mut ms);
    assert_eq!(s, AbsorberStatus::Ok, "{}", text(&e.field));
    // NULL storage: no field, no value.
    let mut e = blank();
    let mut h = null_mut();
    // SAFETY: NULL storage is refused before anything is read.
    let s = unsafe {
        absorber_init(
            core::ptr::null_mut(),
            0,
            ABSORBER_VARIANT_FREE_N3_F32,
            &defaults(),
            0.0,
            &mut h,
            &mut e,
        )
    };
    assert_eq!(s, AbsorberStatus::NullPointer);
    assert_eq!(text(&e.field), "");
    assert_eq!(e.has_value, 0);
    assert!(e.value.is_nan());
}
