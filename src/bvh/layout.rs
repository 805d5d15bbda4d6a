//! Byte layouts of hierarchy arenas: `[BvhArenaHeader | nodes | refs]` for
//! every builder, `[boxes | keys | links | clusters]` for a static build's
//! scratch (the insertion order alone for an R-tree's build and deletes).
//! Counts in, bytes out, checked ([`crate::arena::Parts`]).

use super::rtree::{RTree, RTreeParams, RTreeState, Split};
use super::{BvhInfo, BvhNode, BvhRequirements};
use crate::arena::Parts;
use crate::limits::MAX_PRIMS;
use crate::{Aabb, Error};
use core::mem::size_of;

/// Bytes reserved for the header at the start of a hierarchy arena.
pub const BVH_HEADER_BYTES: usize = 128;

/// Magic word of a hierarchy arena: "CRBV".
pub const BVH_MAGIC: u32 = u32::from_le_bytes(*b"CRBV");
/// Layout version of [`BvhArenaHeader`] and [`BvhNode`].
pub const BVH_VERSION: u32 = 2;

/// [`BvhArenaHeader::rtree_flags`]: the R*-tree's rules.
pub const BVH_FLAG_RSTAR: u32 = 1;
/// [`BvhArenaHeader::rtree_flags`]: forced reinsertion.
pub const BVH_FLAG_REINSERT: u32 = 2;

/// The builder numbers a header records (the C ABI's `CORAY_BVH_BUILDER_*`).
pub mod code {
    use super::super::{rtree::Split, Builder, RTreeParams};
    /// TDBS.
    pub const TDBS: u32 = 0;
    /// TDBS by the SAH.
    pub const TDBS_SAH: u32 = 1;
    /// Bottom-up matching, quadratic search.
    pub const NN: u32 = 2;
    /// Guttman's R-tree.
    pub const RTREE: u32 = 3;
    /// The R*-tree.
    pub const RSTAR: u32 = 4;
    /// Bottom-up matching by a nearest-neighbour chain.
    pub const NN_CHAIN: u32 = 5;

    /// The number of a static builder.
    pub const fn of_static(b: Builder) -> u32 {
        match b {
            Builder::Tdbs => TDBS,
            Builder::TdbsSah => TDBS_SAH,
            Builder::Nn => NN,
            Builder::NnChain => NN_CHAIN,
        }
    }

    /// The number of an R-tree's rules.
    pub const fn of_rtree(p: &RTreeParams) -> u32 {
        match p.split {
            Split::Quadratic => RTREE,
            Split::RStar => RSTAR,
        }
    }

    /// The static builder a number names, if it names one.
    pub const fn to_static(c: u32) -> Option<Builder> {
        match c {
            TDBS => Some(Builder::Tdbs),
            TDBS_SAH => Some(Builder::TdbsSah),
            NN => Some(Builder::Nn),
            NN_CHAIN => Some(Builder::NnChain),
            _ => None,
        }
    }

    /// Whether a number names an R-tree.
    pub const fn is_rtree(c: u32) -> bool {
        c == RTREE || c == RSTAR
    }
}

/// Where the parts of a hierarchy arena lie: `[header | nodes | refs]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhArenaLayout {
    /// Node slots.
    pub nodes: usize,
    /// Reference slots.
    pub refs: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl BvhArenaLayout {
    /// The layout holding `nodes` node slots and `refs` references, or
    /// `None` past [`crate::limits::MAX_ARENA_BYTES`].
    pub fn of(nodes: usize, refs: usize) -> Option<BvhArenaLayout> {
        const _: () = assert!(size_of::<BvhArenaHeader>() <= BVH_HEADER_BYTES);
        let mut p = Parts::after(BVH_HEADER_BYTES);
        let nodes_offset = p.push::<BvhNode>(nodes)?;
        let refs_offset = p.push::<u32>(refs)?;
        Some(BvhArenaLayout {
            nodes,
            refs,
            nodes_offset,
            refs_offset,
            total_bytes: p.total()?,
        })
    }

    /// The arena of an R-tree that holds up to `capacity` objects.
    pub fn rtree(capacity: usize, p: &RTreeParams) -> Option<BvhArenaLayout> {
        let r = RTree::requirements(capacity, p);
        BvhArenaLayout::of(r.nodes, r.refs)
    }

    /// The largest R-tree capacity whose arena fits in `bytes`, if one of
    /// at least `min` does (more bytes never hold fewer objects).
    pub fn rtree_fit(bytes: usize, min: usize, p: &RTreeParams) -> Option<usize> {
        let fits = |c: usize| BvhArenaLayout::rtree(c, p).is_some_and(|l| l.total_bytes <= bytes);
        if !fits(min) {
            return None;
        }
        let (mut lo, mut hi) = (min, MAX_PRIMS);
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        Some(lo)
    }
}

/// Where the parts of a hierarchy build's scratch arena lie:
/// `[boxes | keys | links | clusters]` for the static builders, the
/// insertion order (`links`) alone for R-trees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhScratchLayout {
    /// Element counts.
    pub counts: BvhRequirements,
    /// Offset of the keys.
    pub keys_offset: usize,
    /// Offset of the links.
    pub links_offset: usize,
    /// Offset of the clusters.
    pub clusters_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl BvhScratchLayout {
    /// The scratch layout of `counts`, or `None` past the limit.
    pub fn of(counts: &BvhRequirements) -> Option<BvhScratchLayout> {
        let mut p = Parts::after(0);
        p.push::<Aabb>(counts.boxes)?;
        let keys_offset = p.push::<f32>(counts.keys)?;
        let links_offset = p.push::<u32>(counts.links)?;
        let clusters_offset = p.push::<BvhNode>(counts.clusters)?;
        Some(BvhScratchLayout {
            counts: *counts,
            keys_offset,
            links_offset,
            clusters_offset,
            total_bytes: p.total()?,
        })
    }
}

/// The header at the start of a hierarchy arena: which builder made it,
/// the scene it was built on, its [`BvhInfo`], an R-tree's parameters and
/// state, and how large its parts are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct BvhArenaHeader {
    /// [`BVH_MAGIC`].
    pub magic: u32,
    /// [`BVH_VERSION`].
    pub version: u32,
    /// The builder ([`code`]).
    pub builder: u32,
    /// Triangles, spheres and cones of the scene built on.
    pub scene_counts: [u32; 3],
    /// Shape of the hierarchy.
    pub info: BvhInfo,
    /// R-trees: M and m (0 for the static builders).
    pub max_children: u32,
    /// See `max_children`.
    pub min_children: u32,
    /// R-trees: [`BVH_FLAG_RSTAR`] and [`BVH_FLAG_REINSERT`].
    pub rtree_flags: u32,
    /// R-trees: free lists, counts, digest.
    pub rtree: RTreeState,
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Node slots.
    pub nodes_cap: u32,
    /// Reference slots.
    pub refs_cap: u32,
    /// Most objects the hierarchy may hold: the static builders' object
    /// count; for an R-tree, what its layout holds in the worst case
    /// (inserts beyond it are refused, so deletes' scratch stays bounded).
    pub capacity: u32,
}

impl BvhArenaHeader {
    /// Checks magic, version and that the layout the capacities give fits in
    /// `arena_bytes` and matches `layout_bytes`; O(1). The hierarchy itself
    /// is checked by [`super::Bvh::validate`] and [`super::validate_rtree`].
    pub fn layout(&self, arena_bytes: usize) -> Result<BvhArenaLayout, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        if self.magic != BVH_MAGIC {
            return corrupt("magic");
        }
        if self.version != BVH_VERSION {
            return corrupt("version");
        }
        let Some(l) = BvhArenaLayout::of(self.nodes_cap as usize, self.refs_cap as usize) else {
            return corrupt("layout");
        };
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.root >= self.nodes_cap
            || i.node_count > self.nodes_cap
            || i.ref_count > self.refs_cap
            || i.ref_count > self.capacity
        {
            return corrupt("counts");
        }
        Ok(l)
    }

    /// The R-tree parameters the header records (`None` for a static
    /// hierarchy), or `Corrupt` when they break the R-tree's rules.
    pub fn rtree_params(&self) -> Result<Option<RTreeParams>, Error> {
        if !code::is_rtree(self.builder) {
            return Ok(None);
        }
        let p = RTreeParams {
            split: if self.builder == code::RSTAR {
                Split::RStar
            } else {
                Split::Quadratic
            },
            max_children: self.max_children,
            min_children: self.min_children,
            order: super::InsertOrder::Scene,
            forced_reinsert: self.rtree_flags & BVH_FLAG_REINSERT != 0,
        };
        let rstar_flag = self.rtree_flags & BVH_FLAG_RSTAR != 0;
        if p.check().is_err() || self.rtree_flags > 3 || rstar_flag != (p.split == Split::RStar) {
            return Err(Error::Corrupt {
                what: "R-tree parameters",
            });
        }
        Ok(Some(p))
    }

    /// Records an R-tree's parameters and state.
    pub fn set_rtree(&mut self, p: &RTreeParams, state: RTreeState, info: BvhInfo) {
        self.max_children = p.max_children;
        self.min_children = p.min_children;
        let rstar = if p.split == Split::RStar {
            BVH_FLAG_RSTAR
        } else {
            0
        };
        let reinsert = if p.forced_reinsert {
            BVH_FLAG_REINSERT
        } else {
            0
        };
        self.rtree_flags = rstar | reinsert;
        self.rtree = state;
        self.info = info;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_are_checked_and_aligned() {
        let l = BvhArenaLayout::of(3, 5).unwrap();
        assert_eq!(l.nodes_offset, BVH_HEADER_BYTES);
        assert_eq!(l.refs_offset, BVH_HEADER_BYTES + 96);
        assert_eq!(l.total_bytes, l.refs_offset + 32);
        assert!(BvhArenaLayout::of(0x0800_0001, 1).is_none());
        assert!(BvhArenaLayout::of(1, usize::MAX).is_none());
        let s = BvhScratchLayout::of(&BvhRequirements {
            boxes: 1,
            keys: 1,
            links: 1,
            clusters: 1,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(
            (
                s.keys_offset,
                s.links_offset,
                s.clusters_offset,
                s.total_bytes
            ),
            (32, 48, 64, 96)
        );
    }

    #[test]
    fn rtree_fit_grows_with_the_bytes() {
        let p = RTreeParams::rtree();
        let need = BvhArenaLayout::rtree(100, &p).unwrap().total_bytes;
        assert_eq!(BvhArenaLayout::rtree_fit(need - 1, 100, &p), None);
        let c = BvhArenaLayout::rtree_fit(need, 100, &p).unwrap();
        assert!(c >= 100);
        assert!(BvhArenaLayout::rtree_fit(2 * need, 100, &p).unwrap() > c);
    }
}
