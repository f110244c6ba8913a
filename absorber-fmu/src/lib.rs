//! # absorber-fmu — the reduced model as an FMI co-simulation FMU
//!
//! One shared library serves both FMI 3.0 and FMI 2.0 co-simulation FMUs (the functions of the
//! two versions have different names): `host-sim fmu --scene S --fmi-version 3|2` packages it
//! with a `modelDescription.xml` and the scene's configuration (`resources/scene.cfg`). The
//! library reads the configuration when it is instantiated, so one binary runs every scene,
//! element count and scalar that `host-sim run` runs (the core's compile-time choices are
//! instantiated here, as in `host-sim`).
//!
//! Layout, top to bottom: [`vars`] (the one table of variables: value references, names,
//! units, where each value lives), [`config`] (the scene's model and parameters, as written
//! into the FMU), [`xml`] (`modelDescription.xml` from the table), [`sim`] (the core's model and
//! monitor of any scene behind a trait), [`instance`] (the FMI state machine, values, steps,
//! FMU state), and the C functions of [`fmi3`] and [`fmi2`] (thin: they check pointers and
//! call [`instance`]). The headers these follow are the standard's, in `include/fmi/`.
//!
//! Inputs: base acceleration \[m/s²\] and tip load \[N\]; outputs: tip deflection and
//! acceleration, root stress, ball angles, contact state and normal force, Miner damage;
//! parameters: the scene's physical parameters. The step is the scene's h; a communication step
//! of k·h runs k steps of the core, exactly as `host-sim run` steps it (`docs/fmu.md`).

pub mod config;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod sim;
pub mod vars;
pub mod xml;

/// Hash of this crate's and the core's sources at build time (`build.rs`).
pub const BUILD_ID: &str = env!("ABSORBER_FMU_BUILD_ID");

/// The marker string compiled into the shared library (`host-sim fmu` looks for it in the
/// library it packages, so that a library of other sources is never packaged).
pub const BUILD_MARKER: &str = concat!("absorber-fmu-build:", env!("ABSORBER_FMU_BUILD_ID"));

/// [`BUILD_MARKER`] as a C string: exported, so that the library file always holds it.
#[no_mangle]
pub extern "C" fn absorber_fmu_build_marker() -> *const std::ffi::c_char {
    const MARKER: &str = concat!("absorber-fmu-build:", env!("ABSORBER_FMU_BUILD_ID"), "\0");
    MARKER.as_ptr().cast()
}

/// Helpers of the C functions.
pub(crate) mod ffi {
    use crate::instance::{Instance, Snapshot, Status};
    use std::ffi::{c_char, c_void, CStr};

    /// `n` elements at `p` (an empty slice for `n = 0`, whatever `p`); `None` for a NULL `p`.
    ///
    /// # Safety
    /// `p` is NULL or valid for `n` reads of `T`, and not written while the slice lives.
    pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
        if n == 0 {
            return Some(&[]);
        }
        if p.is_null() {
            return None;
        }
        // SAFETY: non-null and valid for `n` reads by the caller's guarantee.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }

    /// As [`slice`], for writes.
    ///
    /// # Safety
    /// `p` is NULL or valid for `n` writes of `T`, not otherwise accessed while the slice
    /// lives.
    pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
        if n == 0 {
            return Some(&mut []);
        }
        if p.is_null() {
            return None;
        }
        // SAFETY: non-null and valid for `n` writes by the caller's guarantee.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }

    /// The string at `p` (lossy UTF-8), or `None` for NULL.
    ///
    /// # Safety
    /// `p` is NULL or a NUL-terminated string.
    pub unsafe fn string(p: *const c_char) -> Option<String> {
        if p.is_null() {
            return None;
        }
        // SAFETY: non-null, NUL-terminated by the caller's guarantee.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }

    /// Runs `f`, turning a panic (a bug: nothing here should panic) into `Fatal`.
    pub fn guard(f: impl FnOnce() -> Status) -> Status {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or(Status::Fatal)
    }

    /// A C string of `s` (interior NULs replaced).
    pub fn c_string(s: &str) -> std::ffi::CString {
        std::ffi::CString::new(s.replace('\0', " ")).unwrap_or_default()
    }

    /// `fmi*GetFMUState`: a new state in `*slot`, or the old one there overwritten.
    ///
    /// # Safety
    /// `slot` is NULL or valid for reads and writes; its value NULL or a state of this library.
    pub unsafe fn get_state(i: &Instance, slot: *mut *mut c_void) -> Status {
        // SAFETY: by the caller's guarantee.
        let Some(slot) = (unsafe { slot.as_mut() }) else {
            return i.say(Status::Error, "get FMU state: NULL argument");
        };
        let s = i.snapshot();
        // SAFETY: a non-NULL value is a state of this library.
        match unsafe { slot.cast::<Snapshot>().as_mut() } {
            Some(old) => *old = s,
            None => *slot = Box::into_raw(Box::new(s)).cast(),
        }
        Status::Ok
    }

    /// `fmi*SetFMUState`.
    ///
    /// # Safety
    /// `state` is NULL or a state of this library.
    pub unsafe fn set_state(i: &mut Instance, state: *mut c_void) -> Status {
        // SAFETY: by the caller's guarantee.
        match unsafe { state.cast::<Snapshot>().as_ref() } {
            Some(s) => i.restore(s),
            None => i.say(Status::Error, "set FMU state: NULL state"),
        }
    }

    /// `fmi*FreeFMUState`: frees `*slot` and sets it to NULL.
    ///
    /// # Safety
    /// `slot` is NULL or valid; its value NULL or a state of this library, not used after.
    pub unsafe fn free_state(slot: *mut *mut c_void) -> Status {
        // SAFETY: by the caller's guarantee.
        if let Some(slot) = unsafe { slot.as_mut() } {
            if !slot.is_null() {
                // SAFETY: a state of this library, made by `Box::into_raw`.
                drop(unsafe { Box::from_raw(slot.cast::<Snapshot>()) });
            }
            *slot = std::ptr::null_mut();
        }
        Status::Ok
    }

    /// `fmi*SerializedFMUStateSize`.
    ///
    /// # Safety
    /// `state` NULL or a state of this library; `size` NULL or valid for a write.
    pub unsafe fn state_size(i: &Instance, state: *mut c_void, size: *mut usize) -> Status {
        // SAFETY: by the caller's guarantee.
        match unsafe { (state.cast::<Snapshot>().as_ref(), size.as_mut()) } {
            (Some(s), Some(n)) => {
                *n = i.serialized_size(s);
                Status::Ok
            }
            _ => i.say(Status::Error, "serialized FMU state size: NULL argument"),
        }
    }

    /// `fmi*SerializeFMUState`.
    ///
    /// # Safety
    /// `state` NULL or a state of this library; `out` NULL or valid for `size` writes.
    pub unsafe fn serialize(i: &Instance, state: *mut c_void, out: *mut u8, size: usize) -> Status {
        // SAFETY: by the caller's guarantee.
        match unsafe { (state.cast::<Snapshot>().as_ref(), slice_mut(out, size)) } {
            (Some(s), Some(out)) => i.serialize(s, out),
            _ => i.say(Status::Error, "serialize FMU state: NULL argument"),
        }
    }

    /// `fmi*DeserializeFMUState`: a new state in `*slot` (one already there is overwritten).
    ///
    /// # Safety
    /// `bytes` NULL or valid for `size` reads; `slot` NULL or valid for reads and writes, its
    /// value NULL or a state of this library.
    pub unsafe fn deserialize(
        i: &Instance,
        bytes: *const u8,
        size: usize,
        slot: *mut *mut c_void,
    ) -> Status {
        // SAFETY: by the caller's guarantee.
        let (Some(bytes), Some(slot)) = (unsafe { slice(bytes, size) }, unsafe { slot.as_mut() })
        else {
            return i.say(Status::Error, "deserialize FMU state: NULL argument");
        };
        match i.deserialize(bytes) {
            Ok(s) => {
                // SAFETY: a non-NULL value is a state of this library.
                match unsafe { slot.cast::<Snapshot>().as_mut() } {
                    Some(old) => *old = s,
                    None => *slot = Box::into_raw(Box::new(s)).cast(),
                }
                Status::Ok
            }
            Err(e) => e,
        }
    }

    /// The configuration in the FMU's resource folder `dir`.
    pub fn load_config(dir: &std::path::Path) -> Result<crate::config::Config, String> {
        let path = dir.join(crate::config::FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "cannot read the FMU's configuration {}: {e} (resources of an FMU made by host-sim fmu)",
                path.display()
            )
        })?;
        crate::config::Config::parse(&text)
            .map_err(|e| format!("bad configuration {}: {e}", path.display()))
    }
}
