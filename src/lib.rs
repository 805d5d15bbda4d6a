//! coray: an allocation-free ray-shooting core.
//!
//! The core never allocates and never uses `unsafe`: every structure lives in
//! typed slices that the caller lends it. Every family (`kd`, `bvh`,
//! `proj`) has the same shape: `requirements` says how many elements each
//! slice needs, `build` fills them and returns a structure that borrows
//! them, `validate` checks one read back from memory, and the structure
//! traces rays ([`Accel`]) on a stack the caller owns. A built structure is
//! immutable: any number of threads may trace it at once.
//!
//! Structures refer to their parts by 32-bit indices, never by pointers, so a
//! built tree can be copied, saved and traced at another address. Each
//! family's `layout` module gives the byte layout of its arenas, which the
//! C ABI (crate `coray-ffi`) carves. Feature `alloc` adds `owned`
//! storage for std users; feature `std` takes square roots from the
//! compiler's intrinsic ([`geom::lanes::sqrt_rn`]).
#![no_std]
#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is true for NaN,
// which is how degenerate input is turned away.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(feature = "alloc")]
extern crate alloc;
// Only for the float square root intrinsic (see `geom::lanes::sqrt_rn`).
#[cfg(feature = "std")]
extern crate std;

pub mod accel;
pub mod arena;
pub mod bvh;
pub mod error;
pub mod geom;
pub mod kd;
pub mod lcts;
pub mod limits;
#[cfg(feature = "oracle")]
pub mod oracle;
#[cfg(feature = "alloc")]
pub mod owned;
pub mod proj;
pub mod rng;
mod sort_key;
pub mod stats;
pub mod tolerance;
pub mod wide;

pub use accel::{Accel, Shape};
pub use error::Error;
pub use geom::{Aabb, Camera, Cone, Corners4, Hit, Ray, Scene, Sphere, Vec3};
pub use stats::TraceStats;
