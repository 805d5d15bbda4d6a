//! The Longest Common Traversal Sequence (Havran and Bittner 2000): rays in
//! a convex shaft whose boundary rays traverse the kd-tree alike can skip
//! what they have in common.
//!
//! - [`history`]: traversal histories of boundary rays, in caller buffers;
//! - [`slcts`]: the common sequence of leaves (SLCTS), unification of empty
//!   leaves, the termination object, and tracing a ray along it then by ropes;
//! - [`hlcts`]: the hierarchical LCTS, the cut where boundary rays stop
//!   deciding alike, built from a parent cut, with its leading leaves;
//! - [`guide`]: ropes guided by the boundary rays' leaves past the common part;
//! - [`image`]: hidden-surface removal by image casting (SLCTS-1D and -2D
//!   undersampling windows, HLCTS-1D and -2D bisection; hierarchical and
//!   rope traversal as references);
//! - [`patch`]: patch-to-patch visibility through one HLCTS;
//! - [`window`]: an LCTS window's rays eight at a time, one test of a
//!   primitive for all of them, together by ropes while they move alike.
//!
//! Every scheme is exact: each pixel gets the primitive and the `t` that
//! hierarchical traversal gives it. A boundary ray whose history does not
//! fit its buffer simply shares nothing; its window falls back to ordinary
//! traversal, so buffer sizes change speed, never results.

pub mod guide;
pub mod history;
pub mod hlcts;
pub mod image;
pub mod layout;
pub mod patch;
pub mod slcts;
pub mod window;

pub use history::{History, HistoryRecord};
pub use image::{
    cast_image, cast_image_by, cast_image_with, cast_image_with_by, cast_rect_with_by,
    image_requirements, CastStats, CornerInfo, ImageRequirements, ImageScratch, PixelRect, Scheme,
};
