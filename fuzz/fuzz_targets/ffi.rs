//! Arbitrary bytes → the C API with arbitrary arguments: every field of `AbsorberParams`
//! (NaN, infinities, out-of-range enums and flags included; half the inputs perturb the
//! defaults, half take raw bytes), a variant (unknown ones too), a monitor configuration, then
//! a sequence of calls (bursts of steps, restart, outputs, energies, root stress, state with any
//! capacity, monitor record/read with an arbitrary report, status names of any integer).
//! Half the inputs run under the firmware's work cap (`ABSORBER_WORK_DEADLINE`, as the
//! firmware does: every step's work bounded); these step the model in bursts of up to 2,041
//! steps of a sine plus a random walk of base acceleration, up to `MAX_STEPS_CAPPED` an input,
//! so that a run puts 10⁷ model steps through `absorber_step_*`. The others (any cap, up to the
//! 50,000-unit "unlimited" one, ~ms a violent step) take at most `MAX_STEPS` steps.
//! Checks: no panic (the library is `panic = abort` in C; here a panic fails the run), every
//! status is one of the header's, an `OK` from `absorber_init` gives a handle, a failed step
//! leaves the state bit for bit, an accepted step's state is finite, energies of a non-finite
//! base are refused. Inputs, API calls and model steps are printed every 10⁶ model steps and
//! when the process exits.
#![no_main]
use absorber_ffi::*;
use libfuzzer_sys::fuzz_target;
use std::ffi::CStr;

struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let (&b, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        b
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn f64(&mut self) -> f64 {
        let mut b = [0u8; 8];
        b.iter_mut().for_each(|x| *x = self.u8());
        f64::from_le_bytes(b)
    }
    /// A value for a parameter of default `d`: kept, scaled, special or raw.
    fn param(&mut self, d: f64) -> f64 {
        match self.u8() % 8 {
            0..=2 => d,
            3 => d * (self.u8() as f64 / 64.0),
            4 => d * 10f64.powi(self.u8() as i32 % 40 - 20),
            5 => [
                f64::NAN,
                f64::INFINITY,
                -f64::INFINITY,
                0.0,
                -d,
                f64::MIN_POSITIVE,
            ][self.u8() as usize % 6],
            _ => self.f64(),
        }
    }
    fn enumeration(&mut self, d: u32) -> u32 {
        match self.u8() % 4 {
            0 | 1 => d,
            2 => self.u8() as u32 % 4,
            _ => self.u32(),
        }
    }
    fn empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A C API call's status checked (and the call counted).
fn status_ok(s: AbsorberStatus) -> AbsorberStatus {
    CALLS.fetch_add(1, Relaxed);
    let raw = s as i32;
    assert!((0..=14).contains(&raw), "status {raw}");
    // SAFETY: a static NUL-terminated string.
    let name = unsafe { CStr::from_ptr(absorber_status_name(raw)) };
    assert!(!name.to_bytes().is_empty() && name.to_bytes() != b"unknown status");
    s
}

#[repr(C, align(16))]
struct Storage([u8; ABSORBER_MODEL_SIZE_FREE_N6_F32]);
#[repr(C, align(16))]
struct MonitorStorage([u8; ABSORBER_MONITOR_SIZE_F64]);

/// Model steps of an input whose cap the fuzzer chose (any `max_work` up to the 50,000-unit
/// "unlimited" one: a violent step costs milliseconds). Later step calls are skipped.
const MAX_STEPS: u32 = 4;
/// Model steps of an input under the firmware's cap (`ABSORBER_WORK_DEADLINE` work units a step
/// at most, tens of microseconds).
const MAX_STEPS_CAPPED: u32 = 4_000;

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
/// Inputs run, C API calls made and model steps taken (`absorber_step_*` calls) over the run.
static INPUTS: AtomicU64 = AtomicU64::new(0);
static CALLS: AtomicU64 = AtomicU64::new(0);
static STEPS: AtomicU64 = AtomicU64::new(0);
/// Of the model steps, those the model took (status `OK`; the others were refused, state kept).
static STEPS_OK: AtomicU64 = AtomicU64::new(0);

extern "C" fn print_counts() {
    eprintln!(
        "fuzz ffi: {} inputs, {} API calls, {} model steps ({} taken, the others refused)",
        INPUTS.load(Relaxed),
        CALLS.load(Relaxed),
        STEPS.load(Relaxed),
        STEPS_OK.load(Relaxed)
    );
}

extern "C" {
    /// The C library's exit hook (libFuzzer ends a run with `exit`).
    fn atexit(f: extern "C" fn()) -> i32;
}
static AT_EXIT: std::sync::Once = std::sync::Once::new();

/// One model step counted; progress every 10⁶.
fn step_counted() {
    let n = STEPS.fetch_add(1, Relaxed) + 1;
    if n % 1_000_000 == 0 {
        print_counts();
    }
}

fuzz_target!(|bytes: &[u8]| {
    // SAFETY: registers a plain function with the C library, once.
    AT_EXIT.call_once(|| unsafe {
        atexit(print_counts);
    });
    INPUTS.fetch_add(1, Relaxed);
    let mut b = Bytes(bytes);
    let mut p = std::mem::MaybeUninit::<AbsorberParams>::uninit();
    // SAFETY: valid for a write.
    CALLS.fetch_add(1, Relaxed);
    assert_eq!(
        unsafe { absorber_params_default(p.as_mut_ptr()) },
        AbsorberStatus::Ok
    );
    // SAFETY: written just above.
    let mut p = unsafe { p.assume_init() };
    let head = b.u8();
    if head % 2 == 1 {
        p.beam.length = b.param(p.beam.length);
        p.beam.mass = b.param(p.beam.mass);
        p.beam.area = b.param(p.beam.area);
        p.beam.modulus = b.param(p.beam.modulus);
        p.beam.inertia = b.param(p.beam.inertia);
        p.tip.mass = b.param(p.tip.mass);
        p.tip.inertia = b.param(p.tip.inertia);
        p.tip.offset = b.param(p.tip.offset);
        p.ball.mass = b.param(p.ball.mass);
        p.ball.inertia = b.param(p.ball.inertia);
        p.ball.radius = b.param(p.ball.radius);
        p.ball.track_radius = b.param(p.ball.track_radius);
        p.ball.stop_angle = b.param(p.ball.stop_angle);
        p.ball.restitution = b.param(p.ball.restitution);
        p.ball.stick_speed = b.param(p.ball.stick_speed);
        p.ball.initial_angle = b.param(p.ball.initial_angle);
        p.ball.impact_model = b.enumeration(p.ball.impact_model);
        p.integrator.gamma = b.param(p.integrator.gamma);
        p.integrator.beta = b.param(p.integrator.beta);
        p.integrator.step = b.param(p.integrator.step);
        p.integrator.tolerance = b.param(p.integrator.tolerance);
        p.integrator.max_iterations = b.enumeration(p.integrator.max_iterations);
        p.integrator.newton = b.enumeration(p.integrator.newton);
        p.integrator.accept_after_budget = b.u8();
        p.integrator.events = b.enumeration(p.integrator.events);
        p.damping.stiffness_proportional = b.param(p.damping.stiffness_proportional);
        p.gravity = b.param(p.gravity);
        p.alpha_m = b.param(p.alpha_m);
        p.alpha_f = b.param(p.alpha_f);
        p.calibration.bending_stiffness = b.param(p.calibration.bending_stiffness);
        p.calibration.axial_stiffness = b.param(p.calibration.axial_stiffness);
        p.calibration.mass_lumping = b.param(p.calibration.mass_lumping);
        p.flight = b.enumeration(p.flight);
        p.landing_restitution = b.param(p.landing_restitution);
        p.max_work = b.enumeration(p.max_work);
        p.at_cap = b.enumeration(p.at_cap);
        if b.u8() == 0 {
            p.size = b.u32();
        }
    }
    // The firmware's cap on half the inputs: these may step the model for long.
    let capped = head & 2 != 0;
    if capped {
        p.max_work = ABSORBER_WORK_DEADLINE;
    }
    let max_steps = if capped { MAX_STEPS_CAPPED } else { MAX_STEPS };
    let known = ABSORBER_VARIANT_FREE_N3_F32 + b.u8() as u32 % 5;
    let variant = b.enumeration(known);
    let is_f64 = variant == ABSORBER_VARIANT_FREE_N3_F64;
    let base = b.param(0.0);
    let mut storage = Box::new(Storage([0; ABSORBER_MODEL_SIZE_FREE_N6_F32]));
    // Any storage size up to the largest variant's.
    let size = match b.u8() % 4 {
        0 => b.u32() as usize % (ABSORBER_MODEL_SIZE_FREE_N6_F32 + 1),
        _ => ABSORBER_MODEL_SIZE_FREE_N6_F32,
    };
    let mut model: *mut AbsorberModel = std::ptr::null_mut();
    let mut error = std::mem::MaybeUninit::<AbsorberError>::uninit();
    // SAFETY: storage valid for `size` ≤ its length, aligned; params, model, error valid.
    let s = status_ok(unsafe {
        absorber_init(
            storage.0.as_mut_ptr().cast(),
            size,
            variant,
            &p,
            base,
            &mut model,
            error.as_mut_ptr(),
        )
    });
    if s != AbsorberStatus::Ok {
        // SAFETY: written on failure.
        let e = unsafe { error.assume_init() };
        assert_eq!(e.status, s);
        // SAFETY: NUL-terminated by the library.
        let reason = unsafe { CStr::from_ptr(e.reason.as_ptr()) };
        assert!(!reason.to_bytes().is_empty());
        return;
    }
    assert!(!model.is_null());
    // A monitor on half the models, with an arbitrary configuration.
    let mut mon_storage = Box::new(MonitorStorage([0; ABSORBER_MONITOR_SIZE_F64]));
    let mut monitor: *mut AbsorberMonitor = std::ptr::null_mut();
    if b.u8() % 2 == 0 {
        let mut c = std::mem::MaybeUninit::<AbsorberMonitorConfig>::uninit();
        // SAFETY: valid for a write.
        status_ok(unsafe { absorber_monitor_config_default(c.as_mut_ptr()) });
        // SAFETY: written just above.
        let mut c = unsafe { c.assume_init() };
        c.detail_category = b.enumeration(c.detail_category);
        c.threshold_rule = b.enumeration(c.threshold_rule);
        c.block = b.enumeration(c.block);
        c.gate = b.param(c.gate);
        c.extreme_fibre = b.param(c.extreme_fibre);
        // SAFETY: storage valid and aligned; the model is live.
        let s = status_ok(unsafe {
            absorber_monitor_init(
                mon_storage.0.as_mut_ptr().cast(),
                ABSORBER_MONITOR_SIZE_F64,
                model,
                &c,
                &mut monitor,
                std::ptr::null_mut(),
            )
        });
        if s != AbsorberStatus::Ok {
            monitor = std::ptr::null_mut();
        }
    }
    let mut calls = 0;
    let mut steps = 0;
    while !b.empty() && calls < 200 {
        calls += 1;
        let op = b.u8();
        let x = b.param(1.0);
        // SAFETY (every call below): the handles are live, outputs valid for writes.
        unsafe {
            match op % 9 {
                0..=2 if steps < max_steps => {
                    // A burst of 1 to 2,041 steps (`MAX_STEPS` in all on an uncapped input):
                    // a sine of amplitude `x` plus a random walk, as long as the steps go.
                    let n = (1 + b.u8() as u32 * 8).min(max_steps - steps);
                    let freq = 0.25 + b.u8() as f64 / 8.0;
                    let walk_step = x * b.u8() as f64 / 2048.0;
                    let mut seed = b.u32() as u64 | 1;
                    let mut walk = 0.0;
                    let dt = p.integrator.step;
                    let snap = |m: *mut AbsorberModel, buf: &mut [f64]| {
                        CALLS.fetch_add(1, Relaxed);
                        let mut info = AbsorberStateInfoF64::default();
                        let mut q32 = [0f32; 3 * ABSORBER_MAX_DOFS];
                        let (q, rest) = buf.split_at_mut(ABSORBER_MAX_DOFS);
                        let (v, a) = rest.split_at_mut(ABSORBER_MAX_DOFS);
                        if is_f64 {
                            absorber_state_f64(
                                m,
                                &mut info,
                                q.as_mut_ptr(),
                                v.as_mut_ptr(),
                                a.as_mut_ptr(),
                                ABSORBER_MAX_DOFS,
                            );
                        } else {
                            let mut i32_ = AbsorberStateInfoF32::default();
                            let (q3, r3) = q32.split_at_mut(ABSORBER_MAX_DOFS);
                            let (v3, a3) = r3.split_at_mut(ABSORBER_MAX_DOFS);
                            absorber_state_f32(
                                m,
                                &mut i32_,
                                q3.as_mut_ptr(),
                                v3.as_mut_ptr(),
                                a3.as_mut_ptr(),
                                ABSORBER_MAX_DOFS,
                            );
                            for (d, s) in buf.iter_mut().zip(q32.iter()) {
                                *d = *s as f64;
                            }
                        }
                    };
                    let mut after = [0f64; 3 * ABSORBER_MAX_DOFS];
                    snap(model, &mut after);
                    for k in 0..n {
                        steps += 1;
                        step_counted();
                        // xorshift64: the walk's increments, uniform in ±`walk_step`.
                        seed ^= seed << 13;
                        seed ^= seed >> 7;
                        seed ^= seed << 17;
                        walk += walk_step * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
                        let t = (k + 1) as f64 * dt;
                        let base = x * (std::f64::consts::TAU * freq * t).sin() + walk;
                        let before = after;
                        let mut report = AbsorberReportF64::default();
                        let mut report32 = AbsorberReportF32::default();
                        let s = if is_f64 {
                            status_ok(absorber_step_f64(model, base, &mut report))
                        } else {
                            status_ok(absorber_step_f32(model, base as f32, &mut report32))
                        };
                        snap(model, &mut after);
                        if s == AbsorberStatus::Ok {
                            STEPS_OK.fetch_add(1, Relaxed);
                            assert!(report.outcome <= 2 && report32.outcome <= 2);
                            assert!(
                                after.iter().all(|z| z.is_finite()),
                                "accepted step with a non-finite state"
                            );
                        } else {
                            let bits =
                                |v: &[f64]| v.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
                            assert_eq!(
                                bits(&before),
                                bits(&after),
                                "failed step {s:?} changed the state"
                            );
                        }
                    }
                }
                // Past the input's steps (`max_steps`).
                0..=2 => {}
                3 => {
                    if is_f64 {
                        status_ok(absorber_restart_f64(model, x));
                    } else {
                        status_ok(absorber_restart_f32(model, x as f32));
                    }
                }
                4 => {
                    let y = b.param(0.0);
                    if is_f64 {
                        let mut o = std::mem::MaybeUninit::<AbsorberEnergiesF64>::uninit();
                        let s = status_ok(absorber_energies_f64(model, x, y, o.as_mut_ptr()));
                        if !(x.is_finite() && y.is_finite()) {
                            assert_ne!(s, AbsorberStatus::Ok, "energies of a non-finite base");
                        }
                    } else {
                        let mut o = std::mem::MaybeUninit::<AbsorberEnergiesF32>::uninit();
                        let s = status_ok(absorber_energies_f32(
                            model,
                            x as f32,
                            y as f32,
                            o.as_mut_ptr(),
                        ));
                        if !((x as f32).is_finite() && (y as f32).is_finite()) {
                            assert_ne!(s, AbsorberStatus::Ok, "energies of a non-finite base");
                        }
                    }
                }
                5 => {
                    if is_f64 {
                        let mut o = std::mem::MaybeUninit::<AbsorberOutputsF64>::uninit();
                        status_ok(absorber_outputs_f64(model, o.as_mut_ptr()));
                        let mut st = 0f64;
                        status_ok(absorber_root_stress_f64(model, &mut st));
                    } else {
                        let mut o = std::mem::MaybeUninit::<AbsorberOutputsF32>::uninit();
                        status_ok(absorber_outputs_f32(model, o.as_mut_ptr()));
                        let mut st = 0f32;
                        status_ok(absorber_root_stress_f32(model, &mut st));
                    }
                }
                6 => {
                    // Any capacity, with buffers that hold it.
                    let cap = b.u8() as usize % (ABSORBER_MAX_DOFS + 2);
                    let mut q = vec![0f64; cap];
                    let mut v = vec![0f64; cap];
                    let mut a = vec![0f64; cap];
                    let mut info = AbsorberStateInfoF64::default();
                    let mut q3 = vec![0f32; cap];
                    let mut v3 = vec![0f32; cap];
                    let mut a3 = vec![0f32; cap];
                    let mut info3 = AbsorberStateInfoF32::default();
                    status_ok(absorber_state_f64(
                        model,
                        &mut info,
                        q.as_mut_ptr(),
                        v.as_mut_ptr(),
                        a.as_mut_ptr(),
                        cap,
                    ));
                    status_ok(absorber_state_f32(
                        model,
                        &mut info3,
                        q3.as_mut_ptr(),
                        v3.as_mut_ptr(),
                        a3.as_mut_ptr(),
                        cap,
                    ));
                }
                7 if !monitor.is_null() => {
                    let mut r = AbsorberReportF64 {
                        iterations: b.u32(),
                        increment: b.param(1e-6),
                        impact: b.u8(),
                        impact_stuck: b.u8(),
                        impact_side: b.u32() as i32,
                        impact_relative_speed: b.param(0.1),
                        separation: b.u8(),
                        landing: b.u8(),
                        work: b.u32(),
                        outcome: b.enumeration(0),
                        ..Default::default()
                    };
                    r.impact_impulse = b.param(0.0);
                    let mut st = 0f64;
                    let mut st32 = 0f32;
                    let r32 = AbsorberReportF32 {
                        iterations: r.iterations,
                        increment: r.increment as f32,
                        impact: r.impact,
                        impact_stuck: r.impact_stuck,
                        impact_side: r.impact_side,
                        separation: r.separation,
                        landing: r.landing,
                        work: r.work,
                        outcome: r.outcome,
                        ..Default::default()
                    };
                    if is_f64 {
                        status_ok(absorber_monitor_record_f64(monitor, model, &r, x, &mut st));
                    } else {
                        status_ok(absorber_monitor_record_f32(
                            monitor, model, &r32, x as f32, &mut st32,
                        ));
                    }
                    let mut o = std::mem::MaybeUninit::<AbsorberMonitorReadingF64>::uninit();
                    let mut o3 = std::mem::MaybeUninit::<AbsorberMonitorReadingF32>::uninit();
                    status_ok(absorber_monitor_read_f64(monitor, o.as_mut_ptr()));
                    status_ok(absorber_monitor_read_f32(monitor, o3.as_mut_ptr()));
                }
                _ => {
                    let raw = b.u32() as i32;
                    CALLS.fetch_add(1, Relaxed);
                    let name = CStr::from_ptr(absorber_status_name(raw));
                    assert!(!name.to_bytes().is_empty());
                }
            }
        }
    }
});
