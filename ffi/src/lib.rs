//! The C ABI of coray. The only crate of the project with `unsafe`: it turns
//! the caller's pointers and byte arenas into the typed slices the core works
//! on, checks them first, and states each invariant in a `// SAFETY:` comment.
//!
//! Conventions (every function):
//! - returns a [`CorayStatus`]; outputs are written only on `CORAY_STATUS_OK`
//!   (`CORAY_STATUS_ARENA_TOO_SMALL` also writes the bytes needed);
//! - never unwinds into C: with feature `std` a panic becomes
//!   `CORAY_STATUS_INTERNAL_ERROR`; the bare build aborts;
//! - never allocates; the caller owns every byte, before and after the call;
//! - parameter structs start with `struct_size` (set it to `sizeof`) and have
//!   a `_default()` function;
//! - a built tree arena is immutable: any number of threads may trace it at
//!   once, provided nobody writes to it meanwhile.
#![no_std]
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs)]
#![allow(clippy::missing_safety_doc)] // Each function's doc has a "Safety" paragraph in prose for C readers.

#[cfg(feature = "std")]
extern crate std;

mod bvh;
mod carve;
mod kdtree;
mod lcts;
mod proj;
mod types;

pub use bvh::*;
pub use kdtree::*;
pub use lcts::*;
pub use proj::*;
pub use types::*;

/// Status of every entry point. Numbers are fixed forever.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CorayStatus {
    /// Success; outputs written.
    Ok = 0,
    /// A required pointer was NULL.
    NullPointer = 1,
    /// An arena (16 bytes) or an input array (its element's alignment) is misaligned.
    Misaligned = 2,
    /// An arena is smaller than the minimum; the bytes needed are reported.
    ArenaTooSmall = 3,
    /// A parameter is out of its documented range, or `struct_size` is wrong.
    InvalidParameter = 4,
    /// A triangle names a vertex that does not exist.
    IndexOutOfRange = 5,
    /// More primitives than the structure can index (2^30), or an arena over 4 GiB.
    TooManyPrimitives = 6,
    /// A tree arena fails its header checks or its validation.
    CorruptArena = 7,
    /// The scene passed to a trace call is not the one the tree was built on.
    SceneMismatch = 8,
    /// A bug in coray (a caught panic). Please report it.
    InternalError = 9,
}

impl From<coray::Error> for CorayStatus {
    fn from(e: coray::Error) -> Self {
        use coray::Error as E;
        match e {
            E::SliceTooSmall { .. } => CorayStatus::ArenaTooSmall,
            E::IndexOutOfRange { .. } => CorayStatus::IndexOutOfRange,
            E::TooManyPrimitives { .. } => CorayStatus::TooManyPrimitives,
            E::InvalidParameter { .. } => CorayStatus::InvalidParameter,
            E::Corrupt { .. } => CorayStatus::CorruptArena,
            E::SceneMismatch => CorayStatus::SceneMismatch,
            _ => CorayStatus::InternalError,
        }
    }
}

/// Runs an entry point's body; with `std`, a panic becomes
/// [`CorayStatus::InternalError`] instead of unwinding into C.
fn guard(f: impl FnOnce() -> Result<(), CorayStatus>) -> CorayStatus {
    #[cfg(feature = "std")]
    let r = std::panic::catch_unwind(core::panic::AssertUnwindSafe(f))
        .unwrap_or(Err(CorayStatus::InternalError));
    #[cfg(not(feature = "std"))]
    let r = f();
    match r {
        Ok(()) => CorayStatus::Ok,
        Err(s) => s,
    }
}

/// A static, NUL-terminated description of `status` (any integer: unknown
/// values get "unknown status"). Never NULL; never free it.
#[no_mangle]
pub extern "C" fn coray_status_str(status: i32) -> *const core::ffi::c_char {
    let s: &'static core::ffi::CStr = match status {
        0 => c"ok",
        1 => c"null pointer",
        2 => c"misaligned arena or array",
        3 => c"arena too small",
        4 => c"invalid parameter",
        5 => c"vertex index out of range",
        6 => c"too many primitives or arena over 4 GiB",
        7 => c"corrupt arena",
        8 => c"scene differs from the one the tree was built on",
        9 => c"internal error (a bug in coray)",
        _ => c"unknown status",
    };
    s.as_ptr()
}

#[cfg(not(feature = "std"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn abort() -> !;
    }
    // SAFETY: C's abort() takes no arguments, touches no Rust state and
    // does not return; it is the only way out of a panic without std.
    unsafe { abort() }
}
