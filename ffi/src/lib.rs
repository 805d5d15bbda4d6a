//! The C ABI of coray, version 1.0. The only crate of the project with
//! `unsafe`: it checks the caller's pointers, sizes and handles, turns byte
//! arenas into the typed slices the core works on, and states each
//! invariant in a `// SAFETY:` comment. docs/c-api.md states the
//! conventions every function follows; in short:
//!
//! - names are `coray_<object>_<verb>`; every function returns a
//!   `CorayStatus` (but `*_default`, `coray_version`, `coray_status_str`);
//! - outputs are written only on `CORAY_STATUS_OK` (`*needed_bytes` of a
//!   build also on `CORAY_STATUS_ARENA_TOO_SMALL`);
//! - no buffer written by a call may overlap another buffer of that call;
//! - every struct passed by pointer, but ray and hit arrays, starts with
//!   `struct_size`;
//! - enumerations are named `uint32_t` types with `CORAY_*` constants;
//! - never unwinds into C, never prints, never allocates: the caller owns
//!   every byte, before and after the call.
#![no_std]
#![allow(clippy::missing_safety_doc)] // Each function's doc has a "Safety" paragraph in prose for C readers.

#[cfg(feature = "std")]
extern crate std;

mod abi;
mod build_jobs;
mod bvh;
mod carve;
mod cast;
mod handle;
mod kdtree;
mod one_ray;
mod proj;
pub mod saved;
pub mod simd;
#[cfg(feature = "std")]
pub mod through_c;
mod tracer;
mod wide;

pub use abi::*;
pub use build_jobs::{CorayKdRunJob, CorayKdRunJobs};
pub use bvh::*;
pub use cast::*;
pub use handle::{CorayBvh, CorayKdTree, CorayProj, CorayWide};
pub use kdtree::*;
pub use proj::*;
pub use saved::{coray_saved_default, coray_saved_open, CoraySaved};
pub use tracer::*;
pub use wide::*;

/// Major version of the C ABI: changes only with an incompatible change.
pub const CORAY_VERSION_MAJOR: u32 = 1;
/// Minor version: new functions or struct fields, compatible.
pub const CORAY_VERSION_MINOR: u32 = 8;
/// Patch version: fixes only.
pub const CORAY_VERSION_PATCH: u32 = 0;

/// Status of every entry point. Numbers are fixed forever; docs/c-api.md
/// says which situations give which status.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CorayStatus {
    /// Success; outputs written.
    Ok = 0,
    /// A required pointer was NULL.
    NullPointer = 1,
    /// An arena or stack (16 bytes), an array or struct (its element's
    /// alignment) is misaligned.
    Misaligned = 2,
    /// An arena, scratch or stack is smaller than needed; a build reports
    /// the bytes needed.
    ArenaTooSmall = 3,
    /// A parameter is out of its documented range, a `struct_size` is too
    /// small, buffers overlap, a handle was not filled by its open call,
    /// or a ray is not one the structure takes.
    InvalidParameter = 4,
    /// A triangle names a vertex that does not exist.
    IndexOutOfRange = 5,
    /// More primitives than a structure can index (2^30), or an arena over
    /// 4 GiB.
    TooManyPrimitives = 6,
    /// An arena fails its header checks or its validation, or a trace met
    /// a broken invariant of an arena that was never validated.
    CorruptArena = 7,
    /// The scene is not the one the arena was built on.
    SceneMismatch = 8,
    /// A bug in coray (a caught panic). Please report it.
    InternalError = 9,
    /// The call walks ropes (an LCTS cast, a patch query) and the kd-tree
    /// was built without them (`omit_ropes`). Since 1.2.
    NoRopes = 10,
    /// A saved file's magic, format version, byte order, length, checksum
    /// or array bounds are wrong (`coray_saved_open`). Since 1.7.
    DamagedFile = 11,
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
            E::NoRopes => CorayStatus::NoRopes,
            _ => CorayStatus::InternalError,
        }
    }
}

/// Runs an entry point's body. With `std`, a panic (a bug: no input can
/// cause one) becomes `CorayStatus::InternalError` instead of unwinding
/// into C; the bare build aborts.
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
    status_description(status).as_ptr()
}

/// What `coray_status_str` returns, for Rust callers.
pub fn status_description(status: i32) -> &'static core::ffi::CStr {
    match status {
        0 => c"ok",
        1 => c"null pointer",
        2 => c"misaligned arena, stack, array or struct",
        3 => c"arena, scratch or stack too small",
        4 => c"invalid parameter",
        5 => c"vertex index out of range",
        6 => c"too many primitives or arena over 4 GiB",
        7 => c"corrupt arena",
        8 => c"scene differs from the one the arena was built on",
        9 => c"internal error (a bug in coray)",
        10 => c"the kd-tree has no ropes (built with omit_ropes)",
        11 => c"damaged saved file (magic, version, byte order, length, checksum or bounds)",
        _ => c"unknown status",
    }
}

/// The library's version, `(major << 16) | (minor << 8) | patch`: compare
/// it with the header's `CORAY_VERSION_*` to catch a header and library
/// of different versions.
#[no_mangle]
pub extern "C" fn coray_version() -> u32 {
    (CORAY_VERSION_MAJOR << 16) | (CORAY_VERSION_MINOR << 8) | CORAY_VERSION_PATCH
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

#[cfg(test)]
mod tests {
    #[test]
    fn version_constants_are_the_crate_version() {
        let v = env!("CARGO_PKG_VERSION");
        let want = std::format!(
            "{}.{}.{}",
            super::CORAY_VERSION_MAJOR,
            super::CORAY_VERSION_MINOR,
            super::CORAY_VERSION_PATCH
        );
        assert_eq!(v, want);
        let packed = super::CORAY_VERSION_MAJOR << 16
            | super::CORAY_VERSION_MINOR << 8
            | super::CORAY_VERSION_PATCH;
        assert_eq!(super::coray_version(), packed);
    }
}
