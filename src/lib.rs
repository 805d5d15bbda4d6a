//! coray: an allocation-free ray-shooting core.
//!
//! The core never allocates and never uses `unsafe`: every structure lives in
//! typed slices that the caller lends it. [`kd::requirements`] says how many
//! elements each slice needs, [`kd::build_sah`] fills them and returns a
//! [`kd::KdTree`] that borrows them, and the tree is then immutable: any
//! number of threads may trace it at once.
//!
//! Structures refer to their parts by 32-bit indices, never by pointers, so a
//! built tree can be copied, saved and traced at another address.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is true for NaN,
// which is how degenerate input is turned away.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod arena;
pub mod bvh;
pub mod error;
pub mod geom;
pub mod kd;
pub mod lcts;
#[cfg(feature = "oracle")]
pub mod oracle;
pub mod proj;
pub mod stats;

pub use error::Error;
pub use geom::{Aabb, Camera, Cone, Hit, Ray, Scene, Sphere, Vec3};
pub use stats::TraceStats;
