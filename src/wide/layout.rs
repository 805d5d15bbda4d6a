//! Byte layouts of wide hierarchy arenas: `[WideArenaHeader | blocks |
//! nodes]`, and `[boxes | keys | links | refs | binary nodes]` for the
//! build's scratch. Counts in, bytes out, checked ([`crate::arena::Parts`]).
//!
//! The nodes come last because the counts of both parts are known only
//! after the build (the requirements bound the nodes at
//! [`super::nodes_bound`] of one leaf per primitive, builds use about a
//! tenth of that; the blocks at one per primitive, builds use about a
//! third): the build moves the nodes down to the blocks it used
//! ([`WideArenaLayout::pack`]) and records its own counts as the
//! capacities, so the arena it needs is a prefix of the one it was given,
//! and a caller may keep only those bytes (`WideArenaLayout::total_bytes`
//! of the recorded counts).

use super::{LeafBlock, WideInfo, WideNode, WideRequirements};
use crate::arena::Parts;
use crate::bvh::BvhNode;
use crate::{Aabb, Error};
use core::mem::size_of;

/// Bytes reserved for the header at the start of a wide hierarchy arena.
pub const WIDE_HEADER_BYTES: usize = 128;

/// Magic word of a wide hierarchy arena: "CRWB".
pub const WIDE_MAGIC: u32 = u32::from_le_bytes(*b"CRWB");
/// Layout version of [`WideArenaHeader`], [`WideNode`] and [`LeafBlock`]
/// (3: nodes of eight, each leaf's primitives in its own blocks).
pub const WIDE_VERSION: u32 = 3;

/// Where the parts of a wide hierarchy arena lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideArenaLayout {
    /// Node slots.
    pub nodes: usize,
    /// Leaf blocks.
    pub blocks: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the blocks.
    pub blocks_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl WideArenaLayout {
    /// The layout holding `nodes` node slots and `blocks` leaf blocks, or
    /// `None` past [`crate::limits::MAX_ARENA_BYTES`].
    pub fn of(nodes: usize, blocks: usize) -> Option<WideArenaLayout> {
        const _: () = assert!(size_of::<WideArenaHeader>() <= WIDE_HEADER_BYTES);
        let mut p = Parts::after(WIDE_HEADER_BYTES);
        let blocks_offset = p.push::<LeafBlock>(blocks)?;
        let nodes_offset = p.push::<WideNode>(nodes)?;
        Some(WideArenaLayout {
            nodes,
            blocks,
            nodes_offset,
            blocks_offset,
            total_bytes: p.total()?,
        })
    }

    /// The layout a build's arena starts with: room for `req`.
    pub fn for_build(req: &WideRequirements) -> Option<WideArenaLayout> {
        WideArenaLayout::of(req.nodes, req.blocks)
    }

    /// Moves the nodes of a hierarchy with `info`, built in `arena` laid
    /// out as `self`, down to the layout holding exactly its nodes and
    /// blocks (the blocks stay where they are), and zeroes the rest of
    /// `self`'s bytes. `None` (nothing moved) when the counts exceed this
    /// layout's or the arena is shorter than it.
    pub fn pack(&self, info: &WideInfo, arena: &mut [u8]) -> Option<WideArenaLayout> {
        let (nodes, blocks) = (info.node_count as usize, info.block_count as usize);
        if nodes > self.nodes || blocks > self.blocks {
            return None;
        }
        let tight = WideArenaLayout::of(nodes, blocks)?;
        let arena = arena.get_mut(..self.total_bytes)?;
        let bytes = nodes * size_of::<WideNode>();
        // The nodes' new place starts at or below their old one.
        arena.copy_within(
            self.nodes_offset..self.nodes_offset + bytes,
            tight.nodes_offset,
        );
        let blocks_end = tight.blocks_offset + blocks * size_of::<LeafBlock>();
        arena[blocks_end..tight.nodes_offset].fill(0);
        arena[tight.nodes_offset + bytes..].fill(0);
        Some(tight)
    }
}

/// Where the parts of a wide build's scratch lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideScratchLayout {
    /// Element counts (`nodes` and `blocks` are the arena's).
    pub counts: WideRequirements,
    /// Offset of the keys (the boxes are at 0).
    pub keys_offset: usize,
    /// Offset of the links.
    pub links_offset: usize,
    /// Offset of the binary hierarchy's references.
    pub refs_offset: usize,
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
        let refs_offset = p.push::<u32>(counts.refs)?;
        let bvh_nodes_offset = p.push::<BvhNode>(counts.bvh_nodes)?;
        Some(WideScratchLayout {
            counts: *counts,
            keys_offset,
            links_offset,
            refs_offset,
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
    /// Leaf blocks.
    pub blocks_cap: u32,
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
        let Some(l) = WideArenaLayout::of(self.nodes_cap as usize, self.blocks_cap as usize) else {
            return corrupt("layout");
        };
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.node_count == 0 || i.node_count > self.nodes_cap || i.block_count > self.blocks_cap {
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
        let l = WideArenaLayout::of(3, 2).unwrap();
        assert_eq!(l.blocks_offset, WIDE_HEADER_BYTES);
        assert_eq!(l.nodes_offset, l.blocks_offset + 2 * 160);
        assert_eq!(l.total_bytes, l.nodes_offset + 3 * 224);
        // Fewer nodes: a prefix of the same arena.
        let fewer = WideArenaLayout::of(1, 2).unwrap();
        assert_eq!(
            (fewer.blocks_offset, fewer.nodes_offset),
            (l.blocks_offset, l.nodes_offset)
        );
        assert_eq!(fewer.total_bytes, l.total_bytes - 2 * 224);
        assert!(WideArenaLayout::of(usize::MAX / 512, 1).is_none());
        let mut h = WideArenaHeader {
            magic: WIDE_MAGIC,
            version: WIDE_VERSION,
            layout_bytes: l.total_bytes as u32,
            nodes_cap: 3,
            blocks_cap: 2,
            ..Default::default()
        };
        h.info.node_count = 1;
        assert_eq!(h.layout(l.total_bytes), Ok(l));
        assert!(h.layout(l.total_bytes - 1).is_err());
        h.info.block_count = 3;
        assert!(h.layout(l.total_bytes).is_err());
        h.info.block_count = 2;
        h.info.node_count = 4;
        assert!(h.layout(l.total_bytes).is_err());
        h.info.node_count = 1;
        h.version = 2;
        assert!(h.layout(l.total_bytes).is_err());
    }

    /// Packing moves the nodes down to the blocks in use, keeps the
    /// blocks, and zeroes everything else.
    #[test]
    fn pack_moves_the_nodes_to_the_blocks_in_use() {
        let l = WideArenaLayout::of(4, 3).unwrap();
        let mut arena = [0u8; 4096];
        for (i, b) in arena[..l.total_bytes].iter_mut().enumerate() {
            *b = (i % 251) as u8 + 1;
        }
        let before = arena;
        let info = WideInfo {
            node_count: 2,
            block_count: 1,
            ..Default::default()
        };
        let t = l.pack(&info, &mut arena).unwrap();
        assert_eq!(t, WideArenaLayout::of(2, 1).unwrap());
        assert_eq!(t.total_bytes, l.total_bytes - 2 * 224 - 2 * 160);
        // The block in use where it was.
        let kept = t.blocks_offset + 160;
        assert_eq!(arena[..kept], before[..kept]);
        // The two nodes from their old place.
        assert_eq!(
            arena[t.nodes_offset..t.total_bytes],
            before[l.nodes_offset..l.nodes_offset + 2 * 224]
        );
        // Zero between and after.
        assert!(arena[kept..t.nodes_offset].iter().all(|&b| b == 0));
        assert!(arena[t.total_bytes..].iter().all(|&b| b == 0));
        // More than the layout holds: refused.
        let too_many = WideInfo {
            node_count: 5,
            ..info
        };
        assert!(l.pack(&too_many, &mut arena).is_none());
        assert!(l.pack(&info, &mut arena[..l.total_bytes - 1]).is_none());
    }
}
