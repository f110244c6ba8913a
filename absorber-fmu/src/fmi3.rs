//! The FMI 3.0 functions (`include/fmi/fmi3FunctionTypes.h`): co-simulation, FMU state and
//! its serialization. Every function of the standard is exported (importers bind them all);
//! those of Model Exchange, Scheduled Execution, clocks and the types this FMU does not use
//! answer `fmi3Error` with a log message.
#![allow(non_snake_case, clippy::missing_safety_doc)]

use crate::ffi::{self as state, c_string, guard, load_config, slice, slice_mut, string};
use crate::instance::{Instance, Log, Status};
use std::ffi::{c_char, c_void};
use std::path::PathBuf;

/// `fmi3Instance`.
pub type Fmi3Instance = *mut c_void;
/// `fmi3FMUState`.
pub type Fmi3FmuState = *mut c_void;
/// `fmi3ValueReference`.
pub type Vr = u32;
/// `fmi3Status` (a C enum: `int`).
pub type Fmi3Status = i32;
/// `fmi3LogMessageCallback`.
pub type LogMessage =
    Option<unsafe extern "C" fn(*mut c_void, Fmi3Status, *const c_char, *const c_char)>;

/// `FMI3_VERSION`: the version string of `fmi3GetVersion`.
pub const VERSION: &std::ffi::CStr = c"3.0";

struct Logger {
    callback: LogMessage,
    environment: *mut c_void,
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.callback {
            let (c, m) = (c_string(category), c_string(message));
            // SAFETY: the importer's callback with its own environment and two valid C
            // strings that outlive the call.
            unsafe { cb(self.environment, status as i32, c.as_ptr(), m.as_ptr()) };
        }
    }
}

/// The instance behind a handle.
///
/// # Safety
/// `instance` is NULL or a live handle of [`fmi3InstantiateCoSimulation`].
unsafe fn inst<'a>(instance: Fmi3Instance) -> Option<&'a mut Instance> {
    // SAFETY: a live handle is a `Box<Instance>` made by `fmi3InstantiateCoSimulation`.
    unsafe { instance.cast::<Instance>().as_mut() }
}

/// Runs `f` on the instance (`fmi3Error` for a NULL handle, `fmi3Fatal` on a panic).
///
/// # Safety
/// As [`inst`].
unsafe fn with(instance: Fmi3Instance, f: impl FnOnce(&mut Instance) -> Status) -> Fmi3Status {
    // SAFETY: forwarded.
    match unsafe { inst(instance) } {
        Some(i) => guard(|| f(i)) as i32,
        None => Status::Error as i32,
    }
}

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    VERSION.as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: Fmi3Instance,
    loggingOn: bool,
    _nCategories: usize,
    _categories: *const *const c_char,
) -> Fmi3Status {
    // SAFETY: the importer passes a handle of this library.
    unsafe {
        with(instance, |i| {
            i.logging = loggingOn;
            Status::Ok
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: *const c_char,
    instantiationToken: *const c_char,
    resourcePath: *const c_char,
    _visible: bool,
    loggingOn: bool,
    _eventModeUsed: bool,
    _earlyReturnAllowed: bool,
    _requiredIntermediateVariables: *const Vr,
    _nRequiredIntermediateVariables: usize,
    instanceEnvironment: *mut c_void,
    logMessage: LogMessage,
    _intermediateUpdate: *mut c_void,
) -> Fmi3Instance {
    let log = Logger {
        callback: logMessage,
        environment: instanceEnvironment,
    };
    // SAFETY: NULL or NUL-terminated strings of the importer.
    let (name, token, resources) = unsafe {
        (
            string(instanceName).unwrap_or_default(),
            string(instantiationToken),
            string(resourcePath),
        )
    };
    let made = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let Some(dir) = resources else {
            return Err(
                "instantiate: resourcePath is NULL; the FMU needs its resources folder (scene.cfg)"
                    .to_string(),
            );
        };
        let config = load_config(&PathBuf::from(dir))?;
        let instance = Instance::new(&name, config, loggingOn, Box::new(log));
        match token {
            Some(t) if t == instance.token() => Ok(instance),
            t => Err(format!(
                "instantiate: instantiationToken {t:?} is not this FMU's {} (modelDescription.xml and resources/scene.cfg of different FMUs?)",
                instance.token()
            )),
        }
    }));
    match made {
        Ok(Ok(i)) => Box::into_raw(Box::new(i)).cast(),
        Ok(Err(m)) => {
            Logger {
                callback: logMessage,
                environment: instanceEnvironment,
            }
            .log(Status::Error, Status::Error.category(), &m);
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: Fmi3Instance) {
    if !instance.is_null() {
        // SAFETY: a live handle is a `Box<Instance>` made by `fmi3InstantiateCoSimulation`;
        // the importer does not use it after this call.
        drop(unsafe { Box::from_raw(instance.cast::<Instance>()) });
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: Fmi3Instance,
    _toleranceDefined: bool,
    _tolerance: f64,
    startTime: f64,
    _stopTimeDefined: bool,
    _stopTime: f64,
) -> Fmi3Status {
    // SAFETY: a handle of this library.
    unsafe { with(instance, |i| i.enter_initialization(startTime)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: Fmi3Instance) -> Fmi3Status {
    // SAFETY: a handle of this library.
    unsafe { with(instance, |i| i.exit_initialization()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: Fmi3Instance) -> Fmi3Status {
    // SAFETY: a handle of this library.
    unsafe { with(instance, |i| i.terminate()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: Fmi3Instance) -> Fmi3Status {
    // SAFETY: a handle of this library.
    unsafe { with(instance, |i| i.reset()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: Fmi3Instance,
    valueReferences: *const Vr,
    nValueReferences: usize,
    values: *mut f64,
    nValues: usize,
) -> Fmi3Status {
    // SAFETY: arrays of the given lengths by the importer's contract.
    unsafe {
        with(instance, |i| {
            match (
                slice(valueReferences, nValueReferences),
                slice_mut(values, nValues),
            ) {
                (Some(v), Some(x)) => i.get_f64(v, x),
                _ => i.say(Status::Error, "fmi3GetFloat64: NULL array"),
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: Fmi3Instance,
    valueReferences: *const Vr,
    nValueReferences: usize,
    values: *const f64,
    nValues: usize,
) -> Fmi3Status {
    // SAFETY: arrays of the given lengths by the importer's contract.
    unsafe {
        with(instance, |i| {
            match (
                slice(valueReferences, nValueReferences),
                slice(values, nValues),
            ) {
                (Some(v), Some(x)) => i.set_f64(v, x),
                _ => i.say(Status::Error, "fmi3SetFloat64: NULL array"),
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: Fmi3Instance,
    valueReferences: *const Vr,
    nValueReferences: usize,
    values: *mut i32,
    nValues: usize,
) -> Fmi3Status {
    // SAFETY: arrays of the given lengths by the importer's contract.
    unsafe {
        with(instance, |i| {
            match (
                slice(valueReferences, nValueReferences),
                slice_mut(values, nValues),
            ) {
                (Some(v), Some(x)) => i.get_i32(v, x),
                _ => i.say(Status::Error, "fmi3GetInt32: NULL array"),
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: Fmi3Instance,
    currentCommunicationPoint: f64,
    communicationStepSize: f64,
    _noSetFMUStatePriorToCurrentPoint: bool,
    eventHandlingNeeded: *mut bool,
    terminateSimulation: *mut bool,
    earlyReturn: *mut bool,
    lastSuccessfulTime: *mut f64,
) -> Fmi3Status {
    // SAFETY: the out-pointers are NULL or valid for a write (importer's contract).
    unsafe {
        with(instance, |i| {
            let (s, t) = i.do_step(currentCommunicationPoint, communicationStepSize);
            for (p, v) in [
                (eventHandlingNeeded, false),
                (terminateSimulation, s >= Status::Error),
                (earlyReturn, false),
            ] {
                if let Some(p) = p.as_mut() {
                    *p = v;
                }
            }
            if let Some(p) = lastSuccessfulTime.as_mut() {
                *p = t;
            }
            s
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: Fmi3Instance,
    FMUState: *mut Fmi3FmuState,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(instance, |i| state::get_state(i, FMUState)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: Fmi3Instance,
    FMUState: Fmi3FmuState,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(instance, |i| state::set_state(i, FMUState)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: Fmi3Instance,
    FMUState: *mut Fmi3FmuState,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(instance, |_| state::free_state(FMUState)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: Fmi3Instance,
    FMUState: Fmi3FmuState,
    size: *mut usize,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(instance, |i| state::state_size(i, FMUState, size)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: Fmi3Instance,
    FMUState: Fmi3FmuState,
    serializedState: *mut u8,
    size: usize,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe {
        with(instance, |i| {
            state::serialize(i, FMUState, serializedState, size)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: Fmi3Instance,
    serializedState: *const u8,
    size: usize,
    FMUState: *mut Fmi3FmuState,
) -> Fmi3Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe {
        with(instance, |i| {
            state::deserialize(i, serializedState, size, FMUState)
        })
    }
}

/// Functions this FMU does not provide: full signature, an error and a log message.
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {
        $(
            #[no_mangle]
            pub unsafe extern "C" fn $name(instance: Fmi3Instance, $($arg: $ty),*) -> Fmi3Status {
                $(let _ = $arg;)*
                // SAFETY: a handle of this library (or NULL).
                unsafe {
                    with(instance, |i| {
                        i.say(
                            Status::Error,
                            concat!(stringify!($name), ": not provided by this FMU (co-simulation with Float64 and Int32 variables)"),
                        )
                    })
                }
            }
        )*
    };
}

type Ptr = *mut c_void;
type CPtr = *const c_void;

unsupported! {
    fmi3EnterEventMode();
    fmi3GetFloat32(a: *const Vr, b: usize, c: *mut f32, d: usize);
    fmi3GetInt8(a: *const Vr, b: usize, c: *mut i8, d: usize);
    fmi3GetUInt8(a: *const Vr, b: usize, c: *mut u8, d: usize);
    fmi3GetInt16(a: *const Vr, b: usize, c: *mut i16, d: usize);
    fmi3GetUInt16(a: *const Vr, b: usize, c: *mut u16, d: usize);
    fmi3GetUInt32(a: *const Vr, b: usize, c: *mut u32, d: usize);
    fmi3GetInt64(a: *const Vr, b: usize, c: *mut i64, d: usize);
    fmi3GetUInt64(a: *const Vr, b: usize, c: *mut u64, d: usize);
    fmi3GetBoolean(a: *const Vr, b: usize, c: *mut bool, d: usize);
    fmi3GetString(a: *const Vr, b: usize, c: *mut *const c_char, d: usize);
    fmi3GetBinary(a: *const Vr, b: usize, c: *mut usize, d: *mut *const u8, e: usize);
    fmi3GetClock(a: *const Vr, b: usize, c: *mut bool);
    fmi3SetFloat32(a: *const Vr, b: usize, c: *const f32, d: usize);
    fmi3SetInt8(a: *const Vr, b: usize, c: *const i8, d: usize);
    fmi3SetUInt8(a: *const Vr, b: usize, c: *const u8, d: usize);
    fmi3SetInt16(a: *const Vr, b: usize, c: *const i16, d: usize);
    fmi3SetUInt16(a: *const Vr, b: usize, c: *const u16, d: usize);
    fmi3SetInt32(a: *const Vr, b: usize, c: *const i32, d: usize);
    fmi3SetUInt32(a: *const Vr, b: usize, c: *const u32, d: usize);
    fmi3SetInt64(a: *const Vr, b: usize, c: *const i64, d: usize);
    fmi3SetUInt64(a: *const Vr, b: usize, c: *const u64, d: usize);
    fmi3SetBoolean(a: *const Vr, b: usize, c: *const bool, d: usize);
    fmi3SetString(a: *const Vr, b: usize, c: *const *const c_char, d: usize);
    fmi3SetBinary(a: *const Vr, b: usize, c: *const usize, d: *const *const u8, e: usize);
    fmi3SetClock(a: *const Vr, b: usize, c: *const bool);
    fmi3GetNumberOfVariableDependencies(a: Vr, b: *mut usize);
    fmi3GetVariableDependencies(a: Vr, b: *mut usize, c: *mut Vr, d: *mut usize, e: *mut i32, f: usize);
    fmi3GetDirectionalDerivative(a: *const Vr, b: usize, c: *const Vr, d: usize, e: *const f64, f: usize, g: *mut f64, h: usize);
    fmi3GetAdjointDerivative(a: *const Vr, b: usize, c: *const Vr, d: usize, e: *const f64, f: usize, g: *mut f64, h: usize);
    fmi3EnterConfigurationMode();
    fmi3ExitConfigurationMode();
    fmi3GetIntervalDecimal(a: *const Vr, b: usize, c: *mut f64, d: *mut i32);
    fmi3GetIntervalFraction(a: *const Vr, b: usize, c: *mut u64, d: *mut u64, e: *mut i32);
    fmi3GetShiftDecimal(a: *const Vr, b: usize, c: *mut f64);
    fmi3GetShiftFraction(a: *const Vr, b: usize, c: *mut u64, d: *mut u64);
    fmi3SetIntervalDecimal(a: *const Vr, b: usize, c: *const f64);
    fmi3SetIntervalFraction(a: *const Vr, b: usize, c: *const u64, d: *const u64);
    fmi3SetShiftDecimal(a: *const Vr, b: usize, c: *const f64);
    fmi3SetShiftFraction(a: *const Vr, b: usize, c: *const u64, d: *const u64);
    fmi3EvaluateDiscreteStates();
    fmi3UpdateDiscreteStates(a: *mut bool, b: *mut bool, c: *mut bool, d: *mut bool, e: *mut bool, f: *mut f64);
    fmi3EnterContinuousTimeMode();
    fmi3CompletedIntegratorStep(a: bool, b: *mut bool, c: *mut bool);
    fmi3SetTime(a: f64);
    fmi3SetContinuousStates(a: *const f64, b: usize);
    fmi3GetContinuousStateDerivatives(a: *mut f64, b: usize);
    fmi3GetEventIndicators(a: *mut f64, b: usize);
    fmi3GetContinuousStates(a: *mut f64, b: usize);
    fmi3GetNominalsOfContinuousStates(a: *mut f64, b: usize);
    fmi3GetNumberOfEventIndicators(a: *mut usize);
    fmi3GetNumberOfContinuousStates(a: *mut usize);
    fmi3EnterStepMode();
    fmi3GetOutputDerivatives(a: *const Vr, b: usize, c: *const i32, d: *mut f64, e: usize);
    fmi3ActivateModelPartition(a: Vr, b: f64);
}

/// Model Exchange and Scheduled Execution are not provided: these instantiate nothing.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instanceName: *const c_char,
    _instantiationToken: *const c_char,
    _resourcePath: *const c_char,
    _visible: bool,
    _loggingOn: bool,
    instanceEnvironment: Ptr,
    logMessage: LogMessage,
) -> Fmi3Instance {
    Logger {
        callback: logMessage,
        environment: instanceEnvironment,
    }
    .log(
        Status::Error,
        Status::Error.category(),
        "this FMU is co-simulation only (no Model Exchange)",
    );
    std::ptr::null_mut()
}

/// As [`fmi3InstantiateModelExchange`].
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: *const c_char,
    _instantiationToken: *const c_char,
    _resourcePath: *const c_char,
    _visible: bool,
    _loggingOn: bool,
    instanceEnvironment: Ptr,
    logMessage: LogMessage,
    _clockUpdate: CPtr,
    _lockPreemption: CPtr,
    _unlockPreemption: CPtr,
) -> Fmi3Instance {
    Logger {
        callback: logMessage,
        environment: instanceEnvironment,
    }
    .log(
        Status::Error,
        Status::Error.category(),
        "this FMU is co-simulation only (no Scheduled Execution)",
    );
    std::ptr::null_mut()
}
