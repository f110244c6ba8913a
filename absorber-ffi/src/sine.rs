//! The sine of the excitation, for C programs that reproduce a Rust run.

/// Single-precision sine of the `libm` crate (musl's algorithm), the one the Rust firmware and
/// host references use for their excitation: a C program that must reproduce a Rust run bit
/// for bit computes its input with it (a C library's `sinf` may differ in the last bit).
#[no_mangle]
pub extern "C" fn absorber_sinf(x: f32) -> f32 {
    libm::sinf(x)
}
