//! The FMI 2.0 functions (`include/fmi/fmi2FunctionTypes.h`): co-simulation, FMU state and
//! its serialization. Every function of the standard is exported; those of Model Exchange and
//! the types this FMU does not use answer `fmi2Error` with a log message.
#![allow(non_snake_case, clippy::missing_safety_doc)]

use crate::ffi::{self as state, c_string, guard, load_config, slice, slice_mut, string};
use crate::instance::{Instance, Log, Status};
use std::ffi::{c_char, c_void};
use std::path::PathBuf;

/// `fmi2Component`.
pub type Fmi2Component = *mut c_void;
/// `fmi2FMUstate`.
pub type Fmi2FmuState = *mut c_void;
/// `fmi2ValueReference`.
pub type Vr = u32;
/// `fmi2Status` (a C enum: `int`).
pub type Fmi2Status = i32;
/// `fmi2Boolean`.
pub type Fmi2Boolean = i32;

/// `fmi2CallbackLogger` (C-variadic: the message is a format string).
pub type Logger = Option<
    unsafe extern "C" fn(*mut c_void, *const c_char, Fmi2Status, *const c_char, *const c_char, ...),
>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    /// `logger`.
    pub logger: Logger,
    /// `allocateMemory` (not used: `canNotUseMemoryManagementFunctions`).
    pub allocate_memory: *const c_void,
    /// `freeMemory` (not used).
    pub free_memory: *const c_void,
    /// `stepFinished` (not used: no asynchronous steps).
    pub step_finished: *const c_void,
    /// `componentEnvironment`.
    pub component_environment: *mut c_void,
}

/// `fmi2LastSuccessfulTime` of `fmi2StatusKind`.
const LAST_SUCCESSFUL_TIME: i32 = 2;
/// `fmi2Terminated` of `fmi2StatusKind`.
const TERMINATED: i32 = 3;

struct Log2 {
    logger: Logger,
    environment: *mut c_void,
    name: std::ffi::CString,
}

impl Log for Log2 {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.logger {
            // The message is the format string (as importers that do not format expect), its
            // `%` doubled for those that do.
            let (c, m) = (c_string(category), c_string(&message.replace('%', "%%")));
            // SAFETY: the importer's logger with its environment and C strings that outlive
            // the call; the format has no conversion, so no variadic argument is read.
            unsafe {
                cb(
                    self.environment,
                    self.name.as_ptr(),
                    status as i32,
                    c.as_ptr(),
                    m.as_ptr(),
                )
            };
        }
    }
}

/// An FMI 2 component: the instance and the start time of `fmi2SetupExperiment`.
struct Component {
    instance: Instance,
    start_time: f64,
    last_failed: bool,
}

/// The path of a `file:` URI (`file:///a/b`, `file:/a/b`, `file://localhost/a/b`), with
/// `%XX` escapes decoded.
pub fn path_of_uri(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let rest = if let Some(r) = rest.strip_prefix("//") {
        // An authority: empty or localhost.
        let slash = r.find('/')?;
        let (host, path) = r.split_at(slash);
        if !(host.is_empty() || host == "localhost") {
            return None;
        }
        path
    } else {
        rest
    };
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' => {
                let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
                out.push(u8::from_str_radix(hex, 16).ok()?);
                i += 3;
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

/// # Safety
/// `c` is NULL or a live handle of [`fmi2Instantiate`].
unsafe fn comp<'a>(c: Fmi2Component) -> Option<&'a mut Component> {
    // SAFETY: a live handle is a `Box<Component>` made by `fmi2Instantiate`.
    unsafe { c.cast::<Component>().as_mut() }
}

/// # Safety
/// As [`comp`].
unsafe fn with(c: Fmi2Component, f: impl FnOnce(&mut Component) -> Status) -> Fmi2Status {
    // SAFETY: forwarded.
    match unsafe { comp(c) } {
        Some(x) => guard(|| {
            let s = f(x);
            x.last_failed = s >= Status::Discard;
            s
        }) as i32,
        None => Status::Error as i32,
    }
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Fmi2Component,
    loggingOn: Fmi2Boolean,
    _nCategories: usize,
    _categories: *const *const c_char,
) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe {
        with(c, |x| {
            x.instance.logging = loggingOn != 0;
            Status::Ok
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: *const c_char,
    fmuType: i32,
    fmuGUID: *const c_char,
    fmuResourceLocation: *const c_char,
    functions: *const CallbackFunctions,
    _visible: Fmi2Boolean,
    loggingOn: Fmi2Boolean,
) -> Fmi2Component {
    // SAFETY: NULL or valid pointers of the importer.
    let (name, guid, location, cb) = unsafe {
        (
            string(instanceName).unwrap_or_default(),
            string(fmuGUID),
            string(fmuResourceLocation),
            functions.as_ref(),
        )
    };
    let log = || Log2 {
        logger: cb.and_then(|f| f.logger),
        environment: cb.map_or(std::ptr::null_mut(), |f| f.component_environment),
        name: c_string(&name),
    };
    let made = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if fmuType != 1 {
            return Err(
                "instantiate: this FMU is co-simulation only (fmuType must be fmi2CoSimulation)"
                    .to_string(),
            );
        }
        let Some(uri) = location else {
            return Err("instantiate: fmuResourceLocation is NULL; the FMU needs its resources folder (scene.cfg)".to_string());
        };
        let dir = path_of_uri(&uri).ok_or_else(|| {
            format!("instantiate: fmuResourceLocation {uri:?} is not a local file: URI")
        })?;
        let config = load_config(&dir)?;
        let instance = Instance::new(&name, config, loggingOn != 0, Box::new(log()));
        match guid {
            Some(g) if g == instance.token() => Ok(instance),
            g => Err(format!(
                "instantiate: fmuGUID {g:?} is not this FMU's {} (modelDescription.xml and resources/scene.cfg of different FMUs?)",
                instance.token()
            )),
        }
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(Component {
            instance,
            start_time: 0.0,
            last_failed: false,
        }))
        .cast(),
        Ok(Err(m)) => {
            log().log(Status::Error, Status::Error.category(), &m);
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
    if !c.is_null() {
        // SAFETY: a live handle is a `Box<Component>`; not used after this call.
        drop(unsafe { Box::from_raw(c.cast::<Component>()) });
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: Fmi2Component,
    _toleranceDefined: Fmi2Boolean,
    _tolerance: f64,
    startTime: f64,
    _stopTimeDefined: Fmi2Boolean,
    _stopTime: f64,
) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe {
        with(c, |x| {
            x.start_time = startTime;
            Status::Ok
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe { with(c, |x| x.instance.enter_initialization(x.start_time)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe { with(c, |x| x.instance.exit_initialization()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: Fmi2Component) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe { with(c, |x| x.instance.terminate()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: Fmi2Component) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe {
        with(c, |x| {
            x.start_time = 0.0;
            x.instance.reset()
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: Fmi2Component,
    vr: *const Vr,
    nvr: usize,
    value: *mut f64,
) -> Fmi2Status {
    // SAFETY: arrays of `nvr` elements by the importer's contract.
    unsafe {
        with(c, |x| match (slice(vr, nvr), slice_mut(value, nvr)) {
            (Some(v), Some(out)) => x.instance.get_f64(v, out),
            _ => x.instance.say(Status::Error, "fmi2GetReal: NULL array"),
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: Fmi2Component,
    vr: *const Vr,
    nvr: usize,
    value: *const f64,
) -> Fmi2Status {
    // SAFETY: arrays of `nvr` elements by the importer's contract.
    unsafe {
        with(c, |x| match (slice(vr, nvr), slice(value, nvr)) {
            (Some(v), Some(vals)) => x.instance.set_f64(v, vals),
            _ => x.instance.say(Status::Error, "fmi2SetReal: NULL array"),
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Fmi2Component,
    vr: *const Vr,
    nvr: usize,
    value: *mut i32,
) -> Fmi2Status {
    // SAFETY: arrays of `nvr` elements by the importer's contract.
    unsafe {
        with(c, |x| match (slice(vr, nvr), slice_mut(value, nvr)) {
            (Some(v), Some(out)) => x.instance.get_i32(v, out),
            _ => x.instance.say(Status::Error, "fmi2GetInteger: NULL array"),
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: Fmi2Component,
    currentCommunicationPoint: f64,
    communicationStepSize: f64,
    _noSetFMUStatePriorToCurrentPoint: Fmi2Boolean,
) -> Fmi2Status {
    // SAFETY: a handle of this library.
    unsafe {
        with(c, |x| {
            x.instance
                .do_step(currentCommunicationPoint, communicationStepSize)
                .0
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: Fmi2Component,
    s: i32,
    value: *mut f64,
) -> Fmi2Status {
    // SAFETY: `value` NULL or valid for a write.
    unsafe {
        with(c, |x| match (s, value.as_mut()) {
            (LAST_SUCCESSFUL_TIME, Some(v)) => {
                *v = x.instance.time();
                Status::Ok
            }
            _ => Status::Discard,
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Fmi2Component,
    s: i32,
    value: *mut Fmi2Boolean,
) -> Fmi2Status {
    // SAFETY: `value` NULL or valid for a write.
    unsafe {
        with(c, |x| match (s, value.as_mut()) {
            (TERMINATED, Some(v)) => {
                *v = i32::from(x.last_failed);
                Status::Ok
            }
            _ => Status::Discard,
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: Fmi2Component,
    FMUstate: *mut Fmi2FmuState,
) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(c, |x| state::get_state(&x.instance, FMUstate)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Fmi2Component, FMUstate: Fmi2FmuState) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(c, |x| state::set_state(&mut x.instance, FMUstate)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: Fmi2Component,
    FMUstate: *mut Fmi2FmuState,
) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(c, |_| state::free_state(FMUstate)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Fmi2Component,
    FMUstate: Fmi2FmuState,
    size: *mut usize,
) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe { with(c, |x| state::state_size(&x.instance, FMUstate, size)) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Fmi2Component,
    FMUstate: Fmi2FmuState,
    serializedState: *mut u8,
    size: usize,
) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe {
        with(c, |x| {
            state::serialize(&x.instance, FMUstate, serializedState, size)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Fmi2Component,
    serializedState: *const u8,
    size: usize,
    FMUstate: *mut Fmi2FmuState,
) -> Fmi2Status {
    // SAFETY: the importer's pointers (FMI contract).
    unsafe {
        with(c, |x| {
            state::deserialize(&x.instance, serializedState, size, FMUstate)
        })
    }
}

/// Functions this FMU does not provide: full signature, an error and a log message.
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {
        $(
            #[no_mangle]
            pub unsafe extern "C" fn $name(c: Fmi2Component, $($arg: $ty),*) -> Fmi2Status {
                $(let _ = $arg;)*
                // SAFETY: a handle of this library (or NULL).
                unsafe {
                    with(c, |x| {
                        x.instance.say(
                            Status::Error,
                            concat!(stringify!($name), ": not provided by this FMU (co-simulation with Real and Integer variables)"),
                        )
                    })
                }
            }
        )*
    };
}

unsupported! {
    fmi2GetBoolean(a: *const Vr, b: usize, d: *mut Fmi2Boolean);
    fmi2GetString(a: *const Vr, b: usize, d: *mut *const c_char);
    fmi2SetInteger(a: *const Vr, b: usize, d: *const i32);
    fmi2SetBoolean(a: *const Vr, b: usize, d: *const Fmi2Boolean);
    fmi2SetString(a: *const Vr, b: usize, d: *const *const c_char);
    fmi2GetDirectionalDerivative(a: *const Vr, b: usize, d: *const Vr, e: usize, f: *const f64, g: *mut f64);
    fmi2EnterEventMode();
    fmi2NewDiscreteStates(a: *mut c_void);
    fmi2EnterContinuousTimeMode();
    fmi2CompletedIntegratorStep(a: Fmi2Boolean, b: *mut Fmi2Boolean, d: *mut Fmi2Boolean);
    fmi2SetTime(a: f64);
    fmi2SetContinuousStates(a: *const f64, b: usize);
    fmi2GetDerivatives(a: *mut f64, b: usize);
    fmi2GetEventIndicators(a: *mut f64, b: usize);
    fmi2GetContinuousStates(a: *mut f64, b: usize);
    fmi2GetNominalsOfContinuousStates(a: *mut f64, b: usize);
    fmi2SetRealInputDerivatives(a: *const Vr, b: usize, d: *const i32, e: *const f64);
    fmi2GetRealOutputDerivatives(a: *const Vr, b: usize, d: *const i32, e: *mut f64);
    fmi2CancelStep();
    fmi2GetStatus(a: i32, b: *mut Fmi2Status);
    fmi2GetIntegerStatus(a: i32, b: *mut i32);
    fmi2GetStringStatus(a: i32, b: *mut *const c_char);
}

#[cfg(test)]
mod tests {
    use super::path_of_uri;
    use std::path::PathBuf;

    #[test]
    fn file_uris_give_their_paths() {
        let p = |s: &str| path_of_uri(s);
        assert_eq!(
            p("file:///tmp/a%20b/resources"),
            Some(PathBuf::from("/tmp/a b/resources"))
        );
        assert_eq!(p("file:/tmp/x"), Some(PathBuf::from("/tmp/x")));
        assert_eq!(p("file://localhost/tmp/x/"), Some(PathBuf::from("/tmp/x/")));
        assert_eq!(p("http://host/x"), None);
        assert_eq!(p("file://other/x"), None);
    }
}
