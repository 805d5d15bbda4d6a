//! Byte layouts of wide hierarchy arenas: `[WideArenaHeader | refs |
//! corners | nodes]`, and `[boxes | keys | links | binary nodes]` for the build's
//! scratch. Counts in, bytes out, checked ([`crate::arena::Parts`]).
//!
//! The nodes come last because their count is known only after the build
//! (the requirements bound it at one per primitive; builds use about a
//! quarter of that): a build records its own node count as the capacity,
//! so the arena it needs is a prefix of the one it was given, and a
//! caller may keep only those bytes (`WideArenaLayout::total_bytes` of
//! the recorded counts).

use super::{WideInfo, WideNode, WideRequirements};
use crate::arena::Parts;
use crate::bvh::BvhNode;
use crate::geom::Corners4;
use crate::{Aabb, Error};
use core::mem::size_of;

/// Bytes reserved for the header at the start of a wide hierarchy arena.
pub const WIDE_HEADER_BYTES: usize = 128;

/// Magic word of a wide hierarchy arena: "CRWB".
pub const WIDE_MAGIC: u32 = u32::from_le_bytes(*b"CRWB");
/// Layout version of [`WideArenaHeader`] and [`WideNode`] (2: the
/// triangles' corners after the references).
pub const WIDE_VERSION: u32 = 2;

/// Where the parts of a wide hierarchy arena lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideArenaLayout {
    /// Node slots.
    pub nodes: usize,
    /// Reference slots.
    pub refs: usize,
    /// Corner blocks: [`super::corners::blocks_for`] `refs`.
    pub corners: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Offset of the corner blocks.
    pub corners_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl WideArenaLayout {
    /// The layout holding `nodes` node slots and `refs` references, or
    /// `None` past [`crate::limits::MAX_ARENA_BYTES`].
    pub fn of(nodes: usize, refs: usize) -> Option<WideArenaLayout> {
        const _: () = assert!(size_of::<WideArenaHeader>() <= WIDE_HEADER_BYTES);
        let mut p = Parts::after(WIDE_HEADER_BYTES);
        let corners = super::corners::blocks_for(refs);
        let refs_offset = p.push::<u32>(refs)?;
        let corners_offset = p.push::<Corners4>(corners)?;
        let nodes_offset = p.push::<WideNode>(nodes)?;
        Some(WideArenaLayout {
            nodes,
            refs,
            corners,
            nodes_offset,
            refs_offset,
            corners_offset,
            total_bytes: p.total()?,
        })
    }
}

/// Where the parts of a wide build's scratch lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideScratchLayout {
    /// Element counts (`nodes` and `refs` are the arena's).
    pub counts: WideRequirements,
    /// Offset of the keys (the boxes are at 0).
    pub keys_offset: usize,
    /// Offset of the links.
    pub links_offset: usize,
    /// Offset of the binary hierarchy's nodes.
    pub bvh_nodes_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl WideScratchLayout {
    /// The scratch layout of `counts`, or `None` past the limit.
    pub fn of(counts: &WideRequirements) -> Option<WideScratchLayout> {
        let mut p = Parts::after(0);
        p.push::<Aabb>(counts.boxes)?;
        let keys_offset = p.push::<f32>(counts.keys)?;
        let links_offset = p.push::<u32>(counts.links)?;
        let bvh_nodes_offset = p.push::<BvhNode>(counts.bvh_nodes)?;
        Some(WideScratchLayout {
            counts: *counts,
            keys_offset,
            links_offset,
            bvh_nodes_offset,
            total_bytes: p.total()?,
        })
    }
}

/// The header at the start of a wide hierarchy arena: the scene it was
/// built on, its [`WideInfo`], and how large its parts are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct WideArenaHeader {
    /// [`WIDE_MAGIC`].
    pub magic: u32,
    /// [`WIDE_VERSION`].
    pub version: u32,
    /// Triangles, spheres and cones of the scene built on.
    pub scene_counts: [u32; 3],
    /// Shape of the hierarchy.
    pub info: WideInfo,
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Node slots.
    pub nodes_cap: u32,
    /// Reference slots.
    pub refs_cap: u32,
}

impl WideArenaHeader {
    /// Checks magic, version, that the layout the capacities give fits in
    /// `arena_bytes` and matches `layout_bytes`, and that the counts fit
    /// the capacities; O(1). The hierarchy itself is checked by
    /// [`super::WideBvh::validate`].
    pub fn layout(&self, arena_bytes: usize) -> Result<WideArenaLayout, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        if self.magic != WIDE_MAGIC {
            return corrupt("magic");
        }
        if self.version != WIDE_VERSION {
            return corrupt("version");
        }
        let Some(l) = WideArenaLayout::of(self.nodes_cap as usize, self.refs_cap as usize) else {
            return corrupt("layout");
        };
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.node_count == 0 || i.node_count > self.nodes_cap || i.ref_count > self.refs_cap {
            return corrupt("counts");
        }
        Ok(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_are_checked_and_aligned() {
        let l = WideArenaLayout::of(3, 5).unwrap();
        assert_eq!(l.refs_offset, WIDE_HEADER_BYTES);
        // The references (20 bytes) padded to 16 bytes, two blocks of
        // corners (2 x 144 bytes) for their 5 slots.
        assert_eq!(l.corners, 2);
        assert_eq!(l.corners_offset, WIDE_HEADER_BYTES + 32);
        assert_eq!(l.nodes_offset, l.corners_offset + 2 * 144);
        assert_eq!(l.total_bytes, l.nodes_offset + 3 * 128);
        // Fewer nodes: a prefix of the same arena.
        let fewer = WideArenaLayout::of(1, 5).unwrap();
        assert_eq!(
            (fewer.refs_offset, fewer.corners_offset, fewer.nodes_offset),
            (l.refs_offset, l.corners_offset, l.nodes_offset)
        );
        assert_eq!(fewer.total_bytes, l.total_bytes - 2 * 128);
        assert!(WideArenaLayout::of(usize::MAX / 256, 1).is_none());
        let mut h = WideArenaHeader {
            magic: WIDE_MAGIC,
            version: WIDE_VERSION,
            layout_bytes: l.total_bytes as u32,
            nodes_cap: 3,
            refs_cap: 5,
            ..Default::default()
        };
        h.info.node_count = 1;
        assert_eq!(h.layout(l.total_bytes), Ok(l));
        assert!(h.layout(l.total_bytes - 1).is_err());
        h.info.ref_count = 6;
        assert!(h.layout(l.total_bytes).is_err());
    }
}
