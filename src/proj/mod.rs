//! Projection hierarchies (Bezerianos 2001, chapters 3 to 5): the scene's
//! boxes projected onto a plane (the image plane, a light's cube faces or a
//! directional light's plane) as 2D view-aligned rectangles, a hierarchy
//! over them, and traversal by the ray's 2D point: a point-in-rectangle
//! test (4 comparisons) instead of a ray-box test.
//!
//! Two kinds of hierarchy ([`Criteria`]): built on the 2D rectangles
//! themselves (R-tree, R*-tree, TDBS, bottom-up matching, all by the 2D
//! boxes' areas), or "dummy": a 3D hierarchy whose nodes carry the union of
//! their children's rectangles (the inner rectangle of the thesis' figure
//! 3.8). Every node keeps both its rectangle and its 3D box, so either
//! kind is traversed by any [`ProjScheme`]: 2D, 3D or combination.
//!
//! A ray may use a plane's hierarchy only when it lies on a line through
//! the plane's eye: primary rays from the camera, shadow rays towards a
//! point light ([`lights`]); the traversal refuses others (`None`), which
//! go, as reflection and refraction rays do, to a global 3D hierarchy. The
//! hits of a ray it takes are exactly those of 3D traversal: rectangles are
//! conservative (padded for rounding; a box that reaches behind the eye
//! covers the whole plane, one wholly behind it is empty) and primitives
//! are tested with the ray itself.

mod build;
pub mod layout;
pub mod lights;
mod plane;
mod traverse;

pub use build::{build, requirements, ProjRequirements, ProjScratch, ProjStorage};
pub use plane::{cube_face_of, cube_faces, ProjPlane, Rect, UNBOUNDED};
pub use traverse::{ProjScheme, Projected, RECT_COST};

use crate::bvh::{Builder, Bvh, RTreeParams};

/// Which algorithm builds a projection hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjBuilder {
    /// TDBS, TDBS-SAH, or bottom-up matching (quadratic or chain).
    Static(Builder),
    /// R-tree or R*-tree, objects inserted in `order`.
    RTree(RTreeParams),
}

/// What the hierarchy's structure is built on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Criteria {
    /// The primitives' 2D rectangles on the plane (their areas and
    /// overlaps); primitives that project to nothing stay out.
    TwoD,
    /// The primitives' 3D boxes, as a view independent hierarchy; the
    /// nodes' rectangles are then the unions of their children's.
    Dummy,
}

/// A projection hierarchy: a hierarchy whose nodes have 3D boxes (in
/// `bvh.nodes`) and rectangles on `plane` (`rects`, same indices), and the
/// rectangle of every primitive (`prim_rects`, by global primitive index).
/// Made only by [`build`] and [`ProjHierarchy::from_parts`].
#[derive(Clone, Copy)]
pub struct ProjHierarchy<'a> {
    /// Structure, 3D boxes, references, scene.
    pub(crate) bvh: Bvh<'a>,
    /// Rectangle of each node.
    pub(crate) rects: &'a [Rect],
    /// Rectangle of each primitive (empty when it projects to nothing).
    pub(crate) prim_rects: &'a [Rect],
    /// The plane the rectangles lie on.
    pub(crate) plane: ProjPlane,
}

impl<'a> ProjHierarchy<'a> {
    /// Reassembles a projection hierarchy from parts read back from memory
    /// with O(1) checks: a rectangle per node slot and per primitive.
    /// [`ProjHierarchy::validate`] checks the rest on untrusted memory.
    #[inline]
    pub fn from_parts(
        bvh: Bvh<'a>,
        rects: &'a [Rect],
        prim_rects: &'a [Rect],
        plane: ProjPlane,
    ) -> Result<ProjHierarchy<'a>, crate::Error> {
        if rects.len() < bvh.nodes.len() || prim_rects.len() < bvh.scene.prim_count() {
            return Err(crate::Error::Corrupt {
                what: "rectangle slices",
            });
        }
        Ok(ProjHierarchy {
            bvh,
            rects,
            prim_rects,
            plane,
        })
    }

    /// The 3D side: structure, boxes, references, scene.
    pub fn bvh(&self) -> &Bvh<'a> {
        &self.bvh
    }

    /// The plane the rectangles lie on.
    pub fn plane(&self) -> &ProjPlane {
        &self.plane
    }

    /// The rectangles of the node slots and of the primitives.
    pub fn rects(&self) -> (&'a [Rect], &'a [Rect]) {
        (self.rects, self.prim_rects)
    }

    /// Entries of traversal stack every trace needs.
    pub fn stack_len(&self) -> usize {
        self.bvh.stack_len()
    }
}
