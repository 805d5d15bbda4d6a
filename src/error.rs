//! Errors of the core. Rich here; the C ABI flattens them to status codes.

use core::fmt;

/// Everything that can go wrong in a build or in reading back a structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// A caller slice holds fewer elements than the requirement formula asks.
    SliceTooSmall {
        /// Which slice (for example "nodes", "events").
        slice: &'static str,
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The vertex index it holds.
        vertex: u32,
    },
    /// More primitives than 32-bit indices can name.
    TooManyPrimitives {
        /// Primitives in the scene.
        count: usize,
    },
    /// A parameter lies outside its documented range.
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
    },
    /// A structure read back from memory breaks one of its invariants.
    Corrupt {
        /// The invariant that failed.
        what: &'static str,
    },
    /// The scene given at trace time is not the one the structure was built on.
    SceneMismatch,
    /// The kd-tree was built without ropes ([`crate::kd::KdParams::ropes`])
    /// and the call walks them (an LCTS cast, a patch's visibility).
    NoRopes,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::SliceTooSmall { slice, needed, got } => {
                write!(
                    f,
                    "slice `{slice}` too small: needs {needed} elements, got {got}"
                )
            }
            Error::IndexOutOfRange { triangle, vertex } => {
                write!(f, "triangle {triangle} refers to missing vertex {vertex}")
            }
            Error::TooManyPrimitives { count } => {
                write!(f, "{count} primitives: more than 32-bit indices can name")
            }
            Error::InvalidParameter { name } => write!(f, "invalid parameter `{name}`"),
            Error::Corrupt { what } => write!(f, "corrupt structure: {what}"),
            Error::SceneMismatch => {
                f.write_str("scene differs from the one the structure was built on")
            }
            Error::NoRopes => {
                f.write_str("the kd-tree has no ropes: build it with ropes for rope-walking casts")
            }
        }
    }
}
