//! Byte layouts of projection arenas: `[ProjArenaHeader | nodes | refs |
//! rects | prim_rects]`, and of a build's scratch: the builder's scratch
//! ([`crate::bvh::layout::BvhScratchLayout`]), then the flat source boxes
//! and the refit's stack. Counts in, bytes out, checked.

use super::{ProjPlane, ProjRequirements, Rect};
use crate::arena::Parts;
use crate::bvh::layout::BvhScratchLayout;
use crate::bvh::{BvhInfo, BvhNode};
use crate::{Aabb, Error, Vec3};
use core::mem::size_of;

/// Bytes reserved for the header at the start of a projection arena.
pub const PROJ_HEADER_BYTES: usize = 128;
/// Magic word of a projection arena: "CRPJ".
pub const PROJ_MAGIC: u32 = u32::from_le_bytes(*b"CRPJ");
/// Layout version of [`ProjArenaHeader`] and [`Rect`].
pub const PROJ_VERSION: u32 = 2;

/// Where the parts of a projection arena lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjArenaLayout {
    /// Node slots (and node rectangles).
    pub nodes: usize,
    /// Reference slots.
    pub refs: usize,
    /// Primitive rectangles.
    pub prim_rects: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Offset of the node rectangles.
    pub rects_offset: usize,
    /// Offset of the primitive rectangles.
    pub prim_rects_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl ProjArenaLayout {
    /// The layout for these counts, or `None` past the limit.
    pub fn of(nodes: usize, refs: usize, prim_rects: usize) -> Option<ProjArenaLayout> {
        const _: () = assert!(size_of::<ProjArenaHeader>() <= PROJ_HEADER_BYTES);
        let mut p = Parts::after(PROJ_HEADER_BYTES);
        let nodes_offset = p.push::<BvhNode>(nodes)?;
        let refs_offset = p.push::<u32>(refs)?;
        let rects_offset = p.push::<Rect>(nodes)?;
        let prim_rects_offset = p.push::<Rect>(prim_rects)?;
        Some(ProjArenaLayout {
            nodes,
            refs,
            prim_rects,
            nodes_offset,
            refs_offset,
            rects_offset,
            prim_rects_offset,
            total_bytes: p.total()?,
        })
    }

    /// The arena of `req`.
    pub fn of_requirements(req: &ProjRequirements) -> Option<ProjArenaLayout> {
        ProjArenaLayout::of(req.nodes, req.refs, req.prim_rects)
    }
}

/// Where the parts of a projection build's scratch lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjScratchLayout {
    /// The builder's scratch, at offset 0.
    pub bvh: BvhScratchLayout,
    /// Offset of the source boxes (one per primitive).
    pub source_offset: usize,
    /// Source boxes.
    pub source: usize,
    /// Offset of the refit's stack.
    pub stack_offset: usize,
    /// Stack entries (`u32`).
    pub stack: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl ProjScratchLayout {
    /// The scratch of `req`, or `None` past the limit.
    pub fn of(req: &ProjRequirements) -> Option<ProjScratchLayout> {
        let bvh = BvhScratchLayout::of(&req.bvh_scratch)?;
        let mut p = Parts::after(bvh.total_bytes);
        let source_offset = p.push::<Aabb>(req.source)?;
        let stack_offset = p.push::<u32>(req.stack)?;
        Some(ProjScratchLayout {
            bvh,
            source_offset,
            source: req.source,
            stack_offset,
            stack: req.stack,
            total_bytes: p.total()?,
        })
    }
}

/// The header at the start of a projection arena.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct ProjArenaHeader {
    /// [`PROJ_MAGIC`].
    pub magic: u32,
    /// [`PROJ_VERSION`].
    pub version: u32,
    /// The builder ([`crate::bvh::layout::code`]).
    pub builder: u32,
    /// 0: built on the rectangles; 1: dummy (3D structure).
    pub criteria: u32,
    /// Triangles, spheres and cones of the scene built on.
    pub scene_counts: [u32; 3],
    /// Shape of the hierarchy.
    pub info: BvhInfo,
    /// 0: perspective; 1: orthographic.
    pub plane_kind: u32,
    /// The plane: eye, right, up, forward (eye unused when orthographic).
    pub plane: [f32; 12],
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Node slots.
    pub nodes_cap: u32,
    /// Reference slots.
    pub refs_cap: u32,
    /// Primitive rectangles.
    pub prim_rects_cap: u32,
}

impl ProjArenaHeader {
    /// The plane the header records.
    pub fn plane(&self) -> ProjPlane {
        let v = |i: usize| Vec3::new(self.plane[i], self.plane[i + 1], self.plane[i + 2]);
        if self.plane_kind == 1 {
            ProjPlane::Orthographic {
                right: v(3),
                up: v(6),
                forward: v(9),
            }
        } else {
            ProjPlane::Perspective {
                eye: v(0),
                right: v(3),
                up: v(6),
                forward: v(9),
            }
        }
    }

    /// Records `p`.
    pub fn set_plane(&mut self, p: &ProjPlane) {
        let (eye, kind) = match *p {
            ProjPlane::Perspective { eye, .. } => (eye, 0),
            ProjPlane::Orthographic { .. } => (Vec3::ZERO, 1),
        };
        let (r, u, f) = p.axes();
        self.plane_kind = kind;
        for (i, v) in [eye, r, u, f].iter().enumerate() {
            self.plane[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
        }
    }

    /// Checks magic, version, plane and layout (O(1)).
    pub fn layout(&self, arena_bytes: usize) -> Result<ProjArenaLayout, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        if self.magic != PROJ_MAGIC {
            return corrupt("magic");
        }
        if self.version != PROJ_VERSION {
            return corrupt("version");
        }
        if self.plane_kind > 1 || self.criteria > 1 || !self.plane.iter().all(|x| x.is_finite()) {
            return corrupt("plane or criteria");
        }
        let Some(l) = ProjArenaLayout::of(
            self.nodes_cap as usize,
            self.refs_cap as usize,
            self.prim_rects_cap as usize,
        ) else {
            return corrupt("layout");
        };
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.root >= self.nodes_cap || i.node_count > self.nodes_cap || i.ref_count > self.refs_cap
        {
            return corrupt("counts");
        }
        Ok(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_checked() {
        let l = ProjArenaLayout::of(3, 2, 4).unwrap();
        assert_eq!(l.nodes_offset, PROJ_HEADER_BYTES);
        assert_eq!(l.refs_offset, PROJ_HEADER_BYTES + 96);
        assert_eq!(l.rects_offset, l.refs_offset + 16);
        assert_eq!(l.prim_rects_offset, l.rects_offset + 64);
        assert_eq!(l.total_bytes, l.prim_rects_offset + 80);
        assert!(ProjArenaLayout::of(0x0800_0001, 1, 1).is_none());
        assert!(ProjArenaLayout::of(1, 1, usize::MAX / 4).is_none());
    }
}
