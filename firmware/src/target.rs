//! Target side: semihosting output and exit code, the reference check, the stack probe and the
//! panic handler.
//!
//! Semihosting arguments (`qemu-system-arm … -append "<args>"`):
//! * `expect=0x<16 hex digits>`: the host's `state_hash`; exit 0 only if this run reproduces it
//!   (1 if not, 2 if no reference was given);
//! * `stack`: paint the 32 KiB below the stack pointer before every step and report the deepest
//!   stack use of `Sim::step` (costs time, so off by default);
//! * `stress=<name>`: a stress scene (`crate::stress`) instead of the paper's run.
//!
//! Every run reports the stack used from reset to the end of the scene's construction (the boot
//! RAM: cortex-m-rt's `paint-stack` fills the stack at reset; the deepest overwritten word after
//! the construction).

use crate::{error_name, run, Probe, Setup, Sim};
use core::fmt::{self, Write};
use core::mem::MaybeUninit;
use semihosting::io::Write as _;

/// The value cortex-m-rt's `paint-stack` fills the stack with at reset (also used per step).
const PAINT: u32 = 0xcccc_cccc;
/// How far below the stack pointer the per-step probe paints \[bytes\].
const WINDOW: usize = 32 * 1024;

extern "C" {
    /// Bottom of the stack (end of `.bss`), from cortex-m-rt's `link.x`.
    static _stack_end: u32;
    /// Top of the stack (end of RAM).
    static _stack_start: u32;
}

struct Out(Option<semihosting::io::Stdout>);

impl Write for Out {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        match &mut self.0 {
            Some(o) => o.write_all(s.as_bytes()).map_err(|_| fmt::Error),
            None => Ok(()),
        }
    }
}

#[inline(always)]
fn sp() -> usize {
    let sp: usize;
    // SAFETY: reads the stack pointer, no side effects.
    unsafe {
        core::arch::asm!("mov {0}, sp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    sp
}

fn stack_bottom() -> usize {
    core::ptr::addr_of!(_stack_end) as usize
}

fn stack_top() -> usize {
    core::ptr::addr_of!(_stack_start) as usize
}

/// Lowest address in `[from, to)` whose word is not the paint (`to` if all painted).
fn lowest_used(from: usize, to: usize) -> usize {
    let mut a = from;
    while a < to {
        // SAFETY: `[from, to)` is RAM below the live stack, word aligned.
        if unsafe { core::ptr::read_volatile(a as *const u32) } != PAINT {
            return a;
        }
        a += 4;
    }
    to
}

/// Stack high-water mark of each step: paints `[sp − WINDOW, sp)` before the call, and after
/// it finds the lowest word the step overwrote.
struct StackProbe {
    enabled: bool,
    k: u32,
    sp: usize,
    floor: usize,
    max: usize,
    max_k: u32,
    overflow: bool,
}

impl Probe for StackProbe {
    #[inline(always)]
    fn before_step(&mut self) {
        self.k += 1;
        if !self.enabled {
            return;
        }
        self.sp = sp();
        self.floor = self.sp.saturating_sub(WINDOW).max(stack_bottom());
        let mut a = self.floor;
        while a < self.sp {
            // SAFETY: below the stack pointer of this (inlined) frame, nothing lives there and
            // no interrupt is enabled.
            unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
            a += 4;
        }
    }

    #[inline(always)]
    fn after_step(&mut self) {
        if !self.enabled {
            return;
        }
        let low = lowest_used(self.floor, self.sp);
        if low == self.floor {
            self.overflow = true;
        }
        let used = self.sp - low;
        if used > self.max {
            self.max = used;
            self.max_k = self.k;
        }
    }
}

/// The firmware's `main`: builds the scene into `slot` (a `static`, so the model is counted in
/// RAM), runs it, checks the fingerprint against `expect=` and exits through semihosting.
pub fn target_main<M: Sim>(slot: &'static mut MaybeUninit<M>) -> ! {
    let mut out = Out(semihosting::io::stdout().ok());
    let mut expect: Option<u64> = None;
    let mut probe = StackProbe {
        enabled: false,
        k: 0,
        sp: 0,
        floor: 0,
        max: 0,
        max_k: 0,
        overflow: false,
    };
    let mut setup = Setup::default();
    if let Ok(args) = semihosting::experimental::env::args::<256>() {
        for a in &args {
            match a {
                Ok("stack") => probe.enabled = true,
                Ok(s) if s.starts_with("expect=") => {
                    let hex = s["expect=".len()..].trim_start_matches("0x");
                    expect = u64::from_str_radix(hex, 16).ok();
                }
                Ok(s) => {
                    if setup.arg(s).is_err() {
                        let _ = writeln!(out, "unknown stress scene in `{s}`");
                        semihosting::process::exit(4)
                    }
                }
                _ => {}
            }
        }
    }
    let bottom = stack_bottom();
    let m = match M::init_in(slot, &setup) {
        Ok(m) => m,
        Err(e) => {
            let _ = writeln!(out, "init failed: {}", error_name(&e));
            semihosting::process::exit(3)
        }
    };
    let init_used = stack_top() - lowest_used(bottom, sp());
    let summary = run(m, &setup, &mut out, &mut probe);
    let _ = writeln!(
        out,
        "# target: size_of model = {} bytes",
        core::mem::size_of::<M>()
    );
    let _ = writeln!(
        out,
        "# target: boot stack from reset = {init_used} bytes (high-water through the scene's construction)"
    );
    if probe.enabled {
        let _ = writeln!(
            out,
            "# target: stack high-water of step = {}{} bytes (step {})",
            if probe.overflow { ">=" } else { "" },
            probe.max,
            probe.max_k
        );
    }
    let code = match expect {
        Some(h) if h == summary.hash => {
            let _ = writeln!(out, "# target: matches the host reference bit for bit");
            0
        }
        Some(h) => {
            let _ = writeln!(out, "# target: MISMATCH: host state_hash=0x{h:016x}");
            1
        }
        None => {
            let _ = writeln!(
                out,
                "# target: no reference given (pass expect=0x<host state_hash>)"
            );
            2
        }
    };
    semihosting::process::exit(code)
}

/// `fw-cost`'s `main`: the configuration from the semihosting arguments, run, exit code.
pub fn cost_main() -> ! {
    let mut out = Out(semihosting::io::stdout().ok());
    let mut c = crate::cost::Config::default();
    if let Ok(args) = semihosting::experimental::env::args::<512>() {
        for a in (&args).into_iter().skip(1).flatten() {
            if let Err(key) = c.set(a) {
                let _ = writeln!(out, "fw-cost: bad argument (key `{key}`)");
                semihosting::process::exit(4)
            }
        }
    }
    let code = crate::cost::run(&c, &mut out);
    semihosting::process::exit(i32::from(code))
}

/// Panics end the run with exit code 101 (the model itself never panics; see docs/embedded.md).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    if let Ok(mut e) = semihosting::io::stderr() {
        let _ = e.write_all(b"panic: ");
        if let Some(l) = info.location() {
            let _ = e.write_all(l.file().as_bytes());
        }
        let _ = e.write_all(b"\n");
    }
    semihosting::process::exit(101)
}
